"""Limits on a spherical joint's swing (a cone) and on a universal joint's two angles
(io/unilateral.py), against the closed form of a compound pendulum's swing in a plane
(models/contact/cone_pendulum.yaml): ω(θ)² = ω_b² − 2k(1 − cos θ), k = m g d / I_p."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

import mbsynth as mb
from mbsynth.core.errors import ModelError

MODEL = Path(__file__).resolve().parents[2] / "models" / "contact" / "cone_pendulum.yaml"
M, G, D, IC, W0, THETA = 1.0, 9.81, 0.5, 0.02, 5.0, 0.6
I_P = IC + M * D**2
K = M * G * D / I_P


def _swing(w_bottom):
    """The time from the bottom to the cone at bottom speed ``w_bottom``."""
    return quad(lambda th: 1 / np.sqrt(w_bottom**2 - 2 * K * (1 - np.cos(th))), 0, THETA, epsabs=1e-14,
                epsrel=1e-13)[0]


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_a_spherical_pendulum_strikes_its_cone_at_the_closed_form_time_and_rebounds_at_e(e):
    """Started hanging at ω0 it strikes the cone at t1 = T(ω0), at ω⁻ = √(ω0² − 2k(1 − cos θ)),
    with the gap's impulse I_p (1 + e) ω⁻ / sin θ (the gap z_A·z_B − cos θ turns at −sin θ θ̇);
    it loses ½ I_p (1 − e²) ω⁻²; with e > 0 it strikes the other side of the cone after
    2 T(ω_b'), ω_b'² = (e ω⁻)² + 2k(1 − cos θ)."""
    system = mb.load(MODEL, parameters={"e": e})
    traj = mb.simulate(system, 1.0, dt=0.01, rtol=1e-11, atol=1e-11)
    impacts = [ev for ev in traj.events if ev.kind == "impact"]
    t1, w_in = _swing(W0), np.sqrt(W0**2 - 2 * K * (1 - np.cos(THETA)))
    assert impacts[0].name == "ball.cone"
    assert impacts[0].t == pytest.approx(t1, rel=1e-9)
    assert impacts[0].impulse == pytest.approx(I_P * (1 + e) * w_in / np.sin(THETA), rel=1e-8)
    after = traj.t > t1
    lost = 0.5 * I_P * (1 - e**2) * w_in**2
    if e < 1:
        assert traj.energy[after][0] == pytest.approx(traj.energy[0] - lost, rel=1e-8)
    else:
        assert np.abs(traj.energy - traj.energy[0]).max() < 1e-8
    if e > 0:
        w_back = np.sqrt((e * w_in) ** 2 + 2 * K * (1 - np.cos(THETA)))
        assert impacts[1].t == pytest.approx(t1 + 2 * _swing(w_back), rel=1e-9)


UNIVERSAL = """name: hooke
parameters: {m: 1.0, g: 9.81}
gravity: [0, 0, -g]
world:
  frames:
    pivot: {position: [0, 0, 0], rpy: [0, -pi/2, 0]}  # z_A = −x, x_A = z
parts:
  arm:
    type: rigid_body
    mass: m
    inertia: [0.01, 0.01, 0.01]
    frames: {top: {position: [0, 0, 0.5], rpy: [0, 0, pi]}}  # x_B = −x: both angles 0 hanging
    initial: {position: [0, 0, -0.5], velocity: [0, 2.0, 0], angular_velocity: [4.0, 0, 0]}
joints:
  - {name: cross, type: universal, parent: world.pivot, child: arm.top, LIMITS}
"""


def test_a_universal_joint_has_a_lower_and_upper_stop_on_each_angle_at_its_values():
    """``limits: [[lo1, hi1], [lo2, hi2]]``: gaps angle1 − lo1, hi1 − angle1, angle2 − lo2,
    hi2 − angle2 (the joint values of model/joint_values.py), named .lower1 … .upper2; a
    swing about z_A = −x (angle1) at 4 rad/s about x strikes its lower stop −0.3 at the
    pendulum's closed-form time."""
    text = UNIVERSAL.replace("LIMITS", "limits: [[-0.3, 0.3], [-0.2, 0.4]], restitution: 1")
    system = mb.loads(text)
    assert [u.name for u in system.unilaterals] == ["cross.lower1", "cross.upper1", "cross.lower2", "cross.upper2"]
    q, qd = system.initial_state()
    p = system.parameter_values
    gaps = [u.row.residuals(0.0, q, qd, p)[0][0] for u in system.unilaterals]
    assert gaps == pytest.approx([0.3, 0.3, 0.2, 0.4], abs=1e-12)  # hanging: both angles 0
    traj = mb.simulate(system, 0.3, dt=0.01, rtol=1e-11, atol=1e-11)
    k = 1.0 * 9.81 * 0.5 / (0.01 + 0.25)
    hit = [ev for ev in traj.events if ev.kind == "impact"][0]
    w0 = 4.0
    expected = quad(lambda th: 1 / np.sqrt(w0**2 - 2 * k * (1 - np.cos(th))), 0, 0.3, epsabs=1e-14)[0]
    assert hit.t == pytest.approx(expected, rel=1e-9)
    assert hit.name == "cross.lower1"


@pytest.mark.parametrize("limits, message", [
    ("limits: [-0.3, 0.3]", "at joints[0].limits[0]: expected a list of 2 numbers or expressions, got float"),
    ("limits: [[0.3, -0.3], [0, 1]]", "at joints[0].limits[0]: lo = 0.3 is above hi = -0.3"),
    ("limits: {cone: 0.5}", "at joints[0].limits: expected a list of 2 numbers or expressions, got a mapping"),
])
def test_bad_universal_limits_are_refused_at_their_line(limits, message):
    with pytest.raises(ModelError) as err:
        mb.loads(UNIVERSAL.replace("LIMITS", limits), name="hooke.yaml")
    assert str(err.value).startswith("hooke.yaml:15: " + message), str(err.value)


@pytest.mark.parametrize("limits, message", [
    ("[-0.5, 0.5]", "at joints[0].limits: expected a mapping"),
    ("{cone: 0}", "at joints[0].limits.cone: a cone's half-angle is in (0, π], got 0"),
    ("{cone: 4}", "at joints[0].limits.cone: a cone's half-angle is in (0, π], got 4"),
    ("{swing: 0.5}", "at joints[0].limits"),
])
def test_bad_cone_limits_are_refused_at_their_line(limits, message):
    text = MODEL.read_text().replace("limits: {cone: theta_max}", f"limits: {limits}")
    with pytest.raises(ModelError) as err:
        mb.loads(text, name="cone.yaml")
    assert str(err.value).startswith("cone.yaml:20: " + message), str(err.value)
