"""Joint values and reactions against Pinocchio, analytic solutions and
finite differences."""

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import sympy as sp
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

import mbsynth as mb
from mbsynth.core.joint_kinds import JOINT_KINDS, KINDS
from mbsynth.model.constraints.base import Constraint
from mbsynth.analysis.projection import project_velocities
from mbsynth.model.joint_values import constraint_symbols
from mbsynth.robots.build import fix_base
from mbsynth.symbolic.derive import T_SYMBOL
from mbsynth.robots.twin import Twin
from mbsynth.robots.validate import sample_pinocchio_state

ROOT = Path(__file__).resolve().parents[2]


def _pinocchio_positions(coordinate, q):
    """A joint's Pinocchio q in mbsynth's form: a continuous joint's angle, a free-flyer's
    quaternion scalar-first."""
    x = q[coordinate.idx_q:coordinate.idx_q + coordinate.nq]
    if coordinate.kind == "continuous":
        return np.array([np.arctan2(x[1], x[0])])
    if coordinate.kind == "free":
        return np.r_[x[:3], x[6], x[3:6]]
    return x


def _same_position(coordinate, ours, theirs):
    """|difference| of joint positions: angles modulo 2π, quaternions up to sign."""
    if coordinate.kind == "free":
        sign = np.sign(ours[3:] @ theirs[3:])
        return np.abs(np.r_[ours[:3], sign * ours[3:]] - theirs).max()
    return np.abs((ours - theirs + np.pi) % (2 * np.pi) - np.pi).max()


@pytest.fixture(scope="module")
def floating_ur5():
    return mb.from_robot("ur5", floating=True)


@pytest.fixture(scope="module", params=[False, True], ids=["fixed", "floating"])
def ur5(request, floating_ur5):
    system = floating_ur5 if request.param else fix_base(floating_ur5)
    return system, Twin(system)


def _driven_state(system, twin, rng):
    """A random state and torques; Pinocchio's (q, v, v̇ = aba) and mbsynth's driven System."""
    model, data = twin.model, twin.data
    q, v = sample_pinocchio_state(twin, rng)
    torques = {c.torque: 10 * rng.normal() for c in twin.coordinates if c.torque}
    tau = np.zeros(model.nv)
    for c in twin.coordinates:
        if c.torque:
            tau[c.idx_v] = torques[c.torque]
    a = pin.aba(model, data, q, v, tau).copy()
    return q, v, a, system.with_parameters(**torques)


def test_joint_values_and_reactions_equal_pinocchio(ur5):
    """joint_values = Pinocchio's (q, v, v̇) joint by joint; a joint's reaction = rnea's
    data.f (the wrench from parent to child in the joint frame), at random states."""
    system, twin = ur5
    rng = np.random.default_rng(7)
    for _ in range(3):
        q, v, a, driven = _driven_state(system, twin, rng)
        qm, qdm = twin.to_maximal(q, v)
        motion = driven.motion(0.0, qm, qdm)
        values = driven.joint_values(0.0, qm, qdm, motion.qdd)
        reactions = driven.reactions(0.0, qm, qdm, motion)
        pin.rnea(twin.model, twin.data, q, v, a)
        assert set(values) == {c.name for c in twin.coordinates}
        for c in twin.coordinates:
            ours, window = values[c.name], slice(c.idx_v, c.idx_v + c.nv)
            assert _same_position(c, ours.position, _pinocchio_positions(c, q)) < 1e-12
            assert np.abs(ours.rate - v[window]).max() < 1e-12 * (1 + np.abs(v).max())
            assert np.abs(ours.acceleration - a[window]).max() < 1e-9 * (1 + np.abs(a).max())
            if c.kind == "free":
                continue
            f = twin.data.f[c.joint_id]
            scale = np.abs(f.vector).max()
            assert np.abs(reactions[c.name].force - f.linear).max() < 1e-9 * scale
            assert np.abs(reactions[c.name].torque - f.angular).max() < 1e-9 * scale


