"""A rigid body in 7 coordinates: its centre of mass r in the world and a unit
quaternion u (scalar-first) for its orientation."""

import numpy as np
import sympy as sp

from ..constraints.base import Constraint
from ...symbolic.cache import placeholder, remembered
from ...core.kinematics import body_rate_matrix, rotation, world_rate_matrix
from ...symbolic.derive import differentiate, positions
from .base import Part
from ...core.memo import MEMO
from .part_type import BODY, PartType, QUATERNION, RIGID_NODE, check

COORDINATES = ("x", "y", "z", "qw", "qx", "qy", "qz")


class RigidBody(Part):
    """M = blockdiag(m I₃, 4 EᵀJE): the rotational block has rank 3 — singular by design,
    closed by the unit-norm constraint uᵀu = 1 that the body adds itself.

    Q = [m g + F;  2 EᵀΓ_body − 8 E(u̇)ᵀ J E(u) u̇], the last term from Lagrange's equations
    with T = ½ m ṙᵀṙ + 2 u̇ᵀ Eᵀ J E u̇ (ω_body = 2 E u̇). ``mass`` (≥ 0) and ``inertia``
    (3 × 3, about the centre of mass, body axes) are sympy expressions of parameters.
    """

    content_fields = ("mass", "inertia", "gravity")

    part_type = check(PartType("rigid_body", node=RIGID_NODE, orientation=QUATERNION, quaternion=slice(3, 7),
                               points=(("x", "y", "z"),), elastic=False, body_rates=True, origin=True,
                               shared_pose=True, drawing=BODY))
    COORDINATES = COORDINATES
    groups = (("x", "y", "z"), ("qw", "qx", "qy", "qz"))
    defaults = {"qw": 1.0}  # the identity orientation

    def __init__(self, name, q, qd, mass, inertia, gravity, params, frames=(), geometry=(), initial=None):
        slots, placeholders, (M, Q, T, V) = _template()
        J = sp.Matrix(inertia)
        self.mass, self.inertia, self.gravity = mass, J, sp.Matrix(gravity)
        constants = list(zip(placeholders, [mass, *J, *self.gravity]))
        super().__init__(name, COORDINATES, q, qd, M, Q, T, V, params, frames, geometry, initial,
                         shared=(*slots, constants))

    def own_constraints(self, q, qd, params):
        """φ = (uᵀu − 1)/2 = 0, differentiated: uᵀü = −u̇ᵀu̇ — one row placed from the rows
        every body shares (``_unit_norm_rows``), derived once per process."""
        where = positions(q, qd)
        rows, slots = _unit_norm_rows()
        return [Constraint.placed(f"{self.name}.unit_quaternion", "holonomic", rows, slots,
                                 [where[s] for s in self.q[3:]], q, qd, params)]

    def pose(self, frame):
        R = rotation(self.q[3:])
        return sp.Matrix(self.q[:3]) + R * frame.position, R * frame.rotation

    def angular_velocity(self):
        return 2 * world_rate_matrix(self.q[3:]) * sp.Matrix(self.qd[3:])

    def idle_directions(self, q):
        """The quaternion's own direction: scaling u turns nothing (E(u) u = G(u) u = 0)."""
        direction = np.zeros((7, 1))
        direction[3:, 0] = q[3:7] / np.linalg.norm(q[3:7])
        return direction



@MEMO.function(1)
def _template():
    """(coordinate slots (q, q̇), placeholders (m, J row by row, g), (M, Q, T, V)): the
    body's equations derived once, for every body (base.Part's ``shared``)."""
    return remembered("rigid-body", (), _derive_template)


@MEMO.function(1)
def _unit_norm_rows():
    """((a over the slots, b, φ, φ̇), slots) of φ = (uᵀu − 1)/2 in four quaternion slots
    (symbolic.differentiate), derived once and kept on disk (symbolic/cache.py)."""
    return remembered("unit-norm", (), _derive_unit_norm)


def _derive_unit_norm():
    u, ud = tuple(placeholder(f"unit_q{i}") for i in range(4)), tuple(placeholder(f"unit_q{i}_dot") for i in range(4))
    phi = (sum(x * x for x in u) - 1) / 2
    a, b, psi = differentiate(phi, list(u), list(ud))
    return ((tuple(a),), (b,), (phi,), (psi,)), (u, ud)


def _derive_template():
    names = ("x", "y", "z", "qw", "qx", "qy", "qz")
    q, qd = [placeholder(f"body_{c}") for c in names], [placeholder(f"body_{c}_dot") for c in names]
    mass, gravity = placeholder("body_m"), sp.Matrix([placeholder(f"body_g{i}") for i in range(3)])
    J = sp.Matrix(3, 3, [placeholder(f"body_J{i}") for i in range(9)])
    r, u = sp.Matrix(q[:3]), sp.Matrix(q[3:])
    rd, ud = sp.Matrix(qd[:3]), sp.Matrix(qd[3:])
    E, Ed = body_rate_matrix(u), body_rate_matrix(ud)
    M = sp.diag(mass * sp.eye(3), 4 * E.T * J * E)
    Q = sp.Matrix.vstack(mass * gravity, -8 * Ed.T * J * E * ud)
    T = mass * (rd.T * rd)[0] / 2 + 2 * (ud.T * E.T * J * E * ud)[0]
    V = -mass * (gravity.T * r)[0]
    return (list(q), list(qd)), [mass, *J, *gravity], (M, Q, T, V)
