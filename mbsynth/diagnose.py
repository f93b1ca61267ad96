"""The well-posedness report behind ``mbsynth check``: Result 3 at a state.

Counts coordinates and constraints, the ranks of M, A and M̂ = [M; A], whether the
motion is unique, each indeterminate direction, and for each the balance
wᵀ(Q + C) = 0 that would close the model (see closure.py).
"""

from dataclasses import asdict, dataclass, field

import numpy as np

from .closure import balances
from .equations import rank_report
from .errors import SolveError

COMPONENT_TOL = 1e-12


@dataclass(frozen=True)
class Diagnosis:
    model: str
    n: int
    m: int
    rank_M: int
    rank_A: int
    rank_Mhat: int
    unique: bool
    indeterminate: list
    suggested_constraints: list
    balances: list
    state_dependent: bool
    closures: list
    constraint_residuals: dict
    qdd: dict = field(default_factory=dict)
    error: str = None

    @property
    def consistent(self):
        return self.error is None

    def to_dict(self):
        return dict(asdict(self), consistent=self.consistent)


def diagnose(system, t=0.0, q=None, qd=None):
    """Result 3 and the closure balances of ``system`` at (t, q, q̇), by default its initial state."""
    q0, qd0 = system.initial_state()
    q = q0 if q is None else np.asarray(q, dtype=float)
    qd = qd0 if qd is None else np.asarray(qd, dtype=float)
    arrays = system.evaluate(t, q, qd)
    report = rank_report(arrays.M, arrays.A)
    found = balances(system, t, q, qd)
    phi, phidot = system.constraint_residuals(t, q, qd)
    residuals = {name: {"phi": _number(a), "phi_dot": _number(b)}
                 for name, a, b in zip(system.constraint_names, phi, phidot)}
    try:
        motion = system.motion(t, q, qd, method="reference")
        qdd, error = dict(zip(system.coordinates, map(float, motion.qdd))), None
    except SolveError as err:
        qdd, error = {}, str(err)
    return Diagnosis(
        model=system.name, n=report.n, m=report.m, rank_M=report.rank_M, rank_A=report.rank_A,
        rank_Mhat=report.rank_Mhat, unique=report.unique,
        indeterminate=[_components(w, system.coordinates) for w in report.nullspace.T],
        suggested_constraints=[b.equation for b in found if not b.free],
        balances=[{"direction": b.direction, "free": b.free,
                   "equation": None if b.free else b.equation} for b in found],
        state_dependent=any(b.state_dependent for b in found),
        closures=[{"constraint": c.constraint, "equation": c.equation, "direction": c.direction,
                   "state_dependent": c.state_dependent} for c in system.closures],
        constraint_residuals=residuals, qdd=qdd, error=error)


def _components(w, coordinates):
    """{coordinate: component} of a direction scaled so its largest component is +1."""
    w = w / w[np.argmax(np.abs(w))]
    return {c: float(x) for c, x in zip(coordinates, w) if abs(x) > COMPONENT_TOL}


def _number(x):
    return None if np.isnan(x) else float(x)
