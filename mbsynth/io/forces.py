"""Reading the top-level ``forces:`` list into force elements (mbsynth.model.forces).

    - {name: s, type: spring, between: [a.frame, b.frame], stiffness: k, rest_length: l0, damping: c}
    - {name: d, type: damper, between: [a.frame, world.anchor], damping: c}
    - {name: f, type: force, at: body.tip, value: [fx, fy, fz]}           world axes
    - {name: m, type: torque, part: body, value: [tx, ty, tz], axes: body}  world (default) or body

Values are expressions of parameters, ``t`` and the coordinates (``part.x``); stiffness,
rest length and damping are expressions of parameters, ≥ 0. ``name`` defaults to
``<type>_<index>``. (A torque names its body with ``part:``: YAML 1.1 reads ``on`` as true.)
"""

from ..model.forces import AXES, applied_force, applied_torque, point_spring
from .joints import frame_reference
from .robot import welded_frame
from .part_types import either, file_types_of
from .parts import read_nonnegative
from .schema import FORCE_SECTIONS


def read_forces(builder):
    """The force elements of the model's ``forces:`` list (empty when absent)."""
    node = builder.root.get("forces")
    if node is None:
        return []
    if not isinstance(node, list):
        builder.fail(("forces",), "expected a list of force elements")
    elements, names = [], set()
    for i, spec in enumerate(node):
        path = ("forces", i)
        if not isinstance(spec, dict) or "type" not in spec:
            builder.fail(path, f"expected a mapping with 'type' (one of {', '.join(FORCE_SECTIONS)}) and its data")
        if True in spec:
            builder.fail(path, "YAML reads the key 'on' as true: name the body with 'part:'")
        kind = spec["type"]
        if kind not in FORCE_SECTIONS:
            builder.fail(path + ("type",), f"unknown force type {kind!r}; known: {', '.join(FORCE_SECTIONS)}")
        builder.section(spec, path, FORCE_SECTIONS[kind])
        name = builder.identifier(spec.get("name", f"{kind}_{i + 1}"), path + ("name",), "force name")
        if name in names:
            builder.fail(path + ("name",), f"duplicate force name '{name}'")
        names.add(name)
        elements.append(READERS[kind](builder, builder.full_name(name), spec, path))
    return elements


def _args(builder):
    return builder.q, builder.qd, builder.parameter_symbols


def _spring(builder, name, spec, path):
    pA, pB = _between(builder, spec["between"], path + ("between",))
    stiffness, rest_length, damping = (read_nonnegative(builder, spec, key, path, default=0)
                                       for key in ("stiffness", "rest_length", "damping"))
    return point_spring(name, pA, pB, stiffness, rest_length, damping, *_args(builder))


def _between(builder, node, path):
    """World positions of the two frames a spring or damper joins (at most one on the world)."""
    if not isinstance(node, list) or len(node) != 2:
        builder.fail(path, "expected two frames, e.g. [body.tip, world.anchor]")
    ends = [frame_reference(builder, text, path + (i,)) for i, text in enumerate(node)]
    if ends[0][0] is None and ends[1][0] is None:
        builder.fail(path, "both ends are on the world: at least one must be on a part")
    return [frame.position if part is None else part.frame_position(frame) for part, frame in ends]


def _force(builder, name, spec, path):
    part, frame = frame_reference(builder, spec["at"], path + ("at",))
    if part is None:
        builder.fail(path + ("at",), "a force must act on a part, not on the world")
    value = builder.vector(spec["value"], path + ("value",), 3, builder.global_symbols)
    return applied_force(name, part.frame_position(frame), value, *_args(builder))


def _torque(builder, name, spec, path):
    part_name = spec["part"]
    welded = welded_frame(builder, part_name, path + ("part",)) if isinstance(part_name, str) else None
    if welded is None and (not isinstance(part_name, str) or part_name not in builder.parts):
        builder.fail(path + ("part",), f"unknown part {part_name!r}; parts: {', '.join(builder.parts)}")
    part = builder.parts[part_name] if welded is None else welded[0]  # a merged link turns with its host
    if not part.part_type.rigid:  # a torque turns a part with an orientation of its own, as one piece
        named = either(file_types_of(lambda part_type: part_type.rigid))
        builder.fail(path + ("part",), f"a torque acts on a {named} part; '{part_name}' is a {part.type_name}")
    axes = spec.get("axes", "world")
    if axes not in AXES:
        builder.fail(path + ("axes",), f"axes must be one of {', '.join(AXES)}, got {axes!r}")
    value = builder.vector(spec["value"], path + ("value",), 3, builder.global_symbols)
    return applied_torque(name, part, value, axes, *_args(builder))


READERS = {"spring": _spring, "damper": _spring, "force": _force, "torque": _torque}
