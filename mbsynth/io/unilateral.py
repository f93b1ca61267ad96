"""Reading unilateral constraints: a joint's ``limits:`` and ``restitution:``, and the
``contacts:`` list (model/unilateral.py says what each gap is).

Each reader returns (Unilateral, path of its entry); the loader keeps the paths to name
the entry of a gap that the initial state penetrates (``check_initial``)."""

import sympy as sp

from ..core.joint_kinds import KINDS
from ..core.tolerances import ASSEMBLED_TOL
from ..model.constraints.base import Constraint
from ..model.joint_templates import pose
from ..model.parts.base import frame_velocity
from ..model.segments import between_segments, to_segment
from ..model.unilateral import Unilateral, gap_row, tangent_basis
from ..symbolic.cache import placeholder
from ..symbolic.dag import Replacing, replaced, symbols_in
from .joints import frame_reference

CONTACT_KINDS = {"plane": "contact_plane", "spheres": "contact_spheres"}  # contact type -> schema section
SHAPES = {"radius": 1, "capsule": 2, "box": 3}  # a plane contact's shape keys -> their sizes (_plane_spheres)


def read_limits(builder, spec, path, joint, own_name):
    """The Unilaterals of a joint's ``limits`` (``own_name``: the joint's name in the file):

    - revolute, prismatic ``[lo, hi]`` on its angle or displacement x: ``<joint>.lower``
      (g = x − lo) and ``<joint>.upper`` (g = hi − x);
    - universal ``[[lo1, hi1], [lo2, hi2]]`` on angle1 and angle2: ``<joint>.lower1``,
      ``.upper1``, ``.lower2``, ``.upper2`` alike;
    - spherical ``{cone: θ}`` (0 < θ ≤ π) on the swing, the angle between the two frames'
      z axes: ``<joint>.cone``, g = z_A·z_B − cos θ (its rate is −sin(swing) × the swing's
      rate, so Newton's law on it is Newton's law on the swing angle)."""
    if "limits" not in spec:
        if "restitution" in spec:
            builder.fail(path + ("restitution",), "restitution needs limits on the joint")
        return []
    where, kind = path + ("limits",), joint.joint_kind
    if kind == "spherical":
        gaps = [("cone", _cone(builder, spec["limits"], where, joint))]
    elif kind == "universal":
        pairs = builder.sized_list(spec["limits"], where, 2)
        gaps = [gap for k, pair in enumerate(pairs, 1)
                for gap in _range(builder, pair, where + (k - 1,), f"{own_name}.angle{k}", str(k))]
    elif KINDS[kind].limited is not None:
        gaps = _range(builder, spec["limits"], where, f"{own_name}.{KINDS[kind].limited}", "")
    else:
        builder.fail(where, f"a {kind} joint takes no limits (revolute, prismatic, universal and spherical "
                            f"joints do)")
    e = _restitution(builder, spec, path)
    args = (builder.q, builder.qd, builder.parameter_symbols)
    return [(Unilateral(f"{joint.name}.{side}", "limit", e, gap_row(f"{joint.name}.{side}", gap, *args)), where)
            for side, gap in gaps]


def _range(builder, node, path, value, suffix):
    """[("lower" + suffix, x − lo), ("upper" + suffix, hi − x)] of ``[lo, hi]`` on the joint
    value ``value`` (``<joint>.<name>``)."""
    lo, hi = builder.constants(node, path, 2)
    if builder.value(lo) > builder.value(hi):
        builder.fail(path, f"lo = {builder.value(lo):g} is above hi = {builder.value(hi):g}")
    x = builder.expression(value, path, builder.constraint_symbols)
    return [("lower" + suffix, x - lo), ("upper" + suffix, hi - x)]


def _cone(builder, node, path, joint):
    """z_A·z_B − cos θ of a spherical joint's ``{cone: θ}``."""
    node = builder.section(node, path, "cone_limit")
    angle = builder.constant(node["cone"], path + ("cone",))
    if not 0 < builder.value(angle) <= float(sp.pi):
        builder.fail(path + ("cone",), f"a cone's half-angle is in (0, π], got {builder.value(angle):g}")
    (parent, child), (frame_a, frame_b) = joint.parts, joint.frames
    z_a, z_b = (sp.Matrix(pose(part, frame)[1])[:, 2] for part, frame in ((parent, frame_a), (child, frame_b)))
    return z_a.dot(z_b) - sp.cos(angle)


