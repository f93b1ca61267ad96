"""A System's arrays at one state, evaluated a structure at a time (grouped.Batch).

An ``Evaluator(system, compiled)`` (a Data's, data.py; ``compiled``: the shared structures
evaluated by their numba kernels, else by numpy) gives

- ``constraints(t, q, qd)``: one evaluation of every constraint's rows: A (sparse CSR), b,
  C, and the residuals φ, φ̇ (NaN on rows without that level) — drift control and
  projection (projection.py) need them together;
- ``parts(t, q, qd)``: the block-diagonal M and the stacked Q of (2.1), force elements included;
- ``energies(t, q, qd)``: kinetic and potential energies of the parts and force elements;
- ``power(t, q, qd)``: the power of the forces that derive from no potential.

The results equal those of calling each constraint and part (``Constraint.evaluate``,
``residuals``, ``Part.evaluate``, ``energy``), which remain the reference.
"""

from typing import NamedTuple

import numpy as np

from ..compiled.grouped import Batch, stacked_agrees
from .parts.base import Part
from ..symbolic.derive import Compiled

DENSE_ENTRIES = 40000  # rows × coordinates up to which dense arrays beat scipy.sparse's overhead


class ConstraintArrays(NamedTuple):
    """The constraints at one state: rows A (m × n, CSR or dense) q̈ = b (2.4), the non-ideal
    force C (2.6), position and velocity residuals φ, φ̇ per row."""

    A: object  # scipy.sparse.csr_matrix or np.ndarray
    b: np.ndarray
    C: np.ndarray
    phi: np.ndarray
    psi: np.ndarray


