"""Joint values: the relative coordinates of a joint's two frames, read off the parts' states.

Frame A is on the parent (or the world), frame B on the child; x, y, z their axes and
p their origins in the world, ω the parts' angular velocities. Per kind of joint:

    revolute     angle θ = atan2((x_A × x_B)·z_A, x_A·x_B)       rate z_A·(ω_B − ω_A)
    prismatic    displacement s = z_A·(p_B − p_A)                rate ṡ
    cylindrical  angle, displacement                             angle_rate, displacement_rate
    universal    angle1 = atan2(z_B·y_A, z_B·x_A) (about z_A),   rate1 = z_A·(ω_B − ω_A),
                 angle2 = atan2(−z_A·y_B, z_A·x_B) (about z_B)   rate2 = z_B·(ω_B − ω_A)
    spherical    rotation vector of R_Aᵀ R_B (rx, ry, rz)        R_Bᵀ(ω_B − ω_A) (wx, wy, wz)
    free         p_B, quaternion of R_B (x y z qw qx qy qz)      R_Bᵀ ṗ_B, R_Bᵀ ω_B (vx vy vz wx wy wz)

A joint's acceleration is the time derivative of its rates' components,
(∂w/∂q̇) q̈ + (∂w/∂q) q̇ + ∂w/∂t, compiled with the rates. These are Pinocchio's
conventions: a revolute joint's (q, v, v̇) are (θ, θ̇, θ̈); a free-flyer's v is the
spatial velocity in its own axes and v̇ its derivative, Rᵀp̈ − ω × Rᵀṗ (not the classical
acceleration); Pinocchio's quaternion is (x, y, z, w), mbsynth's (w, x, y, z). Angles
are atan2 in (−π, π] at one state; ``unwrap`` makes them continuous along a trajectory.
Fixed and distance joints have no values. The names per kind are those of its record in
core/joint_kinds.py, the formulas its entry of ``VALUES``, a table that must name every kind
(``NO_VALUES`` for one without values) and agree with its record, or this module is
refused at import. A joint's free motions, along which its actuation, spring and friction
act (constraints/joints.py), are its first values, from the same formulas (``free_motions``).

The same compiled function gives the pose of the joint's reaction frame (the child frame
B, or a robot's child link frame) and its Jacobian, which turn the generalized force a
joint exerts on its child into a wrench (``System.reactions``).
"""

from typing import NamedTuple

import numpy as np
import sympy as sp

from ..compiled.grouped import Batch
from ..core.joint_kinds import KINDS, check_table
from ..core.kinematics import matrix_quaternion
from .joint_templates import Templates, joint_coordinates, pose, shared
from ..symbolic.derive import T_SYMBOL, JointValue, compile_function, jacobian, time_derivative


class JointValues(NamedTuple):
    """One joint's ``position``, ``rate`` and ``acceleration`` (None without q̈), arrays
    with one entry per joint coordinate (``JointKinematics.names``)."""

    position: np.ndarray
    rate: np.ndarray
    acceleration: np.ndarray = None


class FramePose(NamedTuple):
    """The reaction frame's world ``origin`` and ``rotation`` (frame → world), and
    ``jacobian`` (6 × the child's coordinates): [ṗ; ω] = jacobian · q̇_child."""

    origin: np.ndarray
    rotation: np.ndarray
    jacobian: np.ndarray


class JointKinematics:
    """The compiled joint values of one joint of ``kind`` between ``frame_a`` on ``parent``
    (None: the world) and ``frame_b`` on ``child``, and the pose of ``report_frame`` (a
    frame on the child with B's origin: B itself, or a robot's link frame). Joints alike
    (kind, types of parts, frames fixed on them) share one derivation and one compiled
    function (``TEMPLATES``, joint_templates.py), their frames' values passed in, as
    constraints.joints does."""

    def __init__(self, name, kind, parent, frame_a, child, frame_b, report_frame, system):
        self.name, self.kind = name, kind
        record = KINDS[kind]
        self.position_names, self.rate_names = record.positions, record.rates
        self.acceleration_names, self.angles = record.accelerations, record.angles
        where = {s: i for i, s in enumerate(system.q_symbols)}
        q, qd = joint_coordinates(parent, child)
        self.indices = np.array([where[s] for s in q], dtype=int)
        self.child_indices = np.array([where[s] for s in child.q], dtype=int)
        args = (T_SYMBOL, list(q), list(qd), list(system.parameter_symbols))
        frames = (frame_a, frame_b, report_frame)
        constants = TEMPLATES.constants(frames, set(q))
        if shared(parent, child) and constants is not None:
            slots, exprs = TEMPLATES(kind, parent, child)
            constants = list(constants.items())
            self._evaluate = compile_function((T_SYMBOL, *slots, args[3]), exprs, constants=constants)
        else:
            self._evaluate = compile_function(args, _expressions(kind, parent, child, frames, q, qd))

    @property
    def names(self):
        """The names of its coordinates (``angle``, ``displacement``, ``rx`` …)."""
        return self.position_names

    def values(self, t, q, qd, qdd, p):
        """``JointValues`` at the model's state (q, q̇) and, when given, q̈."""
        i = self.indices
        scalars, rates, rate_a, rate_b, origin, _, RA, RB, _ = self._evaluate(t, q[i], qd[i], p)
        position = _positions(self.kind, scalars.ravel(), RA, RB, origin.ravel())  # free: report frame is B
        acceleration = None if qdd is None else rate_a @ qdd[i] - rate_b.ravel()
        return JointValues(position, rates.ravel(), acceleration)

    def frame(self, t, q, qd, p):
        """The ``FramePose`` of the reaction frame."""
        i = self.indices
        *_, pR, RR, _, _, J = self._evaluate(t, q[i], qd[i], p)
        return FramePose(pR.ravel(), RR, J)


