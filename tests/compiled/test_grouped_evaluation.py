"""evaluation.py (constraints and parts evaluated a structure at a time) against the
reference: each constraint's and part's own compiled function called one by one."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.core.equations import term_scales

MODELS = sorted(str(p) for p in Path(__file__).parents[2].joinpath("models").rglob("*.yaml"))
SLOW_MODEL = "crossed_capsules.yaml"  # two capsules' rows take a minute to derive cold: make test-slow and CI
RNG = np.random.default_rng(7)


def one_by_one(system, t, q, qd):
    """M, Q, A, b, C, φ, φ̇, T, V from a Python loop over parts and constraints."""
    p = system.parameter_values
    n, m = system.n, sum(c.size for c in system.constraints)
    M, Q, A, b, C = np.zeros((n, n)), np.zeros(n), np.zeros((m, n)), np.zeros(m), np.zeros(n)
    phi, psi, T, V = [], [], 0.0, 0.0
    start = row = 0
    for part in system.parts:
        stop = start + len(part.coordinates)
        M[start:stop, start:stop], Q[start:stop] = part.evaluate(t, q[start:stop], qd[start:stop], p)
        kinetic, potential = part.energy(t, q[start:stop], qd[start:stop], p)
        T, V, start = T + kinetic, V + potential, stop
    for element in system.forces:
        Q[element.indices] += element.evaluate(t, q, qd, p)
        V += element.potential(t, q, qd, p)
    for con in system.constraints:
        a, b[row:row + con.size], c = con.evaluate(t, q, qd, p)
        A[row:row + con.size, con.indices] = a
        C[con.indices] += c
        f, g = con.residuals(t, q, qd, p)
        phi.append(f)
        psi.append(g)
        row += con.size
    return M, Q, A, b, C, np.concatenate([np.zeros(0)] + phi), np.concatenate([np.zeros(0)] + psi), T, V


def close(x, y, terms=1.0):
    """Equal to 1e-12 of the largest value or of ``terms``, the size of the terms a residual
    sums (its rounding: a pendulum 1 km long has φ = x² + y² − L² of terms 1e6)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    scale = max(np.abs(y[np.isfinite(y)]).max(initial=0.0), np.max(terms, initial=1.0))
    return x.shape == y.shape and np.allclose(x, y, rtol=1e-12, atol=1e-12 * scale, equal_nan=True)


@pytest.mark.parametrize("path", [pytest.param(p, marks=pytest.mark.slow) if p.endswith(SLOW_MODEL) else p
                                  for p in MODELS], ids=lambda p: Path(p).stem)
def test_batched_arrays_equal_the_loop_over_constraints(path):
    system = mb.load(path)
    q0, qd0 = system.initial_state()
    for k in range(3):  # the first state fixes the layout; the others use it
        q = q0 + 0.1 * k * RNG.normal(size=q0.size)
        qd = qd0 + 0.3 * k * RNG.normal(size=q0.size)
        t = 0.25 * k
        M, Q, A, b, C, phi, psi, T, V = one_by_one(system, t, q, qd)
        arrays = system.evaluate(t, q, qd)
        rows = system.constraint_arrays(t, q, qd)
        assert all(close(x, y) for x, y in ((arrays.M, M), (arrays.Q, Q), (arrays.A, A), (arrays.b, b),
                                              (arrays.C, C), (rows.A.toarray(), A), (rows.b, b), (rows.C, C)))
        assert close(rows.phi, phi, term_scales(A, q)) and close(rows.psi, psi, term_scales(A, qd))
        assert close(system.energy(t, q, qd), (T, V))


@pytest.mark.implementation
def test_a_robots_joints_share_one_call():
    """The UR5's links and joints are built from templates: far fewer raw calls than parts
    and constraints, and the same arrays."""
    system = mb.from_robot("ur5")
    data = system.data()
    q, qd = system.initial_state()
    qd = qd + 0.5
    M, Q, A, b, C, phi, psi, T, V = one_by_one(system, 0.0, q, qd)
    rows = data.constraint_arrays(0.0, q, qd)
    assert close(rows.A.toarray(), A) and close(rows.phi, phi) and close(rows.psi, psi)
    batch = data.evaluator.rows
    groups, singles = batch.groups()
    assert len(groups) + len(singles) < len(system.constraints) / 2


