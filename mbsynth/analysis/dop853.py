"""DOP853, the run loop's default integrator, without scipy.integrate.

Dormand and Prince's explicit Runge–Kutta pair of order 8(5,3) with its 7th-order dense
output (Hairer, Nørsett & Wanner, *Solving Ordinary Differential Equations I*, II.4 and II.10;
the tableau in core/dop853_tableau.py), taken step by step as scipy's ``scipy.integrate.DOP853``
takes it: the same initial step, error norm and step-size control, operation for operation,
so that its steps are the same bit for bit (tests/analysis/test_dop853.py checks them against
scipy's). It has the part of scipy's OdeSolver interface that the run loop reads and
writes (stepper.py): ``step()``, ``status``, ``t``, ``y``, ``f``, ``h_abs``, ``max_step``,
``t_bound``, the last step's ``t_old``, ``y_old``, ``h_previous`` and stages ``K_extended``,
and ``dense_output()``, whose arithmetic is compiled (scipy's costs more than the stages'
motion on a small model; it equals scipy's to a few units of rounding).

Why not scipy's own class: importing scipy.integrate loads scipy.optimize and scipy.special
as well, about 0.15 s of every new process that simulates (a tenth of a warm run's whole
process); the other integrators (stepper.METHODS) still come from scipy, imported when a
run asks for one.

A step is taken in compiled code where the run's right-hand side can (``derivative``: the
run's StateDerivative, whose ``step`` returns None where it cannot), else here in numpy.
"""

import warnings

import numpy as np
from numba import njit

from ..core import dop853_tableau as tableau
from ..core.dop853_tableau import MAX_FACTOR, MIN_FACTOR, SAFETY
from ..core.tolerances import EPS, FIRST_STEP_FLAT, FIRST_STEP_GUESS, FIRST_STEP_ZERO_NORM


