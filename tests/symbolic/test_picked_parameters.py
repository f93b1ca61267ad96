"""A compiled function that picks a few of the model's parameters (``compile_function``'s
``picked``) reads each parameter array it is given: a read-only array owning its numbers (a
Data's) is read once and stands for its content; any other array is read at every call."""

import numpy as np
import sympy as sp

from mbsynth.core.values import read_only
from mbsynth.symbolic.derive import PARAMETERS, compile_function

T = sp.Symbol("t")


def test_each_parameter_array_is_read_for_itself():
    q, qd = sp.symbols("x0:2"), sp.symbols("v0:2")
    p = sp.symbols("a b c d")
    f = compile_function((T, list(q), list(qd), list(p)), [p[1] * qd[0] + p[3] * q[1] ** 2], picked=PARAMETERS)
    x, v = np.array([0.3, -1.2]), np.array([2.0, 0.5])

    def expected(values):
        return values[1] * v[0] + values[3] * x[1] ** 2

    first, second = read_only([1.0, 2.0, 3.0, 4.0]), read_only([1.0, -5.0, 3.0, 0.25])
    for given in (first, second, first, second):
        assert float(f(0.0, x, v, given)[0]) == expected(given)
    writeable = np.array(first)
    for value in (7.0, -0.5):
        writeable[3] = value
        assert float(f(0.0, x, v, writeable)[0]) == expected(writeable)
    view = read_only(np.arange(8.0))[::2]  # read-only but not owning its numbers: read every call
    assert float(f(0.0, x, v, view)[0]) == expected(view)
