"""Joint actuation, joint springs and dampers, and joint friction (viscous and Coulomb,
through the non-ideal C of (2.6)), each checked against a hand-derived equation of the
one free motion of the joint."""

import textwrap
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

import mbsynth as mb

MODELS = Path(__file__).resolve().parents[2] / "models" / "joints"
RNG = np.random.default_rng(11)


def loads(text):
    return mb.loads(textwrap.dedent(text), name="model.yaml")


def G(u):
    """ω_world = 2 G(u) u̇ (kinematics.world_rate_matrix, numerically)."""
    w, v = u[0], u[1:]
    return np.column_stack([-v, w * np.eye(3) + np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])])


# ------------------------------------------------------------ a block on a rail

def block(joint_keys, gravity="[0, 0, -g]", parameters=""):
    """A cube (mass m) on a prismatic joint along the world x axis; the rail's frame sits
    at x = 0.5, so the joint displacement is s = x − 0.5."""
    return loads(f"""\
        parameters: {{m: 2.5, g: 9.81, a: 0.2{parameters}}}
        gravity: {gravity}
        world:
          frames:
            rail: {{position: [0.5, 0, 0], axis: [1, 0, 0]}}
        parts:
          block:
            type: rigid_body
            mass: m
            inertia: [m*a**2/6, m*a**2/6, m*a**2/6]
            frames:
              slide: {{axis: [1, 0, 0]}}
        joints:
          - {{name: rail, type: prismatic, parent: world.rail, child: block.slide, {joint_keys}}}
        """)


def rail_state(x, v):
    return np.array([x, 0, 0, 1, 0, 0, 0.0]), np.array([v, 0, 0, 0, 0, 0, 0.0])


def test_coulomb_friction_on_a_level_rail_decelerates_at_mu_g():
    """Sliding with speed v: the load is N = m g, the friction μ N opposes v, ẍ = −μ g sign v;
    the constraint force Qc (ideal part and friction) has power −μ m g |v|."""
    system = block("friction: {coulomb: mu}", parameters=", mu: 0.35")
    m, g, mu = 2.5, 9.81, 0.35
    for x, v in [(0.3, 1.7), (-1.2, 0.01), (2.0, -0.8)]:
        q, qd = rail_state(x, v)
        motion = system.motion(0.0, q, qd)
        np.testing.assert_allclose(motion.qdd, [-mu * g * np.sign(v), 0, 0, 0, 0, 0, 0], rtol=0, atol=1e-10)
        assert motion.Qc @ qd == pytest.approx(-mu * m * g * abs(v), rel=1e-10)


def test_coulomb_friction_with_a_pushing_actuator():
    """An actuation force F along the rail against the friction: m ẍ = F − μ m g sign v."""
    system = block("actuation: F0*cos(t), friction: {coulomb: mu}", parameters=", mu: 0.2, F0: 7.0")
    m, g, mu, F0 = 2.5, 9.81, 0.2, 7.0
    for t, v in [(0.4, 1.0), (2.5, 0.3), (1.0, -2.0)]:
        qdd = system.motion(t, *rail_state(0.1, v)).qdd
        assert qdd[0] == pytest.approx((F0 * np.cos(t) - mu * m * g * np.sign(v)) / m, abs=1e-10)


def test_no_coulomb_friction_at_rest():
    """Sticking is not modelled: at w = 0 exactly the Coulomb term is zero, so a pushed
    block at rest accelerates at F/m."""
    system = block("actuation: 3.0, friction: {coulomb: 0.5}")
    assert system.motion(0.0, *rail_state(0.0, 0.0)).qdd[0] == pytest.approx(3.0 / 2.5, rel=1e-12)


def test_coulomb_friction_on_an_incline():
    """The slider model: down the slope ẍ = g (sin α − μ cos α), up it g (sin α + μ cos α)
    — both with N = m g cos α."""
    system = mb.load(MODELS / "slider_friction.yaml")
    g, alpha, mu = (system.parameters[k] for k in ("g", "alpha", "mu"))
    axis = np.array([np.cos(alpha), 0, -np.sin(alpha)])  # down the slope
    for s, v in [(0.0, 1.0), (0.7, 0.2), (-0.4, -1.5)]:
        q = np.r_[s * axis, 1, 0, 0, 0]
        qd = np.r_[v * axis, 0, 0, 0, 0]
        qdd = system.motion(0.0, q, qd).qdd
        expected = g * (np.sin(alpha) - mu * np.cos(alpha) * np.sign(v))
        np.testing.assert_allclose(qdd, np.r_[expected * axis, 0, 0, 0, 0], rtol=0, atol=1e-10)


def test_viscous_friction_at_a_prismatic_joint():
    """C = −c ẋ along the rail: ẍ = −c v / m, and the friction's power is −c v²."""
    system = block("friction: {viscous: c}", parameters=", c: 0.9")
    for v in (1.3, -0.4):
        q, qd = rail_state(0.2, v)
        motion = system.motion(0.0, q, qd)
        np.testing.assert_allclose(motion.qdd, [-0.9 * v / 2.5, 0, 0, 0, 0, 0, 0], rtol=0, atol=1e-12)
        assert motion.Qc @ qd == pytest.approx(-0.9 * v**2, rel=1e-12)


