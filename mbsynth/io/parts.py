"""Reading three-dimensional parts, their frames, drawing geometry and initial states.

Each ``read_*`` takes the loader's builder (for error reporting, expressions and the
model's symbols), the part's name, its mapping and key path, and returns a Part.
"""

from pathlib import Path

import numpy as np
import sympy as sp

from ..core.kinematics import axis_matrix, matrix_quaternion, quaternion_matrix, rpy_matrix
from ..model.parts import EulerBody, Frame, LagrangianPart, Particle, PlanarBody, RigidBody, Spring
from ..model.parts.euler_body import SEQUENCES, angle_rates_of, angles_of, coordinates
from ..symbolic.derive import T_SYMBOL
from .placement import quaternion_sign
from ..core.tolerances import (DIVISION_GUARD, INERTIA_NEGATIVE_RTOL, INERTIA_SYMMETRY_RTOL, QUATERNION_NORM_TOL,
                               TRIANGLE_RTOL)
from .source import LineDict, LineList

ORIENTATION_KEYS = ("rpy", "axis", "quaternion")
SHAPES = {"box": 3, "sphere": 1, "cylinder": 2, "capsule": 2, "mesh": None, "line": None}
MESH_FORMATS = (".stl", ".obj", ".dae")
COLORS = {"red": (0.85, 0.2, 0.2), "green": (0.2, 0.7, 0.3), "blue": (0.2, 0.4, 0.85), "grey": (0.6, 0.6, 0.6),
          "gray": (0.6, 0.6, 0.6), "black": (0.1, 0.1, 0.1), "white": (0.95, 0.95, 0.95),
          "orange": (0.95, 0.55, 0.1), "yellow": (0.95, 0.85, 0.2), "purple": (0.55, 0.3, 0.75)}


def read_lagrangian(builder, name, spec, path):
    """A part given by its energies: ``coordinates``, T, V (of the coordinates, their rates ``c_dot``,
    the parameters and t), generalized ``forces`` and frames at expressions of its coordinates."""
    builder.section(spec, path, "lagrangian")
    coords = spec["coordinates"]
    if not isinstance(coords, LineList) or not coords:
        builder.fail(path + ("coordinates",), "expected a non-empty list of coordinate names")
    for i, c in enumerate(coords):
        builder.identifier(c, path + ("coordinates", i), "coordinate")
        if c.endswith("_dot"):
            builder.fail(path + ("coordinates", i), f"coordinate '{c}' must not end in '_dot' (that names velocities)")
        if c in builder.parameters:
            builder.fail(path + ("coordinates", i), f"coordinate '{c}' has the name of a parameter")
        if coords.index(c) != i:
            builder.fail(path + ("coordinates", i), f"coordinate '{c}' is listed twice")
    q, qd = builder.part_symbols(name, coords)
    symbols = dict(builder.param_symbols, t=T_SYMBOL)
    symbols.update(zip(coords, q))
    symbols.update(zip((f"{c}_dot" for c in coords), qd))
    T = builder.differentiable(builder.expression(spec["T"], path + ("T",), symbols), path + ("T",), qd)
    V = builder.differentiable(builder.expression(spec.get("V", 0), path + ("V",), symbols), path + ("V",), ())
    if V.free_symbols & set(qd):
        builder.fail(path + ("V",), "potential energy V must not depend on velocities")
    forces_node = builder.mapping(spec.get("forces", LineDict()), path + ("forces",), set(coords))
    forces = [builder.expression(forces_node[c], path + ("forces", c), symbols) if c in forces_node
              else sp.S.Zero for c in coords]
    frames = read_frames(builder, name, spec.get("frames"), path + ("frames",), True, symbols)
    return LagrangianPart(name, coords, q, qd, T, V, forces, builder.parameter_symbols, frames,
                          read_geometry(builder, spec.get("geometry"), path + ("geometry",)))


def read_rigid_body(builder, name, spec, path):
    builder.section(spec, path, "rigid_body")
    mass = read_mass(builder, spec, path)
    inertia = read_inertia(builder, spec["inertia"], path + ("inertia",))
    sequence = read_sequence(builder, spec, path)
    euler = sequence != "quaternion"
    q, qd = builder.part_symbols(name, coordinates(sequence) if euler else RigidBody.COORDINATES)
    frames = read_frames(builder, name, spec.get("frames"), path + ("frames",), offsets=True)
    initial = read_body_initial(builder, spec.get("initial"), path + ("initial",), planar=False,
                                sequence=sequence if euler else None)
    geometry = read_geometry(builder, spec.get("geometry"), path + ("geometry",))
    if euler:
        return EulerBody(name, sequence, q, qd, mass, inertia, builder.gravity, builder.parameter_symbols,
                         frames, geometry, initial)
    return RigidBody(name, q, qd, mass, inertia, builder.gravity, builder.parameter_symbols, frames,
                     geometry, initial)


