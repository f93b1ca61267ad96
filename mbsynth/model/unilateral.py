"""Unilateral constraints: gaps g(q) ≥ 0 that may open, close and strike.

A ``Unilateral`` is one gap with Newton's restitution coefficient e (0 ≤ e ≤ 1): a joint's
limit (``hinge.lower``: g = angle − lo; ``hinge.upper``: g = hi − angle; a universal
joint's per angle; a spherical joint's ``ball.cone``: g = z_A·z_B − cos θ) or a contact (a
point or sphere on a part's frame against a ground plane, g = n·p − h − r, a capsule's end
spheres and a box's corners each one; two spheres, g = |p_B − p_A| − r_A − r_B; a sphere
against a capsule, its centre's distance to the segment less both radii; two capsules, the
distance between their segments less both radii: io/unilateral.py, segments.py). Its ``row`` is a holonomic Constraint with φ = g, so that its
row a = ∂g/∂q, its b (a q̈ = b while it holds), its φ = g and its φ̇ = ġ come from the same
machinery as every bilateral row; λ > 0 on it pushes the gap open (Qc = Aᵀλ, reactions.py).
A plane contact with Coulomb's ``friction`` μ also has its ``slip`` rows ψ = t_k·v_c, the
contact point's velocity (a sphere's: its centre's plus ω × (−r n)) along two unit tangents
of the plane (``tangent_basis``): an impulse Λ_k on them is the tangential impulse Λ_k t_k
at the point.

While a gap is open the row is no constraint; while it holds (persistent contact) it is one
of the System's rows: ``with_active`` makes the System of an active set (its ``constraints``
followed by the active rows), which the run loop switches between (analysis/impacts.py).
"""

import copy
from dataclasses import dataclass

import numpy as np
import sympy as sp

from .constraints.base import Constraint
from ..core.errors import ModelError
from ..core.tolerances import SPEED_ROUNDING
from ..symbolic.derive import differentiate_through


@dataclass(frozen=True)
class Unilateral:
    """A gap g(q) ≥ 0 named ``name`` (``kind``: "limit" or "contact"), its restitution e (a
    sympy expression of the parameters), its holonomic ``row`` (φ = g), Coulomb's
    ``friction`` μ and the nonholonomic ``slip`` rows (None without friction); a contact's
    ``point`` (where it touches, world) and ``normal`` (the unit direction its impulse
    pushes the child, or the second sphere), sympy columns of q, for the viewer; with
    friction, its slip rows' unit ``tangents`` t1, t2 (the columns of a sympy (3, 2) of the
    parameters)."""

    name: str
    kind: str
    restitution: sp.Expr
    row: Constraint
    friction: sp.Expr = sp.S.Zero
    slip: Constraint = None
    point: sp.Matrix = None
    normal: sp.Matrix = None
    tangents: sp.Matrix = None

    def restitution_at(self, system, p):
        """e at the parameter values ``p`` of ``system``; ModelError unless 0 ≤ e ≤ 1."""
        e = float(sp.sympify(self.restitution).xreplace(dict(zip(system.parameter_symbols, p))))
        if not 0 <= e <= 1:
            raise ModelError(f"model '{system.name}': the restitution of '{self.name}' is {e:g} at these parameter "
                             f"values; it must be between 0 and 1")
        return e

    def friction_at(self, system, p):
        """μ at the parameter values ``p`` of ``system``; ModelError unless μ ≥ 0."""
        mu = float(sp.sympify(self.friction).xreplace(dict(zip(system.parameter_symbols, p))))
        if not mu >= 0:
            raise ModelError(f"model '{system.name}': the friction of '{self.name}' is {mu:g} at these parameter "
                             f"values; it must be ≥ 0")
        return mu


def tangent_basis(n, value=float):
    """Two unit tangents t1, t2 of the unit normal ``n`` (a sympy column, an expression of
    parameters; ``value`` its number): t1 = the first of e_x, e_y least along n at its value,
    made orthogonal to n; t2 = n × t1: a right-handed (t1, t2, n)."""
    axis = sp.Matrix(np.eye(3)[int(np.argmin([abs(value(n[0])), abs(value(n[1]))]))])
    t1 = axis - axis.dot(n) * n
    t1 = t1 / sp.sqrt(t1.dot(t1))
    return t1, n.cross(t1)


def gap_row(name, gap, q, qd, params, through=None):
    """The holonomic Constraint of the gap expression ``gap`` (sympy; joint values allowed);
    ``through``: {symbol: its value, an expression of q} for the symbols ``gap`` is written
    in, differentiated by the chain rule through them (``differentiate_through``)."""
    if through is None:
        return Constraint.holonomic(name, [gap], q, qd, params)
    a, b, psi = differentiate_through(gap, through, q, qd)
    return Constraint(name, "holonomic", a, [b], sp.SparseMatrix(len(q), 1, {}), [gap.xreplace(through)], [psi], q,
                      qd, params)