class Evaluator:
    """The layout of a System's constraints and parts for evaluation in batches."""

    def __init__(self, system, compiled):
        constraints, n = system.constraints, system.n
        self.n = n
        self.m = sum(c.size for c in constraints)
        self.rows = Batch([c._rows for c in constraints], [c.indices for c in constraints], 5, compiled)
        starts = np.cumsum([0] + [c.size for c in constraints])
        pattern = [np.meshgrid(np.arange(s, s + c.size), c.indices, indexing="ij")
                   for s, c in zip(starts, constraints)]
        a_rows = np.concatenate([np.zeros(0, int)] + [r.ravel() for r, _ in pattern])
        a_cols = np.concatenate([np.zeros(0, int)] + [c.ravel() for _, c in pattern])
        self.c_cols = np.concatenate([np.zeros(0, int)] + [c.indices for c in constraints])
        # CSR of A: the entries sorted by (row, column) — a constraint's columns are distinct,
        # its rows its own, so no two entries share a place
        self.a_order = np.lexsort((a_cols, a_rows))
        self.a_indices = a_cols[self.a_order]
        self.a_indptr = np.concatenate([[0], np.cumsum(np.bincount(a_rows, minlength=self.m))])
        self.a_dense = (a_rows, a_cols)
        level = [np.repeat(c._levels[k], c.size) for k in (0, 1) for c in constraints]
        self.no_phi = ~np.concatenate([np.zeros(0, bool)] + level[:len(constraints)])
        self.no_psi = ~np.concatenate([np.zeros(0, bool)] + level[len(constraints):])
        stops = np.cumsum([len(s.coordinates) for s in system.parts])
        ranges = [np.arange(stop - len(s.coordinates), stop) for s, stop in zip(system.parts, stops)]
        grouped = [type(s).evaluate is Part.evaluate and isinstance(s._evaluate, Compiled) for s in system.parts]
        self.blocks = Batch([s._evaluate if g else s.evaluate for s, g in zip(system.parts, grouped)], ranges, 2, compiled)
        self.energy = Batch([s._energy if type(s).energy is Part.energy and isinstance(s._energy, Compiled)
                             else s.energy for s in system.parts], ranges, 2, compiled)
        forces = system.forces
        self.forces = Batch([f._evaluate for f in forces], [f.indices for f in forces], 2, compiled)
        self.f_cols = np.concatenate([np.zeros(0, int)] + [f.indices for f in forces])
        self.working = ([(part, r) for part, r in zip(system.parts, ranges) if part.working],
                        [f for f in forces if not f.conservative and not f.efforts_only],
                        any(x != 0 for c in constraints for x in c.C.values()))  # parts, elements, a non-ideal C
        # the entries of the stacked Q_e whose elements' power is q̇ᵀQ_e (one batched evaluation)
        self.effort_entries = np.concatenate([np.zeros(0, bool)] + [np.full(len(f.indices), f.efforts_only)
                                                                     for f in forces])
        self.effort_elements = [f for f in forces if f.efforts_only]
        self.over_rows = OverRows()
        parts, elements, nonideal = self.working  # ``powers`` over many rows needs the compiled power functions
        self.powers_by_row = bool(nonideal or elements or any(type(part).power is not Part.power for part, _ in parts))
        block = [np.meshgrid(r, r, indexing="ij") for r in ranges]
        self.m_rows = np.concatenate([np.zeros(0, int)] + [r.ravel() for r, _ in block])
        self.m_cols = np.concatenate([np.zeros(0, int)] + [c.ravel() for _, c in block])

    def constraints(self, t, q, qd, p, sparse=True):
        """ConstraintArrays at (t, q, q̇) with parameter values p; A sparse (CSR) or dense
        (an ndarray), or (sparse=None) dense when it has at most DENSE_ENTRIES entries."""
        a, b, c, phi, psi = self.rows(t, q, qd, p)
        if sparse is None:
            sparse = self.m * self.n > DENSE_ENTRIES
        if sparse:
            import scipy.sparse  # loaded with the first sparse A, not with mbsynth

            A = scipy.sparse.csr_matrix((a[self.a_order], self.a_indices, self.a_indptr), shape=(self.m, self.n))
        else:
            A = np.zeros((self.m, self.n))
            A[self.a_dense] = a
        return ConstraintArrays(A, b, np.bincount(self.c_cols, weights=c, minlength=self.n),
                                *self._levels(phi, psi))

    def residuals(self, t, q, qd, p):
        """(φ, φ̇) per row at (t, q, q̇): NaN on rows without that level."""
        return self._levels(*self.rows(t, q, qd, p)[3:])

    def _levels(self, phi, psi):
        phi, psi = phi.copy(), psi.copy()
        phi[self.no_phi] = np.nan
        psi[self.no_psi] = np.nan
        return phi, psi

    def dense_rows(self, t, q, qd, p):
        """(A dense, b, C) at (t, q, q̇)."""
        a, b, c, _, _ = self.rows(t, q, qd, p)
        A = np.zeros((self.m, self.n))
        A[self.a_dense] = a
        return A, b, np.bincount(self.c_cols, weights=c, minlength=self.n)

    def parts(self, t, q, qd, p):
        """(M, Q) at (t, q, q̇): the parts' M block diagonal (dense), their Q stacked plus the
        force elements'."""
        blocks, Q = self.blocks(t, q, qd, p)
        M = np.zeros((self.n, self.n))
        M[self.m_rows, self.m_cols] = blocks
        return M, Q + np.bincount(self.f_cols, weights=self.forces(t, q, qd, p)[0], minlength=self.n)

    def energies(self, t, q, qd, p):
        """(kinetic, potential): the parts' T and V, and the force elements' potentials, summed."""
        T, V = self.energy(t, q, qd, p)
        return float(T.sum()), float(V.sum() + self.forces(t, q, qd, p)[1].sum())

    def powers(self, times, q, qd, p):
        """``power`` at each row of (times, q, q̇) (q, q̇: a row per time), one value per
        row: the compiled power functions of the parts and the force elements' efforts
        called once over all the rows where their numpy form broadcasts along them
        (``OverRows``); a part with a power of its own, an element with a potential and a
        non-ideal C are evaluated row by row."""
        if self.powers_by_row:
            return np.array([self.power(t, q_row, qd_row, p) for t, q_row, qd_row in zip(times, q, qd)])
        args = (np.asarray(times, dtype=float), q, qd, p)
        total = np.zeros(len(times))
        for part, r in self.working[0]:
            total += self.over_rows(part.power_function(), args, r, 1)[0]
        for element in self.effort_elements:
            efforts = self.over_rows(element._evaluate, args, element.indices, len(element.indices))
            total += np.einsum("ij,ji->i", qd[:, element.indices], efforts)
        return total

    def power(self, t, q, qd, p):
        """q̇ᵀ Q_nc at (t, q, q̇): the power of the parts' forces beyond T and V (dampers,
        generalized forces), of the force elements' efforts and of the constraints' non-ideal
        C (2.6; viscous friction) — d(T + V)/dt where nothing holds t explicitly and no
        Coulomb friction acts (``System.unaccounted_work``)."""
        parts, elements, nonideal = self.working
        total = sum(part.power(t, q[r], qd[r], p) for part, r in parts) + sum(e.power(t, q, qd, p) for e in elements)
        if self.effort_entries.any():
            efforts = self.forces(t, q, qd, p)[0][self.effort_entries]
            total += float(qd[self.f_cols[self.effort_entries]] @ efforts)
        if nonideal:
            total += float(qd @ np.bincount(self.c_cols, weights=self.rows(t, q, qd, p)[2], minlength=self.n))
        return float(total)



