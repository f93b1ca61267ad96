"""The rows a step passes, projected through a few exact projections (compiled/row_fit.py),
against the exact projection of each row and the System's own (sympy) residuals; the
kernel's reusing call at rest on loop rows against a full call; the rows of a dense output
grid against those of a sparse one."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.compiled import kernel, row_fit
from mbsynth.compiled.engine import EMPTY, NO_BODIES

ROOT = Path(__file__).resolve().parents[2]
BRICARD = ROOT / "models" / "mechanisms" / "bricard.yaml"
LOOPS = ["bricard.yaml", "bennett.yaml", "sarrus.yaml", "four_bar_3d.yaml"]


@pytest.fixture(autouse=True)
def compiled_path(monkeypatch):
    monkeypatch.setenv("MBSYNTH_COMPILED", "wait")


@pytest.fixture(scope="module")
def bricard():
    return mb.load(BRICARD)


def drifted_rows(system, span, count, seed):
    """``count`` states of a run over ``span`` s (on the constraints) at their fractions θ of
    the span, pushed off the constraints by a smooth drift of 1e-9 that vanishes with its
    slope at θ = 0, as an integrator's interpolant drifts from a projected step start (its
    slope there is the motion, which meets the rows' derivatives: row_fit.py)."""
    traj = mb.simulate(system, 0.2 + span, dt=span / count)
    Q, QD = traj.q[-count:], traj.qd[-count:]
    fractions = (traj.t[-count:] - traj.t[-count - 1]) / span
    rng = np.random.default_rng(seed)
    shape = [rng.standard_normal(Q.shape[1]) for _ in range(4)]
    drift = lambda c: 1e-9 * (fractions[:, None] ** 2 * c[0] + (1 - np.cos(3 * fractions))[:, None] * c[1])
    return Q + drift(shape[:2]), QD + drift(shape[2:]), fractions


def counting(projection):
    """The projection with its exact projections counted (``count[0]``: states)."""
    count, exact = [0], projection._exact

    def counted(Q, QD):
        count[0] += Q.shape[0]
        return exact(Q, QD)
    projection._exact = counted
    return count


@pytest.mark.parametrize("span", [0.1, 2.0], ids=["a step", "a long span, halved"])
def test_fitted_rows_are_the_exact_projections_and_meet_the_systems_constraints(bricard, span):
    """Each row projected through the fit is where the exact projection of that row puts
    it (to 1e-12 of the coordinates), its residuals by the System's sympy rows within the
    exact projection's bounds; far fewer rows are projected exactly. Over a long span the
    fit through NODES rows fails and the span is halved until it holds."""
    Q, QD, fractions = drifted_rows(bricard, span, 120, seed=1)
    projection = bricard.data().engine.projection()
    exact = projection.block(np.zeros(len(Q)), Q, QD)
    count = counting(projection)
    fitted = projection.block(np.zeros(len(Q)), Q, QD, fractions)
    assert fitted.done.all() and exact.done.all()
    assert count[0] < (len(Q) if span > 1 else 2 * row_fit.NODES)
    np.testing.assert_allclose(fitted.q, exact.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fitted.qd, exact.qd, rtol=0, atol=1e-12 * np.abs(QD).max())
    for q, qd, found in zip(fitted.q, fitted.qd, fitted.found):
        phi, psi = bricard.constraint_residuals(0.0, q, qd)
        assert np.abs(phi).max() <= 2e-14 * max(np.abs(q).max(), 1.0)
        assert np.abs(psi).max() <= 2e-12 * max(np.abs(q).max(), 1.0) * np.abs(qd).max()
        np.testing.assert_allclose(found[:2], bricard.energy(0.0, q, qd), rtol=1e-12, atol=1e-12)


def test_a_row_the_fit_misses_is_projected_exactly(bricard):
    """A row pushed off the smooth drift (1e-7, a kink the interpolant cannot follow) fails
    its judgement and is projected on its own: it ends where its exact projection puts it."""
    Q, QD, fractions = drifted_rows(bricard, 0.1, 120, seed=2)
    Q[50] += 1e-7
    projection = bricard.data().engine.projection()
    times = np.zeros(len(Q))
    fitted, exact = projection.block(times, Q, QD, fractions), projection.block(times, Q, QD)
    np.testing.assert_array_equal(fitted.q[50], exact.q[50])
    np.testing.assert_allclose(fitted.q, exact.q, rtol=0, atol=1e-12)


