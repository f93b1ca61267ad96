"""Whole robots as parts, checked against Pinocchio's reduced-coordinate dynamics.

Every robot is built once per module (building one derives every link's joint rows
symbolically). The references are Pinocchio's own: its URDF
parser and aba / crba / constraintDynamics; only the state maps are ours, and those are
checked by a round trip and by finite differences.
"""

import json
import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.analysis.diagnose import diagnose
from mbsynth.core.kinematics import matrix_quaternion
from mbsynth.robots.build import describe, fix_base, robot_files
from mbsynth.robots.twin import Twin
from mbsynth.robots.validate import sample_pinocchio_state, validate_system
from mbsynth.core.tolerances import VALIDATION_RTOL
from tests.helpers.compare import rel

pytestmark = pytest.mark.skipif(not robot_files(), reason="example-robot-data is not installed")
SAMPLES = 4
MODELS = Path(__file__).resolve().parents[2] / "models"


@pytest.fixture(scope="module")
def ur5():
    return mb.from_robot("ur5", floating=True)


@pytest.fixture(scope="module")
def panda():
    return mb.from_robot("panda", floating=True)


@pytest.mark.parametrize("name", ["ur5", pytest.param("panda", marks=pytest.mark.slow)])  # panda: the larger build
def test_joint_accelerations_equal_pinocchio_aba(name, request):
    """ur5 (revolute), panda (revolute and prismatic fingers, a branched tree), each
    floating and fixed: v̇ from (2.14) in 7 coordinates per link equals pinocchio.aba.
    (Every robot of example-robot-data: benchmarks/validate_all_robots.py.)"""
    system = request.getfixturevalue(name)
    model = pin.buildModelFromUrdf(robot_files()[name])
    for base, variant, nv in (("floating", system, model.nv + 6), ("fixed", fix_base(system), model.nv)):
        result = validate_system(variant, samples=SAMPLES, base=base)
        assert result.nv == nv and result.links == len(system.robots[0].description.links)
        assert result.passed and result.max_rel_error <= VALIDATION_RTOL, result


@pytest.mark.parametrize("name", ["ur5", pytest.param("panda", marks=pytest.mark.slow)])
def test_tree_path_equals_pinocchio_aba(name, request):
    """The compiled tree path (mbsynth.compiled) itself, floating and fixed base, against aba:
    panda's fingers are prismatic joints (a rigid transport of rows invariant under
    rotation), its hand a weld, ur5's joints revolute. (Every robot:
    benchmarks/fast_all_robots.py.)"""
    from mbsynth.compiled import engine_for

    system = request.getfixturevalue(name)
    rng = np.random.default_rng(7)
    for variant in (system, fix_base(system)):
        engine, twin = engine_for(variant), Twin(variant)
        for _ in range(SAMPLES):
            q, v = sample_pinocchio_state(twin, rng)
            qm, qdm = twin.to_maximal(q, v)
            fast = engine.motion(0.0, qm, qdm)
            exact = twin.accelerations(q, v, np.zeros(twin.model.nv))
            assert fast is not None
            assert np.abs(twin.to_pinocchio(qm, qdm, fast.qdd)[2] - exact).max() <= 1e-10 * np.abs(exact).max()


def test_consecutive_motions_keep_their_own_arrays_and_equal_aba(ur5):
    """Two motion() calls in a row on the compiled tree path: the kernel writes into the
    Engine's buffers, and each Motion holds copies, so the second call leaves the first
    Motion's q̈ and Qc as they were; each q̈ equals pinocchio.aba's and Qc the reference
    path's (the literal (2.14)), to the tolerances of tests/compiled/test_fast.py."""
    twin, rng = Twin(ur5), np.random.default_rng(5)
    data = ur5.data(path="compiled")
    states = [sample_pinocchio_state(twin, rng) for _ in range(2)]
    maximal = [twin.to_maximal(q, v) for q, v in states]
    first = data.motion(0.0, *maximal[0])
    kept = first.qdd.copy(), first.Qc.copy()
    second = data.motion(0.0, *maximal[1])
    assert first.method == second.method == "tree (Baraff)"
    assert not np.shares_memory(first.qdd, second.qdd) and not np.shares_memory(first.Qc, second.Qc)
    assert np.array_equal(first.qdd, kept[0]) and np.array_equal(first.Qc, kept[1])
    assert not np.allclose(first.qdd, second.qdd)  # two different states: an overwrite would show
    for motion, (q, v), (qm, qdm) in zip((first, second), states, maximal):
        exact = twin.accelerations(q, v, np.zeros(twin.model.nv))
        assert np.abs(twin.to_pinocchio(qm, qdm, motion.qdd)[2] - exact).max() <= 1e-10 * np.abs(exact).max()
        reference = data.motion(0.0, qm, qdm, method="reference")
        assert rel(motion.qdd, reference.qdd) < 1e-10 and rel(motion.Qc, reference.Qc) < 1e-7  # as tests/compiled


