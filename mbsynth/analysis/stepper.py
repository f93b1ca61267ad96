"""scipy's integrators driven one step at a time, moved where the run loop puts them.

``simulate`` steps an OdeSolver (``solve_ivp``'s classes) itself: it moves the state onto
the constraints between steps, stops at control samples and takes a step again when it
drifted too far. An explicit Runge–Kutta pair (RESUMABLE) carries nothing from one step to
the next but its state (t, y), y's derivative f and its next step's size h_abs, so it goes
on from a moved state exactly as a new one started there with that first step would (the
test of this module checks it bit for bit against scipy's own constructor). This is the
only module that writes an OdeSolver's attributes or reads its interpolant's coefficients;
``simulate`` calls these functions and ``step()``.
"""

import numpy as np
import scipy.integrate

try:  # DOP853's interpolant and its coefficients F (``interpolate``): scipy's, not public
    from scipy.integrate._ivp.rk import Dop853DenseOutput
except ImportError:  # a scipy that moved it: every interpolant through scipy's own call
    Dop853DenseOutput = None

METHODS = {kind.__name__: kind for kind in (scipy.integrate.RK23, scipy.integrate.RK45, scipy.integrate.DOP853,
                                            scipy.integrate.Radau, scipy.integrate.BDF, scipy.integrate.LSODA)}
# integrators that go on from a moved state given its derivative: an explicit Runge–Kutta
# pair carries nothing else from one step to the next
RESUMABLE = (scipy.integrate.RK23, scipy.integrate.RK45, scipy.integrate.DOP853)


def proposed_step(solver):
    """The step the solver would take next: its own proposal (h_abs), or for LSODA, which
    keeps it inside its Fortran state, its last step's size."""
    return getattr(solver, "h_abs", None) or solver.step_size


def saved(solver):
    """What ``rewind`` needs to take the solver's last step again."""
    return solver.t, solver.y, solver.f, solver.h_abs


def rewind(solver, state, max_step):
    """The solver back at ``state`` (``saved`` before a step), running, its steps capped at
    ``max_step`` (a step taken again, shorter)."""
    solver.t, solver.y, solver.f, solver.h_abs = state
    solver.status, solver.max_step = "running", max_step


def move(solver, y, f):
    """The solver's state moved to y (onto the constraints), f its derivative there (None:
    not known yet, to be given by a ``move`` before the solver steps again)."""
    solver.y, solver.f = y, f


def stands_at(solver, y):
    """Whether the solver's state is y, its derivative there known."""
    return solver.f is not None and np.array_equal(solver.y, y)


def resume(solver, t_bound, first_step=None):
    """The solver, finished or not, running again towards t_bound, its next step
    ``first_step`` when given."""
    solver.t_bound, solver.status = t_bound, "running"
    if first_step is not None:
        solver.h_abs = first_step


def step_to(solver, t_to):
    """One step of the solver aimed to end at t_to (between its t and its bound): its step
    size set to reach t_to, its bound moved there for the step; a rejected trial shortens it
    as usual (the step then ends before t_to). ``step()``'s message."""
    bound = solver.t_bound
    solver.t_bound, solver.h_abs = t_to, abs(t_to - solver.t)
    try:
        return solver.step()
    finally:
        solver.t_bound = bound
        if solver.status == "finished" and solver.t != bound:
            solver.status = "running"


def cap(solver, max_step):
    """The solver's steps capped at ``max_step`` (np.inf: uncapped)."""
    solver.max_step = max_step


def interpolate(solver, times, out):
    """The states (a row per time) at ``times`` within the solver's last step, from its
    interpolant, into ``out``. DOP853's, y_old + x (F₀ + (1 − x)(F₁ + x (F₂ + (1 − x)(…))))
    with x the step's fraction (scipy's Dop853DenseOutput, which makes seven passes over the
    rows), is one product here: y_old + P F with P[j, k] = x_j (1 − x_j) x_j … (k + 1
    factors, alternating: a running product). Other interpolants through scipy."""
    dense = solver.dense_output()
    if Dop853DenseOutput is None or not isinstance(dense, Dop853DenseOutput):
        out[:] = dense(times).T
        return
    x = (np.asarray(times, dtype=float) - dense.t_old) / dense.h
    factors = np.empty((x.size, len(dense.F)))
    factors[:, 0::2], factors[:, 1::2] = x[:, None], 1 - x[:, None]
    np.matmul(np.cumprod(factors, axis=1), dense.F, out=out)
    out += dense.y_old
