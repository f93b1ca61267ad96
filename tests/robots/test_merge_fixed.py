"""``from_robot(..., merge_fixed=True)`` and a model file's ``merge_fixed: true``: each link
on a fixed joint merged into its nearest ancestor on a movable joint, kept as a frame.

References: Pinocchio's own model of the same URDF (its parser merges fixed joints the
same way and keeps each merged link as a frame): ``aba`` for the joint accelerations,
``updateFramePlacements`` for the merged links' frames; and the robot built without
merging, whose joints move alike.
"""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import mbsynth as mb
from mbsynth.core.kinematics import quaternion_matrix
from mbsynth.model.outputs import OutputEvaluator
from mbsynth.robots.build import identifier, robot_files
from mbsynth.robots.twin import Twin
from mbsynth.robots.validate import sample_pinocchio_state, validate_system
from mbsynth.core.tolerances import VALIDATION_RTOL

pytestmark = pytest.mark.skipif(not robot_files(), reason="example-robot-data is not installed")
MODELS = Path(__file__).resolve().parents[2] / "models" / "robots"
SAME = 1e-10  # joint accelerations of the merged and the unmerged robot, and against aba [rad/s², m/s²]
PLACED = 1e-12  # a merged link's frame against Pinocchio's placement [m, rotation entries]
ROBOTS = [("ur5", False), ("talos", True)]


@pytest.fixture(scope="module", params=ROBOTS, ids=[name for name, _ in ROBOTS])
def pair(request):
    """(the robot as it is, the robot with its welded links merged, Pinocchio's model of the URDF)."""
    name, floating = request.param
    path = robot_files()[name]
    model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(path)
    return (mb.from_robot(name, floating=floating), mb.from_robot(name, floating=floating, merge_fixed=True), model)


def test_merged_robot_has_a_body_per_pinocchio_joint_and_the_same_mass(pair):
    """A body per Pinocchio joint (the root link's for a fixed base: Pinocchio's universe)."""
    whole, merged, model = pair
    welded = merged.robots[0].description.welded
    assert len(merged.parts) == len(whole.parts) - len(welded) == model.njoints - merged.robots[0].floating
    assert sum(float(p.mass) for p in merged.parts) == pytest.approx(sum(float(p.mass) for p in whole.parts), rel=1e-14)
    assert merged.parameters.keys() == whole.parameters.keys()  # tau_<joint> of every movable joint


def test_merged_and_unmerged_robots_move_alike_and_as_aba(pair):
    """At random states (Pinocchio's, mapped into each robot's coordinates) and torques:
    the same v̇, and both Pinocchio's aba."""
    whole, merged, model = pair
    twins = Twin(whole), Twin(merged)
    assert list(twins[0].model.names) == list(twins[1].model.names) == list(model.names)
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, v = sample_pinocchio_state(twins[0], rng)
        torques = {c.torque: float(rng.normal(0, 10)) for c in twins[0].coordinates if c.torque}
        tau = np.zeros(model.nv)
        for c in twins[0].coordinates:
            if c.torque:
                tau[c.idx_v] = torques[c.torque]
        reference = pin.aba(model, model.createData(), q, v, tau)
        a = []
        for system, twin in zip((whole, merged), twins):
            qm, qdm = twin.to_maximal(q, v)
            motion = system.with_parameters(**torques).motion(0.0, qm, qdm)
            a.append(twin.to_pinocchio(qm, qdm, motion.qdd)[2])
        assert np.abs(a[1] - a[0]).max() < SAME and np.abs(a[1] - reference).max() < SAME


def test_merged_links_frames_are_pinocchios_frame_placements(pair):
    """Each merged link's frame on its host's body, at a random state, against Pinocchio's
    placement of the link's frame (its own model of the URDF, ``updateFramePlacements``)."""
    _, merged, model = pair
    robot, twin = merged.robots[0], Twin(merged)
    q, v = sample_pinocchio_state(twin, np.random.default_rng(5))
    qm, _ = twin.to_maximal(q, v)
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    pin.updateFramePlacements(model, data)
    parts, index = {p.name: p for p in merged.parts}, {str(s): i for i, s in enumerate(merged.q_symbols)}
    assert robot.description.welded
    for link, weld in robot.description.welded.items():
        host = parts[robot.parts[weld.host]]
        frame = host.frames[identifier(link)]
        x = qm[[index[str(s)] for s in host.q]]
        R = quaternion_matrix(x[3:])
        expected = data.oMf[model.getFrameId(link, pin.FrameType.BODY)]
        position = x[:3] + R @ np.array(frame.position, dtype=float).ravel()
        rotation = R @ np.array(frame.rotation, dtype=float)
        assert np.abs(position - expected.translation).max() < PLACED, link
        assert np.abs(rotation - expected.rotation).max() < PLACED, link


def test_merged_links_visuals_are_drawn_where_their_links_are(pair):
    """The viewer draws a part's geometry in its axes: a merged link's visuals, carried to its
    host, lie at the same world pose as on the link's own body of the robot as it is."""
    whole, merged, _ = pair
    twins = Twin(whole), Twin(merged)
    q, v = sample_pinocchio_state(twins[0], np.random.default_rng(7))
    poses = []
    for system, twin in zip((whole, merged), twins):
        qm, _ = twin.to_maximal(q, v)
        index = {str(s): i for i, s in enumerate(system.q_symbols)}
        placed = []
        for part in system.parts:
            x = qm[[index[str(s)] for s in part.q]]
            R = quaternion_matrix(x[3:])
            placed += [(g.get("file") or g["shape"], tuple(np.round(x[:3] + R @ np.array(g["position"]), 9)))
                       for g in part.geometry]
        poses.append(sorted(placed))
    assert len(poses[0]) > 0 and poses[0] == poses[1]


