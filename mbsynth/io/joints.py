"""Reading the world's frames, the joints between frames and the ground contacts.

A joint's ``actuation``, ``spring`` and ``friction`` keys are read by ``joint_forces``."""

import sympy as sp

from ..core.joint_kinds import JOINT_KINDS
from ..model.connectors.joints import Joint
from ..model.connectors.rolling import KnifeEdge, RollingDisk
from ..model.parts import Frame
from .joint_forces import read_friction, read_joint_forces
from .parts import read_frames

# ground contacts (their keys: schema.py): the part kinds they may sit on
CONTACT_TYPES = {"rolling_disk": ("rigid_body", "euler_body"), "knife_edge": ("rigid_body", "euler_body", "planar_body")}


def read_world(builder):
    """Frames fixed in the world (``world: {frames: {...}}``)."""
    node = builder.section(builder.root.get("world"), ("world",), "world")
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
        if part.kind in ("lagrangian", "spring") and not frame_name:
            builder.fail(path, f"a {part.kind} part has no frame of its own: name one of its frames "
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
    """(joints and ground contacts, the force elements of the joints' actuation and springs)."""
    node = builder.root.get("joints")
    if node is None:
        return [], []
    if not isinstance(node, list):
        builder.fail(("joints",), "expected a list of joints")
    joints, forces, names = [], [], set()
    for i, spec in enumerate(node):
        path = ("joints", i)
        if isinstance(spec, dict) and spec.get("type") in CONTACT_TYPES:
            joints.append(read_contact(builder, spec, path, names))
            continue
        spec = builder.section(spec, path, "joint")
        name = _joint_name(builder, spec, path, names)
        kind = spec["type"]
        if kind not in JOINT_KINDS:
            builder.fail(path + ("type",), f"unknown joint type {kind!r}; known: "
                                           f"{', '.join((*JOINT_KINDS, *CONTACT_TYPES))}")
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
        friction = read_friction(builder, spec, path, kind)
        joint = Joint(name, kind, parent, frame_a, child, frame_b, builder.q, builder.qd,
                      builder.param_symbols.values(), length, friction)
        joints.append(joint)
        forces.append((spec, path, joint))
    builder.register_joints(joints)  # joint values in the expressions of actuation and springs
    elements = [e for spec, path, joint in forces for e in read_joint_forces(builder, spec, path, joint)]
    return joints, elements


def read_contact(builder, spec, path, names):
    """A ground contact: ``rolling_disk`` (``child`` the disk's centre frame, z along its
    axis; ``radius``; ``ground`` the height of the plane, 0 by default) or ``knife_edge``
    (``child`` a frame whose x axis is the blade)."""
    kind = spec["type"]
    hosts = CONTACT_TYPES[kind]
    spec = builder.section(spec, path, kind)
    name = _joint_name(builder, spec, path, names)
    part, frame = frame_reference(builder, spec["child"], path + ("child",))
    if part is None or part.kind not in hosts:
        named = dict.fromkeys("rigid_body" if h == "euler_body" else h for h in hosts)  # a model file's types
        builder.fail(path + ("child",), f"a {kind} is a frame on a {' or '.join(named)}, not on "
                                        f"{'the world' if part is None else 'a ' + part.kind}")
    args = (builder.q, builder.qd, builder.param_symbols.values())
    if kind == "knife_edge":
        return KnifeEdge(name, part, frame, *args)
    radius = builder.constant(spec["radius"], path + ("radius",))
    if builder.value(radius) <= 0:
        builder.fail(path + ("radius",), "radius must be positive")
    return RollingDisk(name, part, frame, radius, builder.constant(spec.get("ground", 0), path + ("ground",)),
                       *args)


def _joint_name(builder, spec, path, names):
    name = spec["name"]
    builder.identifier(name, path + ("name",), "joint name")
    if name in names:
        builder.fail(path + ("name",), f"duplicate joint name '{name}'")
    names.add(name)
    return name
