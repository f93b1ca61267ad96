"""What the viewer draws, as numbers: nodes with a world transform per drawn time.

Each node carries shapes (the geometry dicts of ``io/parts.py``) at a fixed offset from
it. Its transform follows the part it sits on, the part's ``pose`` of the node's frame (a
part's own node: of its origin): [R(u), r] for a rigid body, R(u) of its quaternion
coordinates normalized (its type's ``quaternion``); [I, r] for a particle; [Rz(θ), (x, y,
0)] for a planar body; a lagrangian part's frames are points given by expressions of its
coordinates, its own geometry stays at the world origin. What a part without geometry is
drawn as is its type's ``drawing`` (model/parts/part_type.py).

Lines (``line:`` shapes between two frames of a part, spring parts, distance joints,
force elements that expose their two ``points``) are nodes whose transform maps the
unit segment (0, 0, 0)–(1, 0, 0) onto the segment between their ends: its first column
is p_B − p_A, so it scales. All poses are one compiled function of (t, q, p).

A flexible body (``flexible_body``) without geometry of its own is drawn as its deformed FE
mesh: a polyline through its nodes in their order (a beam's from end to end), node j at
R + A (x_j + s Φ_j η) with s the ``deformation_scale``. The scale multiplies the elastic
coordinates η wherever a flexible body's poses are drawn (its node frames and their
geometry too): a drawing only, so a scaled node no longer meets the parts joined to it.

A model that declares no geometry is drawn as its structure: a rolling disk as a wheel
of its radius about its frame's z axis, a body as rods from its centre of mass (a small
sphere) to its frames (its own and those its joints and contacts attach to), a particle
as a sphere whose radius grows as the cube root of its mass. Default sizes are fractions
of the model's own length (``Scene.length``: the largest extent of the drawn points at
one time), not of the box its motion fills, so a travelling model keeps its proportions.

A model made of model files (``System.substructures``) draws each top-level substructure
under a path of its own (``cell[0]/...``: meshcat shows and hides it as one), and the parts
of each in one colour of the palette, the next substructure in the next.

A run's contacts are drawn at their events: a point where each struck and an arrow of its
impulse (view/contacts.py), shown for a while after the event and at a vanishing scale
between.

The camera looks at ``Scene.targets``, one point per drawn time: the centre of mass
(mass-weighted over bodies and particles; the middle of the drawn points if nothing has
mass) when the view follows the model, else the middle of the box that holds the whole
motion.
"""

from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from ..core.errors import ModelError
from ..core.joint_kinds import KINDS
from .contacts import contact_items
from ..io.parts import COLORS
from ..model.constraints.rolling import KnifeEdge, RollingDisk
from ..model.parts import Frame
from ..model.parts.part_type import BODY, FE_MESH, FRAMES, LINE, SPHERE
from ..symbolic.derive import T_SYMBOL, compile_function
from ..core.tolerances import FRAME_SPACING_RTOL, SEGMENT_SCALE_FLOOR

FPS = 30  # at most this many drawn states per second of motion
PALETTE = ("blue", "orange", "green", "red", "purple", "yellow")
LINE_COLOR = [0.35, 0.35, 0.35, 1.0]
ROD_COLOR = [0.1, 0.1, 0.1, 1.0]
# default sizes, as fractions of the model's length (Scene.length)
LINE_RADIUS = 0.004  # springs, distance joints, line: shapes
ROD_RADIUS = 0.008  # a body's rods from its centre of mass to its frames
COM_RADIUS = 0.02  # the sphere at a body's centre of mass
PARTICLE_RADIUS = 0.05  # the heaviest particle; a lighter one by the cube root of its share
MASSLESS_RADIUS = 0.01  # a massless particle
WHEEL_WIDTH = 0.1  # a wheel's width, of its radius
WHEEL_OPACITY = 0.45  # a wheel lets the rods behind it show


@dataclass
class Node:
    """A drawn thing: ``transforms`` (rows × 4 × 4, world) and its ``shapes``; ``axes``
    asks for a triad at it."""

    path: str
    transforms: np.ndarray
    shapes: list = field(default_factory=list)
    axes: bool = False


