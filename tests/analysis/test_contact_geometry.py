"""Contact shapes beyond a sphere (io/unilateral.py): a box's corners and a capsule's end
spheres against the ground, a sphere against a capsule, two capsules (their gap against
coal's distance), against the classical rigid-body
impact formulas (Newton's law on the normal rate, the impulse P along the unit normal n at
a point r from the centre of mass: P = (1 + e) v_n / (1/m + (r × n)ᵀ I⁻¹ (r × n)))."""

import subprocess
import sys
from pathlib import Path

import coal
import numpy as np
import pytest

import mbsynth as mb
from mbsynth.core.errors import ModelError

G = 9.81
M, A, B, C = 2.0, 0.4, 0.2, 0.1  # the box's mass and sizes
I_BOX = M / 12 * np.diag([B**2 + C**2, A**2 + C**2, A**2 + B**2])


def _box(h, e, rpy=(0, 0, 0), outputs=""):
    return mb.loads(f"""
name: box_drop
parameters: {{m: {M}, g: {G}, a: {A}, b: {B}, c: {C}, h: {h}, e: {e}}}
gravity: [0, 0, -g]
parts:
  block:
    type: rigid_body
    mass: m
    inertia: [{float(I_BOX[0, 0])!r}, {float(I_BOX[1, 1])!r}, {float(I_BOX[2, 2])!r}]
    initial: {{position: [0, 0, h], rpy: {list(rpy)}}}
contacts:
  - {{name: floor, type: plane, child: block, box: [a, b, c], restitution: e}}
""" + outputs)


def _rpy(roll, pitch, yaw):
    cx, sx, cy, sy, cz, sz = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return (np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]]) @ np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
            @ np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]]))


def _omega(q, qd):
    """The world angular velocity of a body of quaternion q (w, x, y, z) and rate q̇: 2 q̇ q*."""
    w, x, y, z = q
    G_ = np.array([[-x, w, -z, y], [-y, z, w, -x], [-z, -y, x, w]])
    return 2 * G_ @ qd


def test_a_box_dropped_flat_strikes_its_four_lower_corners_at_once_and_rebounds_at_e_v():
    """Dropped flat from h, the lower corners touch at t = √(2(h − c/2)/g) at speed v = g t:
    after the simultaneous impact the box rises at e v without turning, the corners' impulses
    adding up to m (1 + e) v; with e = 0 it rests on the floor, which carries m g."""
    h, e = 0.3, 0.5
    traj = mb.simulate(_box(h, e), 0.3, dt=0.01, rtol=1e-10, atol=1e-10)
    t1 = np.sqrt(2 * (h - C / 2) / G)
    first = [ev for ev in traj.events if ev.kind == "impact" and abs(ev.t - t1) < 1e-9]
    assert first and {ev.name for ev in first} <= {f"floor[{k}]" for k in range(4)}
    assert sum(ev.impulse for ev in first) == pytest.approx(M * (1 + e) * G * t1, rel=1e-9)
    after = traj.t > t1 + 1e-6
    k = int(np.argmax(after))
    vz = traj.qd[k, 2] + G * (traj.t[k] - t1)  # back to the instant after the impact
    assert vz == pytest.approx(e * G * t1, rel=1e-8)
    assert np.abs(traj.qd[after][:, 3:]).max() < 1e-9  # no turning
    forces = "".join(f"  f{k}: {{contact: 'floor[{k}].force'}}\n" for k in range(8))
    rest = mb.simulate(_box(h, 0.0, outputs="outputs:\n" + forces), 0.5, dt=0.01, rtol=1e-10, atol=1e-10)
    late = rest.t > t1 + 1e-6
    assert np.abs(rest.q[late, 2] - C / 2).max() < 1e-9
    total = sum(rest.column(f"f{k}") for k in range(8))
    assert np.abs(total[late] - M * G).max() < 1e-8


