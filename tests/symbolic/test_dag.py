"""symbolic/dag.py: substitution and atom walks that visit each distinct subexpression
once give what sympy's xreplace and atoms give, and finish on expressions whose trees are
exponentially larger than what is stored."""

import math

import sympy as sp

from mbsynth.symbolic.dag import Replacing, atoms_of, replaced

x, y, z, u, v = sp.symbols("x y z u v")
EXPRS = [
    x * y + sp.sin(x * y) - sp.Rational(3, 7) * z ** 2 + sp.Float(0.25) * sp.sqrt(x * y + 1),
    sp.atan2(y, x) + sp.exp(-(x * y) ** 2) / (1 + z),
    sp.Max(x, y * z) + sp.Abs(x - z),
]
PIECEWISE = sp.Piecewise((x * y, (x < y) & (z > 0)), (y - z, sp.Ne(x, z) | (y >= 1)), (sp.cos(x * y), True))


def test_replaced_gives_what_xreplace_gives():
    mapping = {x: u + v, y: sp.cos(v), z: sp.Integer(2)}
    assert replaced(EXPRS, mapping) == [e.xreplace(mapping) for e in EXPRS]
    assert atoms_of(EXPRS, sp.Rational) == set().union(*(e.atoms(sp.Rational) for e in EXPRS))
    assert atoms_of(EXPRS, sp.Symbol) == set().union(*(e.free_symbols for e in EXPRS))


def test_a_piecewise_keeps_its_branches_and_its_values():
    """A Piecewise is rebuilt without being evaluated again: the same values as xreplace's
    at points on either side of every condition."""
    mapping = {x: u + v, y: u * v}
    ours, theirs = Replacing(mapping)(PIECEWISE), PIECEWISE.xreplace(mapping)
    f, g = (sp.lambdify((u, v, z), e) for e in (ours, theirs))
    for point in [(0.5, 2.0, 1.0), (2.0, 0.5, -1.0), (1.0, 1.0, 0.0), (-1.0, 3.0, 2.0), (0.3, 0.2, 0.5)]:
        assert f(*point) == g(*point)


def test_an_expression_shared_at_every_level_is_replaced_in_time_linear_in_its_depth():
    """x_{k+1} = sin(x_k) + cos(x_k)²/3, 60 levels: 2^60 leaves as a tree, 60 levels as
    stored. Its value after x → 0.1 against the recurrence iterated in floats."""
    expr = x
    for _ in range(60):
        expr = sp.sin(expr) + sp.cos(expr) ** 2 / 3
    (put,) = replaced([expr], {x: sp.Float(0.1)})
    value = 0.1
    for _ in range(60):
        value = math.sin(value) + math.cos(value) ** 2 / 3
    assert math.isclose(float(put), value, rel_tol=1e-12)
    assert atoms_of([expr], sp.Symbol) == {x}
