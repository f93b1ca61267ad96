"""Reading unilateral constraints: a joint's ``limits:`` and ``restitution:``, and the
``contacts:`` list (model/unilateral.py says what each gap is).

Each reader returns (Unilateral, path of its entry); the loader keeps the paths to name
the entry of a gap that the initial state penetrates (``check_initial``)."""

import sympy as sp

from ..core.joint_kinds import KINDS
from ..core.tolerances import ASSEMBLED_TOL
from ..model.constraints.base import Constraint
from ..model.parts.base import frame_velocity
from ..model.unilateral import Unilateral, gap_row, tangent_basis
from .joints import frame_reference

CONTACT_KINDS = {"plane": "contact_plane", "spheres": "contact_spheres"}  # contact type -> schema section


def read_limits(builder, spec, path, joint, own_name):
    """The Unilaterals of a joint's ``limits: [lo, hi]`` (``own_name``: the joint's name in
    the file): ``<joint>.lower`` (g = value − lo) and ``<joint>.upper`` (g = hi − value)."""
    if "limits" not in spec:
        if "restitution" in spec:
            builder.fail(path + ("restitution",), "restitution needs limits: [lo, hi] on the joint")
        return []
    value = KINDS[joint.joint_kind].limited
    if value is None:
        builder.fail(path + ("limits",), f"a {joint.joint_kind} joint takes no limits (revolute and prismatic joints do)")
    lo, hi = builder.constants(spec["limits"], path + ("limits",), 2)
    if builder.value(lo) > builder.value(hi):
        builder.fail(path + ("limits",), f"lo = {builder.value(lo):g} is above hi = {builder.value(hi):g}")
    e = _restitution(builder, spec, path)
    x = builder.expression(f"{own_name}.{value}", path + ("limits",), builder.constraint_symbols)
    args = (builder.q, builder.qd, builder.parameter_symbols)
    return [(Unilateral(f"{joint.name}.{side}", "limit", e, gap_row(f"{joint.name}.{side}", gap, *args)),
             path + ("limits",)) for side, gap in (("lower", x - lo), ("upper", hi - x))]


def read_contacts(builder):
    """The Unilaterals of the file's ``contacts:`` list."""
    node = builder.root.get("contacts")
    if node is None:
        return []
    if not isinstance(node, list):
        builder.fail(("contacts",), "expected a list of contacts")
    found, names = [], set()
    for i, spec in enumerate(node):
        path = ("contacts", i)
        kind = spec.get("type") if isinstance(spec, dict) else None
        if kind not in CONTACT_KINDS:
            builder.fail(path + (("type",) if isinstance(spec, dict) else ()),
                         f"a contact's type is one of {', '.join(CONTACT_KINDS)}, got {kind!r}")
        spec = builder.section(spec, path, CONTACT_KINDS[kind])
        name = spec["name"]
        builder.identifier(name, path + ("name",), "contact name")
        if name in names:
            builder.fail(path + ("name",), f"duplicate contact name '{name}'")
        names.add(name)
        gap, point, normal = (_plane_gap if kind == "plane" else _spheres_gap)(builder, spec, path)
        full = builder.full_name(name)
        row = gap_row(full, gap, builder.q, builder.qd, builder.parameter_symbols)
        mu, slip = _friction(builder, spec, path, full) if kind == "plane" else (sp.S.Zero, None)
        found.append((Unilateral(full, "contact", _restitution(builder, spec, path), row, mu, slip, point, normal),
                      path))
    return found


def _friction(builder, spec, path, name):
    """(μ, the slip rows) of a plane contact's ``friction: μ`` (μ ≥ 0, 0 by default): the
    rows ψ = t_k·v_c, the velocity of the contact point along two unit tangents t1, t2 of the
    plane (None without friction). The contact point of a sphere of radius r is c = p − r n
    on the part, so v_c = ṗ + ω × (−r n) with ω the part's angular velocity (a point: r = 0)."""
    if "friction" not in spec:
        return sp.S.Zero, None
    mu = builder.constant(spec["friction"], path + ("friction",))
    if builder.value(mu) < 0:
        builder.fail(path + ("friction",), f"friction must be ≥ 0, got {builder.value(mu):g}")
    part, frame = frame_reference(builder, spec["child"], path + ("child",))
    unit = _normal(builder, spec, path)
    radius = _radius(builder, spec.get("radius", 0), path + ("radius",))
    velocity = frame_velocity(part.pose(frame)[0], builder.q, builder.qd) + \
        part.frame_angular_velocity(frame).cross(-radius * unit)
    rows = [t.dot(velocity) for t in tangent_basis(unit, builder.value)]
    return mu, Constraint.nonholonomic(f"{name}.slip", rows, builder.q, builder.qd, builder.parameter_symbols,
                                      row_labels=["t1", "t2"])


