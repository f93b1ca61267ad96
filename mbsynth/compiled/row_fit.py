"""The projections of a step's many output rows, from a few of them projected exactly.

Within one integrator step the rows are read from its interpolant, a polynomial in the
step's fraction θ, and each is put back on the constraints (compiled/projection.py). The projection
Δ(θ) (of q and of q̇) is a smooth function of θ, as small as the drift, and it vanishes to
second order at the step's start: there the state lies on the constraints and the
interpolant's slope is the motion f there, whose rates and accelerations meet the rows'
derivatives (A q̇ = −φ_t, A q̈ = b), so the drift φ(θ), φ̇(θ) and with it Δ start as θ².
So where a step passes many rows, NODES of them, nearest the Chebyshev–Lobatto points of
(0, 1] (the step's end among them), are projected exactly, Δ is interpolated in the
Chebyshev basis through them and through Δ = 0, Δ' = 0 at θ = 0, and every other row gets
the interpolated Δ: then it is judged as strictly as an exact projection is
(compiled/projection.py's ``judge``), and a row that fails is projected exactly. Where more than
NODES rows fail (a long step: the interpolation error grows as the span's length to the
power NODES), the span is halved and each half fitted again, the second through NODES + 1
rows of its own, its first and last among them.

NODES = 9 with the start's slope is the fewest for which no row of Bricard's mechanism, at
outputs every 1 ms, fails the bounds (relative |φ| within 1e-14, |φ̇| within 1e-12).
"""

import numpy as np
from numba import njit

from .bodies import OPTIONS

NODES = 9  # rows projected exactly per span fitted
MIN_ROWS = 3 * NODES  # a span of fewer rows has each projected exactly
LOBATTO = 0.5 - 0.5 * np.cos(np.pi * np.arange(NODES + 1) / NODES)  # Chebyshev–Lobatto points of [0, 1]


@njit(**OPTIONS)
def nodes(fractions, a):
    """The indices (increasing; the last row's among them) of the rows to project exactly,
    of rows at ``fractions`` θ (increasing) in a span from θ = a: nearest the span's
    Chebyshev–Lobatto points but its start where a is below the first row (the step's
    start, where Δ = 0), else at them all (a: the first row's θ)."""
    first = 1 if a < fractions[0] else 0
    picked = np.empty(LOBATTO.size - first, dtype=np.int64)
    count, row = 0, 1
    for k in range(first, LOBATTO.size):
        target = a + (fractions[-1] - a) * LOBATTO[k]
        while row < fractions.size - 1 and fractions[row] < target:  # the first row at or above it
            row += 1
        at = row - 1 if abs(fractions[row - 1] - target) < abs(fractions[row] - target) else row
        if count == 0 or at != picked[count - 1]:
            picked[count] = at
            count += 1
    return picked[:count]


@njit(**OPTIONS)
def interpolate(fractions, a, at, Q, QD, Q_at, QD_at, Q_on, QD_on):
    """Q_on, Q̇_on ← the states Q, Q̇ (rows at ``fractions``) moved by Δ interpolated
    (module docstring) through the exact projections Q_at, Q̇_at of the rows ``at`` (which
    get those exactly) and, where a is below the first row's θ (the step's start), through
    Δ = 0 and Δ' = 0 at θ = a."""
    k, n = Q.shape[0], Q.shape[1]
    anchored = 1 if a < fractions[0] else 0
    points = at.shape[0] + anchored
    count = points + anchored  # the start's slope: one condition more
    deltas, x = np.zeros((count, 2 * n)), np.full(points, a)
    for i in range(at.shape[0]):
        x[i + anchored] = fractions[at[i]]
        for c in range(n):
            deltas[i + anchored, c] = Q_at[i, c] - Q[at[i], c]
            deltas[i + anchored, n + c] = QD_at[i, c] - QD[at[i], c]
    b = fractions[k - 1]
    conditions = np.zeros((count, count))
    conditions[:points] = _chebyshev(x, a, b, count)
    if anchored:
        for j in range(count):  # T_j'(−1) = (−1)^(j+1) j²: θ = a maps to x = −1
            conditions[points, j] = (j * j) if j % 2 == 1 else -(j * j)
    coefficients = _solved(conditions, deltas)
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


@njit(**OPTIONS)
def _solved(A, B):
    """A⁻¹ B by Gaussian elimination with partial pivoting (LAPACK's gesv, without its
    copies and checks, which cost several times the solve for these NODES + 2 conditions);
    A and B are overwritten, B holding the answer."""
    n = A.shape[0]
    for k in range(n):
        p = k
        for r in range(k + 1, n):
            if abs(A[r, k]) > abs(A[p, k]):
                p = r
        if p != k:
            for c in range(n):
                A[k, c], A[p, c] = A[p, c], A[k, c]
            for c in range(B.shape[1]):
                B[k, c], B[p, c] = B[p, c], B[k, c]
        for r in range(k + 1, n):
            f = A[r, k] / A[k, k]
            if f != 0.0:
                for c in range(k + 1, n):
                    A[r, c] -= f * A[k, c]
                for c in range(B.shape[1]):
                    B[r, c] -= f * B[k, c]
    for k in range(n - 1, -1, -1):
        for c in range(B.shape[1]):
            acc = B[k, c]
            for j in range(k + 1, n):
                acc -= A[k, j] * B[j, c]
            B[k, c] = acc / A[k, k]
    return B
