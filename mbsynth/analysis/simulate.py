"""Motion over time: integrate (q, q̇) with q̈ from (2.14), keeping the constraints.

The accelerations satisfy the constraints only at the acceleration level (2.4), so
positions and velocities drift. ``simulate`` is the run loop, in stages: integration
(integration.py: one interface, the continuous strategy of continuous.py where the compiled
kernel projects states itself, else the cut one of cut.py; the right-hand side and its
counts in derivative.py, scipy's integrators driven by stepper.py, the drift rule in
drift.py), sampled control (control.py) and recording (recording.py). It steps from output
time to output time and control sample; at a sample the controller writes new parameter
values into the run's Data and the integrator restarts, the forces having jumped.

Consistency is judged where it means something. The integrator's stages lie off the
manifold by the integration error, so the motion there follows the drift rule of
``equations`` (least squares where the drift explains an inconsistency of b, as with
dependent rows whose dependency changes with the configuration — Bricard's mechanism —
and nearly dependent directions near a singular position set aside). At each output state
the constraints are judged strictly: a real contradiction raises SolveError there.
``stats["singular_positions"]`` lists the output intervals in which a stage came near a
singular position (σ < 1e-5 σ₁ of the equilibrated A: the drift rule's zone), and, on a
continuous projected run of a small model, each crossing found between the steps' ends
(singular_watch.py); a crossing whose stages all stay farther from it needs no special
treatment, and on other runs may go unlisted.
There a tolerance tighter than the stages' noise makes the integrator crawl; a continuous
run whose watch sees a singular position coming steps across it in one planned step
(crossing.py), and a span that crawls still is integrated again more loosely (cut.py) and
listed in ``stats["relaxed_spans"]``.

A model with joint limits or contacts runs event-driven (impacts.py): the gaps' closing
and the held ones' release found on the steps' dense output, impacts as velocity jumps of
the impulse form of (2.14), the events in ``Trajectory.events``.
"""

import logging
import math
import time

import numpy as np

from .control import SampledControl
from ..core.errors import ControlError, ModelError, SimulationError, SolveError
from ..model.data import Data
from . import stepper
from .continuous import ContinuousIntegration
from .cut import CutIntegration
from .projection import consistent_initial_state
from .recording import Recorder
from .schedule import Schedule
from .trajectory import COMPLETED
from ..core.tolerances import INTEGRATION_ATOL, INTEGRATION_RTOL, LAST_INTERVAL_MERGE

log = logging.getLogger(__name__)

STABILIZATIONS = ("projection", "baumgarte", "none")
DEFAULT_OUTPUTS = 500


