"""A part given by its kinetic energy T, potential energy V and generalized forces."""

import sympy as sp

from ..symbolic import lagrange
from .base import Part


class LagrangianSubsystem(Part):
    """Unconstrained M q̈ = Q (2.1) of a part from Lagrange's equations.

    ``q`` and ``qd`` are this part's coordinate and velocity symbols, ``T``, ``V``
    and ``forces`` (one expression per coordinate) sympy expressions of them,
    of ``params`` and of time. M may be singular (the paper's examples 1 and 3).
    Its frames are points whose world position is an expression of its coordinates.
    """

    kind = "lagrangian"

    def __init__(self, name, coordinates, q, qd, T, V, forces, params, frames=(), geometry=()):
        self.forces = tuple(sp.sympify(f) for f in forces)  # generalized forces beyond V (they may do work)
        M, Q = lagrange(T, V, list(forces), q, qd)
        super().__init__(name, coordinates, q, qd, M, Q, T, V, params, frames, geometry)

    def pose(self, frame):
        return frame.position, frame.rotation
