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
coordinates the jump leaves free.
"""

from typing import NamedTuple

import numpy as np

from ..core.errors import SolveError
from ..core.solvers import kkt_acceleration
from ..core.tolerances import NAME_RTOL
from ..model.reactions import multipliers


class Jump(NamedTuple):
    """q̇⁺ after an impact and Λ, one impulse per row of A (M Δq̇ = AᵀΛ, minimum norm where
    rows are dependent)."""

    qd: np.ndarray
    impulses: np.ndarray


def velocity_jump(M, qd_minus, A, v, *, coordinates=None, constraints=None):
    """Solve (I) for q̇⁺ and Λ (module docstring). Raises SolveError when the jump is not
    unique (Result 3: [M; A] lacks full column rank), naming the coordinates it leaves
    free, or when the rows contradict each other (``equations.constrained_acceleration``)."""
    M, qd_minus = np.asarray(M, dtype=float), np.asarray(qd_minus, dtype=float)
    A = np.asarray(A, dtype=float).reshape(-1, M.shape[0])
    motion = kkt_acceleration(M, M @ qd_minus, A, np.asarray(v, dtype=float), coordinates=coordinates,
                              constraints=constraints)
    if not motion.unique:
        free = np.abs(motion.nullspace).max(axis=1)
        names = coordinates or [f"q[{i}]" for i in range(M.shape[0])]
        named = [c for c, x in zip(names, free) if x > NAME_RTOL * free.max()]
        raise SolveError(f"the velocity jump of the impact is not unique ([M; A] lacks full column rank, "
                         f"Result 3): free in {', '.join(named)}", coordinates=named)
    return Jump(motion.qdd, multipliers(A, M @ (motion.qdd - qd_minus))[0])
