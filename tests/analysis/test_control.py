"""Sampled control (mbsynth.analysis.control) against the exact zero-order-hold solution,
and what a run keeps when its controller fails."""

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.analysis.trajectory import load_trajectory

PUSHED = """
name: pushed
parameters: {m: 2.0, u: 0.0}
parts:
  p: {type: lagrangian, coordinates: [x], T: 0.5*m*x_dot**2, V: -u*x}
initial: {p.x: 0.1, p.x_dot: -0.2}
"""


def held(law, h, count, m=2.0, x=0.1, v=-0.2):
    """x, v after each sample of a force u_k = law(t_k) held for h on a mass m: exactly
    x + h v + h² u / 2m, v + h u / m."""
    rows = [(x, v)]
    for k in range(count):
        u = law(k * h)
        x, v = x + h * v + h * h * u / (2 * m), v + h * u / m
        rows.append((x, v))
    return np.array(rows)


def test_a_held_force_moves_the_mass_as_the_exact_zero_order_hold():
    """u(t) = cos 3t sampled every 0.05 s and held: the run's states at the samples equal
    the exact piecewise-quadratic motion (no two samples alike, so a value applied late
    or early by one sample would be off by about 1e-3)."""
    system = mb.loads(PUSHED, "pushed")
    law = lambda t: np.cos(3 * t)  # noqa: E731
    traj = mb.simulate(system, 1.0, dt=0.05, controller=lambda t, values: {"u": law(t)}, control_dt=0.05)
    exact = held(law, 0.05, 20)
    assert np.abs(traj.q[:, 0] - exact[:, 0]).max() < 1e-12
    assert np.abs(traj.qd[:, 0] - exact[:, 1]).max() < 1e-12


@pytest.mark.parametrize("control_dt", [0, -0.1, float("nan")])
def test_a_control_interval_that_is_not_positive_is_refused(control_dt):
    system = mb.loads(PUSHED, "pushed")
    with pytest.raises(ValueError, match="control_dt must be positive"):
        mb.simulate(system, 1.0, controller=lambda t, values: {}, control_dt=control_dt)


@pytest.mark.parametrize("suffix", [".npz", ".csv"])
def test_a_controller_that_raises_mid_run_stops_it_with_the_rows_before(tmp_path, suffix):
    """The law raises at t = 0.5: a ControlError naming the time and the law's error (chained),
    holding the rows up to 0.45 (equal to the exact motion), and the file has them too."""
    system = mb.loads(PUSHED, "pushed")

    def law(t, values):
        if t >= 0.5 - 1e-12:
            raise ZeroDivisionError("gain schedule ran out")
        return {"u": 1.0}

    out = tmp_path / f"run{suffix}"
    with pytest.raises(mb.ControlError, match=r"t = 0\.5 raised ZeroDivisionError: gain schedule ran out") as caught:
        mb.simulate(system, 1.0, dt=0.05, controller=law, control_dt=0.05, out=out)
    error = caught.value
    assert isinstance(error.__cause__, ZeroDivisionError) and error.time == pytest.approx(0.5)
    kept = error.trajectory
    assert kept.t[-1] == pytest.approx(0.5) and len(kept.t) == 11 and kept.status.startswith("failed at t = 0.5")
    np.testing.assert_allclose(kept.q[:, 0], held(lambda t: 1.0, 0.05, 10)[:, 0], rtol=0, atol=1e-12)
    saved = load_trajectory(out if suffix == ".npz" else tmp_path / f"run{suffix}.partial")
    assert np.array_equal(saved.t, kept.t) and np.array_equal(saved.q, kept.q)


@pytest.mark.parametrize("value, message", [(float("nan"), "non-finite")])
def test_a_controller_value_the_model_cannot_take_stops_the_run_with_the_rows_before(value, message):
    system = mb.loads(PUSHED, "pushed")
    law = lambda t, values: {"u": 1.0 if t < 0.25 else value}  # noqa: E731
    with pytest.raises(mb.ControlError, match=message) as caught:
        mb.simulate(system, 1.0, dt=0.05, controller=law, control_dt=0.05)
    assert caught.value.time == pytest.approx(0.25) and len(caught.value.trajectory.t) == 6
    assert isinstance(caught.value, mb.ModelError)  # bad input: the command line's exit 2
