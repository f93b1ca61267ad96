"""Force elements: forces on the model's coordinates that no single part owns.

Every element is written as a potential V(q, t) and a list of (effort, rate) pairs,
where a rate is linear in the velocities (a joint rate, a spring's lengthening rate, a
point's velocity component) and the effort acts along it. By virtual power its
generalized force is

    Q_e = −∂V/∂q + Σ effort_k ∂rate_k/∂q̇,

added to the parts' Q of (2.1). Dampers use effort = −c·rate; actuators an effort of t.
Gravity is part of each massive part's own Q.
"""

import numpy as np
import sympy as sp

from .symbolic import T_SYMBOL, compile_function


class ForceElement:
    """A named force element: ``Q`` (sympy, over all the model's coordinates) and its
    potential energy ``V`` (0 for non-conservative elements)."""

    def __init__(self, name, V, efforts, q, qd, params):
        self.name = name
        self.V = sp.sympify(V)
        Q = -sp.Matrix([self.V]).jacobian(sp.Matrix(q)).T
        for effort, rate in efforts:
            Q += sp.sympify(effort) * sp.Matrix([rate]).jacobian(sp.Matrix(qd)).T
        self.Q = Q
        used = Q.free_symbols | self.V.free_symbols
        self.indices = np.array([i for i in range(len(q)) if q[i] in used or qd[i] in used or Q[i] != 0], dtype=int)
        local = [int(i) for i in self.indices]
        self._evaluate = compile_function(
            (T_SYMBOL, [q[i] for i in local], [qd[i] for i in local], list(params)),
            [Q.extract(local, [0]), self.V])

    def evaluate(self, t, q, qd, p):
        """Q_e on ``indices`` at the full state (q, qd)."""
        return self._evaluate(t, q[self.indices], qd[self.indices], p)[0].ravel()

    def potential(self, t, q, qd, p):
        return float(self._evaluate(t, q[self.indices], qd[self.indices], p)[1])

    def symbolic(self):
        return self.Q
