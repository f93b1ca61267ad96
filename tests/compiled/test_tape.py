"""The tape (mbsynth/compiled/tape.py): every operation it knows evaluates as numpy does
(sympy's lambdify, the grouped evaluation's reference) over several instances, NaN where
NaN; an expression it does not know is refused, and the structure is then compiled on its
own; the bundled models' structures evaluate on the tape bit for bit as compiled alone."""

from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import mbsynth as mb
from mbsynth.compiled import structures, tape

MODELS = Path(__file__).resolve().parents[2] / "models"
t = sp.Symbol("t")
q = sp.symbols("q0:3")
qd = sp.symbols("qd0:2")
p = sp.symbols("p0:2")
c = sp.symbols("c0:1")
k = sp.symbols("k0:1")
ARGS = (t, q, qd, p, c, k)
x, y, z = q
FORMS = [
    x * y - z / (x + 2) + 3 * qd[0] ** 2 - p[0] * c[0] * k[0],
    sp.sin(x) * sp.cos(y) + sp.tan(z / 4) - t * qd[1],
    sp.asin(x / 3) + sp.acos(y / 3) + sp.atan(z) + sp.atan2(y, x),
    sp.sinh(x / 2) + sp.cosh(y / 2) + sp.tanh(z) + sp.exp(-x ** 2),
    sp.log(x) + sp.sqrt(y) + 1 / sp.sqrt(z) + x ** 5 + y ** -3 + z ** sp.Rational(1, 3) + x ** p[1],
    sp.Abs(x - y) + sp.sign(z) + sp.floor(x * 2) + sp.ceiling(y * 2) + sp.Max(x, y, z) + sp.Min(x, y),
    sp.Piecewise((x, x < y), (y, (y <= z) & (x > 0)), (z, sp.Ne(x, z) | sp.Not(y >= 1)), (t, True)),
    sp.Piecewise((x ** 2, sp.Eq(sp.floor(y), 0)), (-y, sp.Ge(z, x))),  # NaN where no branch holds
    sp.pi * x + sp.E - sp.Rational(2, 3) * y + sp.Float(1e-3) * z,
]


def numpy_of(forms):
    """The numpy evaluation of ``forms`` at each instance, as the grouped evaluation's numpy path."""
    f = sp.lambdify(ARGS, forms, modules="numpy")

    def evaluate(time, Q, QD, P, C, K):
        with np.errstate(all="ignore"):
            return np.array([np.broadcast_to(np.asarray(v, dtype=float), Q.shape[1:])
                             for v in f(time, tuple(Q), tuple(QD), tuple(P), tuple(C), tuple(K))])
    return evaluate


def on_tape(forms, time, Q, QD, P, C, K):
    """The tape's values at each instance m (columns m of Q, QD, C, K)."""
    members = Q.shape[1]
    columns = np.array([[m * len(q) + j for m in range(members)] for j in range(len(q))], dtype=np.int64)
    rates = np.zeros((len(q), members))  # q̇ slot j is the rate of coordinate slot j: read through its column
    rates[:len(qd)] = QD
    return evaluate_one(tape.tape(ARGS, forms), len(forms), time, Q.T.ravel(), rates.T.ravel(), P, columns, C, K)


def evaluate_one(taped, outputs, time, q, qd, p, columns, values, fixed):
    """A structure's tape over its instances (columns, values and fixed: rows × members) as
    a Program of one structure: its outputs × members."""
    dest = np.arange(outputs * columns.shape[1]).reshape(outputs, -1)
    out = np.full(dest.size, np.nan)
    tape.Program([(taped, columns, len(values), fixed, dest)])(time, q, qd, p, np.ravel(values), out)
    return out.reshape(dest.shape)


