"""Equilibrium, linearization and modes (statics.py, linearization.py, modal.py) against
independent numbers: closed forms of the paper's example 3, a double pendulum, a
parallelogram four-bar and a pendulum in Cartesian coordinates, and Pinocchio's
analytical derivatives of robots (validate_modes.py)."""

import json

from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import mbsynth as mb
from mbsynth.analysis.modes import format_modes, mode_motion, to_dict
from mbsynth.cli import main
from mbsynth.robots.validate_modes import eigenvalue_error, validate_modes

REL = 1e-9


def omegas(result):
    """The angular natural frequencies of the vibration modes."""
    return np.sort([2 * np.pi * m.frequency for m in result.modes if m.kind == "vibration"])


# -- the paper's example 3 with a massless node --------------------------------------------

def test_example3_massless_node_single_mode():
    """m1 = 0: the node between k1 and k2 balances (5.40); m2 on the springs in series,
    ω² = k1 k2 / ((k1 + k2) m2); equilibrium at the springs' rest lengths."""
    system = mb.load("models/paper/example3_m1_zero_auto.yaml")
    p = system.parameters
    result = mb.modes(system, equilibrium=True)
    expected = np.sqrt(p["k1"] * p["k2"] / ((p["k1"] + p["k2"]) * p["m2"]))
    assert result.linearization.k == 1
    assert omegas(result) == pytest.approx([expected], rel=REL)
    assert result.modes[0].damping_ratio == pytest.approx(0.0, abs=1e-12)
    q = dict(zip(system.coordinates, result.q))
    assert q["body1.x1"] == pytest.approx(p["l10"], rel=REL)
    assert q["body2.q2"] == pytest.approx(p["l20"], rel=REL)
    assert q["body2.q1"] == pytest.approx(p["l10"] + p["d"], rel=REL)
    shape = dict(zip(system.coordinates, result.modes[0].shape.real))  # the node moves k2/(k1+k2) of m2
    assert shape["body1.x1"] / (shape["body2.q1"] + shape["body2.q2"]) == pytest.approx(
        p["k2"] / (p["k1"] + p["k2"]), rel=REL)


def test_example3_massless_spring_end():
    """m2 = 0: the free spring k2 is slack (5.49) and m1 swings on k1 alone: ω² = k1/m1."""
    system = mb.load("models/paper/example3_m2_zero_auto.yaml")
    result = mb.modes(system, equilibrium=True)
    assert omegas(result) == pytest.approx([np.sqrt(system.parameters["k1"] / system.parameters["m1"])], rel=REL)


def test_massless_node_without_its_balance_is_refused():
    """Without the balance the massless node is indeterminate: a verdict, no spectrum."""
    with open("models/paper/example3_m1_zero_auto.yaml") as f:
        text = f.read().replace("balances: auto", "")
    system = mb.loads(text)
    q = np.array([1.0, 1.2, 0.8])
    with pytest.raises(mb.SolveError, match="not unique|no motion|balance"):
        mb.linearize(system, 0.0, q, np.zeros(3))


def test_massless_link_with_free_spin_is_refused():
    """A massless rigid link between spherical joints spins freely about its axis."""
    system = mb.load("models/mechanisms/massless_link.yaml")
    q, qd = system.initial_state()
    with pytest.raises(mb.SolveError, match="not unique"):
        mb.linearize(system, 0.0, q, np.zeros_like(qd))


# -- a double pendulum of particles on massless rods ------------------------------------------

DOUBLE = (Path(__file__).resolve().parents[2] / "models" / "mechanisms" / "double_pendulum_rods.yaml").read_text()


def test_double_pendulum_on_distance_joints():
    """Equal masses and lengths: ω² = (2 ∓ √2) g/l, each in two planes of swing."""
    system = mb.loads(DOUBLE)
    p = system.parameters
    result = mb.modes(system, equilibrium=True)
    q = dict(zip(system.coordinates, result.q))
    assert q["p2.z"] == pytest.approx(-2 * p["l"], rel=REL)  # hanging straight down
    slow, fast = np.sqrt((2 - np.sqrt(2)) * p["g"] / p["l"]), np.sqrt((2 + np.sqrt(2)) * p["g"] / p["l"])
    assert result.linearization.k == 4
    assert omegas(result) == pytest.approx([slow, slow, fast, fast], rel=REL)
    assert result.stable