class JointValuesBatch:
    """``JointKinematics.values`` of many joints at once: their compiled functions called a
    shared structure at a time (grouped.Batch), the outputs then split per joint."""

    SLOTS = 9  # the outputs of a JointKinematics' function (``_expressions``)

    def __init__(self, kinematics, compiled):
        self.kinematics = list(kinematics)
        self.batch = Batch([k._evaluate for k in self.kinematics], [k.indices for k in self.kinematics], self.SLOTS,
                           compiled)
        self.shapes = None  # per joint, where each output lies in its slot (``_layout``, at the first call)

    def __call__(self, t, q, qd, qdd, p):
        """{joint name: JointValues} at (t, q, q̇) and, when given, q̈."""
        if self.shapes is None:
            self.shapes = self._layout(t, q, qd, p)
        slots = self.batch(t, q, qd, p)
        found = {}
        for k, places in zip(self.kinematics, self.shapes):  # only the outputs the values read
            scalars, rates, rate_a, rate_b, origin, _, RA, RB, _ = places
            if KINDS[k.kind].matrix_positions:
                position = _positions(k.kind, None, slots[6][RA[0]].reshape(RA[1]), slots[7][RB[0]].reshape(RB[1]),
                                      slots[4][origin[0]])
            else:
                position = slots[0][scalars[0]].copy()
            acceleration = None if qdd is None else \
                slots[2][rate_a[0]].reshape(rate_a[1]) @ qdd[k.indices] - slots[3][rate_b[0]]
            found[k.name] = JointValues(position, slots[1][rates[0]].copy(), acceleration)
        return found

    def _layout(self, t, q, qd, p):
        """Per joint, per output: (slice, shape) in the batch's slot of that output."""
        starts, places = [0] * self.SLOTS, []
        for k in self.kinematics:
            outputs = k._evaluate(t, q[k.indices], qd[k.indices], p)
            place = []
            for j, x in enumerate(outputs):
                place.append((slice(starts[j], starts[j] + np.size(x)), np.shape(x)))
                starts[j] += np.size(x)
            places.append(place)
        return places


def _expressions(kind, parent, child, frames, q, qd):
    """What a JointKinematics compiles, in the parts' symbols q, q̇ (parent's then child's):
    scalar positions, rates, ∂rate/∂q̇, the rest of d(rate)/dt (``differentiate``'s b),
    the report frame's origin and rotation, R_A, R_B, and the report frame's Jacobian."""
    pA, RA = pose(parent, frames[0])
    pB, RB = child.pose(frames[1])
    positions, rates = _relative(kind, parent, child, frames, pA, RA, pB, RB, q, qd)
    rates = sp.Matrix(rates) if rates else sp.zeros(0, 1)
    rate_a = jacobian(rates, qd)
    rate_b = -(jacobian(rates, q) * sp.Matrix(qd)) - sp.diff(rates, T_SYMBOL) if rates else sp.zeros(0, 1)
    pR, RR = child.pose(frames[2])
    frame_rate = sp.Matrix.vstack(sp.Matrix([time_derivative(x, q, qd) for x in pR]),
                                  child.frame_angular_velocity(frames[2]))
    J = jacobian(frame_rate, list(child.qd))
    return [sp.Matrix(positions) if positions else sp.zeros(0, 1), rates, rate_a, rate_b, sp.Matrix(pR),
            sp.Matrix(RR), sp.Matrix(RA), sp.Matrix(RB), J]


