"""Contacts with the ground that constrain velocities (non-holonomic).

RollingDisk: a thin disk of radius R, the frame's origin p at its centre and the
frame's z axis a along its axis, rolling without slipping on the plane z = h. Its
contact point is the lowest point of the rim, c = p + ρ with

    ρ = −R d / |d|,   d = n (a·a) − (n·a) a,   n = e_z

(d is the part of n perpendicular to a; the factor a·a keeps it so when a drifting
quaternion makes |a| ≠ 1). Rows:

    height   p_z + ρ_z − h = 0                          holonomic (φ, differentiated twice)
    slip     (v_p + ω × ρ)_x = (v_p + ω × ρ)_y = 0       non-holonomic (ψ, differentiated once)

The vertical slip component is d/dt of the height row (c is the lowest point of the
rim), so it is not repeated. d = 0 when the disk lies flat: no contact point is
defined there.

KnifeEdge: a blade along the x axis of a frame; its origin does not move along the
frame's y axis:  ψ = y_f · v_p = 0 (one non-holonomic row).
"""

import sympy as sp

from .base import Constraint, mixed
from ...symbolic.derive import time_derivative


def _velocity(position, q, qd):
    return sp.Matrix([time_derivative(x, q, qd) for x in position])


class RollingDisk(Constraint):
    """A disk (``frame`` on the rigid ``part``) rolling on the ground z = ``height``:
    rows ``height``, ``slip_x``, ``slip_y``. Keeps ``part``, ``frame`` and ``radius``
    (the viewer draws the wheel)."""

    content_fields = ("frame", "radius")

    def __init__(self, name, part, frame, radius, height, q, qd, params):
        self.part, self.frame, self.radius = part, frame, radius
        p, R = part.pose(frame)
        a, n = R[:, 2], sp.Matrix([0, 0, 1])
        d = n * a.dot(a) - a.dot(n) * a
        rho = -radius * d / sp.sqrt(d.dot(d))
        slip = _velocity(p, q, qd) + part.angular_velocity().cross(rho)
        a_rows, b, phi, psi = mixed([p[2] + rho[2] - height], slip[:2], q, qd)
        super().__init__(name, "nonholonomic", a_rows, b, sp.zeros(len(q), 1), phi, psi, q, qd, params,
                         ["height", "slip_x", "slip_y"])


class KnifeEdge(Constraint):
    """A blade along the x axis of ``frame`` on ``part``: y_f · v_p = 0. Keeps ``part``
    and ``frame``."""

    content_fields = ("frame",)

    def __init__(self, name, part, frame, q, qd, params):
        self.part, self.frame = part, frame
        p, R = part.pose(frame)
        a, b, phi, psi = mixed([], [R[:, 1].dot(_velocity(p, q, qd))], q, qd)
        super().__init__(name, "nonholonomic", a, b, sp.zeros(len(q), 1), phi, psi, q, qd, params)
