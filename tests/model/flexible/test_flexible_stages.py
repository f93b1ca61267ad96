"""An integrator's stages of flexible models on the compiled path (compiled/certify.py): the
20-mode Craig–Bampton strip, whose M has a condition number of about 10⁶, and the flexible
slider-crank, a flexible rod between rigid bodies on tree joints, keep every stage in the
kernel, with the KKT path's drift-rule motion (equations.py: an SVD of the equilibrated
rows) to 1e-9; a run takes no stage to the exact path. So does the spin-up beam where its
stiffening term makes its mass indefinite (the kernel's bordered matrix, kernel._close)."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from benchmarks.flexible_startup import model_text
from mbsynth.compiled import extra_projection, staged
from mbsynth.compiled.projection import DONE

ROOT = Path(__file__).resolve().parents[3]
SLIDER_CRANK = ROOT / "models" / "flexible" / "slider_crank.yaml"
SPIN_UP = ROOT / "models" / "flexible" / "spin_up_beam.yaml"
INDEFINITE_FROM = 2.9  # s: the spin-up beam's bending from here makes its mass indefinite (the stiffening term)


@pytest.fixture(scope="module")
def models():
    """The strip: models/flexible/cantilever.yaml with 20 fixed-interface modes, the first struck."""
    return {"strip": mb.loads(model_text(20), name="strip_20"), "slider_crank": mb.load(SLIDER_CRANK)}


@pytest.mark.parametrize("name", ["strip", "slider_crank"])
def test_stages_off_the_manifold_are_the_kernels_with_the_drift_rules_motion(models, name):
    """States of a run moved 1e-9 (relative) off the manifold: the kernel serves each stage
    (Engine.motion with drift), and its q̈ is the KKT path's drift-rule motion to 1e-9 of
    the largest entry."""
    system = models[name]
    data = system.data()
    engine = data.engine
    assert engine is not None
    run = mb.simulate(system, 0.01, dt=0.005)
    rng = np.random.default_rng(7)
    for q0, qd0 in zip(run.q, run.qd):
        q = q0 + 1e-9 * max(np.abs(q0).max(), 1.0) * rng.standard_normal(q0.size)
        qd = qd0 + 1e-9 * max(np.abs(qd0).max(), 1.0) * rng.standard_normal(q0.size)
        compiled = engine.motion(0.0, q, qd, None, True)
        assert compiled is not None
        exact = data._kkt_motion(0.0, q, qd, "kkt", None, True)
        assert np.abs(compiled.qdd - exact.qdd).max() <= 1e-9 * np.abs(exact.qdd).max()


def test_the_extra_projections_rows_are_the_systems(models):
    """The rows the kernel's projection hands a run's singular watch (ExtraProjection.rows_at,
    from the generated function's entries) are the System's A (its own evaluator) at states
    of a run of the strip, to rounding."""
    system = models["strip"]
    data = system.data()
    projection = data.engine.projection()
    assert isinstance(projection, extra_projection.ExtraProjection)
    run = mb.simulate(system, 0.01, dt=0.005)
    for t, q, qd in zip(run.t, run.q, run.qd):
        A = data.constraint_arrays(t, q, qd, sparse=False).A
        assert np.abs(projection.rows_at(t, q, qd) - A).max() <= 1e-14 * np.abs(A).max()


@pytest.mark.parametrize("name", ["strip", "slider_crank"])
def test_a_run_takes_every_stage_on_the_compiled_path(models, name, monkeypatch):
    """0.05 s of the model: every step is taken in compiled code (staged.py: no stage
    declined), every state the extra coordinates' projection meets is put on the constraints
    there (extra_projection.py), and the exact path's solver is never called (a stage or
    motion the kernel declines goes there)."""
    system = models[name]
    steps, projected = [], []
    step, project = staged.Stages.step, extra_projection.project

    def stepped(self, solver):
        found = step(self, solver)
        steps.append(found[0] is not None)
        return found

    def projecting(times, Q, QD, found, *args):
        project(times, Q, QD, found, *args)
        projected.extend(found[:, DONE] == 1.0)

    def refused(*args, **kwargs):
        raise AssertionError("a stage went to the KKT path")
    monkeypatch.setattr(staged.Stages, "step", stepped)
    monkeypatch.setattr(extra_projection, "project", projecting)
    monkeypatch.setattr(system.data().__class__, "_kkt_motion", refused)
    run = mb.simulate(system, 0.05)
    assert run.status == "completed"
    assert steps and all(steps)
    assert all(projected)
    if isinstance(system.data().engine.projection(), extra_projection.ExtraProjection):
        assert projected


def test_the_spin_up_beams_indefinite_mass_stages_are_the_kernels_with_the_drift_rules_motion(monkeypatch):
    """The spin-up beam past INDEFINITE_FROM: its M (the stiffening term −ηᵀSη in the ω–ω
    block) has an eigenvalue below −1e-9 of its largest beyond the quaternion's null
    direction, so the kernel cannot eliminate the extra coordinates' accelerations through
    their mass. Its run to 3.2 s takes no stage to the exact path, and at states of the run
    moved 1e-9 (relative) off the manifold the kernel serves each stage (the bordered matrix,
    regular: the rows hold the torsion), its q̈ the KKT path's drift-rule motion to 1e-9 of
    the largest entry."""
    system = mb.load(SPIN_UP)
    data = system.data()
    engine = data.engine

    def refused(*args, **kwargs):
        raise AssertionError("a stage went to the KKT path")
    with monkeypatch.context() as patched:
        patched.setattr(data.__class__, "_kkt_motion", refused)
        run = mb.simulate(system, 3.2, dt=0.1)
    assert run.status == "completed"
    rng = np.random.default_rng(7)
    indefinite = 0
    for t, q0, qd0 in zip(run.t, run.q, run.qd):
        if t < INDEFINITE_FROM:
            continue
        q = q0 + 1e-9 * max(np.abs(q0).max(), 1.0) * rng.standard_normal(q0.size)
        qd = qd0 + 1e-9 * max(np.abs(qd0).max(), 1.0) * rng.standard_normal(q0.size)
        M = np.array(data.evaluate(t, q, qd).M)
        u = q[3:7] / np.linalg.norm(q[3:7])
        M[3:7, 3:7] += np.trace(M[3:7, 3:7]) * np.outer(u, u)  # the quaternion's null direction lifted
        values = np.linalg.eigvalsh(M)
        indefinite += values.min() < -1e-9 * values.max()
        compiled = engine.motion(t, q, qd, None, True)
        assert compiled is not None
        exact = data._kkt_motion(t, q, qd, "kkt", None, True)
        assert np.abs(compiled.qdd - exact.qdd).max() <= 1e-9 * np.abs(exact.qdd).max()
    assert indefinite >= 2
