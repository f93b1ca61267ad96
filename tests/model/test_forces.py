"""Force elements (springs, dampers, applied forces and torques) and the ``spring`` part,
each checked against a hand-derived equation of motion, a conservation law, or the other
way of modelling the same spring."""

import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
from tests.helpers.rotations import E, G

import mbsynth as mb
from mbsynth.analysis.diagnose import diagnose
from mbsynth.model.forces import applied_torque
from mbsynth.core.kinematics import quaternion_matrix

MODELS = Path(__file__).resolve().parents[2] / "models" / "forces"
RNG = np.random.default_rng(7)


@pytest.fixture(autouse=True)
def seeded():
    """The same random states whichever tests run."""
    global RNG
    RNG = np.random.default_rng(7)


def loads(text):
    return mb.loads(textwrap.dedent(text), name="model.yaml")


def random_body_state():
    """A unit quaternion u, u̇ = ½ Gᵀω tangent to uᵀu = 1, a position and a velocity."""
    u = RNG.normal(size=4)
    u /= np.linalg.norm(u)
    omega = RNG.normal(size=3)
    return RNG.normal(size=3), u, RNG.normal(size=3), G(u).T @ omega / 2, omega


def spring_force(pA, pB, vA, vB, k, l0, c):
    """The force of a spring-damper on its end B: −(k (ℓ − ℓ0) + c ℓ̇) e, e = (pB − pA)/ℓ."""
    d = pB - pA
    length = np.linalg.norm(d)
    e = d / length
    return -(k * (length - l0) + c * e @ (vB - vA)) * e


PARTICLE = """\
parameters: {{m: 0.8, k: 40.0, l0: 0.5, c: {c}, g: 9.81}}
gravity: [0, 0, -g]
world:
  frames:
    anchor: {{position: [0.1, -0.2, 1.5]}}
parts:
  p: {{type: particle, mass: m}}
forces:
  - {{name: s, type: spring, between: [world.anchor, p], stiffness: k, rest_length: l0, damping: c}}
"""


def test_particle_on_a_vertical_spring_and_damper():
    """On the vertical through the anchor: m z̈ = k (ℓ − ℓ0) − c ż − m g with ℓ = h − z."""
    system = loads(PARTICLE.format(c=0.6))
    m, k, l0, c, g, h = 0.8, 40.0, 0.5, 0.6, 9.81, 1.5
    for z, zd in [(0.7, 0.4), (1.2, -1.3), (1.3, 0.0)]:
        qdd = system.motion(0.0, [0.1, -0.2, z], [0.0, 0.0, zd]).qdd
        np.testing.assert_allclose(qdd, [0, 0, (k * (h - z - l0) - c * zd) / m - g], rtol=1e-12, atol=1e-12)


def test_particle_on_an_off_axis_spring_and_damper():
    """Anywhere: m a = −(k (ℓ − ℓ0) + c ℓ̇) e + m g, e the unit vector from the anchor."""
    system = loads(PARTICLE.format(c=0.6))
    anchor = np.array([0.1, -0.2, 1.5])
    for _ in range(3):
        p, v = RNG.normal(size=3), RNG.normal(size=3)
        expected = spring_force(anchor, p, np.zeros(3), v, 40.0, 0.5, 0.6) / 0.8 + [0, 0, -9.81]
        np.testing.assert_allclose(system.motion(0.0, p, v).qdd, expected, rtol=1e-12)


def test_coincident_spring_ends_give_no_force():
    """At ℓ = 0 the line of action is undefined; the spring and damper (a force element or
    a part) then exert nothing, silently."""
    element = loads(PARTICLE.format(c=0.6))
    part = loads("""\
        parameters: {m: 0.8}
        gravity: [0, 0, -9.81]
        parts:
          s: {type: spring, mass: m, stiffness: 40, rest_length: 0.5, damping: 0.6}
        """)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        element_qdd = element.motion(0.0, [0.1, -0.2, 1.5], [1.0, 2.0, 3.0]).qdd
        part_qdd = part.motion(0.0, np.zeros(6), np.r_[1.0, 2.0, 3.0, 0.0, 0.0, 0.0]).qdd
    np.testing.assert_allclose(element_qdd, [0, 0, -9.81], rtol=1e-15)
    np.testing.assert_allclose(part_qdd, [0, 0, -9.81] * 2, rtol=1e-15)


