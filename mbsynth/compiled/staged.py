"""The run loop's stages in compiled code: ẏ at a state y in the integrator's form
(analysis/velocity_form.py), and whole steps of DOP853, one call each.

``rates`` evaluates ẏ at y as the compiled engine's motion does: (q, q̇) of y, the model's
generated function, the flexible parts' M and Q (flexible.fill), the state's relative drift
where the model closes loops (rows.relative_drift), kernel.motion_rates. ``step`` is
scipy's DOP853 step — its tableau, error norm and step-size control
(``RungeKutta._step_impl``), rejected trials included — with every stage through ``rates``;
``extra`` evaluates the three extra stages of its dense output. The Python path costs scipy's array arithmetic and a few
wrappers per stage, more than the kernel itself on a small model.

A stage the kernel declines (kernel.py's status: the exact treatment's to serve) ends the
call with DECLINED and the caller takes that step or stage again on the Python path
(analysis/derivative.py), which serves every stage: these functions are a faster way to
evaluate the same stages, not another integrator. The model's generated function and the
kernel are called through function pointers (pointers.py), so they compile once for every
model; the flexible parts' kernel and the rows' residuals too, which keeps these small to
compile. ``Stages`` holds the arrays and the addresses of one Engine.
"""

import math

import numpy as np
from numba import njit, typeof, types

from . import flexible, kernel
from ..core.dop853_tableau import MAX_FACTOR, MIN_FACTOR, SAFETY
from .bodies import OPTIONS, state_of
from .packing import pack, view1, view2, view4
from .pointers import address, caster
from .rows import relative_drift, residuals_energy

ACCEPTED, TOO_SMALL, DECLINED = range(3)  # ``step``'s outcome
PART_ARRAYS = 6  # a flexible part's kernel arrays (axes, W, s0, K, D, S: flexible_body.PartArrays)

F1, F2, F4 = types.float64[::1], types.float64[:, ::1], types.float64[:, :, :, ::1]
I1, I2 = types.int64[::1], types.int64[:, ::1]
GENERATED = types.none(types.float64, F1, F1, F1, F1)  # codegen's evaluate(t, q, qd, p, out)
FILL = types.none(F1, F1, F1, types.int64, types.int64, types.int64, types.int64, I1, F2, F1, F2, F2, F4)  # flexible.fill
RESIDUALS = types.UniTuple(types.float64, 6)(F1, F1, I1, F1, I2, F1, F1, F4, types.boolean)  # rows.residuals_energy
KERNEL_ARGUMENTS = (F1, F1, F1, F1, I1, F1, I2, I1, F1, I2, types.int64, types.float64)  # up to ``general``


def rates_signature(general):
    """kernel.motion_rates's signature in the variant whose ``general`` has the numba type given."""
    return types.Tuple((types.int64, types.float64))(*KERNEL_ARGUMENTS, general, I1, F1)


_generated, _fill, _residuals = caster(lambda _: GENERATED), caster(lambda _: FILL), caster(lambda _: RESIDUALS)
_kernel_rates = caster(rates_signature)


@njit(**OPTIONS)
def evaluate(t, q, qd, evaluation):
    """The generated function's outputs at (t, q, q̇) into gen, the flexible parts' M and Q
    among them (flexible.fill). ``evaluation``: ``evaluation_of``'s first item."""
    generated_c, generated_jit, fill_c, fill_jit, p, gen, own_meta, own_ints, own_floats, own_index = evaluation
    if generated_c != 0:
        _generated(generated_c, generated_jit, None)(t, q, qd, p, gen)
    for part in range(own_meta.shape[0]):
        k = PART_ARRAYS * part
        _fill(fill_c, fill_jit, None)(q, qd, gen, own_meta[part, 0], own_meta[part, 1], own_meta[part, 2],
                                      own_meta[part, 3], view1(own_ints, own_index, k),
                                      view2(own_floats, own_index, k + 1), view1(own_floats, own_index, k + 2),
                                      view2(own_floats, own_index, k + 3), view2(own_floats, own_index, k + 4),
                                      view4(own_floats, own_index, k + 5))


