"""A spring (and damper) as a part of its own: the substructuring way of the paper's
example 3, where a spring is a part joined to its neighbours by constraints.
``spring_damper`` is the spring law, shared with the force element ``forces.point_spring``."""

import numpy as np
import sympy as sp

from ...symbolic.derive import generalized_force, time_derivative
from .base import Frame, Part
from .part_type import EXTRA_NODE, LINE, POINT, PartType, check

COORDINATES = ("x1", "y1", "z1", "x2", "y2", "z2")


def spring_damper(pA, pB, stiffness, rest_length, damping, q, qd):
    """(V, [(effort, rate)]) of a linear spring and damper between the points pA, pB:
    ℓ = |p_B − p_A|, V = ½ k (ℓ − ℓ0)², damper effort −c ℓ̇ along the rate ℓ̇.

    At ℓ = 0 the line of action is undefined: ℓ is written Piecewise((√(dᵀd), dᵀd > 0),
    (0, True)), so there the force and ℓ̇ are zero (V = ½ k ℓ0² stays continuous).
    numpy evaluates the unused branch too: evaluate under ``quiet_at_zero_length``."""
    d = sp.Matrix(pB) - sp.Matrix(pA)
    squared = (d.T * d)[0]
    length = sp.Piecewise((sp.sqrt(squared), squared > 0), (0, True))
    rate = time_derivative(length, q, qd)
    efforts = [(-damping * rate, rate)] if damping != 0 else []
    return stiffness * (length - rest_length) ** 2 / 2, efforts


def quiet_at_zero_length():
    """Silence numpy's 0/0 warnings from the discarded branch of ℓ's Piecewise at ℓ = 0."""
    return np.errstate(divide="ignore", invalid="ignore")


class Spring(Part):
    """Coordinates: its two end points p1, p2 in the world. Frames ``end1``, ``end2``
    (the end points, world axes), to be joined to bodies or the world.

    M = m/6 [[2I, I], [I, 2I]], the consistent mass matrix of a uniform bar
    (T = m/6 (ṗ1² + ṗ1·ṗ2 + ṗ2²)), zero for a massless spring (m = 0, singular);
    V = ½ k (ℓ − ℓ0)² − m gᵀ(p1 + p2)/2; Q = −∂V/∂q plus the damper: the spring and
    damper forces on its ends and the consistent gravity load m g/2 per end.
    """

    part_type = check(PartType("spring", node=EXTRA_NODE, orientation=POINT, quaternion=None,
                               points=(("x1", "y1", "z1"), ("x2", "y2", "z2")), elastic=False, body_rates=False, origin=False,
                               shared_pose=False, drawing=LINE))
    COORDINATES = COORDINATES
    groups = (("x1", "y1", "z1"), ("x2", "y2", "z2"))

    def __init__(self, name, q, qd, stiffness, rest_length, damping, mass, gravity, params, initial=None):
        p1, p2 = sp.Matrix(q[:3]), sp.Matrix(q[3:])
        V_spring, efforts = spring_damper(p1, p2, stiffness, rest_length, damping, q, qd)
        self.power_expression = sum((effort * rate for effort, rate in efforts), sp.S.Zero)  # the damper's
        V = V_spring - mass * (sp.Matrix(gravity).T * (p1 + p2))[0] / 2
        I3 = sp.eye(3)
        M = mass / 6 * sp.Matrix(sp.BlockMatrix([[2 * I3, I3], [I3, 2 * I3]]))
        T = (sp.Matrix(qd).T * M * sp.Matrix(qd))[0] / 2
        frames = (Frame(name, "end1", p1, I3), Frame(name, "end2", p2, I3))
        super().__init__(name, COORDINATES, q, qd, M, generalized_force(V, efforts, q, qd), T, V, params,
                         frames, (), initial)

    def evaluate(self, t, q, qd, p):
        with quiet_at_zero_length():
            return super().evaluate(t, q, qd, p)

    def pose(self, frame):
        return frame.position, frame.rotation
