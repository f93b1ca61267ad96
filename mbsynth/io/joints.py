"""Reading the world's frames, the joints between frames and the ground contacts.

A joint's ``actuation``, ``spring`` and ``friction`` keys are read by ``joint_forces``."""

import difflib
import re
from dataclasses import replace

import sympy as sp

from ..core.joint_kinds import JOINT_KINDS, KINDS
from ..model.constraints.joints import Joint
from ..model.constraints.rolling import KnifeEdge, RollingDisk
from ..model.parts import Frame
from ..model.parts.part_type import ANGLES, PLANE, QUATERNION
from .joint_forces import read_friction, read_joint_forces
from .parts import read_frames
from .substructures import COUNT_MAX
from .part_types import either, file_types_of
from .placement import place_height
from .robot import welded_frame

# ground contacts (their keys: schema.py): the orientations (model/parts/part_type.py) of the rigid parts they may sit on
CONTACT_TYPES = {"rolling_disk": (QUATERNION, ANGLES), "knife_edge": (QUATERNION, ANGLES, PLANE)}


def read_world(builder):
    """Frames fixed in the world (``world: {frames: {...}}``); in an included file, placed
    by its ``placement:`` (substructures.py)."""
    node = builder.section(builder.root.get("world"), ("world",), "world")
    frames = read_frames(builder, "world", node.get("frames"), ("world", "frames"), offsets=True)
    if builder.placement.identity:
        return frames
    return [replace(f, position=p, rotation=R) for f in frames for p, R in [builder.placement.frame(f.position,
                                                                                                 f.rotation)]]


def read_ports(builder):
    """Register the file's ``ports: {name: frame}``, each under its full name; the frame
    may be a port of a file this one includes."""
    node = builder.root.get("ports")
    if node is None:
        return
    node = builder.mapping(node, ("ports",), set(node) if isinstance(node, dict) else set())
    for name, text in node.items():
        builder.identifier(name, ("ports", name), "port name")
        if name in builder.parts or name in builder.parameters:
            builder.fail(("ports", name), f"port '{name}' has the name of a part or parameter of the file")
        builder.assembly.ports[builder.full_name(name)] = frame_reference(builder, text, ("ports", name))


def frame_reference(builder, text, path):
    """(part or None for the world, Frame) of ``part.frame``, ``part`` (its own origin and
    axes), ``world``, ``world.frame`` or a port of an included file (``left_leg.hip``); a
    part of an included file is named in full (``left_leg.thigh.knee``), a copy by its
    number or an expression of parameters for it (``cell[N - 1].right``)."""
    if not isinstance(text, str) or not text:
        builder.fail(path, f"expected a frame such as 'link.top' or 'world', got {text!r}")
    if "[" in text:
        text = _BRACKETS.sub(lambda m: _index(builder, m.group(1), path), text)
    port = builder.assembly.ports.get(builder.full_name(text))
    if port is not None:
        return port
    if text in builder.parts:
        part_name, frame_name = text, ""
    else:
        part_name, _, frame_name = text.rpartition(".")
    if text == "world" or part_name == "world":
        frame_name = "" if text == "world" else frame_name
        frames, part = builder.world_frames, None
    elif (welded := welded_frame(builder, text, path)) is not None:
        return welded
    elif part_name in builder.parts:
        part = builder.parts[part_name]
        frames = part.frames
        if not part.part_type.origin and not frame_name:
            builder.fail(path, f"a {part.type_name} part has no frame of its own: name one of its frames "
                               f"({', '.join(frames) or 'it declares none'})")
    else:
        builder.fail(path, unknown_frame(builder, text))
    if not frame_name:
        if part is None:
            position, rotation = builder.placement.frame(sp.zeros(3, 1), sp.eye(3))
            return None, Frame("world", "origin", position, rotation)
        return part, Frame(part.name, "origin", sp.zeros(3, 1), sp.eye(3))
    if frame_name not in frames:
        builder.fail(path, f"'{part_name}' has no frame '{frame_name}'; it has: {', '.join(frames) or 'none'}")
    return part, frames[frame_name]


