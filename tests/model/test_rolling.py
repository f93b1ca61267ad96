"""Non-holonomic ground contacts: a disk rolling without slipping, and a knife edge.

Each test compares with equations derived by hand in its docstring (Newton–Euler for
the disk, body-axis Newton equations for the sleigh), never with mbsynth's own rows."""

import json
import textwrap
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.core.kinematics import matrix_quaternion, quaternion_matrix

MODELS = Path(__file__).resolve().parents[2] / "models" / "rolling"


def world_rate(u):
    """G(u) of ω_world = 2 G(u) u̇ (scalar-first quaternion), numerically."""
    w, (x, y, z) = u[0], u[1:]
    return np.array([[-x, w, -z, y], [-y, z, w, -x], [-z, -y, x, w]])


def rigid_state(position, rotation, velocity, omega):
    """(q, q̇) of a rigid body: u̇ = ½ G(u)ᵀ ω for a unit u."""
    u = matrix_quaternion(rotation)
    return np.r_[position, u], np.r_[velocity, world_rate(u).T @ omega / 2]


def lowest_rim_point(q, radius):
    """ρ: from the centre to the lowest point of the rim of a disk whose axis is body z."""
    axis = quaternion_matrix(q[3:])[:, 2]
    d = np.array([0.0, 0.0, 1.0]) - axis[2] * axis
    return -radius * d / np.linalg.norm(d)


def steady_circle(system, theta, Omega):
    """(q, q̇, expected q̈ pieces) of a disk rolling steadily in a circle.

    Heading b1 = e_x, b2 = e_y, b3 = e_z; the disk leans by θ: axis c2 = cosθ b2 + sinθ b3,
    c1 = b1, c3 = c1 × c2 = −sinθ b2 + cosθ b3 (contact → centre, G = P + R c3). Its
    angular velocity is ω = Ω b3 + s c2 (heading turning at Ω, spin s), i.e. ω = ω_a c2
    + Ω cosθ c3 with ω_a = s + Ω sinθ. Rolling: v_G = ω × R c3 = R ω_a c1 = v c1.

    Steady (θ̇ = 0, ω_a constant), the c-frame turns at Ω b3, so a_G = Ω b3 × v c1 = vΩ b2
    (centripetal: v²/ρ toward a centre at ρ = v/Ω along b2) and, with A and C the
    inertias about a diameter and the axis, H_G = C ω_a c2 + A Ω cosθ c3 has
    Ḣ_G = Ω b3 × H_G = Ω cosθ (A Ω sinθ − C ω_a) c1. The contact force is
    F = m g b3 + m vΩ b2 (Newton) and its moment about G is −R c3 × F =
    m R (g sinθ + vΩ cosθ) c1. Equating the two:

        A Ω² sinθ cosθ − (C + m R²) Ω ω_a cosθ = m g R sinθ.

    Then ω̇ = Ω b3 × ω (ω's c-components are constant) and the axis' height sinθ stays.
    """
    p = system.parameters
    m, R, g = p["m"], p["R"], p["g"]
    A, C = m * R**2 / 4, m * R**2 / 2
    st, ct = np.sin(theta), np.cos(theta)
    w_axis = st * (A * Omega**2 * ct - m * g * R) / ((C + m * R**2) * Omega * ct)
    b1, b2, b3 = np.eye(3)
    c2, c3 = ct * b2 + st * b3, -st * b2 + ct * b3
    omega = w_axis * c2 + Omega * ct * c3
    v = R * w_axis
    q, qd = rigid_state(R * c3, np.column_stack([b1, -c3, c2]), v * b1, omega)
    return q, qd, dict(centre_acceleration=v * Omega * b2, omega_dot=np.cross(Omega * b3, omega),
                       radius=abs(v / Omega), speed=abs(v))


@pytest.fixture(scope="module")
def disk():
    return mb.load(MODELS / "rolling_disk.yaml")