def read_sequence(builder, spec, path):
    """``rotation:`` of a part turned in space: ``quaternion`` or an angle sequence (SEQUENCES)."""
    sequence = spec.get("rotation", "quaternion")
    if sequence != "quaternion" and sequence not in SEQUENCES:
        builder.fail(path + ("rotation",), f"rotation {sequence!r}: quaternion or one of {', '.join(SEQUENCES)}")
    return sequence


def read_particle(builder, name, spec, path):
    builder.section(spec, path, "particle")
    q, qd = builder.part_symbols(name, ("x", "y", "z"))
    frames = read_frames(builder, name, spec.get("frames"), path + ("frames",), offsets=False)
    initial = {}
    node = builder.section(spec.get("initial"), path + ("initial",), "initial_particle")
    for key, suffix in (("position", ""), ("velocity", "_dot")):
        if key in node:
            values = builder.initial_values(node[key], path + ("initial", key), 3)
            initial.update({f"{c}{suffix}": v for c, v in zip("xyz", values)})
    return Particle(name, q, qd, read_mass(builder, spec, path), builder.gravity, builder.parameter_symbols,
                    frames, read_geometry(builder, spec.get("geometry"), path + ("geometry",)), initial)


def read_planar_body(builder, name, spec, path):
    builder.section(spec, path, "planar_body")
    inertia = builder.constant(spec["inertia"], path + ("inertia",))
    if builder.value(inertia) < 0:
        builder.fail(path + ("inertia",), "the moment of inertia I_zz must be ≥ 0")
    q, qd = builder.part_symbols(name, ("x", "y", "theta"))
    frames = read_frames(builder, name, spec.get("frames"), path + ("frames",), offsets=True)
    initial = read_body_initial(builder, spec.get("initial"), path + ("initial",), planar=True)
    return PlanarBody(name, q, qd, read_mass(builder, spec, path), inertia, builder.gravity,
                      builder.parameter_symbols, frames,
                      read_geometry(builder, spec.get("geometry"), path + ("geometry",)), initial)


def read_spring(builder, name, spec, path):
    """A spring part: ends ``end1``, ``end2``; ``initial: {end1: [x, y, z], end2: ...,
    end1_velocity: ..., end2_velocity: ...}``."""
    builder.section(spec, path, "spring")
    stiffness, rest_length, damping, mass = (read_nonnegative(builder, spec, key, path, default=0)
                                             for key in ("stiffness", "rest_length", "damping", "mass"))
    q, qd = builder.part_symbols(name, Spring.COORDINATES)
    node = builder.section(spec.get("initial"), path + ("initial",), "initial_spring")
    initial = {}
    for key, values in node.items():
        end, _, velocity = key.partition("_")
        names = Spring.COORDINATES[:3] if end == "end1" else Spring.COORDINATES[3:]
        suffix = "_dot" if velocity else ""
        initial.update({c + suffix: v for c, v in zip(names, builder.initial_values(values, path + ("initial", key), 3))})
    return Spring(name, q, qd, stiffness, rest_length, damping, mass, builder.gravity,
                  builder.parameter_symbols, initial)


def read_mass(builder, spec, path):
    return read_nonnegative(builder, spec, "mass", path)


def read_nonnegative(builder, spec, key, path, default=None):
    """``spec[key]`` (or ``default`` when absent and not None): an expression of parameters ≥ 0."""
    if key not in spec and default is not None:
        return sp.sympify(default)
    value = builder.constant(spec[key], path + (key,))
    if builder.value(value) < 0:
        builder.fail(path + (key,), f"{key} must be ≥ 0, got {builder.value(value)}")
    return value


def read_inertia(builder, node, path):
    """Principal moments [Ixx, Iyy, Izz] or a full symmetric 3 × 3 matrix about the centre
    of mass; positive semi-definite and obeying the triangle inequality."""
    if isinstance(node, list) and len(node) == 3 and not any(isinstance(x, list) for x in node):
        J = sp.diag(*[builder.constant(x, path + (i,)) for i, x in enumerate(node)])
    elif isinstance(node, list) and len(node) == 3 and all(isinstance(r, list) and len(r) == 3 for r in node):
        J = sp.Matrix([[builder.constant(x, path + (i, j)) for j, x in enumerate(r)] for i, r in enumerate(node)])
    else:
        builder.fail(path, "inertia must be [Ixx, Iyy, Izz] or a 3 × 3 matrix [[...], [...], [...]]")
    values = np.array([[builder.value(x) for x in row] for row in J.tolist()])
    scale = max(np.abs(values).max(), DIVISION_GUARD)
    if np.abs(values - values.T).max() > INERTIA_SYMMETRY_RTOL * scale:
        builder.fail(path, "the inertia matrix is not symmetric")
    moments = np.linalg.eigvalsh(values)
    if moments.min() < -INERTIA_NEGATIVE_RTOL * scale:
        builder.fail(path, f"the inertia matrix is not positive semi-definite (principal moments {moments})")
    a, b, c = moments
    if a + b < c * (1 - TRIANGLE_RTOL) - INERTIA_NEGATIVE_RTOL * scale:
        builder.fail(path, f"principal moments {moments} violate the triangle inequality I1 + I2 ≥ I3: "
                           "no mass distribution has them")
    return J


