"""A part given by its kinetic energy T, potential energy V and generalized forces."""

import sympy as sp

from ...symbolic.derive import energy_template, lagrange
from .base import Part
from .part_type import EXTRA_NODE, FRAMES, OWN, PartType, check


class LagrangianPart(Part):
    """Unconstrained M q̈ = Q (2.1) of a part from Lagrange's equations, derived and
    compiled once for all parts whose energies differ only in the names of their symbols
    (``symbolic.energy_template``).

    ``q`` and ``qd`` are this part's coordinate and velocity symbols, ``T``, ``V``
    and ``forces`` (one expression per coordinate) sympy expressions of them,
    of ``params`` and of time. M may be singular (the paper's examples 1 and 3).
    Its frames are points whose world position is an expression of its coordinates.
    """

    content_fields = ("forces",)

    part_type = check(PartType("lagrangian", node=EXTRA_NODE, orientation=OWN, quaternion=None,
                               points=(), elastic=False, body_rates=False, origin=False,
                               shared_pose=False, drawing=FRAMES))

    def __init__(self, name, coordinates, q, qd, T, V, forces, params, frames=(), geometry=()):
        self.forces = tuple(sp.sympify(f) for f in forces)  # generalized forces beyond V (they may do work)
        self.power_expression = sum((v * f for v, f in zip(qd, self.forces)), sp.S.Zero)
        template = energy_template(T, V, self.forces, q, qd)
        if template is None:  # symbols no slot stands for: derived for this part alone
            M, Q = lagrange(T, V, self.forces, q, qd)
            super().__init__(name, coordinates, q, qd, M, Q, T, V, params, frames, geometry)
        else:  # derived and compiled once for all parts alike, its own symbols put in when asked
            slots, constants, (M, Q, T, V, _) = template
            super().__init__(name, coordinates, q, qd, M, Q, T, V, params, frames, geometry,
                             shared=(*slots, constants))
        self.groups = same_units(coordinates, M)

    def pose(self, frame):
        return frame.position, frame.rotation


def same_units(coordinates, M):
    """The coordinates that move together in projection.py's metric: those whose diagonal
    entries of M are the same nonzero expression. T = ½ q̇ᵀ M q̇ is an energy, so equal
    M_ii give q_i the same units: a point's x and y under T = ½ m (ẋ² + ẏ²) share one
    scale (a scale of its own lets a projection move x by φ/∂φ/∂x where the rod stands
    vertical, x ≈ 0, instead of along the rod); r and θ under T = ½ m (ṙ² + r² θ̇²) do not."""
    alike = {}
    for i, name in enumerate(coordinates):
        if M[i, i] != 0:
            alike.setdefault(M[i, i], []).append(name)
    return tuple(tuple(names) for names in alike.values() if len(names) > 1)
