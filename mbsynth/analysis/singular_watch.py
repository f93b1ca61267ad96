"""The singular positions a continuous run passes between its stages.

At a singular position the rows of A are dependent for an instant (a parallelogram's change
points): σ_r, the r-th singular value of the equilibrated A (r its rank where the watch
starts: rows dependent throughout stay out), dips to about zero and rises again, like
|t − t*|. A's rows and then its columns are scaled to unit norm, so that metres, kilometres
and radians weigh alike and σ_r/σ₁ means the same at every scale. The stages of a
continuous run rarely come within NEAR_SINGULAR σ₁ of it, where derivative.py lists them,
so the run also reads σ_r/σ₁ at each accepted step's end (on the constraints). Where one
end's ratio lies below both its neighbours' (by more than DIP_FLOOR, the SVD's rounding: rows
that do not change, as a clamped part's, give ratios equal but for it), the dip lies between
them: a golden-section search on the positions' cubic Hermite interpolant between the ends
(q and q̇ at each) finds its bottom, listed as a singular position where the ratio falls below NEAR_SINGULAR
there, with the rows of its nearly dependent direction. For models whose A is small enough
to decompose at every step (WATCH_ENTRIES), and whose rows can lose rank at all
(``rows_keep_rank``: not a tree of joints that keep it).
"""

import numpy as np
from numba import njit

from ..compiled.nodes import PARTICLE_NODE
from ..core.tolerances import DIP_FLOOR, NAME_RTOL, NEAR_SINGULAR, RANK_RTOL
from ..model.parts.part_type import QUATERNION

WATCH_ENTRIES = 4096  # the largest A (rows × coordinates) watched: an SVD per step costs little beside the step
SEARCH_STEPS = 60  # golden-section steps: the bracket shrinks to 0.618^60 ≈ 3e-13 of its width
GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0
# joint kinds whose rows are independent wherever they hold (``rows_keep_rank``)
RANK_KEEPING_KINDS = ("fixed", "revolute", "prismatic", "cylindrical", "spherical", "universal")


def rows_keep_rank(system):
    """Whether the System's rows keep their rank along every motion, so that a run passes no
    singular position and its watch has nothing to find: parts turned by a unit quaternion
    (rigid or flexible) or particles, no limits or contacts, and rows that are the parts'
    own unit-quaternion rows and the joints of RANK_KEEPING_KINDS, no joint closing a loop
    (the world counted as one part).

    Why: hung from the world part by part, A is block-triangular, each block a joint's rows
    on the coordinates of the part it brings in, with that part's quaternion row. On a part's
    (r̈, α) a joint's rows are: component rows e_k on r̈; rows d·a (a joint axis) a on r̈; rows
    a·b of two axes a × b on α alone, of unit length where they hold (a ⟂ b), and
    independent there (z_B = ±z_A for the aligned axis: ±y_A, ∓x_A; the orientation lock's
    three are the frame's axes on each of its branches) — on the quaternion's rates through
    2E(u)ᵀ, orthogonal to its own row's u. A flexible part's modes only add columns. So
    every block has full row rank wherever the rows hold: σ_r never dips."""
    own = {f"{part.name}.unit_quaternion" for part in system.parts if part.part_type.orientation == QUATERNION}
    if system.unilaterals or not all(part.part_type.orientation == QUATERNION or
                                     part.part_type.node == PARTICLE_NODE for part in system.parts):
        return False
    joined = {}  # union-find over the parts' names and the world (None)

    def root(name):
        while name in joined:
            name = joined[name]
        return name
    for con in system.constraints:
        if con.name in own and con.size == 1:
            continue
        if getattr(con, "joint_kind", None) not in RANK_KEEPING_KINDS:
            return False
        a, b = (root(None if part is None else part.name) for part in con.parts)
        if a == b:  # the joint closes a loop
            return False
        joined[a] = b
    return True


