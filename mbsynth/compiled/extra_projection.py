"""Putting a state of a model of extra coordinates alone (planar bodies, energy-defined parts,
expression constraints: no kernel node) back on its constraints with the kernel, in the mass
metric.

As compiled/projection.py does for the kernel's own rows: with the generated forces, C and b set to
zero and q̇ = 0, the kernel's q̈ for a right side shifted by −r is the least-M-norm Δ with
A Δ = −r ((2.14) with Q = 0). Positions: Gauss–Newton steps with r = φ, the generated φ of
the extra rows, while a row's |φ| exceeds MASS_PROJECTION_RTOL of its terms (Σ_j |A_ij q_j|, as
core/equations.term_scales: alike at every scale), at most MAX_STEPS of them; then
velocities, one step with r = φ̇ = A q̇ + ∂φ/∂t (linear). A velocity step must cut each row's φ̇ by
MASS_PROJECTION_SHRINK at least, or leave it below MASS_PROJECTION_RATE_RTOL of its terms. The
kernel is called at the state's relative drift, as compiled/projection.py calls it: it takes a
step only where the rows are certainly independent (certify.py; a mass that is not definite,
the spin-up beam's, through the mass augmented by the rows). A state the kernel declines (rows
nearly dependent, or contradicting) or whose steps do not meet these goals goes to
analysis/projection.py (None), as with compiled/projection.py.

Only for Systems whose every coordinate is an extra coordinate, every extra row has a φ
(holonomic rows: a velocity-level row has no position to project). Masses and rows
that depend on time (a servo's prescribed angle) are evaluated at each state's t, their
∂φ/∂t among the generated outputs (engine.Template.phi_rates). The banded Schur step of a larger
model (kernel.py; layout.DENSE_SCHUR_MAX) declines states near a singular position, and
there the mass metric moves the velocity far more than analysis/projection.py's (a velocity 1e-10 off
the N = 40 four-bar's manifold 1e-4 rad from a horizontal position is put 1e-6 from the
exact one; analysis/projection.py: 2e-8): a run steps across such positions with its stages kept
away from them (analysis/crossing.py), from the rows' ``measure``, which its singular watch
gives where the model is small. Its energies are left to the Data (``energies`` False); the
run's singular watch goes on through its states (``watched``).

A projection and a drift are each one compiled call (``project``, ``drift``), with the
model's generated function and the kernel called through their addresses (pointers.py), as
staged.py's stages call them.
"""

import copy
import threading

import numpy as np
from numba import njit, typeof

from . import kernel
from .bodies import OPTIONS
from .kernel import OK, UNCHECKED, WORK
from .least_direction import LeastDirection
from .packing import view1
from .pointers import address, caster
from .projection import DONE, MAX_STEPS, PHI_MAX, PSI_MAX, TINY, ProjectedRows
from .rows import largest, relative_drift
from .staged import evaluate, evaluation_of, rates_signature
from ..core.tolerances import MASS_PROJECTION_RATE_RTOL, MASS_PROJECTION_RTOL, MASS_PROJECTION_SHRINK, DRIFT_FLOOR, TERM_FLOOR


_motion = caster(rates_signature)  # the kernel's one entry (kernel.motion_rates), asked for no rates