def simulate(model, t_end, *, t0=0.0, q0=None, qd0=None, dt=None, method="DOP853", rtol=INTEGRATION_RTOL,
             atol=INTEGRATION_ATOL,
             stabilization="projection", baumgarte=(10.0, 10.0), out=None, progress=None, controller=None,
             control_dt=None, path=None):
    """Integrate ``model`` from t0 to t_end; returns a Trajectory with one row per output time
    (and the model's declared outputs: mbsynth.model.outputs). ``model``: a System (run in
    a new Data of ``path``, at its parameter values) or a Data (run at its parameter values
    and on its path; a controller's values are written into it).

    q0, qd0: the initial state (default: the model's, made consistent by projection
    keeping every value the model sets; the changes are logged and kept in
    ``stats["initial_changes"]``). dt: output interval (default (t_end − t0)/500).
    method, rtol, atol: the integrator (a ``solve_ivp`` method name or a scipy OdeSolver class)
    and its tolerances: an explicit pair (DOP853, the default; RK45, RK23), or for a stiff
    model — high frequencies that hold an explicit pair's steps down — Radau (Radau IIA of
    order 5 on the continuous run loop, given the Jacobian of the motion through the compiled
    kernel; BDF and LSODA too, cut at each output time). An implicit method refuses
    (ModelError) a model with Coulomb friction at joints and a controller. out: a .npz or .csv path written as
    the run goes. progress: a callable(t) called at every output time.
    controller: ``f(t, joint_values) -> {parameter: value}``, called at t0 and every
    ``control_dt`` (default: the output interval), its values held in between (sampled
    control, mbsynth.analysis.control).
    path: the run's path, "compiled" or "kkt" (``System.data``; None: the default, or the
    path of the Data given).
    Raises SimulationError (with the partial trajectory) when the run cannot go on.
    """
    if stabilization not in STABILIZATIONS:
        raise ValueError(f"stabilization must be one of {STABILIZATIONS}, got {stabilization!r}")
    method = stepper.integrator(method)
    if not (np.isfinite(t0) and np.isfinite(t_end) and t_end > t0):
        raise ValueError(f"t_end ({t_end}) must be after t0 ({t0}), both finite")
    data = _run_data(model, path)
    if q0 is None and qd0 is None:
        q, qd, changes = consistent_initial_state(data, t0)
        for name, (given, new) in changes.items():
            log.info("initial %s: %.12g -> %.12g (made consistent with the constraints)", name, given, new)
    else:
        start_q, start_qd = data.initial_state()
        q = start_q if q0 is None else np.asarray(q0, dtype=float)
        qd = start_qd if qd0 is None else np.asarray(qd0, dtype=float)
        changes = {}
    _check_implicit(data.system, method, controller)
    recorder = Recorder(data, _output_count(t0, t_end, dt), out)  # refused here if the rows cannot fit in memory
    times = _output_times(t0, t_end, dt)
    control = None if controller is None else \
        SampledControl(controller, times[1] - times[0] if control_dt is None else control_dt)
    schedule = Schedule(times, None if control is None else control.dt)
    run = _strategy(data.model, method, stabilization)(data, method, rtol, atol, stabilization, baumgarte, schedule)
    if data.model.unilaterals:  # an EventIntegration (``_strategy``)
        run.events = recorder.events
        recorder.contact_forces = run.contact_forces
    recorder.open()
    started = time.perf_counter()
    status = "stopped"
    try:
        if control is not None:
            control.apply(data, t0, q, qd)
            run.restart()
        recorder.record(t0, q, qd, run.projection, run.compiled_energy)
        run.t_now = t0
        for t_next, is_output, is_sample in schedule:
            q, qd = run.advance(t_next, q, qd, schedule.next_stop(t_next))
            if is_sample:
                try:
                    control.apply(data, t_next, q, qd)
                except ControlError:
                    if is_output:  # the state reached is good: its row, with the values held until now
                        recorder.record(t_next, q, qd, run.projection, run.compiled_energy, run.arrays, run.projected)
                    raise
                run.restart()
            if is_output:
                at_hand = () if is_sample else (run.arrays, run.projected)  # a sample's parameters are new
                recorder.record(t_next, q, qd, run.projection, run.compiled_energy, *at_hand)
                if progress is not None:
                    progress(t_next)
                q, qd = _record_ready(run, recorder, schedule, progress, q, qd)
        status = COMPLETED
    except SolveError as err:
        status = f"failed at t = {run.t_failed:.9g}: {err}"
        raise SimulationError(f"run stopped at t = {run.t_failed:.9g} (last good state saved at "
                              f"t = {recorder.t[-1]:.9g}): {err}", time=run.t_failed,
                              trajectory=_trajectory(recorder, run, status),
                              constraints=err.constraints, coordinates=err.coordinates) from None
    except ControlError as err:
        status = f"failed at t = {err.time:.9g}: {err}"
        err.trajectory = _trajectory(recorder, run, status)
        raise
    except KeyboardInterrupt:
        status = f"interrupted at t = {recorder.t[-1]:.9g}"
        raise
    finally:
        recorder.close(status)
    traj = _trajectory(recorder, run, status)
    traj.stats.update(wall_time=time.perf_counter() - started, initial_changes=changes)
    return traj