@pytest.mark.parametrize("theta, Omega", [(0.3, 2.0), (0.6, -3.0), (-0.2, 5.0), (1.0, 0.7)])
def test_steady_circular_rolling(disk, theta, Omega):
    q, qd, expected = steady_circle(disk, theta, Omega)
    qdd = disk.motion(0.0, q, qd).qdd
    centre = qdd[:3]
    np.testing.assert_allclose(centre, expected["centre_acceleration"], atol=1e-9)
    assert np.linalg.norm(centre) == pytest.approx(expected["speed"] ** 2 / expected["radius"], rel=1e-9)
    u, ud, udd = q[3:], qd[3:], qdd[3:]
    omega = 2 * world_rate(u) @ ud
    omega_dot = 2 * world_rate(u) @ udd  # G(u̇) u̇ = 0
    np.testing.assert_allclose(omega_dot, expected["omega_dot"], atol=1e-9)
    axis = quaternion_matrix(u)[:, 2]
    tilt_acceleration = np.cross(omega_dot, axis) + np.cross(omega, np.cross(omega, axis))
    assert abs(tilt_acceleration[2]) < 1e-9  # d²/dt² of sinθ = axis_z
    # the state itself: rim on the ground, contact point at rest, residuals zero
    rho = lowest_rim_point(q, disk.parameters["R"])
    assert abs(q[2] + rho[2]) < 1e-15
    np.testing.assert_allclose(qd[:3] + np.cross(omega, rho), 0.0, atol=1e-14)
    phi, psi = disk.constraint_residuals(0.0, q, qd)
    names = disk.constraint_names
    assert abs(phi[names.index("contact[height]")]) < 1e-15
    assert np.isnan(phi[names.index("contact[slip_x]")]) and np.isnan(phi[names.index("contact[slip_y]")])
    assert np.abs(psi).max() < 1e-14


def test_model_file_starts_in_steady_rolling(disk):
    """The file's initial state is the steady circle at θ = 0.3, Ω = 2; after one turn of
    the heading (t = 2π/Ω) the disk is back where it started, still leaning by θ."""
    q, qd, _ = steady_circle(disk, 0.3, 2.0)
    q0, qd0 = disk.initial_state()
    np.testing.assert_allclose(q0, q, atol=1e-14)
    np.testing.assert_allclose(qd0, qd, atol=1e-14)
    period = 2 * np.pi / 2.0
    trajectory = mb.simulate(disk, period, dt=period / 8)
    end = trajectory.q[-1]
    np.testing.assert_allclose(end[:3], q[:3], atol=1e-7)
    assert quaternion_matrix(end[3:])[2, 2] == pytest.approx(np.sin(0.3), abs=1e-8)
    assert np.ptp(trajectory.energy) < 1e-8


@pytest.mark.parametrize("slope", [0.0, 0.25])
def test_upright_disk_rolls_straight(slope):
    """An upright disk rolling along x on a plane inclined by α (gravity tilted instead):
    m a = m g sinα − F, C ω̇ = R F, a = R ω̇ give a = g sinα / (1 + C/(m R²)) = ⅔ g sinα,
    and zero acceleration on level ground. Axis along +y: rolling at v needs ω = (v/R) e_y."""
    m, R, g, v = 2.0, 0.3, 9.81, 1.5
    system = mb.loads(textwrap.dedent(f"""\
        parameters: {{m: {m}, R: {R}, g: {g}, alpha: {slope}}}
        gravity: [g*sin(alpha), 0, -g*cos(alpha)]
        parts:
          disk: {{type: rigid_body, mass: m, inertia: [m*R**2/4, m*R**2/4, m*R**2/2]}}
        joints:
          - {{name: contact, type: rolling_disk, child: disk, radius: R, ground: 0.5}}
        """), name="incline.yaml")
    q, qd = rigid_state([0, 0, 0.5 + R], quaternion_matrix([1, -1, 0, 0]), [v, 0, 0], [0, v / R, 0])
    qdd = system.motion(0.0, q, qd).qdd
    a = g * np.sin(slope) / (1 + 0.5)
    np.testing.assert_allclose(qdd[:3], [a, 0, 0], atol=1e-12)
    np.testing.assert_allclose(2 * world_rate(q[3:]) @ qdd[3:], [0, a / R, 0], atol=1e-12)


def sleigh(offset, I=0.02, m=1.0):
    return mb.loads(textwrap.dedent(f"""\
        parameters: {{m: {m}, I: {I}, a: {offset}}}
        parts:
          sleigh:
            type: planar_body
            mass: m
            inertia: I
            frames: {{blade: {{position: [a, 0, 0]}}}}
        joints:
          - {{name: blade, type: knife_edge, child: sleigh.blade}}
        """), name="sleigh.yaml")


