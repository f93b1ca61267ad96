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
from numba import njit

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
    interpolant, into ``out``. DOP853's as scipy's ``dense_output`` makes it — three extra
    stages (compiled, as the steps, where the solver's ``derivative`` can), then
    y_old + x (F₀ + (1 − x)(F₁ + x (F₂ + (1 − x)(…)))) with x the step's fraction — with the
    arithmetic compiled (scipy's costs more than the stages' motion on a small model). Other
    interpolants (another method's, a step of no length) through the solver's ``dense_output``."""
    if not (isinstance(solver, DOP853) and solver.t != solver.t_old):
        out[:] = solver.dense_output()(times).T
        return
    K, h, t_old, y_old = solver.K_extended, solver.h_previous, solver.t_old, solver.y_old
    done = solver.derivative.extra(solver) if solver.derivative is not None else 0
    for s, (a, c) in enumerate(zip(solver.A_EXTRA[done:], solver.C_EXTRA[done:]), start=solver.n_stages + 1 + done):
        K[s] = solver.fun(t_old + c * h, _stage_state(K, a, s, h, y_old))
    F = np.empty((solver.D.shape[0] + 3, y_old.size))
    _coefficients(K, solver.D, h, solver.y, y_old, solver.f, F)
    _rows(np.asarray(times, dtype=float), t_old, h, F, y_old, out)


@njit(cache=True)
def _stage_state(K, a, s, h, y_old):
    """y_old + h Σ_{i<s} a_i K_i: the state of an extra stage."""
    y = np.empty(y_old.shape[0])
    for c in range(y.shape[0]):
        acc = 0.0
        for i in range(s):
            acc += K[i, c] * a[i]
        y[c] = y_old[c] + acc * h
    return y


@njit(cache=True)
def _coefficients(K, D, h, y, y_old, f, F):
    """DOP853's interpolant coefficients F: Δy, h f_old − Δy, 2Δy − h (f + f_old), then h D K."""
    for c in range(y.shape[0]):
        dy = y[c] - y_old[c]
        F[0, c], F[1, c], F[2, c] = dy, h * K[0, c] - dy, 2 * dy - h * (f[c] + K[0, c])
        for r in range(D.shape[0]):
            acc = 0.0
            for s in range(K.shape[0]):
                acc += D[r, s] * K[s, c]
            F[3 + r, c] = h * acc


@njit(cache=True)
def _rows(times, t_old, h, F, y_old, out):
    """The interpolant's rows: out[j] = y_old + Σ_k P[j, k] F[k], P[j, k] = x (1 − x) x … (k + 1
    factors, alternating) at x = (t_j − t_old)/h."""
    for j in range(times.shape[0]):
        x = (times[j] - t_old) / h
        out[j] = y_old
        p = 1.0
        for k in range(F.shape[0]):
            p *= x if k % 2 == 0 else 1.0 - x
            for c in range(y_old.shape[0]):
                out[j, c] += p * F[k, c]
