"""Parts of a mechanical system, each in its own coordinates with its own M and Q (2.1).

A part knows only its own coordinates. It offers
``evaluate(t, q, qd, p) -> (M, Q)`` on its own slice of the state (``p``: the
model's parameter values in the model's order), ``symbolic()`` returning the same
M and Q as sympy matrices (used to derive balances), its energies, and the
world pose of its named frames for constraints and force elements. Each part class declares
its type's record (part_type.py); ``PART_TYPES`` gathers them: a new type of part is a module
here and its line below.
"""

from .base import LINK_FRAME, Frame, Part
from .euler_body import EulerBody
from .flexible_body import FlexibleBody
from .flexible_euler_body import EulerFlexibleBody
from .lagrangian import LagrangianPart
from .particle import Particle
from .planar_body import PlanarBody
from .rigid_body import RigidBody
from .spring import Spring

PART_TYPES = {cls.part_type.name: cls.part_type for cls in (
    LagrangianPart,
    RigidBody,
    EulerBody,
    Particle,
    PlanarBody,
    Spring,
    FlexibleBody,
    EulerFlexibleBody,
)}

__all__ = ["LINK_FRAME", "PART_TYPES", "EulerBody", "EulerFlexibleBody", "FlexibleBody", "Frame", "Part", "LagrangianPart", "Particle", "PlanarBody", "RigidBody", "Spring"]
