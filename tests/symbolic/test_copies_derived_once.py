"""Copies of an energy-defined part (one cell used many times, each copy with symbols of its
own) are derived by sympy once, compiled once, and each copy gets its own M, Q (2.1): those
Lagrange's equations give for it alone."""

import numpy as np
import sympy as sp

import mbsynth as mb
from mbsynth.compiled import codegen, layout
from mbsynth.symbolic import derive

COPIES = 12
# a particle in polar coordinates on a spring of rest length l about the origin, in a plane
# without gravity, and a rod-free cell constraint keeping it at r <= 2 l (a holonomic row)
CELL = """\
  cell_{i}:
    type: lagrangian
    coordinates: [r, th]
    T: 0.5*m_{i}*(r_dot**2 + r**2*th_dot**2)
    V: 0.5*k_{i}*(r - l_{i})**2
"""


def model(count, first=0):
    """The flat model text of ``count`` cells numbered from ``first``, each with its own
    m, k, l, the angle of each joined to its neighbour's by a holonomic constraint."""
    parameters = ", ".join(f"m_{i}: {1 + 0.1 * i}, k_{i}: {50 + i}, l_{i}: {0.5 + 0.01 * i}"
                           for i in range(first, first + count))
    cells = "".join(CELL.format(i=i) for i in range(first, first + count))
    constraints = "".join(f"  - {{name: c_{i}, holonomic: cell_{i}.th - cell_{i}.r*l_{i}}}\n"
                          for i in range(first, first + count))
    initial = ", ".join(f"cell_{i}.r: {0.6 + 0.01 * i}, cell_{i}.th: {(0.6 + 0.01 * i) * (0.5 + 0.01 * i)}, "
                        f"cell_{i}.r_dot: 0.1" for i in range(first, first + count))
    return (f"name: cells\nparameters: {{{parameters}}}\nparts:\n{cells}constraints:\n{constraints}"
            f"initial: {{{initial}}}\n")


def test_copies_are_derived_once_and_each_gets_its_own_equations(monkeypatch):
    derive._lagrange.cache_clear()
    derive._differentiated.cache_clear()
    asked = []
    remembered = derive.remembered
    monkeypatch.setattr(derive, "remembered", lambda kind, *rest, **kw: asked.append(kind) or remembered(kind, *rest, **kw))
    system = mb.loads(model(COPIES))
    assert asked.count("lagrange") == 1  # one sympy derivation of Lagrange's equations for all the copies
    assert asked.count("differentiated") == 1  # one differentiation of the constraints alike
    parts = system.parts
    assert len({id(part._evaluate.raw) for part in parts}) == 1  # one compiled function

    # Lagrange's equations for this T, V by hand: M = diag(m, m r²),
    # Q = (m r θ̇² − k (r − l), −2 m r ṙ θ̇)
    for i, part in enumerate(parts):
        r, th = part.q
        rd, thd = part.qd
        m, k, l = sp.symbols(f"m_{i} k_{i} l_{i}")
        assert sp.simplify(part.M - sp.diag(m, m * r**2)) == sp.zeros(2, 2)
        assert sp.simplify(part.Q - sp.Matrix([m * r * thd**2 - k * (r - l), -2 * m * r * rd * thd])) == sp.zeros(2, 1)

    # and copy i's M, Q equal those of copy i loaded alone, its own derivation
    i = 7
    alone = mb.loads(model(1, first=i)).parts[0]
    assert alone.q == parts[i].q and alone.qd == parts[i].qd
    assert sp.simplify(alone.M - parts[i].M) == sp.zeros(2, 2)
    assert sp.simplify(alone.Q - parts[i].Q) == sp.zeros(2, 1)

    # numerically, through the compiled functions: copy i at a state, against the formulas
    p = system.parameter_values
    values = dict(zip(system.parameters, p))
    state = np.array([0.7, 0.3]), np.array([0.2, -0.4])
    for i in (0, 5, COPIES - 1):
        M, Q = parts[i].evaluate(0.0, *state, p)
        m, k, l = values[f"m_{i}"], values[f"k_{i}"], values[f"l_{i}"]
        (r, th), (rd, thd) = state
        assert np.allclose(M, np.diag([m, m * r**2]), rtol=1e-14, atol=0)
        assert np.allclose(Q, [m * r * thd**2 - k * (r - l), -2 * m * r * rd * thd], rtol=1e-14, atol=0)


def test_copies_simulate_on_the_compiled_path_in_one_loop_per_form(monkeypatch):
    monkeypatch.setenv("MBSYNTH_COMPILED", "wait")  # the compiled path, built now
    system = mb.loads(model(COPIES))
    exprs = layout.build(system)[1]
    text = codegen.source(exprs, system.q_symbols, system.qd_symbols, system.parameter_symbols)
    assert text.count(f"for _m in range({COPIES}):") >= 5  # M, Q, rows, b, φ of the copies: loops, not copies
    assert system.data().engine is not None  # the compiled path
    result = mb.simulate(system, 0.05)
    for i in (0, 4, COPIES - 1):  # each copy moves as the cell alone, on the KKT path (the copies are not coupled)
        monkeypatch.setenv("MBSYNTH_COMPILED", "off")
        alone = mb.simulate(mb.loads(model(1, first=i)), 0.05)
        at = system.coordinates.index(f"cell_{i}.r")
        assert np.allclose(result.q[-1][at:at + 2], alone.q[-1], rtol=0, atol=1e-8)
