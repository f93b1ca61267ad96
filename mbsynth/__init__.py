"""mbsynth: multibody dynamics composed from simple parts.

Each part is described in its own coordinates by its unconstrained equation
M q̈ = Q (M may be singular); parts are joined by constraints A q̈ = b; the motion
follows from the explicit equation (2.14) of Udwadia & Phohomsiri (2006), with
Result 3 (full column rank of [M; A]) as the exact test of uniqueness.

``import mbsynth`` loads numpy and the equations only; every other public name is
imported on first use (PEP 562), so sympy, scipy, pandas, dask, matplotlib, meshcat,
pinocchio and numba load when their feature is used.
"""

import importlib
import sys
import types

from .equations import Motion, RankReport, constrained_acceleration, rank_report, udwadia_kalaba
from .errors import ModelError, SimulationError, SolveError

__version__ = "0.1.0"

# Public names imported on first use: name -> the submodule that defines it.
_LAZY = {
    "load": "io", "loads": "io", "System": "system", "from_robot": "robots", "simulate": "simulate",
    "sweep": "sweep", "Trajectory": "trajectory", "load_trajectory": "trajectory",
    "equilibrium": "statics", "linearize": "linearization", "Linearization": "linearization",
    "modes": "modal", "Modes": "modal",
}
# Public submodules imported on first use: mb.viewer.show, mb.viewer.to_html.
_SUBMODULES = ("viewer",)

__all__ = [
    "Motion", "RankReport", "constrained_acceleration", "rank_report", "udwadia_kalaba",
    "ModelError", "SolveError", "SimulationError", *_LAZY, *_SUBMODULES,
]


def __getattr__(name):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value  # later look-ups do not come back here
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))


class _Package(types.ModuleType):
    """The package's module type. Importing a submodule binds it as an attribute of the
    package; ``mb.simulate`` and ``mb.sweep`` name functions that share their modules'
    names, so that binding is skipped and the function stays what the name means."""

    def __setattr__(self, name, value):
        if not (name in _LAZY and isinstance(value, types.ModuleType)):
            super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