def test_a_box_tipped_on_a_corner_takes_the_classical_impulse_there():
    """Tipped (roll 0.3, pitch 0.2), it falls onto its lowest corner alone: the impulse there
    is (1 + e) v / (1/m + (r × n)ᵀ I⁻¹ (r × n)) and the jump of the centre's velocity P n / m,
    of the angular velocity I⁻¹ (r × P n) (I the world inertia R I_body Rᵀ)."""
    e, rpy = 0.5, (0.3, 0.2, 0.0)
    R = _rpy(*rpy)
    corners = [R @ (np.array([(2 * (k >> j & 1) - 1) for j in range(3)]) * np.array([A, B, C]) / 2) for k in range(8)]
    lowest = int(np.argmin([x[2] for x in corners]))
    h = 0.25 - corners[lowest][2]
    traj = mb.simulate(_box(h, e, rpy), 0.25, dt=0.01, rtol=1e-11, atol=1e-11)
    impact = traj.events[0]
    assert (impact.name, impact.kind) == (f"floor[{lowest}]", "impact")
    t1 = np.sqrt(2 * 0.25 / G)
    assert impact.t == pytest.approx(t1, rel=1e-9)
    v, n, r = G * t1, np.array([0.0, 0.0, 1.0]), corners[lowest]
    I_world = R @ I_BOX @ R.T
    rn = np.cross(r, n)
    P = (1 + e) * v / (1 / M + rn @ np.linalg.solve(I_world, rn))
    assert impact.impulse == pytest.approx(P, rel=1e-8)
    k = int(np.argmax(traj.t > t1))  # the first row after it, before any other impact
    assert traj.t[k] < min([ev.t for ev in traj.events[1:]], default=np.inf)
    dt = traj.t[k] - t1
    assert traj.qd[k, :3] == pytest.approx([0.0, 0.0, -v + P / M - G * dt], abs=1e-8)
    omega = np.linalg.solve(I_world, np.cross(r, P * n))  # torque-free after: L constant, ω follows R(t)
    L = I_world @ omega
    R_k = _quaternion_matrix(traj.q[k, 3:])
    assert R_k @ I_BOX @ R_k.T @ _omega(traj.q[k, 3:], traj.qd[k, 3:]) == pytest.approx(L, abs=1e-8)