def _derive_template(kind, parent, child, at):
    """((q slots, q̇ slots), ``_expressions`` in them and ``at``'s placeholder frames)."""
    return at.slots, [e.xreplace(at.to_slots) for e in _expressions(kind, parent, child, at.frames, at.q, at.qd)]


# what JointKinematics compiles, in placeholder form, per kind and types of parts
TEMPLATES = Templates("joint_value", "ABR", _derive_template)


def value_expressions(joint):
    """{name: sympy expression} of a joint's values that are expressions of the state (the
    names model files use as ``<joint>.<name>``): its positions except a spherical joint's
    rotation vector, and its rates."""
    kind = KINDS[joint.joint_kind]
    if not kind.rates:
        return {}
    if kind.motions:  # its values are the joint's own (shared) free motions: angle and/or displacement
        exprs = [getattr(joint, m) for m in kind.motions] + [getattr(joint, f"{m}_rate") for m in kind.motions]
        return dict(zip(kind.positions + kind.rates, exprs))
    parent, child = joint.parts
    q, qd = joint_coordinates(parent, child)
    pA, RA = pose(parent, joint.frames[0])
    pB, RB = child.pose(joint.frames[1])
    scalars, rate_exprs = _relative(kind.name, parent, child, joint.frames, pA, RA, pB, RB, q, qd)
    return dict(zip(kind.positions[:len(scalars)] + kind.rates, list(scalars) + list(rate_exprs)))


def value_names(joint):
    """The names of ``value_expressions`` (found without deriving them)."""
    kind = KINDS[joint.joint_kind]
    return list(kind.positions if not kind.matrix_positions else ()) + list(kind.rates)


def constraint_symbols(joint):
    """``value_expressions`` for constraints: each angle a ``symbolic.JointValue`` whose
    derivative is its rate, so that a constraint on it (a servo row ``angle − θ(t)``) is
    differentiated through the rate, not through the atan2 (exact on the manifold)."""
    exprs = value_expressions(joint)
    if not exprs:
        return exprs
    kind = KINDS[joint.joint_kind]
    for position, rate, is_angle in zip(kind.positions, kind.rates, kind.angles):
        if is_angle:
            exprs[position] = JointValue(f"{joint.name}.{position}", exprs[position], exprs[rate])
    return exprs


class _Frames(NamedTuple):
    """What a kind's value formulas read: the two frames' poses (pA, RA), (pB, RB) on
    ``parent`` (None: the world) and ``child``, the ``frames`` (A, B) and the coordinates."""

    parent: object
    child: object
    frames: tuple
    pA: sp.Matrix
    RA: sp.Matrix
    pB: sp.Matrix
    RB: sp.Matrix
    q: list
    qd: list

    def axis(self, end, k):
        return (self.RA, self.RB)[end][:, k]

    @property
    def omega(self):
        """ω_B − ω_A."""
        parent = self.parent
        omega_a = parent.frame_angular_velocity(self.frames[0]) if parent is not None else sp.zeros(3, 1)
        return self.child.frame_angular_velocity(self.frames[1]) - omega_a

    @property
    def angle(self):
        """The turn about z_A: atan2((x_A × x_B)·z_A, x_A·x_B)."""
        xa, xb, za = self.axis(0, 0), self.axis(1, 0), self.axis(0, 2)
        return sp.atan2(xa.cross(xb).dot(za), xa.dot(xb))

    @property
    def displacement(self):
        return self.axis(0, 2).dot(self.pB - self.pA)

    def rate_of(self, position):
        return time_derivative(position, self.q, self.qd)


def _turns(f):
    return [f.angle], [f.axis(0, 2).dot(f.omega)]


def _slides(f):
    return [f.displacement], [f.rate_of(f.displacement)]


def _turns_and_slides(f):
    (angle,), (angle_rate,) = _turns(f)
    (displacement,), (displacement_rate,) = _slides(f)
    return [angle, displacement], [angle_rate, displacement_rate]


def _crosses(f):
    xa, ya, za, xb, yb, zb = (f.axis(end, k) for end in range(2) for k in range(3))
    omega = f.omega
    return [sp.atan2(zb.dot(ya), zb.dot(xa)), sp.atan2(-za.dot(yb), za.dot(xb))], [za.dot(omega), zb.dot(omega)]


def _rotates(f):
    return [], list(f.RB.T * f.omega)


def _floats(f):
    velocity = sp.Matrix([f.rate_of(x) for x in f.pB])
    return [], list(f.RB.T * velocity) + list(f.RB.T * f.child.frame_angular_velocity(f.frames[1]))


def _rotation_vector(RA, RB, origin):
    from scipy.spatial.transform import Rotation  # scipy.spatial is imported only where used
    return Rotation.from_matrix(_orthonormal(RA.T @ RB)).as_rotvec()


