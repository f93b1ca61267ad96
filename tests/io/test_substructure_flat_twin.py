"""A composed model and its flat twin are the same System.

The composed model nests two deep: ``top.yaml`` includes ``mid.yaml`` twice (placed by rpy and
by a quaternion, both with a translation), each ``mid.yaml`` includes ``link.yaml`` (placed by
rpy and a translation); parameters are overridden at both levels by expressions of the
including file's parameters. ``link.yaml`` holds a rigid arm on a revolute joint reached
through a port and a massless bead between two springs, closed by ``balances: auto`` (the
paper's example 3: the bead's force balance (5.40) is appended). The flat twin is written
here by hand, every placed pose and velocity computed with scipy's Rotation (not the
loader's placement code), with the same parts in the same order."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbsynth as mb

AGREE = 1e-12  # the twins' initial states and accelerations agree to rounding

LINK = """\
name: link
parameters: {m: 1.0, L: 0.5, k1: 40.0, k2: 60.0, w: 1.5, alpha: 0.3}
balances: auto
world:
  frames:
    anchor: {position: [0.1, -0.2, -0.3]}
parts:
  arm:
    type: rigid_body
    mass: m
    inertia: [m*L**2/200, m*L**2/12, m*L**2/12 + m*L**2/200]
    frames:
      hinge: {position: [-L/2, 0, 0]}
      tip: {position: [L/2, 0, 0]}
    initial:
      position: [L/2*cos(alpha), L/2*sin(alpha), 0]
      rpy: [0, 0, alpha]
      velocity: [-L/2*w*sin(alpha), L/2*w*cos(alpha), 0]
      angular_velocity: [0, 0, w]
  bead: {type: particle, mass: 0}
forces:
  - {name: inner, type: spring, between: [arm.tip, bead], stiffness: k1, rest_length: 0}
  - {name: outer, type: spring, between: [bead, world.anchor], stiffness: k2, rest_length: 0}
initial:
  bead.x: (k1*L*cos(alpha) + k2*0.1)/(k1 + k2)
  bead.y: (k1*L*sin(alpha) - k2*0.2)/(k1 + k2)
  bead.z: -k2*0.3/(k1 + k2)
ports: {hinge: arm.hinge}
"""
MID = """\
name: mid
parameters: {m: 1.0, L: 0.5, k: 50.0}
world:
  frames:
    socket: {}
parts:
  plate:
    type: rigid_body
    mass: 3*m
    inertia: [0.02*m, 0.03*m, 0.04*m]
    frames:
      top: {position: [0, 0, 0.2]}
      mount: {position: [0.3, 0, 0], rpy: [0.4, -0.3, 0.7]}
      hook: {position: [-0.2, 0.1, 0]}
    initial: {position: [0, 0, -0.2]}
  link:
    type: model
    file: link.yaml
    parameters: {m: m/2 + 0.1, L: 0.8*L, k1: k, k2: 2*k}
    placement: {position: [0.3, 0, -0.2], rpy: [0.4, -0.3, 0.7]}
  ball: {type: particle, mass: m/4, initial: {position: [-0.2, 0.1, -0.2]}}
joints:
  - {name: shoulder, type: spherical, parent: world.socket, child: plate.top}
  - {name: elbow, type: revolute, parent: plate.mount, child: link.hinge}
  - {name: hang, type: spherical, parent: plate.hook, child: ball}
ports: {bob: ball}
"""
TOP = """\
name: top
parameters: {m0: 1.2, L0: 0.6, k0: 30.0, g: 9.81}
gravity: [0, 0, -g]
parts:
  left:
    type: model
    file: mid.yaml
    parameters: {m: 2*m0, L: L0, k: k0}
    placement: {position: [0.5, 0, 1.0], rpy: [0.2, 0.5, -0.4]}
  hub: {type: particle, mass: m0/3, initial: {position: [0, 0.1, 0.8]}}
  right:
    type: model
    file: mid.yaml
    parameters: {m: m0 + 0.5, L: 1.2*L0}
    placement: {position: [-0.5, 0.2, 1.1], quaternion: [0.8, 0.2, -0.4, 0.4]}
forces:
  - {name: tether, type: spring, between: [hub, left.bob], stiffness: k0, rest_length: 0.3}
joints:
  - {name: leash, type: distance, parent: right.bob, child: hub, length: 0.5}
