"""Motion over time: integrate (q, q̇) with q̈ from (2.14), keeping the constraints.

The accelerations satisfy the constraints only at the acceleration level (2.4), so
positions and velocities drift. ``simulate`` steps one of scipy's adaptive integrators
(its OdeSolver classes, as ``solve_ivp`` would) in one of two ways.

Continuously, where the compiled kernel can put a state back on the constraints itself
(compiled/correction.py: a tree of kernel joints and bodies, no loops) and the default
``stabilization="projection"`` asks for it, with an explicit Runge–Kutta pair (RK23, RK45,
DOP853): the steps are chosen by the error control alone, up to the next control sample
or the end; each accepted step is corrected and the integrator goes on from there, given
the corrected state's derivative, its steps capped (``max_step``) to keep the drift
between corrections below DRIFT_TARGET (drift.py); each output row is read from the step's dense
output (the interpolant ``solve_ivp`` gives at ``t_eval``) and corrected (a copy: the
integrator goes on from its own state), the rows a step passed in one block with its
end (correction.Correction.block, on all cores).

Cut at each output time otherwise: the integrator's last step is cut short there and,
with projection, (q, q̇) projected back onto the constraints (projection.py), there and
between output times as often as keeps the drift below DRIFT_TARGET. The integrator is
not restarted: an explicit pair goes on from the projected state, given its derivative,
with the step it proposed before the cut (``_Run._resumed``); an implicit one (Radau,
BDF, LSODA) starts afresh with that step. ``"baumgarte"`` replaces b by
b − 2α φ̇ − β² φ (Baumgarte 1972), its drift growing with the step; ``"none"`` does
neither.

Consistency is judged where it means something. The integrator's stages lie off the
manifold by the integration error, so the motion there follows the drift rule of
``equations`` (least squares where the drift explains an inconsistency of b, as with
dependent rows whose dependency changes with the configuration — Bricard's mechanism —
and nearly dependent directions near a singular position set aside). At each projected
output state the constraints are judged strictly: a real contradiction raises
SolveError there. ``stats["singular_positions"]`` lists the output intervals in which a
stage came near a singular position (σ < 1e-5 σ₁ of the equilibrated A: the drift rule's
zone); a crossing whose stages all stay farther from it needs no special treatment and
may go unlisted. There the stages' accelerations carry noise of about |q̇| ψ / σ² (ψ the
velocity drift the projection leaves, about 1e-12): a tolerance tighter than that noise
allows makes the integrator crawl. A span (a continuous run: its output interval) that
takes more than CRAWL_CALLS evaluations after its first stage near a singular position is
integrated again, cut, at RELAXED_RTOL (atol relaxed by the same factor; ten times
looser again while it crawls still — RELAXED_CRAWL_CALLS evaluations after its first
stage there — up to RELAXED_MAX) and listed in ``stats["relaxed_spans"]``.
"""

import bisect
import logging
import time

import numpy as np
import scipy.integrate

from .control import SampledControl
from ..core.errors import SimulationError, SolveError
from . import stepper
from .drift import next_cap
from .projection import consistent_initial_state, project, relative_drift
from .recording import Recorder
from .trajectory import COMPLETED

log = logging.getLogger(__name__)

STABILIZATIONS = ("projection", "baumgarte", "none")
DEFAULT_OUTPUTS = 500
MAX_STATE = 1e12  # a coordinate or velocity beyond this counts as an exploding state
# a step-size collapse: COLLAPSE_CALLS evaluations (~80 steps) advance t by less than
# COLLAPSE_SPAN of the output interval, or than 1e4 ε |t| (steps near the resolution of t);
# scipy would crawl on for minutes at that step size before it gives up by itself
COLLAPSE_CALLS = 1000
COLLAPSE_SPAN = 1e-8
# near a singular position the stages' accelerations carry noise of about |q̇| ψ / σ² (ψ the
# velocity drift, σ the smallest singular value of A), which a tight tolerance chases with
# ever smaller steps: a span whose stages came near one (Motion.singular) and then took
# more than CRAWL_CALLS evaluations is integrated again at RELAXED_RTOL (atol alike), and
# again ten times looser each time it crawls still, up to RELAXED_MAX. Each loosening costs
# accuracy where it counts (a crossing of a singular position loses energy with each factor
# of ten): a span already relaxed gets RELAXED_CRAWL_CALLS
CRAWL_CALLS = 240
RELAXED_CRAWL_CALLS = 1000
RELAXED_RTOL = 1e-8
RELAXED_MAX = 1e-7


