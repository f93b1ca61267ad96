"""equations.py against independent numbers: numpy's literal pseudo-inverse and rank,
the paper's closed forms (examples 1–3), and Udwadia–Kalaba (4.24) for positive-definite M."""

import numpy as np
import pytest

from mbsynth.core.equations import (RANK_RTOL, constrained_acceleration, rank_report,
                               udwadia_kalaba)
from mbsynth.core.errors import SolveError

from tests.helpers.compare import rel
from tests.helpers.literal import augmented, literal_2_14


def psd(rng, n, r):
    L = rng.standard_normal((n, r))
    return L @ L.T


def constraints_of_rank(rng, m, n, k):
    """m × n matrix of rank k (rows beyond the k-th are combinations of the first k)."""
    base = rng.standard_normal((k, n))
    return rng.standard_normal((m, k)) @ base if m > k else base[:m]


def consistent_force(rng, M, A, n):
    """A random Q + C orthogonal to null([M; A]), i.e. satisfying condition (b)."""
    F = rng.standard_normal(n)
    N = np.linalg.svd(np.vstack([M, A]))[2][np.linalg.matrix_rank(np.vstack([M, A])):].T
    return F - N @ (N.T @ F)


# ---------------------------------------------------------------- Lemma 3.1 / Result 3


@pytest.mark.parametrize("seed", range(6))
def test_lemma_3_1_rank_and_nullspace(seed):
    rng = np.random.default_rng(seed)
    checked = 0
    for n in range(1, 7):
        for r in range(n + 1):
            m = int(rng.integers(0, n + 1))
            k = int(rng.integers(0, m + 1))  # k < m: deliberately dependent rows
            M, A = psd(rng, n, r), constraints_of_rank(rng, m, n, k) if m else np.zeros((0, n))
            Mbar = np.vstack([(np.eye(n) - np.linalg.pinv(A) @ A) @ M, A])
            rank_hat = np.linalg.matrix_rank(np.vstack([M, A]))
            assert np.linalg.matrix_rank(Mbar) == rank_hat  # Lemma 3.1
            assert rank_hat == min(n, r + k)  # generic rank of the construction
            rep = rank_report(M, A)
            assert (rep.rank_M, rep.rank_A, rep.rank_Mhat, rep.n, rep.m) == (r, k, rank_hat, n, m)
            assert rep.unique == (rank_hat == n)
            N = rep.nullspace
            assert N.shape == (n, n - rank_hat)
            assert np.allclose(N.T @ N, np.eye(n - rank_hat), atol=1e-12)
            assert np.linalg.norm(M @ N) <= 1e-10 * max(np.linalg.norm(M), 1)
            assert np.linalg.norm(A @ N) <= 1e-10 * max(np.linalg.norm(A), 1)
            checked += 1
    assert checked == 27


# ---------------------------------------------------------------- (2.14) against numpy and (4.24)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("n", [1, 3, 6, 10])
def test_2_15_equals_4_24_for_positive_definite_M(seed, n):
    rng = np.random.default_rng(100 * seed + n)
    M = psd(rng, n, n) + 0.1 * np.eye(n)
    m = int(rng.integers(0, n + 1))
    A = rng.standard_normal((m, n))
    b, Q, C = rng.standard_normal(m), rng.standard_normal(n), rng.standard_normal(n)
    ref = constrained_acceleration(M, Q, A, b, C)
    uk = udwadia_kalaba(M, Q, A, b, C)
    assert ref.unique and uk.unique
    assert rel(ref.qdd, uk.qdd) < 1e-10
    assert rel(ref.qdd, literal_2_14(M, Q, A, b, C)) < 1e-10
    # (4.24) written out independently with scipy's sqrtm and numpy's pinv
    from scipy.linalg import sqrtm
    Mih = np.linalg.inv(np.real(sqrtm(M)))
    a = np.linalg.solve(M, Q)
    Bp = np.linalg.pinv(A @ Mih)
    expected = a + Mih @ Bp @ (b - A @ a) + Mih @ (np.eye(n) - Bp @ A @ Mih) @ Mih @ C
    assert rel(uk.qdd, expected) < 1e-9
    assert uk.method == "udwadia-kalaba (4.24)" and ref.method == "pseudoinverse (2.14)"


