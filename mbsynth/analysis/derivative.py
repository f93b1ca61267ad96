"""The run loop's right-hand side: ẏ at the integrator's stages, y = (q, v) the integrator's
form of the state (velocity_form.py: q̇ with each rigid body's quaternion rates replaced by
its angular velocity), from (q̇, q̈) at the state, q̈ from (2.14) (the compiled engine's where
it covers the state, else the Data's stage motion), and what the stages tell about the run.

The stages lie off the constraint manifold by the integration error, so their motion follows
the drift rule of ``equations`` (least squares where the drift explains an inconsistency of
b, nearly dependent directions near a singular position set aside). Counted here, per
interval of integration (``begin``):

- a step-size collapse: COLLAPSE_CALLS evaluations that advance t by less than COLLAPSE_SPAN
  of the interval (or than 1e4 ε |t|, steps near the resolution of t) raise SolveError
  naming the fastest changing coordinates (where scipy would crawl on);
- a crawl near a singular position: near one the stages' accelerations carry noise of about
  |q̇| ψ / σ² (ψ the velocity drift the projection leaves, σ the smallest singular value of
  A), which a tight tolerance chases with ever smaller steps; more than CRAWL_CALLS
  evaluations (RELAXED_CRAWL_CALLS in an interval already relaxed) after the interval's
  first stage near one (``Motion.singular``) raise Crawl, for the cut integrator to
  integrate the interval again more loosely (cut.py); one that crawls still at the loosest
  tolerance (``may_crawl`` False) raises SolveError naming the rows after STUCK_CALLS;
- a crawl near the singular position of a part's angles (model/angle_singularity.py): there
  the angle rates grow like 1/|det H| and the steps shrink without end; more than
  ANGLES_CRAWL_CALLS evaluations in an interval at stages within ANGLES_NEAR of it raise
  SolveError naming the part, its angles and their singular value (no tolerance helps: the
  coordinates fail there). A collapse or a state that explodes near it names it too;
- the stages near a singular position, per interval (``note_singular``), and whether the
  motion was not unique at any stage.
"""

import logging

import numpy as np

from ..compiled.rows import largest
from ..core.errors import SolveError
from ..model.angle_singularity import AngleParts, explain
from ..core.tolerances import ANGLES_NEAR, COLLAPSE_SPAN, JACOBIAN_STEP, MAX_STATE, STEP_RESOLUTION

log = logging.getLogger(__name__)

COLLAPSE_CALLS = 1000  # ~80 steps of an explicit pair
CRAWL_CALLS = 240
RELAXED_CRAWL_CALLS = 1000
STUCK_CALLS = 20000  # an interval that crawls this long near a singular position at the loosest tolerance stops
ANGLES_CRAWL_CALLS = 5000  # ~400 steps of an explicit pair within ANGLES_NEAR in one interval: a body that
# passes by needs a few, one that falls onto the position (a bicycle lying down) never gets past it


class Crawl(Exception):
    """An interval's stages near a singular position take too many evaluations (CRAWL_CALLS)."""


