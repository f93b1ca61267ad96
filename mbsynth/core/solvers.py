"""Faster solves equivalent to the reference equation (2.14) in ``equations.py``.

Each returns exactly what ``equations.constrained_acceleration`` returns, and is tested
against it; where its own method does not apply it falls back to the reference.
"""

from __future__ import annotations

import numpy as np

from . import equations
from .equations import Motion
from .tolerances import DIVISION_GUARD, KKT_RCOND_MIN, KKT_RESIDUAL_MAX


SPARSE_SIZE = 200  # KKT systems of this order and larger are factored sparse (SuperLU)


def kkt_acceleration(M, Q, A, b, C=None, *, coordinates=None, constraints=None,
                     rcond_min=KKT_RCOND_MIN, drift=None) -> Motion:
    """q̈ from the augmented (KKT) system [[M, Aᵀ], [A, 0]] [q̈; λ] = [Q + C; b].

    Why it gives (2.14): by (2.10), P Qc = P C with P = I − A⁺A, so Qc − C lies in
    null(P) = range(Aᵀ): Qc = C − Aᵀλ for some λ, and (2.5) becomes M q̈ + Aᵀλ = Q + C
    with A q̈ = b (2.4). Conversely any solution satisfies (2.11), since P Aᵀ = 0, and
    (2.4), i.e. all of (2.12), C ≠ 0 included. The KKT matrix is nonsingular iff
    [M; A] has full column rank (Result 3: q̈ unique) and A has full row rank (λ unique).

    The system is equilibrated as in ``equations`` (rows of A and b by the row norms of A,
    M and Q + C by max |M|), LU-factored (LAPACK getrf, or SuperLU from order
    ``SPARSE_SIZE`` on) and its reciprocal condition number in the 1-norm estimated (gecon,
    or Higham's estimate); one step of iterative refinement restores accuracy on moderately
    ill-conditioned systems. ``residual`` is the relative residual of the equilibrated KKT
    equations (its numerator bounds that of (2.12), since P Aᵀ = 0 and ‖P‖ = 1). When
    rcond is below ``rcond_min``, when that residual exceeds ``KKT_RESIDUAL_MAX``,
    or when anything is not finite, the reference ``equations.constrained_acceleration``
    decides instead (with ``drift`` passed on): non-unique motion, dependent constraints,
    near-singular positions, or ``SolveError`` for inconsistent data. One verdict: rcond
    stays below σ_min/σ_max of the equilibrated [M; A] in the sampled problems, so the
    default 1e-8, four orders above the reference's rank cut (RANK_RTOL), leaves every
    problem near that cut to the reference, and so every "not unique" to its rule.
    """
    d = equations._prepare(M, Q, A, b, C, coordinates, constraints)
    n, m = d.n, d.m
    rhs = np.concatenate([d.F / d.mu, d.be])
    solve = _sparse_solve if n + m >= SPARSE_SIZE else _dense_solve
    K, x, rcond = solve(d)
    if x is not None and rcond >= rcond_min and np.isfinite(x).all():
        residual = np.linalg.norm(K @ x - rhs) / (_norm(K) * np.linalg.norm(x) + np.linalg.norm(rhs) + DIVISION_GUARD)
        if residual <= KKT_RESIDUAL_MAX:
            qdd = x[:n]
            return Motion(qdd=qdd, unique=True, nullspace=np.zeros((n, 0)), Qc=d.M @ qdd - d.Q,
                          residual=float(residual), method="kkt")
    return equations.constrained_acceleration(M, Q, A, b, C, coordinates=coordinates,
                                              constraints=constraints, drift=drift)


def _dense_solve(d):
    """(K, x, rcond) by LAPACK: LU (getrf), the 1-norm condition estimate (gecon), one step
    of iterative refinement; x None when K is singular."""
    from scipy.linalg import lapack  # scipy loads with the first KKT solve, not with mbsynth

    n, m = d.n, d.m
    K = np.zeros((n + m, n + m))
    K[:n, :n], K[:n, n:], K[n:, :n] = d.M / d.mu, d.Ae.T, d.Ae
    lu, piv, info = lapack.dgetrf(K)
    if info != 0:
        return K, None, 0.0
    rcond, info = lapack.dgecon(lu, np.abs(K).sum(axis=0).max(), norm="1")
    rhs = np.concatenate([d.F / d.mu, d.be])
    x = lapack.dgetrs(lu, piv, rhs)[0]
    x += lapack.dgetrs(lu, piv, rhs - K @ x)[0]  # one step of iterative refinement
    return K, x, rcond if info == 0 else 0.0


def _sparse_solve(d):
    """(K, x, rcond) by SuperLU on the sparse K, the 1-norm of K⁻¹ estimated by Higham's
    block algorithm (scipy's onenormest, a few solves with K and Kᵀ), one step of
    iterative refinement; x None when K is singular."""
    import scipy.sparse.linalg

    Ae = scipy.sparse.csc_matrix(d.Ae)
    K = scipy.sparse.bmat([[scipy.sparse.csc_matrix(d.M / d.mu), Ae.T], [Ae, None]], format="csc")
    try:
        lu = scipy.sparse.linalg.splu(K)
    except RuntimeError:  # exactly singular
        return K, None, 0.0
    inverse = scipy.sparse.linalg.LinearOperator(K.shape, matvec=lu.solve, rmatvec=lambda y: lu.solve(y, trans="T"),
                                                 dtype=float)
    rcond = 1.0 / (scipy.sparse.linalg.norm(K, 1) * scipy.sparse.linalg.onenormest(inverse))
    rhs = np.concatenate([d.F / d.mu, d.be])
    x = lu.solve(rhs)
    x += lu.solve(rhs - K @ x)
    return K, x, rcond


def _norm(K):
    """The Frobenius norm of a dense or sparse K."""
    if isinstance(K, np.ndarray):
        return np.linalg.norm(K)
    import scipy.sparse.linalg

    return scipy.sparse.linalg.norm(K)
