"""What the viewer draws, as numbers: nodes with a world transform per drawn time.

Each node carries shapes (the geometry dicts of ``io/parts.py``) at a fixed offset from
it. Its transform follows the part it sits on:

- rigid_body: [R(u), r] with R(u) of the quaternion coordinates, normalized;
- particle: [I, r]; planar_body: [Rz(θ), (x, y, 0)];
- a frame: the part's ``pose(frame)`` (a lagrangian part's frames are points given by
  expressions of its coordinates; its own geometry stays at the world origin).

Lines (``line:`` shapes between two frames of a part, spring parts, distance joints,
force elements that expose their two ``points``) are nodes whose transform maps the
unit segment (0, 0, 0)–(1, 0, 0) onto the segment between their ends: its first column
is p_B − p_A, so it scales. All poses are one compiled function of (t, q, p).
"""

from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from ..core.errors import ModelError
from ..io.parts import COLORS
from ..model.parts import Frame
from ..symbolic.derive import T_SYMBOL, compile_function

FPS = 30  # at most this many drawn states per second of motion
PALETTE = ("blue", "orange", "green", "red", "purple", "yellow")
LINE_COLOR = [0.35, 0.35, 0.35, 1.0]
ROD_COLOR = [0.1, 0.1, 0.1, 1.0]
POINT_LIKE = ("particle",)
BODIES = ("rigid_body", "planar_body")


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
    """The nodes, the times they are drawn at, and the box that holds the motion."""

    times: np.ndarray
    nodes: list
    lower: np.ndarray
    upper: np.ndarray

    @property
    def size(self):
        """A length for default sizes: the diagonal of the bounding box (1 if it is a point)."""
        return float(np.linalg.norm(self.upper - self.lower)) or 1.0


@dataclass
class _Spec:
    """A node before its poses are evaluated: ``pose`` indexes the pose list."""

    path: str
    pose: int
    shapes: list
    default: str = None  # the shape drawn when there is none: "sphere", "box" or "marker"
    color: list = None
    axes: bool = False


def build_scene(system, trajectory, axes=False, joints=False, fps=FPS):
    """The Scene of ``trajectory``, at most ``fps`` rows per second of motion.

    axes: a triad at every body and frame; joints: a marker at both frames of every joint.
    """
    if tuple(trajectory.coordinates) != tuple(system.coordinates):
        raise ModelError(f"the trajectory's coordinates ({', '.join(trajectory.coordinates)}) are not those "
                         f"of model '{system.name}' ({', '.join(system.coordinates)})")
    rows = drawn_rows(trajectory.t, fps)
    poses = _Poses()
    specs, lines = [], []
    model_drawn = any(_has_geometry(part) for part in system.parts)
    for i, part in enumerate(system.parts):
        color = [*COLORS[PALETTE[i % len(PALETTE)]], 1.0]
        specs += _part_specs(part, poses, color, axes, model_drawn)
        lines += _part_lines(part, poses)
    joint_lines, markers = _joint_items(system, poses, joints)
    specs = [s for s in specs + markers if s.shapes or s.default or s.axes]
    lines += joint_lines
    for element in system.forces:
        ends = getattr(element, "points", None)  # a force element between two points may expose them
        if ends is not None:
            lines.append((element.name, *(poses.add_point(p) for p in ends), LINE_COLOR))
    if not specs and not lines:
        raise ModelError(f"model '{system.name}' has nothing to draw: give its lagrangian parts frames "
                         "(positions in their coordinates) with geometry")
    transforms = poses.evaluate(system, trajectory.t[rows], trajectory.q[rows])
    positions = transforms[:, :, :3, 3]
    lower, upper = _bounds(specs, lines, transforms)
    scene = Scene(trajectory.t[rows], [], lower, upper)
    for spec in specs:
        scene.nodes.append(Node(spec.path, transforms[spec.pose], spec.shapes or _default_shapes(spec, scene.size),
                                spec.axes))
    for name, a, b, color in lines:
        scene.nodes.append(Node(f"lines/{name}", segment_transforms(positions[a], positions[b]),
                                [{"shape": "line", "size": [0.004 * scene.size], "color": color}]))
    return scene


def drawn_rows(t, fps=FPS):
    """Indices of the rows to draw: none closer than 1/fps to the previous, and the last."""
    if len(t) == 0:
        raise ValueError("the trajectory has no rows to draw")
    keep = [0]
    for i in range(1, len(t)):
        if t[i] - t[keep[-1]] >= (1 - 1e-9) / fps:
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
    T[:, :3, 0] = x * np.maximum(length, 1e-9)[:, None]
    T[:, :3, 1], T[:, :3, 2], T[:, :3, 3], T[:, 3, 3] = y, z, a, 1.0
    return T