@pytest.mark.slow  # a UR5's motion under six servo rows, simulated
def test_servo_constraints_give_the_inverse_dynamics(floating_ur5):
    """Every joint angle of the UR5 prescribed by a holonomic constraint (Udwadia's servo
    constraints) θ_i(t) = θ0_i + 0.3 (sin(2t + i) − sin i), no torques applied: along the simulated
    motion each servo row's multiplier is the joint torque that makes it, Pinocchio's rnea,
    and the joints follow their θ_i."""
    system = fix_base(floating_ur5)
    twin = Twin(system)
    start = np.random.default_rng(3).uniform(-2, 2, twin.model.nq)
    qm, _ = twin.to_maximal(start, np.zeros(twin.model.nv))
    joints = {c.name: c for c in system.constraints}
    t = T_SYMBOL
    targets = {c.name: start[c.idx_q] + 0.3 * (sp.sin(2 * t + i) - np.sin(i)) for i, c in enumerate(twin.coordinates)}
    servos = [Constraint.holonomic(f"{name}_servo", [constraint_symbols(joints[name])["angle"] - target],
                                  system.q_symbols, system.qd_symbols, system.parameter_symbols)
              for name, target in targets.items()]
    servoed = system.with_constraints(servos)
    qd0 = project_velocities(servoed, 0.0, qm, np.zeros(system.n))
    trajectory = mb.simulate(servoed, 0.5, q0=qm, qd0=qd0, dt=0.125)
    assert trajectory.status == "completed"
    for time, q, qd in zip(trajectory.t, trajectory.q, trajectory.qd):
        motion = servoed.motion(time, q, qd)
        assert motion.unique
        qp, v, a = twin.to_pinocchio(q, qd, motion.qdd)
        assert np.allclose(qp, [float(x.subs(T_SYMBOL, time)) for x in targets.values()], rtol=0, atol=1e-9)
        torque = pin.rnea(twin.model, twin.data, qp, v, a)
        reactions = servoed.reactions(time, q, qd, motion)
        found = np.array([reactions[f"{name}_servo"].multipliers[0] for name in targets])
        assert np.abs(found - torque).max() < 1e-9 * np.abs(torque).max()
        # the same formula (System._multipliers) from two evaluations of the rows, which may
        # differ in the last bits: a plain System's groups move to their compiled kernels
        # when these are ready (grouped.py), possibly between the two
        assert np.abs(motion.lam[-len(servos):] - found).max() <= 1e-13 * np.abs(found).max()


def test_pendulum_hinge_reaction_is_newtons():
    """driven_pendulum.yaml: the hinge carries the rod's m (a_c − g) and, about its axis,
    the actuation less the friction, I θ̈ + m g (L/2) sin θ (the rod's angular balance)."""
    system = mb.load("models/joints/driven_pendulum.yaml")
    p = system.parameters
    m, L, g, c = p["m"], p["L"], p["g"], p["c"]
    trajectory = mb.simulate(system, 0.7, dt=0.35)
    q, qd = trajectory.q[-1], trajectory.qd[-1]
    t = trajectory.t[-1]
    motion = system.motion(t, q, qd)
    (theta,), (rate,), (acceleration,) = system.joint_values(t, q, qd, motion.qdd)["hinge"]
    inertia = m * L**2 / 3
    tau = p["tau0"] + p["A"] * np.sin(p["w"] * t)
    assert acceleration == pytest.approx((-m * g * L / 2 * np.sin(theta) + tau - c * rate) / inertia, rel=1e-9)
    # the centre of mass at (−L/2 sin θ, 0, −L/2 cos θ): (the hinge turns about y)
    s, co = np.sin(theta), np.cos(theta)
    a_c = L / 2 * np.array([-co * acceleration + s * rate**2, 0.0, s * acceleration + co * rate**2])
    force_world = m * (a_c - np.array([0.0, 0.0, -g]))
    reaction = system.reactions(t, q, qd, motion)["hinge"]
    frame = system.joint_kinematics()["hinge"].frame(t, q, qd, system.parameter_values)
    assert np.allclose(frame.rotation @ reaction.force, force_world, rtol=0, atol=1e-9 * m * g)
    assert reaction.torque[2] == pytest.approx(tau - c * rate, rel=1e-9)
    assert reaction.torque[2] == pytest.approx(inertia * acceleration + m * g * L / 2 * s, rel=1e-9)
    assert np.abs(reaction.torque[:2]).max() < 1e-9 * m * g * L


