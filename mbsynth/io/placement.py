"""Placing a substructure: one rigid transform (R, t) applied to the initial state of its
parts and to its world frames.

A model file used as a part (``type: model`` with ``placement:``) is written in its own
axes; placed, every pose in it becomes ``x ↦ R x + t`` and every velocity ``v ↦ R v``. The
coordinates of a rigid body (position, unit quaternion), a particle, a spring's ends, a
flexible body's floating frame and a planar body (a turn about z) transform linearly, so
expressions of parameters in their initial values stay expressions (``with_parameters``
follows them). A part given by its energies (``lagrangian``) has coordinates of its own
meaning and a body with angle coordinates a singular position a turn would move: neither
can be placed (translation alone is allowed for the body with angles). A rolling disk's
ground z = ground is the file's: raised by t_z, and not tilted (``place_height``).
"""

import numpy as np
import sympy as sp

from ..core.kinematics import matrix_quaternion
from ..core.tolerances import PLANE_RTOL, SIGN_TOL
from ..model.parts.part_type import ANGLES, PLANE, QUATERNION


class Placement:
    """A rigid transform: ``R`` (3 × 3 floats) and ``t`` (sympy 3-vector, expressions of
    the model's parameters); ``then(inner)`` is this transform after ``inner``."""

    def __init__(self, R=None, t=None):
        self.R = np.eye(3) if R is None else np.asarray(R, dtype=float)
        self.t = sp.zeros(3, 1) if t is None else sp.Matrix(t)
        self.turns = not np.array_equal(self.R, np.eye(3))
        self.identity = not self.turns and all(x == 0 for x in self.t)

    @property
    def tilts(self):
        """Whether the turn moves the z axis (a horizontal plane would not stay horizontal)."""
        return abs(self.R[2, 2] - 1) > PLANE_RTOL

    def then(self, inner):
        """The transform x ↦ self(inner(x))."""
        if inner.identity or self.identity:
            return self if inner.identity else inner
        return Placement(self.R @ inner.R, _rotated(self.R, inner.t) + self.t)

    def frame(self, position, rotation):
        """(position, rotation) of a world frame given in the placed axes."""
        if self.identity:
            return position, rotation
        return _rotated(self.R, position) + self.t, sp.Matrix(self.R) * rotation


def place_initial(part, values, placement, fail):
    """The initial ``values`` of ``part`` ({coordinate or coordinate_dot: number or sympy
    expression}, the part's own names) moved by ``placement``: a new dict holding every
    coordinate the transform sets. ``fail(message)`` raises for a part that cannot be placed."""
    if placement.identity:
        return dict(values)
    full = {c: sp.sympify(values.get(c, part.defaults.get(c, 0))) for c in part.coordinates}
    full.update({f"{c}_dot": sp.sympify(values.get(f"{c}_dot", 0)) for c in part.coordinates})
    kind = part.part_type
    moved = dict(full)
    for end in kind.points:
        _move_point(moved, full, end, placement)
    if kind.orientation == QUATERNION:
        turn = _quaternion_product(matrix_quaternion(placement.R))
        names = list(part.coordinates[kind.quaternion])
        for suffix in ("", "_dot"):
            moved.update(zip((n + suffix for n in names), turn * sp.Matrix([full[n + suffix] for n in names])))
        if not any(sp.sympify(moved[n]).free_symbols for n in names) and \
                quaternion_sign([float(moved[n]) for n in names]) < 0:
            moved.update({n: -moved[n] for n in names + [f"{n}_dot" for n in names]})
    elif kind.orientation == ANGLES and placement.turns:
        fail(f"part '{part.name}' has angle coordinates ({part.sequence}): a placement that turns it would move "
             "their singular position; give it rotation: quaternion, or place it by translation alone")
    elif kind.orientation == PLANE:
        _place_planar(part, moved, full, placement, fail)
    elif not kind.points:
        fail(f"part '{part.name}' is a {kind.name} part: its coordinates are its own, with no pose a placement "
             "could move; give its position through parameters, or include the file without placement")
    return {k: v for k, v in moved.items() if v != full[k] or k in values}


def place_height(placement, height, fail):
    """The world height of the horizontal plane z = ``height`` of a placed file (a rolling
    contact's ground): ``height`` + t_z. ``fail(message)`` raises for a placement that
    tilts the plane (a contact's ground is horizontal)."""
    if placement.tilts:
        fail("a rolling_disk rolls on the horizontal ground z = ground: the placement of the file that holds it "
             "may turn it about the vertical and shift it, not tilt it")
    return height + placement.t[2]


def _move_point(moved, full, names, placement):
    position = sp.Matrix([full[c] for c in names])
    velocity = sp.Matrix([full[f"{c}_dot"] for c in names])
    moved.update(zip(names, _rotated(placement.R, position) + placement.t))
    moved.update(zip((f"{c}_dot" for c in names), _rotated(placement.R, velocity)))


def _place_planar(part, moved, full, placement, fail):
    """A planar body moves in the xy plane: a turn about z and a shift within the plane."""
    R = placement.R
    if placement.tilts or placement.t[2] != 0:
        fail(f"part '{part.name}' is a planar body (it moves in the xy plane): its placement may only turn "
             "about z and shift within the plane")
    angle = float(np.arctan2(R[1, 0], R[0, 0]))
    R2 = sp.Matrix(R[:2, :2])
    moved.update(zip(("x", "y"), R2 * sp.Matrix([full["x"], full["y"]]) + placement.t[:2, 0]))
    moved.update(zip(("x_dot", "y_dot"), R2 * sp.Matrix([full["x_dot"], full["y_dot"]])))
    moved["theta"] = full["theta"] + angle


def quaternion_sign(u):
    """+1 or −1: the sign that makes the first of u's components (w, x, y, z) beyond SIGN_TOL
    positive. u and −u are one orientation; this picks one as every initial pose is read
    (parts.read_body_initial) and placed, w > 0 but at a half turn, where w is rounding and
    the sign of ``matrix_quaternion`` would be too: a pose written in a file and the same pose
    reached by a placement's turn get the same coordinates."""
    first = next(x for x in u if abs(x) > SIGN_TOL)
    return 1.0 if first > 0 else -1.0


def _rotated(R, v):
    """R v for numeric R and a sympy vector v, without sympy's exact arithmetic on R's floats
    where v is numeric too."""
    v = sp.Matrix(v)
    if not v.free_symbols:
        return sp.Matrix(R @ np.array(v, dtype=float).ravel())
    return sp.Matrix(R) * v


def _quaternion_product(u):
    """The 4 × 4 matrix L(u) with u ⊗ v = L(u) v (scalar-first quaternions)."""
    w, x, y, z = (float(c) for c in u)
    return sp.Matrix([[w, -x, -y, -z], [x, w, -z, y], [y, z, w, -x], [z, -y, x, w]])
