"""Continuous integration with the kernel's own projection: the compiled rows
(fast/rows.py) against the System's residuals and energies, the projection
(fast/compiled/projection.py) against the least-mass-norm step's defining identity, and a whole
run against Pinocchio's aba in the same scipy integrator."""

import multiprocessing
from pathlib import Path
from queue import Empty

import numpy as np
import pinocchio as pin
import pytest
import scipy.integrate
import scipy.linalg

import mbsynth as mb
import mbsynth.compiled.projection as projection_module
from mbsynth.robots.twin import Twin

ROOT = Path(__file__).resolve().parents[2]
MODELS = ["rigid/double_pendulum_3d.yaml", "rigid/tennis_racket.yaml", "robots/ur5_payload.yaml"]
# joint ends on particles too: the rows read a particle's frame origin at its position
WITH_PARTICLES = ["mechanisms/massless_link.yaml", "mechanisms/double_pendulum_rods.yaml"]
# extra coordinates alone (compiled/extra_projection.py): an energy-defined part (a full M), planar bodies
EXTRA = ["mechanisms/andrews.yaml", "mechanisms/four_bar.yaml", "mechanisms/slider_crank.yaml"]


@pytest.fixture(autouse=True)
def compiled_path(monkeypatch):
    monkeypatch.setenv("MBSYNTH_COMPILED", "wait")


def projection_of(system):
    engine = system.data().engine
    assert engine is not None
    projection = engine.projection()
    assert projection is not None
    return projection


def drifted_state(system, rng, size=1e-6, rate_size=1.0):
    """The model's consistent initial state, moving, pushed off the constraints by ``size``
    (positions) and ``rate_size`` (rates)."""
    traj = mb.simulate(system, 0.05, dt=0.05)
    q, qd = traj.q[-1], traj.qd[-1]
    return q + size * rng.standard_normal(q.size), qd + rate_size * rng.standard_normal(qd.size)