def read_contacts(builder):
    """The Unilaterals of the file's ``contacts:`` list: one per sphere or point, per end of
    a capsule and per corner of a box (``NAME[k]``, ``_plane_spheres``)."""
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
        e = _restitution(builder, spec, path)
        if kind == "spheres":
            gap, point, normal, through = _spheres_gap(builder, spec, path)
            found.append((Unilateral(builder.full_name(name), "contact", e, _row(builder, path, name, gap, through),
                                     point=point, normal=normal), path))
            continue
        unit = _normal(builder, spec, path)
        mu = _friction(builder, spec, path)
        ground = builder.constant(spec.get("ground", 0), path + ("ground",))
        for suffix, centre, radius, omega in _plane_spheres(builder, spec, path):
            full = builder.full_name(name + suffix)
            slip, tangents = (None, None) if mu is None else _slip(builder, full, centre, radius, omega, unit)
            row = _row(builder, path, name + suffix, unit.dot(centre) - ground - radius)
            found.append((Unilateral(full, "contact", e, row, sp.S.Zero if mu is None else mu, slip,
                                     centre - radius * unit, unit, tangents), path))
    return found


def _row(builder, path, name, gap, through=None):
    """The gap's row (model/unilateral.gap_row); the contact at ``path`` is refused where its
    gap changes with no coordinate (it could never touch or leave)."""
    in_coordinates = gap if through is None else replaced([gap], through)[0]
    if not symbols_in([in_coordinates]) & set(builder.q):
        builder.fail(path, f"contact '{name}': its gap {in_coordinates} changes with no coordinate, so it can never "
                           "touch or leave (a normal across its part's plane of motion?)")
    return gap_row(builder.full_name(name), gap, builder.q, builder.qd, builder.parameter_symbols, through)


def _friction(builder, spec, path):
    """A plane contact's ``friction: μ`` (μ ≥ 0; None where it has none)."""
    if "friction" not in spec:
        return None
    mu = builder.constant(spec["friction"], path + ("friction",))
    if builder.value(mu) < 0:
        builder.fail(path + ("friction",), f"friction must be ≥ 0, got {builder.value(mu):g}")
    return mu


def _slip(builder, name, centre, radius, omega, unit):
    """(the slip rows, their tangents) of a sphere of radius r centred at ``centre`` (world,
    on a part turning at ω) against a plane of unit normal n: the rows ψ = t_k·v_c, the
    velocity of the contact point c = centre − r n along two unit tangents t1, t2 of the
    plane (the columns of a (3, 2) matrix), v_c = ċentre + ω × (−r n)."""
    velocity = frame_velocity(centre, builder.q, builder.qd) + omega.cross(-radius * unit)
    tangents = tangent_basis(unit, builder.value)
    rows = [t.dot(velocity) for t in tangents]
    return Constraint.nonholonomic(f"{name}.slip", rows, builder.q, builder.qd, builder.parameter_symbols,
                                   row_labels=["t1", "t2"]), sp.Matrix.hstack(*tangents)


def _plane_spheres(builder, spec, path):
    """[(name suffix, centre (world), radius, the part's ω)] of a plane contact: the ``child``
    frame's sphere of ``radius`` (a point where 0), or a ``capsule: [r, length]`` along the
    frame's z about its origin (its two end spheres, ``[0]`` at −length/2, ``[1]`` at
    +length/2), or a ``box: [x, y, z]`` (sizes along the frame's axes, about its origin:
    its eight corners, ``[k]`` at (±x/2, ±y/2, ±z/2), the signs of x, y, z from bits 0, 1, 2
    of k, 0 for −). A gap of each is n·centre − ground − radius."""
    if not builder.placement.identity:
        builder.fail(path, "a ground contact in an included file with a placement: give it in the including file")
    shapes = [key for key in SHAPES if key in spec]
    if len(shapes) > 1:
        builder.fail(path + (shapes[1],), f"a contact has one of {', '.join(SHAPES)}, got {' and '.join(shapes)}")
    part, frame = frame_reference(builder, spec["child"], path + ("child",))
    if part is None:
        builder.fail(path + ("child",), "a contact's sphere sits on a part, not on the world")
    origin, rotation = part.pose(frame)
    omega = part.frame_angular_velocity(frame)
    shape = shapes[0] if shapes else "radius"
    if shape == "radius":
        return [("", origin, _radius(builder, spec.get("radius", 0), path + ("radius",)), omega)]
    where = path + (shape,)
    sizes = [_size(builder, x, where + (k,)) for k, x in enumerate(builder.sized_list(spec[shape], where,
                                                                                      SHAPES[shape]))]
    if shape == "capsule":
        radius, length = sizes
        axis = sp.Matrix(rotation)[:, 2]
        return [(f"[{k}]", origin + sign * length / 2 * axis, radius, omega) for k, sign in enumerate((-1, 1))]
    half = sp.Matrix(sizes) / 2
    return [(f"[{k}]", origin + sp.Matrix(rotation) * sp.Matrix([(2 * (k >> j & 1) - 1) * half[j] for j in range(3)]),
             sp.S.Zero, omega) for k in range(8)]