def test_a_robots_joint_torques_share_one_call_and_equal_their_sympy_force():
    """Talos's 32 actuations, each with its own torque parameter: one stacked call per joint
    template, and Q equal to the sum of the elements' sympy Q put in numbers by substitution."""
    import sympy as sp
    system = mb.from_robot("talos", floating=True)
    torques = sorted(k for k in system.parameters if k.startswith("tau_"))
    system = system.with_parameters(**{k: 0.1 + 0.01 * i for i, k in enumerate(torques)})
    q, qd = system.initial_state()
    qd = qd + RNG.normal(size=qd.size)
    Q = np.zeros(system.n)
    values = {sp.Symbol(k): v for k, v in system.parameters.items()}
    values.update(zip(system.q_symbols + system.qd_symbols, np.concatenate([q, qd])))
    for element in system.forces:
        for (i, _), x in element.Q.todok().items():
            Q[i] += float(x.xreplace(values))
    forces = system.data().evaluator
    for _ in range(2):  # the first call lays the groups out, the second uses them
        stacked = np.bincount(forces.f_cols, weights=forces.forces(0.0, q, qd, system.parameter_values)[0],
                              minlength=system.n)
        assert np.abs(stacked - Q).max() <= 1e-12 * np.abs(Q).max()
    groups, singles = forces.forces.groups()
    assert len(torques) == len(system.forces) == 32 and len(groups) + len(singles) <= 3


def test_each_parameter_array_is_read_for_itself_by_the_shared_groups():
    """Two Datas of one model share the stacked calls; each call reads the values of the array
    it is given: the Datas' read-only arrays in turn, and a writeable array changed in place
    between calls. Q against the elements' sympy Q put in numbers by substitution."""
    import sympy as sp
    system = mb.from_robot("ur5")
    torques = sorted(k for k in system.parameters if k.startswith("tau_"))
    first, second = system.data(), system.data()
    second.set_parameters({k: 0.2 + 0.05 * i for i, k in enumerate(torques)})
    q, qd = system.initial_state()
    qd = qd + RNG.normal(size=qd.size)
    forces = first.evaluator
    assert forces is second.evaluator

    def expected(p):
        values = dict(zip((sp.Symbol(k) for k in system.parameters), p))
        values.update(zip(system.q_symbols + system.qd_symbols, np.concatenate([q, qd])))
        Q = np.zeros(system.n)
        for element in system.forces:
            for (i, _), x in element.Q.todok().items():
                Q[i] += float(x.xreplace(values))
        return Q

    def stacked(p):
        return np.bincount(forces.f_cols, weights=forces.forces(0.0, q, qd, p)[0], minlength=system.n)

    writeable = second.parameter_values.copy()
    for data in (first, second, first, second):
        assert not data.parameter_values.flags.writeable
        Q = expected(data.parameter_values)
        assert np.abs(stacked(data.parameter_values) - Q).max() <= 1e-12 * np.abs(Q).max()
    for value in (0.7, -1.3):
        writeable[system.parameter_index[torques[0]]] = value
        Q = expected(writeable)
        assert np.abs(stacked(writeable) - Q).max() <= 1e-12 * np.abs(Q).max()
    assert not np.allclose(expected(first.parameter_values), expected(second.parameter_values))


@pytest.mark.parametrize("compiled", [True, False])
def test_constants_that_read_the_state_are_put_in_at_every_call(compiled):
    """Eight functions of one structure whose constants read t, a coordinate and a parameter
    (one read-only parameter array, kept between calls where only it is read): the Batch's
    outputs at three states equal their closed form and each function called alone, on the
    tape and on numpy."""
    import sympy as sp
    from mbsynth.compiled.grouped import Batch
    from mbsynth.core.values import read_only
    from mbsynth.symbolic.cache import placeholder
    from mbsynth.symbolic.derive import compile_function
    t, k = sp.symbols("t k")
    x, y, xd, yd = sp.symbols("x y xd yd")
    c0, c1 = placeholder("c0"), placeholder("c1")
    args = (t, [x, y], [xd, yd], [k])
    form = [sp.Matrix([c0 * x + c1 * yd, c0 * c1])]
    functions = [compile_function(args, form, constants=[(c0, sp.sin(t) + x ** 2), (c1, 3 * k)]) for _ in range(8)]
    indices = [np.array([i, (i + 3) % 8]) for i in range(8)]
    batch = Batch(functions, indices, 1, compiled)
    p = read_only(np.array([0.7]))
    for t0 in (0.0, 0.4, 1.3):
        q, qd = RNG.normal(size=8), RNG.normal(size=8)
        (got,) = batch(t0, q, qd, p)
        c0, c1 = np.sin(t0) + q[:8] ** 2, 3 * 0.7  # each member's constants, its x the coordinate i
        want = np.ravel([[a * q[i] + c1 * qd[(i + 3) % 8], a * c1] for i, a in enumerate(c0)])
        assert np.allclose(got, want, rtol=1e-14, atol=1e-14)
        alone = np.concatenate([np.ravel(f(t0, q[i], qd[i], p)[0]) for f, i in zip(functions, indices)])
        assert np.allclose(got, alone, rtol=1e-14, atol=1e-14)
    groups, singles = batch.groups()
    assert len(groups) == 1 and not singles
