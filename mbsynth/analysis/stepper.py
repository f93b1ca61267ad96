"""The run loop's integrators driven one step at a time, moved where the run loop puts them.

``simulate`` steps an OdeSolver (``solve_ivp``'s classes; DOP853 its own, dop853.py, which
steps as scipy's) itself: it moves the state onto the constraints between steps, stops at
control samples and takes a step again when it drifted too far. An explicit Runge–Kutta
pair (``resumable``) carries nothing from one step to the next but its state (t, y), y's
derivative f and its next step's size h_abs, so it goes on from a moved state exactly as a
new one started there with that first step would (the test of this module checks it bit
for bit against scipy's own constructor). Radau IIA (``movable``, for stiff models) carries
besides its Newton matrix — the Jacobian J and its LU factors at the step size — and its
last step's collocation polynomial, the Newton iteration's first guess: a move by a
projection (the drift, within the tolerance) leaves both good enough, so it goes on from
the moved state too; where its step size is set here its factors are made afresh. This is
the only module that writes an OdeSolver's attributes or reads its internals (DOP853's
extra stages and interpolant, ``interpolate``); ``simulate`` calls these functions and
``step()``. scipy.integrate is imported only for a method other than DOP853 (its import
costs a tenth of a warm run's process: dop853.py).
"""

import importlib
import sys

import numpy as np

from .dop853 import DOP853

METHODS = ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA")  # solve_ivp's method names
RESUMABLE = ("RK23", "RK45", "DOP853")  # explicit pairs: nothing carried from step to step but (t, y, f, h_abs)
IMPLICIT = ("Radau", "BDF", "LSODA")  # given the Jacobian of the motion (derivative.StateDerivative.jacobian)


def integrator(method):
    """The OdeSolver class of ``method``: a solve_ivp method name (one of METHODS) or such a
    class. DOP853 is the run loop's own (dop853.py; scipy's class too is taken as it), the
    others scipy's."""
    if isinstance(method, type):
        integrate = sys.modules.get("scipy.integrate")  # an OdeSolver subclass exists only where it was imported
        if issubclass(method, DOP853):
            return method
        if integrate is not None and issubclass(method, integrate.OdeSolver):
            return DOP853 if method is integrate.DOP853 else method
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)} (or a scipy OdeSolver class), got {method!r}")
    return DOP853 if method == "DOP853" else getattr(importlib.import_module("scipy.integrate"), method)


def _among(method, names):
    """Whether the integrator class ``method`` is one of the methods ``names`` or derives from one."""
    if issubclass(method, DOP853):
        return "DOP853" in names
    integrate = sys.modules["scipy.integrate"]  # a class not ours is scipy's: imported already
    return issubclass(method, tuple(getattr(integrate, name) for name in names))


def resumable(method):
    """Whether ``method`` goes on from a moved state given its derivative: an explicit pair."""
    return _among(method, RESUMABLE)


def movable(method):
    """Whether ``method`` goes on from a moved state given its derivative (module docstring):
    the continuous run loop's (continuous.py)."""
    return _among(method, RESUMABLE + ("Radau",))


def implicit(method):
    """Whether ``method`` takes the Jacobian of the motion."""
    return _among(method, IMPLICIT)


def start(method, f, t, y, t_bound, **options):
    """A new integrator of the OdeSolver class ``method`` on the right-hand side f (a
    StateDerivative) from (t, y): DOP853's steps compiled where f can take them."""
    solver = method(f, t, y, t_bound, **options)
    if method is DOP853:
        solver.derivative = f
    return solver


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
    solver.t, solver.y, solver.f = state[:3]
    _set_step(solver, state[3])
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
        _set_step(solver, first_step)


def step_to(solver, t_to):
    """One step of the solver aimed to end at t_to (between its t and its bound): its step
    size set to reach t_to, its bound moved there for the step; a rejected trial shortens it
    as usual (the step then ends before t_to). ``step()``'s message."""
    bound = solver.t_bound
    solver.t_bound = t_to
    _set_step(solver, abs(t_to - solver.t))
    try:
        return solver.step()
    finally:
        solver.t_bound = bound
        if solver.status == "finished" and solver.t != bound:
            solver.status = "running"


def _set_step(solver, h_abs):
    """The solver's next step size h_abs; Radau's Newton factors (LU_real, LU_complex), made
    for another step size, made afresh."""
    if h_abs != solver.h_abs and hasattr(solver, "LU_real"):
        solver.LU_real = solver.LU_complex = None
    solver.h_abs = h_abs


def cap(solver, max_step):
    """The solver's steps capped at ``max_step`` (np.inf: uncapped)."""
    solver.max_step = max_step


def interpolate(solver, times, out):
    """The states (a row per time) at ``times`` within the solver's last step, from its
    interpolant, into ``out``: DOP853's compiled (dop853.Interpolant), another method's
    through its ``dense_output``."""
    if isinstance(solver, DOP853):
        solver.dense_output().into(np.asarray(times, dtype=float), out)
    else:
        out[:] = solver.dense_output()(times).T
