"""Putting a state of a model of extra coordinates alone (planar bodies, energy-defined parts,
expression constraints: no kernel node) back on its constraints with the kernel, in the mass
metric.

As compiled/projection.py does for the kernel's own rows: with the generated forces, C and b set to
zero and q̇ = 0, the kernel's q̈ for a right side shifted by −r is the least-M-norm Δ with
A Δ = −r ((2.14) with Q = 0). Positions: Gauss–Newton steps with r = φ, the generated φ of
the extra rows, while a row's |φ| exceeds MASS_PROJECTION_RTOL of its terms (Σ_j |A_ij q_j|, as
core/equations.term_scales: alike at every scale), at most MAX_STEPS of them; then
velocities, one step with r = φ̇ = A q̇ (linear). A velocity step must cut each row's φ̇ by
MASS_PROJECTION_SHRINK at least, or leave it below MASS_PROJECTION_RATE_RTOL of its terms. A state the
kernel declines (its dense Schur step finds the rows contradict) or whose steps do not meet these goals goes
to analysis/projection.py (None), as with compiled/projection.py.

Only for Systems whose every coordinate is an extra coordinate, every extra row has a φ
(holonomic rows: a velocity-level row has no position to project), whose masses and rows
do not depend on time (a projection is called without t). The banded Schur step of a larger
model (kernel.py; layout.DENSE_SCHUR_MAX) declines states near a singular position, and
there the mass metric moves the velocity far more than analysis/projection.py's (a velocity 1e-10 off
the N = 40 four-bar's manifold 1e-4 rad from a horizontal position is put 1e-6 from the
exact one; analysis/projection.py: 2e-8): a run steps across such positions with its stages kept
away from them (analysis/crossing.py), from the rows' ``measure``, which its singular watch
gives where the model is small. Its energies are left to the Data (``energies`` False); the
run's singular watch goes on through its states (``watched``).
"""

import copy
import threading

import numpy as np

from . import kernel
from .projection import MAX_STEPS, TINY, Projected, ProjectedRows
from ..core.equations import entry_term_scales
from ..core.tolerances import MASS_PROJECTION_RATE_RTOL, MASS_PROJECTION_RTOL, MASS_PROJECTION_SHRINK, DRIFT_FLOOR, TERM_FLOOR
from .least_direction import LeastDirection


