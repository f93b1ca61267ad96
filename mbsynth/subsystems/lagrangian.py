"""A part given by its kinetic energy T, potential energy V and generalized forces."""

from ..symbolic import T_SYMBOL, compile_function, lagrange


class LagrangianSubsystem:
    """Unconstrained M q̈ = Q (2.1) of a part from Lagrange's equations.

    ``q`` and ``qd`` are this part's coordinate and velocity symbols, ``T``, ``V``
    and ``forces`` (one expression per coordinate) sympy expressions of them,
    of ``params`` and of time. M may be singular (the paper's examples 1 and 3).
    """

    def __init__(self, name, coordinates, q, qd, T, V, forces, params):
        self.name = name
        self.coordinates = tuple(coordinates)
        self.q, self.qd = list(q), list(qd)
        self.T, self.V, self.forces = T, V, list(forces)
        self.M, self.Q = lagrange(T, V, self.forces, self.q, self.qd)
        self._evaluate = compile_function((T_SYMBOL, self.q, self.qd, list(params)), [self.M, self.Q])

    def evaluate(self, t, q, qd, p):
        """(M, Q) of this part at its own coordinates q, velocities qd (2.1)."""
        M, Q = self._evaluate(t, q, qd, p)
        return M, Q.ravel()

    def symbolic(self):
        """(M, Q) as sympy matrices of the model's symbols."""
        return self.M, self.Q