def test_parts_are_the_links_with_their_masses(ur5):
    """One rigid body per URDF link, massless links included (a zero block of M); the
    masses add up to Pinocchio's total mass of the floating robot."""
    description = ur5.robots[0].description
    assert [p.name for p in ur5.parts] == list(description.links)
    assert all(p.type_name == "rigid_body" for p in ur5.parts)
    model = pin.buildModelFromUrdf(description.path, pin.JointModelFreeFlyer())
    assert sum(float(p.mass) for p in ur5.parts) == pytest.approx(pin.computeTotalMass(model), rel=1e-12)
    q, qd = ur5.initial_state()
    M = ur5.evaluate(0.0, q, qd).M
    tool = ur5.coordinates.index("tool0.x")
    assert np.all(M[tool:tool + 7, tool:tool + 7] == 0)
    assert sorted(ur5.parameters) == sorted(f"tau_{j}" for j in ("shoulder_pan_joint", "shoulder_lift_joint",
                                                                   "elbow_joint", "wrist_1_joint", "wrist_2_joint",
                                                                   "wrist_3_joint"))


def test_a_joint_torque_accelerates_by_the_inverse_mass_matrix(ur5):
    """At rest, the change of v̇ that a torque τ on one joint makes is M⁻¹ e τ, with M
    from Pinocchio's crba (an algorithm independent of aba)."""
    fixed = fix_base(ur5)
    twin = Twin(fixed)
    q, _ = sample_pinocchio_state(twin, np.random.default_rng(3))
    v = np.zeros(twin.model.nv)
    qm, qdm = twin.to_maximal(q, v)
    base = twin.to_pinocchio(qm, qdm, fixed.motion(0.0, qm, qdm).qdd)[2]
    driven = fixed.with_parameters(tau_elbow_joint=7.5)
    pushed = twin.to_pinocchio(qm, qdm, driven.motion(0.0, qm, qdm).qdd)[2]
    M = pin.crba(twin.model, twin.data, q)
    M = np.triu(M) + np.triu(M, 1).T
    e = np.zeros(twin.model.nv)
    e[twin.model.joints[twin.model.getJointId("elbow_joint")].idx_v] = 7.5
    np.testing.assert_allclose(pushed - base, np.linalg.solve(M, e), rtol=1e-10, atol=1e-10)


def test_state_maps_round_trip(ur5):
    """Pinocchio (q, v) → maximal (q, q̇) → Pinocchio gives (q, v) back: the quaternion
    up to its sign, the joint angles modulo 2π."""
    twin = Twin(ur5)
    q, v = sample_pinocchio_state(twin, np.random.default_rng(5))
    back_q, back_v, _ = twin.to_pinocchio(*twin.to_maximal(q, v))
    np.testing.assert_allclose(back_v, v, atol=1e-12)
    np.testing.assert_allclose(back_q[:3], q[:3], atol=1e-12)
    assert abs(abs(back_q[3:7] @ q[3:7]) - 1) < 1e-12
    np.testing.assert_allclose(np.angle(np.exp(1j * (back_q[7:] - q[7:]))), 0, atol=1e-12)


