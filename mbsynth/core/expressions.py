"""Safe parsing of model expressions into sympy.

A model file holds expressions such as ``0.5*m*(R*theta_dot)**2`` or
``wheel.y - R*wheel.theta*sin(alpha)``. They are parsed with Python's ``ast``
module (which never executes anything) and translated node by node into sympy;
only numbers, names the caller allows, arithmetic and the functions in
``FUNCTIONS`` are accepted. ``sympy.sympify`` is never used: it calls ``eval``.

Bounds keep every expression cheap and its numbers usable in double precision:
at most ``MAX_LENGTH`` characters and ``MAX_DEPTH`` levels of nesting (a chain
``a + b - c + ...`` counts as one level); no exact power of numbers beyond
``MAX_POWER_BITS`` bits (``2**2**2**2**2**2`` would never finish); and the result
holds no number beyond the double range, no division by zero and nothing complex.
"""

import ast
import re

import numpy as np
import sympy as sp
from .memo import MEMO

FUNCTIONS = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan,
    "asin": sp.asin, "acos": sp.acos, "atan": sp.atan, "atan2": sp.atan2,
    "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh,
    "exp": sp.exp, "log": sp.log, "sqrt": sp.sqrt,
    "abs": sp.Abs, "sign": sp.sign, "min": sp.Min, "max": sp.Max,
}
CONSTANTS = {"pi": sp.pi}
MAX_LENGTH = 10_000
MAX_DEPTH = 50
MAX_POWER_BITS = 10_000  # largest exact numeric power computed while parsing
MAX_EXPONENT = 1024  # largest exponent of a number that is not rational (sqrt(2)**e)
LARGEST = sp.Float(np.finfo(float).max)

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
    found = _from_form(text.strip(), symbols)
    if found is not None:
        return found
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        where = f" at column {err.offset}" if err.offset else ""
        raise ExpressionError(f"malformed expression {_short(text)}: {err.msg}{where}") from None
    except (ValueError, RecursionError, MemoryError) as err:  # null bytes; nesting Python cannot parse
        raise ExpressionError(f"malformed expression {_short(text)}: "
                              f"{'nested too deeply' if not isinstance(err, ValueError) else err}") from None
    return _check_value(_Translator(symbols, text.strip()).visit(tree.body), text)


_NAME = re.compile(r"(?<![\w.])[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*")  # a name, dotted or not, not inside a number


def _from_form(text, symbols):
    """``parse(text, symbols)`` through the text's *form* (each name of ``symbols`` replaced
    by a positional placeholder ``_v0, _v1, …``), parsed once per form and its placeholders
    replaced by the symbols: copies of an expression that differ only in their names (a
    cell used a thousand times) are parsed once. None where that could differ from parsing
    the text itself: a name that is not a plain Symbol of ``symbols`` (a function, a
    constant, an expression, an unknown name), or a form that does not parse (the text is
    parsed then, for its own message)."""
    names = []
    for name in _NAME.findall(text):
        if name not in names:
            if name in FUNCTIONS or name in CONSTANTS:
                if name in symbols:
                    return None
                continue
            if name not in symbols or type(symbols[name]) is not sp.Symbol:
                return None
            names.append(name)
    place = {name: f"_v{j}" for j, name in enumerate(names)}
    form = _NAME.sub(lambda m: place.get(m.group(0), m.group(0)), text)
    try:
        expr = _parsed_form(form, len(names))
    except (ValueError, SyntaxError, RecursionError, MemoryError):  # ExpressionError among them
        return None
    return expr.xreplace({_form_slot(j): symbols[name] for j, name in enumerate(names)}) if names else expr


def _form_slot(j):
    """The symbol standing for a form's j-th name: a name no model symbol has."""
    return sp.Symbol(f"\0v{j}")


@MEMO.function(4096)
def _parsed_form(form, count):
    slots = {f"_v{j}": _form_slot(j) for j in range(count)}
    return _check_value(_Translator(slots, form).visit(ast.parse(form, mode="eval").body), form)


def _check_value(expr, text):
    """``expr`` unless it holds an infinity or NaN, a number beyond the double range, or
    a complex constant (sqrt(-1), (-8)**(1/3), log(-1))."""
    if expr.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise ExpressionError(f"{_short(text)} divides by zero or is not finite")
    if any(abs(x) > LARGEST for x in expr.atoms(sp.Number)):
        raise ExpressionError(f"{_short(text)} holds a number beyond the double range (±{float(LARGEST):.3g})")
    if expr.has(sp.I) or any(x.base.is_negative and not x.exp.is_integer
                             for x in expr.atoms(sp.Pow) if x.base.is_number and x.exp.is_number):
        raise ExpressionError(f"{_short(text)} is not real (a root or logarithm of a negative number)")
    return expr


def _short(text, size=80):
    """repr of ``text`` cut to about ``size`` characters, for messages."""
    text = repr(text)
    return text if len(text) <= size else text[:size - 5] + "...'"