@pytest.mark.parametrize("seed", range(8))
def test_solution_satisfies_2_12_and_2_10(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 9))
    r = int(rng.integers(0, n))
    m = int(rng.integers(1, n + 1))
    M, A = psd(rng, n, r), rng.standard_normal((m, n))
    F = consistent_force(rng, M, A, n)
    C = rng.standard_normal(n)
    Q = F - C
    b = rng.standard_normal(m)
    mo = constrained_acceleration(M, Q, A, b, C)
    expected, (Mbar, P) = literal_2_14(M, Q, A, b, C), augmented(M, A)
    assert rel(mo.qdd, expected) < 1e-9
    assert rel(A @ mo.qdd, b) < 1e-10  # (2.4)
    force = np.linalg.norm(M) * np.linalg.norm(mo.qdd) + np.linalg.norm(Q) + np.linalg.norm(C)
    assert np.linalg.norm(P @ M @ mo.qdd - P @ (Q + C)) < 1e-10 * force  # (2.11)
    assert np.linalg.norm(P @ mo.Qc - P @ C) < 1e-10 * force  # (2.10): P Qc = P C
    assert rel(mo.Qc, M @ mo.qdd - Q) < 1e-14  # (2.5)
    assert mo.residual < 1e-13
    assert mo.unique == (np.linalg.matrix_rank(np.vstack([M, A])) == n)
    # η = 0 is the minimum-norm solution: orthogonal to the free directions
    assert np.linalg.norm(mo.nullspace.T @ mo.qdd) <= 1e-10 * np.linalg.norm(mo.qdd)
    lstsq = np.linalg.lstsq(Mbar, np.concatenate([P @ (Q + C), b]), rcond=None)[0]
    assert rel(mo.qdd, lstsq) < 1e-9
    # any η: the shifted acceleration still satisfies (2.12)
    moved = mo.qdd + mo.nullspace @ rng.standard_normal(mo.nullspace.shape[1])
    assert rel(Mbar @ moved, np.concatenate([P @ (Q + C), b])) < 1e-10


# ---------------------------------------------------------------- the paper's examples


def example_1(m, R, Ic, g, alpha):
    M = np.array([[m * R**2 + Ic, 0.0], [0.0, 0.0]])  # (5.6)
    Q = np.array([0.0, m * g])  # (5.7)
    A = np.array([[-R * np.sin(alpha), 1.0]])  # (5.10)
    return M, Q, A, np.zeros(1)  # (5.11)


def wheel_parameters(seed):
    rng = np.random.default_rng(seed)
    return dict(m=rng.uniform(0.5, 10), R=rng.uniform(0.05, 2), Ic=rng.uniform(0.01, 5),
                g=9.81, alpha=rng.uniform(0.05, 1.5))


def wheel_5_17(m, R, Ic, g, alpha):
    s = np.sin(alpha)
    return np.array([m * g * R * s, m * g * R**2 * s**2]) / (m * R**2 + Ic)


@pytest.mark.parametrize("seed", range(5))
def test_example_1_wheel_on_incline(seed):
    p = wheel_parameters(seed)
    mo = constrained_acceleration(*example_1(**p))
    assert mo.unique and mo.nullspace.shape == (2, 0)
    assert rel(mo.qdd, wheel_5_17(**p)) < 1e-12


@pytest.mark.parametrize("seed", range(5))
def test_example_2_massless_particle_is_free(seed):
    p = wheel_parameters(seed)
    M1, Q1, A1, b = example_1(**p)
    M = np.zeros((3, 3))
    M[:2, :2] = M1  # (5.18)
    Q = np.append(Q1, 0.0)  # (5.20)
    A = np.hstack([A1, [[0.0]]])  # (5.19)
    mo = constrained_acceleration(M, Q, A, b)
    assert not mo.unique
    assert mo.nullspace.shape == (3, 1)
    assert np.allclose(np.abs(mo.nullspace[:, 0]), [0, 0, 1], atol=1e-12)  # ±e3
    assert rel(mo.qdd, np.append(wheel_5_17(**p), 0.0)) < 1e-12  # (5.23), η = 0
    rep = rank_report(M, A)
    assert (rep.rank_M, rep.rank_A, rep.rank_Mhat) == (1, 1, 2)


def example_3(m1, m2, k1, k2, x1, q2):
    M = np.array([[m1, 0, 0], [0, m2, m2], [0, m2, m2]], dtype=float)  # (5.33)
    Q = np.array([-k1 * x1, 0.0, -k2 * q2])  # (5.34)
    return M, Q, np.array([[1.0, -1.0, 0.0]]), np.zeros(1)  # (5.35), (5.36)