def test_free_flyer_acceleration_is_the_derivative_of_its_velocity(ur5):
    """Pinocchio's free-flyer v̇ is d/dt of (Rᵀṗ, Rᵀω) (a spatial acceleration): the map
    from q̈ agrees with central differences of v along q(t) = q + t q̇ + t²/2 q̈."""
    twin = Twin(ur5)
    q, v = sample_pinocchio_state(twin, np.random.default_rng(7))
    qm, qdm = twin.to_maximal(q, v)
    qdd = ur5.motion(0.0, qm, qdm).qdd
    h = 1e-5
    ahead, behind = (twin.to_pinocchio(qm + s * h * qdm + h**2 / 2 * qdd, qdm + s * h * qdd)[1] for s in (1, -1))
    np.testing.assert_allclose(twin.to_pinocchio(qm, qdm, qdd)[2][:6], ((ahead - behind) / (2 * h))[:6],
                               rtol=1e-6, atol=1e-6)


def test_continuous_joints_read_as_cos_and_sin():
    """Continuous joints: Pinocchio's q is (cos θ, sin θ); fixed and floating agree with aba."""
    system = mb.from_robot("double_pendulum_continuous", floating=True)
    twin = Twin(system)
    assert [c.kind for c in twin.coordinates] == ["free", "continuous", "continuous"]
    q, v = sample_pinocchio_state(twin, np.random.default_rng(2))
    np.testing.assert_allclose(twin.to_pinocchio(*twin.to_maximal(q, v))[0][7:], q[7:], atol=1e-12)
    for variant in (system, fix_base(system)):
        assert validate_system(variant, samples=SAMPLES).max_rel_error <= VALIDATION_RTOL


def test_four_bar_loop_equals_constraint_dynamics():
    """The spatial four-bar (three rigid bodies, four revolute joints, one closing the
    loop) against pinocchio.constraintDynamics with two CONTACT_3D on the closing axis;
    the closing joint's reaction against lambda_c on the three wrench components a planar
    loop in space determines (in-plane force, moment about the axes; the other three are
    a self-stress: test_loop_reactions.py)."""
    system = mb.load(MODELS / "mechanisms" / "four_bar_3d.yaml")
    twin = Twin(system)
    assert len(twin.constraints) == 2 and twin.model.nv == 3
    result = validate_system(system, samples=SAMPLES)
    assert result.passed and result.max_rel_error <= VALIDATION_RTOL, result
    assert result.loop_reaction_error <= 1e-8 and result.loop_free == 3, result


def arm_with_loop(tmp_path):
    """A model file: the SO-100 arm (type: robot) holds a bar in its gripper link, the
    bar's tip pinned to the world where it is at the zero pose, and a payload hangs from
    the bar by a spring."""
    p, R = describe("so100").poses()["gripper"]
    u = matrix_quaternion(R)
    tip, centre = p + R @ [0, 0, 0.3], p + R @ [0, 0, 0.15]
    path = tmp_path / "arm.yaml"
    path.write_text(textwrap.dedent(f"""\
        name: so100_bar_payload
        parameters: {{k: 60.0, m: 0.3, g: 9.81, tau_arm_elbow_flex: 0.4}}
        gravity: [0, 0, -g]
        world: {{frames: {{anchor: {{position: {tip.tolist()}}}}}}}
        parts:
          arm: {{type: robot, robot: so100}}
          bar:
            type: rigid_body
            mass: 0.2
            inertia: [0.0015, 0.0015, 0.00001]
            frames: {{grip: {{position: [0, 0, -0.15]}}, tip: {{position: [0, 0, 0.15]}}}}
            initial: {{position: {centre.tolist()}, quaternion: {u.tolist()}}}
          payload:
            type: rigid_body
            mass: m
            inertia: [0.0004, 0.0005, 0.0006]
            initial: {{position: {(centre - [0, 0, 0.25]).tolist()}}}
        joints:
          - {{name: grip, type: fixed, parent: arm_gripper.link, child: bar.grip}}
          - {{name: pin, type: spherical, parent: world.anchor, child: bar.tip}}
        forces:
          - {{name: hang, type: spring, between: [bar, payload], stiffness: k, rest_length: 0.2}}
        """))
    return path


