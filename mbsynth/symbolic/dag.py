"""Walks of sympy expressions that visit each distinct subexpression once.

sympy's ``xreplace``, ``atoms`` and ``free_symbols`` visit a subexpression every time it
occurs. Expressions in which subexpressions occur many times over (the closed-form distance
between two capsules, its branches differentiated through the chain rule,
model/segments.py) are small as stored but large as trees, so those walks take time
proportional to the tree, not to what is stored. These give the same results, visiting
each distinct subexpression once.
"""

from sympy import Basic, Piecewise, Symbol, sympify


class Replacing:
    """``replacing(e)`` = ``e.xreplace(mapping)``, each distinct subexpression of all the
    expressions given to one Replacing looked up in ``mapping`` and rebuilt once; a
    Piecewise rebuilt as it stands, its branches not merged or dropped again (a walk of the
    whole tree per Piecewise, where xreplace evaluates it: the same values)."""

    def __init__(self, mapping):
        self.mapping, self.done = mapping, {}

    def __call__(self, expr):
        if not isinstance(expr, Basic):  # an argument that is no expression (as xreplace keeps it)
            return expr
        found = self.done.get(expr)
        if found is None:
            found = self.mapping.get(expr)
            if found is None:
                args = expr.args
                new = tuple(self(a) for a in args)
                if any(a is not b for a, b in zip(new, args)):
                    found = Piecewise(*new, evaluate=False) if isinstance(expr, Piecewise) else expr.func(*new)
                else:
                    found = expr
            self.done[expr] = found
        return found


def replaced(exprs, mapping):
    """[e.xreplace(mapping) for e in exprs], each distinct subexpression rebuilt once."""
    replacing = Replacing(mapping)
    return [replacing(e) for e in exprs]


def atoms_of(exprs, kind):
    """The subexpressions of ``exprs`` that are instances of ``kind`` (``atoms``), each
    stored subexpression visited once."""
    seen, found, stack = set(), set(), [e for e in exprs if isinstance(e, Basic)]
    while stack:
        expr = stack.pop()
        if id(expr) in seen:
            continue
        seen.add(id(expr))
        if isinstance(expr, kind):
            found.add(expr)
        stack.extend(a for a in expr.args if isinstance(a, Basic))
    return found


def symbols_in(exprs):
    """The symbols in ``exprs``, as ``free_symbols`` gives them for expressions without
    bound variables (derivatives, which share subexpressions)."""
    return atoms_of([sympify(e) for e in exprs], Symbol)