def _quaternion_matrix(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _capsule(theta, e):
    return mb.loads(f"""
name: capsule_drop
parameters: {{m: 1.5, g: {G}, r: 0.03, L: 0.6, e: {e}, theta: {theta}}}
gravity: [0, 0, -g]
parts:
  rod:
    type: rigid_body
    mass: m
    inertia: [m*L**2/12, m*L**2/12, m*r**2/2]
    initial: {{position: [0, 0, 0.2 + r + L/2*cos(theta)], rpy: [0, theta, 0]}}
contacts:
  - {{name: floor, type: plane, child: rod, capsule: [r, L], restitution: e}}
""")


@pytest.mark.parametrize("e", [0.0, 0.8])
def test_a_capsule_falling_on_one_end_takes_the_rod_on_one_end_impulse(e):
    """A capsule (a rod of length L between its end spheres' centres) tilted θ from the
    vertical falls 0.2 onto its lower end ([0], at −L/2 along its axis): with d = (L/2) sin θ
    the horizontal arm, P = m (1 + e) v / (1 + m d²/I), I = m L²/12; after it the centre
    moves at −v + P/m and the rod turns at ω = P d / I about y (e > 0: it flies off)."""
    theta, m, L = 0.4, 1.5, 0.6
    traj = mb.simulate(_capsule(theta, e), 0.21, dt=0.01, rtol=1e-11, atol=1e-11)
    t1 = np.sqrt(2 * 0.2 / G)
    impact = next(ev for ev in traj.events if ev.kind == "impact")
    assert (impact.name, impact.t) == ("floor[0]", pytest.approx(t1, rel=1e-9))
    v, d, inertia = G * t1, L / 2 * np.sin(theta), m * L**2 / 12
    P = m * (1 + e) * v / (1 + m * d**2 / inertia)
    assert impact.impulse == pytest.approx(P, rel=1e-8)
    if e == 0:  # its end stays on the floor: no free flight to compare with
        return
    k = int(np.argmax(traj.t > t1))
    dt = traj.t[k] - t1
    assert traj.qd[k, 2] == pytest.approx(-v + P / m - G * dt, abs=1e-8)
    assert _omega(traj.q[k, 3:], traj.qd[k, 3:]) == pytest.approx([0.0, P * d / inertia, 0.0], abs=1e-8)


def _sphere_capsule(offset, e):
    return mb.loads(f"""
name: sphere_capsule
parameters: {{m1: 0.4, m2: 1.2, r: 0.05, R: 0.03, L: 0.5, v: 2.0, e: {e}, s: {offset}}}
parts:
  ball: {{type: particle, mass: m1, initial: {{position: [-0.3, 0, s], velocity: [v, 0, 0]}}}}
  rod: {{type: rigid_body, mass: m2, inertia: [m2*L**2/12, m2*L**2/12, m2*R**2/2]}}
contacts:
  - {{name: hit, type: spheres, between: [ball, rod], radius: [r, R], length: [0, L], restitution: e}}
""")


@pytest.mark.parametrize("offset", [0.0, 0.15])
@pytest.mark.parametrize("e", [0.5, 1.0])  # they part after it (e = 0 holds a contact: a slow phase to build)
def test_a_sphere_striking_a_capsule_across_its_axis_takes_the_effective_mass_impulse(offset, e):
    """A ball (m1, moving at v along x) strikes an upright capsule (m2, I = m2 L²/12 about its
    centre) at height s on its segment: the normal is x, and P = (1 + e) v / (1/m1 + 1/m2 +
    s²/I) (head-on at s = 0: the textbook v1' = (m1 − e m2) v/(m1 + m2)); it strikes when
    the ball has covered 0.3 − r − R."""
    m1, m2, L, v, r, R = 0.4, 1.2, 0.5, 2.0, 0.05, 0.03
    traj = mb.simulate(_sphere_capsule(offset, e), 0.115, dt=0.005, rtol=1e-11, atol=1e-11)
    impact = traj.events[0]
    assert (impact.name, impact.kind) == ("hit", "impact")
    assert impact.t == pytest.approx((0.3 - r - R) / v, rel=1e-9)
    P = (1 + e) * v / (1 / m1 + 1 / m2 + offset**2 / (m2 * L**2 / 12))
    assert impact.impulse == pytest.approx(P, rel=1e-8)
    assert traj.qd[-1, 0] == pytest.approx(v - P / m1, abs=1e-8)
    assert traj.qd[-1, 3] == pytest.approx(P / m2, abs=1e-8)
    if offset == 0:
        assert traj.qd[-1, 0] == pytest.approx((m1 - e * m2) * v / (m1 + m2), abs=1e-8)


def test_a_sphere_beyond_a_capsules_end_strikes_its_end_sphere():
    """A ball moving down the capsule's axis (s beyond L/2) meets its end sphere: at the
    distance 0.3 − r − R − ... from the end's centre, head-on, P = (1 + e) v m1 m2/(m1 + m2)."""
    system = mb.loads("""
name: end_on
parameters: {m1: 0.4, m2: 1.2, r: 0.05, R: 0.03, L: 0.5, v: 2.0}
parts:
  ball: {type: particle, mass: m1, initial: {position: [0, 0, 0.6], velocity: [0, 0, -v]}}
  rod: {type: rigid_body, mass: m2, inertia: [m2*L**2/12, m2*L**2/12, m2*R**2/2]}
contacts:
  - {name: hit, type: spheres, between: [ball, rod], radius: [r, R], length: [0, L], restitution: 1}
""")
    traj = mb.simulate(system, 0.2, dt=0.01, rtol=1e-11, atol=1e-11)
    impact = traj.events[0]
    assert impact.t == pytest.approx((0.6 - 0.25 - 0.05 - 0.03) / 2.0, rel=1e-9)
    assert impact.impulse == pytest.approx(2 * 2.0 * 0.4 * 1.2 / 1.6, rel=1e-9)
    assert traj.qd[-1, [2, 5]] == pytest.approx([-2.0 * (0.4 - 1.2) / 1.6, -2 * 0.4 * 2.0 / 1.6], abs=1e-9)


def test_two_spheres_colliding_obliquely_exchange_normal_velocities_by_e_and_keep_tangential_ones():
    """Sphere 1 (m1, velocity v along x) strikes sphere 2 (m2, at rest) offset by b across:
    the normal n = (√(D² − b²), b, 0)/D (D = r1 + r2); along n the textbook
    v1n' = (m1 − e m2) v_n/(m1 + m2), v2n' = (1 + e) m1 v_n/(m1 + m2); across n nothing
    changes."""
    m1, m2, r1, r2, v, b, e = 0.3, 0.5, 0.04, 0.06, 1.5, 0.05, 0.7
    system = mb.loads(f"""
name: oblique
parameters: {{m1: {m1}, m2: {m2}, v: {v}}}
parts:
  one: {{type: particle, mass: m1, initial: {{position: [-0.4, 0, 0], velocity: [v, 0, 0]}}}}
  two: {{type: particle, mass: m2, initial: {{position: [0, {b}, 0]}}}}
contacts:
  - {{name: hit, type: spheres, between: [one, two], radius: [{r1}, {r2}], restitution: {e}}}
""")
    traj = mb.simulate(system, 0.5, dt=0.01, rtol=1e-11, atol=1e-11)
    D = r1 + r2
    n = np.array([np.sqrt(D**2 - b**2), b, 0.0]) / D
    assert traj.events[0].t == pytest.approx((0.4 - np.sqrt(D**2 - b**2)) / v, rel=1e-9)
    vn = v * n[0]
    v1 = np.array([v, 0, 0]) + ((m1 - e * m2) * vn / (m1 + m2) - vn) * n
    v2 = (1 + e) * m1 * vn / (m1 + m2) * n
    assert traj.qd[-1] == pytest.approx(np.concatenate([v1, v2]), abs=1e-10)


HEAD = """name: bad
parts:
  block: {type: rigid_body, mass: 1, inertia: [1, 1, 1], initial: {position: [0, 0, 1]}}
  ball: {type: particle, mass: 1, initial: {position: [2, 0, 1]}}
contacts:
"""


@pytest.mark.parametrize("entry, message", [
    ("{name: floor, type: plane, child: block, box: [0.4, 0.2]}",
     "contacts[0].box: expected a list of 3 numbers or expressions, got a list of 2"),
    ("{name: floor, type: plane, child: block, capsule: 0.1}",
     "contacts[0].capsule: expected a list of 2 numbers or expressions, got float"),
    ("{name: floor, type: plane, child: block, box: [0.4, -0.2, 0.1]}",
     "contacts[0].box[1]: a contact's dimensions are > 0, got -0.2"),
    ("{name: floor, type: plane, child: block, capsule: [0.1, 0]}",
     "contacts[0].capsule[1]: a contact's dimensions are > 0, got 0"),
    ("{name: floor, type: plane, child: block, radius: 0.1, box: [1, 1, 1]}",
     "contacts[0].box: a contact has one of radius, capsule, box, got radius and box"),
    ("{name: floor, type: plane, child: lid, box: [1, 1, 1]}", "contacts[0].child"),
    ("{name: hit, type: spheres, between: [ball, block], radius: [0.1, -0.1], length: [0.2, 0.3]}",
     "contacts[0].radius[1]: a radius is ≥ 0, got -0.1"),
    ("{name: hit, type: spheres, between: [ball, block], radius: [0.1, 0.1], length: [0.2, -0.3]}",
     "contacts[0].length[1]: a length is ≥ 0, got -0.3"),
    ("{name: hit, type: spheres, between: [block, block], radius: [0.1, 0.1], length: [0.2, 0.3]}",
     "contacts[0].between: the two spheres must be on two parts"),
    ("{name: hit, type: spheres, between: [ball, block], radius: [0.1, 0.1], length: [0, -1]}",
     "contacts[0].length[1]: a length is ≥ 0, got -1"),
])
def test_a_contact_shape_without_its_sizes_or_with_bad_ones_is_refused_at_its_line(entry, message):
    with pytest.raises(ModelError) as err:
        mb.loads(HEAD + f"  - {entry}\n", name="bad.yaml")
    assert str(err.value).startswith("bad.yaml:6: at " + message), str(err.value)


@pytest.mark.parametrize("roll, pitch", [(0.3, 0.0), (0.3, 0.2)])
def test_a_tipped_box_falls_over_onto_its_face_and_rests_there_carrying_its_weight(roll, pitch):
    """models/contact/box_drop.yaml with e = 0, tipped: it lands on an edge or a corner,
    falls over onto its face and rests on its corners (a corner tipping in from rest below
    the contact tolerance is held, not left to sink: no chatter), the centre at c/2 and the
    corners' forces adding up to m g."""
    text = (Path(__file__).resolve().parents[2] / "models" / "contact" / "box_drop.yaml").read_text()
    forces = "".join(f"  f{k}: {{contact: 'floor[{k}].force'}}\n" for k in range(8))
    system = mb.loads(text + forces, parameters={"e": 0.0, "roll": roll, "pitch": pitch})
    traj = mb.simulate(system, 1.0, rtol=1e-10, atol=1e-10)
    assert traj.status == "completed"
    assert traj.q[-1, 2] == pytest.approx(C / 2, abs=1e-9)
    assert sum(traj.column(f"f{k}") for k in range(8))[-1] == pytest.approx(M * G, rel=1e-8)


def test_the_command_line_refuses_a_box_with_a_negative_size_with_one_line(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(HEAD + "  - {name: floor, type: plane, child: block, box: [0.4, -0.2, 0.1]}\n")
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "simulate", str(path), "--t-end", "1"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0
    assert "bad.yaml:6: at contacts[0].box[1]: a contact's dimensions are > 0, got -0.2" in done.stderr


R1, R2, L1, L2 = 0.05, 0.08, 0.6, 0.9  # the two capsules' radii and segment lengths


@pytest.fixture(scope="module")
def capsules():
    return mb.loads(f"""
name: two_capsules
parts:
  one: {{type: rigid_body, mass: 1, inertia: [1, 1, 1]}}
  two: {{type: rigid_body, mass: 1, inertia: [1, 1, 1], initial: {{position: [0, 0, 1]}}}}
contacts:
  - {{name: hit, type: spheres, between: [one, two], radius: [{R1}, {R2}], length: [{L1}, {L2}]}}
""")


def _quaternion(axis, spin):
    """The unit quaternion (w, x, y, z) that turns by ``spin`` about z, then z onto ``axis``."""
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    across = np.cross([0.0, 0.0, 1.0], axis)
    angle = np.arctan2(np.linalg.norm(across), axis[2])
    across = across / np.linalg.norm(across) if np.linalg.norm(across) > 0 else np.array([1.0, 0.0, 0.0])
    turn = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * across])
    return _product(turn, [np.cos(spin / 2), 0.0, 0.0, np.sin(spin / 2)])