def unknown_frame(builder, text):
    """Why ``text`` names no frame: an unknown part, a copy's index out of range or missing,
    an index on an entry without copies, an included file's unknown port or part."""
    head = text.split(".")[0]
    base, _, index = head.partition("[")
    copies = sorted(name for name, _ in builder.children)
    for name, children in builder.children:
        if base != name:
            continue
        counted = children[0].prefix != builder.prefix + name + "."  # count: copies name[0] …
        last = f"{name}[{len(children) - 1}]"
        if counted and not index:
            return f"'{name}' has {len(children)} copies (count:): name one of them, {name}[0] … {last}"
        if index and not counted:
            return f"'{name}' is one file, not numbered copies (it has no count:): write '{name}.…' without [{index}"
        if index and (not index.rstrip("]").isdigit() or int(index.rstrip("]")) >= len(children)):
            return f"'{head}' is out of range: '{name}' has copies {name}[0] … {last}"
        child = next(c for c in children if c.prefix == builder.prefix + head + ".")
        ports = sorted(port[len(child.prefix):] for port in builder.assembly.ports if port.startswith(child.prefix))
        rest = text[len(head) + 1:]
        problem = (f"has no port or part frame '{rest}'" if rest
                   else "is a substructure, not a frame: name one of its ports or its parts' frames")
        return (f"'{head}' (the file {child.doc.name}) {problem}; its ports: "
                f"{', '.join(ports) or 'none'}; its parts: {', '.join(sorted(child.parts)[:20])}")
    names = ["world", *(name for name in builder.parts if "." not in name), *copies]
    close = difflib.get_close_matches(head, names, n=3)
    hint = f" (did you mean {', '.join(close)}?)" if close else ""
    shown = names if len(names) <= 30 else names[:30] + [f"… {len(names) - 30} more"]
    return f"unknown part '{head}' in frame '{text}'{hint}; parts: {', '.join(shown)}"


def read_joints(builder):
    """(joints and ground contacts, the force elements of the joints' actuation and springs)."""
    node = builder.root.get("joints")
    if node is None:
        return [], []
    if not isinstance(node, list):
        builder.fail(("joints",), "expected a list of joints")
    joints, forces, names = [], [], set()
    for i, spec, suffix, loop in _each_joint(builder, node):
        with builder.extra_names(loop):
            joint = _read_joint(builder, spec, ("joints", i), names, suffix)
        joints.append(joint)
        if isinstance(joint, Joint):
            forces.append((spec, ("joints", i), joint))
            builder.limited.append((spec, ("joints", i), joint, spec["name"] + suffix, loop))
    builder.register_joints(joints)  # joint values in the expressions of actuation and springs
    elements = [e for spec, path, joint in forces for e in read_joint_forces(builder, spec, path, joint)]
    return joints, elements


def _read_joint(builder, spec, path, names, suffix):
    """A joint or ground contact of the ``joints:`` list."""
    if isinstance(spec, dict) and spec.get("type") in CONTACT_TYPES:
        return read_contact(builder, spec, path, names, suffix)
    spec = builder.section(spec, path, "joint")
    name = _joint_name(builder, spec, path, names, suffix)
    kind = spec["type"]
    if kind not in JOINT_KINDS:
        builder.fail(path + ("type",), f"unknown joint type {kind!r}; known: "
                                       f"{', '.join((*JOINT_KINDS, *CONTACT_TYPES))}")
    parent, frame_a = frame_reference(builder, spec["parent"], path + ("parent",))
    child, frame_b = frame_reference(builder, spec["child"], path + ("child",))
    if child is None or child is parent:
        builder.fail(path + ("child",), "the child of a joint must be a part other than its parent")
    length = None
    if KINDS[kind].has_length:
        if "length" not in spec:
            builder.fail(path, "a distance joint needs 'length'")
        length = builder.constant(spec["length"], path + ("length",))
        if builder.value(length) <= 0:
            builder.fail(path + ("length",), "length must be positive")
    elif "length" in spec:
        builder.fail(path + ("length",), f"only a distance joint has a length, not a {kind} joint")
    friction = read_friction(builder, spec, path, kind)
    return Joint(name, kind, parent, frame_a, child, frame_b, builder.q, builder.qd,
                 builder.parameter_symbols, length, friction)


