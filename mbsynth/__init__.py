"""mbsynth: multibody dynamics composed from simple parts.

Each part is described in its own coordinates by its unconstrained equation
M q̈ = Q (M may be singular); parts are joined by constraints A q̈ = b; the motion
follows from the explicit equation (2.14) of Udwadia & Phohomsiri (2006), with
Result 3 (full column rank of [M; A]) as the exact test of uniqueness.

``import mbsynth`` loads numpy and the equations only; every other public name is
imported on first use (PEP 562), so sympy, scipy, pandas, dask, matplotlib, meshcat,
pinocchio and numba load when their feature is used.
"""

from .core.equations import Motion, RankReport, constrained_acceleration, rank_report, udwadia_kalaba
from .core.errors import ControlError, ModelError, NoEquilibrium, SimulationError, SolveError
from .core import collection as _collection, leaving as _leaving

_leaving.skip_final_collections()

__version__ = "0.1.0"

# Public names imported on first use: name -> the submodule that defines it.
_LAZY = {
    "load": "io", "loads": "io", "System": "model.system", "from_robot": "robots.build",
    "simulate": "analysis.simulate", "sweep": "studies.sweep", "Trajectory": "analysis.trajectory",
    "load_trajectory": "analysis.trajectory", "equilibrium": "analysis.statics",
    "linearize": "analysis.linearization", "Linearization": "analysis.linearization",
    "modes": "analysis.modes", "Modes": "analysis.modes", "steady_motion": "analysis.steady",
    "campbell": "analysis.campbell", "Campbell": "analysis.campbell",
    "compose": "io.compose", "substructure": "io.compose",
}
# Public submodules imported on first use: mb.viewer.show, mb.viewer.to_html.
_SUBMODULES = {"viewer": "view.viewer"}

__all__ = [
    "Motion", "RankReport", "constrained_acceleration", "rank_report", "udwadia_kalaba",
    "ModelError", "SolveError", "SimulationError", "ControlError", "NoEquilibrium", *_LAZY, *_SUBMODULES,
]


def __getattr__(name):
    if name in _LAZY:
        value = getattr(_collection.imported(f"{__name__}.{_LAZY[name]}"), name)
    elif name in _SUBMODULES:
        value = _collection.imported(f"{__name__}.{_SUBMODULES[name]}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # later look-ups do not come back here
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