def _product(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def _poses(rng):
    """[(kind, q)] of the two capsules: crossed, skew, parallel (and antiparallel) side by side
    overlapping or not, end to end along one line, an end against a side."""
    found = []
    for _ in range(6):
        u = _unit(rng.normal(size=3))
        w = _unit(np.cross(u, rng.normal(size=3)))
        v = np.cross(u, w)
        s, t = rng.uniform(-L1 / 2, L1 / 2), rng.uniform(-L2 / 2, L2 / 2)
        c1 = rng.normal(size=3)
        gap = rng.uniform(0.01, 0.3)
        found.append(("crossed", c1, u, c1 + s * u + (R1 + R2 + gap) * w - t * v, v))
        found.append(("skew", c1, u, c1 + rng.normal(size=3), _unit(rng.normal(size=3))))
        sign = rng.choice([-1.0, 1.0])
        found.append(("parallel", c1, u, c1 + rng.uniform(-1.2, 1.2) * u + (R1 + R2 + gap) * w, sign * u))
        found.append(("end to end", c1, u, c1 + sign * ((L1 + L2) / 2 + R1 + R2 + gap) * u,
                      rng.choice([-1.0, 1.0]) * u))
        tilt = _unit(u + rng.uniform(-0.3, 0.3) * w)
        found.append(("end to side", c1, w, c1 + s * u + (R1 + R2 + gap + L1 / 2) * w + L2 / 2 * tilt, tilt))
    return [(kind, np.concatenate([c1, _quaternion(u1, rng.uniform(0, 6)), c2, _quaternion(u2, rng.uniform(0, 6))]))
            for kind, c1, u1, c2, u2 in found]


def _unit(v):
    return v / np.linalg.norm(v)


def _coal_distance(q):
    """coal's distance between the capsules at q (its Capsule(radius, length) along z, centred)."""
    shapes = [coal.Capsule(R1, L1), coal.Capsule(R2, L2)]
    frames = [coal.Transform3s(_quaternion_matrix(q[k + 3:k + 7]), q[k:k + 3]) for k in (0, 7)]
    return coal.distance(shapes[0], frames[0], shapes[1], frames[1], coal.DistanceRequest(), coal.DistanceResult())


def _moved(q, twist, h):
    """q after moving both bodies for h along ``twist`` (per body: velocity, world angular velocity)."""
    q = q.copy()
    for k, (v, w) in zip((0, 7), twist):
        q[k:k + 3] += h * v
        angle = np.linalg.norm(w) * h
        turn = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * w / np.linalg.norm(w)])
        q[k + 3:k + 7] = _product(turn, q[k + 3:k + 7])
    return q


