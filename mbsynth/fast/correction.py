"""Putting a state back on the constraints with the kernel itself, in the mass metric.

At q̇ = 0, with no gravity and no generated forces, the kernel's Q and b vanish (every
b term of a kernel row is quadratic in q̇), so its q̈ for a right side shifted by −r is
the least-M-norm Δ with A Δ = −r ((2.14) with Q = 0). One such call is a Gauss–Newton
step of the projection in the mass metric: positions with r = φ(q) (repeated while φ is
above TOLERANCE of the coordinates' size, at most MAX_STEPS times), then velocities with
r = φ̇(q, q̇) = A q̇, a linear problem one step solves. From an integrator's drift of
5e-9 one step leaves rounding (2e-15 on a UR5). After a single position step of at most
REUSE of the coordinates' size, with φ̇ at most REUSE of the rates, the velocity step
reuses that step's factorization: A at the uncorrected q leaves φ̇ off by about
|Δq| |Δq̇|, REUSE² relative. The kernel's own residual check is skipped (kernel.UNCHECKED):
the rows after each step check it, and a velocity step that does not cut φ̇ sends the
state to projection.py. A correction costs a kernel call with its factorization, one
that reuses it and three passes of the rows (on talos about 45, 31 and 3 × 11 µs), where
projection.py's sparse factorization costs a millisecond (UR5) to ten (talos).

Only for Systems all of whose rows and coordinates the kernel's tree covers (rows.py's
``covers``; no loops, no extra coordinates); elsewhere, and at any state the kernel
declines, the caller projects with projection.py.
"""

import threading
from typing import NamedTuple

import numpy as np

from . import kernel
from .rows import Rows

TOLERANCE = 1e-14  # largest |φ| left, relative to the largest coordinate (at least 1): about 50 ε
MAX_STEPS = 3  # position steps before the state goes to projection.py
REUSE = 1e-8  # the largest position step and φ̇ (relative) for which the velocity step reuses a factorization
SHRINK = 1e-3  # a velocity step must cut φ̇ by this much at least ...
ROUNDING = 1e-12  # ... or to this, relative to the largest coordinate (at least 1) times the largest rate
TINY = np.finfo(float).tiny  # the largest rate's floor


class Corrected(NamedTuple):
    """A corrected state and, there (rows.py), the kinetic and potential energy and the
    largest |φ| and |φ̇|."""

    q: np.ndarray
    qd: np.ndarray
    kinetic: float
    potential: float
    phi_max: float
    psi_max: float


class Correction:
    """The kernel's projection: ``rows`` (rows.py) on an Engine's Layout and ``at_rest``, that
    Engine with no gravity (Engine.at_rest)."""

    def __init__(self, rows, at_rest):
        self.rows, self.at_rest = rows, at_rest
        self.rest, self.no_forces = np.zeros(at_rest.n), np.zeros(at_rest.outputs)
        self.lock = threading.Lock()  # Systems that differ in parameters only share it (Engine.at)

    @classmethod
    def build(cls, engine):
        """The Correction on ``engine``'s Layout, or None where its kernel does not cover the System."""
        rows = Rows(engine.L, engine.packed, int(engine.L.sizes[1]))
        return cls(rows, engine.at_rest()) if rows.covers else None

    def __call__(self, q, qd):
        """``Corrected`` (q, q̇) on the constraints (new arrays) with their rows, or None where
        the kernel declines a state, MAX_STEPS position steps leave φ above TOLERANCE, or the
        velocity step leaves φ̇ above SHRINK of what it was (and above rounding)."""
        with self.lock:
            phi, psi, _, _, phi_max, psi_max, q_max, qd_max = self.rows(q, qd)
            size = max(q_max, 1.0)
            factored = None  # the q of a single small position step: its factorization the Work holds
            for step in range(MAX_STEPS + 1):
                if phi_max <= TOLERANCE * size:
                    break
                delta = None if step == MAX_STEPS else self._delta(q, phi, kernel.UNCHECKED)
                if delta is None:
                    return None
                small = step == 0 and np.abs(delta).max(initial=0.0) <= REUSE * size
                factored, q = (q if small else None), q + delta
                phi, psi, _, _, phi_max, psi_max, _, _ = self.rows(q, qd)
            rates = max(qd_max, TINY)
            if factored is None or psi_max > REUSE * rates:
                delta = self._delta(q, psi, kernel.UNCHECKED)
            else:
                delta = self._delta(factored, psi, kernel.REUSED)
            if delta is None:
                return None
            before, qd = psi_max, qd + delta
            _, _, kinetic, potential, phi_max, psi_max, _, _ = self.rows(q, qd)
            if not psi_max <= max(SHRINK * before, ROUNDING * size * rates):
                return None
            return Corrected(q, qd, kinetic, potential, phi_max, psi_max)

    def _delta(self, q, r, mode):
        """The least-M-norm Δ with A(q) Δ = −r, or None where the kernel declines (``mode``:
        kernel.motion's; the caller checks the result through the rows)."""
        status, _ = kernel.motion(q, self.rest, self.no_forces, -r, *self.at_rest.buffers, mode)
        return None if status != kernel.OK else self.at_rest.W.qdd.copy()

    def residuals_energy(self, q, qd):
        """(φ, φ̇, T, V) at (q, q̇): the System's residuals and its parts' energies."""
        with self.lock:
            phi, psi, kinetic, potential = self.rows(q, qd)[:4]
            return phi.copy(), psi.copy(), kinetic, potential

    def drift(self, q, qd):
        """The largest |φ| relative to the largest coordinate (at least 1: a quaternion's
        unit), or |φ̇| relative to the largest rate."""
        with self.lock:
            phi_max, psi_max, q_max, qd_max = self.rows(q, qd)[4:]
        return max(phi_max / max(q_max, 1.0), psi_max / max(qd_max, TINY))
