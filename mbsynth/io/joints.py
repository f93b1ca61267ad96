"""Reading the world's frames and the joints between frames."""

import sympy as sp

from ..connectors import JOINT_KINDS, Joint
from ..subsystems import Frame
from .parts import read_frames

JOINT_KEYS = {"name", "type", "parent", "child", "length", "description"}


def read_world(builder):
    """Frames fixed in the world (``world: {frames: {...}}``)."""
    node = builder.mapping(builder.root.get("world"), ("world",), {"frames"})
    return read_frames(builder, "world", node.get("frames"), ("world", "frames"), offsets=True)


def frame_reference(builder, text, path):
    """(part or None for the world, Frame) of ``part.frame``, ``part`` (its own origin and
    axes), ``world`` or ``world.frame``."""
    if not isinstance(text, str) or not text:
        builder.fail(path, f"expected a frame such as 'link.top' or 'world', got {text!r}")
    part_name, _, frame_name = text.partition(".")
    if part_name == "world":
        frames, part = builder.world_frames, None
    elif part_name in builder.parts:
        part = builder.parts[part_name]
        frames = part.frames
        if part.kind == "lagrangian" and not frame_name:
            builder.fail(path, f"a lagrangian part has no frame of its own: name one of its frames "
                               f"({', '.join(frames) or 'it declares none'})")
    else:
        builder.fail(path, f"unknown part '{part_name}' in frame '{text}'; parts: "
                           f"{', '.join(['world', *builder.parts])}")
    if not frame_name:
        return part, Frame(part_name, "origin", sp.zeros(3, 1), sp.eye(3))
    if frame_name not in frames:
        builder.fail(path, f"'{part_name}' has no frame '{frame_name}'; it has: {', '.join(frames) or 'none'}")
    return part, frames[frame_name]


def read_joints(builder):
    node = builder.root.get("joints")
    if node is None:
        return []
    if not isinstance(node, list):
        builder.fail(("joints",), "expected a list of joints")
    joints, names = [], set()
    for i, spec in enumerate(node):
        path = ("joints", i)
        spec = builder.mapping(spec, path, JOINT_KEYS, required=("name", "type", "parent", "child"))
        name = spec["name"]
        builder.identifier(name, path + ("name",), "joint name")
        if name in names:
            builder.fail(path + ("name",), f"duplicate joint name '{name}'")
        names.add(name)
        kind = spec["type"]
        if kind not in JOINT_KINDS:
            builder.fail(path + ("type",), f"unknown joint type {kind!r}; known: {', '.join(JOINT_KINDS)}")
        parent, frame_a = frame_reference(builder, spec["parent"], path + ("parent",))
        child, frame_b = frame_reference(builder, spec["child"], path + ("child",))
        if child is None or child is parent:
            builder.fail(path + ("child",), "the child of a joint must be a part other than its parent")
        length = None
        if kind == "distance":
            if "length" not in spec:
                builder.fail(path, "a distance joint needs 'length'")
            length = builder.constant(spec["length"], path + ("length",))
            if builder.value(length) <= 0:
                builder.fail(path + ("length",), "length must be positive")
        elif "length" in spec:
            builder.fail(path + ("length",), f"only a distance joint has a length, not a {kind} joint")
        joints.append(Joint(name, kind, parent, frame_a, child, frame_b, builder.q, builder.qd,
                            builder.param_symbols.values(), length))
    return joints
