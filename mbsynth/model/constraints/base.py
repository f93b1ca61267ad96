"""Constraints as sympy expressions of the model's coordinates: the rows of A q̈ = b (2.4)."""

import numpy as np
import sympy as sp

from ...core.values import Keyed
from ...symbolic.derive import (PARAMETERS, T_SYMBOL, compile_function, differentiated, differentiated_template,
    expand_joint_values, joint_values_in, placed_values, positions, symbols_in, turn_residual)

from ...core.memo import MEMO

class Constraint(Keyed):
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
        n = len(q)
        a = sp.SparseMatrix(a if isinstance(a, sp.SparseMatrix) else sp.Matrix(a).reshape(len(b), n))
        self._symbolic = (a, sp.Matrix(b), sp.SparseMatrix(C), None if phi is None else sp.Matrix(phi),
                          None if psi is None else sp.Matrix(psi))
        self._defined_by = self._symbolic
        self._name_rows(name, kind, len(b), row_labels)
        self._levels = (phi is not None, psi is not None)  # which residuals the rows have
        exprs = [e for e in self._symbolic if e is not None]
        where = positions(q, qd)
        used = {where[s] for e in exprs for s in e.free_symbols if s in where}
        used |= {i for _, i in a.todok()} | {i for i, _ in self.C.todok()}
        self.indices = np.array(sorted(used), dtype=int)
        local = [int(i) for i in self.indices]
        k, zeros = len(b), sp.zeros(len(b), 1)
        self._rows = compile_function(
            (T_SYMBOL, [q[i] for i in local], [qd[i] for i in local], list(params)),
            [a.extract(list(range(k)), local), self.b, self.C.extract(local, [0]),
             zeros if self.phi is None else self.phi, zeros if self.psi is None else self.psi], picked=PARAMETERS)

    def _name_rows(self, name, kind, k, row_labels):
        self.name, self.kind = name, kind
        labels = row_labels or [str(i) for i in range(k)]
        self.row_names = [name] if k == 1 and row_labels is None else [f"{name}[{x}]" for x in labels]

    def _place(self, name, kind, rows, slots, coordinates, constants, q, qd, params, row_labels):
        """Rows given in placeholder symbols, shared with constraints alike (joints.py):
        ``rows`` = (a over the slots, b, φ, ψ) with the coordinate slots ``slots`` = (q
        slots, q̇ slots) standing for the model's coordinates ``coordinates`` (indices),
        and ``constants`` (placeholder, value) pairs. They are compiled once for all such
        constraints; their sympy form over the model's symbols is built only when asked."""
        self._name_rows(name, kind, len(rows[1]), row_labels)
        q_slots, qd_slots = slots
        free = _slots_in(rows, slots)
        used = sorted({coordinates[j] for j in free})
        slot_of = {c: j for j, c in enumerate(coordinates)}
        local = [slot_of[i] for i in used]
        self.indices = np.array(used, dtype=int)
        self._symbolic = None
        self._levels = (True, True)
        self._placed = (rows, slots, coordinates, dict(constants), q, qd)
        self._defined_by = self._placed
        self._zero_C = sp.SparseMatrix(len(q), 1, {})
        self._rows = compile_function(
            (T_SYMBOL, [q_slots[j] for j in local], [qd_slots[j] for j in local], list(params)),
            _placed_rows(rows, tuple(local)), constants=constants, picked=PARAMETERS)

    @classmethod
    def placed(cls, name, kind, rows, slots, coordinates, q, qd, params, constants=(), row_labels=None):
        """A constraint of rows given in placeholder symbols (``_place``)."""
        constraint = cls.__new__(cls)
        constraint._place(name, kind, rows, slots, coordinates, constants, q, qd, params, row_labels)
        return constraint

    # attributes beyond the base's that define a constraint of a subclass (``content``)
    content_fields = ()

    def content(self):
        """What defines the constraint (its equality, ``core.values``): its name, kind, row
        names and the rows it was given (sympy, or a template with its values), and the
        subclass's ``content_fields``."""
        base = (self.name, self.kind, tuple(self.row_names), self._levels, self._defined_by)
        return base + tuple(getattr(self, name) for name in self.content_fields)

    def _materialized(self):
        """(a, b, C, φ, ψ) as sympy expressions of the model's symbols."""
        if self._symbolic is None:
            (a, b, phi, psi), slots, coordinates, constants, q, qd = self._placed
            n, put = len(q), placed_values(slots, coordinates, constants, q, qd)
            entries = {(r, coordinates[j]): x.xreplace(put) for r, row in enumerate(a) for j, x in enumerate(row)
                       if x != 0}
            self._symbolic = (sp.SparseMatrix(len(b), n, entries), sp.Matrix([x.xreplace(put) for x in b]),
                              self._zero_C, sp.Matrix([x.xreplace(put) for x in phi]),
                              sp.Matrix([x.xreplace(put) for x in psi]))
        return self._symbolic

    a = property(lambda self: self._materialized()[0], doc="rows of A over all coordinates (sparse)")
    b = property(lambda self: self._materialized()[1], doc="right sides b")
    C = property(lambda self: self._zero_C if self._symbolic is None else self._symbolic[2],
                 doc="the non-ideal force C (2.6), over all coordinates (zero for placed rows)")
    phi = property(lambda self: self._materialized()[3], doc="position-level residuals φ (None for none)")
    psi = property(lambda self: self._materialized()[4], doc="velocity-level residuals φ̇ or ψ (None for none)")

    @property
    def size(self):
        return len(self.row_names)

    @classmethod
    def holonomic(cls, name, phis, q, qd, params, C=None, row_labels=None):
        phis = [sp.sympify(phi) for phi in phis]
        if C is None and not any(joint_values_in(phi) for phi in phis):  # rows shared with constraints alike
            (a, b, psi), forms, slots, involved, constants = differentiated_template(phis, q, qd)
            return cls.placed(name, "holonomic", (a, b, forms, psi), slots, involved, q, qd, params, constants,
                              row_labels)
        a, b, psi = differentiated(phis, q, qd)
        phis = [turn_residual(phi) for phi in phis]
        return cls(name, "holonomic", a, b, _vector(C, len(q)), phis, psi, q, qd, params, row_labels)

    @classmethod
    def nonholonomic(cls, name, psis, q, qd, params, C=None, row_labels=None):
        a, b, _ = differentiated(psis, q, qd)
        psis = [expand_joint_values(psi) for psi in psis]
        return cls(name, "nonholonomic", a, b, _vector(C, len(q)), None, psis, q, qd, params, row_labels)

    @classmethod
    def acceleration(cls, name, a, b, q, qd, params, C=None):
        return cls(name, "acceleration", [a], [b], _vector(C, len(q)), None, None, q, qd, params)

    def evaluate(self, t, q, qd, p):
        """(a, b, C) on ``indices`` at the full state (q, qd) of the model."""
        a, b, C, _, _ = self._rows(t, q[self.indices], qd[self.indices], p)
        return a, b.ravel(), C.ravel()

    def wrong_branch(self, values):
        """A message when the rows hold at ``values`` in a pose the constraint does not
        mean (joints.py); None for rows without such poses."""
        return None

    def residuals(self, t, q, qd, p):
        """(φ, φ̇) per row: position- and velocity-level residuals; NaN where the kind has none."""
        _, _, _, phi, psi = self._rows(t, q[self.indices], qd[self.indices], p)
        nan = np.full(self.size, np.nan)
        return (phi.ravel() if self._levels[0] else nan, psi.ravel() if self._levels[1] else nan)