def _plane_gap(builder, spec, path):
    """(n·p − ground − r, the contact point p − r n, n) of a sphere on the ``child`` frame
    against the plane n·x = ground."""
    if not builder.placement.identity:
        builder.fail(path, "a ground contact in an included file with a placement: give it in the including file")
    p = _centre(builder, spec["child"], path + ("child",))
    unit = _normal(builder, spec, path)
    radius = _radius(builder, spec.get("radius", 0), path + ("radius",))
    ground = builder.constant(spec.get("ground", 0), path + ("ground",))
    return unit.dot(p) - ground - radius, p - radius * unit, unit


def _normal(builder, spec, path):
    """The plane's unit normal n (sympy, an expression of parameters)."""
    normal = builder.constants(spec.get("normal", [0, 0, 1]), path + ("normal",), 3)
    length = sum(builder.value(x) ** 2 for x in normal) ** 0.5
    if not length > 0:
        builder.fail(path + ("normal",), "the plane's normal is zero")
    return (normal / sp.sqrt(sum(x**2 for x in normal))).evalf()  # a number's root as a float, not an integer's


def _spheres_gap(builder, spec, path):
    """(|p_B − p_A| − r_A − r_B, the contact point p_A + r_A u, u = (p_B − p_A)/|p_B − p_A|)
    of two spheres on two parts."""
    between = builder.sized_list(spec["between"], path + ("between",), 2)
    radii = builder.sized_list(spec["radius"], path + ("radius",), 2)
    (part_a, p_a), (part_b, p_b) = (_centre(builder, x, path + ("between", k), True) for k, x in enumerate(between))
    if part_a is part_b:
        builder.fail(path + ("between",), "the two spheres must be on two parts")
    d = p_b - p_a
    r_a, r_b = (_radius(builder, r, path + ("radius", k)) for k, r in enumerate(radii))
    unit = d / sp.sqrt(d.dot(d))
    return sp.sqrt(d.dot(d)) - r_a - r_b, p_a + r_a * unit, unit


def _centre(builder, text, path, with_part=False):
    """The world position (sympy) of the frame ``text`` on a part (not the world)."""
    part, frame = frame_reference(builder, text, path)
    if part is None:
        builder.fail(path, "a contact's sphere sits on a part, not on the world")
    position = part.pose(frame)[0]
    return (part, position) if with_part else position


def _radius(builder, text, path):
    radius = builder.constant(text, path)
    if builder.value(radius) < 0:
        builder.fail(path, f"a radius is ≥ 0, got {builder.value(radius):g}")
    return radius


def _restitution(builder, spec, path):
    """The entry's coefficient of restitution e (0 ≤ e ≤ 1; 0 by default), an expression of
    parameters."""
    e = builder.constant(spec.get("restitution", 0), path + ("restitution",))
    if not 0 <= builder.value(e) <= 1:
        builder.fail(path + ("restitution",), f"restitution must be between 0 and 1, got {builder.value(e):g}")
    return e


def check_initial(system, found):
    """Fail at the entry of the first gap that the initial state penetrates by more than
    ASSEMBLED_TOL (saying by how much); ``found``: (Unilateral, path, the builder of its file)."""
    q, qd = system.initial_state()
    p = system.parameter_values
    for unilateral, path, builder in found:
        g = unilateral.row.residuals(0.0, q, qd, p)[0][0]
        if g < -ASSEMBLED_TOL:
            builder.fail(path, f"the initial state penetrates '{unilateral.name}' by {-g:.6g} "
                               f"(its gap must be ≥ 0)")
