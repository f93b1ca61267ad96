"""Constraints as sympy expressions of the model's coordinates: the rows of A q̈ = b (2.4)."""

import numpy as np
import sympy as sp

from ..symbolic import T_SYMBOL, compile_function, differentiated, positions


class Connector:
    """k rows ``a q̈ = b`` of (2.4), an optional non-ideal force C (2.6), and the
    position- and velocity-level residuals φ, φ̇ used for drift control.

    Build one with ``holonomic`` (φ(q, t) = 0, differentiated twice), ``nonholonomic``
    (ψ(q, q̇, t) = 0, differentiated once) or ``acceleration`` (rows given directly, as
    the paper writes (5.41)). ``a`` (k × n) and ``C`` (n) are over all the model's
    coordinates, kept sparse (a model has thousands of coordinates, a row a handful);
    numeric evaluation touches only ``indices``, the coordinates involved.
    ``row_labels`` name the rows (``hinge[x]``) in error messages.
    """

    def __init__(self, name, kind, a, b, C, phi, psi, q, qd, params, row_labels=None):
        self.name, self.kind = name, kind
        n = len(q)
        self.a = sp.SparseMatrix(a if isinstance(a, sp.SparseMatrix) else sp.Matrix(a).reshape(len(b), n))
        self.b, self.C = sp.Matrix(b), sp.SparseMatrix(C)
        self.phi = None if phi is None else sp.Matrix(phi)
        self.psi = None if psi is None else sp.Matrix(psi)
        k = len(b)
        labels = row_labels or [str(i) for i in range(k)]
        self.row_names = [name] if k == 1 and row_labels is None else [f"{name}[{x}]" for x in labels]
        exprs = [self.a, self.b, self.C] + [e for e in (self.phi, self.psi) if e is not None]
        where = positions(q, qd)
        used = {where[s] for e in exprs for s in e.free_symbols if s in where}
        used |= {i for _, i in self.a.todok()} | {i for i, _ in self.C.todok()}
        self.indices = np.array(sorted(used), dtype=int)
        local = [int(i) for i in self.indices]
        zeros = sp.zeros(k, 1)
        self._rows = compile_function(
            (T_SYMBOL, [q[i] for i in local], [qd[i] for i in local], list(params)),
            [self.a.extract(list(range(k)), local), self.b, self.C.extract(local, [0]),
             zeros if self.phi is None else self.phi, zeros if self.psi is None else self.psi])

    @property
    def size(self):
        return len(self.b)

    @classmethod
    def holonomic(cls, name, phis, q, qd, params, C=None, row_labels=None):
        a, b, psi = differentiated(phis, q, qd)
        return cls(name, "holonomic", a, b, _vector(C, len(q)), list(phis), psi, q, qd, params, row_labels)

    @classmethod
    def nonholonomic(cls, name, psis, q, qd, params, C=None, row_labels=None):
        a, b, _ = differentiated(psis, q, qd)
        return cls(name, "nonholonomic", a, b, _vector(C, len(q)), None, list(psis), q, qd, params, row_labels)

    @classmethod
    def acceleration(cls, name, a, b, q, qd, params, C=None):
        return cls(name, "acceleration", [a], [b], _vector(C, len(q)), None, None, q, qd, params)

    def evaluate(self, t, q, qd, p):
        """(a, b, C) on ``indices`` at the full state (q, qd) of the model."""
        a, b, C, _, _ = self._rows(t, q[self.indices], qd[self.indices], p)
        return a, b.ravel(), C.ravel()

    def residuals(self, t, q, qd, p):
        """(φ, φ̇) per row: position- and velocity-level residuals; NaN where the kind has none."""
        _, _, _, phi, psi = self._rows(t, q[self.indices], qd[self.indices], p)
        nan = np.full(self.size, np.nan)
        return (nan if self.phi is None else phi.ravel(), nan if self.psi is None else psi.ravel())


def mixed(holonomic, nonholonomic, q, qd):
    """(a, b, φ, ψ) of position-level rows φ(q, t) = 0 followed by velocity-level rows
    ψ(q, q̇, t) = 0 in one connector (2.4): φ is NaN on the velocity-level rows, which
    have no position form."""
    a, b, psi = differentiated(list(holonomic) + list(nonholonomic), q, qd)
    return a, b, list(holonomic) + [sp.nan] * len(nonholonomic), psi


def _vector(C, n):
    return sp.SparseMatrix(n, 1, {}) if C is None else sp.SparseMatrix(C)
