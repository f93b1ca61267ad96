"""Rigid bodies in quaternion coordinates against independent references: Euler's
equations and the conservation laws of a torque-free body, Pinocchio's articulated-body
algorithm for a free-flyer under a wrench, and a 3D double pendulum of two bodies against
the same pendulum written by hand in its two joint angles."""

import functools
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import mbsynth as mb
from mbsynth.analysis.diagnose import diagnose
from tests.helpers.rotations import E, G, R, R_rate, body_coordinates, rotation_about

RIGID = Path(__file__).resolve().parents[2] / "models" / "rigid"
load = functools.cache(mb.load)  # each model compiled once per session
ZERO_LOADS = dict(g=0.0, Fx=0.0, Fy=0.0, Fz=0.0, Tx=0.0, Ty=0.0, Tz=0.0)


@pytest.fixture(scope="module")
def free_body():
    return load(RIGID / "free_body.yaml")


def numeric(system, expr):
    values = {sp.Symbol(k): v for k, v in system.parameters.items()}
    return np.array(sp.Matrix(expr).subs(values).evalf(), dtype=float)


def random_body_states(count, seed):
    """(q, q̇, ω_body) of a free body: a random unit quaternion, u̇ = ½ E(u)ᵀ ω_body
    tangent to uᵀu = 1 (E Eᵀ = I), random position and velocity."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        u = rng.normal(size=4)
        u /= np.linalg.norm(u)
        omega = 3 * rng.normal(size=3)
        q = np.concatenate([rng.normal(size=3), u])
        qd = np.concatenate([rng.normal(size=3), E(u).T @ omega / 2])
        yield q, qd, omega


def test_torque_free_body_obeys_euler_and_conserves_momentum_and_energy(free_body):
    """Full inertia J: ω̇_body = 2 E(u) ü (E(u̇) u̇ = 0) equals J⁻¹(−ω × Jω); r̈ = 0;
    uᵀü = −u̇ᵀu̇; d/dt (R J ω) = 0 and d/dt T = 0 at the state, computed from q̈."""
    system = free_body.with_parameters(**ZERO_LOADS)
    body = system.parts[0]
    J, m = numeric(system, body.inertia), float(numeric(system, [body.mass])[0, 0])
    assert abs(J[0, 1]) > 0 and abs(J[1, 2]) > 0  # a full inertia, not principal axes
    for q, qd, omega in random_body_states(5, seed=11):
        motion = system.motion(0.0, q, qd)
        assert motion.unique
        rdd, u, ud, udd = motion.qdd[:3], q[3:], qd[3:], motion.qdd[3:]
        omega_dot = 2 * E(u) @ udd
        euler = np.linalg.solve(J, -np.cross(omega, J @ omega))
        np.testing.assert_allclose(omega_dot, euler, rtol=1e-10, atol=1e-10 * np.abs(euler).max())
        np.testing.assert_allclose(2 * E(u) @ qd[3:], omega, rtol=1e-12)
        assert np.abs(rdd).max() < 1e-12
        assert u @ udd == pytest.approx(-ud @ ud, rel=1e-12)
        H = R(u) @ J @ omega
        H_rate = R_rate(u, ud) @ J @ omega + R(u) @ J @ omega_dot
        assert np.linalg.norm(H_rate) < 1e-10 * np.linalg.norm(H) * np.linalg.norm(omega)
        T = 0.5 * m * qd[:3] @ qd[:3] + 0.5 * omega @ J @ omega
        assert system.energy(0.0, q, qd)[0] == pytest.approx(T, rel=1e-12)
        T_rate = m * qd[:3] @ rdd + omega @ J @ omega_dot
        assert abs(T_rate) < 1e-10 * T * np.linalg.norm(omega)


def test_free_body_under_a_wrench_matches_pinocchio_aba(free_body):
    """A force F (world axes) at the body point p and a torque Γ (body axes), and gravity:
    Pinocchio's free-flyer with the joint at the centre of mass, local-frame velocity
    v = (Rᵀṙ, ω_body) and the local wrench (RᵀF, Γ + p × RᵀF). aba returns the spatial
    acceleration a; the classical one of the origin is a_lin + ω × v_lin = Rᵀ r̈."""
    pin = pytest.importorskip("pinocchio")
    system = free_body
    body = system.parts[0]
    J, m = numeric(system, body.inertia), float(numeric(system, [body.mass])[0, 0])
    p = numeric(system, body.frames["handle"].position).ravel()
    par = system.parameters
    force = np.array([par["Fx"], par["Fy"], par["Fz"]])
    torque = np.array([par["Tx"], par["Ty"], par["Tz"]])
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "free")
    model.appendBodyToJoint(joint, pin.Inertia(m, np.zeros(3), J), pin.SE3.Identity())
    model.gravity.linear = np.array([0.0, 0.0, -par["g"]])
    data = model.createData()
    for q, qd, omega in random_body_states(5, seed=12):
        u, Rm = q[3:], R(q[3:])
        q_pin = np.concatenate([q[:3], u[1:], u[:1]])  # Pinocchio stores (x, y, z, w)
        v_pin = np.concatenate([Rm.T @ qd[:3], omega])
        f_body = Rm.T @ force
        a = pin.aba(model, data, q_pin, v_pin, np.concatenate([f_body, torque + np.cross(p, f_body)]))
        qdd = system.motion(0.0, q, qd).qdd
        np.testing.assert_allclose(Rm.T @ qdd[:3], a[:3] + np.cross(omega, v_pin[:3]), rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(2 * E(u) @ qdd[3:], a[3:], rtol=1e-10, atol=1e-10)


# (body model, angle model, elbow axis in link 1's axes); the shoulder turns about world y
PENDULUMS = [("double_pendulum_3d.yaml", "double_pendulum_angles.yaml", [0.0, 1.0, 0.0]),
             ("double_pendulum_spatial.yaml", "double_pendulum_spatial_angles.yaml", [1.0, 0.0, 0.0])]
PIVOT, SHOULDER = np.array([0.0, 0.0, 2.0]), np.array([0.0, 1.0, 0.0])


def pendulum_bodies(angles, rates, L1, L2, elbow):
    """Body coordinates (q, q̇) of both links, the elbow axis in the world and the links'
    angular velocities, from the joint angles: R1 = Rot(y, θ1), R2 = R1 Rot(elbow, θ2),
    each link hanging along its −z axis from its top end."""
    R1 = rotation_about(SHOULDER, angles[0])
    R2 = R1 @ rotation_about(elbow, angles[1])
    axis = R1 @ elbow
    w1 = rates[0] * SHOULDER
    w2 = w1 + rates[1] * axis
    half1, half2 = R1 @ [0, 0, L1 / 2], R2 @ [0, 0, L2 / 2]
    r1, r2 = PIVOT - half1, PIVOT - 2 * half1 - half2
    v1 = np.cross(w1, -half1)
    v2 = np.cross(w1, -2 * half1) + np.cross(w2, -half2)
    q1, qd1 = body_coordinates(r1, R1, v1, w1)
    q2, qd2 = body_coordinates(r2, R2, v2, w2)
    return np.concatenate([q1, q2]), np.concatenate([qd1, qd2]), axis, w1


@pytest.mark.parametrize("bodies, angle_model, elbow", PENDULUMS)
def test_double_pendulum_of_bodies_equals_the_pendulum_in_joint_angles(bodies, angle_model, elbow):
    """At random joint angles and rates, the two bodies' angular accelerations 2 G(u) ü
    equal those the hand-written Lagrangian's θ̈ give: ω̇1 = θ̈1 y, ω̇2 = ω̇1 + θ̈2 a + θ̇2 ω1 × a
    with a the elbow axis in the world."""
    system, reference = load(RIGID / bodies), load(RIGID / angle_model)
    assert system.parameters == reference.parameters
    rng = np.random.default_rng(13)
    L1, L2 = system.parameters["L1"], system.parameters["L2"]
    for _ in range(4):
        angles, rates = rng.uniform(-np.pi, np.pi, 2), 2 * rng.normal(size=2)
        q, qd, axis, w1 = pendulum_bodies(angles, rates, L1, L2, np.array(elbow))
        phi, phi_dot = system.constraint_residuals(0.0, q, qd)
        assert np.abs(phi).max() < 1e-12 and np.abs(phi_dot).max() < 1e-12
        motion = system.motion(0.0, q, qd)
        assert motion.unique
        thdd = reference.motion(0.0, angles, rates).qdd
        w1_dot = thdd[0] * SHOULDER
        w2_dot = w1_dot + thdd[1] * axis + rates[1] * np.cross(w1, axis)
        np.testing.assert_allclose(2 * G(q[3:7]) @ motion.qdd[3:7], w1_dot, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(2 * G(q[10:]) @ motion.qdd[10:], w2_dot, rtol=1e-9, atol=1e-9)


def test_double_pendulum_starts_where_its_angle_model_starts():
    """double_pendulum_3d.yaml's initial body state is the one of double_pendulum_angles.yaml's
    initial angles and rates: each link's position, rotation R(u), velocity and 2 G(u) u̇."""
    system, reference = load(RIGID / "double_pendulum_3d.yaml"), load(RIGID / "double_pendulum_angles.yaml")
    q0, qd0 = system.initial_state()
    q, qd, _, _ = pendulum_bodies(*reference.initial_state(), system.parameters["L1"], system.parameters["L2"],
                                  SHOULDER)
    for link in (slice(0, 7), slice(7, 14)):
        (r0, u0), (r, u) = (q0[link][:3], q0[link][3:]), (q[link][:3], q[link][3:])
        np.testing.assert_allclose(r0, r, atol=1e-12)
        np.testing.assert_allclose(R(u0), R(u), atol=1e-12)
        np.testing.assert_allclose(qd0[link][:3], qd[link][:3], atol=1e-12)
        np.testing.assert_allclose(2 * G(u0) @ qd0[link][3:], 2 * G(u) @ qd[link][3:], atol=1e-12)


@pytest.mark.parametrize("name", ["free_body.yaml", "double_pendulum_3d.yaml", "double_pendulum_angles.yaml",
                                  "double_pendulum_spatial_angles.yaml"])
def test_rigid_models_check_clean(name):
    """`mbsynth check` would exit 0: unique motion and a consistent initial state."""
    report = diagnose(load(RIGID / name))
    assert report.unique and report.consistent and report.suggested_constraints == []