def simulate(system, t_end, *, t0=0.0, q0=None, qd0=None, dt=None, method="DOP853", rtol=1e-10, atol=1e-10,
             stabilization="projection", baumgarte=(10.0, 10.0), out=None, progress=None, controller=None,
             control_dt=None):
    """Integrate ``system`` from t0 to t_end; returns a Trajectory with one row per output time
    (and the model's declared outputs: mbsynth.model.outputs).

    q0, qd0: the initial state (default: the model's, made consistent by projection
    keeping every value the model sets; the changes are logged and kept in
    ``stats["initial_changes"]``). dt: output interval (default (t_end − t0)/500).
    method, rtol, atol: the integrator (a ``solve_ivp`` method name or a scipy OdeSolver class)
    and its tolerances. out: a .npz or .csv path written as
    the run goes. progress: a callable(t) called at every output time.
    controller: ``f(t, joint_values) -> {parameter: value}``, called at t0 and every
    ``control_dt`` (default: the output interval), its values held in between (sampled
    control, mbsynth.analysis.control).
    Raises SimulationError (with the partial trajectory) when the run cannot go on.
    """
    if stabilization not in STABILIZATIONS:
        raise ValueError(f"stabilization must be one of {STABILIZATIONS}, got {stabilization!r}")
    method = _integrator(method)
    if not t_end > t0:
        raise ValueError(f"t_end ({t_end}) must be after t0 ({t0})")
    data = system.data()  # the run's workspace: one motion path (compiled or KKT) for the whole run
    run = _Run(data, method, rtol, atol, stabilization, baumgarte)
    if q0 is None and qd0 is None:
        q, qd, changes = consistent_initial_state(data, t0)
        for name, (given, new) in changes.items():
            log.info("initial %s: %.12g -> %.12g (made consistent with the constraints)", name, given, new)
    else:
        start_q, start_qd = system.initial_state()
        q = start_q if q0 is None else np.asarray(q0, dtype=float)
        qd = start_qd if qd0 is None else np.asarray(qd0, dtype=float)
        changes = {}
    times = _output_times(t0, t_end, dt)
    control = None if controller is None else SampledControl(controller, control_dt or times[1] - times[0])
    samples = set() if control is None else set(control.times(t0, t_end))
    outputs = set(times)
    recorder = Recorder(data, out)
    started = time.perf_counter()
    status = "stopped"
    try:
        if control is not None:
            control.apply(data, t0, q, qd)
            run.restart()
        recorder.record(t0, q, qd, run.correction, run.compiled_energy)
        run.t_now = t0
        stops = sorted(samples | {times[-1]})  # where a continuous integrator stops: the forces jump, or the run ends
        run.times = sorted(outputs | samples)
        for t_next in run.times[1:]:
            q, qd = run.advance(t_next, q, qd, stops[bisect.bisect_left(stops, t_next)])
            if t_next in samples:
                control.apply(data, t_next, q, qd)
                run.restart()
            if t_next in outputs:
                at_hand = () if t_next in samples else (run.arrays, run.corrected)  # a sample's parameters are new
                recorder.record(t_next, q, qd, run.correction, run.compiled_energy, *at_hand)
                if progress is not None:
                    progress(t_next)
        status = COMPLETED
    except SolveError as err:
        status = f"failed at t = {run.t_failed:.9g}: {err}"
        raise SimulationError(f"run stopped at t = {run.t_failed:.9g} (last good state saved at "
                              f"t = {recorder.t[-1]:.9g}): {err}", time=run.t_failed,
                              trajectory=_trajectory(recorder, run, status),
                              constraints=err.constraints, coordinates=err.coordinates) from None
    except KeyboardInterrupt:
        status = f"interrupted at t = {recorder.t[-1]:.9g}"
        raise
    finally:
        recorder.close(status)
    traj = _trajectory(recorder, run, status)
    traj.stats.update(wall_time=time.perf_counter() - started, initial_changes=changes)
    return traj


def _trajectory(recorder, run, status):
    """The rows recorded, with the run's counts."""
    traj = recorder.trajectory(status)
    traj.stats.update(run.stats())
    return traj