def test_a_dense_output_grid_leaves_the_motion_as_a_sparse_one(bricard):
    """The steps do not depend on the output times: the rows of a run every 1 ms at the
    times of a run every 0.5 s are those rows (to the fit's 1e-12), and the rows every 1 ms
    meet the constraints; a file written as the run goes holds every row."""
    sparse = mb.simulate(bricard, 2.0, dt=0.5)
    dense = mb.simulate(bricard, 2.0, dt=1e-3)
    assert dense.stats["steps"] == sparse.stats["steps"]
    common = np.searchsorted(dense.t, sparse.t)
    np.testing.assert_allclose(dense.t[common], sparse.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(dense.q[common], sparse.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(dense.qd[common], sparse.qd, rtol=0, atol=1e-11)
    size, rates = max(np.abs(dense.q).max(), 1.0), np.abs(dense.qd).max()
    assert dense.residual_position.max() <= 1e-14 * size and dense.residual_velocity.max() <= 1e-12 * size * rates
    energy = np.array([sum(bricard.energy(t, q, qd)) for t, q, qd in zip(dense.t[::97], dense.q[::97], dense.qd[::97])])
    np.testing.assert_allclose(dense.energy[::97], energy, rtol=0, atol=1e-12 * np.abs(energy).max())


@pytest.mark.implementation
def test_each_step_of_a_run_projects_nodes_rows_exactly(bricard, monkeypatch):
    """The integrator's own drift starts as θ² at each step's start, slope included
    (row_fit.py): on a real run no row fails the fit through NODES exact projections, so
    each step projects NODES rows exactly, no more (without the slope condition some fail)."""
    from mbsynth.compiled import projection
    exact, count = projection.Projection._exact, [0]

    def counted(self, Q, QD):
        count[0] += Q.shape[0]
        return exact(self, Q, QD)
    monkeypatch.setattr(projection.Projection, "_exact", counted)
    dense = mb.simulate(bricard, 2.0, dt=1e-3)
    assert count[0] <= row_fit.NODES * dense.stats["steps"] + 2  # the start's and the end's own projections


def test_a_dense_grid_reports_every_row_to_progress_and_the_file(bricard, tmp_path):
    """Rows recorded at once still reach ``progress`` one by one and the file as the run goes."""
    seen = []
    traj = mb.simulate(bricard, 0.5, dt=1e-3, out=tmp_path / "bricard.npz", progress=seen.append)
    np.testing.assert_array_equal(seen, traj.t[1:])
    saved = np.load(tmp_path / "bricard.npz")
    np.testing.assert_array_equal(saved["t"], traj.t)
    np.testing.assert_array_equal(saved["q"], traj.q)
    mb.simulate(bricard, 0.5, dt=1e-3, out=tmp_path / "bricard.csv")
    lines = (tmp_path / "bricard.csv").read_text().splitlines()
    assert sum(line[:1].isdigit() for line in lines) == len(traj.t)


@pytest.mark.parametrize("model", LOOPS)
def test_a_reusing_call_at_rest_solves_loop_rows_as_a_full_call(model):
    """kernel.motion's REUSED at rest with shifts on the joint rows of a model with loop
    rows (a projection's velocity step) solves the Schur system with the last call's
    eigendecomposition: its q̈ equals a full call's at the same state and shifts, and meets
    the System's sympy rows (A q̈ = shift, a shift in range(A): the loops' rows are
    dependent in Bricard's and Bennett's mechanisms)."""
    system = mb.load(ROOT / "models" / "mechanisms" / model)
    traj = mb.simulate(system, 0.05, dt=0.05)
    q = traj.q[-1]
    rest = system.data().engine.at_rest()
    gen, qd = np.zeros(rest.outputs), np.zeros(q.size)
    A = np.asarray(system.evaluate(0.0, q, qd).A)
    rng = np.random.default_rng(9)
    direction = rng.standard_normal(q.size)
    for row in (r for r in rest.L.quat_row if r >= 0):  # no move along a quaternion: its unit-norm row unshifted
        columns = np.flatnonzero(A[row])
        direction[columns] -= (A[row, columns] @ direction[columns]) / (A[row, columns] @ A[row, columns]) * A[row, columns]
    shift = A @ direction
    shift[[r for r in rest.L.quat_row if r >= 0]] = 0.0

    def call(right, mode):
        status = kernel.motion_rates(q, qd, gen, right, *rest.buffers, mode, 1e-12, rest.general, NO_BODIES, EMPTY)[0]
        assert status == kernel.OK
        return rest.W.qdd.copy()

    call(A @ rng.standard_normal(q.size), kernel.UNCHECKED)  # factors at q, for another right side
    reused = call(shift, kernel.REUSED)
    full = call(shift, kernel.UNCHECKED)
    np.testing.assert_allclose(reused, full, rtol=0, atol=1e-12 * np.abs(full).max())
    np.testing.assert_allclose(A @ reused, shift, rtol=0, atol=1e-10 * np.abs(shift).max())