class ExtraProjection:
    """The kernel's projection of an Engine whose model has extra coordinates alone."""

    energies = False  # Projected's kinetic and potential energy are not computed here
    watched = True  # the run's singular watch measures the states it projects (analysis/singular_watch.py)

    def __init__(self, engine):
        L = engine.L
        self.n = engine.n
        counts = [L.gen_q.size, L.gen_c.size, L.gen_mi.size, L.gen_arow.size, L.gen_brow.size]
        starts = np.cumsum([0] + counts)
        self.rows, self.columns = L.gen_arow, L.x_coord[L.gen_acol]
        self.xrow_row, self.m = L.xrow_row, int(L.sizes[1])
        self.entries = slice(int(starts[3]), int(starts[4]))  # the rows' entries in gen
        self.gen = np.zeros(engine.outputs)
        phi_from = engine.outputs - engine.template.phi_outputs
        rates_from = phi_from - engine.template.phi_rates if engine.template.phi_rates else -1
        packed_work, _ = engine.new_work()
        kernel_c, kernel_jit = address(kernel.motion_rates, rates_signature(typeof(engine.general)))
        count = self.xrow_row.size
        # rows, columns, their entries, Q and C to zero, b to zero, φ and ∂φ/∂t (or −1: none) in gen, the
        # System's rows of the extra rows
        self.layout = (self.rows, self.columns, int(starts[3]), int(starts[2]), int(starts[4]), int(starts[5]),
                       phi_from, rates_from, self.xrow_row, kernel_c, kernel_jit, *engine.packed, *packed_work)
        # the right side's shift per System row, q̇ = 0, then per extra row: φ, φ̇, φ̇ before the step, term sizes
        self.work = (np.zeros(self.m), np.zeros(self.n), *(np.zeros(count) for _ in range(4)))
        self.lock = threading.Lock()
        self.least = None  # the rows' LeastDirection, made at the first ``measure``
        self._use(engine)

    def _use(self, engine):
        """Evaluate the generated function of ``engine`` (its parameter values)."""
        self.engine, self.general = engine, engine.general
        self.evaluation, self.keep = evaluation_of(engine, self.gen)

    @classmethod
    def build(cls, engine):
        """The ExtraProjection of ``engine``, or None where its model is not of extra
        coordinates alone, or has no row or a row without φ."""
        L = engine.L
        if L.node_kind.size or L.x_coord.size != engine.n or not L.xrow_row.size:
            return None
        if engine.template.phi_outputs != L.xrow_row.size:
            return None
        return cls(engine)

    def at(self, engine):
        """This projection on ``engine``, a copy of its Engine at other parameter values
        (``Engine.at``): the same buffers and lock, the rows at ``engine``'s values."""
        other = copy.copy(self)
        other._use(engine)
        return other

    def __call__(self, t, q, qd):
        """``Projected`` (q, q̇) at t on the constraints (new arrays; kinetic and potential
        energy NaN), or None (module docstring)."""
        return self.block([t], np.asarray(q, dtype=float)[None, :], np.asarray(qd, dtype=float)[None, :]).row(0)

    def block(self, times, Q, QD, fractions=None):
        """Each state (row of Q, Q̇, at its entry of ``times``) projected, as ProjectedRows
        (``fractions``, the states' fractions of a step, are not used: each state is projected
        on its own)."""
        Q_on, QD_on = np.array(Q, dtype=float, order="C"), np.array(QD, dtype=float, order="C")
        found = np.full((Q_on.shape[0], DONE + 1), np.nan)
        with self.lock:
            project(np.asarray(times, dtype=float), Q_on, QD_on, found, self.evaluation, self.layout, self.work,
                    self.general)
        return ProjectedRows(Q_on, QD_on, found)

    def measure(self, t, q, qd):
        """σ_min/σ₁ of the rows' A at (q, q̇), each row scaled to unit norm
        (least_direction.py): what a run's step plan near singular positions reads
        (analysis/crossing.py) where its singular watch does not."""
        return self._least(t, q, qd)[0]

    def least_rows(self, t, q, qd, share):
        """The System's rows that take part in the least direction of the rows' A at (t, q, q̇):
        those of weight above ``share`` of the largest."""
        weights = self._least(t, q, qd)[1]
        return tuple(int(r) for r in self.xrow_row[weights > share * weights.max(initial=0.0)])

    def rows_at(self, t, q, qd):
        """The System's A at (t, q, q̇), dense (m × n), from the rows' entries of the generated
        function (compiled), or None where the extra rows are not all of the System's."""
        if self.xrow_row.size != self.m:
            return None
        A = np.zeros((self.m, self.n))
        with self.lock:
            self._evaluate(t, q, qd)
            _dense_rows(self.gen, self.layout, A)
        return A

    def _least(self, t, q, qd):
        """(σ_min/σ₁, the rows' weights in the least direction) at (t, q, q̇)."""
        with self.lock:
            self._evaluate(t, q, qd)
            values = self.gen[self.entries].copy()
        if self.least is None:
            self.least = LeastDirection(self.rows, self.columns, self.xrow_row.size)
        return self.least(values)

    def _evaluate(self, t, q, qd):
        """The generated outputs at (t, q, q̇) into gen."""
        evaluate(float(t), np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float),
                 self.evaluation)

    def residuals_energy(self, t, q, qd):
        """(φ, φ̇ of the extra rows at (t, q, q̇), NaN, NaN): the energies are the Data's."""
        qd = np.ascontiguousarray(qd, dtype=float)
        with self.lock:
            self._evaluate(t, q, qd)
            phi, psi = np.zeros(self.xrow_row.size), np.zeros(self.xrow_row.size)
            _phi(self.gen, self.layout, phi)
            _rates(qd, self.gen, self.layout, psi)
            return phi, psi, np.nan, np.nan

    def drift(self, t, q, qd):
        """The largest |φ| or |φ̇| at (t, q, q̇) relative to its row's terms (``_terms`` with
        DRIFT_FLOOR, as analysis/projection.relative_drift)."""
        with self.lock:
            return drift(float(t), np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float),
                         self.evaluation, self.layout, self.work)


