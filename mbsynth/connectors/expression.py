"""Constraints written as expressions of the model's coordinates."""

import numpy as np
import sympy as sp

from ..symbolic import T_SYMBOL, compile_function, differentiate

KINDS = ("holonomic", "nonholonomic", "acceleration")


class ExpressionConstraint:
    """One row ``a q̈ = b`` of (2.4), with an optional non-ideal force C (2.6).

    Build it with ``holonomic`` (φ(q, t) = 0, differentiated twice),
    ``nonholonomic`` (ψ(q, q̇, t) = 0, differentiated once) or ``acceleration``
    (the row given directly, as the paper writes (5.41)). ``a`` and ``C`` are
    sympy vectors over all the model's coordinates; the numeric evaluation only
    touches ``indices``, the coordinates the constraint involves.
    """

    def __init__(self, name, kind, a, b, C, phi, psi, q, qd, params):
        self.name, self.kind = name, kind
        self.a, self.b, self.C = sp.Matrix(a).reshape(1, len(q)), b, sp.Matrix(C)
        self.phi, self.psi = phi, psi
        n = len(q)
        exprs = [self.a, b, self.C] + [e for e in (phi, psi) if e is not None]
        used = set().union(*(sp.sympify(e).free_symbols for e in exprs))
        self.indices = np.array([i for i in range(n) if q[i] in used or qd[i] in used
                                 or self.a[i] != 0 or self.C[i] != 0], dtype=int)
        local = [int(i) for i in self.indices]
        self._rows = compile_function(
            (T_SYMBOL, [q[i] for i in local], [qd[i] for i in local], list(params)),
            [self.a.extract([0], local), b, self.C.extract(local, [0]),
             phi if phi is not None else sp.Integer(0), psi if psi is not None else sp.Integer(0)])

    @classmethod
    def holonomic(cls, name, phi, q, qd, params, C=None):
        a, b, psi = differentiate(phi, q, qd)
        return cls(name, "holonomic", a, b, _vector(C, len(q)), phi, psi, q, qd, params)

    @classmethod
    def nonholonomic(cls, name, psi, q, qd, params, C=None):
        a, b, _ = differentiate(psi, q, qd)
        return cls(name, "nonholonomic", a, b, _vector(C, len(q)), None, psi, q, qd, params)

    @classmethod
    def acceleration(cls, name, a, b, q, qd, params, C=None):
        return cls(name, "acceleration", a, b, _vector(C, len(q)), None, None, q, qd, params)

    def evaluate(self, t, q, qd, p):
        """(a, b, C) on ``indices`` at the full state (q, qd) of the model."""
        a, b, C, _, _ = self._rows(t, q[self.indices], qd[self.indices], p)
        return a.ravel(), float(b), C.ravel()

    def residuals(self, t, q, qd, p):
        """(φ, φ̇): position- and velocity-level residuals; NaN where the kind has none."""
        _, _, _, phi, psi = self._rows(t, q[self.indices], qd[self.indices], p)
        return (float(phi) if self.phi is not None else np.nan,
                float(psi) if self.psi is not None else np.nan)


def _vector(C, n):
    return sp.zeros(n, 1) if C is None else sp.Matrix(C)