def test_linear_spring_at_a_prismatic_joint():
    """V = ½ k (s − s0)², s = x − 0.5: ẍ = −k (s − s0)/m, and the potential energy is V."""
    system = block("spring: {stiffness: k, rest: s0}", gravity="[0, 0, 0]", parameters=", k: 12.0, s0: 0.25")
    for x in (0.1, 0.75, 2.0):
        q, qd = rail_state(x, 0.6)
        s = x - 0.5
        assert system.motion(0.0, q, qd).qdd[0] == pytest.approx(-12.0 * (s - 0.25) / 2.5, rel=1e-12)
        assert system.energy(0.0, q, qd)[1] == pytest.approx(6.0 * (s - 0.25) ** 2, rel=1e-12)


# ------------------------------------------------------------ a rod on a hinge

def rod(joint_keys, gravity="[0, 0, -g]", parameters=""):
    """A rod (mass m, length L) hinged at its top about the world y axis."""
    return loads(f"""\
        parameters: {{m: 1.2, L: 0.8, r: 0.02, g: 9.81{parameters}}}
        gravity: {gravity}
        world:
          frames:
            pivot: {{axis: [0, 1, 0]}}
        parts:
          rod:
            type: rigid_body
            mass: m
            inertia: [m*L**2/12, m*L**2/12, m*r**2/2]
            frames:
              top: {{position: [0, 0, L/2], axis: [0, 1, 0]}}
        joints:
          - {{name: hinge, type: revolute, parent: world.pivot, child: rod.top, {joint_keys}}}
        """)


def rod_state(theta, theta_dot, L):
    """The rod turned by θ about y (the joint angle), turning at θ̇."""
    h = L / 2
    u = np.array([np.cos(theta / 2), 0, np.sin(theta / 2), 0])
    ud = theta_dot / 2 * np.array([-np.sin(theta / 2), 0, np.cos(theta / 2), 0])
    r = np.array([-h * np.sin(theta), 0, -h * np.cos(theta)])
    rd = theta_dot * np.array([-h * np.cos(theta), 0, h * np.sin(theta)])
    return np.r_[r, u], np.r_[rd, ud]


def theta_ddot(q, qdd):
    """θ̈ = ω̇_y, with ω̇ = 2 G(u) ü (G(u̇) u̇ = 0)."""
    return (2 * G(q[3:]) @ qdd[3:])[1]


def test_driven_pendulum_with_joint_damping():
    """The model's one-angle equation I θ̈ = −m g (L/2) sin θ + τ(t) − c θ̇, I = m L²/3,
    with τ = τ0 + A sin(w t) the actuation and c the hinge's viscous friction."""
    system = mb.load(MODELS / "driven_pendulum.yaml")
    m, L, g, c, tau0, A, w = (system.parameters[k] for k in ("m", "L", "g", "c", "tau0", "A", "w"))
    for _ in range(4):
        t, theta, theta_dot = RNG.uniform(0, 5), RNG.uniform(-3, 3), RNG.normal(scale=2)
        q, qd = rod_state(theta, theta_dot, L)
        qdd = system.motion(t, q, qd).qdd
        tau = tau0 + A * np.sin(w * t)
        expected = (-m * g * L / 2 * np.sin(theta) + tau - c * theta_dot) / (m * L**2 / 3)
        assert theta_ddot(q, qdd) == pytest.approx(expected, rel=1e-10)


def test_torsional_spring_and_damper_without_gravity():
    """V = ½ k (θ − θ0)²: I θ̈ = −k (θ − θ0) − c θ̇ about the pivot, and the potential is V."""
    system = rod("spring: {stiffness: k, damping: c, rest: th0}", gravity="[0, 0, 0]",
                 parameters=", k: 5.0, c: 0.3, th0: 0.4")
    I = 1.2 * 0.8**2 / 3
    for theta, theta_dot in [(1.1, 0.5), (-2.5, -1.0), (0.4, 2.0)]:
        q, qd = rod_state(theta, theta_dot, 0.8)
        expected = (-5.0 * (theta - 0.4) - 0.3 * theta_dot) / I
        assert theta_ddot(q, system.motion(0.0, q, qd).qdd) == pytest.approx(expected, rel=1e-10)
        assert system.energy(0.0, q, qd)[1] == pytest.approx(2.5 * (theta - 0.4) ** 2, rel=1e-12)


def pin_friction_acceleration(theta, theta_dot, m, L, g, mu_r):
    """θ̈ of a rod on a pin with Coulomb friction, by Newton–Euler: the pin's force on the
    rod is F = m a_c − m g (a_c the centre's acceleration, linear in θ̈) and
    I θ̈ = −m g (L/2) sin θ − μ r |F| sign θ̇ about the pivot: a scalar root."""
    h, I = L / 2, m * L**2 / 3

    def residual(x):
        a_c = np.array([-h * (np.cos(theta) * x - np.sin(theta) * theta_dot**2), 0,
                        h * (np.sin(theta) * x + np.cos(theta) * theta_dot**2)])
        load = np.linalg.norm(m * a_c - m * np.array([0, 0, -g]))
        return I * x + m * g * h * np.sin(theta) + mu_r * load * np.sign(theta_dot)
    return residual


