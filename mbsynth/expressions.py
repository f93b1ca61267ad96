"""Safe parsing of model expressions into sympy.

A model file holds expressions such as ``0.5*m*(R*theta_dot)**2`` or
``wheel.y - R*wheel.theta*sin(alpha)``. They are parsed with Python's ``ast``
module (which never executes anything) and translated node by node into sympy;
only numbers, names the caller allows, arithmetic and the functions in
``FUNCTIONS`` are accepted. ``sympy.sympify`` is never used: it calls ``eval``.
"""

import ast

import numpy as np
import sympy as sp

FUNCTIONS = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan,
    "asin": sp.asin, "acos": sp.acos, "atan": sp.atan, "atan2": sp.atan2,
    "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh,
    "exp": sp.exp, "log": sp.log, "sqrt": sp.sqrt,
    "abs": sp.Abs, "sign": sp.sign, "min": sp.Min, "max": sp.Max,
}
CONSTANTS = {"pi": sp.pi}
MAX_LENGTH = 10_000

_BINARY = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
    ast.Pow: lambda a, b: a**b,
}


class ExpressionError(ValueError):
    """An expression that is malformed or uses something not allowed."""


def parse(text, symbols):
    """Translate ``text`` into a sympy expression.

    ``symbols`` maps each allowed name (``"m"``, ``"theta_dot"``, ``"wheel.y"``)
    to its sympy symbol. Raises ExpressionError naming the offending piece.
    """
    if isinstance(text, bool):
        raise ExpressionError(f"expected a number or an expression, got {text!r}")
    if isinstance(text, (int, float)):
        return _number(text)
    if not isinstance(text, str):
        raise ExpressionError(f"expected a number or an expression, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression longer than {MAX_LENGTH} characters")
    if not text.strip():
        raise ExpressionError("empty expression")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        raise ExpressionError(f"malformed expression {text!r}: {err.msg} at column {err.offset}") from None
    return _Translator(symbols, text).visit(tree.body)


class _Translator:
    def __init__(self, symbols, text):
        self.symbols = symbols
        self.text = text

    def fail(self, node, why):
        col = getattr(node, "col_offset", None)
        where = f" at column {col + 1}" if col is not None else ""
        raise ExpressionError(f"{why}{where} in {self.text!r}")

    def visit(self, node):
        method = getattr(self, "visit_" + type(node).__name__, None)
        if method is None:
            self.fail(node, f"'{ast.unparse(node)}' is not allowed (only arithmetic, numbers, names and "
                            f"the functions {', '.join(sorted(FUNCTIONS))})")
        return method(node)

    def visit_Constant(self, node):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            self.fail(node, f"constant {node.value!r} is not a number")
        return _number(node.value)

    def visit_BinOp(self, node):
        op = _BINARY.get(type(node.op))
        if op is None:
            hint = " (use ** for powers)" if isinstance(node.op, ast.BitXor) else ""
            self.fail(node, f"operator '{ast.unparse(node)}' is not allowed{hint}")
        return op(self.visit(node.left), self.visit(node.right))

    def visit_UnaryOp(self, node):
        if isinstance(node.op, ast.USub):
            return -self.visit(node.operand)
        if isinstance(node.op, ast.UAdd):
            return self.visit(node.operand)
        self.fail(node, f"operator '{ast.unparse(node)}' is not allowed")

    def visit_Name(self, node):
        return self.lookup(node, node.id)

    def visit_Attribute(self, node):
        return self.lookup(node, _dotted_name(node) or self.fail(node, f"'{ast.unparse(node)}' is not a name"))

    def lookup(self, node, name):
        if name in self.symbols:
            return self.symbols[name]
        if name in CONSTANTS:
            return CONSTANTS[name]
        close = [s for s in self.symbols if s.split(".")[-1] == name.split(".")[-1]]
        hint = f" (did you mean {', '.join(sorted(close))}?)" if close else ""
        self.fail(node, f"unknown name '{name}'{hint}")

    def visit_Call(self, node):
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in FUNCTIONS:
            self.fail(node, f"unknown function '{ast.unparse(node.func)}' (allowed: {', '.join(sorted(FUNCTIONS))})")
        if node.keywords:
            self.fail(node, f"keyword arguments are not allowed in {name}()")
        try:
            return FUNCTIONS[name](*[self.visit(arg) for arg in node.args])
        except (TypeError, ValueError) as err:
            self.fail(node, f"bad call {ast.unparse(node)}: {err}")


def _number(value):
    """An exact sympy number: 0.5 becomes 1/2, so derived balances print cleanly."""
    if isinstance(value, float) and not np.isfinite(value):
        raise ExpressionError(f"{value!r} is not a finite number")
    return sp.Integer(value) if isinstance(value, int) else sp.Rational(repr(value))


def _dotted_name(node):
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    parts.append(node.id)
    return ".".join(reversed(parts))