class DOP853:
    """DOP853 on ẏ = fun(t, y) from (t0, y0) towards t_bound (module docstring); the
    arguments as scipy's ``DOP853`` takes them (rtol a number, atol a number or one per entry
    of y, first_step None: chosen as scipy chooses it; no defaults: the run loop's are its own)."""

    TOO_SMALL_STEP = "Required step size is less than spacing between numbers."  # scipy's message
    n_stages, order, error_estimator_order = tableau.N_STAGES, 8, 7
    A = tableau.A[:n_stages, :n_stages]
    B = tableau.B
    C = tableau.C[:n_stages]
    E3, E5, D = tableau.E3, tableau.E5, tableau.D
    A_EXTRA = tableau.A[n_stages + 1:]
    C_EXTRA = tableau.C[n_stages + 1:]
    derivative = None  # the run's StateDerivative where its steps may be compiled (stepper.start)

    def __init__(self, fun, t0, y0, t_bound, *, rtol, atol, max_step=np.inf, first_step=None):
        y0 = np.asarray(y0).astype(float, copy=False)
        if y0.ndim != 1:
            raise ValueError("`y0` must be 1-dimensional.")
        if not np.isfinite(y0).all():
            raise ValueError("All components of the initial state `y0` must be finite.")
        if max_step <= 0:
            raise ValueError("`max_step` must be positive.")
        self.fun, self.t, self.y, self.t_bound, self.max_step = fun, t0, y0, t_bound, max_step
        self.t_old = self.y_old = self.h_previous = None
        self.direction = np.sign(t_bound - t0) if t_bound != t0 else 1
        self.n, self.status = y0.size, "running"
        self.rtol, self.atol = _tolerances(rtol, atol, self.n)
        self.f = self.fun(self.t, self.y)
        if first_step is None:
            self.h_abs = _initial_step(self.fun, self.t, self.y, t_bound, max_step, self.f, self.direction,
                                       self.error_estimator_order, self.rtol, self.atol)
        else:
            if first_step <= 0:
                raise ValueError("`first_step` must be positive.")
            if first_step > np.abs(t_bound - t0):
                raise ValueError("`first_step` exceeds bounds.")
            self.h_abs = first_step
        self.K_extended = np.empty((tableau.N_STAGES_EXTENDED, self.n))
        self.K = self.K_extended[:self.n_stages + 1]
        self.error_exponent = -1 / (self.error_estimator_order + 1)

    @property
    def step_size(self):
        """The last step's size (None before the first)."""
        return None if self.t_old is None else np.abs(self.t - self.t_old)

    def step(self):
        """One step (scipy's OdeSolver.step); returns None, or why the solver failed."""
        if self.status != "running":
            raise RuntimeError("Attempt to step on a failed or finished solver.")
        if self.n == 0 or self.t == self.t_bound:
            self.t_old, self.t, self.status = self.t, self.t_bound, "finished"
            return None
        t = self.t
        success, message = self._step_impl()
        if not success:
            self.status = "failed"
        else:
            self.t_old = t
            if self.direction * (self.t - self.t_bound) >= 0:
                self.status = "finished"
        return message

    def _step_impl(self):
        """One accepted step, compiled where ``derivative`` takes it, else ``_numpy_step``:
        (True, None), or (False, TOO_SMALL_STEP)."""
        taken = None if self.derivative is None else self.derivative.step(self)
        return self._numpy_step() if taken is None else taken

    def _numpy_step(self):
        """scipy's RungeKutta._step_impl: trial steps until the error norm is below 1."""
        t, y, rtol, atol = self.t, self.y, self.rtol, self.atol
        min_step = 10 * np.abs(np.nextafter(t, self.direction * np.inf) - t)
        h_abs = self.max_step if self.h_abs > self.max_step else (min_step if self.h_abs < min_step else self.h_abs)
        rejected = False
        while True:
            if h_abs < min_step:
                return False, self.TOO_SMALL_STEP
            t_new = t + h_abs * self.direction
            if self.direction * (t_new - self.t_bound) > 0:
                t_new = self.t_bound
            h = t_new - t
            h_abs = np.abs(h)
            y_new, f_new = self._stages(t, y, h)
            scale = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
            error_norm = self._error_norm(self.K, h, scale)
            if error_norm < 1:
                factor = MAX_FACTOR if error_norm == 0 else min(MAX_FACTOR, SAFETY * error_norm ** self.error_exponent)
                h_abs *= min(1, factor) if rejected else factor
                break
            h_abs *= max(MIN_FACTOR, SAFETY * error_norm ** self.error_exponent)
            rejected = True
        self.h_previous, self.y_old = h, y
        self.t, self.y, self.h_abs, self.f = t_new, y_new, h_abs, f_new
        return True, None

    def _stages(self, t, y, h):
        """The step's stages into K and (y_new, f_new) (scipy's rk_step)."""
        K = self.K
        K[0] = self.f
        for s, (a, c) in enumerate(zip(self.A[1:], self.C[1:]), start=1):
            K[s] = self.fun(t + c * h, y + np.dot(K[:s].T, a[:s]) * h)
        y_new = y + h * np.dot(K[:-1].T, self.B)
        f_new = self.fun(t + h, y_new)
        K[-1] = f_new
        return y_new, f_new

    def _error_norm(self, K, h, scale):
        """DOP853's error norm: the 5th-order estimate tempered by the 3rd (dop853.f)."""
        err5 = np.dot(K.T, self.E5) / scale
        err3 = np.dot(K.T, self.E3) / scale
        err5_norm_2 = np.linalg.norm(err5) ** 2
        err3_norm_2 = np.linalg.norm(err3) ** 2
        if err5_norm_2 == 0 and err3_norm_2 == 0:
            return 0.0
        return np.abs(h) * err5_norm_2 / np.sqrt((err5_norm_2 + 0.01 * err3_norm_2) * len(scale))

    def dense_output(self):
        """The interpolant of the last step (``Interpolant``): its three extra stages
        evaluated in compiled code where ``derivative`` can (as the steps), else through ``fun``."""
        if self.t_old is None:
            raise RuntimeError("Dense output is available after a successful step was made.")
        if self.n == 0 or self.t == self.t_old:
            return Interpolant(self.t_old, self.t, self.y, np.zeros((0, self.n)))
        K, h, t_old, y_old = self.K_extended, self.h_previous, self.t_old, self.y_old
        done = 0 if self.derivative is None else self.derivative.extra(self)
        for s, (a, c) in enumerate(zip(self.A_EXTRA[done:], self.C_EXTRA[done:]), start=self.n_stages + 1 + done):
            K[s] = self.fun(t_old + c * h, _stage_state(K, a, s, h, y_old))
        F = np.empty((tableau.INTERPOLATOR_POWER, self.n))
        _coefficients(K, self.D, h, self.y, y_old, self.f, F)
        return Interpolant(t_old, self.t, y_old, F)