class OverRows:
    """A compiled function (``symbolic.derive.Compiled``) called once for many states,
    its numpy form broadcasting along the rows, where that reproduces calling it state by
    state (checked at the first call, per function, as grouped.Batch checks its stacked
    calls); row by row otherwise."""

    def __init__(self):
        self.broadcasts = {}  # function -> whether its call over rows reproduces the single calls

    def __call__(self, function, args, columns, count):
        """The first ``count`` outputs of ``function(t, q[columns], q̇[columns], p)`` at
        each row of ``args`` = (times, q, q̇, p), as a (count, rows) array."""
        times, q, qd, p = args
        q, qd = q[:, columns], qd[:, columns]
        verdict = self.broadcasts.get(function)
        if verdict is None:  # judged at the first call of more than one row
            single = _one_by_one(function, times, q, qd, p, count)
            if len(times) > 1:
                self.broadcasts[function] = (isinstance(function, Compiled)
                                             and _over_rows_agrees(function, times, q, qd, p, count, single))
            return single
        return _stacked(function, times, q, qd, p, count) if verdict else _one_by_one(function, times, q, qd, p, count)


def _one_by_one(function, times, q, qd, p, count):
    rows = [np.concatenate([np.ravel(x) for x in function(t, q_row, qd_row, p)])[:count]
            for t, q_row, qd_row in zip(times, q, qd)]
    return np.array(rows, dtype=float).reshape(len(times), count).T


def _stacked(function, times, q, qd, p, count):
    """One call of the function's numpy form with a column per row (lambdify unpacks the
    coordinates as rows): its first ``count`` outputs, a value per row each."""
    given = (times, q.T, qd.T, p)
    with np.errstate(all="ignore"):  # NaN and inf are reported where the rows are used
        out = function.raw(*given, function.values(*given), function.fixed)
    result = np.empty((count, len(times)))
    for row, x in zip(result, out[:count]):
        row[...] = x  # a value per row, or one value (an output that reads no coordinate) for all
    return result


def _over_rows_agrees(function, times, q, qd, p, count, single):
    try:
        got = _stacked(function, times, q, qd, p, count)
    except Exception:  # noqa: BLE001 - a numpy form that does not broadcast is called row by row
        return False
    return stacked_agrees(got, single)