BODY = """\
parameters: {k: 30.0, l0: 0.4, c: 0.7, m: 2.0}
gravity: [0, 0, -9.81]
world:
  frames:
    anchor: {position: [0.2, 0.3, 1.0]}
parts:
  body:
    type: rigid_body
    mass: m
    inertia: [[0.3, 0.02, 0.0], [0.02, 0.5, 0.01], [0.0, 0.01, 0.4]]
    frames:
      tip: {position: [0.1, -0.25, 0.35]}
"""


def body_model(snippet, gravity=-9.81):
    return mb.loads(BODY.replace("-9.81", str(gravity)) + textwrap.dedent(snippet), name="model.yaml")


TIP = np.array([0.1, -0.25, 0.35])
J_BODY = np.array([[0.3, 0.02, 0.0], [0.02, 0.5, 0.01], [0.0, 0.01, 0.4]])


def test_force_element_spring_equals_the_spring_part():
    """The same spring as a force element and as a massless ``spring`` part joined by
    spherical joints to the world and the body: the body's q̈ agree at random states."""
    element = body_model("""\
        forces:
          - {type: spring, between: [world.anchor, body.tip], stiffness: k, rest_length: l0, damping: c}
        """)
    part = body_model("""\
          s: {type: spring, stiffness: k, rest_length: l0, damping: c}
        joints:
          - {name: fixed_end, type: spherical, parent: world.anchor, child: s.end1}
          - {name: body_end, type: spherical, parent: body.tip, child: s.end2}
        """)
    assert part.coordinates[7:] == tuple(f"s.{c}" for c in ("x1", "y1", "z1", "x2", "y2", "z2"))
    anchor = np.array([0.2, 0.3, 1.0])
    for _ in range(4):
        r, u, rd, ud, omega = random_body_state()
        arm = quaternion_matrix(u) @ TIP
        tip, tip_velocity = r + arm, rd + np.cross(omega, arm)
        q, qd = np.concatenate([r, u]), np.concatenate([rd, ud])
        expected = element.motion(0.0, q, qd).qdd
        got = part.motion(0.0, np.concatenate([q, anchor, tip]), np.concatenate([qd, np.zeros(3), tip_velocity]))
        scale = np.abs(expected).max()
        np.testing.assert_allclose(got.qdd[:7], expected, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(got.qdd[7:10], 0, atol=1e-10 * scale)   # the world end stays put


def chain_state(system):
    """A random 3D state of spring_part_chain.yaml with the springs' ends on the masses."""
    p1, p2, v1, v2 = (RNG.normal(size=3) for _ in range(4))
    p2 += [0, 0, -1.5]
    values = {"mass1": (p1, v1), "mass2": (p2, v2), "spring1": (np.r_[0, 0, 0, p1], np.r_[0, 0, 0, v1]),
              "spring2": (np.r_[p1, p2], np.r_[v1, v2])}
    q = np.concatenate([values[part.name][0] for part in system.parts])
    qd = np.concatenate([values[part.name][1] for part in system.parts])
    return q, qd


def test_chain_of_spring_parts_equals_the_two_mass_closed_form():
    """Ceiling – spring part – m1 – spring part – m2 (the paper's example 3 by substructuring):
    m1 a1 = −k1 (ℓ1 − l10) e1 + k2 (ℓ2 − l20) e2 + m1 g,  m2 a2 = −k2 (ℓ2 − l20) e2 + m2 g."""
    system = mb.load(MODELS / "spring_part_chain.yaml")
    m1, m2, k1, k2, l10, l20, g = (system.parameters[k] for k in ("m1", "m2", "k1", "k2", "l10", "l20", "g"))
    gravity = np.array([0, 0, -g])
    index = {c: i for i, c in enumerate(system.coordinates)}
    for q, qd in [system.initial_state()] + [chain_state(system) for _ in range(3)]:
        p1, p2 = q[[index[f"mass1.{c}"] for c in "xyz"]], q[[index[f"mass2.{c}"] for c in "xyz"]]
        v1, v2 = qd[[index[f"mass1.{c}"] for c in "xyz"]], qd[[index[f"mass2.{c}"] for c in "xyz"]]
        f2 = spring_force(p1, p2, v1, v2, k2, l20, 0.0)
        a1 = (spring_force(np.zeros(3), p1, np.zeros(3), v1, k1, l10, 0.0) - f2) / m1 + gravity
        a2 = f2 / m2 + gravity
        motion = system.motion(0.0, q, qd)
        assert motion.unique
        qdd = motion.qdd
        np.testing.assert_allclose(qdd[[index[f"mass1.{c}"] for c in "xyz"]], a1, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(qdd[[index[f"mass2.{c}"] for c in "xyz"]], a2, rtol=1e-10, atol=1e-10)
    q, qd = system.initial_state()   # vertical: m1 z̈1 = 100·0.1 − 60·0.15 − 1.5 g, m2 z̈2 = 60·0.15 − 2 g
    qdd = system.motion(0.0, q, qd).qdd
    np.testing.assert_allclose([qdd[index["mass1.z"]], qdd[index["mass2.z"]]],
                               [(10 - 9) / 1.5 - 9.81, 9 / 2.0 - 9.81], rtol=1e-12)


def test_massive_spring_part_uses_the_consistent_bar_mass():
    """A uniform bar spring (mass m) with end 1 fixed: the free end has mass m/3 and carries
    half the bar's weight, so (m/3) a2 = −(k (ℓ − ℓ0) + c ℓ̇) e + m g/2."""
    system = loads("""\
        parameters: {m: 0.9, k: 25.0, l0: 0.6, c: 0.3}
        gravity: [0, 0, -9.81]
        parts:
          s: {type: spring, mass: m, stiffness: k, rest_length: l0, damping: c}
        joints:
          - {name: fix, type: spherical, parent: world, child: s.end1}
        """)
    p2, v2 = RNG.normal(size=3), RNG.normal(size=3)
    qdd = system.motion(0.0, np.r_[0, 0, 0, p2], np.r_[0, 0, 0, v2]).qdd
    expected = (spring_force(np.zeros(3), p2, np.zeros(3), v2, 25.0, 0.6, 0.3) + 0.9 * np.array([0, 0, -9.81]) / 2) * 3 / 0.9
    np.testing.assert_allclose(qdd, np.r_[0, 0, 0, expected], rtol=1e-12, atol=1e-12)


def test_check_reports_the_free_end_of_a_massless_spring():
    """A massless spring part with a free end: its three end coordinates carry no mass and
    no constraint (rank [M; A] = 3 of 6), and each needs the spring force along it to vanish."""
    system = loads("""\
        parameters: {k: 50.0, l0: 1.0}
        parts:
          s: {type: spring, stiffness: k, rest_length: l0, initial: {end2: [1.2, 0.3, 0.0]}}
        joints:
          - {name: fix, type: spherical, parent: world, child: s.end1}
        """)
    report = diagnose(system)
    assert (report.rank_M, report.rank_A, report.rank_Mhat) == (0, 3, 3) and not report.unique
    assert {c for w in report.indeterminate for c in w} == {"s.x2", "s.y2", "s.z2"}
    assert len(report.suggested_constraints) == 3 and not report.consistent  # stretched by 0.237: no balance


def test_applied_force_at_an_offset_frame():
    """F (world, time dependent) at the body point r: r̈ = F/m and, in body axes,
    ω̇ = J⁻¹(r × Rᵀ F − ω × J ω), read from ü as ω̇_body = 2 E(u) ü (E(u̇) u̇ = 0)."""
    system = body_model("""\
        forces:
          - {name: push, type: force, at: body.tip, value: [3*cos(2*t), -1.5, 2*t]}
        """, gravity=0)
    m, J = 2.0, J_BODY
    t = 0.8
    F = np.array([3 * np.cos(2 * t), -1.5, 2 * t])
    for _ in range(3):
        r, u, rd, ud, omega = random_body_state()
        qdd = system.motion(t, np.r_[r, u], np.r_[rd, ud]).qdd
        R = quaternion_matrix(u)
        w = R.T @ omega
        alpha = np.linalg.solve(J, np.cross(TIP, R.T @ F) - np.cross(w, J @ w))
        np.testing.assert_allclose(qdd[:3], F / m, rtol=1e-12)
        np.testing.assert_allclose(2 * E(u) @ qdd[3:], alpha, rtol=1e-10, atol=1e-12)


def test_body_and_world_torques_agree_and_obey_euler():
    """A torque Γ in world axes and Rᵀ Γ in body axes move the body alike at orientation R,
    with J ω̇ + ω × J ω = Rᵀ Γ (Euler); on a planar body θ̈ = Γ_z / I_zz."""
    r, u, rd, ud, omega = random_body_state()
    R = quaternion_matrix(u)
    torque = np.array([0.4, -1.1, 0.7])
    body = R.T @ torque
    systems = [body_model(f"""\
        forces:
          - {{type: torque, part: body, value: [{x[0]:.17g}, {x[1]:.17g}, {x[2]:.17g}], axes: {axes}}}
        """) for x, axes in ((torque, "world"), (body, "body"))]
    q, qd = np.r_[r, u], np.r_[rd, ud]
    world_qdd, body_qdd = (s.motion(0.0, q, qd).qdd for s in systems)
    np.testing.assert_allclose(body_qdd, world_qdd, rtol=1e-10, atol=1e-12)
    J, w = J_BODY, R.T @ omega
    np.testing.assert_allclose(2 * E(u) @ world_qdd[3:], np.linalg.solve(J, body - np.cross(w, J @ w)),
                               rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(world_qdd[:3], [0, 0, -9.81], rtol=1e-12)
    planar = loads("""\
        parts:
          disk: {type: planar_body, mass: 1.0, inertia: 0.25}
        forces:
          - {type: torque, part: disk, value: [0.3, 0.2, 0.5*t], axes: body}
        """)
    np.testing.assert_allclose(planar.motion(2.0, [0, 0, 0.7], [0, 0, 3.0]).qdd, [0, 0, 1.0 / 0.25], rtol=1e-12)


def test_applied_torque_rejects_unknown_axes():
    system = loads(BODY)
    with pytest.raises(ValueError, match="axes must be one of"):
        applied_torque("m", system.parts[0], [0, 0, 1], "local", system.q_symbols, system.qd_symbols, [])


def energy_rate(system, t, q, qd):
    """d/dt (T + V) = ∇E · (q̇, q̈) along the motion: the five-point derivative of E on
    the line (t + s, q + s q̇, q̇ + s q̈) at s = 0 (error O(h⁴))."""
    qdd = system.motion(t, q, qd).qdd
    h = 1e-3

    def energy(s):
        return sum(system.energy(t + s, q + s * qd, qd + s * qdd))

    return (energy(-2 * h) - 8 * energy(-h) + 8 * energy(h) - energy(2 * h)) / (12 * h)


def test_energy_of_a_particle_on_a_spring():
    """T + V = ½ m v² + ½ k (ℓ − ℓ0)² + m g z is conserved without the damper and falls
    at the rate c ℓ̇² with it."""
    anchor = np.array([0.1, -0.2, 1.5])
    p, v = RNG.normal(size=3), RNG.normal(size=3)
    system = loads(PARTICLE.format(c=0.0))
    length = np.linalg.norm(p - anchor)
    T, V = system.energy(0.0, p, v)
    assert T == pytest.approx(0.5 * 0.8 * v @ v, rel=1e-14)
    assert V == pytest.approx(0.5 * 40.0 * (length - 0.5) ** 2 + 0.8 * 9.81 * p[2], rel=1e-14)
    assert abs(energy_rate(system, 0.0, p, v)) < 1e-8 * (T + abs(V))
    damped = loads(PARTICLE.format(c=0.6))
    length_rate = (p - anchor) @ v / length
    assert energy_rate(damped, 0.0, p, v) == pytest.approx(-0.6 * length_rate**2, abs=1e-9 * (T + abs(V)))


def test_energy_of_the_spring_pendulum_and_the_spring_chain():
    """A rigid body on a spring (force element) and the spring-part chain: with the dampers
    off, d/dt (T + V) = 0 along the constrained motion."""
    pendulum = mb.load(MODELS / "spring_pendulum.yaml").with_parameters(c=0.0)
    r, u, rd, ud, _ = random_body_state()
    q, qd = np.r_[r, u], np.r_[rd, ud]
    assert abs(energy_rate(pendulum, 0.0, q, qd)) < 1e-7 * sum(map(abs, pendulum.energy(0.0, q, qd)))
    chain = mb.load(MODELS / "spring_part_chain.yaml")
    q, qd = chain_state(chain)
    assert abs(energy_rate(chain, 0.0, q, qd)) < 1e-7 * sum(map(abs, chain.energy(0.0, q, qd)))


def test_energy_of_a_massive_spring_part():
    """The bar spring's T = m/6 (v1² + v1·v2 + v2²) and V = ½ k (ℓ − ℓ0)² − m g·(p1 + p2)/2."""
    system = loads("""\
        parameters: {m: 0.9, k: 25.0, l0: 0.6}
        gravity: [0, 0, -9.81]
        parts:
          s: {type: spring, mass: m, stiffness: k, rest_length: l0}
        """)
    q, qd = RNG.normal(size=6), RNG.normal(size=6)
    v1, v2 = qd[:3], qd[3:]
    T, V = system.energy(0.0, q, qd)
    assert T == pytest.approx(0.9 / 6 * (v1 @ v1 + v1 @ v2 + v2 @ v2), rel=1e-14)
    length = np.linalg.norm(q[3:] - q[:3])
    assert V == pytest.approx(0.5 * 25.0 * (length - 0.6) ** 2 + 0.9 * 9.81 * (q[2] + q[5]) / 2, rel=1e-14)
    assert abs(energy_rate(system, 0.0, q, qd)) < 1e-7 * (T + abs(V))


HEAD = """\
parameters: {k: 10.0}
world:
  frames:
    a: {position: [0, 0, 1]}
parts:
  p: {type: particle, mass: 1.0}
  b: {type: rigid_body, mass: 1.0, inertia: [1, 1, 1], frames: {tip: {position: [1, 0, 0]}}}
forces:
"""
FORCE_ERRORS = [
    ("  - {type: spring, between: [world.a, p], stiffness: -k, rest_length: 1}\n", "forces[0].stiffness",
     "stiffness must be ≥ 0"),
    ("  - {type: spring, between: [world.a, q], stiffness: k, rest_length: 1}\n", "forces[0].between[1]",
     "unknown part 'q'"),
    ("  - {type: spring, between: [world.a, b.top], stiffness: k, rest_length: 1}\n", "forces[0].between[1]",
     "'b' has no frame 'top'"),
    ("  - {type: spring, between: [world.a, world], stiffness: k, rest_length: 1}\n", "forces[0].between",
     "both ends are on the world"),
    ("  - {type: spring, between: [p], stiffness: k, rest_length: 1}\n", "forces[0].between", "expected two frames"),
    ("  - {type: spring, between: [world.a, p], stifness: k, rest_length: 1}\n", "forces[0].stifness",
     "did you mean 'stiffness'"),
    ("  - {type: damper, between: [world.a, p], damping: -1}\n", "forces[0].damping", "damping must be ≥ 0"),
    ("  - {type: damper, between: [world.a, p], damping: 1, stiffness: k}\n", "forces[0].stiffness",
     "unknown key 'stiffness'"),
    ("  - {type: spring, between: [world.a, p], stiffness: k}\n", "forces[0]", "missing required key 'rest_length'"),
    ("  - {type: push, at: p, value: [1, 0, 0]}\n", "forces[0].type", "unknown force type 'push'"),
    ("  - {at: p, value: [1, 0, 0]}\n", "forces[0]", "expected a mapping with 'type'"),
    ("  - {type: force, at: p, value: [1, 0]}\n", "forces[0].value", "a list of 3 numbers or expressions, got a list of 2"),
    ("  - {type: force, at: p, value: [1, 0, x]}\n", "forces[0].value[2]", "unknown name 'x'"),
    ("  - {type: force, at: world.a, value: [1, 0, 0]}\n", "forces[0].at", "not on the world"),
    ("  - {type: torque, part: p, value: [1, 0, 0]}\n", "forces[0].part", "'p' is a particle"),
    ("  - {type: torque, part: c, value: [1, 0, 0]}\n", "forces[0].part", "unknown part 'c'"),
    ("  - {type: torque, on: b, value: [1, 0, 0]}\n", "forces[0]", "YAML reads the key 'on' as true"),
    ("  - {type: torque, part: b, value: [1, 0, 0], axes: local}\n", "forces[0].axes", "axes must be one of world, body"),
    ("  - {name: f, type: force, at: p, value: [1, 0, 0]}\n  - {name: f, type: force, at: b, value: [1, 0, 0]}\n",
     "forces[1].name", "duplicate force name 'f'"),
]


@pytest.mark.parametrize("entry, where, fragment", FORCE_ERRORS)
def test_force_mistakes_name_file_line_and_key(entry, where, fragment):
    text = HEAD + entry
    line = text.count("\n") if where == "forces[1].name" else HEAD.count("\n") + 1
    with pytest.raises(mb.ModelError) as err:
        mb.loads(text, name="bad.yaml")
    message = str(err.value)
    assert message.startswith(f"bad.yaml:{line}: at {where}:"), message
    assert fragment in message, message


@pytest.mark.parametrize("text, line, fragment", [
    ("parts:\n  s:\n    type: spring\n    stiffness: 1\n    rest_length: -0.5\n", 5, "rest_length must be ≥ 0"),
    ("parts:\n  s:\n    type: spring\n    stiffness: 1\n", 2, "missing required key 'rest_length'"),
    ("parts:\n  s:\n    type: spring\n    stiffness: 1\n    rest_length: 1\n    initial: {end3: [0, 0, 0]}\n",
     6, "unknown key 'end3'"),
    ("parts:\n  s: {type: spring, stiffness: 1, rest_length: 1, initial: {end1: [0, 0]}}\n", 2,
     "list of 3 numbers"),
    ("parts:\n  s: {type: spring, stiffness: 1, rest_length: 1}\njoints:\n"
     "  - {name: j, type: spherical, parent: world, child: s}\n", 4, "a spring part has no frame of its own"),
])
def test_spring_part_mistakes(text, line, fragment):
    with pytest.raises(mb.ModelError) as err:
        mb.loads(text, name="bad.yaml")
    assert str(err.value).startswith(f"bad.yaml:{line}:"), str(err.value)
    assert fragment in str(err.value), str(err.value)


def test_spring_part_initial_state():
    system = loads("""\
        parts:
          s:
            type: spring
            stiffness: 1
            rest_length: 1
            initial: {end1: [1, 2, 3], end2: [4, 5, 6], end2_velocity: [7, 8, 9]}
        """)
    q, qd = system.initial_state()
    np.testing.assert_array_equal(q, [1, 2, 3, 4, 5, 6])
    np.testing.assert_array_equal(qd, [0, 0, 0, 7, 8, 9])