class StateDerivative:
    """f(t, y) of the run on ``data`` (its Data), y = (q, v) in ``form`` (a
    velocity_form.VelocityForm), with ``baumgarte`` (α, β) or None."""

    def __init__(self, data, baumgarte, form):
        self.data, self.n, self.baumgarte, self.form = data, data.model.n, baumgarte, form
        self.evaluations = 0
        self.jacobians = 0  # Jacobians given to an implicit integrator (``jacobian``)
        self.t_failed = float("nan")  # where the run was when it failed: its last stage or state looked at
        self.non_unique = False
        self.singular = []  # (t, rows) of the interval's stages near a singular position
        self.singular_positions = []  # per interval with such stages: {t_from, t_to, rows}
        self.on_manifold = None  # (t, q, q̇) -> the state on the constraints or None: a step across a singular position
        self.angles = AngleParts(data.model)  # the parts that turn by angles, watched for their singular position
        self.use(None)
        self.begin(0.0, 0.0)

    def use(self, engine):
        """Its motion from the Data's parameter values as they are now (new at a control
        sample), ``engine`` the compiled Engine serving the stages (Data.engine) or None."""
        # the compiled engine's ẏ (compiled/staged.py) where stage_motion would call it anyway: no Motion per stage
        self.staged = None if engine is None or self.baumgarte is not None else engine.stages(self.form.starts)
        # a stage the engine declined goes to the KKT path at once
        self.stage_motion = self.data.stage_motion(self.baumgarte, drift=True, compiled=self.staged is None)

    def begin(self, t, t_next, relaxed=False, may_crawl=True):
        """Count the evaluations from here: an interval from t to t_next; ``relaxed``: it is
        integrated more loosely already (it may crawl longer); ``may_crawl``: False where it
        cannot be relaxed further (SolveError after STUCK_CALLS instead of Crawl)."""
        self.calls, self.t_mark, self.span = 0, t, t_next - t
        self.singular_call = None  # the interval's evaluation count at its first stage near a singular position
        self.may_crawl = may_crawl
        self.crawl_calls = (RELAXED_CRAWL_CALLS if relaxed else CRAWL_CALLS) if may_crawl else STUCK_CALLS
        self.angle_calls = 0  # the interval's evaluations within ANGLES_NEAR of the angles' singular position

    def __call__(self, t, y):
        self.t_failed = t
        if self.on_manifold is not None:  # a step across a singular position (crossing.py)
            y = self._on_manifold(t, y)
        self._count(1, t, y)
        if self.angles and self.angles.nearest(y) < ANGLES_NEAR:
            self.angle_calls += 1
            if self.angle_calls > ANGLES_CRAWL_CALLS:
                raise self._angles_crawl(t, y)
        rates = self._rates(t, y, True)
        self._crawled(t, y)
        return rates

    def step(self, solver):
        """One step of the DOP853 ``solver`` in compiled code (staged.Stages.step: its
        ``_step_impl``'s result), its stages counted as ``__call__`` counts them; None where
        the step is the Python path's: no compiled stages, a step across a singular position
        (``on_manifold``), parts turned by angles (watched per stage), a stage the kernel
        declined."""
        if not self._compiled_steps:
            return None
        self.t_failed = solver.t
        taken, evaluations = self.staged.step(solver)
        self._count(evaluations, solver.t, solver.y)
        self._crawled(solver.t, solver.y)
        return taken

    def extra(self, solver):
        """DOP853's extra stages of the solver's last step in compiled code, as far as the
        kernel takes them (``step``'s conditions); returns how many."""
        if not self._compiled_steps:
            return 0
        done = self.staged.extra(solver, solver.K_extended, solver.n_stages + 1)
        self._count(done, solver.t, solver.y)
        return done

    @property
    def _compiled_steps(self):
        """Whether whole steps may be taken in compiled code: compiled stages, no step across a
        singular position (``on_manifold``), no parts turned by angles (watched per stage)."""
        return self.staged is not None and self.on_manifold is None and not self.angles

    def _count(self, count, t, y):
        """``count`` evaluations more, the last at (t, y); raise the step-size collapse's
        SolveError where COLLAPSE_CALLS more of them moved t too little (module docstring)."""
        before = self.calls
        self.calls += count
        self.evaluations += count
        if self.calls // COLLAPSE_CALLS > before // COLLAPSE_CALLS:
            if abs(t - self.t_mark) < max(COLLAPSE_SPAN * self.span, STEP_RESOLUTION * abs(t)):
                raise self.collapse(t, y, f"{COLLAPSE_CALLS} evaluations moved t by {abs(t - self.t_mark):.3g}")
            self.t_mark = t

    def _crawled(self, t, y):
        """Raise Crawl (or the stuck SolveError) where the interval's evaluations since its
        first stage near a singular position exceed its allowance (module docstring)."""
        if self.singular_call is not None and self.calls - self.singular_call > self.crawl_calls:
            raise Crawl if self.may_crawl else self._stuck(t, y)

    def _rates(self, t, y, noted=False):
        """ẏ at the stage (t, y): the compiled engine's (in the integrator's form) where it
        covers the state (unique, far from singular), else the stage motion's, whose
        non-unique and singular stages are noted where ``noted``; NaN where y is beyond
        MAX_STATE."""
        found = None if self.staged is None else self.staged.rates(t, y)
        if found is not None:
            return found
        if not np.abs(y).max(initial=0.0) <= MAX_STATE:  # a stage of a trial step gone wild (NaN included):
            return np.full(self.form.size, np.nan)  # its error estimate, NaN, makes the integrator reject the step
        q, qd = self.form.to_state(y)
        motion = self.stage_motion(t, q, qd)
        if noted:
            self.non_unique |= not motion.unique
            if motion.singular:
                self.singular.append((t, motion.singular))
                self.singular_call = self.calls if self.singular_call is None else self.singular_call
        return self.form.rates(y, np.concatenate([qd, motion.qdd]))

    def jacobian(self, t, y):
        """∂ẏ/∂y at the state (t, y), the Newton matrix of an implicit integrator (stepper.IMPLICIT):
        forward differences of ``_rates`` — the compiled kernel's motion where it covers the
        state — one evaluation per entry of y, each moved by JACOBIAN_STEP times its size (at
        least 1). Counted in ``evaluations`` and ``jacobians``. Raises SolveError naming the
        coordinates whose columns are not finite (a motion with no derivative there)."""
        y = np.array(y, dtype=float)
        base = self._rates(t, y).copy()
        J = np.empty((y.size, y.size))
        moved = y.copy()
        for j in range(y.size):
            moved[j] = y[j] + JACOBIAN_STEP * max(abs(y[j]), 1.0)
            J[:, j] = (self._rates(t, moved) - base) / (moved[j] - y[j])
            moved[j] = y[j]
        self.evaluations += y.size + 1
        self.jacobians += 1
        bad = ~np.isfinite(J).all(axis=0)
        if bad.any():
            self.t_failed = t
            names = self.form.names(self.data.model.coordinates)
            culprits = [names[j] for j in np.flatnonzero(bad)]
            raise SolveError(f"the Jacobian of the motion an implicit integrator needs is not finite at t = {t:.9g} "
                             f"(by {', '.join(culprits[:6])}): the motion has no derivative there; use an explicit "
                             f"method (DOP853)", coordinates=culprits)
        return J

    def _on_manifold(self, t, y):
        """The stage (t, y) put on the constraints by ``on_manifold`` (as it is where that declines)."""
        if not np.abs(y).max(initial=0.0) <= MAX_STATE:
            return y
        projected = self.on_manifold(t, *self.form.to_state(y))
        return y if projected is None else self.form.to_integrator(projected.q, projected.qd)

    def add_singular(self, t, rows, within):
        """A singular position passed at t (``rows``: its nearly dependent rows) found between
        the stages (singular_watch.py), unless a stage came near one within ``within`` of t."""
        listed = [(e["t_from"], e["t_to"]) for e in self.singular_positions] + [(u, u) for u, _ in self.singular]
        if not any(t_from - within <= t <= t_to + within for t_from, t_to in listed):
            self.singular.append((t, rows))

    def note_singular(self):
        """One entry of ``singular_positions`` for the stages of the interval just done (an
        entry it overlaps, a crossing found between the stages and then integrated again,
        takes it in)."""
        if self.singular:
            times = [t for t, _ in self.singular]
            rows = {r for _, names in self.singular for r in names}
            t_from, t_to = min(times), max(times)
            self.singular = []
            for entry in self.singular_positions:
                if entry["t_from"] <= t_to and t_from <= entry["t_to"]:
                    entry.update(t_from=min(t_from, entry["t_from"]), t_to=max(t_to, entry["t_to"]),
                                 rows=sorted(rows | set(entry["rows"])))
                    return
            self.singular_positions.append(dict(t_from=t_from, t_to=t_to, rows=sorted(rows)))
            log.info("singular position near t = %.6g (nearly dependent rows %s)", t_from, ", ".join(sorted(rows)))

    def _stuck(self, t, y):
        """The SolveError of an interval that crawls near a singular position of the rows
        at the loosest tolerance."""
        self.t_failed = t
        rows = sorted({r for _, names in self.singular for r in names})
        return SolveError(f"the steps crawl near a singular position of the constraints ({STUCK_CALLS} evaluations "
                          f"of this interval at the loosest tolerance; nearly dependent rows "
                          f"{', '.join(rows)}){self._angles_note(y[:self.n])}",
                          constraints=rows)

    def _angles_crawl(self, t, y):
        """The SolveError of a crawl at the singular position of a part's angles, at (t, y)."""
        self.t_failed = t
        near = self.angles.near(y[:self.n], ANGLES_NEAR)
        return SolveError(f"the steps crawl at the singular position of a part's angles ({ANGLES_CRAWL_CALLS} "
                          f"evaluations of this interval within {ANGLES_NEAR:g} of it): "
                          f"{explain(near, 'approaching')}",
                          coordinates=[a.coordinate for a in near])

    def _angles_note(self, q):
        """'; ' and the parts whose angles are within ANGLES_NEAR of their singular position at
        q (what a collapse there chases), or ''."""
        near = self.angles.near(q, ANGLES_NEAR) if self.angles else []
        return f"; {explain(near, 'near')}" if near else ""

    def collapse(self, t, y, why):
        """The SolveError of a step-size collapse at (t, y), naming the coordinates of the
        largest accelerations (within a factor 10 of the largest): what the steps chase."""
        self.t_failed = t
        data = self.data
        qdd = np.abs(data.motion(t, *self.form.to_state(y), baumgarte=self.baumgarte, drift=True).qdd)
        fastest = [(c, a) for c, a in zip(data.model.coordinates, qdd) if a >= qdd.max() / 10]
        return SolveError(f"step-size collapse, the integrator gave up ({why}); fastest changing: "
                          f"{', '.join(f'{c} (q̈ = {a:.3g})' for c, a in fastest)}{self._angles_note(y[:self.n])}",
                          coordinates=[c for c, _ in fastest])

    def check(self, t, q, qd):
        """Raise SolveError naming the coordinates where the state (q, q̇) is not finite or
        beyond MAX_STATE."""
        if largest(q) <= MAX_STATE and largest(qd) <= MAX_STATE:  # not if NaN (largest gives NaN then)
            return
        self.t_failed = t
        y = np.concatenate([q, qd])
        names = [*self.data.model.coordinates, *(c + "_dot" for c in self.data.model.coordinates)]
        culprits = [names[i] for i in np.flatnonzero(~np.isfinite(y) | (np.abs(y) > MAX_STATE))]
        raise SolveError(f"the state is not finite or exploded (|value| > {MAX_STATE:g}) in "
                         f"{', '.join(culprits[:6])}{self._angles_note(np.nan_to_num(q))}", coordinates=culprits)

