"""The explicit equation of motion of Udwadia & Phohomsiri (2006), and nothing else.

Given the unconstrained equation M q̈ = Q (2.1) with symmetric positive semi-definite,
possibly singular M, the constraints A q̈ = b (2.4) and the non-ideal constraint vector
C (2.6), the constrained acceleration is (2.14) with η = 0,

    q̈ = M̄⁺ [Q + C; b],     M̄ = [(I − A⁺A) M; A],                       (2.13)

the minimum-norm solution of (2.12). It is unique iff M̂ = [M; A] has full column rank
(Lemma 3.1, Result 3); otherwise any multiple of null(M̂) = null(M̄) may be added.

Rank rule (scale-aware). Rows of A (and b) are divided by their 2-norms (zero rows stay
zero and so contribute nothing); M is divided by its largest absolute entry μ (an all-zero
M contributes nothing). A singular value of the equilibrated matrix counts as zero when
it is below ``rtol`` times the largest one. Row scaling changes neither the null space nor
the rank, nor, for consistent data, the minimum-norm solution of (2.12), so the equilibrated
system is solved in place of the literal one. ``RANK_RTOL`` = 1e-12 lies far above the
rounding noise of evaluated expressions (~n ε ≈ 1e-15) and below any physically meaningful
mass ratio (after dividing by the largest entry of M). rank M and rank A use the same rule on
their own blocks. How firm a verdict is: the condition number σ₁/σ_n of the equilibrated
M̂, and the margin between the cut-off rtol σ₁ and the singular values on either side of
it (the smallest kept one, the largest dropped one); a margin below ``VERDICT_MARGIN``
means a rounding error or a slightly different parameter could change the rank.

Consistency rule. (2.12) has a solution iff (a) b ∈ range(A) and (b) wᵀ(Q + C) = 0 for
every w ∈ null([M; A]) (proof in ``constrained_acceleration``). Either failure raises
``SolveError`` at a state on the constraint manifold. A violation counts when the
offending component exceeds ``tol`` times a scale of the data, with
tol = max(CONSISTENCY_RTOL, 8 k ε σ₁/σ_r): the second term is the rounding error of the
computed null space (its angle error is about ε σ₁/σ_r, σ_r the smallest kept singular
value), so a consistent problem is never rejected for the inaccuracy of its own basis.
The scales are the sizes of the terms, not of their sum, since rounding grows with the
terms even where they cancel: for (a), ‖b_e‖ + ‖q̈‖ (b_e the equilibrated b, whose rows
of A have unit norm, so ‖A_e q̈‖ ≤ √m ‖q̈‖); for (b), ‖Q‖ + ‖C‖ + ‖M q̈‖ (the applied,
the non-ideal and the inertial forces).

Drift rule (``drift`` given: a state that may lie off the constraint manifold, such as an
integrator's stage or a projection's iterate). There b is only as accurate as the state
is close to φ = 0, φ̇ = 0, so (a) is not judged: the constraints are replaced by their
trusted part and (2.14) gives the least-squares, minimum-norm acceleration, which is what
M̄⁺ yields anyway; drift control then brings the state back, and the contradiction test
(a) is made at the projected state. With A_e = U Σ Vᵀ and c = Uᵀ b_e, a direction is
trusted when σ_i is above the rank cut and, if it is nearly dependent
(σ_i < ``NEAR_SINGULAR`` σ₁, a configuration near a singular position or dependent rows
whose dependency moves with the configuration), when (1) σ_i exceeds what the drift
itself can make of a dependent direction, ``DRIFT_RANK`` δ σ₁, with δ = max |φ_i| over
the rows relative to the size of their terms (``term_scales``: the state's relative
distance from the manifold; A moves by about that much over it), and (2) the acceleration it asks for,
|c_i|/σ_i, is at most ``DRIFT_GAIN`` times that of the rest of the motion. On the
manifold c_i = σ_i v_iᵀq̈, so a trusted direction changes nothing; off it, the drift's
share of c_i is amplified by 1/σ_i → ∞ at the singular position, and a direction that
fails (1) or (2) is treated as dependent. A direction that passes (1) is a singular
position near (not a dependent row off its manifold): its rows are named in
``Motion.singular``, whether (2) kept it or not. Through a singular position the motion keeps its velocity and so
the branch it came from.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .errors import SolveError
from .tolerances import (CONSISTENCY_ROUNDING, CONSISTENCY_RTOL, DRIFT_RANK, NAME_RTOL, NEAR_SINGULAR, RANK_RTOL,
                         SYMMETRY_RTOL, TERM_FLOOR, VERDICT_MARGIN)

DRIFT_GAIN = 10.0  # a nearly dependent direction asking more than this times the rest's acceleration is drift

_EPS = np.finfo(float).eps
_TINY = np.finfo(float).tiny


@dataclass(frozen=True, eq=False)
class RankReport:
    """Ranks behind Lemma 3.1 and Result 3 (equilibrated as in the module docstring).

    ``nullspace``: n × (n − rank_Mhat) orthonormal basis of null([M; A]) = null(M̄);
    ``singular_values``: those of the equilibrated M̂ (descending); ``rtol``: the rule's
    relative tolerance.
    """

    rank_M: int
    rank_A: int
    rank_Mhat: int
    n: int
    m: int
    nullspace: np.ndarray
    singular_values: np.ndarray
    rtol: float

    @property
    def unique(self) -> bool:
        """Result 3: the acceleration is unique iff M̂ = [M; A] has full column rank n."""
        return self.rank_Mhat == self.n

    @property
    def condition(self) -> float:
        """σ₁/σ_n of the equilibrated M̂ (inf when σ_n = 0)."""
        s = self.singular_values
        return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")

    @property
    def margins(self) -> tuple:
        """(σ_r / cut-off, cut-off / σ_(r+1)) for the cut-off rtol σ₁ and r = rank M̂: how
        far the smallest kept and the largest dropped singular value lie from it (inf
        where there is none, or when M̂ = 0)."""
        s, r = self.singular_values, self.rank_Mhat
        cut = self.rtol * s[0]
        if cut == 0:
            return float("inf"), float("inf")
        kept = s[r - 1] / cut if r > 0 else float("inf")
        dropped = cut / s[r] if r < s.size and s[r] > 0 else float("inf")
        return float(kept), float(dropped)

    @property
    def verdict_margin(self) -> float:
        """The smaller of the two ``margins``: below VERDICT_MARGIN the rank, and with it the
        verdict on uniqueness, is uncertain."""
        return min(self.margins)


@dataclass(frozen=True, eq=False)
class Motion:
    """The constrained acceleration at one state.

    ``qdd``: the minimum-norm solution of (2.12), (2.14) with η = 0; ``nullspace``: n × r
    orthonormal basis of the directions it leaves free (n × 0 when ``unique``); ``Qc``:
    the constraint force M q̈ − Q of (2.5); ``residual``: relative residual of the
    row-equilibrated (2.12) at q̈; ``method``: the formula that produced q̈;
    ``singular``: under the drift rule, the constraint rows of the nearly dependent
    directions at this state (a singular position near; empty elsewhere); ``C``: the
    non-ideal force used where it depends on q̈ (Coulomb friction), else None;
    ``lam``: the multipliers, one per row of A, with Qc − C = Aᵀλ (reactions.py),
    computed on first use where the Motion knows its rows (System.motion). Each Motion
    holds its own arrays: a later call leaves them as they are.
    """

    qdd: np.ndarray
    unique: bool
    nullspace: np.ndarray
    Qc: np.ndarray
    residual: float
    method: str
    singular: tuple = ()
    C: np.ndarray = None

    @property
    def lam(self):
        """λ, one multiplier per row of A (Qc − C = Aᵀλ, minimum norm where rows are
        dependent); None where the Motion was made without its rows."""
        if "_lam" not in self.__dict__:
            source = self.__dict__.get("_lam_source")
            self.__dict__["_lam"] = None if source is None else source(self)
        return self.__dict__["_lam"]

    def with_multipliers(self, source):
        """This Motion, with ``source(motion)`` giving ``lam`` on first use."""
        self.__dict__["_lam_source"] = source
        self.__dict__.pop("_lam", None)
        return self

    def __getattr__(self, name):
        """``residual`` of a Motion ``made`` with a source of it: computed on first read."""
        source = self.__dict__.get("_residual_source") if name == "residual" else None
        if source is None:
            raise AttributeError(f"'Motion' object has no attribute {name!r}")
        self.__dict__["residual"] = value = source()
        return value

    @classmethod
    def made(cls, qdd, unique, nullspace, Qc, residual, method, singular=()):
        """The same Motion without the frozen dataclass's __init__ (one object.__setattr__
        per field): for the compiled path, which makes one per call. ``residual``: a number, or
        a callable that gives it when first read (compiled/engine.py)."""
        motion = object.__new__(cls)
        motion.__dict__.update(qdd=qdd, unique=unique, nullspace=nullspace, Qc=Qc, method=method, singular=singular,
                               C=None)
        motion.__dict__["_residual_source" if callable(residual) else "residual"] = residual
        return motion


@dataclass(frozen=True, eq=False)
class _Data:
    """Validated float arrays of one problem and their equilibrated forms."""

    M: np.ndarray
    Q: np.ndarray
    C: np.ndarray
    F: np.ndarray  # Q + C
    A: np.ndarray
    b: np.ndarray
    Ae: np.ndarray  # rows of A divided by their 2-norms (zero rows stay zero)
    be: np.ndarray  # b divided by the same norms
    mu: float  # max |M|, 1 when M = 0
    coordinates: tuple
    constraints: tuple

    @property
    def n(self):
        return self.M.shape[0]

    @property
    def m(self):
        return self.A.shape[0]


def rank_report(M, A, *, rtol=RANK_RTOL) -> RankReport:
    """rank M, rank A, rank M̂ and null(M̂) of M̂ = [M; A] (Lemma 3.1, Result 3)."""
    M, A = np.asarray(M, dtype=float), np.asarray(A, dtype=float)
    if M.ndim != 2:
        raise ValueError(f"M must be a square 2-d array, got shape {M.shape}")
    d = _prepare(M, np.zeros(M.shape[0]), A, np.zeros(A.shape[0] if A.ndim == 2 else 0), None)
    return _rank_report(d, rtol)[0]


def constrained_acceleration(M, Q, A, b, C=None, *, rtol=RANK_RTOL,
                             coordinates=None, constraints=None, drift=None) -> Motion:
    """The acceleration of (2.14) with η = 0: q̈ = M̄⁺ [Q + C; b], M̄ = [(I − A⁺A)M; A].

    M may be singular (symmetric positive semi-definite). M̄⁺ keeps exactly rank M̂
    singular values, since null(M̄) = null(M̂) (Lemma 3.1). The result is unique iff
    rank M̂ = n (Result 3); otherwise ``nullspace`` spans the free directions and q̈ is
    the solution orthogonal to them.

    Solvability of (2.12), i.e. when some q̈ satisfies both (2.4) and (2.11): (2.4) needs
    b ∈ range(A); then q̈ = A⁺b + P z with P = I − A⁺A and (2.11) reads
    P M P z = P(Q + C − M A⁺b). P M P is symmetric, so this is solvable iff the right side
    is orthogonal to null(P M P) = {z : M P z = 0} (M ⪰ 0: zᵀPMPz = ‖M^½ P z‖²). With
    w = P z, which ranges over {w : A w = 0, M w = 0} = null([M; A]), the condition is
    wᵀ(Q + C) − (M w)ᵀA⁺b = wᵀ(Q + C) = 0. Hence (a) b ∈ range(A) and (b) wᵀ(Q + C) = 0
    for all w ∈ null([M; A]) are necessary and sufficient; a violation raises
    ``SolveError`` naming the constraints (a) or coordinates (b) involved, as does
    NaN/inf input. Shape errors raise ``ValueError``. ``drift``: None for a state on the
    constraint manifold; for a state that may be off it, a callable returning (φ per row
    of A, NaN where a row has none; the positions q), called only near a
    singular position: (a) gives way to the drift rule of the module docstring.
    """
    d = _prepare(M, Q, A, b, C, coordinates, constraints)
    singular, row_space = (), None
    if drift is not None and d.m:
        d, row_space, singular = _trusted(d, rtol, drift)
        qdd = _definite_solution(d, row_space, rtol)
        if qdd is not None:  # unique, and (b) holds with no null space
            return _motion(d, qdd, row_space[2], "pseudoinverse (2.14)", np.zeros((d.n, 0)), singular)
    report, s_hat, Ua, sa, Vk, qdd = _solve(d, row_space, rtol=rtol)
    if drift is None:
        _check_constraints(d, Ua, sa, Vk.shape[1], qdd)
    _check_forces(d, report.nullspace, s_hat, report.rank_Mhat, qdd)
    return _motion(d, qdd, Vk, "pseudoinverse (2.14)", report.nullspace, singular)


def _solve(d: "_Data", row_space=None, *, rtol):
    """(2.14) with η = 0 on equilibrated data: (rank report, σ of M̂, SVD of A_e as
    (U, s, V_k), q̈). ``row_space``: that SVD when already known. M̄⁺ is applied to (2.12)'s
    right side [(I − A⁺A)(Q + C); b]: the same q̈ as [Q + C; b] (M̄ᵀ maps the difference
    [A⁺A(Q + C); 0] to M(I − A⁺A)A⁺A(Q + C) = 0), but a consistent system, whose computed
    solution is off by about κ ε rather than the κ² ε of a least-squares residual (κ: the
    condition number of M̄, ≈ 1e9 for a link of a billionth of the others' mass)."""
    Ua, sa, Vk = _row_space(d.Ae, rtol) if row_space is None else row_space
    report, s_hat = _rank_report(d, rtol, sa)
    r = report.rank_Mhat
    Mbar = np.vstack([(d.M - Vk @ (Vk.T @ d.M)) / d.mu, d.Ae])  # (2.13), rows equilibrated
    U, s, Vt = np.linalg.svd(Mbar, full_matrices=False)
    rhs = np.concatenate([(d.F - Vk @ (Vk.T @ d.F)) / d.mu, d.be])  # (2.12)'s right side
    return report, s_hat, Ua, sa, Vk, Vt[:r].T @ ((U[:, :r].T @ rhs) / s[:r])


def _trusted(d: "_Data", rtol, drift):
    """The drift rule (module docstring): d with A_e, b_e replaced by their trusted part
    (same rows, consistent by construction), that part's SVD as (U, s, V_k) and the names
    of the rows of the nearly dependent directions of a singular position near."""
    U, s, Vt = np.linalg.svd(d.Ae, full_matrices=False)
    c = U.T @ d.be
    keep = s > rtol * s[0] if s[0] > 0 else np.zeros(s.size, dtype=bool)
    near = keep & (s < NEAR_SINGULAR * s[0])
    singular = ()
    if near.any():
        dependent = near & (s <= DRIFT_RANK * _relative_drift(d, drift) * s[0])  # (1): the drift's own
        keep &= ~dependent
        near &= ~dependent
        rest = _trusted_solution(*_restricted(d, U, s, Vt, c, keep & ~near), rtol)
        asks = np.abs(c[near]) / s[near]
        drifted = np.flatnonzero(near)[asks > DRIFT_GAIN * np.linalg.norm(rest)]
        keep[drifted] = False
        if near.any():
            singular = tuple(d.constraints[i] for i in _named(np.abs(U[:, near]).max(axis=1)))
    kept, row_space = _restricted(d, U, s, Vt, c, keep)
    return kept, row_space, singular


def _trusted_solution(d: "_Data", row_space, rtol):
    """q̈ of (2.14) on data whose rows are consistent by construction (``_restricted``)."""
    qdd = _definite_solution(d, row_space, rtol)
    return _solve(d, row_space, rtol=rtol)[-1] if qdd is None else qdd


def _definite_solution(d: "_Data", row_space, rtol):
    """q̈ of (2.14) where M is certainly positive definite by the rank rule, else None.

    With the row space (U_k, σ_k, V_k) of rows consistent by construction (the drift rule's
    trusted part, ``_restricted``), A_e q̈ = b_e reads V_kᵀ q̈ = σ_k⁻¹ U_kᵀ b_e, and (2.12)'s
    unique solution is the KKT one, q̈ = W (F/μ − V_k ν) with W = (M/μ)⁻¹ and
    (V_kᵀ W V_k) ν = V_kᵀ W F/μ − σ_k⁻¹ U_kᵀ b_e: M̄⁺ gives it when M̂ has full column rank,
    with no SVD of M̂ or M̄. Certain: σ_min(M̂) ≥ λ_min(M/μ) and σ₁(M̂) ≤ (‖M/μ‖∞² + σ₁(A_e)²)^½,
    so λ_min(M/μ) above VERDICT_MARGIN · rtol times that bound is full rank beyond doubt.
    λ_min is read off a diagonal M (planar bodies, particles); a full one is left to the SVDs."""
    M = d.M / d.mu
    diagonal = np.diag(M)
    if np.count_nonzero(M) != np.count_nonzero(diagonal):
        return None
    Ua, sa, Vk = row_space
    top = np.sqrt(np.abs(diagonal).max() ** 2 + (sa[0] ** 2 if sa.size else 0.0))
    if not diagonal.min() > VERDICT_MARGIN * rtol * top:
        return None
    W = 1.0 / diagonal
    WF = W * d.F / d.mu
    if Vk.shape[1] == 0:
        return WF
    WV = W[:, None] * Vk
    nu = np.linalg.solve(Vk.T @ WV, Vk.T @ WF - (Ua.T @ d.be) / sa)
    return WF - WV @ nu


def _relative_drift(d: "_Data", drift):
    """δ = max |φ_i| / (the size of row i's terms, ``term_scales``) over the rows."""
    phi, q = drift()
    relative = np.abs(np.asarray(phi, dtype=float)) / np.maximum(term_scales(d.A, q), _TINY)
    finite = relative[np.isfinite(relative)]
    return float(finite.max(initial=0.0))


def entry_term_scales(rows, columns, values, count, x, floor=TERM_FLOOR):
    """``term_scales`` of the ``count`` rows of A given by its entries (row, column, value)."""
    weights, x = np.abs(values), np.abs(x)
    terms = np.bincount(rows, weights=weights * x[columns], minlength=count)
    norms = np.bincount(rows, weights=weights, minlength=count)
    return terms + floor * norms * x.max(initial=0.0)


def term_scales(A, x, floor=TERM_FLOOR):
    """The size of the terms of each row's residual at x, estimated from its row of A:
    Σ_j |A_ij x_j| (x² + y² − L² at x, y ≈ L: 2L², where rounding is ε L²; each
    coordinate counts in its own units, so angles and millimetres mix), plus ``floor``
    (a thousandth unless given) of ‖A_i‖₁ ‖x‖∞ for rows whose coordinates are near zero.
    A dense or scipy.sparse A."""
    x = np.abs(np.asarray(x, dtype=float))
    if hasattr(A, "tocsr"):  # scipy.sparse, from the CSR arrays (scipy's abs and sum would build matrices)
        A = A.tocsr()
        return entry_term_scales(np.repeat(np.arange(A.shape[0]), np.diff(A.indptr)), A.indices, A.data, A.shape[0],
                                 x, floor)
    else:
        weights = np.abs(A)
        terms, norms = weights @ x, weights.sum(axis=1)
    return terms + floor * norms * x.max(initial=0.0)


def _restricted(d: "_Data", U, s, Vt, c, keep):
    """(d with A_e = U Σ Vᵀ and b_e = U c kept on the singular directions ``keep`` only,
    the SVD of that A_e as (U, s, V_k))."""
    kept = replace(d, Ae=(U[:, keep] * s[keep]) @ Vt[keep], be=U[:, keep] @ c[keep])
    return kept, (U[:, keep], s[keep], Vt[keep].T)


def udwadia_kalaba(M, Q, A, b, C=None, *, coordinates=None, constraints=None) -> Motion:
    """The Udwadia–Kalaba equation (4.24), valid for positive-definite M only:

    q̈ = a + M^-½ B⁺ (b − A a) + M^-½ (I − B⁺B) M^-½ C,   a = M⁻¹Q,  B = A M^-½ (4.3).

    M^-½ comes from the eigendecomposition of M. A singular or indefinite M (Cholesky
    fails or λ_min ≤ n ε λ_max) raises ``SolveError`` pointing to (2.14),
    ``constrained_acceleration``. B⁺ keeps the singular values of the row-equilibrated B
    allowed by ``RANK_RTOL`` (dependent constraint rows are fine); contradictory
    constraints raise ``SolveError`` as in ``constrained_acceleration``.
    """
    d = _prepare(M, Q, A, b, C, coordinates, constraints)
    lam, V = np.linalg.eigh(d.M)
    bad = lam <= d.n * _EPS * max(lam[-1], 0.0)
    try:
        np.linalg.cholesky(d.M)
    except np.linalg.LinAlgError:
        bad[0] = True
    if bad.any():
        names = [d.coordinates[i] for i in _named(np.linalg.norm(V[:, bad], axis=1))]
        raise SolveError(
            f"M is singular or not positive definite (eigenvalues from {lam[0]:.3g} to "
            f"{lam[-1]:.3g}); M^-1/2 in (4.24) does not exist. The null/negative directions "
            f"involve {', '.join(names)}. Use constrained_acceleration, eq. (2.14), which "
            "handles singular mass matrices.", coordinates=names)
    Mih = (V / np.sqrt(lam)) @ V.T  # M^-1/2
    a = V @ ((V.T @ d.Q) / lam)  # M⁻¹Q
    Be, norms = equilibrate_rows(d.A @ Mih)  # B of (4.3), rows scaled to unit norm
    Ub, sb, Vb = _row_space(Be, RANK_RTOL)
    k = Vb.shape[1]
    Bplus_e = Vb @ (Ub[:, :k].T / sb[:k, None])  # B⁺ of the row-equilibrated B
    x = Mih @ (d.F - d.Q)  # M^-½ C
    qdd = a + Mih @ (Bplus_e @ ((d.b - d.A @ a) / norms)) + Mih @ (x - Vb @ (Vb.T @ x))  # (4.24)
    Ua, sa, Vk = _row_space(d.Ae, RANK_RTOL)
    _check_constraints(d, Ua, sa, Vk.shape[1], qdd)
    return _motion(d, qdd, Vk, "udwadia-kalaba (4.24)", np.zeros((d.n, 0)))


# ---------------------------------------------------------------- shared helpers


def _prepare(M, Q, A, b, C, coordinates=None, constraints=None) -> _Data:
    """Check shapes (ValueError), finiteness and symmetry of M (SolveError); equilibrate."""
    M, Q, A, b = (np.asarray(x, dtype=float) for x in (M, Q, A, b))
    if Q.ndim != 1 or Q.shape[0] == 0:
        raise ValueError(f"Q must be a 1-d array of n >= 1 entries, got shape {Q.shape}")
    n = Q.shape[0]
    if M.shape != (n, n):
        raise ValueError(f"M must have shape ({n}, {n}) to match Q, got {M.shape}")
    if A.size == 0 and b.size == 0:
        A, b = A.reshape(0, n), b.reshape(0)
    if A.ndim != 2 or A.shape[1] != n:
        raise ValueError(f"A must have shape (m, {n}), got {A.shape}")
    m = A.shape[0]
    if b.shape != (m,):
        raise ValueError(f"b must have shape ({m},) to match A, got {b.shape}")
    C = np.zeros(n) if C is None else np.asarray(C, dtype=float)
    if C.shape != (n,):
        raise ValueError(f"C must have shape ({n},) to match Q, got {C.shape}")
    coordinates = _names(coordinates, n, "coordinates", "q[{}]")
    constraints = _names(constraints, m, "constraints", "row {}")
    for label, x in (("M", M), ("Q", Q), ("C", C), ("A", A), ("b", b)):
        _check_finite(label, x, coordinates, constraints)
    mu = float(np.abs(M).max())
    asym = np.abs(M - M.T)
    if asym.max() > SYMMETRY_RTOL * mu:
        i, j = np.unravel_index(np.argmax(asym), asym.shape)
        raise SolveError(
            f"M is not symmetric: M[{coordinates[i]}, {coordinates[j]}] = {M[i, j]:.6g} but "
            f"M[{coordinates[j]}, {coordinates[i]}] = {M[j, i]:.6g}",
            coordinates=(coordinates[i], coordinates[j]))
    Ae, norms = equilibrate_rows(A)
    return _Data(M=M, Q=Q, C=C, F=Q + C, A=A, b=b, Ae=Ae, be=b / norms,
                 mu=mu if mu > 0 else 1.0, coordinates=coordinates, constraints=constraints)


def equilibrate_rows(X):
    """(X with each row divided by its 2-norm, the norms used): zero rows stay zero
    (their norm counts as 1). Row scaling keeps null spaces, ranks and, for consistent
    data, the minimum-norm solution (module docstring)."""
    norms = np.linalg.norm(X, axis=1)
    norms[norms == 0] = 1.0
    return X / norms[:, None], norms


def _names(names, count, label, pattern):
    if names is None:
        return tuple(pattern.format(i) for i in range(count))
    if not (isinstance(names, tuple) and all(type(x) is str for x in names)):  # a System's are
        names = tuple(str(x) for x in names)
    if len(names) != count:
        raise ValueError(f"{label} must name {count} entries, got {len(names)}")
    return names


def _check_finite(label, x, coordinates, constraints):
    """SolveError naming the array, and the coordinate/constraint, of a NaN or inf entry."""
    bad = ~np.isfinite(x)
    if not bad.any():
        return
    index = tuple(int(i) for i in np.argwhere(bad)[0])
    value = x[index]
    if label in ("Q", "C"):
        coords, cons, where = (coordinates[index[0]],), (), f" at {coordinates[index[0]]}"
    elif label == "M":
        coords = (coordinates[index[0]], coordinates[index[1]])
        cons, where = (), f" at [{coords[0]}, {coords[1]}]"
    elif label == "A":
        coords, cons = (coordinates[index[1]],), (constraints[index[0]],)
        where = f" in constraint {cons[0]}, coordinate {coords[0]}"
    else:
        coords, cons = (), (constraints[index[0]],)
        where = f" in constraint {cons[0]}"
    raise SolveError(f"{label} contains {value}{where}", constraints=cons, coordinates=coords)


def _rank(s, rtol):
    """Number of singular values s (descending) above rtol · s[0]."""
    return int(np.count_nonzero(s > rtol * s[0])) if s.size and s[0] > 0 else 0


def _rank_report(d: _Data, rtol, s_A=None):
    """RankReport of M̂ = [M/μ; A_e] and the singular values of that matrix. ``s_A``: the
    singular values of A_e when already known. M is symmetric: its singular values are the
    absolute values of its eigenvalues."""
    _, s, Vt = np.linalg.svd(np.vstack([d.M / d.mu, d.Ae]), full_matrices=False)
    r = _rank(s, rtol)
    rank_M = _rank(np.sort(np.abs(np.linalg.eigvalsh(d.M / d.mu)))[::-1], rtol)
    if s_A is None and d.m:
        s_A = np.linalg.svd(d.Ae, compute_uv=False)
    rank_A = _rank(s_A, rtol) if d.m else 0
    report = RankReport(rank_M=rank_M, rank_A=rank_A, rank_Mhat=r, n=d.n, m=d.m,
                        nullspace=Vt[r:].T.copy(), singular_values=s, rtol=rtol)
    return report, s


def _row_space(X, rtol):
    """SVD of X (m × n) as (U, s, V_k): V_k an orthonormal basis of the row space, so that
    X⁺X = V_k V_kᵀ and I − X⁺X is the projector P of (2.8)."""
    if X.shape[0] == 0:
        return np.zeros((0, 0)), np.zeros(0), np.zeros((X.shape[1], 0))
    U, s, Vt = np.linalg.svd(X, full_matrices=True)
    return U, s, Vt[:_rank(s, rtol)].T


def _tol(s, r, size):
    """Relative tolerance for components along a computed null space (module docstring)."""
    return max(CONSISTENCY_RTOL, CONSISTENCY_ROUNDING * size * s[0] / s[r - 1]) if r else CONSISTENCY_RTOL


def _named(weights):
    """Indices whose weight is non-negligible relative to the largest."""
    return [i for i, w in enumerate(weights) if w > NAME_RTOL * np.max(weights)]


def _check_constraints(d: _Data, Ua, sa, k, qdd):
    """(a): b ∈ range(A), tested on the left null space of the equilibrated A, against the
    size of b, of q̈ and of the acceleration the forces alone give, |Q + C| / max |M| (a
    body held at rest by dependent rows has q̈ = 0 and b of its velocity's rounding)."""
    if d.m == 0:
        return
    U0 = Ua[:, k:]
    u = U0 @ (U0.T @ d.be)  # the part of b_e that no q̈ can produce
    size = np.linalg.norm(u)
    scale = np.linalg.norm(d.be) + np.linalg.norm(qdd) + np.linalg.norm(d.F) / d.mu + _TINY
    if size <= _tol(sa, k, d.m) * scale:
        return
    names = [d.constraints[i] for i in _named(np.abs(u))]
    raise SolveError(
        f"contradictory constraints: {', '.join(names)} cannot hold together; A q̈ = b has no "
        f"solution (b has a component of norm {size:.3g} outside the range of A, with each "
        "row of A scaled to unit norm)", constraints=names)


def _check_forces(d: _Data, N, s_hat, r, qdd):
    """(b): wᵀ(Q + C) = 0 for every w in null([M; A])."""
    if N.shape[1] == 0:
        return
    g = N.T @ d.F
    imbalance = float(np.linalg.norm(g))
    scale = np.linalg.norm(d.Q) + np.linalg.norm(d.C) + np.linalg.norm(d.M @ qdd) + _TINY
    if imbalance <= _tol(s_hat, r, d.n) * scale:
        return
    w = N @ g / imbalance
    index = _named(np.abs(w))
    names = [d.coordinates[i] for i in index]
    direction = ", ".join(f"{d.coordinates[i]}: {w[i]:+.3g}" for i in index)
    raise SolveError(
        f"force on a direction no mass resists: wᵀ(Q + C) = {imbalance:.6g} ≠ 0 for w in "
        f"null([M; A]) along ({direction}). No motion exists: these coordinates carry no "
        "mass and no constraint fixes them; add the force balance wᵀ(Q + C) = 0 as a "
        "constraint (as (5.40), (5.49) do) or give them mass.", coordinates=names)


def _motion(d: _Data, qdd, Vk, method, nullspace, singular=()) -> Motion:
    """Motion with Qc = M q̈ − Q (2.5) and the relative residual of the equilibrated (2.12);
    Vk spans the row space of A, so P x = x − V_k V_kᵀ x."""
    def P(x):
        return x - Vk @ (Vk.T @ x)
    force = d.M @ qdd
    res = np.concatenate([P(force - d.F) / d.mu, d.Ae @ qdd - d.be])
    rhs = np.concatenate([P(d.F) / d.mu, d.be])
    scale = ((np.linalg.norm(d.M) / d.mu + np.linalg.norm(d.Ae)) * np.linalg.norm(qdd)
             + np.linalg.norm(rhs) + _TINY)
    return Motion(qdd=qdd, unique=nullspace.shape[1] == 0, nullspace=nullspace,
                  Qc=force - d.Q, residual=float(np.linalg.norm(res) / scale), method=method,
                  singular=singular)