@pytest.mark.parametrize("form", range(len(FORMS)))
def test_every_operation_evaluates_as_numpy_does(form):
    rng = np.random.default_rng(7)
    members = 64
    Q = rng.uniform(-2.5, 2.5, (len(q), members))
    Q[:, :4] = [[0.0, 1.0, -1.0, 0.5]] * 3  # zeros, equal values, the Piecewise's edges
    QD = rng.uniform(-1, 1, (len(qd), members))
    P, C, K = np.array([0.7, 1.5]), rng.uniform(0.5, 2, (1, members)), rng.uniform(-1, 1, (1, members))
    want = numpy_of([FORMS[form]])(0.3, Q, QD, P, C, K)
    got = on_tape([FORMS[form]], 0.3, Q, QD, P, C, K)
    assert np.isnan(want).any() == np.isnan(got).any()
    assert np.allclose(got, want, rtol=1e-14, atol=1e-14, equal_nan=True)


def test_an_expression_the_tape_does_not_know_is_refused():
    with pytest.raises(tape.Unsupported, match="gamma"):
        tape.tape(ARGS, [sp.gamma(x) + y])
    with pytest.raises(tape.Unsupported, match="ImaginaryUnit"):
        tape.tape(ARGS, [sp.I * x])


@pytest.mark.parametrize("path", ["rolling/bicycle.yaml", "mechanisms/andrews.yaml"])
def test_a_models_structures_on_the_tape_equal_them_compiled_alone(path):
    """Each constraint structure of the model: the tape's values and those of the structure's
    own compiled function, at the initial state, are the same numbers (to rounding: the
    compiled function may group a product or a sum otherwise)."""
    model = mb.load(MODELS / path)
    q0, qd0 = model.initial_state()
    data = model.data("compiled")
    data.constraint_arrays(0.0, q0, qd0)
    groups, _ = data.evaluator.rows.groups()
    assert groups
    for group in groups:
        args, forms = group.raw.structure()
        alone = structures.load(structures.source(args, forms), prefix="mbsynth_structure").evaluate
        values = group.stacked_values(0.0, q0, qd0, data.parameter_values)
        compiled = np.empty(group.dest.shape)
        taped = evaluate_one(tape.tape(args, forms), len(forms), 0.0, q0, qd0, data.parameter_values,
                             group.columns, values, group.fixed)
        alone(0.0, q0, qd0, data.parameter_values, group.columns, values, group.fixed, compiled)
        assert np.allclose(taped, compiled, rtol=1e-13, atol=1e-13, equal_nan=True)


def test_a_structure_the_tape_does_not_know_is_compiled_on_its_own_once():
    """Three functions of a structure holding Γ (no tape operation): grouped on the
    structure's own compiled function, their values those of math.gamma, and that
    function compiled once, for the read-only parameter array a Data passes (numba
    compiles a function again for each kind of array)."""
    import math
    from mbsynth.compiled.grouped import Batch
    from mbsynth.core.values import read_only
    from mbsynth.symbolic.derive import compile_function
    t, k = sp.Symbol("t"), sp.Symbol("k")
    x, y, xd, yd = sp.symbols("x y xd yd")
    functions = [compile_function((t, [x, y], [xd, yd], [k]), [sp.Matrix([sp.gamma(x ** 2 + 1) * k + yd])])
                 for _ in range(3)]
    indices = [np.array([i, i + 3]) for i in range(3)]
    batch = Batch(functions, indices, 1, True)
    p = read_only(np.array([0.7]))
    q, qd = np.linspace(0.1, 0.9, 6), np.linspace(-1.0, 1.0, 6)
    for _ in range(2):  # the first call lays the groups out, the second runs them
        (got,) = batch(0.2, q, qd, p)
    want = [math.gamma(q[i] ** 2 + 1) * 0.7 + qd[i + 3] for i in range(3)]
    assert np.allclose(got, want, rtol=1e-14, atol=0)
    (group,), singles = batch.groups()
    assert not singles and callable(group.kernel) and len(group.kernel.signatures) == 1
