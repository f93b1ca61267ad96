"""The paper's examples, loaded from models/paper/*.yaml, against its closed forms
(5.17), (5.23), (5.39), (5.47) and (5.56) for several parameter values and states."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb

MODELS = Path(__file__).resolve().parents[2] / "models" / "paper"
RNG = np.random.default_rng(20061)


def load(name):
    return mb.load(MODELS / name)


def random_parameters(count, **ranges):
    for _ in range(count):
        yield {k: float(RNG.uniform(*r)) for k, r in ranges.items()}


def wheel_closed_form(p):
    """(5.17): θ̈ = m g R sinα / (mR² + Ic), ÿ = m g R² sin²α / (mR² + Ic)."""
    s = np.sin(p["alpha"])
    return np.array([p["m"] * p["g"] * p["R"] * s, p["m"] * p["g"] * p["R"] ** 2 * s**2]) / (
        p["m"] * p["R"] ** 2 + p["Ic"])


WHEEL_RANGES = dict(m=(0.5, 5.0), R=(0.1, 1.0), Ic=(0.01, 1.0), g=(9.0, 10.0), alpha=(0.1, 1.4))
SPRING_RANGES = dict(k1=(10.0, 500.0), k2=(10.0, 500.0), l10=(0.5, 2.0), l20=(0.5, 2.0), d=(0.1, 0.5))


@pytest.mark.parametrize("method", ["kkt", "reference"])
def test_example1_wheel_matches_5_17(method):
    base = load("example1_wheel.yaml")
    assert base.coordinates == ("wheel.theta", "wheel.y")
    for p in random_parameters(5, **WHEEL_RANGES):
        system = base.with_parameters(**p)
        q, qd = RNG.normal(size=2), RNG.normal(size=2)
        motion = system.motion(RNG.uniform(0, 5), q, qd, method=method)
        assert motion.unique
        np.testing.assert_allclose(motion.qdd, wheel_closed_form(p), rtol=1e-10)


def test_example1_mass_matrix_is_5_6_and_force_5_7():
    p = dict(m=2.0, R=0.3, Ic=0.09, g=9.81, alpha=0.4)
    arrays = load("example1_wheel.yaml").evaluate(0.0, [0.3, 0.1], [1.0, 2.0])
    np.testing.assert_allclose(arrays.M, [[p["m"] * p["R"] ** 2 + p["Ic"], 0], [0, 0]], atol=1e-14)
    np.testing.assert_allclose(arrays.Q, [0, p["m"] * p["g"]], rtol=1e-14)
    np.testing.assert_allclose(arrays.A, [[-p["R"] * np.sin(p["alpha"]), 1]], rtol=1e-14)  # (5.10)
    np.testing.assert_allclose(arrays.b, [0], atol=1e-14)  # (5.11)


@pytest.mark.parametrize("method", ["kkt", "reference"])
def test_example2_massless_particle_is_free_5_23(method):
    base = load("example2_massless_particle.yaml")
    for p in random_parameters(4, **WHEEL_RANGES):
        motion = base.with_parameters(**p).motion(0.0, RNG.normal(size=3), RNG.normal(size=3), method=method)
        assert not motion.unique
        assert motion.nullspace.shape == (3, 1)
        np.testing.assert_allclose(np.abs(motion.nullspace[:, 0]), [0, 0, 1], atol=1e-12)
        np.testing.assert_allclose(motion.qdd, [*wheel_closed_form(p), 0.0], rtol=1e-10, atol=1e-12)


def two_mass_state(p):
    """A random state; x̄1 = x1 − l10 and q̄2 = q2 − l20 as in (5.26)."""
    q, qd = RNG.normal(size=3), RNG.normal(size=3)
    return q, qd, q[0] - p["l10"], q[2] - p["l20"]


@pytest.mark.parametrize("method", ["kkt", "reference"])
def test_example3_case_5_1_matches_5_39(method):
    base = load("example3_two_masses.yaml")
    for p in random_parameters(6, m1=(0.2, 5.0), m2=(0.2, 5.0), **SPRING_RANGES):
        q, qd, x1bar, q2bar = two_mass_state(p)
        motion = base.with_parameters(**p).motion(0.0, q, qd, method=method)
        a = (-p["k1"] * x1bar + p["k2"] * q2bar) / p["m1"]
        assert motion.unique
        np.testing.assert_allclose(motion.qdd, [a, a, -a - p["k2"] * q2bar / p["m2"]], rtol=1e-10)


@pytest.mark.parametrize("name", ["example3_m1_zero.yaml", "example3_m1_zero_auto.yaml"])
@pytest.mark.parametrize("method", ["kkt", "reference"])
def test_example3_case_5_2_matches_5_47(name, method):
    base = load(name)
    assert base.parameters["m1"] == 0.0
    for p in random_parameters(6, m2=(0.2, 5.0), **SPRING_RANGES):
        q, qd, x1bar, q2bar = two_mass_state(p)
        motion = base.with_parameters(**p).motion(0.0, q, qd, method=method)
        k1, k2, s = p["k1"], p["k2"], x1bar + q2bar
        expected = np.array([-k1 * k2**2 * s, -k1 * k2**2 * s, -k1**2 * k2 * s]) / (p["m2"] * (k1 + k2) ** 2)
        assert motion.unique
        np.testing.assert_allclose(motion.qdd, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
        # (5.48) with its sign projected: m2 ẍ2 = −k1 k2 / (k1 + k2) · (x̄1 + q̄2), springs in series
        np.testing.assert_allclose(motion.qdd[1] + motion.qdd[2], -k1 * k2 / (k1 + k2) * s / p["m2"], rtol=1e-9)


@pytest.mark.parametrize("name", ["example3_m2_zero.yaml", "example3_m2_zero_auto.yaml"])
@pytest.mark.parametrize("method", ["kkt", "reference"])
def test_example3_case_5_3_matches_5_56(name, method):
    base = load(name)
    assert base.parameters["m2"] == 0.0
    for p in random_parameters(6, m1=(0.2, 5.0), **SPRING_RANGES):
        q, qd, x1bar, _ = two_mass_state(p)
        motion = base.with_parameters(**p).motion(0.0, q, qd, method=method)
        a = -p["k1"] * x1bar / p["m1"]
        assert motion.unique
        np.testing.assert_allclose(motion.qdd, [a, a, 0.0], rtol=1e-10, atol=1e-12 * abs(a))


def test_balances_auto_appends_the_papers_balances():
    """balances: auto derives (5.40) for m1 = 0 and (5.49) for m2 = 0 (up to a factor)."""
    m1_zero = load("example3_m1_zero_auto.yaml")
    m2_zero = load("example3_m2_zero_auto.yaml")
    assert len(m1_zero.appended_balances) == len(m2_zero.appended_balances) == 1
    q = np.array([1.3, 0.4, 0.7])
    for system, expected in ((m1_zero, lambda p: p["k1"] * (q[0] - p["l10"]) - p["k2"] * (q[2] - p["l20"])),
                             (m2_zero, lambda p: p["k2"] * (q[2] - p["l20"]))):
        phi, _ = system.constraint_residuals(0.0, q, np.zeros(3))
        ratio = phi[-1] / expected(system.parameters)
        assert abs(abs(ratio) - 1) < 1e-12, ratio  # wᵀQ with w scaled so its largest entry is ±1