@njit(**OPTIONS)
def _dense_rows(gen, layout, A):
    """The System's A (m × n, zeros) from the rows' entries as evaluated last, each added at
    its System row and coordinate (entries at one place summed)."""
    rows, columns, entries, xrow_row = layout[0], layout[1], layout[2], layout[8]
    for e in range(rows.shape[0]):
        A[xrow_row[rows[e]], columns[e]] += gen[entries + e]


@njit(**OPTIONS)
def _terms(x, floor, gen, layout, out):
    """The size of each row's terms at x (core/equations.entry_term_scales, at least TINY) into
    ``out``, from the rows' entries as evaluated last: residuals are judged against them,
    alike at every scale."""
    rows, columns, entries = layout[0], layout[1], layout[2]
    norms = np.zeros(out.shape[0])
    out[:] = 0.0
    for e in range(rows.shape[0]):
        weight = abs(gen[entries + e])
        out[rows[e]] += weight * abs(x[columns[e]])
        norms[rows[e]] += weight
    size = largest(x)
    for r in range(out.shape[0]):
        out[r] = max(out[r] + floor * norms[r] * size, TINY)


@njit(**OPTIONS)
def _rates(qd, gen, layout, out):
    """φ̇ = A q̇ + ∂φ/∂t per extra row into ``out``, from the rows' entries (and ∂φ/∂t, where
    the rows have it) as evaluated last."""
    rows, columns, entries, rates_from = layout[0], layout[1], layout[2], layout[7]
    for r in range(out.shape[0]):
        out[r] = gen[rates_from + r] if rates_from >= 0 else 0.0
    for e in range(rows.shape[0]):
        out[rows[e]] += gen[entries + e] * qd[columns[e]]


@njit(**OPTIONS)
def _phi(gen, layout, out):
    """φ of the extra rows, as evaluated last, into ``out``."""
    for r in range(out.shape[0]):
        out[r] = gen[layout[6] + r]


@njit(**OPTIONS)
def _step(q, residual, gen, layout, work, general):
    """The least-M-norm Δ with A Δ = −residual (rows as evaluated last at q) into the Work's
    q̈: (2.14) with the generated forces, C and b zero and q̇ = 0, at q's relative drift (as
    compiled/projection.py calls the kernel: the rows certified, else declined); whether the
    kernel gave it."""
    (_, _, _, forces_to, rights_from, rights_to, phi_from, _, xrow_row, kernel_c, kernel_jit, LI, LF, LX, WI, WF,
     WX) = layout
    shift, rest = work[0], work[1]
    drift = relative_drift(0.0, gen, phi_from, phi_from + xrow_row.shape[0], q)
    for k in range(forces_to):
        gen[k] = 0.0
    for k in range(rights_from, rights_to):
        gen[k] = 0.0
    for x in range(xrow_row.shape[0]):
        shift[xrow_row[x]] = -residual[x]
    return _motion(kernel_c, kernel_jit, general)(q, rest, gen, shift, LI, LF, LX, WI, WF, WX, UNCHECKED, drift,
                                                  general, np.zeros(0, np.int64), np.zeros(0))[0] == OK


