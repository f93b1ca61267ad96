"""mbsynth: multibody dynamics composed from simple parts.

Each part is described in its own coordinates by its unconstrained equation
M q̈ = Q (M may be singular); parts are joined by constraints A q̈ = b; the motion
follows from the explicit equation (2.14) of Udwadia & Phohomsiri (2006), with
Result 3 (full column rank of [M; A]) as the exact test of uniqueness.
"""

from .equations import Motion, RankReport, constrained_acceleration, rank_report, udwadia_kalaba
from .errors import ModelError, SimulationError, SolveError
from .io import load, loads
from .linearization import Linearization, linearize
from .modal import Modes, modes
from .robots import from_robot
from .simulate import simulate
from .statics import equilibrium
from .sweep import sweep
from .system import System
from .trajectory import Trajectory, load_trajectory
from . import viewer  # mb.viewer.show, mb.viewer.to_html (meshcat is imported on first use)

__version__ = "0.1.0"

__all__ = [
    "Motion", "RankReport", "constrained_acceleration", "rank_report", "udwadia_kalaba",
    "ModelError", "SolveError", "SimulationError", "load", "loads", "System",
    "simulate", "sweep", "Trajectory", "load_trajectory", "from_robot", "viewer",
    "equilibrium", "linearize", "Linearization", "modes", "Modes",
]
