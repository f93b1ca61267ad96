"""The quadruped of models/legged: four placed copies of one leg file whose knee is a massless
link between two torsional springs. It stands (its initial pose is a static equilibrium and
the ground carries its weight), Result 3's verdict is right with and without the link's
torque balance, and it equals its flat twin written out from the leg file by hand."""

import re
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import yaml

import mbsynth as mb

MODELS = Path(__file__).resolve().parents[2] / "models" / "legged"
HEXAPOD = Path(__file__).resolve().parent / "data" / "legged" / "hexapod.yaml"  # beside its standing_leg.yaml
LEGS = ("front_left", "front_right", "hind_left", "hind_right")
STILL = 1e-9  # accelerations [m/s², rad/s²] of a model at rest in equilibrium: rounding only
SAME = 1e-12  # composed and flat: the same arithmetic up to the order of sums
STANCE = {"start": 0.5}  # the legs start bent as in the stance (the files start a little lower)


@pytest.fixture(scope="module")
def quadruped():
    return mb.load(MODELS / "quadruped.yaml", parameters=STANCE)


@pytest.fixture(scope="module")
def unbalanced(tmp_path_factory):
    """The quadruped with legs that leave out the massless link's balance (leg.yaml's
    ``constraints:`` block cut from a copy)."""
    folder = tmp_path_factory.mktemp("legs")
    leg = (MODELS / "leg.yaml").read_text()
    cut = re.sub(r"^constraints:\n(?:[ #].*\n)*", "", leg, flags=re.M)
    assert "holonomic" in leg and "holonomic" not in cut
    (folder / "leg.yaml").write_text(cut)
    (folder / "quadruped.yaml").write_text((MODELS / "quadruped.yaml").read_text())
    return mb.load(folder / "quadruped.yaml", parameters=STANCE)


def rotation(u):
    """The rotation matrix of a scalar-first unit quaternion."""
    w, x, y, z = u / np.linalg.norm(u)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def link_turn(system, q, leg):
    """q̇ of ``leg``'s knee link turning at 1 rad/s about its own y axis (the knee axis; its
    frames sit at its centre) with every other coordinate at rest: u̇ = ½ u ⊗ (0, 0, 1, 0)."""
    i = system.coordinates.index(f"{leg}.link.qw")
    w, x, y, z = q[i:i + 4]
    turn = np.zeros(system.n)
    turn[i:i + 4] = 0.5 * np.array([-y, -z, w, x])
    return turn


def turned(system, q, leg, angle):
    """q with ``leg``'s knee link turned by ``angle`` about its own y axis."""
    i = system.coordinates.index(f"{leg}.link.qw")
    w, x, y, z = q[i:i + 4]
    c, s = np.cos(angle / 2), np.sin(angle / 2)
    q = q.copy()
    q[i:i + 4] = [w * c - y * s, x * c - z * s, y * c + w * s, z * c + x * s]  # u ⊗ (c, 0, s, 0)
    return q


# --- (a) it stands ----------------------------------------------------------------------------

def standing_still(system, feet, weight):
    """Assert that ``system`` rests in its initial pose (q̈ = 0 by the System's solver and by
    (2.14)) and that the vertical forces of the ankle joints ``feet`` ({joint: the shank
    part}) on the feet, turned into world axes here, add up to ``weight``, a share each."""
    q, qd = system.initial_state()
    assert not qd.any()
    motion, reference = system.motion(0.0, q, qd), system.motion(0.0, q, qd, method="reference")
    assert motion.unique and reference.unique
    assert np.abs(motion.qdd).max() < STILL and np.abs(reference.qdd).max() < STILL
    reactions = system.reactions(0.0, q, qd, motion)
    parts = {part.name: part for part in system.parts}
    vertical = []
    for joint, shank in feet.items():
        i = system.coordinates.index(f"{shank}.qw")
        frame = np.array(parts[shank].frames["foot"].rotation.subs(system.parameters), dtype=float)
        vertical.append((rotation(q[i:i + 4]) @ frame @ reactions[joint].force)[2])
    assert sum(vertical) == pytest.approx(weight, rel=1e-12)
    assert vertical == pytest.approx([weight / len(feet)] * len(feet), rel=1e-9)  # symmetric