def merged_model(name, extra=""):
    """A model file of models/robots with ``merge_fixed: true`` on its robot entries."""
    text = (MODELS / f"{name}.yaml").read_text()
    return re.sub(r"(\n    type: robot\n)", r"\1    merge_fixed: true\n", text) + extra


def test_model_file_attaching_to_a_merged_link_moves_alike(tmp_path):
    """ur5_holding_bar welds its bar to the flange ``arm_tool0``, a link on a fixed joint:
    merged, the flange is a frame of the wrist's body. The bar moves alike, the flange's
    position output is the same, and the model equals Pinocchio's constraintDynamics."""
    outputs = "outputs:\n  flange: {position: arm_tool0}\n  wrist: {position: arm_tool0.link}\n"
    text = (MODELS / "ur5_holding_bar.yaml").read_text() + outputs
    whole, merged = mb.loads(text, folder=MODELS), mb.loads(merged_model("ur5_holding_bar", outputs), folder=MODELS)
    assert "arm_tool0" in {p.name for p in whole.parts} - {p.name for p in merged.parts}
    assert len(merged.parts) == len(whole.parts) - 4  # base_link (the root's weld to world), ee_link, tool0, base
    rows, bar = [], []
    for system in (whole, merged):
        q, qd = system.initial_state()
        rows.append(OutputEvaluator(system).evaluate(0.0, q, qd))
        qdd = system.motion(0.0, q, qd).qdd
        bar.append(qdd[[system.coordinates.index(f"bar.{c}") for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]])
    assert np.abs(rows[1] - rows[0]).max() < PLACED and np.abs(bar[1] - bar[0]).max() < SAME
    result = validate_system(merged, samples=2)
    assert result.passed and result.max_rel_error <= VALIDATION_RTOL, result


def test_model_file_errors_name_the_merged_link(tmp_path):
    """A merged fixed joint's reaction, or a frame a merged link never had: ModelError
    naming the file, line, key and link."""
    path = tmp_path / "m.yaml"
    path.write_text(merged_model("ur5_payload", "outputs:\n  grip: {reaction: arm_wrist_3_link_tool0_fixed_joint.force}\n"))
    with pytest.raises(mb.ModelError, match=r"m\.yaml:\d+: at outputs\.grip\.reaction: 'arm_wrist_3_link_tool0_fixed"
                                             r"_joint' is the fixed joint of link 'tool0', merged into its parent"):
        mb.load(path)
    path.write_text(merged_model("ur5_payload").replace("[arm_tool0, payload.hook]", "[arm_tool0.tip, payload.hook]"))
    with pytest.raises(mb.ModelError, match=r"at forces\[0\]\.between\[0\]: 'arm_tool0' \(link 'tool0', merged into "
                                             r"'arm_wrist_3_link' by merge_fixed\) has no frame 'tip'; it has: link, wrist_3_link_tool0_fixed_joint$"):
        mb.load(path)
    path.write_text(merged_model("ur5_payload").replace("merge_fixed: true", "merge_fixed: 1"))
    with pytest.raises(mb.ModelError, match=r"at parts\.arm\.merge_fixed: expected true or false, got 1"):
        mb.load(path)


def test_validate_command_merge_fixed():
    run = [sys.executable, "-m", "mbsynth.cli", "validate"]
    done = subprocess.run(run + ["ur5", "--merge-fixed", "--samples", "2"], capture_output=True, text=True)
    assert done.returncode == 0 and "ur5 (ur5): 7 bodies" in done.stdout and "FAILED" not in done.stdout
    done = subprocess.run(run + [str(MODELS / "ur5_payload.yaml"), "--merge-fixed"], capture_output=True, text=True)
    assert done.returncode == 2 and done.stderr.strip() == (
        "error: --merge-fixed is for a robot name or URDF file; in a model file give the robot entry "
        "'merge_fixed: true'")


def test_a_merged_link_named_as_a_joint_frame_of_its_host_is_refused(tmp_path):
    """Link 'b' welded to 'a' becomes frame 'b' of a's body, which the revolute joint named
    'b' below it already names: refused, naming the file and the link."""
    inertial = '<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>'
    path = tmp_path / "clash.urdf"
    path.write_text(f"""<robot name="clash">
      <link name="a">{inertial}</link><link name="b">{inertial}</link><link name="c">{inertial}</link>
      <joint name="weld" type="fixed"><parent link="a"/><child link="b"/></joint>
      <joint name="b" type="revolute"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    </robot>""")
    assert len(mb.from_robot(str(path)).parts) == 3
    with pytest.raises(mb.ModelError, match=r"clash\.urdf: merged link 'b' would be frame 'b' of 'a', which has a "
                                             r"frame of that name \(a joint's\): build without merge_fixed"):
        mb.from_robot(str(path), merge_fixed=True)


def test_a_merged_joints_reaction_says_it_was_merged_away(pair):
    """The reactions of the merged robot have no entry for a merged fixed joint; asking for
    one says why, where the unmerged robot has it; a name no constraint has gets the
    nearest names."""
    whole, merged, _ = pair
    joint = next(iter(merged.robots[0].welded_joints))
    q, qd = merged.initial_state()
    found = merged.reactions(0.0, q, qd)
    with pytest.raises(KeyError, match=f"'{re.escape(joint)}' is a fixed joint merged away with merge_fixed"):
        found[joint]
    assert joint in whole.reactions(0.0, *whole.initial_state())
    near = next(iter(found))
    with pytest.raises(KeyError, match=f"no constraint named '{re.escape(near)}x'; nearest: {re.escape(near)}"):
        found[near + "x"]