def evaluation_of(engine, gen):
    """(``evaluate``'s tuple for ``engine``'s generated function and flexible parts, writing
    into ``gen``; the code its addresses point into, to be kept while it is used)."""
    module = engine.module
    own = getattr(module, "own", ())
    generated = getattr(module, "generated", module)
    p = np.array(engine.p, dtype=float)  # writeable and C-contiguous: the pointer's signature
    generated_c, generated_jit = (0, 0) if generated is None else address(generated.evaluate, GENERATED)
    fill_c, fill_jit = address(flexible.fill, FILL) if own else (0, 0)
    own_meta = np.array([(o.start, o.m0, o.q0, o.g0) for o in own], dtype=np.int64).reshape(-1, 4)
    own_ints, own_floats, own_index = pack([np.asarray(a) for o in own for a in o.arrays])
    return (generated_c, generated_jit, fill_c, fill_jit, p, gen, own_meta, own_ints, own_floats, own_index), \
        (generated, module)


@njit(**OPTIONS)
def rates(t, y, out, bundle, general):
    """ẏ at (t, y) into ``out`` (the integrator's form); returns kernel.py's status (out is
    left as it was unless OK). ``bundle``: Stages.bundle; ``general``: the kernel's variant."""
    (evaluation, residuals_c, residuals_jit, kernel_c, kernel_jit, q, qd, starts, closes, phi_from, phi_to, phi, psi,
     Rs, LI, LF, LX, WI, WF, WX, mode) = bundle
    state_of(y, starts, q, qd)
    evaluate(t, q, qd, evaluation)
    gen = evaluation[5]
    drift = -1.0
    if closes:
        phi_max = _residuals(residuals_c, residuals_jit, None)(q, qd, LI, LF, LX, phi, psi, Rs, False)[2]
        drift = relative_drift(phi_max, gen, phi_from, phi_to, q)
    empty = np.zeros(0)
    return _kernel_rates(kernel_c, kernel_jit, general)(q, qd, gen, empty, LI, LF, LX, WI, WF, WX, mode, drift,
                                                         general, starts, out)[0]


@njit(**OPTIONS)
def _stage(t, h, y, K, a, s, out, bundle, general):
    """K[s] ← ẏ at (t, y + h Σ_{i<s} a_i K_i), ``out`` holding that state; returns the status.
    The sum runs along K's rows (contiguous: three times faster than down its columns), each
    entry's terms in the same order."""
    n = y.shape[0]
    for c in range(n):
        out[c] = 0.0
    for i in range(s):
        Ki, ai = K[i], a[i]
        for c in range(n):
            out[c] += Ki[c] * ai
    for c in range(n):
        out[c] = y[c] + out[c] * h
    return rates(t, out, K[s], bundle, general)


@njit(**OPTIONS)
def step(t, y, f, h_abs, t_bound, max_step, rtol, atol, direction, A, B, C, E3, E5, exponent, K, y_new, f_new,
         stage, bundle, general):
    """One DOP853 step from (t, y) with f = ẏ there, as scipy's ``RungeKutta._step_impl``
    takes it: its stages into K, the solution and its ẏ into y_new, f_new. Returns
    (outcome, t_new, h, the next step's h_abs, evaluations): ACCEPTED; TOO_SMALL (the step
    size fell below ten units of t's rounding, as scipy's message); DECLINED (a stage the
    kernel declined: nothing is decided, the caller takes the step again). Each retry cuts
    the step by at least SAFETY (by MIN_FACTOR where the error norm is not finite), so the
    loop ends at TOO_SMALL at the latest."""
    n, stages = y.shape[0], A.shape[0]
    min_step = 10.0 * abs(np.nextafter(t, direction * np.inf) - t)
    h_abs = max_step if h_abs > max_step else max(h_abs, min_step)
    rejected, evaluations = False, 0
    while True:
        if h_abs < min_step:
            return TOO_SMALL, t, 0.0, h_abs, evaluations
        t_new = t + h_abs * direction
        if direction * (t_new - t_bound) > 0:
            t_new = t_bound
        h = t_new - t
        h_abs = abs(h)
        K[0] = f
        for s in range(1, stages):
            evaluations += 1
            if _stage(t + C[s] * h, h, y, K, A[s], s, stage, bundle, general) != kernel.OK:
                return DECLINED, t, h, h_abs, evaluations
        evaluations += 1
        if _stage(t + h, h, y, K, B, stages, y_new, bundle, general) != kernel.OK:
            return DECLINED, t, h, h_abs, evaluations
        f_new[:] = K[stages]
        err5 = err3 = 0.0
        for c in range(n):
            scale = atol[c] + max(abs(y[c]), abs(y_new[c])) * rtol
            e5 = e3 = 0.0
            for i in range(stages + 1):
                e5 += K[i, c] * E5[i]
                e3 += K[i, c] * E3[i]
            err5 += (e5 / scale) ** 2
            err3 += (e3 / scale) ** 2
        norm = 0.0 if err5 == 0.0 and err3 == 0.0 else h_abs * err5 / math.sqrt((err5 + 0.01 * err3) * n)
        if norm < 1.0:
            factor = MAX_FACTOR if norm == 0.0 else min(MAX_FACTOR, SAFETY * norm ** exponent)
            return ACCEPTED, t_new, h, h_abs * (min(1.0, factor) if rejected else factor), evaluations
        h_abs *= max(MIN_FACTOR, SAFETY * norm ** exponent)
        rejected = True


