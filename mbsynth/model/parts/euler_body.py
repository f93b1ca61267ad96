"""A rigid body in 6 coordinates: its centre of mass r in the world and three angles of
an intrinsic sequence (``rotation: zxy`` in a model file; Tait–Bryan with three different
axes, or proper Euler such as zxz).

The choice for bodies that spin: with the spin axis last in the sequence, the spin angle
is a coordinate that nothing in an axisymmetric body's M and Q, nor in a joint or a
rolling contact on its axis, depends on (it is cyclic), so a steady motion is a state
whose other coordinates stay still (analysis/linearization.py). The price: the angles
are singular where H below loses rank: the middle turn at ±90° (Tait–Bryan) or at 0 and
180° (proper Euler: zxz for a disk whose axis is its z axis, singular only when it lies
flat)."""

import warnings

import numpy as np
import sympy as sp

from ...core.kinematics import euler_rate_matrix, euler_rotation
from ...core.tolerances import NEAR_SINGULAR
from ...symbolic.cache import placeholder, remembered
from .base import Part
from ...core.memo import MEMO
from .part_type import ANGLES, BODY, EXTRA_NODE, PartType, check

SEQUENCES = ("xyz", "xzy", "yxz", "yzx", "zxy", "zyx",  # Tait–Bryan: three different axes
             "xyx", "xzx", "yxy", "yzy", "zxz", "zyz")  # proper Euler: the first axis again last


class EulerBody(Part):
    """M = blockdiag(m I₃, HᵀJH), Q = [m g;  −Hᵀ(J Ḣ α̇ + ω × J ω)] with ω = H(α) α̇ the
    body-axes angular velocity (``euler_rate_matrix``): Euler's equations J ω̇ + ω × Jω = τ
    premultiplied by Hᵀ, as virtual turns are H δα. M is regular away from the angles'
    singular position; the body adds no constraint of its own."""

    content_fields = ("sequence", "mass", "inertia", "gravity")

    part_type = check(PartType("euler_body", node=EXTRA_NODE, orientation=ANGLES, quaternion=None,
                               points=(("x", "y", "z"),), elastic=False, body_rates=False, origin=True,
                               shared_pose=False, drawing=BODY))
    groups = (("x", "y", "z"),)

    def __init__(self, name, sequence, q, qd, mass, inertia, gravity, params, frames=(), geometry=(),
                 initial=None):
        if sequence not in SEQUENCES:
            raise ValueError(f"rotation sequence {sequence!r}: one of {', '.join(SEQUENCES)}")
        self.sequence = sequence
        slots, placeholders, (M, Q, T, V) = _template(sequence)
        J = sp.Matrix(inertia)
        self.mass, self.inertia, self.gravity = mass, J, sp.Matrix(gravity)
        constants = list(zip(placeholders, [mass, *J, *self.gravity]))
        super().__init__(name, coordinates(sequence), q, qd, M, Q, T, V, params, frames, geometry, initial,
                         shared=(*slots, constants))

    def pose(self, frame):
        R = euler_rotation(self.sequence, self.q[3:])
        return sp.Matrix(self.q[:3]) + R * frame.position, R * frame.rotation

    def angular_velocity(self):
        return euler_rotation(self.sequence, self.q[3:]) * euler_rate_matrix(self.sequence, self.q[3:]) \
            * sp.Matrix(self.qd[3:])

    def singular_direction(self, angles):
        """The unit null vector of H at the numeric ``angles`` (over the three angles): the
        angle rates that turn the body not at all at the singular position."""
        H = np.array(euler_rate_matrix(self.sequence, [float(a) for a in angles]), dtype=float)
        return np.linalg.svd(H)[2][-1]


def coordinates(sequence):
    """The coordinate names: x, y, z and ``angle_<axis>`` for each turn of ``sequence``
    (``angle_<axis>2`` for the second turn about the same axis)."""
    return ("x", "y", "z", *(f"angle_{axis}{'2' if axis in sequence[:i] else ''}" for i, axis in enumerate(sequence)))


def proper_euler(sequence):
    """Whether ``sequence`` turns about its first axis again last (zxz), not Tait–Bryan."""
    return sequence[0] == sequence[2]


def singular_values_text(sequence):
    """Where the middle angle of ``sequence`` is singular, in words."""
    return "0 and ±π" if proper_euler(sequence) else "±π/2"


def angles_of(sequence, R):
    """The angles of ``sequence`` whose rotation is the numeric matrix R (the middle turn in
    [−90°, 90°] for Tait–Bryan, [0, 180°] for proper Euler; at the singular position the
    last angle is 0)."""
    from scipy.spatial.transform import Rotation  # at load time only: building a robot imports no scipy
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # scipy's "gimbal lock": the last angle is set to 0
        return Rotation.from_matrix(np.asarray(R, dtype=float)).as_euler(sequence.upper())


def angle_rates_of(sequence, angles, omega_world):
    """α̇ of the world angular velocity ``omega_world`` at ``angles``: H(α)⁻¹ Rᵀ ω; None at
    the angles' singular position (H singular: not every ω has angle rates)."""
    a = sp.symbols("a0:3")
    values = dict(zip(a, angles))
    R = np.array(euler_rotation(sequence, a).subs(values), dtype=float)
    H = np.array(euler_rate_matrix(sequence, a).subs(values), dtype=float)
    singular = np.linalg.svd(H, compute_uv=False)
    if singular[-1] < NEAR_SINGULAR * singular[0]:
        return None
    return np.linalg.solve(H, R.T @ np.asarray(omega_world, dtype=float))


@MEMO.function(len(SEQUENCES))
def _template(sequence):
    """(coordinate slots, placeholders (m, J row by row, g), (M, Q, T, V)) of a body whose
    angles follow ``sequence``, derived once (base.Part's ``shared``)."""
    return remembered("euler-body", (sequence,), lambda: _derive_template(sequence))


def _derive_template(sequence):
    names = coordinates(sequence)
    q, qd = [placeholder(f"euler_{c}") for c in names], [placeholder(f"euler_{c}_dot") for c in names]
    mass, gravity = placeholder("euler_m"), sp.Matrix([placeholder(f"euler_g{i}") for i in range(3)])
    J = sp.Matrix(3, 3, [placeholder(f"euler_J{i}") for i in range(9)])
    r, alpha, rd, alpha_d = sp.Matrix(q[:3]), q[3:], sp.Matrix(qd[:3]), sp.Matrix(qd[3:])
    H = euler_rate_matrix(sequence, alpha)
    H_dot = sum((H.diff(a) * ad for a, ad in zip(alpha, alpha_d)), sp.zeros(3, 3))
    omega = H * alpha_d
    M = sp.diag(mass * sp.eye(3), H.T * J * H)
    Q = sp.Matrix.vstack(mass * gravity, -H.T * (J * H_dot * alpha_d + omega.cross(J * omega)))
    T = mass * (rd.T * rd)[0] / 2 + (omega.T * J * omega)[0] / 2
    V = -mass * (gravity.T * r)[0]
    return (list(q), list(qd)), [mass, *J, *gravity], (M, Q, T, V)