"""

M0, L0, K0 = 1.2, 0.6, 30.0  # top.yaml's parameters
# each copy of mid.yaml: its turn and shift in the world, and its parameters m, L, k as
# top.yaml gives them ({name: (expression, value)}; right's k is mid.yaml's own)
MIDS = {"left": (Rotation.from_euler("xyz", [0.2, 0.5, -0.4]), [0.5, 0, 1.0],
                 {"m": ("2*m0", 2 * M0), "L": ("L0", L0), "k": ("k0", K0)}),
        "right": (Rotation.from_quat([0.2, -0.4, 0.4, 0.8]), [-0.5, 0.2, 1.1],  # scipy: scalar last
                  {"m": ("m0 + 0.5", M0 + 0.5), "L": ("1.2*L0", 1.2 * L0), "k": ("50.0", 50.0)})}
LINK_IN_MID = (Rotation.from_euler("xyz", [0.4, -0.3, 0.7]), np.array([0.3, 0, -0.2]))  # link.yaml in mid.yaml
ALPHA, W, ANCHOR = 0.3, 1.5, np.array([0.1, -0.2, -0.3])


def numbers(vector):
    """A YAML list of the floats, every digit kept."""
    return "[" + ", ".join(repr(float(x)) for x in vector) + "]"


def quaternion(rotation):
    """Scalar-first, w ≥ 0 (the sign a model file's orientation gives)."""
    x, y, z, w = rotation.as_quat()
    return numbers(np.copysign(1.0, w) * np.array([w, x, y, z]))


def flat_twin():
    """The composed model written out by hand: every part of every file under its prefix
    (dots as underscores), the placements applied with scipy."""
    parameters = {"m0": "1.2", "L0": "0.6", "k0": "30.0", "g": "9.81"}
    world, parts, joints, forces, initial = [], [], [], [], []
    for side, (R_mid, t_mid, given) in MIDS.items():
        t_mid = np.array(t_mid, dtype=float)
        p = f"{side}_"
        parameters.update({p + key: text for key, (text, _) in given.items()})
        length, k = given["L"][1], given["k"][1]
        link = {"m": f"{p}m/2 + 0.1", "L": f"0.8*{p}L", "k1": f"{p}k", "k2": f"2*{p}k", "w": "1.5", "alpha": "0.3"}
        for key, text in link.items():
            parameters[f"{p}link_{key}"] = text
        L_link, k1, k2 = 0.8 * length, k, 2 * k  # link.yaml's L, k1, k2 as mid.yaml gives them

        def place(point, inner=(Rotation.identity(), np.zeros(3))):
            """A point of the file placed by ``inner`` (in mid.yaml) then by the mid's placement."""
            return R_mid.apply(inner[0].apply(point) + inner[1]) + t_mid

        R_link = R_mid * LINK_IN_MID[0]
        world += [f"    {p}socket: {{position: {numbers(t_mid)}, quaternion: {quaternion(R_mid)}}}",
                  f"    {p}link_anchor: {{position: {numbers(place(ANCHOR, LINK_IN_MID))}, "
                  f"quaternion: {quaternion(R_link)}}}"]
        arm = np.array([L_link / 2 * np.cos(ALPHA), L_link / 2 * np.sin(ALPHA), 0])
        arm_velocity = W * np.cross([0, 0, 1], arm)
        bead = np.array([k1 * L_link * np.cos(ALPHA) + k2 * ANCHOR[0], k1 * L_link * np.sin(ALPHA) + k2 * ANCHOR[1],
                         k2 * ANCHOR[2]]) / (k1 + k2)
        parts += [
            f"  {p}plate:",
            f"    type: rigid_body",
            f"    mass: 3*{p}m",
            f"    inertia: [0.02*{p}m, 0.03*{p}m, 0.04*{p}m]",
            f"    frames:",
            f"      top: {{position: [0, 0, 0.2]}}",
            f"      mount: {{position: [0.3, 0, 0], rpy: [0.4, -0.3, 0.7]}}",
            f"      hook: {{position: [-0.2, 0.1, 0]}}",
            f"    initial: {{position: {numbers(place([0, 0, -0.2]))}, quaternion: {quaternion(R_mid)}}}",
            f"  {p}link_arm:",
            f"    type: rigid_body",
            f"    mass: {p}link_m",
            f"    inertia: [{p}link_m*{p}link_L**2/200, {p}link_m*{p}link_L**2/12, "
            f"{p}link_m*{p}link_L**2/12 + {p}link_m*{p}link_L**2/200]",
            f"    frames:",
            f"      hinge: {{position: [-{p}link_L/2, 0, 0]}}",
            f"      tip: {{position: [{p}link_L/2, 0, 0]}}",
            f"    initial:",
            f"      position: {numbers(place(arm, LINK_IN_MID))}",
            f"      quaternion: {quaternion(R_link * Rotation.from_euler('z', ALPHA))}",
            f"      velocity: {numbers(R_link.apply(arm_velocity))}",
            f"      angular_velocity: {numbers(R_link.apply([0, 0, W]))}",
            f"  {p}link_bead: {{type: particle, mass: 0}}",
            f"  {p}ball: {{type: particle, mass: {p}m/4, initial: {{position: {numbers(place([-0.2, 0.1, -0.2]))}}}}}",
        ]
        if side == "left":
            parts.append("  hub: {type: particle, mass: m0/3, initial: {position: [0, 0.1, 0.8]}}")
        initial += [f"  {p}link_bead.{c}: {float(x)!r}" for c, x in zip("xyz", place(bead, LINK_IN_MID))]
        joints += [f"  - {{name: {p}shoulder, type: spherical, parent: world.{p}socket, child: {p}plate.top}}",
                   f"  - {{name: {p}elbow, type: revolute, parent: {p}plate.mount, child: {p}link_arm.hinge}}",
                   f"  - {{name: {p}hang, type: spherical, parent: {p}plate.hook, child: {p}ball}}"]
        forces += [f"  - {{name: {p}link_inner, type: spring, between: [{p}link_arm.tip, {p}link_bead], "
                   f"stiffness: {p}link_k1, rest_length: 0}}",
                   f"  - {{name: {p}link_outer, type: spring, between: [{p}link_bead, world.{p}link_anchor], "
                   f"stiffness: {p}link_k2, rest_length: 0}}"]
    joints.append("  - {name: leash, type: distance, parent: right_ball, child: hub, length: 0.5}")
    forces.append("  - {name: tether, type: spring, between: [hub, left_ball], stiffness: k0, rest_length: 0.3}")
    lines = ["name: flat", "balances: auto", "gravity: [0, 0, -g]", "parameters:",
             *(f"  {key}: {text}" for key, text in parameters.items()), "world:", "  frames:", *world,
             "parts:", *parts, "joints:", *joints, "forces:", *forces, "initial:", *initial]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def twins(tmp_path_factory):
    """(the composed System, its flat twin)."""
    folder = tmp_path_factory.mktemp("composed")
    for name, text in (("link.yaml", LINK), ("mid.yaml", MID), ("top.yaml", TOP)):
        (folder / name).write_text(text)
    return mb.load(folder / "top.yaml"), mb.loads(flat_twin(), name="flat.yaml")


def flat_name(name):
    """The flat twin's name of a composed coordinate or parameter: the part's prefix with
    underscores (``left.link.arm.qw`` → ``left_link_arm.qw``)."""
    head, dot, last = name.rpartition(".")
    return head.replace(".", "_") + dot + last


def test_same_coordinates_in_the_same_order(twins):
    composed, flat = twins
    assert [flat_name(c) for c in composed.coordinates] == list(flat.coordinates)
    assert len(composed.coordinates) == 43  # 4 rigid bodies (7), 4 particles and 1 hub (3)


def test_same_parameters_passed_down(twins):
    composed, flat = twins
    for name, value in composed.parameters.items():
        assert flat.parameters[name.replace(".", "_")] == pytest.approx(value, rel=AGREE), name
    assert composed.parameters["left.link.m"] == pytest.approx(2 * M0 / 2 + 0.1, rel=AGREE)
    assert composed.parameters["right.link.k2"] == pytest.approx(100.0, rel=AGREE)


def test_same_constraints_and_appended_balances(twins):
    composed, flat = twins
    assert [c.name.replace(".", "_") for c in composed.constraints] == [c.name.replace(".", "_")
                                                                        for c in flat.constraints]
    assert len(composed.appended_balances) == len(flat.appended_balances) == 6  # each massless bead's three balances (5.40)


def test_same_initial_state(twins):
    composed, flat = twins
    for a, b in zip(composed.initial_state(), flat.initial_state()):
        np.testing.assert_allclose(a, b, rtol=0, atol=AGREE)
    q, qd = composed.initial_state()
    assert np.abs(qd).max() > 0.5  # the arms turn at the start: their velocities were placed too


def test_initial_state_is_assembled(twins):
    """The hand-placed poses close the joints (positions and velocities) and balance the
    beads (positions; they start at rest while the arms turn): the twins agree on a state
    the joints hold, not merely on the same numbers. The top's leash starts stretched."""
    composed, _ = twins
    q, qd = composed.initial_state()
    phi, phid = (np.asarray(r) for r in composed.constraint_residuals(0.0, q, qd))
    names = composed.constraint_names
    held = [i for i, name in enumerate(names) if not name.startswith("leash")]
    joints = [i for i in held if not name_of(names[i]).startswith("balance_")]
    assert len(joints) < len(held)
    assert np.abs(phi[held]).max() < 1e-12
    assert np.abs(phid[joints]).max() < 1e-12


def name_of(row):
    """The constraint's name of a row name (``left.shoulder[2]`` → ``left.shoulder``)."""
    return row.split("[")[0]


@pytest.mark.parametrize("method", ["kkt", "reference"])
def test_same_accelerations(twins, method):
    composed, flat = twins
    a, b = (system.motion(0.0, *system.initial_state(), method=method) for system in twins)
    assert a.unique and b.unique
    np.testing.assert_allclose(a.qdd, b.qdd, rtol=0, atol=AGREE)


def test_a_top_parameter_moves_both_alike(twins):
    """m0 reaches every mass through two levels of expressions (left.m = 2 m0, left.link.m =
    left.m/2 + 0.1, ...): changed on either twin, their accelerations move alike."""
    before = twins[0].motion(0.0, *twins[0].initial_state(), method="reference").qdd
    moved = [system.with_parameters(m0=2.0) for system in twins]
    assert moved[0].parameters["right.link.m"] == pytest.approx((2.0 + 0.5) / 2 + 0.1, rel=AGREE)
    a, b = (system.motion(0.0, *system.initial_state(), method="reference").qdd for system in moved)
    assert np.abs(a - before).max() > 0.1
    np.testing.assert_allclose(a, b, rtol=0, atol=AGREE)


def test_placed_orientation_keeps_its_sign(tmp_path):
    """A placement turning a body past half a turn (yaw 0.3 then 3.0: 3.3 rad about z) gives
    the quaternion a file's ``rpy: [0, 0, 3.3]`` gives (qw ≥ 0), not its negative: the same
    coordinates and accelerations as the flat file."""
    body = "{type: rigid_body, mass: 1, inertia: [1, 2, 3], frames: {end: {position: [1, 0, 0]}}, initial: {%s}}"
    pin = "joints:\n  - {name: pin, type: spherical, parent: world, child: %s.end}\n"
    (tmp_path / "child.yaml").write_text(f"parts:\n  b: {body % 'rpy: [0, 0, 0.3], angular_velocity: [0, 1, 1]'}\n")
    (tmp_path / "top.yaml").write_text("gravity: [0, 0, -9.81]\nparts:\n"
                                       "  c: {type: model, file: child.yaml, placement: {rpy: [0, 0, 3.0]}}\n"
                                       + pin % "c.b")
    turn = Rotation.from_euler("z", 3.0)
    start = (f"quaternion: {quaternion(turn * Rotation.from_euler('z', 0.3))}, "
             f"angular_velocity: {numbers(turn.apply([0, 1, 1]))}")
    flat = f"gravity: [0, 0, -9.81]\nparts:\n  b: {body % start}\n" + pin % "b"
    composed, flat = mb.load(tmp_path / "top.yaml"), mb.loads(flat)
    assert composed.initial_q[3] > 0.07  # cos(3.3 / 2) is −0.079: the sign a product of turns gives
    for a, b in zip(composed.initial_state(), flat.initial_state()):
        np.testing.assert_allclose(a, b, rtol=0, atol=AGREE)
    a, b = (system.motion(0.0, *system.initial_state(), method="reference").qdd for system in (composed, flat))
    np.testing.assert_allclose(a, b, rtol=0, atol=AGREE)