def _size(builder, text, path):
    size = builder.constant(text, path)
    if not builder.value(size) > 0:
        builder.fail(path, f"a contact's dimensions are > 0, got {builder.value(size):g}")
    return size


def _normal(builder, spec, path):
    """The plane's unit normal n (sympy, an expression of parameters)."""
    normal = builder.constants(spec.get("normal", [0, 0, 1]), path + ("normal",), 3)
    length = sum(builder.value(x) ** 2 for x in normal) ** 0.5
    if not length > 0:
        builder.fail(path + ("normal",), "the plane's normal is zero")
    return (normal / sp.sqrt(sum(x**2 for x in normal))).evalf()  # a number's root as a float, not an integer's


def _spheres_gap(builder, spec, path):
    """(gap, contact point, unit normal u) of a sphere or a capsule against a sphere or a
    capsule on another part: two spheres, |p_B − p_A| − r_A − r_B; a sphere of centre p
    against a capsule (``length: [L_A, L_B]``, > 0 for a capsule: its segment c ± (L/2) z
    along its frame's z), the distance from p to the segment (to its nearest point s,
    closed form) less both radii; two capsules, the distance between their segments (their
    nearest pair, model/segments.py) less both radii, written in symbols standing for their
    centres and axes (``through``: {symbol: value}, None for the others; gap_row). u
    points from the first's nearest point to the second's; the contact point is the first's
    surface there."""
    between = builder.sized_list(spec["between"], path + ("between",), 2)
    radii = builder.sized_list(spec["radius"], path + ("radius",), 2)
    lengths = builder.sized_list(spec.get("length", [0, 0]), path + ("length",), 2)
    (part_a, pose_a), (part_b, pose_b) = (_centre(builder, x, path + ("between", k))
                                          for k, x in enumerate(between))
    if part_a is part_b:
        builder.fail(path + ("between",), "the two spheres must be on two parts")
    r_a, r_b = (_radius(builder, r, path + ("radius", k)) for k, r in enumerate(radii))
    l_a, l_b = (_radius(builder, x, path + ("length", k), "length") for k, x in enumerate(lengths))
    p_a, p_b, through = pose_a[0], pose_b[0], {}
    z_a, z_b = sp.Matrix(pose_a[1])[:, 2], sp.Matrix(pose_b[1])[:, 2]
    if builder.value(l_a) > 0 and builder.value(l_b) > 0:
        # differentiated in the segments' centres and axes, then through them (gap_row)
        c_a, z_a, c_b, z_b = (_standing_for(x, through) for x in (p_a, z_a, p_b, z_b))
        distance, p_a, p_b = between_segments(c_a, z_a, l_a / 2, c_b, z_b, l_b / 2)
    elif builder.value(l_a) > 0:
        distance, p_a = to_segment(p_b, p_a, z_a, l_a / 2)
    elif builder.value(l_b) > 0:
        distance, p_b = to_segment(p_a, p_b, z_b, l_b / 2)
    else:
        distance = sp.sqrt((p_b - p_a).dot(p_b - p_a))
    unit = (p_b - p_a) / sp.sqrt((p_b - p_a).dot(p_b - p_a))
    put = Replacing(through)  # the nearest points share their subexpressions
    return distance - r_a - r_b, (p_a + r_a * unit).applyfunc(put), unit.applyfunc(put), through or None


def _standing_for(column, through):
    """A column of symbols standing for the entries of ``column``, recorded in ``through``
    (the same symbols in every contact: a gap alike is differentiated once, gap_row)."""
    symbols = sp.Matrix([placeholder(f"segments{len(through) + k}") for k in range(len(column))])
    through.update(zip(symbols, column))
    return symbols


def _centre(builder, text, path):
    """(part, (world position, rotation)) of the frame ``text`` on a part (not the world)."""
    part, frame = frame_reference(builder, text, path)
    if part is None:
        builder.fail(path, "a contact's sphere sits on a part, not on the world")
    return part, part.pose(frame)


def _radius(builder, text, path, what="radius"):
    radius = builder.constant(text, path)
    if builder.value(radius) < 0:
        builder.fail(path, f"a {what} is ≥ 0, got {builder.value(radius):g}")
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