def test_coulomb_pin_friction_uses_the_pin_load():
    """Friction torque μ r N with N the magnitude of the pin's reaction force, which itself
    depends on θ̈ (so the iteration in friction.py must find the fixed point)."""
    system = rod("friction: {coulomb: mu, radius: rp}", parameters=", mu: 0.4, rp: 0.1")
    for theta, theta_dot in [(0.7, 1.5), (-1.9, -0.6), (2.8, 3.0)]:
        residual = pin_friction_acceleration(theta, theta_dot, 1.2, 0.8, 9.81, 0.04)
        expected = brentq(residual, -1e3, 1e3, xtol=1e-14, rtol=1e-15)
        q, qd = rod_state(theta, theta_dot, 0.8)
        assert theta_ddot(q, system.motion(0.0, q, qd).qdd) == pytest.approx(expected, rel=1e-10)


def test_coulomb_friction_without_a_solution_is_a_solve_error():
    """With μ r > I/(m L/2) the friction torque grows faster with θ̈ than the inertia: at this
    state the one-angle equation has no root (Painlevé), and motion says so, naming the joint."""
    system = rod("friction: {coulomb: 1.0, radius: 2.0}")
    theta, theta_dot = 1.2, 0.5
    residual = pin_friction_acceleration(theta, theta_dot, 1.2, 0.8, 9.81, 2.0)
    assert min(residual(x) for x in np.linspace(-1e3, 1e3, 200001)) > 0  # no θ̈ exists
    with pytest.raises(mb.SolveError, match="hinge") as err:
        system.motion(0.0, *rod_state(theta, theta_dot, 0.8))
    assert err.value.constraints == ("hinge",)


def test_cylindrical_joint_takes_a_torque_and_a_force():
    """A body turning and sliding on its own z axis: I_zz ω̇_z = τ, m z̈ = f."""
    system = loads("""\
        parameters: {m: 1.5, J: 0.2}
        world:
          frames:
            axle: {position: [0, 0, 1]}
        parts:
          sleeve: {type: rigid_body, mass: m, inertia: [0.3, 0.3, J]}
        joints:
          - name: shaft
            type: cylindrical
            parent: world.axle
            child: sleeve
            actuation: {torque: 0.5*t, force: -2.0}
        """)
    phi, omega = 0.9, 1.3
    q = np.r_[0, 0, 1.4, np.cos(phi / 2), 0, 0, np.sin(phi / 2)]
    qd = np.r_[0, 0, 0.2, omega / 2 * np.array([-np.sin(phi / 2), 0, 0, np.cos(phi / 2)])]
    qdd = system.motion(2.0, q, qd).qdd
    assert (2 * G(q[3:]) @ qdd[3:])[2] == pytest.approx(0.5 * 2.0 / 0.2, rel=1e-12)
    assert qdd[2] == pytest.approx(-2.0 / 1.5, rel=1e-12)


# ------------------------------------------------------------ mistakes

HEAD = """\
parameters: {m: 1.0}
world:
  frames:
    a: {axis: [1, 0, 0]}
parts:
  b: {type: rigid_body, mass: m, inertia: [1, 1, 1]}
joints:
  - name: j
    parent: world.a
    child: b
"""


@pytest.mark.parametrize("entry, key, fragment", [
    ("    type: spherical\n    friction: {viscous: 1}\n", "friction", "friction acts at revolute and prismatic"),
    ("    type: prismatic\n    friction: {coulomb: -0.2}\n", "friction.coulomb", "coulomb must be ≥ 0"),
    ("    type: distance\n    length: 1\n    actuation: 2*t\n", "actuation", "not a distance joint"),
    ("    type: revolute\n    friction: {coulomb: 0.2}\n", "friction", "needs 'radius'"),
    ("    type: prismatic\n    friction: {viscous: 1, radius: 0.1}\n", "friction.radius", "pin radius"),
    ("    type: cylindrical\n    actuation: 1.0\n", "actuation", "write 'actuation: {torque"),
    ("    type: revolute\n    actuation: {force: 1.0}\n", "actuation.force", "unknown key 'force'"),
    ("    type: cylindrical\n    spring: {stiffness: 1}\n", "spring", "not at a cylindrical joint"),
    ("    type: revolute\n    spring: {stiffness: 1, rest: 4}\n", "spring.rest", "[−π, π]"),
    ("    type: prismatic\n    spring: {damping: 1}\n", "spring", "missing required key 'stiffness'"),
    ("    type: revolute\n    actuation: k*t\n", "actuation", "unknown name 'k'"),
])
def test_joint_force_mistakes_name_file_line_and_key(entry, key, fragment):
    text = HEAD + entry
    line = text.count("\n")  # the mistake is on the last line
    with pytest.raises(mb.ModelError) as err:
        mb.loads(text, name="bad.yaml")
    message = str(err.value)
    assert message.startswith(f"bad.yaml:{line}: at joints[0].{key}:"), message
    assert fragment in message, message
