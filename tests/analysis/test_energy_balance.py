"""The work of the forces that derive from no potential (dampers, friction, actuation) is
integrated along a run (``Trajectory.work``, ``Data.power``): the change of T + V beyond it
is the integrator's drift. Checked against the damped oscillator's exact solution."""

import numpy as np
import pytest

import mbsynth as mb

M, K, C, X0 = 1.0, 40.0, 0.8, 0.1  # m ẍ + c ẋ + k x = 0, from x = X0 at rest: underdamped

LAGRANGIAN = f"""
name: damped_oscillator
parameters: {{m: {M}, k: {K}, c: {C}}}
parts:
  mass:
    type: lagrangian
    coordinates: [x]
    T: 0.5*m*x_dot**2
    V: 0.5*k*x**2
    forces: {{x: -c*x_dot}}
initial: {{mass.x: {X0}}}
"""

SLIDER = """
name: damped_slider
parameters: {{m: {m}, k: {k}, c: {c}}}
world: {{frames: {{rail: {{axis: [1, 0, 0]}}}}}}
parts:
  block:
    type: rigid_body
    mass: m
    inertia: [0.01, 0.01, 0.01]
    frames: {{rail: {{axis: [1, 0, 0]}}}}
    initial: {{position: [{x0}, 0, 0]}}
joints:
  - {{name: slide, type: prismatic, parent: world.rail, child: block.rail, {law}}}
"""
JOINT_DAMPER = SLIDER.format(m=M, k=K, c=C, x0=X0, law="spring: {stiffness: k, damping: c, rest: 0}")
VISCOUS_FRICTION = SLIDER.format(m=M, k=K, c=C, x0=X0, law="spring: {stiffness: k, rest: 0}, friction: {viscous: c}")


def exact_energy(t):
    """T + V of the exact motion x(t) = e^(−ζω t)(X0 cos ω_d t + B sin ω_d t)."""
    omega = np.sqrt(K / M)
    zeta = C / (2 * np.sqrt(K * M))
    decay, omega_d = zeta * omega, omega * np.sqrt(1 - zeta ** 2)
    B = decay * X0 / omega_d
    e, c, s = np.exp(-decay * t), np.cos(omega_d * t), np.sin(omega_d * t)
    x = e * (X0 * c + B * s)
    v = e * (-decay * (X0 * c + B * s) + omega_d * (-X0 * s + B * c))
    return 0.5 * M * v ** 2 + 0.5 * K * x ** 2


@pytest.mark.parametrize("text", [LAGRANGIAN, JOINT_DAMPER, VISCOUS_FRICTION],
                         ids=["generalized_force", "joint_damper", "viscous_friction"])
def test_damped_oscillator_dissipates_what_the_exact_motion_loses(tmp_path, text):
    """Over 2 s (about two periods; a third of the energy left) the work of the damper
    equals the exact solution's energy loss, and T + V changes by that work alone."""
    path = tmp_path / "model.yaml"
    path.write_text(text)
    system = mb.load(path)
    assert system.working_forces() and system.unaccounted_work() == []
    traj = mb.simulate(system, 2.0)
    lost = exact_energy(2.0) - exact_energy(0.0)
    assert lost < -0.5 * exact_energy(0.0)
    assert traj.work[-1] == pytest.approx(lost, rel=1e-6)
    np.testing.assert_allclose(traj.work, exact_energy(traj.t) - exact_energy(0.0), atol=1e-7 * exact_energy(0.0))
    assert traj.energy_drift < 1e-7


def test_a_constant_torque_does_its_work_and_a_zero_one_none():
    """The driven pendulum without its damper: at tau0 = 0 (a Data's values) nothing works
    (no power recorded, T + V conserved); at tau0 = 0.4 the recorded work is tau0·Δθ, the
    work of a constant torque through the hinge's turn."""
    from pathlib import Path

    from mbsynth.model.joint_values import along

    path = Path(__file__).resolve().parents[2] / "models" / "joints" / "driven_pendulum.yaml"
    system = mb.load(path, parameters={"A": 0.0, "c": 0.0})
    data = system.data()
    data.set_parameters({"tau0": 0.0})
    assert data.model.working_forces(data.parameter_values) == []
    idle = mb.simulate(data, 1.0)
    assert not np.any(idle.power) and idle.energy_drift < 1e-8
    data.set_parameters({"tau0": 0.4})
    assert data.model.working_forces(data.parameter_values) == ["hinge.actuation"]
    driven = mb.simulate(data, 1.0)
    angle = along(data, driven.t, driven.q, driven.qd)["hinge"].position[:, 0]
    turned = angle - angle[0]
    assert np.ptp(turned) > 0.3
    np.testing.assert_allclose(driven.work, 0.4 * turned, atol=1e-7)
    np.testing.assert_allclose(driven.energy - driven.energy[0], driven.work, atol=1e-7)


@pytest.mark.parametrize("model", ["joints/driven_pendulum.yaml", "joints/pd_pendulum.yaml", "mechanisms/andrews.yaml",
                                   "flexible/cantilever.yaml"])
def test_power_over_many_rows_is_the_power_at_each(model):
    """``Data.powers`` (the recorder's: a compiled power called once over the rows where it
    broadcasts) equals ``Data.power`` state by state, at states along a run, twice (the
    second call on the path the first one chose)."""
    from pathlib import Path

    system = mb.load(Path(__file__).resolve().parents[2] / "models" / model)
    data = system.data()
    traj = mb.simulate(data, 0.01, rtol=1e-8, atol=1e-8)
    one_by_one = np.array([data.power(t, q, qd) for t, q, qd in zip(traj.t, traj.q, traj.qd)])
    assert np.abs(one_by_one).max() > 1e-6  # the models' forces work along the run
    for _ in range(2):
        np.testing.assert_allclose(data.powers(traj.t, traj.q, traj.qd), one_by_one, rtol=1e-12,
                                   atol=1e-12 * np.abs(one_by_one).max())
