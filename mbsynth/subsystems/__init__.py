"""Parts of a mechanical system, each in its own coordinates with its own M and Q (2.1).

A subsystem knows only its own coordinates. It offers
``evaluate(t, q, qd, p) -> (M, Q)`` on its own slice of the state (``p``: the
model's parameter values in the model's order) and ``symbolic()`` returning the
same M and Q as sympy matrices, used to derive closure balances.
"""

from .lagrangian import LagrangianSubsystem

__all__ = ["LagrangianSubsystem"]