@njit(**OPTIONS)
def extra(t_old, h, y_old, K, A, C, first, stage, bundle, general):
    """DOP853's extra stages K[first + j] (j < len(C)) of the step from (t_old, y_old) of
    size h; returns how many were evaluated before one the kernel declined (all: len(C))."""
    for j in range(C.shape[0]):
        if _stage(t_old + C[j] * h, h, y_old, K, A[j], first + j, stage, bundle, general) != kernel.OK:
            return j
    return C.shape[0]


class Stages:
    """The compiled stages of one Engine (its buffers, parameter values and code) for states
    in the integrator's form with rigid bodies' quaternions at ``starts``
    (velocity_form.VelocityForm.starts). The caller holds the Engine's lock around a call."""

    def __init__(self, engine, starts):
        self.engine, self.general, self.n = engine, engine.general, engine.n
        self.size = 2 * engine.n - starts.size
        evaluation, self.keep = evaluation_of(engine, engine.gen)
        kernel_c, kernel_jit = address(kernel.motion_rates, rates_signature(typeof(engine.general)))
        closes = engine.rows is not None
        residuals_c, residuals_jit = address(residuals_energy, RESIDUALS) if closes else (0, 0)
        phi, psi, Rs = (engine.rows.phi, engine.rows.psi, *engine.rows.work) if closes else \
            (np.zeros(0), np.zeros(0), np.zeros((1, 2, 3, 3)))
        self.bundle = (evaluation, residuals_c, residuals_jit, kernel_c, kernel_jit, np.zeros(self.n),
                       np.zeros(self.n), starts, closes, engine.generated_phi.start, engine.generated_phi.stop, phi,
                       psi, Rs, *engine.buffers, engine.mode)
        self.stage = np.empty(self.size)

    def rates(self, t, y):
        """ẏ at (t, y), a new array, or None where the kernel declines the stage."""
        out = np.empty(self.size)
        y = np.ascontiguousarray(y, dtype=float)
        with self.engine.lock:
            status = rates(float(t), y, out, self.bundle, self.general)
        return out if status == kernel.OK else None

    def step(self, solver):
        """One step of the DOP853 ``solver`` (analysis/dop853.py) in compiled code, its state
        written as its ``_step_impl`` writes it: (True, None) for a step taken, (False,
        message) where the step size fell too small, None where a stage was declined (the
        solver untouched: its step is the Python path's). Also returns the evaluations made:
        (result, evaluations)."""
        y_new, f_new = np.empty(self.size), np.empty(self.size)
        with self.engine.lock:
            outcome, t_new, h, h_abs, evaluations = step(
                solver.t, solver.y, solver.f, solver.h_abs, solver.t_bound, solver.max_step, solver.rtol,
                solver.atol, float(solver.direction), solver.A, solver.B, solver.C, solver.E3, solver.E5,
                solver.error_exponent, solver.K, y_new, f_new, self.stage, self.bundle, self.general)
        if outcome == DECLINED:
            return None, evaluations
        if outcome == TOO_SMALL:
            return (False, solver.TOO_SMALL_STEP), evaluations
        solver.h_previous, solver.y_old = h, solver.y
        solver.t, solver.y, solver.h_abs, solver.f = t_new, y_new, h_abs, f_new
        return (True, None), evaluations

    def extra(self, solver, K, first):
        """The extra stages of the solver's last step into K[first:]; returns how many were
        evaluated before one the kernel declined."""
        with self.engine.lock:
            return extra(solver.t_old, solver.h_previous, solver.y_old, K, solver.A_EXTRA, solver.C_EXTRA, first,
                         self.stage, self.bundle, self.general)