def test_robot_holding_a_pinned_bar_with_a_hanging_payload(tmp_path):
    """A robot, a loop and parts of the user's own in one model file: the bar is welded
    to the arm (appended to its wrist in Pinocchio), its pin to the world closes a loop
    (CONTACT_3D), the payload is a free-flyer driven by the spring through Sᵀ Q_spring.
    Unique motion at the initial state; equal to pinocchio.constraintDynamics, and the
    pin's reaction (the whole force: the loop is not redundant) equal to its lambda_c."""
    system = mb.load(arm_with_loop(tmp_path))
    assert system.parameters["tau_arm_elbow_flex"] == 0.4  # the model's value wins over the default 0
    assert "arm_gripper" in [p.name for p in system.parts] and system.robots[0].prefix == "arm_"
    report = diagnose(system)
    assert report.unique and report.consistent
    phi, _ = system.constraint_residuals(0.0, *system.initial_state())
    assert np.nanmax(np.abs(phi)) < 1e-12  # the pin holds where the bar starts
    twin = Twin(system)
    assert len(twin.constraints) == 1 and twin.model.nv == 6 + 6
    result = validate_system(system, samples=SAMPLES)
    assert result.passed and result.max_rel_error <= VALIDATION_RTOL, result
    assert result.loop_reaction_error <= 1e-8 and result.loop_free == 0, result


def massless_leaf_urdf(tmp_path):
    """The double pendulum of example-robot-data with its last link's mass taken away."""
    tree = ET.parse(robot_files()["double_pendulum"])
    inertial = next(link for link in tree.getroot().findall("link") if link.get("name") == "link2").find("inertial")
    inertial.find("mass").set("value", "0")
    for key in inertial.find("inertia").attrib:
        inertial.find("inertia").set(key, "0")
    path = tmp_path / "massless_leaf.urdf"
    tree.write(path)
    return path


def test_massless_leaf_pinocchio_nan_mbsynth_names_the_direction(tmp_path):
    """A massless link on a revolute joint at the end of the chain: pinocchio.aba divides
    by its zero articulated inertia (NaN); mbsynth finds one indeterminate direction, the
    leaf turning about its joint, on which no force acts (free); a torque on that joint
    would leave no motion at all (a force on a direction no mass resists)."""
    system = mb.from_robot(massless_leaf_urdf(tmp_path))
    twin = Twin(system)
    q, v = sample_pinocchio_state(twin, np.random.default_rng(0))
    with np.errstate(all="ignore"):
        assert not np.all(np.isfinite(pin.aba(twin.model, twin.data, q, v, np.zeros(twin.model.nv))))
    qm, qdm = twin.to_maximal(q, v)
    motion = system.motion(0.0, qm, qdm)
    assert not motion.unique and motion.nullspace.shape[1] == 1
    moving = {c.split(".")[0] for c, x in zip(system.coordinates, motion.nullspace[:, 0]) if abs(x) > 1e-9}
    assert moving == {"link2"}
    report = diagnose(system, q=qm, qd=qdm)
    assert [b["free"] for b in report.balances] == [True]
    result = validate_system(system, samples=2)
    assert not result.passed and "NaN" in result.note and "mbsynth: no motion exists" in result.note


def test_yaml_robot_entry_errors_name_file_line_and_key(tmp_path):
    def load(text):
        path = tmp_path / "model.yaml"
        path.write_text(textwrap.dedent(text))
        return mb.load(path)

    with pytest.raises(mb.ModelError, match=r"model\.yaml:3: at parts\.arm\.robot: no robot or URDF file"):
        load("""\
            parts:
              arm:
                robot: no_such_robot
                type: robot
            """)
    with pytest.raises(mb.ModelError, match=r"at parts\.arm\.floating: expected true or false"):
        load("parts:\n  arm: {type: robot, robot: double_pendulum, floating: 'yes'}\n")
    with pytest.raises(mb.ModelError, match=r"at parts\.arm\.base\.rpy: expected a list of 3"):
        load("parts:\n  arm: {type: robot, robot: double_pendulum, base: {rpy: [0, 1]}}\n")
    with pytest.raises(mb.ModelError, match=r"at parts\.arm: robot 'arm' has a link part 'arm_link1'"):
        load("parts:\n  arm: {type: robot, robot: double_pendulum}\n"
             "  arm_link1: {type: particle, mass: 1}\n")


