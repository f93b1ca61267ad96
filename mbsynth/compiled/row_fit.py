"""The corrections of a step's many output rows, from a few of them corrected exactly.

Within one integrator step the rows are read from its interpolant, a polynomial in the
step's fraction θ, and each is put back on the constraints (correction.py). The correction
Δ(θ) (of q and of q̇) is a smooth function of θ: zero at the step's start (θ = 0, a state on
the constraints) and as small as the drift. So where a step passes many rows, NODES of
them, nearest the Chebyshev–Lobatto points of (0, 1] (the step's end among them), are
corrected exactly, Δ is interpolated through them and θ = 0 in the Chebyshev basis, and
every other row gets the interpolated Δ: then it is judged as strictly as an exact
correction is (correction.py's ``judge``), and a row that fails is corrected exactly.
Where more than NODES rows fail (a long step: the interpolation error grows as the span's
length to the power NODES), the span is halved and each half fitted again, the second
through NODES + 1 rows of its own, its first and last among them.

Measured on Bricard's mechanism at outputs every 1 ms (about 114 rows a step): with ten
nodes every row passed, its relative |φ| at most 3e-15 and |φ̇| at most 6e-13 (the bounds:
1e-14 and 1e-12); with eight, two thirds failed.
"""

import numpy as np
from numba import njit

from .bodies import OPTIONS

NODES = 10  # rows corrected exactly per span fitted
MIN_ROWS = 3 * NODES  # a span of fewer rows has each corrected exactly
LOBATTO = 0.5 - 0.5 * np.cos(np.pi * np.arange(NODES + 1) / NODES)  # Chebyshev–Lobatto points of [0, 1]


def nodes(fractions, a):
    """The indices (increasing; the last row's among them) of the rows to correct exactly,
    of rows at ``fractions`` θ (increasing) in a span from θ = a: nearest the span's
    Chebyshev–Lobatto points but its start where a is below the first row (the step's
    start, where Δ = 0), else at them all (a: the first row's θ)."""
    targets = a + (fractions[-1] - a) * (LOBATTO[1:] if a < fractions[0] else LOBATTO)
    picked = np.clip(np.searchsorted(fractions, targets), 1, fractions.size - 1)
    nearer_below = np.abs(fractions[picked - 1] - targets) < np.abs(fractions[picked] - targets)
    return np.unique(picked - nearer_below)


@njit(**OPTIONS)
def interpolate(fractions, a, at, Q, QD, Q_at, QD_at, Q_on, QD_on):
    """Q_on, Q̇_on ← the states Q, Q̇ (rows at ``fractions``) moved by Δ interpolated
    (module docstring) through the exact corrections Q_at, Q̇_at of the rows ``at`` (which
    get those exactly) and, where a is below the first row's θ, Δ = 0 at θ = a."""
    k, n = Q.shape[0], Q.shape[1]
    anchored = 1 if a < fractions[0] else 0
    count = at.shape[0] + anchored
    deltas, x = np.zeros((count, 2 * n)), np.full(count, a)
    for i in range(at.shape[0]):
        x[i + anchored] = fractions[at[i]]
        for c in range(n):
            deltas[i + anchored, c] = Q_at[i, c] - Q[at[i], c]
            deltas[i + anchored, n + c] = QD_at[i, c] - QD[at[i], c]
    b = fractions[k - 1]
    coefficients = np.linalg.solve(_chebyshev(x, a, b, count), deltas)
    moved = np.dot(_chebyshev(fractions, a, b, count), coefficients)
    for r in range(k):
        for c in range(n):
            Q_on[r, c] = Q[r, c] + moved[r, c]
            QD_on[r, c] = QD[r, c] + moved[r, n + c]
    for i in range(at.shape[0]):
        for c in range(n):
            Q_on[at[i], c], QD_on[at[i], c] = Q_at[i, c], QD_at[i, c]


@njit(**OPTIONS)
def _chebyshev(fractions, a, b, count):
    """T_j(x) for j < count, a row per θ of ``fractions``, x = θ mapped from [a, b] onto
    [−1, 1] (the three-term recurrence)."""
    T = np.ones((fractions.shape[0], count))
    for r in range(fractions.shape[0]):
        x = (2.0 * fractions[r] - a - b) / (b - a)
        if count > 1:
            T[r, 1] = x
        for j in range(2, count):
            T[r, j] = 2.0 * x * T[r, j - 1] - T[r, j - 2]
    return T
