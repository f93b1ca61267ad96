"""The run loop's stages in compiled code (mbsynth.compiled.staged) against independent
results: ẏ at a stage against (2.14) on the KKT path, a whole DOP853 step against the
solver's Python step on the same right-hand side (analysis/dop853.py: scipy's ``_step_impl``
bit for bit, tests/analysis/test_dop853.py; its trials, error norm and next step size), and a
stage the kernel declines left to the Python path with the integrator untouched."""

import copy

import numpy as np
import pytest
from scipy.integrate._ivp import rk

import mbsynth as mb
from mbsynth.analysis.dop853 import DOP853
from mbsynth.analysis.velocity_form import VelocityForm
from mbsynth.compiled import engine_for, staged
from tests.helpers.compare import rel
from tests.model.flexible.test_flexible_pendulum import pendulum_yaml

@pytest.fixture(scope="module", params=["ur5", "flexible pendulum"])
def model(request):
    """A rigid tree of quaternion bodies (its integrator form turns their rates into angular
    velocities) and a flexible part on a revolute joint (extra coordinates, rows outside
    the tree: the stage's drift is measured)."""
    system = mb.from_robot("ur5") if request.param == "ur5" else mb.loads(pendulum_yaml(4))
    engine = engine_for(system)
    form = VelocityForm(system)
    q, qd = system.initial_state()
    qd = qd + 0.3 * np.sin(np.arange(qd.size))  # moving; the quaternions' rates along u drop out of y
    y = form.to_integrator(q, qd)
    return system, engine.stages(form.starts), form, y


def test_a_stage_is_the_motion_of_2_14(model):
    """ẏ = (q̇, v̇) at the stage, v̇ from q̈ of (2.14) on the KKT path (velocity_form.rates)."""
    system, stages, form, y = model
    q, qd = form.to_state(y)
    found = stages.rates(0.4, y)
    qdd = system.motion(0.4, q, qd, method="reference").qdd
    expected = form.rates(y, np.concatenate([qd, qdd]))
    assert found.shape == (form.size,)
    assert np.array_equal(found[:system.n], qd)
    assert rel(found, expected) < 1e-9


def test_a_step_is_scipys(model):
    """Eight DOP853 steps taken by ``Stages.step`` and by the solver's Python step from the same
    solver state on the same right-hand side: the same outcome, t, y, ẏ and next step size
    to rounding, rejected trials and their shorter retries among them. The error estimate is
    a sum of the stages that cancels to about rtol of them, so the rounding of its two
    summation orders (a loop here, BLAS there) moves a retried step's size by about 1e-11 of
    itself, and the state with it."""
    system, stages, form, y = model
    solver = DOP853(lambda t, y: stages.rates(t, y), 0.0, y, 1.0, rtol=1e-7, atol=1e-7)
    rejected = 0
    for _ in range(8):
        mine, theirs = copy.deepcopy(solver), copy.deepcopy(solver)
        taken, evaluations = stages.step(mine)
        assert taken == theirs._step_impl() == (True, None)
        rejected += evaluations > 12
        assert evaluations % 12 == 0
        assert mine.t == pytest.approx(theirs.t, rel=1e-10)
        assert rel(mine.y, theirs.y) < 1e-10 and rel(mine.f, theirs.f) < 1e-8
        assert mine.h_abs == pytest.approx(theirs.h_abs, rel=1e-7)
        assert mine.h_previous == pytest.approx(theirs.h_previous, rel=1e-10) and np.array_equal(mine.y_old, solver.y)
        solver.step()
    assert rejected >= 1
    assert (staged.SAFETY, staged.MIN_FACTOR, staged.MAX_FACTOR) == (rk.SAFETY, rk.MIN_FACTOR, rk.MAX_FACTOR)


def test_a_step_below_the_smallest_fails_as_scipys(model):
    """A step size capped below ten units of t's rounding: the Python step's failure and message
    (scipy's)."""
    system, stages, form, y = model
    solver = DOP853(lambda t, y: stages.rates(t, y), 1.0, y, 2.0, rtol=1e-7, atol=1e-7)
    solver.max_step = 1e-300
    taken, evaluations = stages.step(solver)
    assert taken == copy.deepcopy(solver)._step_impl() and taken[0] is False
    assert evaluations == 0 and solver.t == 1.0


def test_a_declined_stage_leaves_the_step_to_the_python_path(model):
    """A state the kernel declines (not finite): ``rates`` gives None, and ``step`` returns
    None with the solver's state as it was, for the Python path to take the step."""
    system, stages, form, y = model
    assert stages.rates(0.0, np.full_like(y, np.nan)) is None
    solver = DOP853(lambda t, y: stages.rates(t, y), 0.0, y, 1.0, rtol=1e-7, atol=1e-7)
    solver.f = np.full_like(solver.f, np.nan)  # the first stage moves the state by NaN
    before = (solver.t, solver.y, solver.h_abs)
    taken, evaluations = stages.step(solver)
    assert taken is None and evaluations == 1
    assert (solver.t, solver.y, solver.h_abs) == before


def test_a_run_takes_every_step_compiled(monkeypatch):
    """UR5 falling 0.5 s: every step of the run is taken by ``Stages.step`` (none falls back),
    and the run ends where the same run on the Python path ends, to its tolerance."""
    system = mb.from_robot("ur5")
    outcomes = []
    original = staged.Stages.step

    def counted(self, solver):
        taken, evaluations = original(self, solver)
        outcomes.append(taken)
        return taken, evaluations

    monkeypatch.setattr(staged.Stages, "step", counted)
    compiled = mb.simulate(system, 0.5, rtol=1e-10, atol=1e-10)
    assert outcomes and all(taken == (True, None) for taken in outcomes)
    assert len(outcomes) == compiled.stats["steps"]
    monkeypatch.setattr(staged.Stages, "step", lambda self, solver: (None, 0))
    python = mb.simulate(system, 0.5, rtol=1e-10, atol=1e-10)
    assert np.abs(compiled.q[-1] - python.q[-1]).max() < 1e-8
