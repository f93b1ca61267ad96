"""One verdict on uniqueness: every path — the KKT solve, the tree kernel, the
Udwadia–Kalaba form — says "unique" exactly where the reference (2.14) does, and gives its
q̈, on random singular, redundant and near-singular problems. The faster solves defer to the
reference near their own thresholds, so the reference's rank rule decides every close case.

Agreement: 1e-9 relative, or what two backward-stable solves of one problem may differ by
(``agreement``: about κ ε, κ the condition number of the equilibrated [M; A], which is
≈ 1e12 near the rank cut-off).
"""

from pathlib import Path

import mpmath
import numpy as np
import pytest
import scipy.linalg
from hypothesis import given, settings
from hypothesis import strategies as st

import mbsynth as mb
from mbsynth.core.equations import RANK_RTOL, constrained_acceleration, equilibrate_rows, rank_report, udwadia_kalaba
from mbsynth.core.solvers import SPARSE_SIZE, kkt_acceleration

from tests.helpers.compare import rel

ROOT = Path(__file__).resolve().parents[2]
EPS = np.finfo(float).eps


def agreement(M, A, F, qdd):
    """1e-9, or the forward error of backward-stable solves of the equilibrated (2.12):
    1e3 ε κ(M̂) κ(A), times 1 + ‖Q + C‖/(μ ‖q̈‖) where the loads dwarf the inertia they
    move (μ = max |M|: a near-massless model's q̈ comes from a cancellation of forces).
    κ(A) (σ₁/σ_r of the equilibrated A over its rank) enters through (2.14)'s projector
    I − A⁺A, κ(M̂) through the solve itself."""
    mu = max(np.abs(M).max(), 1e-300)
    loads = np.linalg.norm(F) / max(mu * np.linalg.norm(qdd), 1e-300)
    s = np.linalg.svd(equilibrate_rows(np.asarray(A, dtype=float).reshape(-1, M.shape[0]))[0], compute_uv=False)
    kept = s[s > RANK_RTOL * s[0]] if s.size and s[0] > 0 else np.ones(1)
    return max(1e-9, 1e3 * EPS * rank_report(M, A).condition * kept[0] / kept[-1] * (1 + loads))


@st.composite
def problems(draw):
    """M ⪰ 0 whose eigenvalues span up to 16 decades (some exactly zero), A with repeated
    combinations of its rows, b in range(A) and Q + C balanced on null([M; A]): consistent
    data whose motion may be unique, not unique, or near the rank cut-off."""
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    n = draw(st.integers(1, 8))
    decades = np.array(draw(st.lists(st.sampled_from([0, 0, 3, 6, 9, 10, 11, 11.5, 12, 12.5, 13, 16, np.inf]),
                                     min_size=n, max_size=n)))
    V = np.linalg.qr(rng.standard_normal((n, n)))[0]
    M = (V * 10.0 ** -decades) @ V.T
    M = (M + M.T) / 2
    independent = draw(st.integers(0, n))
    A = rng.standard_normal((independent, n))
    repeats = draw(st.integers(0, 2))
    if independent and repeats:
        A = np.vstack([A, rng.standard_normal((repeats, independent)) @ A])
    b = A @ rng.standard_normal(n)
    W = rank_report(M, A).nullspace
    F = rng.standard_normal(n)
    F -= W @ (W.T @ F)  # no load on a direction no mass resists
    C = 0.3 * rng.standard_normal(n)
    C -= W @ (W.T @ C)
    return M, F - C, A, b, C


@settings(max_examples=300, deadline=None)
@given(problems())
def test_every_path_gives_the_verdict_and_acceleration_of_2_14(problem):
    M, Q, A, b, C = problem
    ref = constrained_acceleration(M, Q, A, b, C)
    kkt = kkt_acceleration(M, Q, A, b, C)
    assert kkt.unique == ref.unique
    assert kkt.nullspace.shape == ref.nullspace.shape
    tolerance = agreement(M, A, Q + C, ref.qdd)
    assert rel(kkt.qdd, ref.qdd) < tolerance
    if ref.unique and np.linalg.eigvalsh(M).min() > 1e-6 * np.abs(M).max():
        # (4.24) adds the constraint projection to a = M⁻¹Q: it cancels ‖a‖/‖q̈‖ digits
        cancelled = 1 + np.linalg.norm(np.linalg.solve(M, Q)) / max(np.linalg.norm(ref.qdd), 1e-300)
        assert rel(udwadia_kalaba(M, Q, A, b, C).qdd, ref.qdd) < tolerance * cancelled