def test_redundant_loop_multipliers():
    """four_bar_3d.yaml has three dependent rows: the minimum-norm λ still balances
    Qc − C = Aᵀλ (2.5), has no component along the dependencies, and the loop's joints
    are marked redundant."""
    system = mb.load("models/mechanisms/four_bar_3d.yaml")
    q, qd = system.initial_state()
    motion = system.motion(0.0, q, qd)
    arrays = system.evaluate(0.0, q, qd)
    lam = motion.lam
    assert np.abs(arrays.A.T @ lam - (motion.Qc - arrays.C)).max() < 1e-10 * np.abs(motion.Qc).max()
    u, _, _ = np.linalg.svd(arrays.A)  # 23 rows of rank 20
    left_null = u[:, -3:]
    assert np.abs(left_null.T @ lam).max() < 1e-9 * np.abs(lam).max()
    reactions = system.reactions(0.0, q, qd, motion)
    loop = ["ground_O", "crank_coupler", "coupler_rocker", "ground_D"]
    assert [reactions[j].redundant for j in loop] == [True] * 4
    assert not any(reactions[f"{b}.unit_quaternion"].redundant for b in ("crank", "coupler", "rocker"))


SPATIAL_CHAIN = """
name: spatial_chain
gravity: [0, 0, -9.81]
parts:
  a: {type: rigid_body, mass: 1.0, inertia: [0.02, 0.03, 0.04], frames: {top: {position: [0, 0, 0.3]}, bottom: {position: [0, 0, -0.3]}},
      initial: {position: [0, 0, -0.3], velocity: [0.2, -0.1, 0], angular_velocity: [0.3, -0.5, 0]}}
  b: {type: rigid_body, mass: 0.7, inertia: [0.01, 0.02, 0.015], frames: {top: {position: [0, 0, 0.25]}, bottom: {position: [0, 0, -0.25]}},
      initial: {position: [0, 0, -0.85], angular_velocity: [0.4, 0.2, 0.7]}}
  c: {type: rigid_body, mass: 0.5, inertia: [0.01, 0.01, 0.01], frames: {top: {position: [0, 0, 0.2]}},
      initial: {position: [0, 0, -1.3]}}
world: {frames: {origin: {position: [0, 0, 0], rpy: [1.5707963267948966, 0, 0]}}}
joints:
  - {name: cross, type: universal, parent: world.origin, child: a.top}
  - {name: ball, type: spherical, parent: a.bottom, child: b.top}
  - {name: sleeve, type: cylindrical, parent: b.bottom, child: c.top}
"""


def value_chain():
    """A hanging chain with one joint of every kind that has values (core/joint_kinds.py),
    each between frames that meet its rows at the start (aligned; a universal joint's child
    frame turned a quarter about x), tilted by gravity and set spinning."""
    kinds = [k for k in JOINT_KINDS if KINDS[k].rates]
    bodies = "\n".join(f"  b{i}: {{type: rigid_body, mass: {1 - 0.1 * i:.1f}, inertia: [0.02, 0.03, 0.04], "
                       f"frames: {{top: {{position: [0, 0, 0.2]}}, bottom: {{position: [0, 0, -0.2]}}, "
                       f"cross: {{position: [0, 0, 0.2], rpy: [1.5707963267948966, 0, 0]}}}}, "
                       f"initial: {{position: [0, 0, {-0.2 - 0.4 * i:.1f}], angular_velocity: [0.3, -0.2, 0.5]}}}}"
                       for i in range(len(kinds)))
    joints = "\n".join(f"  - {{name: j_{kind}, type: {kind}, parent: {'world' if i == 0 else f'b{i - 1}.bottom'}, "
                       f"child: b{i}.{'cross' if kind == 'universal' else 'top'}}}" for i, kind in enumerate(kinds))
    return mb.loads(f"name: value_chain\ngravity: [1.5, -0.8, -9.81]\nparts:\n{bodies}\njoints:\n{joints}\n")