DAMPED = """
name: damped_bob
parameters: {m: 1.2, k: 80.0, l0: 0.5, c: 1.5, g: 9.81}
gravity: [0, 0, -g]
world: {frames: {anchor: {position: [0, 0, 0]}}}
parts:
  bob: {type: particle, mass: m, initial: {position: [0.05, 0.02, -0.6]}}
forces:
  - {name: spring, type: spring, between: [world.anchor, bob], stiffness: k, rest_length: l0, damping: c}
"""


def test_damped_spring_pendulum():
    """A bob on a spring-damper: bouncing at ω² = k/m with ζ = c/(2√(km)); swinging, as a
    pendulum of the stretched length l0 + mg/k, undamped (the damper acts along the spring,
    whose length a small swing does not change)."""
    system = mb.loads(DAMPED)
    p = system.parameters
    result = mb.modes(system, equilibrium=True)
    swing = np.sqrt(p["g"] / (p["l0"] + p["m"] * p["g"] / p["k"]))
    assert [m.kind for m in result.modes] == ["vibration"] * 3
    assert 2 * np.pi * result.frequencies == pytest.approx([swing, swing, np.sqrt(p["k"] / p["m"])], rel=REL)
    assert result.damping_ratios == pytest.approx([0, 0, p["c"] / (2 * np.sqrt(p["k"] * p["m"]))], rel=REL, abs=1e-12)
    assert result.stable


# -- a four-bar: a parallelogram, its coupler translating -----------------------------------

def parallelogram(crank_angle):
    """A parallelogram four-bar in the x-y plane, gravity along −y: cranks of length a at
    O = (0, 0) and D = (d, 0) at ``crank_angle`` from hanging straight down, the coupler
    (length d) joining their ends."""
    return f"""
name: parallelogram
parameters: {{a: 0.4, d: 1.1, m1: 0.5, m2: 1.2, m3: 0.9, I2: 0.15, g: 9.81, th: {crank_angle!r}}}
gravity: [0, -g, 0]
world: {{frames: {{O: {{position: [0, 0, 0]}}, D: {{position: [d, 0, 0]}}}}}}
parts:
  crank:
    type: planar_body
    mass: m1
    inertia: m1*a**2/12
    frames: {{O: {{position: [-a/2, 0, 0]}}, B: {{position: [a/2, 0, 0]}}}}
    initial: {{position: [a/2*sin(th), -a/2*cos(th)], theta: th - pi/2}}
  coupler:
    type: planar_body
    mass: m2
    inertia: I2
    frames: {{B: {{position: [-d/2, 0, 0]}}, C: {{position: [d/2, 0, 0]}}}}
    initial: {{position: [d/2 + a*sin(th), -a*cos(th)], theta: 0}}
  rocker:
    type: planar_body
    mass: m3
    inertia: m3*a**2/12
    frames: {{D: {{position: [-a/2, 0, 0]}}, C: {{position: [a/2, 0, 0]}}}}
    initial: {{position: [d + a/2*sin(th), -a/2*cos(th)], theta: th - pi/2}}
joints:
  - {{name: ground_O, type: revolute, parent: world.O, child: crank.O}}
  - {{name: crank_coupler, type: revolute, parent: crank.B, child: coupler.B}}
  - {{name: coupler_rocker, type: revolute, parent: coupler.C, child: rocker.C}}
  - {{name: ground_D, type: revolute, parent: world.D, child: rocker.D}}
"""


def test_four_bar_single_mode():
    """The cranks swing together and the coupler translates: with θ the cranks' angle,
    T = ½ (m1 a²/3 + m3 a²/3 + m2 a²) θ̇², V = −(m1/2 + m3/2 + m2) g a cos θ, so
    ω² = (m1/2 + m3/2 + m2) g a / (m1 a²/3 + m3 a²/3 + m2 a²)."""
    system = mb.loads(parallelogram(0.3))
    p = system.parameters
    a, g, m1, m2, m3 = p["a"], p["g"], p["m1"], p["m2"], p["m3"]
    result = mb.modes(system, equilibrium=True)
    expected = np.sqrt((m1 / 2 + m3 / 2 + m2) * g * a / (m1 * a**2 / 3 + m3 * a**2 / 3 + m2 * a**2))
    assert result.linearization.k == 1
    assert omegas(result) == pytest.approx([expected], rel=REL)
    joints = result.modes[0].joint_shape  # both cranks turn alike, the coupler does not turn
    assert joints["ground_O"][0] == pytest.approx(joints["ground_D"][0], rel=REL)
    assert abs(joints["ground_O"][0]) > 0
    assert joints["crank_coupler"][0] == pytest.approx(-joints["ground_O"][0], rel=REL)