def spring_parameters(seed):
    rng = np.random.default_rng(seed)
    return dict(m1=rng.uniform(0.1, 10), m2=rng.uniform(0.1, 10), k1=rng.uniform(1, 1000),
                k2=rng.uniform(1, 1000), x1=rng.uniform(-1, 1), q2=rng.uniform(-1, 1))


@pytest.mark.parametrize("seed", range(6))
def test_example_3_case_5_1(seed):
    p = spring_parameters(seed)
    m1, m2, k1, k2, x1, q2 = p.values()
    mo = constrained_acceleration(*example_3(**p))
    f = (-k1 * x1 + k2 * q2) / m1
    assert mo.unique
    assert rel(mo.qdd, [f, f, -f - k2 * q2 / m2]) < 1e-11  # (5.39)
    assert rank_report(example_3(**p)[0], example_3(**p)[2]).rank_M == 2


@pytest.mark.parametrize("seed", range(6))
def test_example_3_case_5_2_massless_m1(seed):
    p = dict(spring_parameters(seed), m1=0.0)
    _, m2, k1, k2, x1, q2 = p.values()
    M, Q, _, _ = example_3(**p)
    A = np.array([[1.0, -1.0, 0.0], [k1, 0.0, -k2]])  # (5.42)
    mo = constrained_acceleration(M, Q, A, np.zeros(2), coordinates=["x1", "q1", "q2"])
    assert mo.unique
    s = (x1 + q2) / (m2 * (k1 + k2) ** 2)
    assert rel(mo.qdd, [-k1 * k2**2 * s, -k1 * k2**2 * s, -k1**2 * k2 * s]) < 1e-11  # (5.47)
    # (5.48) with its missing minus sign restored: the springs in series pull m2 back
    assert rel(mo.qdd[1] + mo.qdd[2], -k1 * k2 / (k1 + k2) * (x1 + q2) / m2) < 1e-11


@pytest.mark.parametrize("seed", range(6))
def test_example_3_case_5_3_massless_m2(seed):
    p = dict(spring_parameters(seed), m2=0.0)
    m1, _, k1, k2, x1, q2 = p.values()
    M, Q, _, _ = example_3(**p)
    A = np.array([[1.0, -1.0, 0.0], [0.0, 0.0, k2]])  # (5.51)
    mo = constrained_acceleration(M, Q, A, np.zeros(2))
    assert mo.unique
    assert rel(mo.qdd, [-k1 * x1 / m1, -k1 * x1 / m1, 0.0]) < 1e-12  # (5.56)


@pytest.mark.parametrize("seed", range(4))
def test_example_3_without_the_balance_needs_the_force_balance(seed):
    """m1 = 0 with only (5.35): null([M; A]) = (1, 1, −1)/√3, so wᵀQ = −k1 x̄1 + k2 q̄2
    must vanish, which is the paper's closing constraint (5.40)."""
    p = dict(spring_parameters(seed), m1=0.0)
    _, m2, k1, k2, x1, q2 = p.values()
    M, Q, A, b = example_3(**p)
    with pytest.raises(SolveError) as info:
        constrained_acceleration(M, Q, A, b, coordinates=["x1", "q1", "q2"])
    assert info.value.coordinates == ("x1", "q1", "q2")
    imbalance = abs(-k1 * x1 + k2 * q2) / np.sqrt(3)
    assert f"{imbalance:.6g}" in str(info.value)
    # on the balance (5.40) the motion exists but is not unique
    Q_bal = np.array([-k1 * x1, 0.0, -k1 * x1])  # k2 q̄2 = k1 x̄1
    mo = constrained_acceleration(M, Q_bal, A, b)
    assert not mo.unique
    assert np.allclose(np.abs(mo.nullspace[:, 0]), np.ones(3) / np.sqrt(3), atol=1e-12)
    # m2 = 0 with only (5.35): w = e3 (q̄2 is free), so k2 q̄2 must vanish: (5.49)
    M, Q, A, b = example_3(**dict(p, m1=1.0, m2=0.0))
    with pytest.raises(SolveError) as info:
        constrained_acceleration(M, Q, A, b, coordinates=["x1", "q1", "q2"])
    assert info.value.coordinates == ("q2",)


# ---------------------------------------------------------------- dependent and absent constraints