def read_rotation(builder, node, path, fixed=True):
    """A numeric 3 × 3 rotation from ``rpy`` (URDF: Rz(yaw) Ry(pitch) Rx(roll)), ``axis``
    (z along the vector) or ``quaternion`` (w, x, y, z); identity when none is given.
    Its parameters are built in at load (``builder.numbers``; ``fixed`` False: a drawing's)."""
    given = [k for k in ORIENTATION_KEYS if k in node]
    if len(given) > 1:
        builder.fail(path, f"give at most one of {', '.join(ORIENTATION_KEYS)}, got {', '.join(given)}")
    if not given:
        return np.eye(3)
    key = given[0]
    values = builder.numbers(node[key], path + (key,), 4 if key == "quaternion" else 3, fixed)
    if key == "rpy":
        return rpy_matrix(*values)
    if np.linalg.norm(values) == 0:
        builder.fail(path + (key,), f"{key} must not be zero")
    if key == "axis":
        return axis_matrix(values)
    if abs(np.linalg.norm(values) - 1) > QUATERNION_NORM_TOL:
        builder.fail(path + (key,), f"quaternion {values} is not of unit norm (norm {np.linalg.norm(values):.6g})")
    return quaternion_matrix(values)


def read_frames(builder, part, node, path, offsets, symbols=None):
    """Named frames: ``position`` (expressions of parameters, or of ``symbols``) and an
    orientation."""
    frames = []
    node = builder.mapping(node, path, set(node) if isinstance(node, dict) else set())
    for name, spec in node.items():
        fpath = path + (name,)
        builder.identifier(name, fpath, "frame name")
        spec = builder.section(spec, fpath, "frame")
        position = (builder.vector(spec.get("position", [0, 0, 0]), fpath + ("position",), 3, symbols) if symbols
                    else builder.constants(spec.get("position", [0, 0, 0]), fpath + ("position",), 3))
        for i, x in enumerate(position):
            builder.differentiable(x, fpath + ("position", i))
        if not offsets and any(x != 0 for x in position):
            builder.fail(fpath + ("position",), "a particle is a point: its frames cannot be offset")
        rotation = sp.Matrix(read_rotation(builder, spec, fpath))
        frames.append(Frame(part, name, position, rotation,
                            read_geometry(builder, spec.get("geometry"), fpath + ("geometry",), set(node) - {name})))
    return frames


def read_body_initial(builder, node, path, planar, sequence=None):
    """Coordinate values from ``position``, an orientation (``theta`` when planar),
    ``velocity`` and ``angular_velocity`` (world axes); the angles of ``sequence`` and their
    rates for a body with angles (euler_body.py), else its quaternion and its rates."""
    node = builder.section(node, path, "initial_planar_body" if planar else "initial_rigid_body")
    size = 2 if planar else 3
    names = ("x", "y", "z")[:size]
    values = {}
    if "position" in node:
        values.update(zip(names, builder.initial_values(node["position"], path + ("position",), size)))
    if "velocity" in node:
        values.update(zip((c + "_dot" for c in names),
                          builder.initial_values(node["velocity"], path + ("velocity",), size)))
    if planar:
        if "theta" in node:
            values["theta"] = builder.initial_values([node["theta"]], path + ("theta",), 1)[0]
        if "angular_velocity" in node:
            values["theta_dot"] = builder.initial_values([node["angular_velocity"]], path + ("angular_velocity",), 1)[0]
        return values
    if sequence is not None:
        names = coordinates(sequence)[3:]
        angles = np.zeros(3)
        if any(k in node for k in ORIENTATION_KEYS):
            angles = angles_of(sequence, read_rotation(builder, node, path))
            values.update(zip(names, angles))
        if "angular_velocity" in node:
            omega = builder.numbers(node["angular_velocity"], path + ("angular_velocity",), 3)
            rates = angle_rates_of(sequence, angles, omega)
            if rates is None:
                builder.fail(path + ("angular_velocity",), f"the angles {sequence} are at their singular position "
                             f"here ({', '.join(f'{a:.6g}' for a in angles)} rad): no angle rates give this angular "
                             "velocity; turn the body's axes, or choose another rotation sequence")
            values.update(zip((c + "_dot" for c in names), rates))
        return values
    u = matrix_quaternion(read_rotation(builder, node, path))
    u = quaternion_sign(u) * u
    if any(k in node for k in ORIENTATION_KEYS):
        values.update(zip(("qw", "qx", "qy", "qz"), u))
    if "angular_velocity" not in node:
        return values
    omega = builder.numbers(node["angular_velocity"], path + ("angular_velocity",), 3)
    w, v = u[0], u[1:]
    G = np.column_stack([-v, w * np.eye(3) + np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])])
    values.update(zip(("qw_dot", "qx_dot", "qy_dot", "qz_dot"), G.T @ np.asarray(omega) / 2))  # ω = 2 G u̇
    return values


