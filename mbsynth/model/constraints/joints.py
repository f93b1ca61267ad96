"""Joints between two frames: holonomic constraints φ(q) = 0 on their world poses.

Frame A belongs to the parent (a part or the world), frame B to the child. With p the
frame origins and x, y, z their axes in the world:

    spherical    p_B − p_A = 0                                   3 rows
    revolute     spherical, and z_B ⟂ x_A, z_B ⟂ y_A             5 rows (turns about z)
    universal    spherical, and z_A ⟂ z_B                        4 rows (cross axes z_A, z_B)
    cylindrical  z_B ⟂ x_A, z_B ⟂ y_A, (p_B − p_A) ⟂ x_A, y_A     4 rows (turns and slides along z)
    prismatic    orientation locked, (p_B − p_A) ⟂ x_A, y_A      5 rows (slides along z)
    fixed        spherical, orientation locked                   6 rows
    distance     (|p_B − p_A|² − L²) / 2L = 0                    1 row  (a massless rod)

The orientation lock is x_A·y_B = y_A·z_B = z_A·x_B = 0: independent near aligned
frames, so assemble the frames aligned. It also holds with B turned 180° about an axis
of A, or 120° about a diagonal (x → y → z), and the axis rows z_B ⟂ x_A, y_A hold with
z_B = −z_A: poses the joint does not mean. ``Joint.wrong_branch`` tells them from the
meant one (frames turned less than 90° apart). Rows of A and b follow by differentiating φ
twice (symbolic.differentiate), exactly — once per kind of joint and types of parts
(``TEMPLATES``, joint_templates.py): φ is derived with the frames' offsets and rotations as
placeholder symbols and the parts' coordinates as slots, compiled once, and each joint
passes its frames' values and coordinates (Constraint._place); its sympy rows are built only
when asked. Joints on parts whose frames move with their coordinates, or with friction, are
derived directly. The rows of each kind are those of its record in core/joint_kinds.py.
"""

from typing import NamedTuple

import numpy as np
import sympy as sp

from .base import Constraint
from ...core.joint_kinds import ALIGNED_AXIS, JOINT_KINDS, KINDS, OPERATIONS, ORIENTATION_LOCK
from ...core.kinematics import euler_rotation, quaternion_rotation
from ..joint_templates import Templates, joint_coordinates, pose, shared
from ..joint_values import MOTION_NAMES, free_motions
from ..parts.part_type import ANGLES, PLANE, POINT, QUATERNION
from ...symbolic.cache import placeholder
from ...symbolic.derive import compile_function, differentiate, differentiated, jacobian, placed_values, positions

from ...core.memo import MEMO

def joint_equations(kind, pA, RA, pB, RB, length=None):
    """(φ rows, row labels) of a joint of ``kind`` between poses (pA, RA) and (pB, RB): the
    rows of its record in core/joint_kinds.py, on d = pB − pA and the axes of RA and RB, each
    its operation's φ (``OPERATIONS``)."""
    if kind not in JOINT_KINDS:
        raise ValueError(f"unknown joint kind {kind!r}; known: {', '.join(JOINT_KINDS)}")
    vectors = (pB - pA, RA[:, 0], RA[:, 1], RA[:, 2], RB[:, 0], RB[:, 1], RB[:, 2])
    phis = []
    for _, operation, first, second in KINDS[kind].rows:
        spec = OPERATIONS[operation]
        phis.append(spec.phi(vectors[first], second if spec.second == "component" else vectors[second], length))
    return phis, list(KINDS[kind].labels)