@pytest.mark.parametrize("seed", range(6))
def test_dependent_rows_change_nothing(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 8))
    M = psd(rng, n, int(rng.integers(1, n)))
    A = rng.standard_normal((n - 1, n))
    b, Q = rng.standard_normal(n - 1), consistent_force(rng, M, A, n)
    base = constrained_acceleration(M, Q, A, b)
    w = rng.standard_normal(n - 1)
    for A2, b2 in [(np.vstack([A, A[1]]), np.append(b, b[1])),  # a duplicate row
                   (np.vstack([A, w @ A]), np.append(b, w @ b)),  # a combination of rows
                   (np.vstack([A, 1e6 * A[0]]), np.append(b, 1e6 * b[0]))]:
        mo = constrained_acceleration(M, Q, A2, b2)
        assert rel(mo.qdd, base.qdd) < 1e-10
        assert mo.unique == base.unique
        assert rank_report(M, A2).rank_A == n - 1
        assert mo.residual < 1e-13


def test_no_constraints_with_positive_definite_M():
    rng = np.random.default_rng(7)
    M = psd(rng, 5, 5) + np.eye(5)
    Q = rng.standard_normal(5)
    for solve in (constrained_acceleration, udwadia_kalaba):
        mo = solve(M, Q, np.zeros((0, 5)), np.zeros(0))
        assert mo.unique and rel(mo.qdd, np.linalg.solve(M, Q)) < 1e-12
        assert np.linalg.norm(mo.Qc) < 1e-12 * np.linalg.norm(Q)


def test_no_constraints_with_singular_M():
    M = np.diag([2.0, 0.0])
    mo = constrained_acceleration(M, [4.0, 0.0], np.zeros((0, 2)), np.zeros(0))
    assert not mo.unique and rel(mo.qdd, [2.0, 0.0]) < 1e-15
    with pytest.raises(SolveError, match="q\\[1\\]"):
        constrained_acceleration(M, [4.0, 1.0], np.zeros((0, 2)), np.zeros(0))


# ---------------------------------------------------------------- inconsistent data


def test_contradictory_constraints_are_named():
    M, Q = np.eye(3), np.ones(3)
    A = np.array([[1.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.0]])
    with pytest.raises(SolveError) as info:
        constrained_acceleration(M, Q, A, [1.0, 5.0, 2.0], constraints=["hinge", "floor", "rod"])
    assert info.value.constraints == ("hinge", "rod")
    assert "hinge" in str(info.value) and "rod" in str(info.value)
    assert "floor" not in str(info.value)
    with pytest.raises(SolveError) as info:  # default names, a row that is a sum of two
        constrained_acceleration(M, Q, np.vstack([A[:2], A[0] + A[1]]), [1.0, 5.0, 7.0])
    assert info.value.constraints == ("row 0", "row 1", "row 2")
    with pytest.raises(SolveError) as info:  # 0 · q̈ = 1
        constrained_acceleration(M, Q, [[0.0, 0.0, 0.0]], [1.0])
    assert info.value.constraints == ("row 0",)
    with pytest.raises(SolveError):  # (4.24) refuses too
        udwadia_kalaba(M, Q, A, [1.0, 5.0, 2.0])
    # consistent within rounding is accepted: b2 = b0 (1 + 1e-14)
    mo = constrained_acceleration(M, Q, A, [1.0, 5.0, 1.0 + 1e-14])
    assert rel(A @ mo.qdd, [1.0, 5.0, 1.0]) < 1e-12


def test_force_on_massless_particle_is_named():
    p = wheel_parameters(0)
    M1, Q1, A1, b = example_1(**p)
    M = np.zeros((3, 3))
    M[:2, :2] = M1
    A = np.hstack([A1, [[0.0]]])
    with pytest.raises(SolveError) as info:
        constrained_acceleration(M, np.append(Q1, 0.25), A, b, coordinates=["theta", "y", "x"])
    assert info.value.coordinates == ("x",)
    assert "0.25" in str(info.value) and "x" in str(info.value)


@pytest.mark.parametrize("where", ["Q", "A", "b", "M", "C"])
def test_non_finite_input_raises(where):
    arrays = dict(M=np.eye(2), Q=np.ones(2), A=np.array([[1.0, 0.0]]), b=np.zeros(1),
                  C=np.zeros(2))
    arrays[where] = arrays[where].copy()
    arrays[where].flat[-1] = np.nan if where != "A" else np.inf
    with pytest.raises(SolveError) as info:
        constrained_acceleration(**arrays, coordinates=["u", "v"], constraints=["pin"])
    assert str(info.value).startswith(where)
    if where in ("Q", "C", "A", "M"):
        assert "v" in info.value.coordinates
    if where in ("A", "b"):
        assert info.value.constraints == ("pin",)