def test_mode_motion_stays_on_the_constraints():
    """The animation of the four-bar's mode: every frame on the loop's constraints, the
    crank swinging by about the amplitude, back where it started after whole periods."""
    system = mb.loads(parallelogram(0.3))
    result = mb.modes(system, equilibrium=True)
    motion = mode_motion(system, result, 0, amplitude=0.01, periods=1, frames=21)
    for q in motion.q:
        assert np.abs(system.constraint_residuals(0.0, q, 0 * q)[0]).max() < 1e-10
    swing = np.ptp(motion.column(result.linearization.state_names[0]))
    assert swing == pytest.approx(0.02, rel=1e-2)
    assert motion.q[-1] == pytest.approx(motion.q[0], abs=1e-10)


@pytest.mark.parametrize("offset", [0.0, 1e-7])
def test_four_bar_at_and_near_its_change_point(offset):
    """All four links in line (cranks horizontal): the loop's rows are dependent there
    (a change point): a verdict, not a spectrum with a spurious degree of freedom."""
    system = mb.loads(parallelogram(np.pi / 2 + offset))
    q, qd = system.initial_state()
    with pytest.raises(mb.SolveError, match="singular position"):
        mb.linearize(system, 0.0, q, qd)


# -- a pendulum in Cartesian coordinates, linearized while it moves --------------------------

CARTESIAN = """
name: cartesian_pendulum
parameters: {m: 0.8, l: 1.3, g: 9.81}
parts:
  bob:
    type: lagrangian
    coordinates: [x, z]
    T: 0.5*m*(x_dot**2 + z_dot**2)
    V: m*g*z
constraints:
  - {name: rod, holonomic: bob.x**2 + bob.z**2 - l**2}
"""


def test_linearization_while_moving_matches_the_reduced_equation():
    """With u = x independent, z = −√(l² − u²) and the pendulum's equation give
    ü = −g (u/l)√(1 − u²/l²) − u u̇²/(l² − u²); its exact derivatives (sympy, here) are
    the second row of A at a moving state."""
    system = mb.loads(CARTESIAN)
    p = system.parameters
    l, g = p["l"], p["g"]
    theta, rate = 0.4, 1.7
    q = np.array([l * np.sin(theta), -l * np.cos(theta)])
    qd = np.array([l * np.cos(theta), l * np.sin(theta)]) * rate
    lin = mb.linearize(system, 0.0, q, qd)
    assert lin.state_names == ("bob.x", "bob.x_dot")
    u, v = sp.symbols("u v")
    udd = -g * (u / l) * sp.sqrt(1 - u**2 / l**2) - u * v**2 / (l**2 - u**2)
    at = {u: q[0], v: qd[0]}
    expected = [float(sp.diff(udd, u).subs(at)), float(sp.diff(udd, v).subs(at))]
    assert lin.A[0] == pytest.approx([0.0, 1.0], abs=1e-12)
    assert lin.A[1] == pytest.approx(expected, rel=1e-9)
    assert lin.qdd[0] == pytest.approx(float(udd.subs(at)), rel=1e-9)


def test_state_off_the_constraints_is_refused():
    system = mb.loads(CARTESIAN)
    with pytest.raises(mb.SolveError, match="off the constraints"):
        mb.linearize(system, 0.0, np.array([0.5, -1.0]), np.zeros(2))


# -- equilibrium verdicts --------------------------------------------------------------------

FREE = """
name: drifting
parameters: {m: 1.0, g: 0.0}
gravity: [0, 0, -g]
parts:
  p: {type: particle, mass: m}
"""


def test_equilibrium_not_isolated_names_the_free_directions():
    with pytest.raises(mb.NoEquilibrium, match="not isolated") as err:
        mb.equilibrium(mb.loads(FREE))
    assert set(err.value.coordinates) == {"p.x", "p.y", "p.z"}


def test_no_equilibrium_found():
    """A particle under gravity falls for ever: a verdict (NoEquilibrium, exit 1), naming
    the coordinate it keeps accelerating along at g."""
    with pytest.raises(mb.NoEquilibrium, match=r"no static equilibrium found .*after 5 steps .*largest q̈ -9\.81 "
                                               r"along p\.z") as err:
        mb.equilibrium(mb.loads(FREE.replace("g: 0.0", "g: 9.81")), max_iterations=5)
    assert err.value.coordinates == ("p.z",)


# -- the rest nearest the start: closed forms, energy, Pinocchio ------------------------------

MODELS = Path(__file__).resolve().parents[2] / "models"