@pytest.mark.parametrize("model", MODELS + WITH_PARTICLES + EXTRA)
def test_compiled_rows_equal_the_systems_residuals_and_energies(model):
    system = mb.load(ROOT / "models" / model)
    rng = np.random.default_rng(3)
    q, qd = drifted_state(system, rng)
    phi, psi, kinetic, potential = projection_of(system).residuals_energy(0.0, q, qd)
    phi_ref, psi_ref = system.constraint_residuals(0.0, q, qd)
    np.testing.assert_allclose(phi, phi_ref, rtol=1e-10, atol=1e-15)
    np.testing.assert_allclose(psi, psi_ref, rtol=1e-10, atol=1e-13)
    if projection_of(system).energies and all(f.V == 0 for f in system.forces):
        np.testing.assert_allclose((kinetic, potential), system.energy(0.0, q, qd), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("size", [0, 1, 3, 4, 7, 420])
def test_the_rows_largest_entry_is_numpys_and_a_nan_shows(size):
    """rows.largest (four interleaved maxima) against numpy's max |x|, each entry in turn the
    largest (every place of the four); a NaN or an infinity anywhere shows."""
    from mbsynth.compiled.rows import largest
    x = np.random.default_rng(size).uniform(-1.0, 1.0, size)
    assert largest(x) == (np.abs(x).max() if size else 0.0)
    for i in range(size):
        y = x.copy()
        y[i] = -5.0
        assert largest(y) == 5.0
        y[i] = np.nan
        assert np.isnan(largest(y))
        y[i] = -np.inf
        assert largest(y) == np.inf


@pytest.mark.parametrize("drift", [(1e-6, 1.0), (1e-10, 1e-10)], ids=["large", "integrator's"])
@pytest.mark.parametrize("model", MODELS + EXTRA)
def test_a_projection_is_the_least_mass_norm_step_onto_the_constraints(model, drift):
    """The step Δ onto A Δ = −r that is least in the mass metric satisfies M Δ ∈ range(Aᵀ)
    (its Lagrange condition, with A where the step was taken): Nᵀ M Δ = 0 for a basis N of
    null(A) (a free body's M Δ is zero: its unit-norm row is projected along the
    quaternion, which M does not weigh). The position step is taken at the drifted q
    (Gauss–Newton), the velocity step at the projected one — or, after an integrator's
    drift, with the position step's factorization (A at the drifted q, equal to the
    identity's tolerance). After them, φ and φ̇ vanish to rounding."""
    system = mb.load(ROOT / "models" / model)
    q, qd = drifted_state(system, np.random.default_rng(4), *drift)
    q_on, qd_on = projection_of(system)(0.0, q, qd)[:2]
    phi, psi = system.constraint_residuals(0.0, q_on, qd_on)
    assert np.abs(phi).max() < 1e-14 * max(np.abs(q).max(), 1) and np.abs(psi).max() < 1e-12 * np.abs(qd).max()
    for at, start, end in ((q, q, q_on), (q_on, qd, qd_on)):
        arrays = system.evaluate(0.0, at, qd)
        M, N = np.asarray(arrays.M), scipy.linalg.null_space(np.asarray(arrays.A))
        step = end - start  # exact but for rounding of the sum: ε |start| per entry
        rounding = len(step) * np.finfo(float).eps * np.abs(start).max()
        assert np.abs(step).max() > 0
        assert np.abs(N.T @ M @ step).max() < np.abs(M).max() * (1e-9 * np.abs(step).max() + rounding)


@pytest.mark.parametrize("model", MODELS + ["mechanisms/double_pendulum_rods.yaml"])
def test_a_reusing_call_at_rest_solves_as_a_full_call(model):
    """kernel.motion's REUSED at rest (q̇ = 0, no gravity) with shifts on the joint rows
    alone — a projection's velocity step — rebuilds only the right side (the shifts,
    equilibrated) and solves with the factorization of the call before it: its q̈ equals
    that of a full call at the same state and shifts, and meets the rows as the System's
    sympy derivation gives them (A q̈ = shift: b vanishes at rest); with a unit-norm row
    shifted too it makes the full call itself. (A massless link at rest, with no gravity,
    is a singular tree block: the kernel declines it.)"""
    from mbsynth.compiled import kernel
    from mbsynth.compiled.engine import EMPTY, NO_BODIES
    system = mb.load(ROOT / "models" / model)
    rng = np.random.default_rng(8)
    q = drifted_state(system, rng, 1e-6)[0]
    rest = system.data().engine.at_rest()
    quat = [r for r in rest.L.quat_row if r >= 0]
    gen, qd = np.zeros(rest.outputs), np.zeros(q.size)

    def call(shift, mode):
        status = kernel.motion_rates(q, qd, gen, shift, *rest.buffers, mode, -1.0, rest.general, NO_BODIES, EMPTY)[0]
        assert status == kernel.OK
        return rest.W.qdd.copy()

    first, joint_rows = rng.standard_normal(len(system.constraint_names)), rng.standard_normal(len(system.constraint_names))
    joint_rows[quat] = 0.0
    unit_too = joint_rows.copy()
    unit_too[quat] = rng.standard_normal(len(quat))
    A = np.asarray(system.evaluate(0.0, q, qd).A)  # the rows as sympy derived them; b = 0 at rest
    for shift in (joint_rows, unit_too):
        call(first, kernel.UNCHECKED)  # factors the tree at q, for another right side
        reused = call(shift, kernel.REUSED)
        full = call(shift, kernel.UNCHECKED)
        assert np.abs(full).max() > 0 or not shift.any()  # (a lone body has no joint rows)
        np.testing.assert_allclose(reused, full, rtol=0, atol=1e-12 * np.abs(full).max())
        np.testing.assert_allclose(A @ reused, shift, rtol=0, atol=1e-10 * max(np.abs(shift).max(), 1))


def test_a_block_of_states_is_projected_as_each_state_alone():
    """Projection.block splits many states among threads, each with its own Work and rows:
    every state comes out bit for bit as a projection of that state alone, and one the
    kernel declines (not finite) comes out None without disturbing the others."""
    system = mb.load(ROOT / "models" / "robots/ur5_payload.yaml")
    rng = np.random.default_rng(6)
    q, qd = drifted_state(system, rng, 0.0, 0.0)
    count = 2 * projection_module.PER_THREAD // q.size + 2  # enough for two threads
    Q, QD = q + 1e-9 * rng.standard_normal((count, q.size)), qd + 1e-9 * rng.standard_normal((count, q.size))
    Q[7] = np.nan
    projection = projection_of(system)
    block = projection.block(np.zeros(count), Q, QD)
    assert len(block.q) == count and block.row(7) is None
    for i, (q, qd) in enumerate(zip(Q, QD)):
        together, alone = block.row(i), projection(0.0, q, qd)
        if alone is None:
            assert together is None
            continue
        for a, b in zip(alone, together):
            np.testing.assert_array_equal(a, b)


def _simulate_into(queue, system):
    queue.put(mb.simulate(system, 0.02, dt=1e-4).q)


def test_a_forked_process_projects_in_threads_of_its_own():
    """Each step of a UR5 passes tens of output rows (every 0.1 ms), projected in blocks
    on the shared threads (fast/threads.py); a process forked after that has none of the
    parent's threads, makes its own and gives the parent's trajectory to the bit."""
    system = mb.load(ROOT / "models" / "robots/ur5_payload.yaml")
    expected = mb.simulate(system, 0.02, dt=1e-4)
    assert len(expected.t) * system.n > expected.stats["steps"] * 2 * projection_module.PER_THREAD
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_simulate_into, args=(queue, system))
    child.start()
    try:
        reached = queue.get(timeout=120)
    except Empty:
        child.kill()
        pytest.fail("the forked process hung or failed")
    child.join(10)
    np.testing.assert_array_equal(reached, expected.q)