@dataclass
class Scene:
    """The nodes, the times they are drawn at, the box that holds the motion (``lower``,
    ``upper``), the model's own length, and the camera's targets.

    ``targets`` (rows × 3): the world point at the middle of the view at each drawn time;
    ``follow``: whether they follow the model's centre of mass (else they all are the
    middle of ``lower``–``upper``); ``view_lower``, ``view_upper``: the box, relative to
    the target, that holds what is drawn at every time."""

    times: np.ndarray
    nodes: list
    lower: np.ndarray
    upper: np.ndarray
    length: float
    targets: np.ndarray
    follow: bool
    view_lower: np.ndarray
    view_upper: np.ndarray

    @property
    def size(self):
        """The diameter of the sphere about the target that holds the view box (the
        diagonal of the motion's box when the camera stays still; 1 if it is a point)."""
        reach = np.maximum(np.abs(self.view_lower), np.abs(self.view_upper))
        return 2 * float(np.linalg.norm(reach)) or 1.0


@dataclass
class _Spec:
    """A node before its poses are evaluated: ``pose`` indexes the pose list."""

    path: str
    pose: int
    shapes: list
    default: str = None  # the shape drawn when there is none: "sphere", "marker", "com" or "particle"
    color: list = None
    axes: bool = False
    mass: float = 0.0  # a particle's, for its default sphere


def build_scene(system, trajectory, axes=False, joints=False, fps=FPS, follow=None, deformation_scale=1.0):
    """The Scene of ``trajectory``, at most ``fps`` rows per second of motion.

    axes: a triad at every body and frame; joints: a marker at both frames of every joint;
    follow: the camera follows the centre of mass (True), stays on the box that holds the
    whole motion (False), or (None) follows when the centre of mass travels further than
    the model's length; deformation_scale: the factor on flexible bodies' elastic
    displacements in the drawing (module docstring).
    """
    if tuple(trajectory.coordinates) != tuple(system.coordinates):
        raise ModelError(f"the trajectory's coordinates ({', '.join(trajectory.coordinates)}) are not those "
                         f"of model '{system.name}' ({', '.join(system.coordinates)})")
    rows = drawn_rows(trajectory.t, fps)
    poses = _Poses(deformation_scale)
    specs, lines = [], []
    model_drawn = any(_has_geometry(part) for part in system.parts)
    masses = _masses(system, trajectory.q[rows[0]])
    groups = {substructure.name for substructure in system.substructures}
    colors = part_colors(system, groups)
    for part in system.parts:
        specs += _part_specs(part, poses, colors[part.name], axes, model_drawn, masses.get(part.name, 0.0))
        lines += _part_lines(part, poses) + _mesh_lines(part, poses, colors[part.name])
    if not model_drawn:
        wheels, rods = _structure(system, poses, colors)
        specs, lines = specs + wheels, lines + rods
    joint_lines, markers = _joint_items(system, poses, joints)
    specs = [s for s in specs + markers if s.shapes or s.default or s.axes]
    lines += joint_lines
    for element in system.forces:
        ends = getattr(element, "points", None)  # a force element between two points may expose them
        if ends is not None:
            lines.append((f"lines/{element.name}", *(poses.add_point(p) for p in ends), LINE_COLOR, LINE_RADIUS))
    if not specs and not lines:
        raise ModelError(f"model '{system.name}' has nothing to draw: give its lagrangian parts frames "
                         "(positions in their coordinates) with geometry")
    centre_poses = [(poses.add(part, ORIGIN), masses[part.name]) for part in system.parts if part.name in masses]
    transforms = poses.evaluate(system, trajectory.t[rows], trajectory.q[rows])
    positions = transforms[:, :, :3, 3]
    lows, highs = _instant_bounds(specs, lines, transforms)
    lower, upper = lows.min(axis=0), highs.max(axis=0)
    length = float(np.linalg.norm(highs - lows, axis=1).max()) or float(np.linalg.norm(upper - lower)) or 1.0
    centres = centre_of_mass(centre_poses, positions)
    if centres is None:
        centres = (lows + highs) / 2
    if follow is None:
        follow = bool(np.linalg.norm(centres.max(axis=0) - centres.min(axis=0)) > length)
    targets = centres if follow else np.tile((lower + upper) / 2, (len(rows), 1))
    scene = Scene(trajectory.t[rows], [], lower, upper, length, targets, bool(follow),
                  (lows - targets).min(axis=0), (highs - targets).max(axis=0))
    heaviest = max((s.mass for s in specs if s.default == "particle"), default=0.0)
    for spec in specs:
        scene.nodes.append(Node(grouped(spec.path, groups), transforms[spec.pose],
                                spec.shapes or _default_shapes(spec, length, heaviest), spec.axes))
    for path, a, b, color, radius in lines:
        scene.nodes.append(Node(grouped(path, groups), segment_transforms(positions[a], positions[b]),
                                [{"shape": "line", "size": [radius * length], "color": color}]))
    for item in contact_items(system, trajectory, scene.times, length):
        T = segment_transforms(item.start, item.end) if item.end is not None else _translations(item.start)
        T[~item.shown, :3, :3] *= SEGMENT_SCALE_FLOOR  # not drawn at this row
        scene.nodes.append(Node(item.path, T, item.shapes))
    return scene


