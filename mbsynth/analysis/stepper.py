"""scipy's integrators driven one step at a time, moved where the run loop puts them.

``simulate`` steps an OdeSolver (``solve_ivp``'s classes) itself: it moves the state onto
the constraints between steps, stops at control samples and takes a step again when it
drifted too far. An explicit Runge–Kutta pair (RESUMABLE) carries nothing from one step to
the next but its state (t, y), y's derivative f and its next step's size h_abs, so it goes
on from a moved state exactly as a new one started there with that first step would (the
test of this module checks it bit for bit against scipy's own constructor). Radau IIA
(MOVABLE, for stiff models) carries besides its Newton matrix — the Jacobian J and its LU
factors at the step size — and its last step's collocation polynomial, the Newton
iteration's first guess: a move by a projection (the drift, within the tolerance) leaves
both good enough, so it goes on from the moved state too; where its step size is set here
its factors are made afresh. This is the only module that writes an OdeSolver's attributes
or reads its internals (DOP853's extra stages and interpolant, ``interpolate``); ``simulate``
calls these functions and ``step()``.
"""

import numpy as np
import scipy.integrate
from numba import njit

# what ``interpolate`` reads of DOP853 (scipy's, not public): its extra stages' tableau (A_EXTRA,
# C_EXTRA), its interpolant's matrix D and, per step, K_extended; where a scipy lacks them,
# every interpolant goes through scipy's own call
DOP853_INTERNALS = all(hasattr(scipy.integrate.DOP853, name) for name in ("A_EXTRA", "C_EXTRA", "D", "n_stages"))

METHODS = {kind.__name__: kind for kind in (scipy.integrate.RK23, scipy.integrate.RK45, scipy.integrate.DOP853,
                                            scipy.integrate.Radau, scipy.integrate.BDF, scipy.integrate.LSODA)}
# integrators that go on from a moved state given its derivative: an explicit Runge–Kutta
# pair carries nothing else from one step to the next
RESUMABLE = (scipy.integrate.RK23, scipy.integrate.RK45, scipy.integrate.DOP853)
# integrators that go on from a moved state given its derivative (module docstring): the
# continuous run loop's (continuous.py)
MOVABLE = RESUMABLE + (scipy.integrate.Radau,)
# integrators given the Jacobian of the motion (derivative.StateDerivative.jacobian)
IMPLICIT = (scipy.integrate.Radau, scipy.integrate.BDF, scipy.integrate.LSODA)


class CompiledDOP853(scipy.integrate.DOP853):
    """scipy's DOP853 whose steps and extra stages are taken in compiled code where the run's
    right-hand side can (compiled/staged.py, through ``derivative``'s ``step`` and ``extra``),
    else by scipy's own Python (a stage the kernel declines, a run outside the compiled
    engine): the same method, tableau and step-size control either way."""

    derivative = None  # the run's StateDerivative (analysis/derivative.py)

    def _step_impl(self):
        taken = None if self.derivative is None else self.derivative.step(self)
        return super()._step_impl() if taken is None else taken


def start(method, f, t, y, t_bound, **options):
    """A new integrator of the OdeSolver class ``method`` on the right-hand side f (a
    StateDerivative) from (t, y): DOP853's steps compiled where f can take them."""
    if method is not scipy.integrate.DOP853 or not DOP853_INTERNALS:
        return method(f, t, y, t_bound, **options)
    solver = CompiledDOP853(f, t, y, t_bound, **options)
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
    """The solver's next step size h_abs; Radau's Newton factors, made for another step
    size, made afresh."""
    if h_abs != solver.h_abs and isinstance(solver, scipy.integrate.Radau):
        solver.LU_real = solver.LU_complex = None
    solver.h_abs = h_abs


def cap(solver, max_step):
    """The solver's steps capped at ``max_step`` (np.inf: uncapped)."""
    solver.max_step = max_step


def interpolate(solver, times, out):
    """The states (a row per time) at ``times`` within the solver's last step, from its
    interpolant, into ``out``. DOP853's as scipy's ``dense_output`` makes it — three extra
    stages (compiled, as the steps, where CompiledDOP853's derivative can), then
    y_old + x (F₀ + (1 − x)(F₁ + x (F₂ + (1 − x)(…)))) with x the step's fraction — with the
    arithmetic compiled (scipy's costs more than the stages' motion on a small model). Other
    interpolants through scipy."""
    if not (DOP853_INTERNALS and isinstance(solver, scipy.integrate.DOP853) and solver.t != solver.t_old):
        out[:] = solver.dense_output()(times).T
        return
    K, h, t_old, y_old = solver.K_extended, solver.h_previous, solver.t_old, solver.y_old
    done = solver.derivative.extra(solver) if getattr(solver, "derivative", None) is not None else 0
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
