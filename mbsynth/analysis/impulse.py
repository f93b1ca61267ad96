"""The impulse form of the singular-mass equation: the velocity jump of an impact.

Over an impact of vanishing duration the bounded forces do no work on the momentum and the
positions stay; integrating (2.5), M q̈ = Q + Qc, across it gives

    M (q̇⁺ − q̇⁻) = Aᵀ Λ,        A q̇⁺ = v                                     (I)

with A the rows that act in the impact (the bilateral ones, velocity-level, v their
right side so that they keep holding; the striking unilateral ones with Newton's law
v_i = −e_i a_i q̇⁻) and Λ the impulses (ideal: Qc = Aᵀλ as in (2.5)–(2.10)). (I) is (2.12)
with q̈ → q̇⁺, Q → M q̇⁻, b → v: the same KKT/(2.14) solve applies (core/solvers.py), and a
singular M (massless links, quaternion coordinates) stays allowed. By Result 3 the jump is
unique exactly when [M; A] has full column rank; otherwise SolveError names the
coordinates the jump leaves free. Coulomb friction at a striking contact (``Rough``) adds
its slip rows to A (stick) or a given impulse P to the right side, M Δq̇ = AᵀΛ + P (slip).
"""

from typing import NamedTuple

import numpy as np

from ..core.errors import SolveError
from ..core.solvers import kkt_acceleration
from ..core.tolerances import COMPLEMENTARITY_RTOL, NAME_RTOL
from ..model.reactions import multipliers


class Jump(NamedTuple):
    """q̇⁺ after an impact and Λ, one impulse per row of A (M Δq̇ = AᵀΛ, minimum norm where
    rows are dependent)."""

    qd: np.ndarray
    impulses: np.ndarray


def velocity_jump(M, qd_minus, A, v, *, impulse=None, coordinates=None, constraints=None):
    """Solve (I) for q̇⁺ and Λ (module docstring); ``impulse``: a given generalized impulse P
    beside AᵀΛ (M Δq̇ = AᵀΛ + P, the non-ideal impulse of sliding friction). Raises
    SolveError when the jump is not unique (Result 3: [M; A] lacks full column rank),
    naming the coordinates it leaves free, or when the rows contradict each other
    (``equations.constrained_acceleration``)."""
    M, qd_minus = np.asarray(M, dtype=float), np.asarray(qd_minus, dtype=float)
    A = np.asarray(A, dtype=float).reshape(-1, M.shape[0])
    given = np.zeros(M.shape[0]) if impulse is None else np.asarray(impulse, dtype=float)
    motion = kkt_acceleration(M, M @ qd_minus + given, A, np.asarray(v, dtype=float), coordinates=coordinates,
                              constraints=constraints)
    if not motion.unique:
        free = np.abs(motion.nullspace).max(axis=1)
        names = coordinates or [f"q[{i}]" for i in range(M.shape[0])]
        named = [c for c, x in zip(names, free) if x > NAME_RTOL * free.max()]
        raise SolveError(f"the velocity jump of the impact is not unique ([M; A] lacks full column rank, "
                         f"Result 3): free in {', '.join(named)}", coordinates=named)
    return Jump(motion.qdd, multipliers(A, M @ (motion.qdd - qd_minus) - given)[0])


class Rough:
    """Coulomb friction at the impact of the gaps ``chosen`` (indices into ``gaps``, the
    active set of impacts.py's complementarity problem) at (t, q, q̇): the contacts with
    μ > 0 among them stick or slip through the impact (Brach's algebraic impact law with
    Newton's law on the normal):

    - stick: their slip rows (the contact point's tangential velocity T q̇) are held at
      zero beside (I); it holds where the tangential impulse |Λ_t| ≤ μ Λ_n;
    - slip, where it does not: the tangential impulse is μ Λ_n s, s the unit direction of
      the impulse sticking would need (against the slip), a given generalized impulse
      P = Σ μ Λ_n Tᵀs beside (I). Λ_n is affine in the P assumed, so it is found exactly
      by one solve per slipping contact and a small linear system.
    """

    def __init__(self, gaps, t, q, qd, p, chosen):
        self.gaps, self.chosen = gaps, list(chosen)
        self.rough = [i for i in self.chosen if gaps.friction[i] > 0]
        self.slip = {i: gaps.slip_rows(t, q, qd, p, i) for i in self.rough}

    def jump(self, M, qd, A_b, v_b, names_b, A_gaps, target, coordinates):
        """(q̇⁺, the normal impulses of ``chosen``, {rough gap: (mode, |Λ_t|)}) of the impact
        with the model's rows A_b q̇⁺ = v_b and Newton's targets ``target`` on ``chosen``."""
        names = names_b + [self.gaps.names[i] for i in self.chosen]
        first, count = len(v_b), len(self.chosen)

        def solve(sticking, impulse=None):
            A = np.vstack([A_b, A_gaps[self.chosen], *(self.slip[i] for i in sticking)])
            v = np.concatenate([v_b, target, np.zeros(sum(len(self.slip[i]) for i in sticking))])
            slip_names = [f"{self.gaps.names[i]}.slip" for i in sticking for _ in self.slip[i]]
            return velocity_jump(M, qd, A, v, impulse=impulse, coordinates=coordinates,
                                 constraints=names + slip_names)

        stuck = solve(self.rough)
        normal = stuck.impulses[first:first + count]
        tangential = self._tangential(stuck, first + count, self.rough)
        limit = {i: self.gaps.friction[i] * normal[self.chosen.index(i)] for i in self.rough}
        slipping = [i for i in self.rough if np.linalg.norm(tangential[i]) > limit[i] * (1 + COMPLEMENTARITY_RTOL)]
        if not slipping:
            return stuck.qd, normal, {i: ("stick", float(np.linalg.norm(tangential[i]))) for i in self.rough}
        sticking = [i for i in self.rough if i not in slipping]
        # P per unit normal impulse of each slipping contact: μ Tᵀ s
        per_unit = [self.gaps.friction[i] * self.slip[i].T @ (tangential[i] / np.linalg.norm(tangential[i]))
                    for i in slipping]
        at = [first + self.chosen.index(i) for i in slipping]

        def normals(x):
            jump = solve(sticking, sum(xj * d for xj, d in zip(x, per_unit)))
            return jump, jump.impulses[at]

        alpha = normals(np.zeros(len(slipping)))[1]
        B = np.column_stack([normals(unit)[1] - alpha for unit in np.eye(len(slipping))])
        try:
            x = np.linalg.solve(np.eye(len(slipping)) - B, alpha)
        except np.linalg.LinAlgError:
            raise SolveError(f"no consistent sliding impact at {', '.join(self.gaps.names[i] for i in slipping)} "
                             f"(the friction impulse undoes the normal impulse: Painlevé-type)",
                             constraints=[self.gaps.names[i] for i in slipping]) from None
        jump = normals(x)[0]
        modes = {i: ("stick", float(np.linalg.norm(x))) for i, x in self._tangential(jump, first + count,
                                                                                     sticking).items()}
        modes.update({i: ("slip", float(self.gaps.friction[i] * xi)) for i, xi in zip(slipping, x)})
        return jump.qd, jump.impulses[first:first + count], modes

    def _tangential(self, jump, start, sticking):
        """{gap: its slip rows' impulses} of the ``sticking`` gaps, whose rows follow ``start``."""
        found = {}
        for i in sticking:
            found[i], start = jump.impulses[start:start + len(self.slip[i])], start + len(self.slip[i])
        return found