@pytest.mark.slow  # two capsules' rows take a minute to derive with a cold cache (make test-slow)
def test_two_capsules_gap_is_coals_distance_and_its_rates_are_coals_derivatives(capsules):
    """At seeded poses of each kind the gap is coal's capsule distance to 1e-9; along a rigid
    motion of both (velocities v, world angular velocities ω, the quaternions' q̇ = ½ ω q and
    q̈ = −¼|ω|² q) the row's rate a q̇ and g̈ = a q̈ − b are coal's distance differentiated
    by central differences (parallel capsules turned alike)."""
    hit, p = capsules.unilaterals[0], capsules.parameter_values
    rng = np.random.default_rng(7)
    kinds = set()
    for kind, q in _poses(rng):
        distance = _coal_distance(q)
        assert distance > 0.005, kind
        g = hit.row.residuals(0.0, q, np.zeros(14), p)[0][0]
        assert g == pytest.approx(distance, abs=1e-9), kind
        twist = [(rng.normal(size=3), rng.normal(size=3)) for _ in range(2)]
        if kind == "parallel":  # turned alike, they stay parallel: turned apart, the nearest pair jumps to an
            twist[1] = (twist[1][0], twist[0][1])  # end of the overlap, where the distance has a kink
        qd, qdd = np.zeros(14), np.zeros(14)
        for k, (v, w) in zip((0, 7), twist):
            qd[k:k + 3] = v
            qd[k + 3:k + 7] = 0.5 * _product(np.concatenate([[0.0], w]), q[k + 3:k + 7])
            qdd[k + 3:k + 7] = -0.25 * w @ w * q[k + 3:k + 7]
        a, b, _ = hit.row.evaluate(0.0, q, qd, p)
        h = 1e-5
        rate = (_coal_distance(_moved(q, twist, h)) - _coal_distance(_moved(q, twist, -h))) / (2 * h)
        assert a[0] @ qd[hit.row.indices] == pytest.approx(rate, abs=1e-6), kind
        h = 1e-4
        second = (_coal_distance(_moved(q, twist, h)) - 2 * distance + _coal_distance(_moved(q, twist, -h))) / h**2
        assert a[0] @ qdd[hit.row.indices] - b[0] == pytest.approx(second, abs=1e-4 * max(1.0, abs(second))), kind
        kinds.add(kind)
    assert len(kinds) == 5


