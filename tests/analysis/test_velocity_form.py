"""The integrator's form of the state (analysis/velocity_form.py): each rigid body's
quaternion rates replaced by half its body angular velocity, against tests/helpers/rotations.py's E and a
rotation in closed form; and the tennis-racket flip through ``simulate`` against Euler's
equations."""

from pathlib import Path

import numpy as np
import pytest
import scipy.integrate

import mbsynth as mb
from mbsynth.analysis.velocity_form import VelocityForm
from tests.helpers.rotations import E
from tests.helpers.states import quaternion_of, random_state

ROOT = Path(__file__).resolve().parents[2]


def hamilton(a, b):
    """The quaternion product a ⊗ b (scalar first)."""
    return np.concatenate([[a[0] * b[0] - a[1:] @ b[1:]], a[0] * b[1:] + b[0] * a[1:] + np.cross(a[1:], b[1:])])


@pytest.fixture(scope="module")
def rod():
    """Particles before and after a rigid body: the body's block inside the state."""
    system = mb.load(ROOT / "models" / "mechanisms" / "massless_rod.yaml")
    assert [p.type_name for p in system.parts if p.coordinates][1:4] == ["particle", "rigid_body", "particle"]
    return system


def test_the_integrators_velocities_are_half_each_bodys_angular_velocity_and_convert_back(rod):
    form = VelocityForm(rod)
    rng = np.random.default_rng(5)
    (q, qd), u = random_state(rod, rng, tangent=True), quaternion_of(rod, "rod")
    y = form.to_integrator(q, qd)
    assert y.size == 2 * rod.n - 1
    v = y[rod.n:]
    np.testing.assert_array_equal(y[:rod.n], q)
    np.testing.assert_allclose(v[u.start:u.start + 3], E(q[u]) @ qd[u], rtol=1e-14, atol=1e-15)  # ω = 2 E u̇
    np.testing.assert_array_equal(v[:u.start], qd[:u.start])  # the particles before and after
    np.testing.assert_array_equal(v[u.start + 3:], qd[u.stop:])
    q_back, qd_back = form.to_state(y)
    np.testing.assert_array_equal(q_back, q)
    np.testing.assert_allclose(qd_back, qd, rtol=0, atol=1e-15)
    rows = np.array([y, form.to_integrator(*random_state(rod, rng, tangent=True))])
    q_rows, qd_rows = form.states(rows)
    for row, q_row, qd_row in zip(rows, q_rows, qd_rows):
        np.testing.assert_array_equal(np.concatenate([q_row, qd_row]), form.state(row))
    assert form.represents(y, *form.to_state(y)) and not form.represents(y, q, qd + 1e-9)


def test_a_quaternion_off_unit_norm_keeps_its_norm_and_angular_velocity(rod):
    """u = s û: u̇ = E(u)ᵀ h is tangent (|u| stays) and s times û's rate, so h = ω/2 is û's."""
    form = VelocityForm(rod)
    (q, qd), u = random_state(rod, np.random.default_rng(6), norm=1 + 1e-6, tangent=True), quaternion_of(rod, "rod")
    y = form.to_integrator(q, qd)
    _, qd_back = form.to_state(y)
    assert abs(q[u] @ qd_back[u]) < 1e-15
    unit = q[u] / np.linalg.norm(q[u])
    omega = 2 * E(unit) @ (qd[u] / np.linalg.norm(q[u]))  # the unit quaternion's own
    np.testing.assert_allclose(y[rod.n + u.start:rod.n + u.start + 3], omega / 2, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(form.to_integrator(q, qd_back), y, rtol=1e-14, atol=1e-15)


def test_rates_of_a_body_turning_about_a_body_axis_give_its_angular_acceleration(rod):
    """u(t) = u₀ ⊗ (cos θ/2, sin θ/2 a): the body turns about its own axis a, ω = θ̇ a and
    ω̇ = θ̈ a in closed form (u̇ = ½ u ⊗ (0, ω)); the integrator holds ω/2."""
    form = VelocityForm(rod)
    rng = np.random.default_rng(7)
    (q, qd), u = random_state(rod, rng, tangent=True), quaternion_of(rod, "rod")
    qdd = rng.standard_normal(rod.n)
    u0 = q[u].copy()
    a = np.array([0.3, -0.8, 0.5]) / np.linalg.norm([0.3, -0.8, 0.5])
    theta, theta_d, theta_dd = 0.7, 1.9, -2.3
    half = np.concatenate([[np.cos(theta / 2)], np.sin(theta / 2) * a])
    turned = np.concatenate([[-np.sin(theta / 2)], np.cos(theta / 2) * a])  # d half / dθ × 2
    q[u] = hamilton(u0, half)
    qd[u] = hamilton(u0, theta_d / 2 * turned)
    qdd[u] = hamilton(u0, theta_dd / 2 * turned - theta_d ** 2 / 4 * half)
    y = form.to_integrator(q, qd)
    np.testing.assert_allclose(y[rod.n + u.start:rod.n + u.start + 3], theta_d / 2 * a, rtol=1e-14, atol=1e-14)
    rates = form.rates(y, np.concatenate([form.to_state(y)[1], qdd]))
    np.testing.assert_allclose(rates[rod.n + u.start:rod.n + u.start + 3], theta_dd / 2 * a, rtol=1e-14,
                               atol=1e-14)
    np.testing.assert_allclose(rates[:rod.n], form.to_state(y)[1], rtol=0, atol=0)


def euler_reference(inertia, omega0, times, tolerance):
    """Body angular velocities of a torque-free body at ``times`` from Euler's equations
    (scipy DOP853, rtol = atol = ``tolerance``)."""
    a, b, c = inertia

    def euler(t, w):
        return [(b - c) / a * w[1] * w[2], (c - a) / b * w[2] * w[0], (a - b) / c * w[0] * w[1]]

    solution = scipy.integrate.solve_ivp(euler, (times[0], times[-1]), omega0, method="DOP853", rtol=tolerance,
                                         atol=tolerance, t_eval=times)
    return solution.y.T


@pytest.mark.parametrize("stabilization", ["projection", "baumgarte"])
def test_tennis_racket_flip_follows_eulers_equations_at_the_default_tolerance(stabilization):
    """The intermediate-axis spin turns over twice in 20 s. At the default tolerance (1e-10)
    ω ends within 1e-7 rad/s of Euler's equations (rtol 1e-13), and strays on the way by at
    most a few times what Euler's equations themselves integrated at 1e-10 stray: continuous
    (projection) and cut (Baumgarte) runs alike."""
    system = mb.load(ROOT / "models" / "rigid" / "tennis_racket.yaml")
    p = system.parameters
    traj = mb.simulate(system, 20.0, stabilization=stabilization)
    omega = np.array([2 * E(q[3:]) @ qd[3:] for q, qd in zip(traj.q, traj.qd)])
    omega0, inertia = [0.05, 8.0, 0.05], (p["a"], p["b"], p["c"])  # the model file's initial angular velocity
    np.testing.assert_allclose(omega[0], omega0, rtol=1e-14)
    reference = euler_reference(inertia, omega0, traj.t, 1e-13)
    assert (np.diff(np.sign(reference[:, 1])) != 0).sum() >= 2  # it flips
    error = np.abs(omega - reference).max(axis=1)
    assert error[-1] < 1e-7
    same_tolerance = np.abs(euler_reference(inertia, omega0, traj.t, 1e-10) - reference).max()
    assert error.max() < 5 * same_tolerance