def test_a_ur5_falls_as_pinocchio_integrates_it_with_as_many_evaluations():
    """0.5 s of a UR5 from joint rates of ±1 rad/s, DOP853 at 1e-10, against Pinocchio's
    aba in scipy's solve_ivp with the same settings: the same end to 1e-8 m, the same
    number of evaluations within 30 % (the integrator is not restarted at output times),
    the constraints kept to 1e-12 and the energy to 1e-8 J."""
    twin = Twin(mb.from_robot("ur5"))
    rng = np.random.default_rng(5)
    v0 = rng.uniform(-1, 1, twin.model.nv)
    q0 = pin.neutral(twin.model)
    data = twin.model.createData()

    def aba(t, y):
        q, v = y[:twin.model.nq], y[twin.model.nq:]
        return np.concatenate([v, pin.aba(twin.model, data, q, v, np.zeros(twin.model.nv))])

    reference = scipy.integrate.solve_ivp(aba, (0, 0.5), np.concatenate([q0, v0]), method="DOP853", rtol=1e-10,
                                          atol=1e-10)
    start = dict(zip(("q0", "qd0"), twin.to_maximal(q0, v0)))
    traj = mb.simulate(twin.system, 0.5, method="DOP853", rtol=1e-10, atol=1e-10, **start)
    reached = twin.to_maximal(reference.y[:twin.model.nq, -1], np.zeros(twin.model.nv))[0]
    assert np.abs((reached - traj.q[-1]).reshape(-1, 7)[:, :3]).max() < 1e-8
    assert traj.stats["evaluations"] < 1.3 * reference.nfev
    assert traj.max_residual < 1e-12
    assert np.ptp(traj.energy) < 1e-8


def test_rows_that_read_the_time_are_projected_at_the_states_time():
    """The spin-up beam's servo row (hub angle = θ(t)): a state of its run at 7 s (θ̇ = 2.8
    rad/s), pushed off the constraints, is put on them at 7 s — φ and φ̇ by the System's own
    rows at 7 s (φ̇ with its ∂φ/∂t) vanish to rounding — and not at another time: projected
    as if 1 ms earlier, its rows at 7 s are off by about θ's change (2.8 mrad)."""
    system = mb.load(ROOT / "models" / "flexible" / "spin_up_beam.yaml")
    run = mb.simulate(system, 7.0, dt=7.0)
    q, qd = run.q[-1], run.qd[-1]
    rng = np.random.default_rng(9)
    q, qd = q + 1e-7 * rng.standard_normal(q.size), qd + 1e-7 * rng.standard_normal(q.size)
    projection = projection_of(system)
    on = projection(7.0, q, qd)
    phi, psi = system.constraint_residuals(7.0, on.q, on.qd)
    assert np.abs(phi).max() < 1e-13 and np.abs(psi).max() < 1e-11 * np.abs(qd).max()
    elsewhere = projection(7.0 - 1e-3, q, qd)
    phi, psi = system.constraint_residuals(7.0, elsewhere.q, elsewhere.qd)
    assert 2e-3 < np.abs(phi).max() < 4e-3 and np.abs(psi).max() > 1e-4
