"""Broken URDF files: each one is read, or refused with a ModelError that names the file
(and the link or joint where the mistake is in one); never another exception.

Hand-picked mistakes first (a joint without <parent>, an <axis> without xyz, a <sphere/>
without radius, NaN, negative masses, cycles, missing links, duplicate names), each with
the message it must get, and through the ``mbsynth`` command (exit 2, not 3: a bug).
Then a mutation fuzzer (hypothesis), as tests/test_hostile_files.py fuzzes the YAML
loader: one to three edits of a small hand-written URDF or of example-robot-data's ur5 —
an element or attribute dropped, duplicated or moved, an attribute set to a hostile
value, a joint hung from another link.
"""

import copy
import xml.etree.ElementTree as ET
from datetime import timedelta
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.robots.build import Robot, describe, robot_files

TINY = """\
<?xml version="1.0"?>
<robot name="tiny">
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <link name="base">
    <inertial><origin xyz="0 0 0.05"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"/></inertial>
    <visual><geometry><box size="0.2 0.2 0.1"/></geometry><material name="grey"/></visual>
  </link>
  <link name="arm">
    <inertial><origin xyz="0 0 0.25" rpy="0 0 0"/><mass value="1.0"/>
      <inertia ixx="0.021" ixy="0" ixz="0" iyy="0.021" iyz="0" izz="0.001"/></inertial>
    <visual><origin xyz="0 0 0.25"/><geometry><cylinder radius="0.03" length="0.5"/></geometry></visual>
  </link>
  <link name="slider">
    <inertial><mass value="0.5"/><inertia ixx="0.001" iyy="0.001" izz="0.001"/></inertial>
    <visual><geometry><sphere radius="0.05"/></geometry><material name="red"><color rgba="1 0 0 1"/></material>
    </visual>
  </link>
  <link name="tool"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0.1" rpy="0 0.3 0"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" effort="10" velocity="2"/>
  </joint>
  <joint name="slide" type="prismatic">
    <parent link="arm"/><child link="slider"/><origin xyz="0 0 0.5"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.2" effort="5" velocity="1"/>
  </joint>
  <joint name="flange" type="fixed">
    <parent link="slider"/><child link="tool"/><origin xyz="0 0 0.05"/>
  </joint>
</robot>
"""


def write(folder, text, name="robot.urdf"):
    path = Path(folder) / name
    path.write_text(text)
    return path


def edited(old, new, count=1):
    """TINY with ``old`` replaced by ``new`` (``old`` must occur ``count`` times)."""
    assert TINY.count(old) == count, old
    return TINY.replace(old, new)


def test_the_file_to_break_is_read(tmp_path):
    description = describe(write(tmp_path, TINY))
    assert list(description.links) == ["base", "arm", "slider", "tool"] and description.root == "base"
    assert [j.name for j in description.tree_order()] == ["shoulder", "slide", "flange"]


MISTAKES = [  # (old text of TINY, new text, what the message must say after "robot.urdf: ")
    ('<parent link="base"/>', "", "joint 'shoulder': no <parent>"),
    ('<child link="slider"/>', '<child/>', "joint 'slide': <child> has no 'link'"),
    ('<axis xyz="0 1 0"/>', "<axis/>", "joint 'shoulder': <axis> has no 'xyz'"),
    ('<axis xyz="0 1 0"/>', '<axis xyz="0 1"/>', "joint 'shoulder': <axis xyz> must be 3 finite numbers, got '0 1'"),
    ('<axis xyz="0 0 1"/>', '<axis xyz="0 nan 1"/>', "joint 'slide': <axis xyz> must be 3 finite numbers"),
    ('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>', "joint 'slide' has a zero axis"),
    ('<sphere radius="0.05"/>', "<sphere/>", "link 'slider': <visual>: <sphere> has no 'radius'"),
    ('<box size="0.2 0.2 0.1"/>', "<box/>", "link 'base': <visual>: <box> has no 'size'"),
    ('radius="0.03"', 'radius="-0.03"', "link 'arm': <visual>: a <cylinder> of negative size"),
    ('<origin xyz="0 0 0.25"/>', '<origin xyz="0 0 abc"/>', "link 'arm': <visual>: <origin xyz> must be 3"),
    ('<mass value="1.0"/>', '<mass value="nan"/>', "link 'arm': <mass value> must be 1 finite number, got 'nan'"),
    ('<mass value="1.0"/>', "<mass/>", "link 'arm': <mass> has no 'value'"),
    ('<mass value="1.0"/>', '<mass value="-1.0"/>', "link 'arm' has a negative mass -1.0"),
    ('izz="0.01"', 'izz="1e999"', "link 'base': <inertia izz> must be 1 finite number, got '1e999'"),
    ('<origin xyz="0 0 0.05"/><mass', '<origin xyz="0 0 0.05" rpy="0 0 inf"/><mass', "link 'base': <origin rpy>"),
    ('effort="10"', 'effort="lots"', "joint 'shoulder': <limit effort> must be 1 finite number"),
    ('lower="-1.5" upper="1.5"', 'lower="1.5" upper="-1.5"', "joint 'shoulder': its <limit> has lower 1.5 > upper"),
    ('<color rgba="1 0 0 1"/>', '<color rgba="1 0 0"/>', "link 'slider': <visual>: <color rgba> must be 4"),
    ('<material name="grey"><color', "<material><color", "a <material>: <material> has no 'name'"),
    ('<link name="tool"/>', "<link/>", "a <link> without a name"),
    ('<joint name="flange" type="fixed">', '<joint type="fixed">', "a <joint> without a name"),
    ('<joint name="flange" type="fixed">', '<joint name="flange" type="floating">',
     "joint 'flange' is of type 'floating'; supported"),
    ('<child link="tool"/>', '<child link="hand"/>', "joint 'flange' names an unknown link 'hand'"),
    ('<link name="tool"/>', '<link name="arm"/>', "link 'arm' is defined twice"),
    ('<joint name="flange"', '<joint name="slide"', "joint 'slide' is defined twice"),
    ('<child link="tool"/>', '<child link="arm"/>', "links ['arm'] hang from more than one joint"),
    ('<parent link="base"/><child link="arm"/>', '<parent link="slider"/><child link="arm"/>',
     "root link 'base': joints ['shoulder', 'slide', 'flange'] do not hang from it (a cycle)"),
    ('<link name="tool"/>', '<link name="tool"/>\n'
     '  <joint name="back" type="fixed"><parent link="tool"/><child link="base"/></joint>',
     "expected one root link (a link no joint hangs), found none"),
    ('<link name="tool"/>', '<link name="tool"/><link name="loop"/>\n'
     '  <joint name="loop" type="fixed"><parent link="loop"/><child link="loop"/></joint>',
     "joints ['loop'] do not hang from it (a cycle)"),
]


