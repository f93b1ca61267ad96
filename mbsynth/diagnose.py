"""The well-posedness report behind ``mbsynth check``: Result 3 at a state.

Counts coordinates and constraints, the ranks of M, A and M̂ = [M; A], whether the
motion is unique, each indeterminate direction, and for each the balance
wᵀ(Q + C) = 0 that would close the model (see closure.py). How firm the verdict is:
the condition number of the equilibrated M̂, the rank tolerance, the verdict margin
(equations.py) and a warning when that margin is below ``VERDICT_MARGIN``.
"""

from dataclasses import asdict, dataclass, field

import numpy as np

from .closure import balances
from .equations import VERDICT_MARGIN, rank_report
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
    condition: float = None  # σ₁/σ_n of the equilibrated [M; A]; None when infinite
    rank_tolerance: float = None  # singular values below rank_tolerance · σ₁ count as zero
    verdict_margin: float = None  # see RankReport.verdict_margin; None when infinite
    warnings: list = field(default_factory=list)

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
        constraint_residuals=residuals, qdd=qdd, error=error, condition=_finite(report.condition),
        rank_tolerance=report.rtol, verdict_margin=_finite(report.verdict_margin), warnings=_warnings(report))


def _warnings(report):
    """A warning for each side of the rank cut-off that a singular value comes close to."""
    kept, dropped = report.margins
    found = []
    if kept < VERDICT_MARGIN:
        found.append(f"uncertain verdict: the smallest singular value kept in rank [M; A] = {report.rank_Mhat} "
                     f"is only {kept:.3g} times the cut-off ({report.rtol:g} of the largest, equilibrated); "
                     "a nearly singular mass or nearly dependent constraints: the motion may in fact not "
                     "be unique")
    if dropped < VERDICT_MARGIN:
        found.append(f"uncertain verdict: the largest singular value of [M; A] counted as zero is only "
                     f"{dropped:.3g} times below the cut-off ({report.rtol:g} of the largest, equilibrated); "
                     "the motion may in fact be unique")
    return found


def _finite(x):
    return float(x) if np.isfinite(x) else None


def _components(w, coordinates):
    """{coordinate: component} of a direction scaled so its largest component is +1."""
    w = w / w[np.argmax(np.abs(w))]
    return {c: float(x) for c, x in zip(coordinates, w) if abs(x) > COMPONENT_TOL}


def _number(x):
    return None if np.isnan(x) else float(x)
