"""The run loop's integration stage: one interface, two strategies behind it.

An Integration takes a run's state from the time it reached (``t_now``) to the next output
time or control sample (``advance``), stepping one of scipy's OdeSolvers (stepper.py) on the
right-hand side of derivative.py. With ``stabilization="projection"`` the state it hands
back lies on the constraints (projected by analysis/projection.py, or by the compiled kernel,
compiled/projection.py) and has been judged strictly there: a real contradiction raises
SolveError. ``restart`` follows a jump of the forces (new parameter values in the Data, at a
control sample): the integrator's f is computed afresh there.

- ContinuousIntegration (continuous.py): with an explicit pair and projection, the steps
  are chosen by the error control alone, up to the next control sample or the end, each
  projected (by the kernel where it covers the model, else by analysis/projection.py).
- CutIntegration (cut.py): otherwise, and for an interval the continuous integrator cannot
  do, each interval integrated on its own, the last step cut short at its end, the state
  projected there and between as the drift asks.

``simulate`` chooses (ContinuousIntegration.fits). Both count the same (``stats``) and share
how an integrator goes on from a state: the same explicit pair or Radau where it can
(stepper.movable), else a new one; an implicit one (stepper.implicit) is given the Jacobian
of the motion (derivative.StateDerivative.jacobian). Both integrate y = (q, v), each rigid body's quaternion
rates replaced by its angular velocity (velocity_form.py), and hand back (q, q̇).
"""

import logging

from . import stepper
from .derivative import StateDerivative
from .singular_watch import rows_keep_rank
from .velocity_form import VelocityForm
from ..core.tolerances import DRIFT_TARGET

log = logging.getLogger(__name__)


def drift_target(method, rtol, keeps_rank):
    """The largest relative drift between projections (drift.py) of a run with the OdeSolver
    class ``method`` at ``rtol``: DRIFT_TARGET, or rtol where larger, for an implicit method
    or rows that keep their rank (singular_watch.rows_keep_rank). The tight
    target keeps the stages near the manifold, where the drift rule judges nearly dependent
    rows by the drift (kernel.py, core/equations.py); rows that keep their rank have none to
    judge, and an implicit method's long steps, where the stiff parts are quasi-static, drift
    by about their local error. There a step may drift as far as its error control lets it:
    DRIFT_TARGET would cut a loose run's steps to a tight one's length (a stiff model's
    explicit steps included, whose stability then holds them)."""
    if stepper.implicit(method) or keeps_rank:
        return max(DRIFT_TARGET, rtol)
    return DRIFT_TARGET


class Integration:
    """What both strategies hold: the settings, the right-hand side ``f`` with its counts,
    the integrator kept from interval to interval, and the state reached. ``schedule``: the
    run's output times and control samples (schedule.Schedule)."""

    def __init__(self, data, method, rtol, atol, stabilization, baumgarte, schedule):
        self.data, self.method, self.rtol, self.atol = data, method, rtol, atol
        self.stabilization, self.schedule, self.n = stabilization, schedule, data.model.n
        self.form = VelocityForm(data.model)  # the integrator's y = (q, v) and (q, q̇)
        self.f = StateDerivative(data, baumgarte if stabilization == "baumgarte" else None, self.form)
        self.steps = 0
        self.keeps_rank = rows_keep_rank(data.system)  # no singular position to pass (singular_watch.py)
        self.drift_target = drift_target(method, rtol, self.keeps_rank)
        self.solver = None  # the integrator, kept from interval to interval (``resumed``)
        self.solver_tolerances = None  # its (rtol, atol)
        self.next_step = None  # the step it proposed after its last step not cut short at an interval's end
        self.t_now = None  # the time the state has reached (outputs and control samples alike)
        self.arrays = None  # the ConstraintArrays at the state ``advance`` reached, if at hand
        self.projected = None  # the kernel's projection.Projected there, if at hand
        self.relaxed_spans = []  # {t_from, t_to, rtol, atol} of the spans integrated again, more loosely
        self.potential_free = all(f.V == 0 for f in data.model.forces)  # no force element with a potential
        self.restart()

    @property
    def t_failed(self):
        """Where the run was when it failed."""
        return self.f.t_failed

    def restart(self):
        """Go on from the Data's parameter values (new at a control sample: the forces
        jump, so the integrator's f is computed afresh): its stages' motion and its compiled
        projection, where the kernel covers the model."""
        self.forces_jumped = True
        engine = self.data.engine
        self.f.use(engine)
        self.projection = None if engine is None else engine.projection()
        self.compiled_energy = self.projection is not None and self.projection.energies and self.potential_free

    def advance(self, t_next, q, qd, t_stop):
        """The state (q, q̇) at t_next from (q, q̇) at ``t_now``; t_stop: the next control
        sample or the end, where a continuous integrator must stop."""
        raise NotImplementedError

    def resumed(self, t, q, qd, t_bound, rtol, atol):
        """The integrator at the state (t, q, q̇), bound for t_bound, its first step the one
        it last proposed: the same explicit pair where it stands at t with these tolerances
        (stepper.movable), moved to the state — given f there — where a projection moved it
        or the forces jumped; else a new one, as ``solve_ivp`` would start it."""
        first = None if self.next_step is None else min(self.next_step, t_bound - t)
        solver = self.solver
        if solver is not None and stepper.movable(type(solver)) and solver.t == t and \
                self.solver_tolerances == (rtol, atol):
            y = solver.y if self.form.represents(solver.y, q, qd) else self.form.to_integrator(q, qd)
            if self.forces_jumped or not stepper.stands_at(solver, y):
                stepper.move(solver, y, self.f(t, y))
            stepper.resume(solver, t_bound, first)
        else:
            y = self.form.to_integrator(q, qd)
            jacobian = dict(jac=self.f.jacobian) if stepper.implicit(self.method) else {}
            solver = self.solver = stepper.start(self.method, self.f, t, y, t_bound, rtol=rtol, atol=atol,
                                                 first_step=first, **jacobian)
            self.solver_tolerances = (rtol, atol)
        self.forces_jumped = False
        return solver

    def arrived(self, t_next, q, qd, arrays=None, projected=None):
        """The state reached at t_next (``arrays``: its ConstraintArrays, if at hand), judged
        strictly there with projection, unless the kernel ``projected`` it (its checks passed
        there already; projection.Projected, with the rows there)."""
        self.f.note_singular()
        if self.stabilization == "projection" and projected is None:
            self.f.t_failed = t_next
            self.data.motion(t_next, q, qd)  # on the manifold: a contradiction raises here
        self.t_now, self.arrays, self.projected = t_next, arrays, projected
        return q, qd

    def ready(self):
        """(times, ProjectedRows) of output rows after ``t_now`` reached already and projected,
        taken as arrived, for ``simulate`` to record at once; None: none (continuous.py's
        integrator has them)."""
        return None

    def failed_step(self, solver, message):
        """The SolveError of the integrator's own failure (its step size too small)."""
        return self.f.collapse(solver.t, solver.y, (message or "the integrator failed").rstrip("."))

    def stats(self):
        """The run's counts for ``Trajectory.stats``."""
        f = self.f
        if f.non_unique:
            log.warning("the motion was not unique somewhere on this run; the free directions got zero "
                        "acceleration (η = 0 in (2.14))")
        return dict(steps=self.steps, evaluations=f.evaluations, jacobians=f.jacobians, non_unique=f.non_unique,
                    singular_positions=f.singular_positions, relaxed_spans=self.relaxed_spans)
