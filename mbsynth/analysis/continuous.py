"""The continuous strategy of the run loop: every run with ``stabilization="projection"``
and an explicit Runge–Kutta pair (RK23, RK45, DOP853) or Radau IIA (stepper.movable).

The steps are chosen by the error control alone, up to the next control sample or the end;
each accepted step is put back on the constraints and the integrator goes on from there,
given that state's derivative, its steps capped (``max_step``) to keep the drift between
projections below DRIFT_TARGET (drift.py). Each output row is read from the step's dense
output (the interpolant ``solve_ivp`` gives at ``t_eval``) and put back on the constraints
too (a copy: the integrator goes on from its own state). Where the compiled kernel covers
the model (compiled/projection.py: kernel joints and bodies, in a tree or closing loops; or
compiled/extra_projection.py: a small model of extra coordinates alone) it projects the rows
a step passed in one block with its end (``block``, on all cores where it threads);
elsewhere each state is projected (projection.py) and judged strictly there
(Integration.arrived), and a model with no rows has nothing to project. An output interval
in which the integrator crawls near a singular position, or fails, is integrated again,
cut (cut.py), from the last output: a failure is then reported in the interval it happens
in, the rows before it kept. Where the kernel projects the states and the run's singular
watch or the projection measures how near the rows are to losing rank, a singular position
seen coming is crossed by one planned step whose stages keep away from it and are put on
the constraints first (crossing.py): no crawl.
"""

import bisect
import contextlib
from typing import NamedTuple

import numpy as np
from numba import njit

from . import stepper
from ..core.errors import EventError, SolveError
from .crossing import NAMED_SHARE, Crossing
from .cut import CutIntegration
from .derivative import Crawl
from .drift import next_cap
from .projection import project, relative_drift
from .singular_watch import SingularWatch
from ..compiled.rows import largest
from ..core.tolerances import MAX_STATE, RELAXED_MAX


class Passed(NamedTuple):
    """The states a step passed: at ``times`` (the output times and control samples it
    passed, then its end) the integrator's ``states`` (rows of y), their projections
    (ProjectedRows, or None where the kernel projects nothing) and whether each is within
    MAX_STATE (``bounded``)."""

    times: list
    states: np.ndarray
    projected: object
    bounded: np.ndarray

    def index(self, t):
        """The row at the time t, or None where the step passed no such time."""
        i = bisect.bisect_left(self.times, t)
        return i if i < len(self.times) and self.times[i] == t else None

    def at(self, t):
        """(y, Projected or None, bounded) at the time t (one the step passed)."""
        i = self.index(t)
        return self.states[i], None if self.projected is None else self.projected.row(i), self.bounded[i]