def _translations(points):
    """(rows, 4, 4) transforms moving the origin to each of ``points``."""
    T = np.tile(np.eye(4), (len(points), 1, 1))
    T[:, :3, 3] = points
    return T


def group_of(name, groups):
    """The top-level substructure (one of ``groups``, the names of ``System.substructures``)
    whose prefix begins ``name`` (a part's, frame's, joint's or force's full name); None
    for a name of the including model's own."""
    head, dot, _ = name.partition(".")
    return head if dot and head in groups else None


def grouped(path, groups):
    """A node's path under its top-level substructure: ``cell[0]/cell[0].v``,
    ``cell[0]/structure/cell[0].v.top``; the path itself outside any."""
    group = group_of(path.rpartition("/")[2], groups)
    return path if group is None else f"{group}/{path}"


def part_colors(system, groups):
    """{part name: RGBA}: the PALETTE's colours in turn, one per top-level substructure
    (shared by all its parts) and one per part of the including model's own."""
    keys = {part.name: group_of(part.name, groups) or part.name for part in system.parts}
    turn = {key: i for i, key in enumerate(dict.fromkeys(keys.values()))}
    return {name: [*COLORS[PALETTE[turn[key] % len(PALETTE)]], 1.0] for name, key in keys.items()}


def centre_of_mass(weighted, positions):
    """(rows × 3) Σ mᵢ rᵢ / Σ mᵢ of (pose index, mass) pairs at ``positions`` (poses ×
    rows × 3); None when they have no mass."""
    total = sum(m for _, m in weighted)
    if total <= 0:
        return None
    return sum(m * positions[i] for i, m in weighted) / total


def drawn_rows(t, fps=FPS):
    """Indices of the rows to draw: none closer than 1/fps to the previous, and the last."""
    if len(t) == 0:
        raise ValueError("the trajectory has no rows to draw")
    keep = [0]
    for i in range(1, len(t)):
        if t[i] - t[keep[-1]] >= (1 - FRAME_SPACING_RTOL) / fps:
            keep.append(i)
    if keep[-1] != len(t) - 1:
        keep.append(len(t) - 1)
    return np.array(keep)