class SingularWatch:
    """The watch of a run on ``data`` (a run's Data) from the state (t, q, q̇)."""

    @staticmethod
    def fits(data):
        """Whether the model's A is worth watching: some rows, at most WATCH_ENTRIES entries."""
        entries = len(data.system.constraint_names) * data.model.n
        return 0 < entries <= WATCH_ENTRIES

    def __init__(self, data, t, q, qd):
        self.data = data
        s = np.linalg.svd(self._equilibrated(t, q, qd), compute_uv=False)
        self.rank = int(np.count_nonzero(s > RANK_RTOL * s[0])) if s.size and s[0] > 0 else 0
        self.ends = []  # the last three step ends: (t, q, q̇, σ_r/σ₁)

    def restart(self):
        """Forget the ends: the run goes on from a state not reached by a watched step."""
        self.ends = []

    @property
    def measure(self):
        """σ_r/σ₁ at the last end (1 where the rows have no rank to lose)."""
        return self.ends[-1][3] if self.ends else 1.0

    def passed(self, t, q, qd, A=None):
        """After a step ending at the state (t, q, q̇) on the constraints (``A``: its rows,
        if at hand): (t*, row names, the bracket's width) of the singular position whose dip
        the last three ends bracket, if it reaches NEAR_SINGULAR; None otherwise."""
        if not self.rank:
            return None
        self.ends = self.ends[-2:] + [(t, q.copy(), qd.copy(), self._measure(t, q, qd, A))]
        if len(self.ends) < 3 or not self.ends[1][3] < min(self.ends[0][3], self.ends[2][3]) - DIP_FLOOR:
            return None
        t_star = self._bottom()
        q_star, qd_star = self._state(t_star)
        U, s, _ = np.linalg.svd(self._equilibrated(t_star, q_star, qd_star), full_matrices=False)
        if not s[self.rank - 1] < NEAR_SINGULAR * s[0]:
            return None
        weights = np.abs(U[:, self.rank - 1])
        names = self.data.system.constraint_names
        rows = tuple(names[i] for i in np.flatnonzero(weights > NAME_RTOL * weights.max()))
        return t_star, rows, self.ends[2][0] - self.ends[0][0]

    def _equilibrated(self, t, q, qd, A=None):
        """A at (t, q, q̇) (``A``, if given), its rows and then its columns scaled to unit norm
        (a new array)."""
        A = self.data.constraint_arrays(t, q, qd, sparse=False).A if A is None else A
        A = np.array(A.toarray() if hasattr(A, "toarray") else A, dtype=float, order="C")
        _unit_rows(A)
        _unit_rows(A.T)
        return A

    def _measure(self, t, q, qd, A=None):
        """σ_r/σ₁ of the equilibrated A at (t, q, q̇) (``A``: the rows there, if at hand)."""
        return _ratio(self._equilibrated(t, q, qd, A), self.rank)

    def _bottom(self):
        """The time of the smallest ratio between the first and the last end (golden section)."""
        a, b = self.ends[0][0], self.ends[2][0]
        c, d = b - GOLDEN * (b - a), a + GOLDEN * (b - a)
        fc, fd = self._measure(c, *self._state(c)), self._measure(d, *self._state(d))
        for _ in range(SEARCH_STEPS):
            if fc < fd:
                b, d, fd = d, c, fc
                c = b - GOLDEN * (b - a)
                fc = self._measure(c, *self._state(c))
            else:
                a, c, fc = c, d, fd
                d = a + GOLDEN * (b - a)
                fd = self._measure(d, *self._state(d))
        return (a + b) / 2

    def _state(self, t):
        """(q, q̇) at t on the cubic Hermite interpolant of the step ends around it."""
        (t0, q0, v0, _), (t1, q1, v1, _) = self.ends[:2] if t <= self.ends[1][0] else self.ends[1:]
        h = t1 - t0
        s = (t - t0) / h
        h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
        d00, d10, d01, d11 = 6 * s**2 - 6 * s, 3 * s**2 - 4 * s + 1, -6 * s**2 + 6 * s, 3 * s**2 - 2 * s
        q = h00 * q0 + h10 * h * v0 + h01 * q1 + h11 * h * v1
        qd = (d00 * q0 + d01 * q1) / h + d10 * v0 + d11 * v1
        return q, qd


@njit(cache=True)
def _ratio(A, rank):
    """σ_rank/σ₁ of A; 0 where σ₁ is."""
    s = np.linalg.svd(A, full_matrices=False)[1]
    return s[rank - 1] / s[0] if s[0] > 0 else 0.0


@njit(cache=True)
def _unit_rows(X):
    """Each row of X divided by its 2-norm, in place (zero rows stay zero)."""
    for i in range(X.shape[0]):
        norm = np.sqrt(np.sum(X[i] * X[i]))
        if norm != 0.0:
            X[i] /= norm
