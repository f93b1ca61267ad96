"""``type: solid``: a rigid body whose mass and inertia come from its shape and a density.

    block:
      type: solid
      shape: {box: [0.4, 0.2, 0.1], color: blue}     # or sphere, cylinder, capsule, mesh (a closed .stl/.obj/.dae)
      density: 2700                                  # kg/m³
      frames: {tip: {position: [0.2, 0, 0]}}         # in the shape's axes

The shape is a ``geometry`` shape (schema section *geometry*, its ``origin`` included): the
volume V, centre of mass c and inertia per unit density J₁ about c are coal's
(``computeVolume``, ``computeCOM``, ``computeMomentofInertiaRelatedToCOM``: Pinocchio's
collision library, the same for primitives and closed triangle meshes). The part is a
RigidBody (model/parts/rigid_body.py) of mass ρV and inertia ρJ₁; its coordinates x, y, z
are its centre of mass, so its frames and its drawn shape, written in the entry's axes, are
moved by −c (a primitive at the origin has c = 0). The shape's numbers are built in at load
(``System.fixed_parameters``); the density stays a parameter expression.
"""

from dataclasses import replace

import numpy as np
import sympy as sp

from ..model.parts import RigidBody
from .parts import read_body_initial, read_frames, read_geometry, read_nonnegative
from .schema import SHARED_KEYS, Key, Section

SOLID = Section(
    "solid", "``parts: {NAME: {type: solid, ...}}``",
    "A rigid body (coordinates x, y, z of its centre of mass and the unit quaternion qw, qx, qy, qz) "
    "whose mass and inertia are its shape's volume and inertia (computed by coal) times its density. "
    "Frames and the shape are written in the entry's axes; for a shape whose centre of mass is not at "
    "their origin (a mesh, a shape with an ``origin``) they are moved so that the body's coordinates "
    "are its centre of mass. The viewer draws the shape.",
    (Key("type", "string", "``solid``: rigid body with the mass and inertia of its shape", "solid", required=True),
     Key("shape", "one shape (section *geometry*): box, sphere, cylinder, capsule or mesh",
         "the body's shape, drawn and weighed; a mesh must be closed", "{box: [0.4, 0.2, 0.1], color: blue}",
         required=True),
     Key("density", "expression of parameters, ≥ 0", "density [kg/m³]", "2700", required=True),
     SHARED_KEYS["frames"],
     Key("initial", "mapping (section *initial_rigid_body*)", "initial pose and velocities (``position``: of "
         "the centre of mass)", "{position: [0, 0, 1]}", default="at rest at the origin"),
     SHARED_KEYS["description"]))
SHAPES = ("box", "sphere", "cylinder", "capsule", "mesh")  # the shapes with a volume


def read_solid(builder, name, spec, path):
    builder.section(spec, path, "solid")
    where = path + ("shape",)
    if isinstance(spec["shape"], list):
        builder.fail(where, "a solid has one shape (a mapping), not a list")
    (shape,) = read_geometry(builder, spec["shape"], where)
    if shape["shape"] not in SHAPES:
        builder.fail(where, f"a solid's shape is one of {', '.join(SHAPES)}, not a {shape['shape']}")
    _built_in(builder, spec["shape"], where)
    volume, centre, inertia = _unit_density(builder, shape, where)
    density = read_nonnegative(builder, spec, "density", path)
    frames = read_frames(builder, name, spec.get("frames"), path + ("frames",), offsets=True)
    if np.any(centre):  # frames written in the entry's axes, placed from the centre of mass
        frames = [replace(f, position=sp.Matrix(f.position) - sp.Matrix(centre)) for f in frames]
    drawn = {**shape, "position": (np.asarray(shape["position"], dtype=float) - centre).tolist()}
    q, qd = builder.part_symbols(name, RigidBody.COORDINATES)
    initial = read_body_initial(builder, spec.get("initial"), path + ("initial",), planar=False)
    return RigidBody(name, q, qd, density * sp.Float(volume), density * sp.Matrix(inertia), builder.gravity,
                     builder.parameter_symbols, frames, (drawn,), initial)


def _unit_density(builder, shape, path):
    """(V, c, J₁) of ``shape`` (a read geometry dict) in the entry's axes: its volume, centre
    of mass and inertia about it at density 1, from coal, turned and moved by its ``origin``."""
    import coal  # Pinocchio's collision library: loaded where a model has a solid

    size = shape.get("size")
    kind = shape["shape"]
    if kind == "mesh":
        try:
            geometry = coal.MeshLoader().load(shape["file"], np.asarray(shape["scale"], dtype=float))
        except Exception as err:  # coal's loader raises its own error types
            builder.fail(path + ("mesh",), f"mesh {shape['file']!r} could not be read: {err}")
        if not _closed(geometry):
            builder.fail(path + ("mesh",), f"mesh {shape['file']!r} is not closed (an edge is not shared by exactly "
                                           "two faces, turned alike): it encloses no volume to weigh")
    else:
        geometry = {"box": coal.Box, "sphere": coal.Sphere, "cylinder": coal.Cylinder, "capsule": coal.Capsule}[kind](*size)
    volume = float(geometry.computeVolume())
    if not volume > 0:
        builder.fail(path, f"the {kind} encloses no volume ({volume:.3g} m³): a solid's mesh must have its faces "
                           "turned outward")
    R = np.asarray(shape["rotation"], dtype=float)
    centre = np.asarray(shape["position"], dtype=float) + R @ np.asarray(geometry.computeCOM(), dtype=float)
    inertia = R @ np.asarray(geometry.computeMomentofInertiaRelatedToCOM(), dtype=float) @ R.T
    return volume, centre, (inertia + inertia.T) / 2


def _closed(mesh):
    """Whether a triangle mesh (coal's BVHModel) is closed and oriented: each edge of a face is
    run the other way by exactly one other face."""
    edges = {}
    for i in range(mesh.num_tris):
        a, b, c = (mesh.tri_indices(i)[k] for k in range(3))
        for edge in ((a, b), (b, c), (c, a)):
            edges[edge] = edges.get(edge, 0) + 1
    return bool(edges) and all(count == 1 and edges.get((b, a)) == 1 for (a, b), count in edges.items())


def _built_in(builder, node, path):
    """Record the parameters the shape's numbers use as built in at load (its mass follows them)."""
    for key, value in node.items():
        if key in ("mesh", "color"):
            continue
        if isinstance(value, dict):
            _built_in(builder, value, path + (key,))
        else:
            for i, x in enumerate(value if isinstance(value, list) else [value]):
                builder.fixed_value(builder.constant(x, path + (key, i)), path + (key,))