def _run_data(model, path):
    """The run's workspace, one motion path (compiled or KKT) for the whole run: a new Data
    of ``path`` for a model, a Data itself (ValueError for a ``path`` other than its own)."""
    if not isinstance(model, Data):
        return model.data(path)
    if path not in (None, model.path):
        raise ValueError(f"path={path!r}: the Data given runs on its own path, {model.path!r}")
    return model


def _strategy(system, method, stabilization):
    """The Integration class of the run: with events where the model has limits or
    contacts (impacts.py), else continuous where it can be, else cut."""
    continuous = ContinuousIntegration.fits(method, stabilization)
    if system.unilaterals:
        if not (continuous and stepper.resumable(method)):
            raise ValueError(f"model '{system.name}' has limits or contacts: its run needs an explicit "
                             f"Runge–Kutta method ({', '.join(stepper.RESUMABLE)}) and "
                             f"stabilization='projection'")
        from .impacts import EventIntegration  # loaded only by a model with limits or contacts (start-up)
        return EventIntegration
    return ContinuousIntegration if continuous else CutIntegration


def _check_implicit(system, method, controller):
    """Raise ModelError where an implicit method (stepper.implicit) cannot serve the run: its
    Newton iteration needs the Jacobian of the motion, which Coulomb friction at a joint has
    not (C jumps with the sign of the sliding rate, friction.py); a sampled controller's
    forces jump at every sample, where it would start afresh (Jacobian, factors, a small
    first step) each time."""
    if not stepper.implicit(method):
        return
    rubbing = [con.name for con in system.constraints if getattr(con, "coulomb", None)]
    if rubbing:
        raise ModelError(f"method={method.__name__}: model '{system.name}' has Coulomb friction at "
                         f"{', '.join(rubbing)}, whose force jumps with the sign of the sliding rate: the motion has "
                         f"no Jacobian there for the implicit method's Newton iteration; use an explicit method "
                         f"(DOP853)")
    if controller is not None:
        raise ModelError(f"method={method.__name__}: a sampled controller's forces jump at every sample, where an "
                         f"implicit method starts afresh (a new Jacobian, a small first step); use an explicit "
                         f"method (DOP853)")


def _record_ready(run, recorder, schedule, progress, q, qd):
    """The rows the integrator has passed and projected already (ContinuousIntegration.ready),
    recorded at once and skipped in the ``schedule``; returns the last state recorded
    (q, q̇ as they were where there are none)."""
    rows = run.ready()
    if rows is None:
        return q, qd
    times, projected = rows
    recorder.record_rows(times, projected, run.compiled_energy)
    schedule.skip_through(times[-1])
    if progress is not None:
        for t in times:
            progress(t)
    return projected.q[-1], projected.qd[-1]


def _trajectory(recorder, run, status):
    """The rows recorded, with the run's counts."""
    traj = recorder.trajectory(status)
    traj.stats.update(run.stats())
    return traj


def _output_count(t0, t_end, dt):
    """The number of output times from t0 to t_end every dt (``_output_times``), counted
    without making them."""
    if dt is None:
        return DEFAULT_OUTPUTS + 1
    if not dt > 0:
        raise ValueError(f"dt must be positive, got {dt}")
    count = math.ceil((t_end - t0) / dt)  # np.arange's length
    return count + 1 if t_end - (t0 + (count - 1) * dt) > LAST_INTERVAL_MERGE * dt else count


def _output_times(t0, t_end, dt):
    """Every dt from t0, and t_end (a last interval shorter than LAST_INTERVAL_MERGE · dt merged into the
    one before)."""
    if dt is None:
        return np.linspace(t0, t_end, DEFAULT_OUTPUTS + 1)
    times = np.arange(t0, t_end, dt)
    return np.append(times, t_end) if t_end - times[-1] > LAST_INTERVAL_MERGE * dt else np.append(times[:-1], t_end)