def with_active(system, names, sliding=None, sticking=()):
    """``system`` with the rows of its unilaterals named in ``names`` appended to its
    constraints, in the order of ``system.unilaterals``: the System of that active set. A
    contact named in ``sliding`` ({name: (μ, the slip's direction where it has no speed)})
    carries its Coulomb friction; one named in ``sticking`` also has its slip rows held
    (T q̇ = 0, bilateral while it sticks), after its gap's row."""
    sliding = sliding or {}
    if not names:
        return system
    rows = []
    for u in system.unilaterals:
        if u.name in names:
            row = u.row
            if u.name in sliding:
                row = copy.copy(row)
                row.coulomb = Sliding(u, *sliding[u.name])
            rows.append(row)
            if u.name in sticking:
                rows.append(u.slip)
    return system.with_constraints(rows)


class Sliding:
    """Coulomb's friction of a held contact that slides, as friction.py's ``coulomb`` of its
    gap row: C = −μ N Tᵀû (N the gap row's force, T its slip rows, û the unit slip T q̇/|T q̇|,
    or ``direction`` where the slip's speed is rounding or below ``floor``, the run's
    resolution: at its onset from rest)."""

    def __init__(self, unilateral, mu, direction, floor=0.0):
        self.joint, self.slip, self.mu = unilateral.name, unilateral.slip, mu
        self.indices = unilateral.slip.indices
        self.direction, self.floor = np.asarray(direction, dtype=float), floor
        self.load_rows = np.array([0])

    def evaluate(self, t, q, qd, p):
        """(1, μ Tᵀû on ``indices``): friction.py's (w, direction) with w > 0."""
        T = self.slip.evaluate(t, q, qd, p)[0]
        return 1.0, self.mu * T.T @ slip_direction(T, qd[self.indices], self.direction, np.abs(qd).max(initial=0.0),
                                                   self.floor)


def slip_direction(T, qd, direction, speed, floor=0.0):
    """The unit slip T q̇/|T q̇|, or ``direction`` where |T q̇| is rounding (SPEED_ROUNDING ×
    ‖T‖₁ × ``speed``, the largest |q̇|) or not above ``floor``."""
    u = T @ qd
    size = np.linalg.norm(u)
    return u / size if size > max(SPEED_ROUNDING * np.abs(T).sum(axis=1).max() * speed, floor) else direction


class Gaps:
    """The gaps of ``system``'s unilaterals, evaluated together; ``restitution`` at the
    parameter values ``p``."""

    def __init__(self, system, p):
        self.unilaterals, self.n = tuple(system.unilaterals), system.n
        self.names = tuple(u.name for u in self.unilaterals)
        self.restitution = np.array([u.restitution_at(system, p) for u in self.unilaterals], dtype=float)
        self.friction = np.array([u.friction_at(system, p) if u.slip is not None else 0.0
                                  for u in self.unilaterals], dtype=float)
        values = dict(zip(system.parameter_symbols, p))
        self.tangents = [None if u.tangents is None else np.array(u.tangents.xreplace(values), dtype=float)
                         for u in self.unilaterals]  # (3, 2): a contact's unit tangents t1, t2 as columns

    def __len__(self):
        return len(self.unilaterals)

    def values(self, t, q, qd, p):
        """(g, ġ) per gap at (t, q, q̇)."""
        found = [u.row.residuals(t, q, qd, p) for u in self.unilaterals]
        return (np.array([phi[0] for phi, _ in found]), np.array([psi[0] for _, psi in found]))

    def rows(self, t, q, qd, p):
        """(A, b) of the gaps: A's row i is ∂g_i/∂q over all n coordinates, and
        g̈_i = A_i q̈ − b_i."""
        A, b = np.zeros((len(self.unilaterals), self.n)), np.zeros(len(self.unilaterals))
        for i, u in enumerate(self.unilaterals):
            a, b_row, _ = u.row.evaluate(t, q, qd, p)
            A[i, u.row.indices], b[i] = a[0], b_row[0]
        return A, b

    def slip_rows(self, t, q, qd, p, i):
        """The (2, n) rows T of gap i's slip velocity T q̇ (its tangential velocity)."""
        return self.slip_arrays(t, q, qd, p, i)[0]

    def slip_arrays(self, t, q, qd, p, i):
        """(T, b) of gap i's slip rows: T q̈ = b holds them at rest."""
        u = self.unilaterals[i]
        T = np.zeros((u.slip.size, self.n))
        a, b, _ = u.slip.evaluate(t, q, qd, p)
        T[:, u.slip.indices] = a
        return T, b