def segment_transforms(a, b):
    """(rows, 4, 4) transforms mapping (0, 0, 0) to a and (1, 0, 0) to b, rotation and
    a scale along x only (a zero-length segment gets a vanishing scale)."""
    d = b - a
    length = np.linalg.norm(d, axis=1)
    x = np.where(length[:, None] > 0, d / np.where(length > 0, length, 1)[:, None], [1.0, 0.0, 0.0])
    helper = np.where(np.abs(x[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    y = np.cross(x, helper)
    y /= np.linalg.norm(y, axis=1)[:, None]
    z = np.cross(x, y)
    T = np.zeros((len(a), 4, 4))
    T[:, :3, 0] = x * np.maximum(length, SEGMENT_SCALE_FLOOR)[:, None]
    T[:, :3, 1], T[:, :3, 2], T[:, :3, 3], T[:, 3, 3] = y, z, a, 1.0
    return T


def _instant_bounds(specs, lines, transforms):
    """(lows, highs), rows × 3: at each row, the box holding every drawn node and line end
    and each given shape's bounding sphere about its centre."""
    points = [transforms[i][:, :3, 3] for line in lines for i in line[1:3]]
    for spec in specs:
        T = transforms[spec.pose]
        points.append(T[:, :3, 3])
        for shape in spec.shapes:
            centre = T[:, :3, :3] @ np.asarray(shape.get("position", [0, 0, 0]), dtype=float) + T[:, :3, 3]
            points += [centre - shape_radius(shape), centre + shape_radius(shape)]
    points = np.stack(points)
    return points.min(axis=0), points.max(axis=0)


def shape_radius(shape):
    """The radius of a sphere about the shape's centre that holds it (0 for meshes, whose
    size is not known here)."""
    size = np.asarray(shape.get("size", [0.0]), dtype=float)
    return {"box": lambda: np.linalg.norm(size) / 2, "sphere": lambda: size[0],
            "cylinder": lambda: np.hypot(size[0], size[1] / 2),
            "capsule": lambda: size[0] + size[1] / 2}.get(shape["shape"], lambda: 0.0)()


def _default_shapes(spec, length, heaviest):
    """A small sphere for points, a smaller one for joint markers, a dark one at a body's
    centre of mass, and for a particle a sphere whose radius is PARTICLE_RADIUS ×
    (m / heaviest)^(1/3) of the model's length (at least MASSLESS_RADIUS)."""
    if spec.default == "particle":
        share = np.cbrt(spec.mass / heaviest) if heaviest > 0 else 0.0
        return [{"shape": "sphere", "size": [max(PARTICLE_RADIUS * share, MASSLESS_RADIUS) * length],
                 "color": spec.color}]
    radius = {"sphere": 0.02, "marker": 0.012, "com": COM_RADIUS}.get(spec.default)
    if radius is None:
        return []
    return [{"shape": "sphere", "size": [radius * length], "color": ROD_COLOR if spec.default == "com" else spec.color}]


def _joint_items(system, poses, markers):
    """Lines of the distance joints (massless rods) and, if ``markers``, a marker at both
    frames of every other joint."""
    lines, specs = [], []
    for con in system.constraints:
        if getattr(con, "joint_kind", None) is None:
            continue
        ends = [poses.add(part, frame) for part, frame in zip(con.parts, con.frames)]
        if KINDS[con.joint_kind].has_length:  # a massless rod
            lines.append((f"lines/{con.name}", *ends, ROD_COLOR, LINE_RADIUS))
        elif markers:
            specs += [_Spec(f"joints/{con.name}.{end}", key, [], "marker", ROD_COLOR) for end, key in zip("AB", ends)]
    return lines, specs


def _has_geometry(part):
    return bool(part.geometry) or any(f.geometry for f in part.frames.values())


def _part_specs(part, poses, color, axes, model_drawn, mass):
    """The node of the part's own pose and one per frame (line shapes apart). A part with
    no geometry gets a default: a sphere sized by its ``mass`` for a particle; for a body
    the sphere at its centre of mass (``_structure`` adds its rods), or only its axes when
    the model draws other parts (a robot's frame-like links)."""
    drawn, drawing = _has_geometry(part), part.part_type.drawing
    specs = []
    if drawing != LINE:
        body = drawing == BODY and not drawn
        default = "particle" if drawing == SPHERE and not drawn else "com" if body and not model_drawn else None
        specs.append(_Spec(part.name, poses.add(part, ORIGIN), _solid(part.geometry), default, color,
                           (axes or (body and model_drawn)) and drawing != FRAMES, mass))
    for frame in part.frames.values():
        default = "sphere" if drawing == FRAMES and not drawn else None
        specs.append(_Spec(f"{part.name}.{frame.name}", poses.add(part, frame), _solid(frame.geometry), default,
                           color, axes and drawing != LINE))
    return specs


def _part_lines(part, poses):
    """(path, pose A, pose B, colour, radius) of the ``line:`` shapes on a part's frames; a
    spring part is the line between its ends."""
    if part.part_type.drawing == LINE:
        return [(f"lines/{part.name}", poses.add(part, part.frames["end1"]), poses.add(part, part.frames["end2"]),
                 LINE_COLOR, LINE_RADIUS)]
    return [(f"lines/{part.name}.{frame.name}-{shape['to']}", poses.add(part, frame),
             poses.add(part, part.frames[shape["to"]]), shape["color"], LINE_RADIUS)
            for frame in part.frames.values() for shape in frame.geometry if shape["shape"] == "line"]


def _mesh_lines(part, poses, color):
    """(path, pose A, pose B, colour, radius) of the segments between consecutive FE nodes of a
    flexible body without geometry of its own, at ``mesh/<part>.<j>``."""
    if part.part_type.drawing != FE_MESH or part.geometry:
        return []
    reduction = part.reduction
    eta = sp.Matrix(part.q[part.elastic])
    ends = []
    for j, place in enumerate(reduction.fe.nodes):
        shift = sp.Matrix(reduction.basis[reduction.node_rows(j)[:3]].tolist()) * eta
        ends.append(poses.add(part, Frame(part.name, f"<FE node {j}>", sp.Matrix(place) + shift, sp.eye(3))))
    return [(f"mesh/{part.name}.{j}", a, b, color, LINE_RADIUS) for j, (a, b) in enumerate(zip(ends, ends[1:]))]


def _structure(system, poses, colors):
    """(wheel specs, rod lines) of a model that declares no geometry: each rolling disk a
    wheel at ``wheels/<contact>`` (a see-through disk of its radius and WHEEL_WIDTH about
    its frame's z axis, with a dark spoke along its x axis that shows the spin); each
    body's rods at ``structure/<part>.<frame>``, from its centre of mass to each of its
    frames away from it, its own and those its joints and contacts attach to."""
    values = dict(zip(system.parameter_symbols, system.parameter_values))
    attached, wheels = {}, []
    for con in system.constraints:
        if getattr(con, "joint_kind", None) is not None:
            ends = zip(con.parts, con.frames)
        elif isinstance(con, (RollingDisk, KnifeEdge)):
            ends = [(con.part, con.frame)]
        else:
            continue
        for part, frame in ends:
            if part is not None:
                attached.setdefault(part.name, {})[frame.name] = frame
        if isinstance(con, RollingDisk):
            R = float(sp.sympify(con.radius).xreplace(values))
            wheels.append(_Spec(f"wheels/{con.name}", poses.add(con.part, con.frame),
                                [{"shape": "cylinder", "size": [R, WHEEL_WIDTH * R],
                                  "color": [*colors[con.part.name][:3], WHEEL_OPACITY]},
                                 {"shape": "box", "size": [2 * R, 0.15 * R, 1.2 * WHEEL_WIDTH * R], "color": ROD_COLOR}]))
    rods = []
    for part in system.parts:
        if part.part_type.drawing != BODY:
            continue
        centre = poses.add(part, ORIGIN)
        for frame in {**part.frames, **attached.get(part.name, {})}.values():
            if sp.Matrix(frame.position).is_zero_matrix is not True:
                rods.append((f"structure/{part.name}.{frame.name}", centre, poses.add(part, frame),
                             colors[part.name], ROD_RADIUS))
    return wheels, rods


def _masses(system, q):
    """{part name: mass} of the bodies and particles (M's first diagonal entry, at ``q``)."""
    p, masses, start = system.parameter_values, {}, 0
    for part in system.parts:
        n = len(part.coordinates)
        if part.part_type.drawing in (BODY, SPHERE):
            M, _ = part.evaluate(0.0, q[start:start + n], np.zeros(n), p)
            masses[part.name] = float(M[0, 0])
        start += n
    return masses


def _solid(shapes):
    return [s for s in shapes if s["shape"] != "line"]


ORIGIN = Frame("", "origin", sp.zeros(3, 1), sp.eye(3))  # a part's own pose (pose keys are by frame name)


class _Poses:
    """World poses (4 × 4, sympy) to evaluate along the motion in one compiled function; a
    flexible body's with its elastic coordinates times ``deformation_scale``."""

    def __init__(self, deformation_scale=1.0):
        self.exprs, self.index = [], {}
        self.scale = deformation_scale

    def add(self, part, frame):
        """The index of ``frame``'s pose on ``part`` (None: a frame fixed in the world)."""
        key = (part.name if part is not None else "world", frame.name)
        if key not in self.index:
            p, R = (sp.Matrix(frame.position), sp.Matrix(frame.rotation)) if part is None else part.pose(frame)
            if part is not None and part.part_type.elastic and self.scale != 1:
                scaled = {x: self.scale * x for x in part.q[part.elastic]}
                p, R = p.xreplace(scaled), R.xreplace(scaled)
            self.index[key] = self._append(p, R)
        return self.index[key]

    def add_point(self, position):
        return self._append(sp.Matrix(position), sp.eye(3))

    def _append(self, p, R):
        self.exprs.append(sp.Matrix.vstack(sp.Matrix.hstack(sp.Matrix(R), sp.Matrix(p)), sp.Matrix([[0, 0, 0, 1]])))
        return len(self.exprs) - 1

    def evaluate(self, system, times, q):
        """(poses, rows, 4, 4) at each (t, q), every rigid body's quaternion normalized."""
        f = compile_function((T_SYMBOL, list(system.q_symbols), system.parameter_symbols), self.exprs)
        p = system.parameter_values
        out = np.empty((len(times), len(self.exprs), 4, 4))
        for row, (t, q_row) in enumerate(zip(times, q)):
            out[row] = f(t, normalized_quaternions(system, q_row), p)
        return out.transpose(1, 0, 2, 3)


def normalized_quaternions(system, q):
    """q with every part's quaternion (its type's ``quaternion`` coordinates) scaled to unit
    norm: R(u) of kinematics.rotation is a rotation only for a unit u."""
    q = np.array(q, dtype=float)
    start = 0
    for part in system.parts:
        u = part.part_type.quaternion
        if u is not None:
            q[start + u.start:start + u.stop] /= np.linalg.norm(q[start + u.start:start + u.stop])
        start += len(part.coordinates)
    return q