def read_contact(builder, spec, path, names, suffix=""):
    """A ground contact: ``rolling_disk`` (``child`` the disk's centre frame, z along its
    axis; ``radius``; ``ground`` the height of the plane, 0 by default, in the file's axes:
    raised with its placement) or ``knife_edge`` (``child`` a frame whose x axis is the blade)."""
    kind = spec["type"]
    hosts = _contact_host(CONTACT_TYPES[kind])
    spec = builder.section(spec, path, kind)
    name = _joint_name(builder, spec, path, names, suffix)
    part, frame = frame_reference(builder, spec["child"], path + ("child",))
    if part is None or not hosts(part.part_type):
        named = file_types_of(hosts)  # a model file's types
        builder.fail(path + ("child",), f"a {kind} is a frame on a {either(named)} part, not on "
                                        f"{'the world' if part is None else 'a ' + part.type_name}")
    args = (builder.q, builder.qd, builder.parameter_symbols)
    if kind == "knife_edge":
        return KnifeEdge(name, part, frame, *args)
    radius = builder.constant(spec["radius"], path + ("radius",))
    if builder.value(radius) <= 0:
        builder.fail(path + ("radius",), "radius must be positive")
    ground = builder.constant(spec.get("ground", 0), path + ("ground",))
    ground = place_height(builder.placement, ground, lambda why: builder.fail(path, why))
    return RollingDisk(name, part, frame, radius, ground, *args)


def _contact_host(orientations):
    """Whether a part type may carry a contact that needs one of ``orientations``: a rigid part turned so."""
    return lambda part_type: part_type.rigid and part_type.orientation in orientations


def _joint_name(builder, spec, path, names, suffix=""):
    """The model's name of the joint (``for:`` copies: ``name[i]``), checked unique in the file."""
    name = spec["name"]
    builder.identifier(name, path + ("name",), "joint name")
    if name + suffix in names:
        builder.fail(path + ("name",), f"duplicate joint name '{name}'")
    names.add(name + suffix)
    return builder.full_name(name + suffix)


_BRACKETS = re.compile(r"\[([^\[\]]*)\]")


def _each_joint(builder, node):
    """(index in ``joints:``, entry, name suffix) of each joint; an entry with ``for: {i:
    [first, last]}`` gives one joint per i = first … last (both included; none when last is
    first - 1), named ``name[i]``, with each ``[expression of i]`` in its frames replaced by
    its value (``parent: cell[i].right``, ``child: cell[i+1].left``)."""
    for i, spec in enumerate(node):
        if not (isinstance(spec, dict) and "for" in spec):
            yield i, spec, "", {}
            continue
        path = ("joints", i, "for")
        loop = spec["for"]
        if not (isinstance(loop, dict) and len(loop) == 1):
            builder.fail(path, "expected one name and its range, e.g. 'for: {i: [0, N - 2]}'")
        (variable, bounds), = loop.items()
        builder.identifier(variable, path + (variable,), "loop name")
        if variable in builder.param_symbols:
            builder.fail(path + (variable,), f"the loop name '{variable}' is a parameter's")
        first, last = (builder.fixed_value(x, path + (variable, k))
                       for k, x in enumerate(builder.constants(bounds, path + (variable,), 2)))
        if first != int(first) or last != int(last):
            builder.fail(path + (variable,), f"the range [{first:g}, {last:g}] must be of whole numbers")
        if last < first - 1:  # [k, k - 1] is empty (one copy: no joints between copies), a lower last a mistake
            builder.fail(path + (variable,), f"the range [{first:g}, {last:g}] runs backwards: give [first, last] "
                                             "with last ≥ first (or first - 1 for none)")
        if last - first + 1 > COUNT_MAX:
            builder.fail(path + (variable,), f"the range [{first:g}, {last:g}] gives more than {COUNT_MAX} joints")
        for k in range(int(first), int(last) + 1):
            copy = type(spec)({key: value for key, value in spec.items() if key != "for"})
            copy.line, copy.key_lines = spec.line, spec.key_lines
            yield i, copy, f"[{k}]", {variable: sp.Integer(k)}


def _index(builder, text, path):
    """``[text]`` of a frame name, ``text`` an expression of parameters (and of a ``for:``
    entry's name): the whole number it gives, in brackets."""
    number = builder.fixed_value(builder.constant(text, path), path)
    if number != int(number) or number < 0:
        builder.fail(path, f"[{text}] is {number:g}: a copy's number is a whole number ≥ 0")
    return f"[{int(number)}]"