@pytest.mark.parametrize("offset", [0.0, 0.2, -0.35])
def test_knife_edge_accelerations(offset):
    """Body axes x_b, y_b (turned by θ); u, w the centre's velocity along them, ω = θ̇, the
    blade at a x_b. No slip sideways: w + a ω = 0. Newton in body axes with the blade's
    force λ y_b: m (u̇ − ω w) = 0, m (ẇ + ω u) = λ, I ω̇ = a λ. With w = −aω:
    u̇ = −a ω², ω̇ = m a u ω / (I + m a²), and the centre accelerates by
    R(θ) (0, u ω − a ω̇): for a = 0 uniform circular motion (v ω toward the centre)."""
    m, I, a = 1.0, 0.02, offset
    system = sleigh(a, I, m)
    theta, u, omega = 0.7, 1.3, -0.8
    c, s = np.cos(theta), np.sin(theta)
    w = -a * omega
    q, qd = np.array([0.4, -0.2, theta]), np.array([u * c - w * s, u * s + w * c, omega])
    omega_dot = m * a * u * omega / (I + m * a**2)
    lateral = u * omega - a * omega_dot
    expected = [-s * lateral, c * lateral, omega_dot]
    np.testing.assert_allclose(system.motion(0.0, q, qd).qdd, expected, atol=1e-13)
    assert abs(system.constraint_residuals(0.0, q, qd)[1][0]) < 1e-15


def test_chaplygin_sleigh_closed_form():
    """With K = (I + m a²)/m the energy gives u² + K ω² = c², so u̇ = −a ω² =
    −(a/K)(c² − u²): u = c tanh σ with σ = σ₀ − (a c/K) t, σ₀ = atanh(u₀/c). Then
    ω̇ = (a/K) u ω gives ω = ω₀ cosh σ₀ / cosh σ, and θ = θ₀ − (K ω₀ cosh σ₀/(a c))
    (atan sinh σ − atan sinh σ₀). The model file's sleigh (a ahead of the centre)
    turns round and ends running backwards: u → −c, ω → 0."""
    system = mb.load(MODELS / "knife_edge.yaml")
    p = system.parameters
    m, I, a = p["m"], p["I"], p["a"]
    K = (I + m * a**2) / m
    u0, omega0 = p["u0"], p["omega0"]
    c = np.sqrt(u0**2 + K * omega0**2)
    s0 = np.arctanh(u0 / c)
    trajectory = mb.simulate(system, 3.0, dt=0.25)
    t, q, qd = trajectory.t, trajectory.q, trajectory.qd
    sigma = s0 - a * c / K * t
    theta = -K * omega0 * np.cosh(s0) / (a * c) * (np.arctan(np.sinh(sigma)) - np.arctan(np.sinh(s0)))
    u = qd[:, 0] * np.cos(q[:, 2]) + qd[:, 1] * np.sin(q[:, 2])
    np.testing.assert_allclose(u, c * np.tanh(sigma), atol=1e-8)
    np.testing.assert_allclose(qd[:, 2], omega0 * np.cosh(s0) / np.cosh(sigma), atol=1e-8)
    np.testing.assert_allclose(q[:, 2], theta, atol=1e-8)
    assert u[-1] < -0.999 * c


@pytest.mark.parametrize("name, n, m", [("rolling_disk.yaml", 7, 4), ("knife_edge.yaml", 3, 1)])
def test_check_reports_unique_motion(capsys, name, n, m):
    """A massive disk (rank M = 6, quaternion norm + 3 contact rows) and a massive sleigh
    (rank M = 3) move uniquely: rank [M; A] = n (Result 3)."""
    code = main(["check", str(MODELS / name), "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == 0 and report["unique"] and report["consistent"]
    assert (report["n"], report["m"], report["rank_Mhat"]) == (n, m, n)


@pytest.mark.parametrize("joint, message", [
    ("{name: c, type: rolling_disk, child: disk}", "missing required key 'radius'"),
    ("{name: c, type: rolling_disk, child: disk, radius: -1}", "radius must be positive"),
    ("{name: c, type: rolling_disk, child: cart, radius: 1}",
     "a rolling_disk is a frame on a rigid_body, robot or solid part, not on a planar_body"),
    ("{name: c, type: knife_edge, child: world}", "not on the world"),
    ("{name: c, type: knife_edge, child: cart, radius: 1}", "unknown key 'radius'"),
])
def test_contact_mistakes_name_the_line(joint, message):
    text = textwrap.dedent("""\
        parts:
          disk: {type: rigid_body, mass: 1, inertia: [1, 1, 2]}
          cart: {type: planar_body, mass: 1, inertia: 1}
        joints:
          - JOINT
        """).replace("JOINT", joint)
    with pytest.raises(mb.ModelError, match=r"bad\.yaml:5: at joints\[0\].*" + message):
        mb.loads(text, name="bad.yaml")