def _bounds(specs, lines, transforms):
    """The box holding every drawn node and line end, and each shape's bounding sphere
    about its centre, over all rows."""
    points = [transforms[i][:, :3, 3] for line in lines for i in line[1:3]]
    for spec in specs:
        T = transforms[spec.pose]
        points.append(T[:, :3, 3])
        for shape in spec.shapes:
            centre = T[:, :3, :3] @ np.asarray(shape.get("position", [0, 0, 0]), dtype=float) + T[:, :3, 3]
            points += [centre - shape_radius(shape), centre + shape_radius(shape)]
    points = np.concatenate(points)
    return points.min(axis=0), points.max(axis=0)


def shape_radius(shape):
    """The radius of a sphere about the shape's centre that holds it (0 for meshes, whose
    size is not known here)."""
    size = np.asarray(shape.get("size", [0.0]), dtype=float)
    return {"box": lambda: np.linalg.norm(size) / 2, "sphere": lambda: size[0],
            "cylinder": lambda: np.hypot(size[0], size[1] / 2),
            "capsule": lambda: size[0] + size[1] / 2}.get(shape["shape"], lambda: 0.0)()


def _default_shapes(spec, size):
    """A small sphere for points, a smaller one for joint markers, a small box for bodies."""
    if spec.default == "sphere":
        return [{"shape": "sphere", "size": [0.02 * size], "color": spec.color}]
    if spec.default == "marker":
        return [{"shape": "sphere", "size": [0.012 * size], "color": spec.color}]
    if spec.default == "box":
        return [{"shape": "box", "size": [0.05 * size] * 3, "color": spec.color}]
    return []


def _joint_items(system, poses, markers):
    """Lines of the distance joints (massless rods) and, if ``markers``, a marker at both
    frames of every other joint."""
    lines, specs = [], []
    for con in system.connectors:
        if getattr(con, "joint_kind", None) is None:
            continue
        ends = [poses.add(part, frame) for part, frame in zip(con.parts, con.frames)]
        if con.joint_kind == "distance":
            lines.append((con.name, *ends, ROD_COLOR))
        elif markers:
            specs += [_Spec(f"joints/{con.name}.{end}", key, [], "marker", ROD_COLOR) for end, key in zip("AB", ends)]
    return lines, specs


def _has_geometry(part):
    return bool(part.geometry) or any(f.geometry for f in part.frames.values())


def _part_specs(part, poses, color, axes, model_drawn):
    """The node of the part's own pose and one per frame (line shapes apart). A part with
    no geometry gets a default: a sphere for a particle; for a body a box, or only its
    axes when the model draws other parts (a robot's frame-like links)."""
    drawn = _has_geometry(part)
    specs = []
    if part.kind != "spring":
        body = part.kind in BODIES and not drawn
        default = "sphere" if part.kind in POINT_LIKE and not drawn else "box" if body and not model_drawn else None
        origin = Frame(part.name, "origin", sp.zeros(3, 1), sp.eye(3))
        specs.append(_Spec(part.name, poses.add(part, origin), _solid(part.geometry), default, color,
                           (axes or (body and model_drawn)) and part.kind != "lagrangian"))
    for frame in part.frames.values():
        default = "sphere" if part.kind == "lagrangian" and not drawn else None
        specs.append(_Spec(f"{part.name}.{frame.name}", poses.add(part, frame), _solid(frame.geometry), default,
                           color, axes and part.kind != "spring"))
    return specs


def _part_lines(part, poses):
    """(name, pose A, pose B, colour) of the ``line:`` shapes on a part's frames; a spring
    part is the line between its ends."""
    if part.kind == "spring":
        return [(part.name, poses.add(part, part.frames["end1"]), poses.add(part, part.frames["end2"]), LINE_COLOR)]
    return [(f"{part.name}.{frame.name}-{shape['to']}", poses.add(part, frame), poses.add(part, part.frames[shape["to"]]),
             shape["color"]) for frame in part.frames.values() for shape in frame.geometry if shape["shape"] == "line"]


def _solid(shapes):
    return [s for s in shapes if s["shape"] != "line"]


class _Poses:
    """World poses (4 × 4, sympy) to evaluate along the motion in one compiled function."""

    def __init__(self):
        self.exprs, self.index = [], {}

    def add(self, part, frame):
        """The index of ``frame``'s pose on ``part`` (None: a frame fixed in the world)."""
        key = (part.name if part is not None else "world", frame.name)
        if key not in self.index:
            p, R = (sp.Matrix(frame.position), sp.Matrix(frame.rotation)) if part is None else part.pose(frame)
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
    """q with every rigid body's quaternion (its coordinates qw..qz) scaled to unit norm:
    R(u) of kinematics.rotation is a rotation only for a unit u."""
    q = np.array(q, dtype=float)
    start = 0
    for part in system.parts:
        if part.kind == "rigid_body":
            u = slice(start + 3, start + 7)
            q[u] /= np.linalg.norm(q[u])
        start += len(part.coordinates)
    return q