def _pose(RA, RB, origin):
    return np.concatenate([origin, matrix_quaternion(RB)])


class KindValues(NamedTuple):
    """How a kind's joint values are computed: ``expressions`` (a ``_Frames``) -> (scalar
    position expressions, rate expressions), and for a kind whose record says
    ``matrix_positions``, ``from_matrices`` (R_A, R_B, p_B as floats) -> its positions."""

    expressions: object
    from_matrices: object = None


NO_VALUES = KindValues(None)  # a kind without joint values (its record names none)

VALUES = {  # per kind of core/joint_kinds.KINDS (module docstring)
    "fixed": NO_VALUES,
    "revolute": KindValues(_turns),
    "prismatic": KindValues(_slides),
    "cylindrical": KindValues(_turns_and_slides),
    "spherical": KindValues(_rotates, _rotation_vector),
    "universal": KindValues(_crosses),
    "distance": NO_VALUES,
    "free": KindValues(_floats, _pose),
}


def values_agree(record, values):
    """Whether ``values`` (a ``VALUES`` entry) are what ``record`` names: formulas exactly for
    a kind with joint values, positions from the matrices exactly for ``matrix_positions``,
    its free motions first among its positions (``free_motions`` reads them there)."""
    if (values.expressions is None) == bool(record.rates):
        return "joint values where the record names none, or none where it names some"
    if (values.from_matrices is None) == record.matrix_positions:
        return "positions from the frames' rotations exactly when the record says matrix_positions"
    if record.motions and (record.matrix_positions or record.positions[:len(record.motions)] != record.motions):
        return "its free motions as its first positions (compiled scalars), in the order of its motions"
    return None


check_table("model/joint_values.VALUES", VALUES, agrees=values_agree)


MOTION_NAMES = ("angle", "angle_rate", "displacement", "displacement_rate")  # what ``free_motions`` gives


def free_motions(kind, parent, child, frames, pA, RA, pB, RB, q, qd):
    """(angle, angle rate, displacement, displacement rate) of a joint of ``kind`` between
    ``frames`` (``MOTION_NAMES``; None where it has none): its joint values' formulas
    (``VALUES``) for the free motions of its record (``JointKind.motions``, its first
    positions and rates), which actuation, joint springs and friction act along."""
    found = dict.fromkeys(MOTION_NAMES)
    motions = KINDS[kind].motions
    if motions:
        positions, rates = _relative(kind, parent, child, frames, pA, RA, pB, RB, q, qd)
        for motion, position, rate in zip(motions, positions, rates):
            found[motion], found[f"{motion}_rate"] = position, rate
    return tuple(found.values())


def _relative(kind, parent, child, frames, pA, RA, pB, RB, q, qd):
    """(scalar position expressions, rate expressions) of a joint of ``kind`` between ``frames``
    (A, B) at (pA, RA), (pB, RB): its ``VALUES`` entry's, none for a kind without values."""
    expressions = VALUES[kind].expressions
    return ([], []) if expressions is None else expressions(_Frames(parent, child, frames, pA, RA, pB, RB, q, qd))


def _positions(kind, scalars, RA, RB, origin):
    """The position entries: compiled scalars, or from the frames' rotations (``VALUES``)."""
    from_matrices = VALUES[kind].from_matrices
    return scalars if from_matrices is None else from_matrices(RA, RB, origin)


def _orthonormal(R):
    """The rotation nearest R (R is exact on the constraint manifold; rounding off it)."""
    U, _, Vt = np.linalg.svd(R)
    return U @ Vt


def along(model_or_data, t, q, qd, qdd=None):
    """{joint name: JointValues of arrays (one row per time)} along a trajectory (arrays t,
    q, q̇ and optionally q̈, one row per time), with the angles made continuous (unwrapped):
    a joint turning past π keeps counting. Given a Data, at its parameter values."""
    rows = [model_or_data.joint_values(ti, qi, qdi, None if qdd is None else qdd[i])
            for i, (ti, qi, qdi) in enumerate(zip(t, q, qd))]
    kinematics = getattr(model_or_data, "model", model_or_data).joint_kinematics()
    out = {}
    for name in (rows[0] if rows else {}):
        position, rate, acceleration = (np.array([r[name][k] for r in rows]) if qdd is not None or k < 2 else None
                                        for k in range(3))
        out[name] = JointValues(_unwrapped(kinematics[name], position), rate, acceleration)
    return out


def _unwrapped(kinematics, positions):
    """``positions`` (T × k) of a joint with its angles made continuous."""
    positions = np.array(positions, dtype=float)
    for j, is_angle in enumerate(kinematics.angles):
        if is_angle:
            positions[:, j] = np.unwrap(positions[:, j])
    return positions