@MEMO.function(256)
def _slots_in(rows, slots):
    """The positions j whose coordinate slot or velocity slot the rows (a, b, φ, ψ) hold:
    once per template (constraints alike share their rows)."""
    a, b, phi, psi = rows
    free = symbols_in((*b, *phi, *psi, *(e for row in a for e in row)))
    return [j for j, (s, sd) in enumerate(zip(*slots)) if s in free or sd in free]


@MEMO.function(256)
def _placed_rows(rows, local):
    """[a, b, C, φ, ψ] of ``Constraint._rows`` for rows (a, b, φ, ψ) over the slots at
    ``local``: once per template and selection (constraints alike share it)."""
    a, b, phi, psi = rows
    k = len(b)
    return [sp.Matrix(k, len(local), [a[r][j] for r in range(k) for j in local]), sp.Matrix(b),
            sp.zeros(len(local), 1), sp.Matrix(phi), sp.Matrix(psi)]


def mixed(holonomic, nonholonomic, q, qd):
    """(a, b, φ, ψ) of position-level rows φ(q, t) = 0 followed by velocity-level rows
    ψ(q, q̇, t) = 0 in one constraint (2.4): φ is NaN on the velocity-level rows, which
    have no position form."""
    a, b, psi = differentiated(list(holonomic) + list(nonholonomic), q, qd)
    return a, b, [turn_residual(phi) for phi in holonomic] + [sp.nan] * len(nonholonomic), psi


def _vector(C, n):
    return sp.SparseMatrix(n, 1, {}) if C is None else sp.SparseMatrix(C)