@pytest.mark.parametrize("ratio", [1e-3, 1e-8, 1e-9, 1e-10, 1e-11, 1e-13, 1e-15, 0.0])
def test_a_nearly_massless_link_gets_one_verdict(ratio):
    """The 3D double pendulum with its second link's mass and inertia scaled by ``ratio``:
    the tree kernel (which refuses pivots below 1e-9 of their node's or the model's largest
    mass), the KKT solve (rcond ≥ 1e-8) and (2.14) (cut at 1e-12) agree on uniqueness and on
    q̈; the angular acceleration of a link whose mass and inertia scale together does not
    depend on the scale, so q̈ stays finite down to the cut-off. The cut: σ_min/σ₁ of the
    equilibrated M̂ is 0.29 ratio here, so (2.14) calls the motion unique down to a ratio of
    about 3.4e-12 — between the sampled 1e-11 and 1e-13."""
    system = mb.load(ROOT / "models" / "rigid" / "double_pendulum_3d.yaml")
    system = system.with_parameters(m2=0.8 * ratio)
    q, qd = system.initial_state()
    ref = system.motion(0.0, q, qd, method="reference")
    fast = system.motion(0.0, q, qd)
    assert fast.unique == ref.unique == (ratio >= 1e-11)
    arrays = system.evaluate(0.0, q, qd)
    assert rel(fast.qdd, ref.qdd) < agreement(arrays.M, arrays.A, arrays.Q + arrays.C, ref.qdd)


@pytest.mark.parametrize("ratio", [1e-3, 1e-8, 1e-9, 1e-10, 1e-11])
def test_a_nearly_massless_link_gets_the_exact_acceleration(ratio):
    """Where that pendulum's motion is unique, (2.14) and ``System.motion`` give q̈ to within
    1e2 κ ε of the KKT solution of the same arrays in 50 digits (κ: the condition number of
    the equilibrated M̂): the forward error of a backward-stable solve of the consistent
    (2.12). The unprojected [Q + C; b] of (2.14) is a least-squares problem with a residual,
    whose error grows as κ² ε (58 % at ratio 1e-8)."""
    system = mb.load(ROOT / "models" / "rigid" / "double_pendulum_3d.yaml").with_parameters(m2=0.8 * ratio)
    q, qd = system.initial_state()
    arrays = system.evaluate(0.0, q, qd)
    exact = _kkt_in_50_digits(arrays.M, arrays.Q + arrays.C, arrays.A, arrays.b)
    tolerance = 1e2 * rank_report(arrays.M, arrays.A).condition * EPS
    for motion in (system.motion(0.0, q, qd, method="reference"), system.motion(0.0, q, qd)):
        assert motion.unique
        assert rel(motion.qdd, exact) < tolerance, motion.method


def _kkt_in_50_digits(M, F, A, b):
    """q̈ of [[M, Aᵀ], [A, 0]] [q̈; λ] = [F; b] solved by mpmath in 50 decimal digits."""
    n, m = M.shape[0], A.shape[0]
    K = np.zeros((n + m, n + m))
    K[:n, :n], K[:n, n:], K[n:, :n] = M, A.T, A
    with mpmath.workdps(50):
        x = mpmath.lu_solve(mpmath.matrix(K.tolist()), mpmath.matrix(np.concatenate([F, b]).tolist()))
        return np.array([float(x[i]) for i in range(n)])


@pytest.mark.parametrize("case", ["unique", "dependent row", "massless block", "near cut"])
def test_the_sparse_kkt_path_gives_the_verdict_of_2_14(case):
    """KKT systems of order ≥ SPARSE_SIZE are factored by SuperLU with Higham's condition
    estimate: on a 150-coordinate, 100-row problem (3 × 3 mass blocks, rows touching six
    coordinates) the verdict and q̈ are those of (2.14), a dependent row or a massless
    block left free goes to the reference, and so does a block near the rank cut-off."""
    rng = np.random.default_rng(7)
    n, m = 150, 100
    blocks = [(lambda L: L @ L.T)(rng.standard_normal((3, 3))) for _ in range(n // 3)]
    if case == "massless block":
        blocks[5] = np.zeros((3, 3))
    if case == "near cut":
        blocks[5] = blocks[5] * 1e-11
    M = scipy.linalg.block_diag(*blocks)
    A = np.zeros((m, n))
    for row in A:
        row[rng.choice(n, 6, replace=False)] = rng.standard_normal(6)
    A[:, 15:18] = 0.0  # block 5 is held by its mass alone
    if case == "dependent row":
        A[-1] = A[0] + 2 * A[1]
    assert n + m >= SPARSE_SIZE
    b = A @ rng.standard_normal(n)
    W = rank_report(M, A).nullspace
    Q = rng.standard_normal(n)
    Q -= W @ (W.T @ Q)
    ref = constrained_acceleration(M, Q, A, b)
    kkt = kkt_acceleration(M, Q, A, b)
    assert kkt.unique == ref.unique
    if case != "near cut":  # there the reference's cut decides, whichever way
        assert ref.unique == (case != "massless block")
    assert kkt.method == ("kkt" if case == "unique" else "pseudoinverse (2.14)")
    assert rel(kkt.qdd, ref.qdd) < agreement(M, A, Q, ref.qdd)