def hanging_potential(p):
    """V of the double pendulum hanging straight down (its minimum): links of mass m1, m2
    and length L1, L2, centres at mid-length, from the pivot."""
    return -p["g"] * (p["m1"] * p["L1"] / 2 + p["m2"] * (p["L1"] + p["L2"] / 2))


@pytest.mark.parametrize("start", [(0.6, -0.9), (np.pi - 0.3, 0.2), (-2.5, 1.0)])
def test_equilibrium_goes_down_to_the_hanging_double_pendulum(start):
    """From (0.6, −0.9) rad (the model's start; a Newton iteration on q̈ = 0 alone went up
    to the upright (π, −2π)), from near upright and from the other side: the hanging rest,
    (0, 0) mod 2π, where V is its minimum."""
    system = mb.load(MODELS / "rigid" / "double_pendulum_angles.yaml")
    q = mb.equilibrium(system, np.array(start))
    wrapped = (q + np.pi) % (2 * np.pi) - np.pi
    assert wrapped == pytest.approx([0.0, 0.0], abs=1e-9)
    assert system.energy(0.0, q, np.zeros(2))[1] == pytest.approx(hanging_potential(system.parameters), rel=1e-12)


def test_equilibrium_started_at_an_unstable_rest():
    """Started exactly upright, the pendulum rests, unstably (its modes say so): with
    ``nearest=True`` that rest is the answer; by default, a stable rest, the hanging one."""
    system = mb.load(MODELS / "rigid" / "double_pendulum_angles.yaml")
    upright = np.array([np.pi, 0.0])
    assert mb.equilibrium(system, upright, nearest=True) == pytest.approx(upright, abs=1e-12)
    assert mb.modes(system, upright).verdict.kind == "unstable"
    q = mb.equilibrium(system, upright)
    assert (q + np.pi) % (2 * np.pi) - np.pi == pytest.approx([0.0, 0.0], abs=1e-9)
    assert system.energy(0.0, q, np.zeros(2))[1] == pytest.approx(hanging_potential(system.parameters), rel=1e-12)