def test_quadruped_stands_and_the_ground_carries_its_weight(quadruped):
    """At rest in its stance nothing accelerates (the springs' rest angles are set for a
    static equilibrium), and the ankles carry the weight of torso and legs,
    (m_torso + 4 m_leg) g: the model's momentum balance, checked against the joints' reactions."""
    p = quadruped.parameters
    feet = {joint: f"{leg}.shank" for joint, leg in zip(("foot_fl", "foot_fr", "foot_hl", "foot_hr"), LEGS)}
    standing_still(quadruped, feet, (p["m_torso"] + 4 * p["m_leg"]) * p["g"])


@pytest.mark.slow  # six legs of two nested files, derived
def test_hexapod_of_six_placed_copies_stands():
    """data/legged/hexapod.yaml: six copies (``count: 6``, placed by ``index``) of a file that includes
    leg.yaml in turn (two levels deep, its ankle a placed world frame) stand still on their
    six ankles, which carry (m_torso + 6 m_leg) g."""
    hexapod = mb.load(HEXAPOD, parameters=STANCE)
    assert [s.name for s in hexapod.substructures] == [f"leg[{i}]" for i in range(6)]
    p = hexapod.parameters
    feet = {f"leg[{i}].ankle": f"leg[{i}].leg.shank" for i in range(6)}
    standing_still(hexapod, feet, (p["m_torso"] + 6 * p["m_leg"]) * p["g"])


# --- (b) Result 3 -----------------------------------------------------------------------------

def test_with_the_balance_the_motion_is_unique(quadruped):
    """With each leg's balance, [M; A] has full column rank: the motion is unique, by the
    System's solver and by the explicit (2.14) alike, and both give the same q̈."""
    q, qd = quadruped.initial_state()
    arrays = quadruped.evaluate(0.0, q, qd)
    assert mb.rank_report(arrays.M, arrays.A).rank_Mhat == quadruped.n
    fast, reference = quadruped.motion(0.0, q, qd), quadruped.motion(0.0, q, qd, method="reference")
    assert fast.unique and reference.unique
    assert np.abs(fast.qdd - reference.qdd).max() < STILL


def test_without_the_balance_each_knee_link_is_indeterminate(unbalanced):
    """Without the balance the motion is not unique (Result 3), by both solvers, and the
    indeterminate directions are exactly the four knee links' turns about their knee axes:
    four (one per massless link, counted from the model's make-up), each a null vector of
    [M; A] built here from the link's quaternion, and together spanning the null space."""
    system = unbalanced
    q, qd = system.initial_state()
    fast, reference = system.motion(0.0, q, qd), system.motion(0.0, q, qd, method="reference")
    assert not fast.unique and not reference.unique
    massless = [part.name for part in system.parts if part.type_name == "rigid_body" and part.name.endswith(".link")]
    assert massless == [f"{leg}.link" for leg in LEGS]
    N = reference.nullspace
    assert N.shape[1] == len(massless) == 4
    turns = np.column_stack([link_turn(system, q, leg) for leg in LEGS])
    arrays = system.evaluate(0.0, q, qd)
    assert np.abs(np.vstack([arrays.M, arrays.A]) @ turns).max() < 1e-12
    assert np.abs(turns - N @ (N.T @ turns)).max() < 1e-9  # in the null space, and (4 of 4) span it
    assert np.linalg.matrix_rank(turns) == 4


def test_the_leg_balance_is_result_3s(quadruped, unbalanced):
    """The constraint ``balance`` of leg.yaml is the balance wᵀ(Q + C) = 0 that Result 3 asks
    for along the link's turn w: with the front-left link turned by δ (the springs now pull
    unequally), wᵀ(Q + C) of the unbalanced model, the closed model's residual of the
    balance, and the torsional springs' net torque on the link, k (knee − drive) = −2 k δ,
    are one number."""
    delta = 0.1
    q0, qd = unbalanced.initial_state()
    q = turned(unbalanced, q0, "front_left", delta)
    w = link_turn(unbalanced, q, "front_left")
    arrays = unbalanced.evaluate(0.0, q, qd)
    assert np.abs(np.vstack([arrays.M, arrays.A]) @ w).max() < 1e-12  # still a null vector there
    along = w @ (arrays.Q + arrays.C)
    phi, _ = quadruped.constraint_residuals(0.0, q, qd)
    row = quadruped.constraint_names.index("front_left.balance")
    torque = -2 * quadruped.parameters["k_knee"] * delta
    assert along == pytest.approx(torque, rel=1e-12)
    assert phi[row] == pytest.approx(torque, rel=1e-12)
    others = [i for i, name in enumerate(quadruped.constraint_names) if name.endswith(".balance") and i != row]
    assert np.abs(phi[others]).max() < 1e-12


