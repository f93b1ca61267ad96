"""Reading a model's ``outputs:`` mapping (the kinds are described in mbsynth.model.outputs)."""

import functools

from ..core.errors import ModelError
from ..model.outputs import (BUILT_IN_COLUMNS, contact_output, energy_output, expression_output, frame_output,
                             reaction_output)
from .joints import frame_reference
from .schema import SECTIONS

KINDS = tuple(key.name for key in SECTIONS["output"].keys)


def read_outputs(builder, constraints, gaps=()):
    """The Outputs the file declares (under their full names, ``left_leg.height``);
    ``constraints``: the model's constraints; ``gaps``: the full names of its unilateral
    gaps (contacts, joint limits)."""
    node = builder.root.get("outputs")
    if node is None:
        return ()
    node = builder.mapping(node, ("outputs",), set(node) if isinstance(node, dict) else set())
    by_name = {builder.own_name(c.name): c for c in constraints if c.name.startswith(builder.prefix)}
    outputs = []
    for own, spec in node.items():
        path = ("outputs", own)
        builder.identifier(own, path, "output name")
        name = builder.full_name(own)
        if name in BUILT_IN_COLUMNS:
            builder.fail(path, f"output name '{name}' is a column every trajectory has ({', '.join(BUILT_IN_COLUMNS)}, "
                               "the coordinates and velocities); choose another")
        if not isinstance(spec, dict):
            outputs.append(expression_output(name, builder.expression(spec, path, builder.global_symbols)))
            continue
        spec = builder.section(spec, path, "output")
        if len(spec) != 1:
            builder.fail(path, f"give exactly one of {', '.join(KINDS)} (or an expression)")
        (kind, value), = spec.items()
        kpath = path + (kind,)
        if kind == "reaction":
            constraint, _, which = str(value).rpartition(".")
            link = builder.assembly.welded_joints.get(builder.full_name(constraint))
            if link is not None:
                builder.fail(kpath, f"'{constraint}' is the fixed joint of link '{link}', merged into its parent "
                                    "(merge_fixed: true): it carries no reaction; without merge_fixed it does")
            if constraint not in by_name:
                builder.fail(kpath, f"unknown joint or constraint '{constraint}' in '{value}' (write "
                                    f"'<joint>.force', '.torque' or '.multipliers'); known: {', '.join(by_name)}")
            make = functools.partial(reaction_output, name, by_name[constraint], which)
        elif kind == "contact":
            gap, _, which = str(value).rpartition(".")
            if builder.full_name(gap) not in gaps:
                builder.fail(kpath, f"unknown contact or limit '{gap}' in '{value}' (write '<contact>.force', "
                                    f"'.impulse' or '.friction'); known: {', '.join(gaps) or 'none'}")
            make = functools.partial(contact_output, name, builder.full_name(gap), which)
        elif kind == "energy":
            make = functools.partial(energy_output, name, value)
        else:
            part, frame = frame_reference(builder, value, kpath)
            make = functools.partial(frame_output, name, kind, part, frame, builder.q, builder.qd)
        try:  # the model's own errors get the file and line here (the builder's have them)
            outputs.append(make())
        except ModelError as err:
            builder.fail(kpath, str(err))
    return tuple(outputs)