@pytest.mark.parametrize("model, sizes", [
    (SPATIAL_CHAIN, {"cross": 2, "ball": 3, "sleeve": 2}),
    (None, {f"j_{k}": len(KINDS[k].positions) for k in JOINT_KINDS if KINDS[k].rates})])
def test_joint_rates_are_derivatives_of_positions(model, sizes):
    """Along the motion, each joint's rate is the time derivative of its position (the
    relative angular velocity R_relᵀ Ṙ_rel for a spherical joint), and its acceleration
    the derivative of its rate: central differences on the motion's Taylor path. On a
    spatial chain, and on a chain of every kind of the table that has values (``None``:
    ``value_chain``; a floating robot's free joint: against Pinocchio above)."""
    system = mb.loads(model) if model else value_chain()
    trajectory = mb.simulate(system, 0.3, dt=0.3)
    t, q, qd = trajectory.t[-1], trajectory.q[-1], trajectory.qd[-1]
    qdd = system.motion(t, q, qd).qdd
    values = system.joint_values(t, q, qd, qdd)
    assert {k: v.position.size for k, v in values.items()} == sizes
    kinds = {c.name: c.joint_kind for c in system.constraints if hasattr(c, "joint_kind")}
    assert all(np.abs(v.rate).max() > 1e-3 for v in values.values())  # every joint moves

    def at(h):
        return system.joint_values(t + h, q + h * qd + h**2 / 2 * qdd, qd + h * qdd)

    h = 1e-5
    after, before = at(h), at(-h)
    for name, value in values.items():
        rate = (after[name].rate - before[name].rate) / (2 * h)
        assert np.allclose(rate, value.acceleration, rtol=0, atol=1e-4 * (1 + np.abs(value.acceleration).max()))
        if kinds[name] == "spherical":
            R = [Rotation.from_rotvec(x[name].position).as_matrix() for x in (after, before)]
            R0 = Rotation.from_rotvec(value.position).as_matrix()
            W = R0.T @ (R[0] - R[1]) / (2 * h)
            derivative = np.array([W[2, 1], W[0, 2], W[1, 0]])
        else:
            derivative = (after[name].position - before[name].position) / (2 * h)
        assert np.allclose(derivative, value.rate, rtol=0, atol=1e-7 * (1 + np.abs(value.rate).max()))


PD_PENDULUM = (ROOT / "models" / "joints" / "pd_pendulum.yaml").read_text()



def test_pd_law_on_joint_values_settles_at_the_static_balance():
    """A PD law written on ``hinge.angle`` and ``hinge.rate`` holds the rod where the
    spring torque balances gravity: kp (θ − target) = −m g (L/2) sin θ."""
    system = mb.loads(PD_PENDULUM)
    trajectory = mb.simulate(system, 6.0, dt=1.0)
    (theta,), (rate,), _ = system.joint_values(trajectory.t[-1], trajectory.q[-1], trajectory.qd[-1])["hinge"]
    balance = brentq(lambda x: 50.0 * (x - 0.5) + 9.81 * 0.5 * np.sin(x), 0.0, 1.0)
    assert theta == pytest.approx(balance, abs=1e-6)
    assert abs(rate) < 1e-5