@pytest.mark.slow  # two capsules' rows take a minute to derive with a cold cache (make test-slow)
@pytest.mark.parametrize("angle", [0.0, 3e-10, 1e-7, 1e-5])
@pytest.mark.parametrize("across", [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
def test_nearly_parallel_capsules_gap_is_coals_distance(capsules, angle, across):
    """Two capsules side by side along z, the second's axis turned by ``angle`` towards the
    offset (x) or across it (y): within PARALLEL_SIN2 (sin² < 1e-16) and beyond it the gap
    is coal's distance to 1e-9, with no division by the angle (finite a and b)."""
    hit, p = capsules.unilaterals[0], capsules.parameter_values
    axis = np.cos(angle) * np.array([0.0, 0.0, 1.0]) + np.sin(angle) * np.array(across)
    q = np.concatenate([[0.0, 0.0, 0.0], _quaternion([0, 0, 1], 0.0), [0.2, 0.0, 0.1], _quaternion(axis, 0.0)])
    assert hit.row.residuals(0.0, q, np.zeros(14), p)[0][0] == pytest.approx(_coal_distance(q), abs=1e-9)
    a, b, _ = hit.row.evaluate(0.0, q, np.full(14, 0.1), p)
    assert np.isfinite(a).all() and np.isfinite(b).all()


CROSSED = (Path(__file__).resolve().parents[2] / "models" / "contact" / "crossed_capsules.yaml").read_text()


@pytest.mark.slow  # two capsules' rows take a minute to derive with a cold cache (make test-slow)
@pytest.mark.parametrize("ox, oy", [(0.0, 0.0), (0.25, -0.1)])
@pytest.mark.parametrize("e", [0.5, 1.0])
def test_two_capsules_crossing_at_right_angles_take_the_two_body_impulse(e, ox, oy):
    """models/contact/crossed_capsules.yaml: a bar (m1, along x, at rest) and a rod (m2, along
    y, falling at v along −z) cross at right angles, touching at ox along the bar and oy
    along the rod: the normal is z, the arms across it ox and oy, and P = (1 + e) v / (1/m1 +
    1/m2 + ox²/I1 + oy²/I2) (I = m L²/12): after it the bar moves at −P/m1 and turns at
    P ox/I1 about y, the rod at −v + P/m2 and P oy/I2 about x; their contact points part
    at e v."""
    m1, m2, r1, r2, l1, l2, v = 1.5, 0.8, 0.04, 0.03, 0.8, 0.6, 1.5
    i1, i2 = m1 * l1**2 / 12, m2 * l2**2 / 12
    traj = mb.simulate(mb.loads(CROSSED, parameters={"e": e, "ox": ox, "oy": oy}), 0.2, dt=0.01, rtol=1e-12, atol=1e-12)
    impact = traj.events[0]
    assert (impact.name, impact.kind) == ("hit", "impact")
    assert impact.t == pytest.approx((0.3 - r1 - r2) / v, rel=1e-10)
    assert len([ev for ev in traj.events if ev.kind == "impact"]) == 1
    P = (1 + e) * v / (1 / m1 + 1 / m2 + ox**2 / i1 + oy**2 / i2)
    assert impact.impulse == pytest.approx(P, rel=1e-10)
    q, qd = traj.q[-1], traj.qd[-1]
    assert qd[:3] == pytest.approx([0.0, 0.0, -P / m1], abs=1e-10)
    assert qd[7:10] == pytest.approx([0.0, 0.0, -v + P / m2], abs=1e-10)
    w1, w2 = _omega(q[3:7], qd[3:7]), _omega(q[10:14], qd[10:14])
    assert w1 == pytest.approx([0.0, P * ox / i1, 0.0], abs=1e-10)
    assert w2 == pytest.approx([P * oy / i2, 0.0, 0.0], abs=1e-10)
    parting = (qd[9] + w2[0] * oy) - (qd[2] - w1[1] * ox)  # the contact points' normal velocities just after
    assert parting == pytest.approx(e * v, abs=1e-10)
