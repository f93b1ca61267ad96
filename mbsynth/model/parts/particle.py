"""A point mass in 3 coordinates."""

import sympy as sp

from .base import Part
from .part_type import PARTICLE_NODE, POINT, PartType, SPHERE, check


class Particle(Part):
    """M = m I₃ (m ≥ 0; a massless particle is legal), Q = m g. Its frames are the point."""

    part_type = check(PartType("particle", node=PARTICLE_NODE, orientation=POINT, quaternion=None,
                               points=(("x", "y", "z"),), elastic=False, body_rates=False, origin=True,
                               shared_pose=True, drawing=SPHERE))
    groups = (("x", "y", "z"),)

    def __init__(self, name, q, qd, mass, gravity, params, frames=(), geometry=(), initial=None):
        r, rd = sp.Matrix(q), sp.Matrix(qd)
        g = sp.Matrix(gravity)
        super().__init__(name, ("x", "y", "z"), q, qd, mass * sp.eye(3), mass * g,
                         mass * (rd.T * rd)[0] / 2, -mass * (g.T * r)[0], params, frames, geometry, initial)

    def pose(self, frame):
        return sp.Matrix(self.q), frame.rotation