# --- (c) the flat twin ------------------------------------------------------------------------

class _Plain(yaml.SafeDumper):
    def ignore_aliases(self, data):  # YAML anchors of the top file written out in full
        return True


def renamed(node, rename):
    """``node`` (a part's mapping) with ``rename`` applied to its text values (expressions),
    not to its keys (frame names)."""
    if isinstance(node, dict):
        return {key: renamed(value, rename) for key, value in node.items()}
    if isinstance(node, list):
        return [renamed(value, rename) for value in node]
    return rename(node) if isinstance(node, str) else node


def flat_twin():
    """quadruped.yaml with its four legs written out from leg.yaml's text by hand: each leg's
    parts, joints and constraint renamed ``<leg>_<name>``, its parameters ``<leg>_<name>``
    set to the entry's expressions, its initial positions moved by the placement (a turn
    about z by yaw, then the shift), its pitch angles given the placement's yaw."""
    leg = yaml.safe_load((MODELS / "leg.yaml").read_text())
    top = yaml.safe_load((MODELS / "quadruped.yaml").read_text())
    parameters = dict(top["parameters"])
    parts, joints, constraints = {}, [], []
    for name, entry in top["parts"].items():
        if entry.get("type") != "model":
            parts[name] = entry
            continue
        own = list(leg["parameters"]) + [part for part in leg["parts"]] + [j["name"] for j in leg["joints"]]
        pattern = re.compile(r"\b(" + "|".join(own) + r")\b")

        def rename(text, prefix=f"{name}_", pattern=pattern):
            return pattern.sub(lambda m: prefix + m.group(1), str(text))

        for key, value in leg["parameters"].items():
            parameters[f"{name}_{key}"] = entry["parameters"].get(key, value)
        position = [str(x) for x in entry["placement"]["position"]]
        yaw = str(entry["placement"].get("rpy", [0, 0, 0])[2])
        assert entry["placement"].get("rpy", [0, 0, 0])[:2] == [0, 0]
        for part_name, part in leg["parts"].items():
            part = renamed(part, rename)
            initial = part["initial"]
            x, y, z = initial["position"]
            initial["position"] = [f"{position[0]} + cos({yaw})*({x}) - sin({yaw})*({y})",
                                   f"{position[1]} + sin({yaw})*({x}) + cos({yaw})*({y})",
                                   f"{position[2]} + {z}"]
            roll, pitch, turn = initial.get("rpy", [0, 0, 0])
            assert roll == 0 and turn == 0
            initial["rpy"] = [0, pitch, yaw]
            parts[f"{name}_{part_name}"] = part
        for joint in leg["joints"]:
            joint = dict(joint, name=f"{name}_{joint['name']}", parent=f"{name}_{joint['parent']}",
                         child=f"{name}_{joint['child']}", spring={k: rename(v) for k, v in joint["spring"].items()})
            joints.append(joint)
        constraints += [{"name": f"{name}_{c['name']}", "holonomic": rename(c["holonomic"])}
                        for c in leg["constraints"]]
    ports = {f"{leg_name}.{port}": f"{leg_name}_{frame}" for leg_name in LEGS for port, frame in leg["ports"].items()}
    for joint in top["joints"]:
        joints.append(dict(joint, parent=ports.get(joint["parent"], joint["parent"]),
                           child=ports.get(joint["child"], joint["child"])))
    flat = dict(name="quadruped_flat", parameters=parameters, gravity=top["gravity"], world=top["world"],
                parts=parts, joints=joints, constraints=constraints)
    return yaml.dump(flat, Dumper=_Plain, sort_keys=False)


@pytest.fixture(scope="module")
def flat():
    return mb.loads(flat_twin(), name="quadruped_flat.yaml", parameters=STANCE)