def test_validate_command_json_and_the_robot_list(capsys):
    assert main(["validate", "double_pendulum", "--samples", "3", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["robot"] == "double_pendulum" and report["passed"] is True and report["samples"] == 3
    assert report["max_rel_error"] <= VALIDATION_RTOL and [r["base"] for r in report["results"]] == ["fixed", "floating"]
    assert main(["robots", "--json"]) == 0
    robots = {r["name"]: r for r in json.loads(capsys.readouterr().out)["robots"]}
    assert robots["ur5"]["pinocchio"] and robots["ur5"]["links"] == 11 and robots["talos"]["movable_joints"] == 32
    assert main(["validate", str(MODELS / "mechanisms" / "four_bar.yaml")]) == 2  # planar bodies: no Pinocchio twin
    assert "no equivalent Pinocchio model" in capsys.readouterr().err


def test_an_inertia_no_rigid_body_has_is_refused_naming_file_and_link(tmp_path):
    """tiago's antenna links have |ixy| > √(ixx iyy): a negative principal moment (−3.5e-8);
    Pinocchio takes it, mbsynth refuses it by name."""
    tree = ET.parse(robot_files()["double_pendulum"])
    inertia = next(link for link in tree.getroot().findall("link") if link.get("name") == "link2").find("inertial/inertia")
    inertia.attrib.update(ixx="1e-3", iyy="1e-3", ixy="2e-3")  # eigenvalues of the xy block: 3e-3 and −1e-3
    path = tmp_path / "bad_inertia.urdf"
    tree.write(path)
    with pytest.raises(mb.ModelError, match=r"bad_inertia\.urdf: link 'link2': its inertia is not positive semi-definite"
                                            r".*-0\.001"):
        mb.from_robot(path)


def test_an_inertia_of_rounding_noise_is_zero_not_refused(tmp_path):
    """icub's head: moments of ±2.4e-35 kg m² (a zero inertia printed with noise) are kept."""
    tree = ET.parse(robot_files()["double_pendulum"])
    inertia = next(link for link in tree.getroot().findall("link") if link.get("name") == "link2").find("inertial/inertia")
    inertia.attrib.update(ixx="0", iyy="0", izz="0", ixy="2.4e-35", ixz="0", iyz="0")
    path = tmp_path / "noise.urdf"
    tree.write(path)
    assert mb.from_robot(path).n == 21  # three links, seven coordinates each


def test_robot_entry_initial_joint_positions_place_the_links_as_pinocchio(tmp_path):
    """``initial: {joint: value}`` under a robot entry: every link's frame where Pinocchio's
    forward kinematics puts it at those joint positions, the base moved and turned as
    ``base`` says; a joint the URDF has not (or a fixed one) is refused, the movable ones listed."""
    angles = {"shoulder_pan_joint": 0.3, "shoulder_lift_joint": -0.4, "elbow_joint": 0.8, "wrist_2_joint": 0.5}
    path = tmp_path / "arm.yaml"
    path.write_text("parts:\n  arm: {type: robot, robot: ur5, base: {position: [0.1, 0, 1], rpy: [0, 0, 0.2]}, "
                    f"initial: {json.dumps(angles)}}}\n")
    system = mb.load(path)
    model = pin.buildModelFromUrdf(describe("ur5").path)
    data = model.createData()
    q = np.array([angles.get(model.names[j], 0.0) for j in range(1, model.njoints)])
    pin.framesForwardKinematics(model, data, q)
    base = pin.SE3(pin.rpy.rpyToMatrix(0, 0, 0.2), np.array([0.1, 0, 1]))
    index = {c: i for i, c in enumerate(system.coordinates)}
    for link, values in system.robots[0].parts.items():
        frame = base * data.oMf[model.getFrameId(link, pin.BODY)]
        com = describe("ur5").links[link].com
        at = [index[f"{values}.{c}"] for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]
        np.testing.assert_allclose(system.initial_q[at[:3]], frame.translation + frame.rotation @ com, atol=1e-12)
        u = system.initial_q[at[3:]]
        np.testing.assert_allclose(np.abs(matrix_quaternion(frame.rotation) @ u), 1.0, atol=1e-12)
    path.write_text("parts:\n  arm: {type: robot, robot: ur5, initial: {elbo_joint: 0.5}}\n")
    with pytest.raises(mb.ModelError, match=r"arm\.yaml:2: at parts\.arm\.initial\.elbo_joint: unknown key "
                                            r"'elbo_joint' \(did you mean 'elbow_joint'\?\); allowed: elbow_joint, "
                                            r"shoulder_lift_joint, shoulder_pan_joint, wrist_1_joint"):
        mb.load(path)