def read_geometry(builder, node, path, frames=()):
    """Drawing shapes: a mapping or a list of them, each with one of box [x, y, z],
    sphere r, cylinder [r, length] (along z), capsule [r, length], mesh: file (.stl, .obj
    or .dae, relative to the model file's folder; stored absolute; with ``scale``) or, on
    a frame, line: another of the part's ``frames`` (drawn between the two), and optional
    ``color`` (name or [r, g, b(, a)] in 0..1) and an ``origin`` pose."""
    if node is None:
        return ()
    items = node if isinstance(node, list) else [node]
    shapes = []
    for i, item in enumerate(items):
        ipath = path + (i,) if isinstance(node, list) else path
        item = builder.section(item, ipath, "geometry")
        kinds = [k for k in SHAPES if k in item]
        if len(kinds) != 1:
            builder.fail(ipath, f"a shape needs exactly one of {', '.join(SHAPES)}; got {kinds or 'none'}")
        kind = kinds[0]
        shape = {"shape": kind}
        if kind == "line":
            shape["to"] = read_line_end(builder, item, frames, ipath)
            shape["color"] = read_color(builder, item.get("color", "grey"), ipath + ("color",))
            shapes.append(shape)
            continue
        if kind == "mesh":
            shape["file"] = read_mesh_file(builder, item["mesh"], ipath + ("mesh",))
            shape["scale"] = builder.numbers(item.get("scale", [1, 1, 1]), ipath + ("scale",), 3, fixed=False)
        else:
            size = builder.numbers(item[kind] if isinstance(item[kind], list) else [item[kind]],
                                   ipath + (kind,), SHAPES[kind], fixed=False)
            if min(size) <= 0:
                builder.fail(ipath + (kind,), f"{kind} dimensions must be positive, got {size}")
            shape["size"] = size
        shape["color"] = read_color(builder, item.get("color", "grey"), ipath + ("color",))
        origin = builder.section(item.get("origin"), ipath + ("origin",), "pose")
        shape["position"] = builder.numbers(origin.get("position", [0, 0, 0]), ipath + ("origin", "position"), 3,
                                            fixed=False)
        shape["rotation"] = read_rotation(builder, origin, ipath + ("origin",), fixed=False).tolist()
        shapes.append(shape)
    return tuple(shapes)


def read_line_end(builder, item, frames, path):
    """The frame a ``line:`` shape runs to: another frame of the same part."""
    extra = set(item) - {"line", "color"}
    if extra:
        builder.fail(path + (sorted(extra)[0],), "a line takes only 'color'")
    if item["line"] not in frames:
        builder.fail(path + ("line",), f"a line runs from a frame to another frame of the same part "
                                       f"({', '.join(sorted(frames)) or 'none here'}), got {item['line']!r}")
    return item["line"]


def read_mesh_file(builder, text, path):
    """The absolute path of a mesh file named relative to the model's folder (``Document.folder``)."""
    if not isinstance(text, str) or not text:
        builder.fail(path, "mesh must be a file path")
    file = Path(text).expanduser()
    if not file.is_absolute():
        file = builder.doc.folder / file
    if file.suffix.lower() not in MESH_FORMATS:
        builder.fail(path, f"mesh {text!r}: the viewer reads {', '.join(MESH_FORMATS)} files")
    if not file.is_file():
        builder.fail(path, f"mesh file {text!r} not found (looked for {file})")
    return str(file.resolve())


def read_color(builder, node, path):
    if isinstance(node, str):
        if node not in COLORS:
            builder.fail(path, f"unknown colour '{node}'; known: {', '.join(COLORS)} or [r, g, b(, a)]")
        return [*COLORS[node], 1.0]
    if not isinstance(node, list) or len(node) not in (3, 4):
        builder.fail(path, "colour must be a name or [r, g, b] / [r, g, b, a] in 0..1")
    values = builder.numbers(node, path, len(node), fixed=False)
    if min(values) < 0 or max(values) > 1:
        builder.fail(path, f"colour components must lie in 0..1, got {values}")
    return values + [1.0] * (4 - len(values))