def test_shape_errors_are_value_errors():
    with pytest.raises(ValueError, match="M must have shape"):
        constrained_acceleration(np.eye(3), np.ones(2), np.zeros((0, 2)), np.zeros(0))
    with pytest.raises(ValueError, match="A must have shape"):
        constrained_acceleration(np.eye(2), np.ones(2), np.ones((1, 3)), np.zeros(1))
    with pytest.raises(ValueError, match="b must have shape"):
        constrained_acceleration(np.eye(2), np.ones(2), np.ones((1, 2)), np.zeros(2))
    with pytest.raises(ValueError, match="coordinates"):
        constrained_acceleration(np.eye(2), np.ones(2), np.ones((1, 2)), np.zeros(1),
                                 coordinates=["a"])


def test_udwadia_kalaba_refuses_singular_or_asymmetric_M():
    M, Q, A, b = example_1(**wheel_parameters(1))
    with pytest.raises(SolveError, match="constrained_acceleration") as info:
        udwadia_kalaba(M, Q, A, b, coordinates=["theta", "y"])
    assert info.value.coordinates == ("y",)
    with pytest.raises(SolveError, match="not positive definite"):
        udwadia_kalaba(np.diag([1.0, -1.0]), Q, A, b)
    with pytest.raises(SolveError, match="not symmetric"):
        udwadia_kalaba([[2.0, 1.0], [0.0, 2.0]], Q, A, b)


# ---------------------------------------------------------------- scale awareness


@pytest.mark.parametrize("seed", range(4))
def test_scaling_rows_and_units_changes_nothing(seed):
    p = spring_parameters(seed)
    cases = [example_3(**p), example_3(**dict(p, m2=0.0))]  # unique / contradictory-free
    M, Q, _, _ = cases[1]
    cases[1] = (M, Q, np.array([[1.0, -1.0, 0.0], [0.0, 0.0, p["k2"]]]), np.zeros(2))
    pw = wheel_parameters(seed)
    M1, Q1, A1, b = example_1(**pw)
    M2 = np.zeros((3, 3))
    M2[:2, :2] = M1
    cases.append((M2, np.append(Q1, 0.0), np.hstack([A1, [[0.0]]]), b))  # non-unique
    for M, Q, A, b in cases:
        base, rep = constrained_acceleration(M, Q, A, b), rank_report(M, A)
        A_big, b_big = A.copy(), b.copy()
        A_big[0] *= 1e8
        b_big[0] *= 1e8
        for M2_, Q2_, A2_, b2_ in [(M, Q, A_big, b_big), (1e-6 * M, 1e-6 * Q, A, b),
                                   (1e6 * M, 1e6 * Q, A, b), (1e-6 * M, 1e-6 * Q, A_big, b_big)]:
            mo, rep2 = constrained_acceleration(M2_, Q2_, A2_, b2_), rank_report(M2_, A2_)
            assert (rep2.rank_M, rep2.rank_A, rep2.rank_Mhat) == (rep.rank_M, rep.rank_A,
                                                                    rep.rank_Mhat)
            assert mo.unique == base.unique
            assert rel(mo.qdd, base.qdd) < 1e-10


def test_rank_tolerance_is_relative():
    """A mass 1e-9 of the largest is a mass; one below RANK_RTOL of it is not."""
    A = np.array([[1.0, -1.0, 0.0]])
    assert rank_report(np.diag([1.0, 1e-9, 1e-9]), A).unique
    assert rank_report(np.diag([1.0, 1e-9, 0.1 * RANK_RTOL]), A).rank_Mhat == 2
    assert rank_report(np.diag([1e-20, 1e-29, 1e-29]), A).unique  # all tiny, ratio 1e-9
    assert rank_report(np.zeros((3, 3)), np.eye(3)).unique
    assert rank_report(np.zeros((3, 3)), np.zeros((0, 3))).rank_Mhat == 0


