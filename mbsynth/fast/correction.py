"""Putting a state back on the constraints with the kernel itself, in the mass metric.

At q̇ = 0, with no gravity and no generated forces, the kernel's Q and b vanish (every
b term of a kernel row is quadratic in q̇), so its q̈ for a right side shifted by −r is
the least-M-norm Δ with A Δ = −r ((2.14) with Q = 0). One such call is a Gauss–Newton
step of the projection in the mass metric: positions with r = φ(q) (repeated while φ is
above TOLERANCE of the coordinates' size, at most MAX_STEPS times), then velocities with
r = φ̇(q, q̇) = A q̇, a linear problem one step solves. From an integrator's drift of
5e-9 one step leaves rounding (2e-15 on a UR5). A call costs one kernel evaluation, where
projection.py's sparse factorization costs a millisecond (UR5) to ten (talos).

Only for Systems all of whose rows and coordinates the kernel's tree covers (rows.py's
``covers``; no loops, no extra coordinates); elsewhere, and at any state the kernel
declines, the caller projects with projection.py.
"""

import threading

import numpy as np

from . import kernel
from .rows import Rows

TOLERANCE = 1e-14  # largest |φ| left, relative to the largest coordinate (at least 1): about 50 ε
MAX_STEPS = 3  # position steps before the state goes to projection.py


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
        rows = Rows(engine.L, int(engine.L.sizes[1]))
        return cls(rows, engine.at_rest()) if rows.covers else None

    def __call__(self, q, qd):
        """(q, q̇) on the constraints (new arrays), or None where the kernel declines a state
        or MAX_STEPS position steps leave φ above TOLERANCE."""
        with self.lock:
            phi, psi, _, _ = self.rows(q, qd)
            size = max(np.abs(q).max(initial=0.0), 1.0)
            for step in range(MAX_STEPS + 1):
                if np.abs(phi).max(initial=0.0) <= TOLERANCE * size:
                    break
                delta = None if step == MAX_STEPS else self._delta(q, phi)
                if delta is None:
                    return None
                q = q + delta
                phi, psi, _, _ = self.rows(q, qd)
            delta = self._delta(q, psi)
            return None if delta is None else (q, qd + delta)

    def _delta(self, q, r):
        """The least-M-norm Δ with A(q) Δ = −r, or None where the kernel declines."""
        status, _ = kernel.motion(q, self.rest, self.no_forces, -r, *self.at_rest.buffers)
        return None if status != kernel.OK else self.at_rest.W.qdd.copy()

    def residuals_energy(self, q, qd):
        """(φ, φ̇, T, V) at (q, q̇): the System's residuals and its parts' energies."""
        with self.lock:
            phi, psi, kinetic, potential = self.rows(q, qd)
            return phi.copy(), psi.copy(), kinetic, potential

    def drift(self, q, qd):
        """The largest |φ| relative to the largest coordinate (at least 1: a quaternion's
        unit), or |φ̇| relative to the largest rate."""
        with self.lock:
            phi, psi, _, _ = self.rows(q, qd)
            return max(np.abs(phi).max(initial=0.0) / max(np.abs(q).max(initial=0.0), 1.0),
                       np.abs(psi).max(initial=0.0) / max(np.abs(qd).max(initial=0.0), np.finfo(float).tiny))