@pytest.mark.slow  # a second quadruped, written flat, derived
def test_composed_quadruped_equals_its_flat_twin(quadruped, flat):
    """Same coordinates in the same order (``front_left.thigh.x`` ↔ ``front_left_thigh.x``),
    the same initial state (the hind legs' parts are half-turned: their quaternions have w = 0
    and the same sign both ways), and the same q̈ at a state that moves: the front-left knee
    link turned (its springs pull unequally) and a velocity on the constraints."""
    assert [c.replace(".", "_", c.count(".") - 1) for c in quadruped.coordinates] == list(flat.coordinates)
    (q, qd), (qf, qdf) = quadruped.initial_state(), flat.initial_state()
    assert np.abs(q - qf).max() < SAME and np.abs(qd - qdf).max() < SAME
    q = turned(quadruped, q, "front_left", 0.05)
    A = quadruped.evaluate(0.0, q, qd).A
    basis = scipy.linalg.null_space(A)
    qd = basis @ np.linspace(0.5, -0.5, basis.shape[1])
    a, b = quadruped.motion(0.0, q, qd), flat.motion(0.0, q, qd)
    assert a.unique and b.unique
    assert np.abs(a.qdd).max() > 0.01  # it moves: far above rounding
    assert np.abs(a.qdd - b.qdd).max() < SAME * max(1.0, np.abs(a.qdd).max())


# --- a half turn: one quaternion, written or placed -------------------------------------------

BODY = """\
name: body
parameters: {pitch: 0.3}
parts:
  block:
    type: rigid_body
    mass: 1.0
    inertia: [0.2, 0.25, 0.3]
    initial: {position: [0.1, 0.2, 0.3], rpy: [0, pitch, 0], angular_velocity: [0.5, -1.0, 2.0]}
"""


@pytest.mark.parametrize("turn", [[0, 0, "pi"], ["pi", 0, 0], [0, "pi - 0.3", 0]])  # each with the pitch: a half turn
def test_a_half_turn_gives_one_quaternion_written_or_placed(tmp_path, turn):
    """A body placed by a half turn has w = 0 in its quaternion, where u and −u are equally
    the orientation and only a convention picks one: the placed body's coordinates (and
    rates) are those of the same pose written in a file (the rotation and angular velocity
    computed here, written as a quaternion and as a matrix's rpy)."""
    (tmp_path / "body.yaml").write_text(BODY)
    (tmp_path / "top.yaml").write_text(
        "name: top\nparts:\n  it: {type: model, file: body.yaml, "
        f"placement: {{rpy: [{', '.join(map(str, turn))}]}}}}\n")
    placed = mb.load(tmp_path / "top.yaml")
    angles = [float(eval(str(x), {"pi": np.pi})) for x in turn]
    P = _turn("z", angles[2]) @ _turn("y", angles[1]) @ _turn("x", angles[0])  # the placement's R = Rz Ry Rx
    R, omega, position = P @ _turn("y", 0.3), P @ [0.5, -1.0, 2.0], P @ [0.1, 0.2, 0.3]
    rpy = [np.arctan2(R[2, 1], R[2, 2]), -np.arcsin(R[2, 0]), np.arctan2(R[1, 0], R[0, 0])]  # R = Rz Ry Rx
    u = placed.initial_state()[0][3:7]
    assert abs(u[0]) < 1e-12  # a half turn
    for orientation in (f"rpy: {_listed(rpy)}", f"quaternion: {_listed(u)}", f"quaternion: {_listed(-u)}"):
        written = mb.loads(BODY.replace("rpy: [0, pitch, 0]", orientation)
                           .replace("[0.1, 0.2, 0.3]", _listed(position)).replace("[0.5, -1.0, 2.0]", _listed(omega)))
        (q, qd), (qw, qdw) = placed.initial_state(), written.initial_state()
        assert np.abs(q - qw).max() < 1e-12 and np.abs(qd - qdw).max() < 1e-12, orientation


def _listed(values):
    return f"[{', '.join(repr(float(x)) for x in values)}]"


def _turn(axis, angle):
    c, s = np.cos(angle), np.sin(angle)
    return {"x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]), "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]