def test_forces_that_cancel_are_judged_against_the_terms_not_their_sum():
    """Q + C = −2⁻⁵² Q on a massless coordinate is rounding of the forces involved (1e3), not
    a load no mass resists: the consistency scale is ‖Q‖ + ‖C‖ + ‖M q̈‖; an
    imbalance of 1e-6 of them still is one."""
    Q = np.array([0.0, 1e3])
    motion = constrained_acceleration(np.diag([1.0, 0.0]), Q, np.zeros((0, 2)), np.zeros(0), C=-Q * (1 + 2**-52))
    assert not motion.unique and motion.qdd[0] == 0.0 and motion.nullspace.shape == (2, 1)
    with pytest.raises(SolveError, match="no mass resists"):
        constrained_acceleration(np.diag([1.0, 0.0]), Q, np.zeros((0, 2)), np.zeros(0), C=-Q * (1 + 1e-6))


def test_drift_rule_takes_dependent_rows_in_the_least_squares_sense():
    """Off the manifold (drift given), dependent rows whose b disagrees by the drift give the
    minimum-norm solution of (2.12) with b projected on range(A) in the equilibrated rows
    (each row of A scaled to unit norm; numpy's lstsq) — while on the manifold the same data
    is a contradiction."""
    M, Q = np.diag([2.0, 1.0, 3.0]), np.array([1.0, -2.0, 0.5])
    A = np.array([[1.0, 1.0, 0.0], [0.0, 0.0, 1.0], [2.0, 2.0, 0.0]])
    b = np.array([1.0, 5.0, 2.0 + 1e-6])
    with pytest.raises(SolveError, match="contradictory"):
        constrained_acceleration(M, Q, A, b)
    motion = constrained_acceleration(M, Q, A, b, drift=lambda: (np.full(3, 1e-12), np.ones(3)))
    norms = np.linalg.norm(A, axis=1)
    Ae, be = A / norms[:, None], b / norms
    consistent = norms * (Ae @ np.linalg.lstsq(Ae, be, rcond=None)[0])
    np.testing.assert_allclose(motion.qdd, constrained_acceleration(M, Q, A, consistent).qdd, rtol=1e-12)
    assert motion.singular == ()


def test_drift_rule_sets_aside_a_nearly_dependent_direction_that_amplifies_drift():
    """Rows 1e-9 from dependent (σ ≈ 7e-10) with b off by 1e-7: the minimum-norm solution asks
    ~140 along the nearly dependent direction, 1e2 times the rest of the motion; the drift rule
    sets it aside (Motion.singular names the rows) and keeps the rest, which is the motion
    with the direction removed."""
    M, Q = np.eye(2), np.array([0.0, 1.0])
    A, b = np.array([[1.0, 0.0], [1.0, 1e-9]]), np.array([0.0, 1e-7])
    strict = constrained_acceleration(M, Q, A, b)
    assert np.abs(strict.qdd).max() > 50
    motion = constrained_acceleration(M, Q, A, b, drift=lambda: (np.zeros(2), np.ones(2)))
    assert set(motion.singular) == {"row 0", "row 1"}
    U, s, Vt = np.linalg.svd(A / np.linalg.norm(A, axis=1)[:, None])
    kept = Vt[:1]  # the well-conditioned direction: x₁ held, x₂ free under its load
    np.testing.assert_allclose(motion.qdd, Q - kept.T @ (kept @ Q), atol=1e-6)


@pytest.mark.parametrize("masses", [[1.0, 1e-6, 3.0, 0.5, 2.0], [1.0, 0.0, 3.0, 0.5, 2.0]])
def test_drift_rule_with_full_row_rank_gives_the_kkt_motion(masses):
    """Off the manifold, rows of full rank far from dependent: the drift rule keeps every
    direction and (2.14) is the solution of the KKT equations M q̈ + Aᵀλ = Q, A q̈ = b
    (numpy's solve), for a diagonal M of masses spanning 1e6 (solved without the SVDs of M̂
    and M̄) and for one with a massless coordinate that the rows fix (solved with them)."""
    rng = np.random.default_rng(4)
    M, Q = np.diag(masses), rng.standard_normal(5)
    A, b = rng.standard_normal((3, 5)), rng.standard_normal(3)
    K = np.block([[M, A.T], [A, np.zeros((3, 3))]])
    expected = np.linalg.solve(K, np.concatenate([Q, b]))[:5]
    motion = constrained_acceleration(M, Q, A, b, drift=lambda: (np.full(3, 1e-12), np.ones(5)))
    assert motion.unique and motion.singular == ()
    np.testing.assert_allclose(motion.qdd, expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())