@njit(**OPTIONS)
def project(times, Q, QD, found, evaluation, layout, work, general):
    """Each state (row of Q, Q̇, at its entry of ``times``) put on the constraints in place
    (module docstring), found's row (NaN energies, PHI_MAX, PSI_MAX, DONE = 1), or DONE = 0
    and the row zero where the kernel declines a step or the steps miss their goals. Positions: Gauss–Newton steps while
    a row's |φ| exceeds MASS_PROJECTION_RTOL of its terms, at most MAX_STEPS; then one
    velocity step, which must cut each row's φ̇ by MASS_PROJECTION_SHRINK or leave it below
    MASS_PROJECTION_RATE_RTOL of its terms."""
    gen = evaluation[5]
    qdd = view1(layout[15], layout[16], WORK.qdd)
    phi, psi, before, terms = work[2], work[3], work[4], work[5]
    for b in range(Q.shape[0]):
        q, qd = Q[b], QD[b]
        found[b, DONE] = 0.0
        done = _project(times[b], q, qd, gen, qdd, phi, psi, before, terms, evaluation, layout, work, general)
        if not done:
            q[:] = 0.0
            qd[:] = 0.0
            continue
        found[b, PHI_MAX], found[b, PSI_MAX], found[b, DONE] = largest(phi), largest(psi), 1.0


@njit(**OPTIONS)
def _project(t, q, qd, gen, qdd, phi, psi, before, terms, evaluation, layout, work, general):
    """``project`` of one state at t; whether it is on the constraints (φ and φ̇ there in phi, psi)."""
    evaluate(t, q, qd, evaluation)
    _phi(gen, layout, phi)
    for step in range(MAX_STEPS + 1):
        _terms(q, TERM_FLOOR, gen, layout, terms)
        met = True
        for r in range(phi.shape[0]):
            met = met and abs(phi[r]) <= MASS_PROJECTION_RTOL * terms[r]
        if met:
            break
        if step == MAX_STEPS or not _moved(t, q, q, qd, phi, gen, qdd, phi, evaluation, layout, work, general):
            return False
    _rates(qd, gen, layout, psi)
    for r in range(psi.shape[0]):
        before[r] = abs(psi[r])
    if not _moved(t, qd, q, qd, psi, gen, qdd, phi, evaluation, layout, work, general):
        return False
    _rates(qd, gen, layout, psi)
    _terms(qd, TERM_FLOOR, gen, layout, terms)
    for r in range(psi.shape[0]):
        if not abs(psi[r]) <= max(MASS_PROJECTION_SHRINK * before[r], MASS_PROJECTION_RATE_RTOL * terms[r]):
            return False
    return True


@njit(**OPTIONS)
def _moved(t, x, q, qd, residual, gen, qdd, phi, evaluation, layout, work, general):
    """x (q or q̇) moved by ``_step``'s Δ for ``residual``, the generated outputs and φ then
    evaluated at (t, q, q̇) into gen and phi; whether the kernel gave Δ."""
    if not _step(q, residual, gen, layout, work, general):
        return False
    for c in range(x.shape[0]):
        x[c] += qdd[c]
    evaluate(t, q, qd, evaluation)
    _phi(gen, layout, phi)
    return True


@njit(**OPTIONS)
def drift(t, q, qd, evaluation, layout, work):
    """The largest |φ| or |φ̇| at (t, q, q̇) relative to its row's terms (DRIFT_FLOOR; NaN if
    any is)."""
    gen = evaluation[5]
    phi, psi, terms = work[2], work[3], work[5]
    evaluate(t, q, qd, evaluation)
    _phi(gen, layout, phi)
    _rates(qd, gen, layout, psi)
    _terms(q, DRIFT_FLOOR, gen, layout, terms)
    for r in range(phi.shape[0]):
        phi[r] /= terms[r]
    _terms(qd, DRIFT_FLOOR, gen, layout, terms)
    for r in range(psi.shape[0]):
        psi[r] /= terms[r]
    position, velocity = largest(phi), largest(psi)
    return position if position > velocity or position != position else velocity