def _integrator(method):
    """The OdeSolver class of ``method``: a ``solve_ivp`` method name or such a class."""
    if isinstance(method, type) and issubclass(method, scipy.integrate.OdeSolver):
        return method
    if method not in stepper.METHODS:
        raise ValueError(f"method must be one of {', '.join(stepper.METHODS)} (or a scipy OdeSolver class), "
                         f"got {method!r}")
    return stepper.METHODS[method]


def _output_times(t0, t_end, dt):
    if dt is None:
        return np.linspace(t0, t_end, DEFAULT_OUTPUTS + 1)
    if not dt > 0:
        raise ValueError(f"dt must be positive, got {dt}")
    times = np.arange(t0, t_end, dt)
    return np.append(times, t_end) if t_end - times[-1] > 1e-12 * dt else np.append(times[:-1], t_end)


class _Run:
    """One integration: its settings, the integrator and its drift control, and its counts
    (the rows are the Recorder's, recording.py). ``system`` is the run's Data (data.py),
    which reads as its System."""

    def __init__(self, data, method, rtol, atol, stabilization, baumgarte):
        self.system, self.method, self.rtol, self.atol = data, method, rtol, atol
        self.stabilization = stabilization
        self.baumgarte = baumgarte if stabilization == "baumgarte" else None
        self.restart()
        self.n = data.n
        self.steps = self.evaluations = 0
        self.solver = None  # the integrator, kept from span to span (``_resumed``, ``_reach``)
        self.times = []  # the times ``advance`` is called for, in order (outputs and control samples)
        self.passed = {}  # a continuous integrator's states at the times its last step passed ({t: y})
        self.solver_tolerances = None  # its (rtol, atol)
        self.arrays = None  # the ConstraintArrays at the state ``advance`` reached, if at hand
        self.corrected = None  # the kernel's correction.Corrected there, if at hand
        self.next_step = None  # the step it proposed after its last step not cut short at a span's end
        self.t_failed = float("nan")
        self.t_now = None  # the time the state has reached (outputs and control samples alike)
        self.non_unique = False
        self.calls, self.t_mark, self.span = 0, 0.0, 0.0
        self.drift_span = np.inf  # the cap on a span between projections (drift.next_cap; np.inf: none)
        self.singular = []  # (t, rows) of the stages near a singular position (Motion.singular)
        self.singular_positions = []  # per output interval with such stages: {t_from, t_to, rows}
        self.singular_call = None  # the span's evaluation count at its first stage near a singular position
        self.span_rtol = rtol  # the rtol the span under way is integrated at
        self.crawl_calls = CRAWL_CALLS  # the evaluations it may take near a singular position (_Crawl)
        self.relaxed_spans = []  # {t_from, t_to, rtol, atol} of the spans integrated again, more loosely

    def restart(self):
        """Go on from the Data's parameter values (new at a control sample: the forces jump,
        so the integrator starts afresh): its stages' motion, and its compiled correction
        where the kernel covers it (then integrated continuously, with an explicit pair and
        projection)."""
        system, self.forces_jumped = self.system, True  # the integrator's f at its state is stale
        self.stage_motion = system.stage_motion(self.baumgarte, drift=True)
        engine = system.tree_engine(True)
        # the compiled engine's (q̇, q̈) where stage_motion would call it anyway: no Motion per stage
        self.derivative = None if engine is None or self.baumgarte is not None else engine.derivative
        self.correction = None if engine is None else engine.correction()
        self.continuous = self.correction is not None and issubclass(self.method, stepper.RESUMABLE) \
            and self.stabilization == "projection"
        self.compiled_energy = self.correction is not None and all(f.V == 0 for f in system.forces)

    def rhs(self, t, y):
        self.t_failed = t
        self.calls += 1
        self.evaluations += 1
        if self.calls % COLLAPSE_CALLS == 0:
            if abs(t - self.t_mark) < max(COLLAPSE_SPAN * self.span, 1e4 * np.finfo(float).eps * abs(t)):
                raise self._collapse(t, y, f"{COLLAPSE_CALLS} evaluations moved t by {abs(t - self.t_mark):.3g}")
            self.t_mark = t
        found = None if self.derivative is None else self.derivative(t, y)  # unique, far from singular
        if found is None:
            q, qd = y[:self.n], y[self.n:]
            motion = self.stage_motion(t, q, qd)
            self.non_unique |= not motion.unique
            if motion.singular:
                self.singular.append((t, motion.singular))
                self.singular_call = self.calls if self.singular_call is None else self.singular_call
            found = np.concatenate([qd, motion.qdd])
        if self.singular_call is not None and self.calls - self.singular_call > self.crawl_calls \
                and self.span_rtol < RELAXED_MAX:
            raise _Crawl
        return found

    def advance(self, t_next, q, qd, t_stop):
        """The state at t_next from (q, q̇) at the time reached (``t_now``), checked and
        projected if asked. A continuous integrator (``_reach``) may go on to t_stop (the
        next control sample or the end), (q, q̇) only starting it; an output interval in
        which it crawls near a singular position, or fails, is integrated again from
        (q, q̇), cut at t_next (``_advance_cut``): a failure is then reported in the interval
        it happens in, the rows before it kept."""
        if not self.continuous:
            return self._advance_cut(t_next, q, qd)
        try:
            y, corrected, bounded = self._reach(t_next, q, qd, t_stop)
        except (_Crawl, SolveError) as stop:
            self.solver = None  # stopped within a step
            q, qd = self._advance_cut(t_next, q, qd, loosen=isinstance(stop, _Crawl))
            self.solver = None  # the continuous integrator starts afresh from t_next
            return q, qd
        if not bounded:
            self._check(t_next, y)
        q, qd = self._on_constraints(t_next, y, corrected)
        return self._arrived(t_next, q, qd, None, corrected)

    def _reach(self, t_next, q, qd, t_stop):
        """The continuous integrator's state at t_next, its correction and whether it is
        finite and within MAX_STATE (``_step``): its
        steps taken until one reaches or passes t_next. A new integrator (at the start,
        after a control sample or a cut interval) starts from (q, q̇) at ``t_now``, its
        first step the one last proposed."""
        self._begin_interval(self.t_now, t_next, self.rtol)
        solver = self.solver
        if solver is None or self.forces_jumped:
            first = None if self.next_step is None else min(self.next_step, t_stop - self.t_now)
            solver = self.solver = self.method(self.rhs, self.t_now, np.concatenate([q, qd]), t_stop,
                                               rtol=self.rtol, atol=self.atol, first_step=first)
            self.solver_tolerances, self.passed, self.forces_jumped = (self.rtol, self.atol), {}, False
        while solver.t < t_next:
            self._step(solver, t_next)
        return self.passed[t_next]

    def _step(self, solver, t_next):
        """One accepted step of the continuous integrator, its state then corrected, and with
        it, in one block (correction.Correction.block), the states at the times from t_next
        to where it reached, read from its interpolant: ``passed`` keeps (state, Corrected
        or None, whether the state is within MAX_STATE: ``_check``) per time. The step is
        capped (``max_step``) to keep the drift between corrections below DRIFT_TARGET:
        halved after a larger drift, doubled after one below a hundredth of it; a step that
        drifted more than DRIFT_REDO × DRIFT_TARGET is taken again at a quarter of its length."""
        start = stepper.saved(solver)
        message = solver.step()
        if solver.status == "failed":
            self.t_failed = solver.t
            raise self._collapse(solver.t, solver.y, (message or "the integrator failed").rstrip("."))
        self.steps += 1
        taken = solver.t - start[0]
        if solver.t != solver.t_bound or self.next_step is None:  # a step cut at the bound proposes less
            self.next_step = solver.h_abs
        self._check(solver.t, solver.y)
        q, qd = solver.y[:self.n], solver.y[self.n:]
        redo, cap = next_cap(self.correction.drift(q, qd), taken, solver.max_step, solver.t_bound - solver.t,
                             self.span)
        if redo:
            stepper.rewind(solver, start, cap)
            self.steps -= 1
            return
        stepper.cap(solver, cap)
        times = self.times[bisect.bisect_left(self.times, t_next):bisect.bisect_left(self.times, solver.t)]
        states = np.empty((len(times) + 1, solver.y.size))
        if times:
            stepper.interpolate(solver, times, states[:-1])
        states[-1] = solver.y
        corrected = self.correction.block(states[:, :self.n], states[:, self.n:])
        bounded = np.abs(states).max(axis=1, initial=0.0) <= MAX_STATE  # per row, at once (False where NaN)
        self.passed = dict(zip([*times, solver.t], zip(states, corrected, bounded)))
        q_on, qd_on = self._on_constraints(solver.t, solver.y, corrected[-1])
        if not (np.array_equal(q_on, q) and np.array_equal(qd_on, qd)):
            y = np.concatenate([q_on, qd_on])
            stepper.move(solver, y, self.rhs(solver.t, y))

    def _on_constraints(self, t, y, corrected):
        """(q, q̇) of the state y on the constraints: ``corrected``'s where the kernel's
        correction put it there (correction.Corrected), else projected (projection.py)."""
        return project(self.system, t, y[:self.n], y[self.n:]) if corrected is None else corrected[:2]

    def _advance_cut(self, t_next, q, qd, loosen=False):
        """Integrate to t_next, check the state, project it if asked. With projection the
        interval is cut into spans short enough that the state drifts off the manifold by
        at most DRIFT_TARGET (relative, projection.relative_drift) between projections: the
        span halves after a larger drift and doubles after one below a hundredth of it; a
        span that drifted more than DRIFT_REDO × DRIFT_TARGET is integrated again in
        quarters (the least-squares motion of the stages is only as good as their drift)."""
        t = self.t_now
        interval = t_next - t
        while t < t_next:
            t_to = t_next if t + 1.5 * self.drift_span >= t_next else t + self.drift_span
            q_to, qd_to = self._integrate(t, t_to, q, qd, loosen)
            arrays = None
            if self.stabilization == "projection":
                self.t_failed = t_to
                arrays = self.system.constraint_arrays(t_to, q_to, qd_to, sparse=None)
                drift = relative_drift(self.system, t_to, q_to, qd_to, arrays)
                redo, self.drift_span = next_cap(drift, t_to - t, self.drift_span, interval, interval)
                if redo:
                    continue
                q_on, qd_on = project(self.system, t_to, q_to, qd_to, arrays=arrays)
                if not (np.array_equal(q_on, q_to) and np.array_equal(qd_on, qd_to)):
                    q_to, qd_to, arrays = q_on, qd_on, None
            t, q, qd = t_to, q_to, qd_to
        return self._arrived(t_next, q, qd, arrays)

    def _arrived(self, t_next, q, qd, arrays, corrected=None):
        """The state reached at t_next (``arrays``: its ConstraintArrays, if at hand), judged
        strictly there with projection, unless the kernel ``corrected`` it (its checks passed
        there already; correction.Corrected, with the rows there)."""
        self._note_singular()
        if self.stabilization == "projection" and corrected is None:
            self.system.motion(t_next, q, qd)  # on the manifold: a contradiction raises here
        self.t_now = t_next
        self.arrays = arrays  # the ConstraintArrays at the state reached, if at hand (for ``record``)
        self.corrected = corrected  # its Corrected, if at hand (for ``record``)
        return q, qd

    def _integrate(self, t, t_next, q, qd, loosen=False):
        """The integrator from (t, q, q̇) to t_next; the state at t_next, checked. A span that
        crawls near a singular position (CRAWL_CALLS) is integrated again at a looser
        tolerance: RELAXED_RTOL, then ten times looser each time, up to RELAXED_MAX
        (``loosen``: it crawled already, integrated continuously)."""
        rtol, atol, proposed = self.rtol, self.atol, self.next_step
        if loosen:
            rtol, atol = _looser(rtol, atol)
        while True:
            try:
                y = self._span(t, t_next, np.concatenate([q, qd]), rtol, atol)
                break
            except _Crawl:
                self.solver, self.next_step = None, proposed  # stopped within a step; its steps are no guide
                rtol, atol = _looser(rtol, atol)
        if rtol != self.rtol:
            self.relaxed_spans.append(dict(t_from=t, t_to=t_next, rtol=rtol, atol=atol))
            log.info("near a singular position between t = %.6g and %.6g: integrated at rtol %g, atol %g",
                     t, t_next, rtol, atol)
        self._check(t_next, y)
        return y[:self.n], y[self.n:]

    def _begin_interval(self, t, t_next, rtol):
        """Count the evaluations from here (the collapse and crawl checks): an interval from t
        to t_next, integrated at rtol."""
        self.calls, self.t_mark, self.span = 0, t, t_next - t
        self.singular_call, self.span_rtol = None, rtol
        self.crawl_calls = CRAWL_CALLS if rtol == self.rtol else RELAXED_CRAWL_CALLS  # a relaxed span crawls longer

    def _span(self, t, t_next, y, rtol, atol):
        """The integrator's steps from (t, y) to t_next (its last step cut short there)."""
        self._begin_interval(t, t_next, rtol)
        solver = self._resumed(t, y, t_next, rtol, atol)
        while solver.status == "running":
            message = solver.step()
            if solver.status == "failed":
                self.t_failed = solver.t
                raise self._collapse(solver.t, solver.y, (message or "the integrator failed").rstrip("."))
            self.steps += 1
            if solver.t != t_next:
                self.next_step = solver.h_abs
        return solver.y.copy()

    def _resumed(self, t, y, t_bound, rtol, atol):
        """The integrator at (t, y), bound for t_bound, its first step the one it proposed
        before the last span's end cut its step short: the same integrator where it can go
        on from there (stepper.RESUMABLE, at the same tolerances; given y's derivative where the
        state was moved, by a projection), else (also where the forces jumped, at a control
        sample) a new one, as ``solve_ivp`` would start it."""
        first = None if self.next_step is None else min(self.next_step, t_bound - t)
        solver = None if self.forces_jumped else self.solver  # a control sample: a new integrator
        self.forces_jumped = False
        if isinstance(solver, stepper.RESUMABLE) and solver.t == t and self.solver_tolerances == (rtol, atol):
            if not np.array_equal(solver.y, y):
                stepper.move(solver, y, self.rhs(t, y))
            stepper.resume(solver, t_bound, first)
            return solver
        self.solver = self.method(self.rhs, t, y, t_bound, rtol=rtol, atol=atol, first_step=first)
        self.solver_tolerances = (rtol, atol)
        return self.solver

    def _note_singular(self):
        """One entry of ``singular_positions`` for the stages of the interval just done."""
        if self.singular:
            times = [t for t, _ in self.singular]
            rows = sorted({r for _, names in self.singular for r in names})
            self.singular_positions.append(dict(t_from=min(times), t_to=max(times), rows=rows))
            log.info("singular position near t = %.6g (nearly dependent rows %s)",
                     min(times), ", ".join(rows))
            self.singular = []

    def _collapse(self, t, y, why):
        """The SolveError of a step-size collapse at (t, y), naming the coordinates of the
        largest accelerations (within a factor 10 of the largest): what the steps chase."""
        qdd = np.abs(self.system.motion(t, y[:self.n], y[self.n:], baumgarte=self.baumgarte, drift=True).qdd)
        fastest = [(c, a) for c, a in zip(self.system.coordinates, qdd) if a >= qdd.max() / 10]
        return SolveError(f"step-size collapse, the integrator gave up ({why}); fastest changing: "
                          f"{', '.join(f'{c} (q̈ = {a:.3g})' for c, a in fastest)}",
                          coordinates=[c for c, _ in fastest])

    def _check(self, t, y):
        if np.abs(y).max(initial=0.0) <= MAX_STATE:  # false where any is NaN
            return
        self.t_failed = t
        names = [c for c in self.system.coordinates] + [c + "_dot" for c in self.system.coordinates]
        culprits = [names[i] for i in np.flatnonzero(~np.isfinite(y) | (np.abs(y) > MAX_STATE))]
        raise SolveError(f"the state is not finite or exploded (|value| > {MAX_STATE:g}) in "
                         f"{', '.join(culprits[:6])}", coordinates=culprits)

    def stats(self):
        """The run's counts for ``Trajectory.stats``."""
        if self.non_unique:
            log.warning("the motion was not unique somewhere on this run; the free directions got zero "
                        "acceleration (η = 0 in (2.14))")
        return dict(steps=self.steps, evaluations=self.evaluations, non_unique=self.non_unique,
                    singular_positions=self.singular_positions, relaxed_spans=self.relaxed_spans)


def _looser(rtol, atol):
    """The next tolerances of a span that crawls: RELAXED_RTOL, then ten times looser, up to
    RELAXED_MAX (atol alike)."""
    looser = min(max(RELAXED_RTOL, 10 * rtol), RELAXED_MAX)
    return looser, atol * looser / rtol


class _Crawl(Exception):
    """A span's stages near a singular position take too many evaluations (CRAWL_CALLS)."""
