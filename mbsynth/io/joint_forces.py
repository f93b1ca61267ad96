"""Reading a joint's ``actuation``, ``spring`` and ``friction`` keys.

    actuation: tau                                 revolute: torque about z; prismatic: force along z
    actuation: {torque: tau, force: f}             either or both, as the joint allows (cylindrical: both)
    spring: {stiffness: k, damping: c, rest: x0}   revolute (torsional) or prismatic (linear)
    friction: {viscous: c, coulomb: mu, radius: r} revolute (r, the pin radius, with coulomb) or prismatic

Actuation efforts are expressions of t, parameters and coordinates; coefficients are
expressions of parameters, ≥ 0 (rest: any value, an angle in [−π, π]). Actuation and
springs become force elements (mbsynth.model.joint_forces), friction the joint's non-ideal C
(mbsynth.model.friction).
"""

import sympy as sp

from ..core.joint_kinds import FRICTION_KINDS, KINDS
from ..model.friction import Friction
from ..model.joint_forces import MOTIONS, actuation, joint_motion, joint_spring
from .parts import read_nonnegative
from .schema import SECTIONS


def read_friction(builder, spec, path, kind):
    """The ``Friction`` of a joint of ``kind`` (None without a ``friction:`` key)."""
    if "friction" not in spec:
        return None
    path = path + ("friction",)
    if kind not in FRICTION_KINDS:
        builder.fail(path, f"friction acts at {' and '.join(FRICTION_KINDS)} joints, not at a {kind} joint")
    node = builder.section(spec["friction"], path, "joint_friction")
    if not {"viscous", "coulomb"} & set(node):
        builder.fail(path, "give 'viscous:' and/or 'coulomb:'")
    viscous, coulomb = (read_nonnegative(builder, node, key, path, default=0) for key in ("viscous", "coulomb"))
    radius = sp.S.One
    turning = KINDS[kind].friction.rate == "angle_rate"  # its Coulomb torque is μ r N
    if "radius" in node and (not turning or "coulomb" not in node):
        builder.fail(path + ("radius",), "radius is the pin radius of Coulomb friction at a revolute joint "
                                         "(friction torque μ r N)")
    if turning and "coulomb" in node:
        if "radius" not in node:
            builder.fail(path, "Coulomb friction at a revolute joint needs 'radius', the pin radius "
                               "(friction torque μ r N)")
        radius = builder.constant(node["radius"], path + ("radius",))
        if builder.value(radius) <= 0:
            builder.fail(path + ("radius",), "radius must be positive")
    return Friction(viscous, coulomb, radius)


def read_joint_forces(builder, spec, path, joint):
    """The force elements of a joint's ``actuation`` and ``spring`` keys."""
    args = (builder.q, builder.qd, builder.parameter_symbols)
    elements = []
    if "actuation" in spec:
        efforts = read_actuation(builder, spec["actuation"], path + ("actuation",), joint)
        elements.append(actuation(f"{joint.name}.actuation", joint, efforts, *args))
    if "spring" in spec:
        elements.append(read_spring(builder, spec["spring"], path + ("spring",), joint, args))
    return elements


def read_actuation(builder, node, path, joint):
    """{"torque" and/or "force": expression} from a scalar or a mapping."""
    allowed = {key for key in SECTIONS["joint_actuation"].allowed if getattr(joint, MOTIONS[key][0]) is not None}
    if not allowed:
        builder.fail(path, "actuation drives a revolute, prismatic or cylindrical joint along its axis, "
                           f"not a {joint.joint_kind} joint")
    if isinstance(node, dict):
        node = builder.mapping(node, path, allowed)
        if not node:
            builder.fail(path, f"give {' and/or '.join(sorted(allowed))}")
        return {key: builder.expression(text, path + (key,), builder.global_symbols) for key, text in node.items()}
    key = joint_motion(joint)
    if key is None:
        builder.fail(path, "a cylindrical joint turns and slides: write 'actuation: {torque: ..., force: ...}'")
    return {key: builder.expression(node, path, builder.global_symbols)}


def read_spring(builder, node, path, joint, args):
    """A torsional (revolute) or linear (prismatic) spring and damper at the joint."""
    if joint_motion(joint) is None:
        builder.fail(path, "a joint spring acts at a revolute (torsional) or prismatic (linear) joint, "
                           f"not at a {joint.joint_kind} joint")
    node = builder.section(node, path, "joint_spring")
    stiffness, damping = (read_nonnegative(builder, node, key, path, default=0) for key in ("stiffness", "damping"))
    rest = builder.constant(node.get("rest", 0), path + ("rest",))
    if MOTIONS[joint_motion(joint)][0] == "angle" and abs(builder.value(rest)) > float(sp.pi):
        builder.fail(path + ("rest",), "the rest angle must lie in [−π, π] (the joint angle is atan2 of the "
                                       "frames' x axes)")
    return joint_spring(f"{joint.name}.spring", joint, stiffness, damping, rest, *args)
