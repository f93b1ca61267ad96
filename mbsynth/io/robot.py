"""Reading ``type: robot`` entries: one entry, a whole robot decomposed into parts.

    arm:
      type: robot
      robot: ur5                 # an example-robot-data name, or a URDF file (relative to the model file)
      floating: false            # default false: the root link welded to the world at ``base``
      base: {position: [0, 0, 0.5], rpy: [0, 0, 0]}   # optional; the initial pose when floating
      initial: {elbow_joint: 0.5}   # optional: initial joint positions (URDF names), 0 where not given
      merge_fixed: false         # default false: true merges each link on a fixed joint into its parent

The entry named ``arm`` gives one rigid body per link, named ``arm_<link>`` (frames: ``link``
at the URDF link frame, one per joint named after it), one joint per URDF joint,
``arm_<joint>``, and one torque parameter per movable joint, ``tau_arm_<joint>`` (default 0;
a value under ``parameters:`` wins). Gravity is the model's ``gravity``. With
``merge_fixed: true`` a link on a fixed joint is no part: its mass joins its nearest ancestor
on a movable joint (robots/build.py), and ``arm_<link>`` (its origin), ``arm_<link>.link`` and
the frames of the joints that hung from it still name frames, on that ancestor's body; its
fixed joint has no reaction.

Entries are read in two steps: ``RobotEntry`` before any part is built, so that its torque
parameters join the model's, then ``parts`` and ``connect`` once the parts' symbols are known.
"""

import os
from dataclasses import replace

import numpy as np

from ..core.errors import ModelError
from ..robots.build import Robot, describe
from .parts import read_rotation


class RobotEntry:
    """A ``type: robot`` entry: the URDF read and the names planned (``robot``)."""

    def __init__(self, builder, name, spec, path):
        builder.section(spec, path, "robot")
        floating, merge = (spec.get(key, False) for key in ("floating", "merge_fixed"))
        for key, value in (("floating", floating), ("merge_fixed", merge)):
            if not isinstance(value, bool):
                builder.fail(path + (key,), f"expected true or false, got {value!r}")
        source = spec["robot"]
        if not isinstance(source, str) or not source:
            builder.fail(path + ("robot",), "expected a robot name (see 'mbsynth robots') or a URDF file")
        here = builder.doc.folder
        if source.endswith(".urdf") and not os.path.isabs(source) and os.path.isfile(os.path.join(here, source)):
            source = os.path.join(here, source)
        try:
            description = describe(source)
        except ModelError as err:
            builder.fail(path + ("robot",), str(err))
        self.name, self.spec, self.path = name, spec, path
        self.robot = Robot.plan(description.merged() if merge else description, prefix=f"{name}_",
                                floating=floating, scope=builder.prefix)
        if not builder.placement.identity:
            builder.fail(path, "a robot in a placed substructure is not supported: give its pose with 'base:' "
                               "and include the file without a placement")

    @property
    def parameters(self):
        return self.robot.parameters

    def parts(self, builder):
        """The robot's bodies, at ``base`` with its joints at ``initial`` (read now: they may
        use the model's parameters)."""
        node = builder.section(self.spec.get("base"), self.path + ("base",), "pose")
        position = builder.numbers(node.get("position", [0, 0, 0]), self.path + ("base", "position"), 3)
        rotation = read_rotation(builder, node, self.path + ("base",))
        where = self.path + ("initial",)
        movable = {j.name for j in self.robot.description.joints if j.kind != "fixed"}
        given = builder.mapping(self.spec.get("initial"), where, movable)
        positions = {joint: builder.value(builder.constant(text, where + (joint,))) for joint, text in given.items()}
        self.robot = replace(self.robot, base=(np.array(position), rotation), positions=positions)
        return self.robot.bodies(builder.gravity, builder.parameter_symbols)

    def connect(self, builder):
        """(joints, torque force elements) of the robot, once every part is known."""
        return self.robot.connect(builder.assembly.parts, builder.q, builder.qd, builder.parameter_symbols)


def read_robots(builder):
    """{entry name: RobotEntry} of the file's ``type: robot`` parts, read before any
    part (the loader adds their torque parameters to the model's; a value the file gives wins)."""
    node = builder.root.get("parts")
    entries = {}
    for name, spec in (node.items() if isinstance(node, dict) else ()):
        if isinstance(spec, dict) and spec.get("type") == "robot":
            path = ("parts", name)
            builder.identifier(name, path, "part name")
            entries[name] = RobotEntry(builder, name, spec, path)
    return entries


def read_robot(builder, name, spec, path):
    """The parts of a ``type: robot`` entry (a list: the loader adds each)."""
    others = set(builder.root["parts"]) - {name}
    robot = builder.robots[name].robot
    for part in map(builder.own_name, (*robot.parts.values(), *robot.welded.values())):
        if part in others or part in builder.parameters:
            builder.fail(path, f"robot '{name}' has a link part '{part}', the name of another part or "
                               "of a parameter: rename one of them")
    builder.assembly.welded.update(dict.fromkeys(robot.welded.values(), builder.robots[name]))
    builder.assembly.welded_joints.update(robot.welded_joints)
    return builder.robots[name].parts(builder)


def welded_frame(builder, text, path):
    """(host part, Frame) of ``text`` where it names a merged link's part (``arm_tool0``) or
    one of its frames (``arm_tool0.link``): the frame on its host's body (Robot.welded_reference);
    None where it names no merged link."""
    welded = builder.assembly.welded
    name, frame = (text, "") if builder.full_name(text) in welded else text.rpartition(".")[::2]
    entry = welded.get(builder.full_name(name))
    if entry is None:
        return None
    try:
        return entry.robot.welded_reference(builder.full_name(name), frame, builder.assembly.parts)
    except ModelError as err:
        builder.fail(path, str(err))


def connect_robots(builder):
    """(joints, torque force elements) of every robot of the model."""
    joints, elements = [], []
    for entry in builder.robots.values():
        more_joints, more_elements = entry.connect(builder)
        joints, elements = joints + more_joints, elements + more_elements
    return joints, elements