class Interpolant:
    """y(t) = y_old + x (F₀ + (1 − x)(F₁ + x (F₂ + (1 − x)(…)))), x = (t − t_old)/(t_new − t_old)
    (no F: the constant y_old), called as scipy's dense output is (a number: a state; an array
    of times: a column per time) or written into rows (``into``)."""

    def __init__(self, t_old, t, y_old, F):
        self.t_old, self.h, self.y_old, self.F = t_old, t - t_old, y_old, F

    def __call__(self, t):
        t = np.asarray(t, dtype=float)
        if t.ndim > 1:
            raise ValueError("`t` must be a float or a 1-D array.")
        out = np.empty((t.size, self.y_old.size))
        self.into(t.reshape(-1), out)
        return out[0] if t.ndim == 0 else out.T

    def into(self, times, out):
        """The states at ``times`` (a 1-d float array), a row each, into ``out``."""
        _rows(times, self.t_old, self.h, self.F, self.y_old, out)


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
    factors, alternating) at x = (t_j − t_old)/h (no F: y_old)."""
    for j in range(times.shape[0]):
        x = (times[j] - t_old) / h if F.shape[0] else 0.0
        out[j] = y_old
        p = 1.0
        for k in range(F.shape[0]):
            p *= x if k % 2 == 0 else 1.0 - x
            for c in range(y_old.shape[0]):
                out[j, c] += p * F[k, c]


def _tolerances(rtol, atol, n):
    """(rtol, atol) as scipy's validate_tol checks them, rtol raised to 100 ε with a warning;
    atol one per entry (the compiled steps read it so; the sums are scipy's all the same)."""
    if np.any(rtol < 100 * EPS):
        warnings.warn(f"At least one element of `rtol` is too small. Setting `rtol = np.maximum(rtol, {100 * EPS})`.",
                      stacklevel=4)
        rtol = np.maximum(rtol, 100 * EPS)
    atol = np.asarray(atol)
    if atol.ndim > 0 and atol.shape != (n,):
        raise ValueError("`atol` has wrong shape.")
    if np.any(atol < 0):
        raise ValueError("`atol` must be positive.")
    return rtol, np.broadcast_to(atol, (n,)).astype(float)


def _rms(x):
    return np.linalg.norm(x) / x.size ** 0.5


def _initial_step(fun, t0, y0, t_bound, max_step, f0, direction, order, rtol, atol):
    """The first step size (Hairer, Nørsett & Wanner II.4; scipy's select_initial_step)."""
    if y0.size == 0:
        return np.inf
    interval_length = abs(t_bound - t0)
    if interval_length == 0.0:
        return 0.0
    scale = atol + np.abs(y0) * rtol
    d0, d1 = _rms(y0 / scale), _rms(f0 / scale)
    h0 = FIRST_STEP_GUESS if d0 < FIRST_STEP_ZERO_NORM or d1 < FIRST_STEP_ZERO_NORM else 0.01 * d0 / d1
    h0 = min(h0, interval_length)
    f1 = fun(t0 + h0 * direction, y0 + h0 * direction * f0)
    d2 = _rms((f1 - f0) / scale) / h0
    h1 = max(FIRST_STEP_GUESS, h0 * 1e-3) if d1 <= FIRST_STEP_FLAT and d2 <= FIRST_STEP_FLAT else \
        (0.01 / max(d1, d2)) ** (1 / (order + 1))
    return min(100 * h0, h1, interval_length, max_step)
