"""solvers.kkt_acceleration against the reference (2.14), an unscaled numpy KKT solve, and,
where it falls back to the reference, (2.14) written out in numpy (``literal_2_14``) and
the numbers the errors must carry."""

import numpy as np
import pytest

from mbsynth.core.equations import constrained_acceleration
from mbsynth.core.errors import SolveError
from mbsynth.core.solvers import kkt_acceleration

from tests.helpers.compare import rel
from tests.helpers.literal import literal_2_14


def unique_problem(rng, n, singular):
    """M ⪰ 0 (rank r < n when ``singular``) with m ≥ n − r generic rows: [M; A] full rank.

    Draws whose KKT matrix has condition number above 1e6 are redrawn: both methods then
    carry errors ~cond · ε, too large for the 1e-10 agreement asserted below."""
    while True:
        M, Q, A, b, C = _draw(rng, n, singular)
        m = len(b)
        if np.linalg.cond(np.block([[M, A.T], [A, np.zeros((m, m))]])) < 1e6:
            return M, Q, A, b, C


def _draw(rng, n, singular):
    r = int(rng.integers(0, n)) if singular else n
    L = rng.standard_normal((n, r))
    M = L @ L.T + (0 if singular else 0.1 * np.eye(n))
    m = int(rng.integers(n - r if singular else 0, n + 1))
    m = max(m, 1) if singular else m
    A = rng.standard_normal((m, n))
    return M, rng.standard_normal(n), A, rng.standard_normal(m), rng.standard_normal(n)


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("singular", [True, False])
def test_kkt_agrees_with_reference_on_unique_problems(seed, singular):
    rng = np.random.default_rng(seed + (1000 if singular else 0))
    n = int(rng.integers(1, 12))
    M, Q, A, b, C = unique_problem(rng, n, singular)
    fast = kkt_acceleration(M, Q, A, b, C)
    ref = constrained_acceleration(M, Q, A, b, C)
    assert fast.method == "kkt"
    assert ref.unique and fast.unique and fast.nullspace.shape == (n, 0)
    assert rel(fast.qdd, ref.qdd) < 1e-10
    assert rel(fast.Qc, ref.Qc) < 1e-9
    assert fast.residual < 1e-13
    # the KKT system of the brief, unscaled, solved by numpy
    m = len(b)
    K = np.block([[M, A.T], [A, np.zeros((m, m))]])
    assert rel(fast.qdd, np.linalg.solve(K, np.concatenate([Q + C, b]))[:n]) < 1e-9


def test_kkt_paper_example_3_case_5_2():
    k1, k2, m2, x1, q2 = 3.0, 5.0, 2.0, 0.2, -0.7
    M = np.array([[0, 0, 0], [0, m2, m2], [0, m2, m2]], dtype=float)
    Q = np.array([-k1 * x1, 0.0, -k2 * q2])
    A = np.array([[1.0, -1.0, 0.0], [k1, 0.0, -k2]])
    mo = kkt_acceleration(M, Q, A, np.zeros(2))
    s = (x1 + q2) / (m2 * (k1 + k2) ** 2)
    assert mo.method == "kkt"
    assert rel(mo.qdd, [-k1 * k2**2 * s, -k1 * k2**2 * s, -k1**2 * k2 * s]) < 1e-12  # (5.47)


def wheel_with_particle(force_on_x=0.0):
    m, R, Ic, g, alpha = 2.0, 0.3, 0.09, 9.81, 0.4
    M = np.diag([m * R**2 + Ic, 0.0, 0.0])  # (5.18)
    A = np.array([[-R * np.sin(alpha), 1.0, 0.0]])  # (5.19)
    Q = np.array([0.0, m * g, force_on_x])  # (5.20), plus a force on x
    expected = np.array([m * g * R * np.sin(alpha), m * g * (R * np.sin(alpha)) ** 2, 0.0])
    return M, Q, A, np.zeros(1), expected / (m * R**2 + Ic)


def test_kkt_falls_back_when_not_unique():
    M, Q, A, b, expected = wheel_with_particle()
    mo = kkt_acceleration(M, Q, A, b)
    assert mo.method == "pseudoinverse (2.14)"
    assert not mo.unique
    assert np.allclose(np.abs(mo.nullspace[:, 0]), [0, 0, 1], atol=1e-12)
    assert rel(mo.qdd, expected) < 1e-12  # (5.23), η = 0


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("singular", [True, False])
def test_kkt_falls_back_on_dependent_rows(seed, singular):
    rng = np.random.default_rng(seed)
    M, Q, A, b, C = unique_problem(rng, 6, singular)
    A2 = np.vstack([A, 2 * A[:1] if len(b) else np.ones((2, 6))])
    b2 = np.concatenate([b, 2 * b[:1] if len(b) else np.ones(2)])
    mo = kkt_acceleration(M, Q, A2, b2, C)
    assert mo.method == "pseudoinverse (2.14)"
    assert rel(mo.qdd, literal_2_14(M, Q, A2, b2, C)) < 1e-9
    if len(b):  # the duplicate changes nothing
        assert rel(mo.qdd, kkt_acceleration(M, Q, A, b, C).qdd) < 1e-10


def test_forced_fallback_gives_the_reference():
    rng = np.random.default_rng(3)
    M, Q, A, b, C = unique_problem(rng, 5, singular=True)
    mo = kkt_acceleration(M, Q, A, b, C, rcond_min=2.0)  # rcond ≤ 1 always
    assert mo.method == "pseudoinverse (2.14)"
    assert rel(mo.qdd, literal_2_14(M, Q, A, b, C)) < 1e-9
    m = len(b)  # unique: the unscaled KKT solve is the same q̈
    K = np.block([[M, A.T], [A, np.zeros((m, m))]])
    assert rel(mo.qdd, np.linalg.solve(K, np.concatenate([Q + C, b]))[:len(Q)]) < 1e-9


def error_of(solve, *args, **kwargs):
    with pytest.raises(SolveError) as info:
        solve(*args, **kwargs)
    return str(info.value), info.value.constraints, info.value.coordinates


def test_kkt_raises_the_errors_of_2_14():
    """The conditions of equations.constrained_acceleration's docstring, with the numbers
    they must report: the force 0.5 on the massless x, which no mass resists; the part of
    b outside the range of A (rows scaled to unit norm), (0, 1) / |a| less its projection
    on (1, 1) / √2; a NaN in Q."""
    M, Q, A, b, _ = wheel_with_particle(force_on_x=0.5)
    names = dict(coordinates=["theta", "y", "x"], constraints=["rolling"])
    message, constraints, coordinates = error_of(kkt_acceleration, M, Q, A, b, **names)
    assert coordinates == ("x",) and "no mass resists: wᵀ(Q + C) = 0.5 ≠ 0" in message
    A2, b2 = np.vstack([A, A]), np.array([0.0, 1.0])
    names = dict(coordinates=["theta", "y", "x"], constraints=["rolling", "again"])
    message, constraints, coordinates = error_of(kkt_acceleration, np.eye(3), Q, A2, b2, **names)
    outside = 1 / np.linalg.norm(A) / np.sqrt(2)
    assert constraints == ("rolling", "again") and f"component of norm {outside:.3g} outside the range" in message
    Q_nan = np.array([0.0, np.nan, 0.0])
    message, _, coordinates = error_of(kkt_acceleration, np.eye(3), Q_nan, A, b, **dict(names, constraints=["r"]))
    assert coordinates == ("y",) and message.startswith("Q")