@pytest.mark.parametrize("old, new, message", MISTAKES, ids=[m[2][:40] for m in MISTAKES])
def test_each_mistake_is_a_model_error_naming_file_and_link_or_joint(tmp_path, old, new, message):
    path = write(tmp_path, edited(old, new, TINY.count(old)))
    with pytest.raises(mb.ModelError) as err:
        describe(path)
    assert str(err.value).startswith(f"{path}: ") and message in str(err.value), str(err.value)


def test_the_command_says_model_error_not_internal_error(tmp_path, capsys):
    """``mbsynth validate`` on a joint without <parent>: exit 2 and one line naming the
    file and the joint (it was exit 3, "internal error", an AttributeError)."""
    path = write(tmp_path, edited('<parent link="base"/>', ""))
    assert main(["validate", str(path)]) == 2
    assert f"error: {path}: joint 'shoulder': no <parent>" in capsys.readouterr().err


def test_a_model_file_names_its_line_and_the_urdf(tmp_path):
    urdf = write(tmp_path, edited('<sphere radius="0.05"/>', "<sphere/>"))
    model = write(tmp_path, f"name: holder\nparts:\n  arm: {{type: robot, robot: {urdf.name}}}\n", "m.yaml")
    with pytest.raises(mb.ModelError, match=rf"m\.yaml:3: at parts\.arm\.robot: {urdf}: link 'slider'"):
        mb.load(model)


# ------------------------------------------------------------------ the mutation fuzzer

HOSTILE = ["", " ", "nan", "inf", "-inf", "1e999", "-1", "0", "-0", "1e-320", "1e300", "abc", "1 2", "1 2 3",
           "1 2 3 4", "0 0 0", "nan 0 0", "1,2,3", "-0.5 -0.5 -0.5", "0x10", "base", "arm", "tool", "shoulder",
           "fixed", "revolute", "continuous", "prismatic", "floating", "planar", "package://nowhere/x.stl"]
ROBOTS = {"tiny": TINY}
if "ur5" in robot_files():
    ROBOTS["ur5"] = Path(robot_files()["ur5"]).read_text()


def mutate(root, data):
    """One edit of the element tree ``root``: an element dropped, duplicated, moved under
    another element or given a new child; an attribute dropped, set to a hostile value or
    to another element's name."""
    elements = list(root.iter())
    element = data.draw(st.sampled_from(elements))
    parents = {child: parent for parent in elements for child in parent}
    operation = data.draw(st.sampled_from(["drop", "duplicate", "move", "add", "unset", "set", "rename"]))
    if element is root or (operation in ("unset", "set", "rename") and not element.attrib and operation != "set"):
        operation = "add"
    if operation == "drop":
        parents[element].remove(element)
    elif operation == "duplicate":
        parents[element].append(copy.deepcopy(element))
    elif operation == "move":
        parents[element].remove(element)
        data.draw(st.sampled_from([e for e in elements if e is not element])).append(element)
    elif operation == "add":
        tag = data.draw(st.sampled_from(["link", "joint", "origin", "axis", "limit", "inertial", "mass", "parent",
                                         "child", "visual", "geometry", "box", "sphere", "material", "color"]))
        element.append(ET.Element(tag, data.draw(st.dictionaries(st.sampled_from(["name", "xyz", "value", "link"]),
                                                                 st.sampled_from(HOSTILE), max_size=2))))
    elif operation == "unset":
        del element.attrib[data.draw(st.sampled_from(sorted(element.attrib)))]
    else:
        key = data.draw(st.sampled_from(sorted(element.attrib) or ["name"]))
        names = [e.get("name") for e in elements if e.get("name")]
        element.set(key, data.draw(st.sampled_from(names if operation == "rename" else HOSTILE)))


@settings(max_examples=200, deadline=timedelta(seconds=5), database=None, suppress_health_check=list(HealthCheck))
@given(robot=st.sampled_from(sorted(ROBOTS)), edits=st.integers(1, 3), data=st.data())
def test_mutated_urdf_files_are_read_or_refused_by_name(tmp_path_factory, robot, edits, data):
    root = ET.fromstring(ROBOTS[robot])
    for _ in range(edits):
        mutate(root, data)
    path = tmp_path_factory.getbasetemp() / f"mutant_{robot}.urdf"
    ET.ElementTree(root).write(path)
    try:
        description = describe(path)
    except mb.ModelError as err:
        assert str(err).startswith(f"cannot read URDF {path}: ") or str(err).startswith(f"{path}: "), str(err)
        return
    robot = Robot.plan(description)  # the names the parts, joints and torques get
    assert set(robot.parts) == set(description.links) and set(robot.joints) == {j.name for j in description.joints}