class _Translator:
    def __init__(self, symbols, text):
        self.symbols = symbols
        self.text = text
        self.depth = 0

    def fail(self, node, why):
        col = getattr(node, "col_offset", None)
        where = f" at column {col + 1}" if col is not None else ""
        raise ExpressionError(f"{why}{where} in {_short(self.text)}")

    def source(self, node):
        """The text of ``node`` (cut short), without ast.unparse's recursion."""
        segment = ast.get_source_segment(self.text, node) or type(node).__name__
        return segment if len(segment) <= 40 else segment[:37] + "..."

    def visit(self, node):
        method = getattr(self, "visit_" + type(node).__name__, None)
        if method is None:
            self.fail(node, f"'{self.source(node)}' is not allowed (only arithmetic, numbers, names and "
                            f"the functions {', '.join(sorted(FUNCTIONS))})")
        if self.depth >= MAX_DEPTH:
            self.fail(node, f"expression nested more than {MAX_DEPTH} levels deep")
        self.depth += 1
        try:
            return method(node)
        finally:
            self.depth -= 1

    def visit_Constant(self, node):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            self.fail(node, f"constant {node.value!r} is not a number")
        return _number(node.value)

    def visit_BinOp(self, node):
        chain = []  # a + b - c ... is nested to the left: walk it as one level
        while isinstance(node, ast.BinOp) and type(node.op) in _BINARY and not isinstance(node.op, ast.Pow):
            chain.append(node)
            node = node.left
        value = self.binary(node) if isinstance(node, ast.BinOp) else self.visit(node)
        for link in reversed(chain):
            value = _BINARY[type(link.op)](value, self.visit(link.right))
        return value

    def binary(self, node):
        """A power, or an operator that is not allowed."""
        if not isinstance(node.op, ast.Pow):
            hint = " (use ** for powers)" if isinstance(node.op, ast.BitXor) else ""
            self.fail(node, f"operator '{self.source(node)}' is not allowed{hint}")
        base, exponent = self.visit(node.left), self.visit(node.right)
        if _huge_power(base, exponent) or not _finite_real(exponent):
            self.fail(node, f"the power '{self.source(node)}' is too large to compute")
        return self.real(node, base**exponent)

    def real(self, node, value):
        """``value`` of ``node``, unless it is a number that is complex or beyond the double range."""
        if not _finite_real(value):
            self.fail(node, f"'{self.source(node)}' is not a finite real number")
        return value

    def visit_UnaryOp(self, node):
        if isinstance(node.op, ast.USub):
            return -self.visit(node.operand)
        if isinstance(node.op, ast.UAdd):
            return self.visit(node.operand)
        self.fail(node, f"operator '{self.source(node)}' is not allowed")

    def visit_Name(self, node):
        return self.lookup(node, node.id)

    def visit_Attribute(self, node):
        return self.lookup(node, _dotted_name(node) or self.fail(node, f"'{self.source(node)}' is not a name"))

    visit_Subscript = visit_Attribute

    def lookup(self, node, name):
        if name in self.symbols:
            return self.symbols[name]
        if name in CONSTANTS:
            return CONSTANTS[name]
        close = [s for s in self.symbols if s.split(".")[-1] == name.split(".")[-1]]
        hint = f" (did you mean {', '.join(sorted(close))}?)" if close else ""
        owner = name.rpartition(".")[0]
        members = sorted(s.rpartition(".")[2] for s in self.symbols if owner and s.rpartition(".")[0] == owner)
        if members:  # a part's or joint's name with a key it has not: say which it has
            hint += f" ('{owner}' has {', '.join(members)})"
        self.fail(node, f"unknown name '{name}'{hint}")

    def visit_Call(self, node):
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in FUNCTIONS:
            self.fail(node, f"unknown function '{self.source(node.func)}' (allowed: {', '.join(sorted(FUNCTIONS))})")
        if node.keywords:
            self.fail(node, f"keyword arguments are not allowed in {name}()")
        args = [self.visit(arg) for arg in node.args]
        if not all(map(_finite_real, args)):
            self.fail(node, f"an argument of '{self.source(node)}' is not finite in double precision")
        try:
            value = FUNCTIONS[name](*args)
        except (TypeError, ValueError) as err:
            self.fail(node, f"bad call {self.source(node)}: {err}")
        return self.real(node, value)


def _finite_real(expr):
    """Whether ``expr`` is not a number, or a real number of the double range. Checked on
    every numeric argument and result, so that no evaluation is ever asked of a number
    beyond it (exp(exp(exp(100))) would need mpmath to reduce an argument of 10^(10^43))."""
    if not expr.is_number:
        return True
    try:
        value = complex(expr.evalf(15))
    except (TypeError, ValueError, OverflowError):
        return False
    return bool(np.isfinite(value)) and value.imag == 0


def _huge_power(base, exponent):
    """Whether sympy would compute base**exponent exactly as a number of more than
    MAX_POWER_BITS bits (or with an exponent above MAX_EXPONENT for other numbers)."""
    if not (base.is_number and exponent.is_Rational) or base in (0, 1, -1):
        return False
    if not base.is_Rational:
        return abs(exponent) > MAX_EXPONENT
    bits = max(abs(base.p).bit_length(), base.q.bit_length())
    return abs(exponent.p) * bits > MAX_POWER_BITS * exponent.q


def _number(value):
    """An exact sympy number: 0.5 becomes 1/2, so derived balances print cleanly."""
    if isinstance(value, float) and not np.isfinite(value):
        raise ExpressionError(f"{value!r} is not a finite number")
    return sp.Integer(value) if isinstance(value, int) else sp.Rational(repr(value))


def _dotted_name(node):
    """``a.b.c`` of a chain of attributes, or None; a copy of a repeated substructure is
    named with its index, ``cell[2].bar.x`` (an integer in brackets after a name)."""
    pieces = []
    while not isinstance(node, ast.Name):
        if isinstance(node, ast.Attribute):
            pieces.append("." + node.attr)
        elif (isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant)
              and type(node.slice.value) is int and node.slice.value >= 0):
            pieces.append(f"[{node.slice.value}]")
        else:
            return None
        node = node.value
    return node.id + "".join(reversed(pieces))