class ContinuousIntegration(CutIntegration):
    """Integration by the error control alone, each step projected (integration.py); an
    interval it cannot do is done cut (CutIntegration.advance)."""

    @staticmethod
    def fits(method, stabilization):
        """Whether a run with the OdeSolver class ``method`` and ``stabilization`` can be
        integrated continuously."""
        return stepper.movable(method) and stabilization == "projection"

    def __init__(self, *args):
        self.passed = None  # the states at the times the last step passed (Passed)
        super().__init__(*args)
        self.has_rows = len(self.data.system.constraint_names) > 0
        self.watch = None  # the singular positions passed between stages (singular_watch.py), on projected runs
        self.crossing = None  # the step plan near singular positions (crossing.py)

    def advance(self, t_next, q, qd, t_stop):
        try:
            y, projected, bounded = self._reach(t_next, q, qd, t_stop)
        except (Crawl, SolveError) as stop:
            if isinstance(stop, EventError):  # found where it happens: no cut interval avoids it
                raise
            self.solver = None  # stopped within a step
            q, qd = super().advance(t_next, q, qd, loosen=isinstance(stop, Crawl))
            self.solver = None  # the continuous integrator starts afresh from t_next
            return q, qd
        if bounded and projected is not None:  # the kernel's projection holds the state on the constraints
            return self.arrived(t_next, projected.q, projected.qd, None, projected)
        q, qd = self.form.to_state(y)
        if not bounded:
            self.f.check(t_next, q, qd)
        q, qd = self._on_constraints(t_next, q, qd, projected)
        return self.arrived(t_next, q, qd, None, projected)

    def _reach(self, t_next, q, qd, t_stop):
        """The state at t_next, its projection and whether it is finite and within MAX_STATE:
        the integrator's steps taken until one reaches or passes t_next. At the start, after a
        control sample or a cut interval it goes on from (q, q̇) at ``t_now`` towards t_stop
        (Integration.resumed)."""
        self.f.begin(self.t_now, t_next, may_crawl=self.rtol < RELAXED_MAX)
        solver = self.solver
        if solver is None or self.forces_jumped:
            if solver is None:
                self._watch_from(self.t_now, q, qd)
            solver = self.resumed(self.t_now, q, qd, t_stop, self.rtol, self.atol)
            self.passed = None
        while solver.t < t_next:
            self._step(solver, t_next)
        return self.passed.at(t_next)

    def ready(self):
        """(times, ProjectedRows) of the output rows after ``t_now`` that the last step passed
        and projected, up to the first one that needs more (a state not projected or beyond
        MAX_STATE, the step's end, a control sample), taken as arrived; None where there are
        none: ``simulate`` records them at once."""
        passed = self.passed
        start = None if passed is None else passed.index(self.t_now)
        if start is None or passed.projected is None:
            return None
        start += 1
        ok = passed.projected.done[start:-1] & passed.bounded[start:-1]  # the step's end is not a row here
        stop = start + (int(np.argmin(ok)) if not ok.all() else ok.size)
        if stop == start:
            return None
        rows = passed.projected
        self.f.note_singular()
        self.t_now, self.arrays, self.projected = passed.times[stop - 1], None, rows.row(stop - 1)
        return passed.times[start:stop], rows.part(start, stop)

    def _step(self, solver, t_next):
        """One accepted step, its state then projected, and with it, in one block
        (projection.Projection.block), the states at the times from t_next to where it
        reached, read from its interpolant: ``passed`` keeps (state, Projected or None,
        whether the state is within MAX_STATE) per time. The step is capped (``max_step``) to
        keep the drift between projections below DRIFT_TARGET: halved after a larger drift,
        doubled after one below a hundredth of it; a step that drifted more than
        DRIFT_REDO × DRIFT_TARGET is taken again at a quarter of its length. Near a singular
        position the step is aimed where ``crossing`` plans it, and the step across it
        evaluates its stages on the constraints (crossing.py). A step that reaches the bound
        (a control sample or the end) leaves f at the projected state to be computed when
        the integrator goes on (Integration.resumed)."""
        start = stepper.saved(solver)
        target, across = (None, False) if self.crossing is None else \
            self.crossing.plan(solver.t, min(stepper.proposed_step(solver), solver.max_step), solver.t_bound)
        self._take(solver, t_next, start, target, across)
        if across and solver.t == target and self.watch is None:  # crossed: the watch would have found it
            self._list_crossing(solver, start[0])

    def _list_crossing(self, solver, t_start):
        """List the singular position the step from t_start just crossed: at t*, where the
        measure falls to zero on a line through the step's ends on either side of it
        (Crossing.crossed), with the rows of the least direction of the state there, read
        from the step's interpolant and put on the constraints (those of weight above
        NAMED_SHARE of the largest: t* is known to the line's accuracy, and off it the
        least direction mixes in others)."""
        t_star = self.crossing.crossed()
        y = np.empty((1, solver.y.size))
        with self._stages_on_manifold(True):  # the interpolant's extra stages, as the step's
            stepper.interpolate(solver, [t_star], y)
        q, qd = self.form.to_state(y[0])
        on = self.projection(t_star, q, qd)
        rows = self.projection.least_rows(t_star, *((q, qd) if on is None else on[:2]), NAMED_SHARE)
        names = self.data.system.constraint_names
        self.f.add_singular(t_star, tuple(names[r] for r in rows), solver.t - t_start)

    def _stages_on_manifold(self, across):
        """A context within which, where ``across`` (a step across a singular position), each
        stage is put on the constraints by the kernel's projection before its motion is
        evaluated (elsewhere nothing changes)."""
        return self._projected_stages() if across else contextlib.nullcontext()

    @contextlib.contextmanager
    def _projected_stages(self):
        """Within: each stage put on the constraints by the kernel's projection."""
        self.f.on_manifold = self.projection  # called with (t, q, q̇)
        try:
            yield
        finally:
            self.f.on_manifold = None

    def _take(self, solver, t_next, start, target, across):
        """``_step``'s step from ``start`` (stepper.saved), aimed at ``target`` (or None),
        across a singular position where ``across``."""
        with self._stages_on_manifold(across):
            message = solver.step() if target is None else stepper.step_to(solver, target)
        if solver.status == "failed":
            raise self.failed_step(solver, message)
        self.steps += 1
        taken = solver.t - start[0]
        if solver.t != solver.t_bound or self.next_step is None:  # a step cut at the bound proposes less
            self.next_step = stepper.proposed_step(solver)
        q, qd = self.form.to_state(solver.y)
        self.f.check(solver.t, q, qd)
        drift, arrays = self._drift(solver.t, q, qd, taken)
        redo, cap = next_cap(drift, taken, solver.max_step, solver.t_bound - solver.t, self.f.span, self.drift_target)
        if redo:
            stepper.rewind(solver, start, cap)
            self.steps -= 1
            return
        if self.event_in(solver, start, target):  # taken again up to the event (impacts.py)
            stepper.rewind(solver, start, solver.max_step)
            self.steps -= 1
            return
        stepper.cap(solver, cap)
        times = self.schedule.between(t_next, solver.t)
        states = np.empty((len(times) + 1, solver.y.size))
        if times:
            with self._stages_on_manifold(across):
                stepper.interpolate(solver, times, states[:-1])
        states[-1] = solver.y
        times.append(solver.t)
        projected = None if self.projection is None else \
            self.projection.block(times, *self.form.states(states), (np.array(times) - start[0]) / taken)
        bounded = _bounded(states)
        self.passed = Passed(times, states, projected, bounded)
        q_on, qd_on = self._on_constraints(solver.t, q, qd, None if projected is None else projected.row(-1), arrays)
        # A before the projection: it moved q by the drift alone
        self._look(solver.t, q_on, qd_on, None if arrays is None else arrays.A)
        if not (np.array_equal(q_on, q) and np.array_equal(qd_on, qd)):
            y = self.form.to_integrator(q_on, qd_on)
            stepper.move(solver, y, None if solver.status == "finished" else self.f(solver.t, y))

    def event_in(self, solver, start, target):
        """Whether the step just taken from ``start`` (aimed at ``target`` or None) passed an
        event it must stop at, to be taken again up to it: never here (impacts.py's runs)."""
        return False

    def _watch_from(self, t, q, qd):
        """Watch for the singular positions passed between stages from the state (t, q, q̇)
        on (singular_watch.py): on runs projected by analysis/projection.py or by compiled/extra_projection.py
        (``watched``) of models whose A is small enough. Plan the steps across them
        (crossing.py) where the kernel projects the states and the watch or the projection
        (extra_projection.py's ``measure``) measures them; none where the rows keep their
        rank (singular_watch.rows_keep_rank)."""
        if self.keeps_rank:
            return
        if self.watch is None and (self.projection is None or self.projection.watched) and \
                SingularWatch.fits(self.data):
            self.watch = SingularWatch(self.data, t, q, qd)
        if self.crossing is None and self.projection is not None and \
                (self.watch is not None or self.projection.measure is not None):
            self.crossing = Crossing(self.method)
        for watching in (self.watch, self.crossing):
            if watching is not None:
                watching.restart()
        self._look(t, q, qd)

    def _look(self, t, q, qd, A=None):
        """The state (t, q, q̇) reached on the constraints (``A``: its rows, if at hand; else
        the kernel's projection's where it has them, extra_projection.py) shown to the watch,
        which may list a singular position passed, and its measure to the step plan."""
        if self.watch is not None:
            if A is None and self.projection is not None:  # the rows from the kernel's projection (compiled)
                A = self.projection.rows_at(t, q, qd)
            found = self.watch.passed(t, q, qd, A)
            if found is not None:
                self.f.add_singular(*found)
        if self.crossing is not None:
            if self.watch is not None:
                m = self.watch.measure
            else:
                m = self.projection.measure(t, q, qd)
            self.crossing.passed(t, m)

    def _drift(self, t, q, qd, span):
        """(the relative drift off the constraints of the state a step of length ``span``
        reached, its ConstraintArrays or None):
        the kernel's rows where it projects the model, else projection.py's."""
        if self.projection is not None:
            return self.projection.drift(t, q, qd), None
        if not self.has_rows:
            return 0.0, None
        arrays = self.data.constraint_arrays(t, q, qd, sparse=None)
        return relative_drift(self.data, t, q, qd, arrays, span), arrays

    def _on_constraints(self, t, q, qd, projected, arrays=None):
        """The state (q, q̇) on the constraints: ``projected``'s where the kernel's projection
        put it there (compiled/projection.py: Projected), else projected by analysis/projection.py
        (``arrays``: the ConstraintArrays at the state, if at hand), as it is in a model with no rows."""
        if projected is not None:
            return projected[:2]
        return project(self.data, t, q, qd, arrays=arrays) if self.has_rows else (q, qd)


@njit(cache=True)
def _bounded(states):
    """Per row of ``states``, whether each entry is within MAX_STATE (False where one is NaN:
    rows.largest gives NaN then)."""
    within = np.empty(states.shape[0], dtype=np.bool_)
    for r in range(states.shape[0]):
        within[r] = largest(states[r]) <= MAX_STATE
    return within
