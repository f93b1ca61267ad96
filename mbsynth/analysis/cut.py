"""The cut strategy of the run loop: each interval between output times (or control
samples) integrated on its own, the integrator's last step cut short at its end.

With projection, (q, q̇) is projected back onto the constraints (projection.py) at the
interval's end and, between, as often as keeps the drift below DRIFT_TARGET (drift.py):
the interval is cut into spans, each integrated and projected. The integrator is not
restarted at a cut: an explicit pair goes on from the projected state, given its
derivative, with the step it proposed before the cut (Integration.resumed); an implicit one
(Radau, BDF, LSODA) starts afresh with that step. ``"baumgarte"`` replaces b by
b − 2α φ̇ − β² φ (Baumgarte 1972), its drift growing with the step; ``"none"`` does neither.

A span that crawls near a singular position (derivative.Crawl) is integrated again at
RELAXED_RTOL (atol relaxed by the same factor), ten times looser again while it crawls
still, up to RELAXED_MAX, and listed in ``stats["relaxed_spans"]``: each loosening costs
accuracy where it counts (a crossing of a singular position loses energy with each factor
of ten), so only the span that crawls is relaxed.
"""

import logging

import numpy as np

from .derivative import Crawl
from .drift import next_cap
from .integration import Integration
from .projection import project, relative_drift
from . import stepper
from ..core.tolerances import RELAXED_MAX, RELAXED_RTOL

log = logging.getLogger(__name__)



class CutIntegration(Integration):
    """Integration interval by interval, projected at each interval's end (integration.py)."""

    def __init__(self, *args):
        self.drift_span = np.inf  # the cap on a span between projections (drift.next_cap; np.inf: none)
        super().__init__(*args)

    def advance(self, t_next, q, qd, t_stop=None, loosen=False):
        """Integrate to t_next, check the state, project it if asked. With projection the
        interval is cut into spans short enough that the state drifts off the manifold by
        at most DRIFT_TARGET (relative, projection.relative_drift) between projections: the
        span halves after a larger drift and doubles after one below a hundredth of it; a
        span that drifted more than DRIFT_REDO × DRIFT_TARGET is integrated again in
        quarters (the least-squares motion of the stages is only as good as their drift).
        ``loosen``: the interval crawled already (integrated continuously); start looser."""
        t = self.t_now
        interval = t_next - t
        while t < t_next:
            t_to = t_next if t + 1.5 * self.drift_span >= t_next else t + self.drift_span
            q_to, qd_to = self._integrate(t, t_to, q, qd, loosen)
            arrays = None
            if self.stabilization == "projection":
                self.f.t_failed = t_to
                arrays = self.data.constraint_arrays(t_to, q_to, qd_to, sparse=None)
                drift = relative_drift(self.data, t_to, q_to, qd_to, arrays, t_to - t)
                redo, self.drift_span = next_cap(drift, t_to - t, self.drift_span, interval, interval,
                                                     self.drift_target)
                if redo:
                    continue
                q_on, qd_on = project(self.data, t_to, q_to, qd_to, arrays=arrays)
                if not (np.array_equal(q_on, q_to) and np.array_equal(qd_on, qd_to)):
                    q_to, qd_to, arrays = q_on, qd_on, None
            t, q, qd = t_to, q_to, qd_to
        return self.arrived(t_next, q, qd, arrays)

    def _integrate(self, t, t_next, q, qd, loosen=False):
        """The integrator from (t, q, q̇) to t_next; the state at t_next, checked. A span that
        crawls near a singular position is integrated again at a looser tolerance:
        RELAXED_RTOL, then ten times looser each time, up to RELAXED_MAX."""
        rtol, atol, proposed = self.rtol, self.atol, self.next_step
        if loosen:
            rtol, atol = _looser(rtol, atol)
        while True:
            try:
                y = self._span(t, t_next, q, qd, rtol, atol)
                break
            except Crawl:
                self.solver, self.next_step = None, proposed  # stopped within a step; its steps are no guide
                rtol, atol = _looser(rtol, atol)
        if rtol != self.rtol:
            self.relaxed_spans.append(dict(t_from=t, t_to=t_next, rtol=rtol, atol=atol))
            log.info("near a singular position between t = %.6g and %.6g: integrated at rtol %g, atol %g",
                     t, t_next, rtol, atol)
        q, qd = self.form.to_state(y)
        self.f.check(t_next, q, qd)
        return q, qd

    def _span(self, t, t_next, q, qd, rtol, atol):
        """The integrator's steps from (t, q, q̇) to t_next (its last step cut short there);
        its state y there (velocity_form.py)."""
        self.f.begin(t, t_next, relaxed=rtol != self.rtol, may_crawl=rtol < RELAXED_MAX)
        solver = self.resumed(t, q, qd, t_next, rtol, atol)
        while solver.status == "running":
            message = solver.step()
            if solver.status == "failed":
                raise self.failed_step(solver, message)
            self.steps += 1
            if solver.t != t_next:
                self.next_step = stepper.proposed_step(solver)
        return solver.y.copy()


def _looser(rtol, atol):
    """The next tolerances of a span that crawls: RELAXED_RTOL, then ten times looser, up to
    RELAXED_MAX (atol alike)."""
    looser = min(max(RELAXED_RTOL, 10 * rtol), RELAXED_MAX)
    return looser, atol * looser / rtol