class Joint(Constraint):
    """A holonomic joint between frame A (on ``parent``, or the world when None) and
    frame B (on ``child``). Rows that vanish identically (a revolute joint between planar
    bodies has no z or axis rows) are left out. Besides its rows it knows, where it has them, its free
    motions: ``angle`` about z_A with rate ``angle_rate`` = z_A·(ω_B − ω_A) (revolute,
    cylindrical), and ``displacement`` z_A·(p_B − p_A) along z_A with its rate
    (prismatic, cylindrical), its joint values' formulas (joint_values.free_motions) — what
    actuation, joint springs and friction act on."""

    content_fields = ("joint_kind", "frames", "part_names", "report_frame", "length", "friction")

    def __init__(self, name, kind, parent, frame_a, child, frame_b, q, qd, params, length=None, friction=None,
                 report_frame=None):
        """``friction`` (a ``friction.Friction``) puts viscous friction into the joint's C
        (2.6) and keeps Coulomb friction, which needs the joint's load, in ``coulomb``.
        ``report_frame``: the frame on the child, with B's origin, in whose axes the
        joint's reaction is given (``System.reactions``); B itself by default."""
        self.joint_kind, self.frames, self.parts = kind, (frame_a, frame_b), (parent, child)
        self.report_frame = frame_b if report_frame is None else report_frame
        self.length = length  # a distance joint's L (sympy), None for the other kinds
        self.friction = friction
        values = TEMPLATES.constants((frame_a, frame_b), positions(q, qd))
        if friction is None and values is not None and shared(parent, child):
            self._place_shared(name, kind, parent, child, values, q, qd, params, length)
            return
        pA, RA = pose(parent, frame_a)
        pB, RB = pose(child, frame_b)
        phis, labels = joint_equations(kind, pA, RA, pB, RB, length)
        kept = [i for i, phi in enumerate(phis) if sp.sympify(phi) != 0]  # e.g. z rows of planar parts
        phis, labels = [phis[i] for i in kept], [labels[i] for i in kept]
        a, b, psi = differentiated(phis, q, qd)
        self._motions, self._motion_put = free_motions(kind, parent, child, (frame_a, frame_b), pA, RA, pB, RB, q,
                                                       qd), None
        C = sp.SparseMatrix(len(q), 1, {}) if friction is None else friction.viscous_force(self, qd)
        super().__init__(name, "holonomic", a, b, C, phis, psi, q, qd, params, labels)
        self.coulomb = None if friction is None else friction.coulomb_force(self, q, qd, params)

    def _place_shared(self, name, kind, parent, child, values, q, qd, params, length):
        """The rows from the template of joints alike (``TEMPLATES``), the frames' values
        and the coordinates of the two parts put in."""
        template = _Template._make(TEMPLATES(kind, parent, child, length is not None))
        constants = dict(values)
        if length is not None:
            constants[_LENGTH] = sp.sympify(length)
        kept = _kept_rows(template, constants)
        rows = tuple(tuple(x[i] for i in kept) for x in (template.a, template.b, template.phis, template.psi))
        where = positions(q, qd)
        coordinates = [where[s] for s in joint_coordinates(parent, child)[0]]
        self._motions, self._template = template.motions, template
        self._motion_put = (template.slots, coordinates, constants, q, qd)
        self.coulomb = None
        self._place(name, "holonomic", rows, template.slots, coordinates, list(constants.items()), q, qd, params,
                    [template.labels[i] for i in kept])

    part_names = property(lambda self: tuple(None if p is None else p.name for p in self.parts),
                          doc="the names of the parent (None: the world) and the child")

    def rate_gradient(self, rate):
        """∂rate/∂q̇ over the velocity slots of the joint's template (``placed``) of ``rate``
        ("angle_rate" or "displacement_rate"); None for a joint without a template or
        without that motion."""
        return None if self._motion_put is None else self._template.gradients[MOTION_NAMES.index(rate)]

    placed = property(lambda self: self._motion_put,
                      doc="(slots, coordinates, constants, q, q̇) of the joint's template, or None")

    def _motion(self, k):
        expr = self._motions[k]
        if expr is None or self._motion_put is None:
            return expr
        return expr.xreplace(placed_values(*self._motion_put))

    def wrong_branch(self, values):
        """A message when the frames, at ``values`` ({symbol: number} of the coordinates,
        parameters and time), meet the joint's orientation rows in a pose it does not
        mean — turned 90° or more from aligned (orientation lock), or z_B against z_A
        (axis rows) — else None."""
        kind = KINDS[self.joint_kind]
        if not (kind.holds(ORIENTATION_LOCK) or kind.holds(ALIGNED_AXIS)):
            return None
        RA, RB = (_rotation_at(part, frame, values) for part, frame in zip(self.parts, self.frames))
        if RA is None or RB is None:
            return None
        if kind.holds(ORIENTATION_LOCK):
            return _turned(self, RA.T @ RB)
        with np.errstate(all="ignore"):
            return _reversed(self, RA[:, 2] @ RB[:, 2] / np.linalg.norm(RB[:, 2]) / np.linalg.norm(RA[:, 2]))

    angle = property(lambda self: self._motion(0), doc="the turn about z_A (revolute, cylindrical), else None")
    angle_rate = property(lambda self: self._motion(1), doc="z_A·(ω_B − ω_A), else None")
    displacement = property(lambda self: self._motion(2), doc="z_A·(p_B − p_A) (prismatic, cylindrical), else None")
    displacement_rate = property(lambda self: self._motion(3), doc="its rate, else None")


