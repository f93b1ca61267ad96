"""Parts of a mechanical system, each in its own coordinates with its own M and Q (2.1).

A subsystem knows only its own coordinates. It offers
``evaluate(t, q, qd, p) -> (M, Q)`` on its own slice of the state (``p``: the
model's parameter values in the model's order), ``symbolic()`` returning the same
M and Q as sympy matrices (used to derive closure balances), its energies, and the
world pose of its named frames for connectors and force elements.
"""

from .base import LINK_FRAME, Frame, Part
from .euler_body import EulerBody
from .flexible_body import FlexibleBody
from .lagrangian import LagrangianPart
from .particle import Particle
from .planar_body import PlanarBody
from .rigid_body import RigidBody
from .spring import Spring

__all__ = ["LINK_FRAME", "EulerBody", "FlexibleBody", "Frame", "Part", "LagrangianPart", "Particle", "PlanarBody", "RigidBody", "Spring"]
