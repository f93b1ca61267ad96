"""Fast paths equivalent to the reference equation (2.14) in ``equations.py``.

Each returns exactly what ``equations.constrained_acceleration`` returns, and is tested
against it; where its own method does not apply it falls back to the reference.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from . import equations
from .equations import Motion


RCOND_MIN = 1e-8  # KKT systems less well conditioned than this go to the reference (2.14)
RESIDUAL_MAX = 1e-9  # a KKT solution whose relative residual of (2.12) exceeds this goes too


def kkt_acceleration(M, Q, A, b, C=None, *, coordinates=None, constraints=None,
                     rcond_min=RCOND_MIN, drift=None) -> Motion:
    """q̈ from the augmented (KKT) system [[M, Aᵀ], [A, 0]] [q̈; λ] = [Q + C; b].

    Why it gives (2.14): by (2.10), P Qc = P C with P = I − A⁺A, so Qc − C lies in
    null(P) = range(Aᵀ): Qc = C − Aᵀλ for some λ, and (2.5) becomes M q̈ + Aᵀλ = Q + C
    with A q̈ = b (2.4). Conversely any solution satisfies (2.11), since P Aᵀ = 0, and
    (2.4), i.e. all of (2.12), C ≠ 0 included. The KKT matrix is nonsingular iff
    [M; A] has full column rank (Result 3: q̈ unique) and A has full row rank (λ unique).

    The system is equilibrated as in ``equations`` (rows of A and b by the row norms of A,
    M and Q + C by max |M|), LU-factored (LAPACK getrf) and its reciprocal condition
    number in the 1-norm estimated (gecon); one step of iterative refinement restores
    accuracy on moderately ill-conditioned systems. When rcond is below ``rcond_min``, when
    the solution's relative residual of the equilibrated (2.12) exceeds ``RESIDUAL_MAX``,
    or when anything is not finite, the reference ``equations.constrained_acceleration``
    decides instead (with ``drift`` passed on): non-unique motion, dependent constraints,
    near-singular positions, or ``SolveError`` for inconsistent data. One verdict: rcond
    stays below σ_min/σ_max of the equilibrated [M; A] in the sampled problems, so the
    default 1e-8, four orders above the reference's rank cut (RANK_RTOL), leaves every
    problem near that cut to the reference, and so every "not unique" to its rule.
    """
    d = equations._prepare(M, Q, A, b, C, coordinates, constraints)
    n, m = d.n, d.m
    K = np.zeros((n + m, n + m))
    K[:n, :n] = d.M / d.mu
    K[:n, n:] = d.Ae.T
    K[n:, :n] = d.Ae
    lu, piv, info = lapack.dgetrf(K)
    if info == 0:
        rcond, info = lapack.dgecon(lu, np.abs(K).sum(axis=0).max(), norm="1")
        if info == 0 and rcond >= rcond_min:
            rhs = np.concatenate([d.F / d.mu, d.be])[:, None]
            x = lapack.dgetrs(lu, piv, rhs)[0]
            x += lapack.dgetrs(lu, piv, rhs - K @ x)[0]  # one step of iterative refinement
            qdd = x[:n, 0]
            if np.isfinite(x).all():
                Vk = np.linalg.qr(d.Ae.T)[0]  # A has full row rank: a basis of its row space
                motion = equations._motion(d, qdd, Vk, "kkt", np.zeros((n, 0)))
                if motion.residual <= RESIDUAL_MAX:
                    return motion
    return equations.constrained_acceleration(M, Q, A, b, C, coordinates=coordinates,
                                              constraints=constraints, drift=drift)
