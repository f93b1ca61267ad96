"""Model expressions are parsed, never executed."""

import pytest
import sympy as sp

from mbsynth.core.expressions import ExpressionError, parse

x, y, m = sp.symbols("x y m")
SYMBOLS = {"x": x, "wheel.y": y, "m": m}


def test_arithmetic_and_functions_translate_to_sympy():
    expr = parse("0.5*m*x**2 - 3*sin(wheel.y)/2 + sqrt(abs(x)) + pi", SYMBOLS)
    assert sp.simplify(expr - (sp.Rational(1, 2) * m * x**2 - sp.Rational(3, 2) * sp.sin(y)
                              + sp.sqrt(sp.Abs(x)) + sp.pi)) == 0


def test_numbers_pass_through():
    assert parse(2, {}) == 2 and parse(0.25, {}) == sp.Rational(1, 4) and parse("1e-3", {}) == sp.Rational(1, 1000)


@pytest.mark.parametrize("text, fragment", [
    ("__import__('os').system('echo hacked')", "unknown function"),
    ("x.__class__", "unknown name 'x.__class__'"),
    ("open('f')", "unknown function 'open'"),
    ("[x for x in y]", "not allowed"),
    ("lambda: 1", "not allowed"),
    ("x if m else 1", "not allowed"),
    ("'text'", "not a number"),
    ("x ^ 2", "use ** for powers"),
    ("z + 1", "unknown name 'z'"),
    ("y + 1", "did you mean wheel.y"),
    ("sin(x, wheel.y, m)", "bad call"),
    ("2 *", "malformed expression"),
    ("", "empty expression"),
    ("x < 1", "not allowed"),
])
def test_forbidden_or_malformed_input_is_refused(text, fragment):
    with pytest.raises(ExpressionError, match=None) as err:
        parse(text, SYMBOLS)
    assert fragment in str(err.value)


def test_booleans_and_other_types_are_refused():
    for value in (True, None, [1]):
        with pytest.raises(ExpressionError):
            parse(value, SYMBOLS)