def test_modes_equilibrium_command_of_the_double_pendulum(capsys):
    """The user's ``mbsynth modes models/rigid/double_pendulum_angles.yaml --equilibrium``:
    the hanging rest, stable, two vibration modes."""
    assert main(["modes", str(MODELS / "rigid" / "double_pendulum_angles.yaml"), "--equilibrium", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert list(result["q"].values()) == pytest.approx([0.0, 0.0], abs=1e-9)
    assert result["stable"] and [m["kind"] for m in result["modes"]] == ["vibration", "vibration"]


def test_equilibrium_of_the_spatial_double_pendulum_in_body_coordinates():
    """double_pendulum_3d.yaml (14 body coordinates; Newton's steps on q̈ = 0 stalled after
    50): both links hang below the pivot at (0, 0, 2), V at its minimum, and vibrate there
    as the same pendulum in its two angles does."""
    system = mb.load(MODELS / "rigid" / "double_pendulum_3d.yaml")
    p = system.parameters
    q = dict(zip(system.coordinates, mb.equilibrium(system)))
    centres = [[q[f"{link}.{c}"] for c in "xyz"] for link in ("link1", "link2")]
    assert centres == [pytest.approx([0, 0, 2 - p["L1"] / 2], abs=1e-9),
                       pytest.approx([0, 0, 2 - p["L1"] - p["L2"] / 2], abs=1e-9)]
    V = system.energy(0.0, np.array(list(q.values())), np.zeros(system.n))[1]
    assert V == pytest.approx(hanging_potential(p) + 2 * p["g"] * (p["m1"] + p["m2"]), rel=1e-12)
    angles = mb.modes(mb.load(MODELS / "rigid" / "double_pendulum_angles.yaml"), equilibrium=True)
    assert omegas(mb.modes(system, equilibrium=True)) == pytest.approx(omegas(angles), rel=1e-9)  # the same pendulum


UR5_HELD = """
name: ur5_hanging
parameters: {g: 9.81}
gravity: [0, 0, -g]
parts:
  arm: {type: robot, robot: ur5, base: {position: [0, 0, 1]},
        initial: {shoulder_lift_joint: -0.5, elbow_joint: 0.7, wrist_2_joint: 0.4}}
constraints:   # the joints about vertical axes at the rest, held (free there: no isolated rest)
  - {name: pan, holonomic: arm_shoulder_pan_joint.angle}
  - {name: wrist, holonomic: arm_wrist_2_joint.angle - 0.4}
  - {name: twist, holonomic: arm_wrist_3_joint.angle}
"""


@pytest.mark.slow  # a UR5's equilibrium search and modes
def test_ur5_comes_to_rest_where_pinocchio_gravity_torques_vanish():
    """A UR5 released at a bent pose, zero torques, its vertical-axis joints held: the rest
    found is where Pinocchio's generalized gravity (rnea at q̇ = q̈ = 0) is zero at every
    joint left free, a stable one (all modes vibrate), lower in V than the start."""
    pin = pytest.importorskip("pinocchio")
    from mbsynth.robots.build import describe
    system = mb.loads(UR5_HELD)
    q = mb.equilibrium(system)
    values = system.joint_values(0.0, q, np.zeros(system.n))
    model = pin.buildModelFromUrdf(describe("ur5").path)
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    angles = np.array([float(np.atleast_1d(values[f"arm_{model.names[j]}"].position)[0])
                       for j in range(1, model.njoints)])
    tau = pin.computeGeneralizedGravity(model, model.createData(), angles)
    start = pin.computeGeneralizedGravity(model, model.createData(), np.array([0, -0.5, 0.7, 0, 0.4, 0]))
    free = [list(model.names)[1:].index(j) for j in ("shoulder_lift_joint", "elbow_joint", "wrist_1_joint")]
    assert np.abs(tau[free]).max() < 1e-9 * np.abs(start).max()
    assert mb.modes(system, q).stable and {m.kind for m in mb.modes(system, q).modes} == {"vibration"}
    assert system.energy(0.0, q, np.zeros(system.n))[1] < system.energy(0.0, system.initial_q, np.zeros(system.n))[1]


# -- refusals: NaN input, time-dependent rows at a moving state -------------------------------

def test_nan_or_inf_input_is_named():
    """NaN in q was reported as "rows ['rod'] restrict velocities … (non-holonomic …)"."""
    system = mb.loads(CARTESIAN)
    with pytest.raises(mb.SolveError, match=r"q contains NaN at bob\.x$") as err:
        mb.linearize(system, 0.0, np.array([np.nan, -1.0]), np.zeros(2))
    assert err.value.coordinates == ("bob.x",)
    with pytest.raises(mb.SolveError, match=r"qd contains inf at bob\.z$"):
        mb.linearize(system, 0.0, np.array([0.0, -1.0]), np.array([0.0, np.inf]))
    with pytest.raises(mb.SolveError, match=r"q contains NaN at bob\.x, bob\.z$"):
        mb.equilibrium(system, np.array([np.nan, np.nan]))
    with pytest.raises(mb.SolveError, match=r"q contains NaN at bob\.z$"):
        mb.modes(system, np.array([0.0, np.nan]))


def test_servo_rows_at_a_moving_state_are_refused():
    """The cart-pole whose cart follows x(t) = 0.2 sin 3t, after 0.2 s: its motion about
    that state is a time-varying system — linearize refuses it naming the servo (it gave
    0.00087 ± 5.42j silently), modes at that configuration says it does not rest there (it
    said "relative residual 2.2e+307")."""
    system = mb.load(MODELS / "joints" / "cart_pole_servo.yaml")
    run = mb.simulate(system, 0.2)
    q, qd = run.q[-1], run.qd[-1]
    with pytest.raises(mb.SolveError, match=r"rows \['servo'\] depend on time .*state moves \(q̇ ≠ 0\)") as err:
        mb.linearize(system, 0.2, q, qd)
    assert err.value.constraints == ("servo",)
    with pytest.raises(mb.NoEquilibrium, match=r"rows \['servo'\] prescribe a motion at t = 0\.2"):
        mb.modes(system, q, t=0.2)
    with pytest.raises(mb.NoEquilibrium, match=r"rows \['servo'\] prescribe a motion"):
        mb.equilibrium(system, q, t=0.2)


def test_servo_held_still_linearizes():
    """Where the servo holds still (x = 0.2 sin² 3t at t = 0: ẋ = 0, the pole hanging at
    rest), the rows do not move the state and the linearization answers: the pole on a cart
    whose motion is prescribed, ∂θ̈/∂θ = −m g l / (I + m l²) at θ = 0."""
    text = (MODELS / "joints" / "cart_pole_servo.yaml").read_text().replace("0.2*sin(3*t)", "0.2*sin(3*t)**2")
    system = mb.loads(text)
    p = system.parameters
    lin = mb.linearize(system, 0.0, system.initial_q, np.zeros(system.n))
    omega = np.sqrt(p["m"] * p["g"] * p["l"] / (p["I"] + p["m"] * p["l"] ** 2))
    assert np.sort(np.abs(lin.eigenvalues.imag)) == pytest.approx([omega, omega], rel=1e-9)
