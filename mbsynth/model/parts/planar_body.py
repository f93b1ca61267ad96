"""A rigid body moving in the world's x-y plane: coordinates x, y, theta."""

import sympy as sp

from ...core.kinematics import rotation_z
from .base import Part
from .part_type import BODY, EXTRA_NODE, PLANE, PartType, check


class PlanarBody(Part):
    """M = diag(m, m, I_zz), Q = (m g_x, m g_y, 0); frames rotate with θ about z."""

    part_type = check(PartType("planar_body", node=EXTRA_NODE, orientation=PLANE, quaternion=None,
                               points=(), elastic=False, body_rates=False, origin=True,
                               shared_pose=True, drawing=BODY))
    groups = (("x", "y"),)

    def __init__(self, name, q, qd, mass, inertia_zz, gravity, params, frames=(), geometry=(), initial=None):
        g = sp.Matrix(gravity)
        xd, yd, thd = qd
        T = mass * (xd**2 + yd**2) / 2 + inertia_zz * thd**2 / 2
        V = -mass * (g[0] * q[0] + g[1] * q[1])
        super().__init__(name, ("x", "y", "theta"), q, qd, sp.diag(mass, mass, inertia_zz),
                         sp.Matrix([mass * g[0], mass * g[1], 0]), T, V, params, frames, geometry, initial)

    def pose(self, frame):
        R = rotation_z(self.q[2])
        return sp.Matrix([self.q[0], self.q[1], 0]) + R * frame.position, R * frame.rotation

    def angular_velocity(self):
        return sp.Matrix([0, 0, self.qd[2]])