class ExtraProjection:
    """The kernel's projection of an Engine whose model has extra coordinates alone."""

    energies = False  # Projected's kinetic and potential energy are not computed here
    watched = True  # the run's singular watch measures the states it projects (analysis/singular_watch.py)

    def __init__(self, engine):
        L = engine.L
        self.engine, self.n = engine, engine.n
        counts = [L.gen_q.size, L.gen_c.size, L.gen_mi.size, L.gen_arow.size, L.gen_brow.size]
        starts = np.cumsum([0] + counts)
        self.forces = slice(0, int(starts[2]))  # Q additions and C
        self.entries = slice(int(starts[3]), int(starts[4]))  # the rows' entries
        self.rights = slice(int(starts[4]), int(starts[5]))  # their b
        self.phi = slice(engine.outputs - engine.template.phi_outputs, engine.outputs)
        self.rows, self.columns = L.gen_arow, L.x_coord[L.gen_acol]
        self.xrow_row, self.m = L.xrow_row, int(L.sizes[1])
        self.gen = np.zeros(engine.outputs)
        self.shift = np.zeros(self.m)
        self.rest = np.zeros(self.n)
        packed_work, self.W = engine.new_work()
        self.buffers = (*engine.packed, *packed_work)
        self.lock = threading.Lock()
        self.least = None  # the rows' LeastDirection, made at the first ``measure``

    @classmethod
    def build(cls, engine):
        """The ExtraProjection of ``engine``, or None where its model is not of extra
        coordinates alone, has no row or a row without φ, or rows or masses that depend on t
        (Template.rows_depend_on_time)."""
        L, template = engine.L, engine.template
        if L.node_kind.size or L.x_coord.size != engine.n or not L.xrow_row.size:
            return None
        if template.phi_outputs != L.xrow_row.size or template.rows_depend_on_time:
            return None
        return cls(engine)

    def at(self, engine):
        """This projection on ``engine``, a copy of its Engine at other parameter values
        (``Engine.at``): the same buffers and lock, the rows at ``engine``'s values."""
        other = copy.copy(self)
        other.engine = engine
        return other

    def _evaluate(self, q, qd):
        """The generated outputs at (q, q̇) (t = 0: they do not depend on it)."""
        self.engine.module.evaluate(0.0, q, qd, self.engine.p, self.gen)

    def _rates(self, qd):
        """φ̇ = A q̇ per extra row, from the rows' entries as evaluated last."""
        return np.bincount(self.rows, weights=self.gen[self.entries] * qd[self.columns], minlength=self.xrow_row.size)

    def _terms(self, x, floor):
        """The size of each row's terms at x (core/equations.term_scales), from the rows'
        entries as evaluated last: residuals are judged against them, alike at every scale."""
        scales = entry_term_scales(self.rows, self.columns, self.gen[self.entries], self.xrow_row.size, x, floor)
        return np.maximum(scales, TINY)

    def _step(self, q, residual):
        """The least-M-norm Δ with A Δ = −residual (rows as evaluated last at q), or None
        where the kernel declines it."""
        gen = self.gen
        gen[self.forces] = 0.0
        gen[self.rights] = 0.0
        self.shift[self.xrow_row] = -residual
        status = kernel.motion(q, self.rest, gen, self.shift, *self.buffers, kernel.UNCHECKED, -1.0,
                               self.engine.general)[0]
        return self.W.qdd.copy() if status == kernel.OK else None

    def __call__(self, q, qd):
        """``Projected`` (q, q̇) on the constraints (new arrays; kinetic and potential energy
        NaN), or None (module docstring)."""
        with self.lock:
            q, qd = np.array(q, dtype=float), np.array(qd, dtype=float)
            self._evaluate(q, qd)
            phi = self.gen[self.phi].copy()
            for step in range(MAX_STEPS + 1):
                if np.all(np.abs(phi) <= MASS_PROJECTION_RTOL * self._terms(q, TERM_FLOOR)):
                    break
                delta = None if step == MAX_STEPS else self._step(q, phi)
                if delta is None:
                    return None
                q += delta
                self._evaluate(q, qd)
                phi = self.gen[self.phi].copy()
            psi = self._rates(qd)
            before = np.abs(psi)
            delta = self._step(q, psi)
            if delta is None:
                return None
            qd += delta
            self._evaluate(q, qd)
            psi = self._rates(qd)
            if not np.all(np.abs(psi) <= np.maximum(MASS_PROJECTION_SHRINK * before,
                                                    MASS_PROJECTION_RATE_RTOL * self._terms(qd, TERM_FLOOR))):
                return None
            return Projected(q, qd, np.nan, np.nan, float(np.abs(self.gen[self.phi]).max(initial=0.0)),
                             float(np.abs(psi).max(initial=0.0)))

    def block(self, Q, QD, fractions=None):
        """``__call__`` of each state (row of Q, Q̇), as ProjectedRows (``fractions``, the
        states' fractions of a step, are not used: each state is projected on its own)."""
        return ProjectedRows.of([self(q, qd) for q, qd in zip(Q, QD)], self.n)

    def measure(self, q, qd):
        """σ_min/σ₁ of the rows' A at (q, q̇), each row scaled to unit norm
        (least_direction.py): what a run's step plan near singular positions reads
        (analysis/crossing.py) where its singular watch does not."""
        return self._least(q, qd)[0]

    def least_rows(self, q, qd, share):
        """The System's rows that take part in the least direction of the rows' A at (q, q̇):
        those of weight above ``share`` of the largest."""
        weights = self._least(q, qd)[1]
        return tuple(int(r) for r in self.xrow_row[weights > share * weights.max(initial=0.0)])

    def _least(self, q, qd):
        """(σ_min/σ₁, the rows' weights in the least direction) at (q, q̇)."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        with self.lock:
            self._evaluate(q, qd)
            values = self.gen[self.entries].copy()
        if self.least is None:
            self.least = LeastDirection(self.rows, self.columns, self.xrow_row.size)
        return self.least(values)

    def residuals_energy(self, q, qd):
        """(φ, φ̇ of the extra rows, NaN, NaN): the energies are the Data's."""
        with self.lock:
            self._evaluate(np.asarray(q, dtype=float), np.asarray(qd, dtype=float))
            return self.gen[self.phi].copy(), self._rates(np.asarray(qd, dtype=float)), np.nan, np.nan

    def drift(self, q, qd):
        """The largest |φ| or |φ̇| relative to its row's terms (``_terms`` with DRIFT_FLOOR,
        as analysis/projection.relative_drift)."""
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        with self.lock:
            self._evaluate(q, qd)
            return max(float((np.abs(self.gen[self.phi]) / self._terms(q, DRIFT_FLOOR)).max(initial=0.0)),
                       float((np.abs(self._rates(qd)) / self._terms(qd, DRIFT_FLOOR)).max(initial=0.0)))