_LENGTH = placeholder("joint_length")


def _numeric(matrix, values):
    """``matrix`` at ``values`` as floats, or None where that is no real number."""
    try:
        return np.array(sp.Matrix(matrix).xreplace(values), dtype=float)
    except TypeError:
        return None


def _rotation_at(part, frame, values):
    """The world rotation of ``frame`` (on ``part``, None: the world) at ``values`` as floats,
    or None where that is no real number. The shared part kinds are computed from their
    coordinates' values — R(u) R_frame in R(u)'s homogeneous form (kinematics.quaternion_rotation),
    R_z(θ) R_frame, R_frame — not by substitution into the pose's sympy matrices, which grows
    with the model (a robot of many links); so are rigid parts turned by three angles
    (R(angles) R_frame); other parts by substitution."""
    by_angles = part is not None and part.part_type.orientation == ANGLES and part.part_type.rigid
    if part is not None and not part.part_type.shared_pose and not by_angles:
        return _numeric(pose(part, frame)[1], values)
    own = frame.constant_rotation
    own = _numeric(frame.rotation, values) if own is None else own
    if own is None or part is None or part.part_type.orientation == POINT:
        return own
    if any(x not in values for x in part.q):
        return None
    if part.part_type.orientation == PLANE:
        theta = float(values[part.q[2]])
        c, s = np.cos(theta), np.sin(theta)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ own
    if part.part_type.orientation == QUATERNION:
        return quaternion_rotation([float(values[x]) for x in part.q[part.part_type.quaternion]]) @ own
    if by_angles:
        return np.array(euler_rotation(part.sequence, [sp.Float(values[x]) for x in part.q[3:6]]), dtype=float) @ own
    raise ValueError(f"a {part.type_name} part shares its poses but turns by {part.part_type.orientation}: no rotation "
                     "from its coordinates here")


def _turned(joint, relative):
    """The message for frames turned 90° or more apart (``relative`` = R_Aᵀ R_B), else None
    (also when ``relative`` is no turn at all: a zero quaternion, left to other checks)."""
    if not (np.all(np.isfinite(relative)) and np.linalg.det(relative) > 0):
        return None
    if np.trace(relative) * np.sqrt(3) > 1.5 * np.linalg.norm(relative):  # well below 90°: for a turn R scaled
        return None  # by s (unnormalized quaternions), tr = s (1 + 2 cos θ) and |sR| = s √3, so cos θ > 0.25
    from scipy.spatial.transform import Rotation  # scipy.spatial is imported only where used

    turn = Rotation.from_matrix(relative).as_rotvec()
    angle = np.degrees(np.linalg.norm(turn))
    if angle < 90:
        return None
    axis = ", ".join(f"{x:.3g}" for x in np.round(turn / np.linalg.norm(turn), 6) + 0.0)
    return (f"{joint.joint_kind} joint '{joint.name}': its frames are turned {angle:.3g}° about ({axis}) "
            "(parent frame axes) from the aligned pose it holds; its rows also hold turned 180° about an "
            f"axis or 120° about a diagonal, and would keep the wrong pose: fix the initial orientation of "
            f"{_named(joint.parts)}")