def test_prescribed_joint_angle_multiplier_is_the_driving_torque():
    """``holonomic: hinge.angle − 0.3 sin 2t`` in place of the actuation: the row's
    multiplier is the torque I θ̈ + m g (L/2) sin θ that makes that motion."""
    text = PD_PENDULUM.replace("    actuation: -kp*(hinge.angle - target) - kd*hinge.rate\n", "")
    text += "constraints:\n  - {name: servo, holonomic: hinge.angle - 0.3*sin(2*t)}\n"
    system = mb.loads(text)
    trajectory = mb.simulate(system, 1.0, dt=0.5)
    t, q, qd = trajectory.t[-1], trajectory.q[-1], trajectory.qd[-1]
    motion = system.motion(t, q, qd)
    theta, acceleration = 0.3 * np.sin(2 * t), -1.2 * np.sin(2 * t)
    assert system.joint_values(t, q, qd)["hinge"].position[0] == pytest.approx(theta, abs=1e-9)
    torque = acceleration / 3 + 9.81 / 2 * np.sin(theta)  # I = m L²/3 about the pivot
    assert system.reactions(t, q, qd, motion)["servo"].multipliers[0] == pytest.approx(torque, rel=1e-8)


def test_joint_named_like_a_part_is_refused():
    text = PD_PENDULUM.replace("name: hinge", "name: rod").replace("hinge.", "rod.")
    with pytest.raises(mb.ModelError, match=r"joints\[0\].*joint 'rod' has the name of part 'rod'"):
        mb.loads(text)


CART_POLE = (ROOT / "models" / "joints" / "cart_pole_servo.yaml").read_text()



def test_under_actuated_cart_pole_servo_force():
    """A cart-pole whose cart follows x(t) = 0.2 sin 3t by a servo row, the pole free: the
    pole obeys (I + m l²) θ̈ − m l cos θ ẍ + m g l sin θ = 0 and the servo's multiplier is
    the force on the cart, (M + m) ẍ − m l cos θ θ̈ + m l sin θ θ̇² (Lagrange's equations)."""
    system = mb.loads(CART_POLE)
    P = system.parameters
    M, m, l, I, g = P["M"], P["m"], P["l"], P["I"], P["g"]
    trajectory = mb.simulate(system, 1.0, dt=0.5)
    t, q, qd = trajectory.t[-1], trajectory.q[-1], trajectory.qd[-1]
    motion = system.motion(t, q, qd)
    values = system.joint_values(t, q, qd, motion.qdd)
    x, xdd = values["slider"].position[0], values["slider"].acceleration[0]
    assert x == pytest.approx(0.2 * np.sin(3 * t), abs=1e-9)
    assert xdd == pytest.approx(-1.8 * np.sin(3 * t), abs=1e-8)
    (theta,), (rate,), (thdd,) = values["hinge"]
    assert (I + m * l**2) * thdd - m * l * np.cos(theta) * xdd + m * g * l * np.sin(theta) == pytest.approx(0, abs=1e-9)
    force = (M + m) * xdd - m * l * np.cos(theta) * thdd + m * l * np.sin(theta) * rate**2
    assert system.reactions(t, q, qd, motion)["servo"].multipliers[0] == pytest.approx(force, rel=1e-9)


def test_angles_along_a_trajectory_keep_counting():
    """A free rod spun about its hinge (no gravity) turns at a constant rate: along the
    trajectory its angle is rate · t, past ±π, not wrapped."""
    text = PD_PENDULUM.replace("    actuation: -kp*(hinge.angle - target) - kd*hinge.rate\n", "")
    text = text.replace("gravity: [0, 0, -g]", "gravity: [0, 0, 0]")
    text = text.replace("initial: {position: [0, 0, -L/2]}", "initial: {position: [0, 0, -L/2], angular_velocity: [0, 4, 0]}")
    system = mb.loads(text)
    trajectory = mb.simulate(system, 2.0, dt=0.1)
    from mbsynth.model.joint_values import along
    hinge = along(system, trajectory.t, trajectory.q, trajectory.qd)["hinge"]
    assert hinge.acceleration is None
    assert np.allclose(hinge.rate[:, 0], 4.0, rtol=1e-9)
    assert np.allclose(hinge.position[:, 0], 4.0 * trajectory.t, atol=1e-8)