def _reversed(joint, cosine):
    """The message for a z_B against z_A (``cosine`` = z_A·z_B ≤ 0), else None."""
    if not cosine <= 0:  # NaN too (a zero axis)
        return None
    angle = np.degrees(np.arccos(np.clip(cosine, -1, 1)))
    return (f"{joint.joint_kind} joint '{joint.name}': its child's z axis points {angle:.3g}° away from its "
            f"parent's (z_A·z_B = {cosine:.3g}); its axis rows also hold with z_B = −z_A, and would keep the "
            f"wrong pose: fix the initial orientation of {_named(joint.parts)}")


def _named(parts):
    return " or ".join(f"'{p.name}'" for p in parts if p is not None)


def _kept_rows(template, constants):
    """The rows of ``template`` that do not vanish identically with the frames' values
    ``constants`` put in (planar parts have no z rows): a row nonzero at a random state is
    kept; one that is zero there is tested exactly (sympy, slow on big rows)."""
    if not all(sp.sympify(v).is_Number for v in constants.values()):
        return [i for i, phi in enumerate(template.phis) if phi.xreplace(constants) != 0]
    symbols = tuple(constants)
    values = _phi_function(template.phis, template.slots[0], symbols)(
        _PROBE[:len(template.slots[0])], np.array([float(constants[s]) for s in symbols]))[0].ravel()
    return [i for i, (phi, value) in enumerate(zip(template.phis, values))
            if value != 0 or phi.xreplace(constants) != 0]


_PROBE = np.random.default_rng(2006).uniform(0.1, 0.9, 64)  # the random state of _kept_rows


@MEMO.function(64)
def _phi_function(phis, slots, symbols):
    return compile_function((list(slots), list(symbols)), [sp.Matrix(phis)])


class _Template(NamedTuple):
    """A joint's rows in placeholder symbols: frames (``TEMPLATES.frames``), the distance
    (``_LENGTH``) and the two parts' coordinates (``slots``: parent's then child's)."""

    slots: tuple
    phis: tuple
    labels: tuple
    a: tuple      # per row, its entries over the slots' coordinates
    b: tuple
    psi: tuple
    motions: tuple    # joint_values.free_motions: angle, its rate, displacement, its rate (None: none)
    gradients: tuple  # per motion: ∂/∂q̇ over the velocity slots of a rate, else None


def _derive_template(kind, parent, child, at, has_length):
    """A ``_Template``'s fields, in ``at``'s slots and placeholder frames."""
    slots, to_slots = at.slots, at.to_slots
    pA, RA = pose(parent, at.frames[0])
    pB, RB = pose(child, at.frames[1])
    pA, RA, pB, RB = (x.xreplace(to_slots) for x in (pA, RA, pB, RB))
    phis, labels = joint_equations(kind, pA, RA, pB, RB, _LENGTH if has_length else None)
    phis = [sp.sympify(phi) for phi in phis]
    rows = [differentiate(phi, list(slots[0]), list(slots[1])) for phi in phis]
    motions = free_motions(kind, parent, child, at.frames[:2], pA, RA, pB, RB, list(slots[0]), list(slots[1]))
    motions = tuple(None if m is None else sp.sympify(m).xreplace(to_slots) for m in motions)
    gradients = tuple(None if m is None or k % 2 == 0 else tuple(jacobian([m], slots[1])) for k, m in enumerate(motions))
    return (slots, tuple(phis), tuple(labels), tuple(tuple(r[0]) for r in rows), tuple(r[1] for r in rows),
            tuple(r[2] for r in rows), motions, gradients)


# joints' rows in placeholder form, per kind, types of parts and whether it has a length
TEMPLATES = Templates("joint", "AB", _derive_template)
