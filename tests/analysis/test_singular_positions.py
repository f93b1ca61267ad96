"""Motion through singular positions: where the constraint rows become dependent
for an instant (a parallelogram's change points, where the degrees of freedom jump from 1
to 2) the motion keeps its velocity and its branch; where they stay independent (a
slider-crank's dead centres) the motion passes with its energy. References: closed forms and
conservation laws, no mbsynth."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbsynth as mb
from mbsynth.analysis import cut, derivative
from mbsynth.analysis.singular_watch import SingularWatch
from mbsynth.core.memo import MEMO
from mbsynth.core.tolerances import INTEGRATION_RTOL, RELAXED_RTOL

ROOT = Path(__file__).resolve().parents[2]
from benchmarks import iftomm_reference as ref
from benchmarks.flexible_startup import model_text


def test_a_cached_scaled_four_bar_changes_no_later_run():
    """A cached value changes how fast an answer comes, never the answer (core/memo.py): the
    parallelogram run after a kilometre-scale four-bar run (the same structure, whose Engine
    it gets at its own parameter values, projection included) gives the end state it gives
    from an empty cache."""
    def parallelogram():
        traj = mb.simulate(mb.loads(ref.n_four_bar_yaml(1, g=0.0), name="parallelogram"), 10.0)
        return traj.q[-1], len(traj.stats["relaxed_spans"])
    MEMO.clear()
    scale = math.sqrt(1e3)
    mb.simulate(mb.loads(ref.n_four_bar_yaml(1, L=1e3, m=1e-3, v0=scale), name="n_four_bar_1"), 1.5 * scale)
    after = parallelogram()
    MEMO.clear()
    alone = parallelogram()
    assert after[0].tobytes() == alone[0].tobytes() and after[1] == alone[1]


def test_a_parallelogram_turns_through_its_change_points_at_constant_rate():
    """Two 1 m cranks 1 m apart joined by a 1 m coupler, no gravity, the cranks turning at
    1 rad/s: on the parallelogram branch the coupler only translates, so the kinetic
    energy is J θ̇²/2 with a constant J and θ = θ₀ − t exactly. Every half turn the bars
    are collinear (rank A drops by one, the anti-parallelogram branch meets this one); the
    motion must stay on its branch: 10 s cross the change points three times (at t = π/2,
    3π/2, 5π/2), at the requested tolerance (no span relaxed), and the run lists each of
    them at its time, though no stage need come near one (analysis/singular_watch.py)."""
    system = mb.loads(ref.n_four_bar_yaml(1, g=0.0), name="parallelogram")
    traj = mb.simulate(system, 10.0)
    assert traj.status == "completed" and not traj.stats["relaxed_spans"]
    listed = traj.stats["singular_positions"]
    assert len(listed) == 3
    for entry, t in zip(listed, [math.pi / 2, 3 * math.pi / 2, 5 * math.pi / 2]):
        assert entry["t_from"] - 1e-8 <= t <= entry["t_to"] + 1e-8, (entry, t)
    theta = np.unwrap(traj.column("v0.theta"))
    turned = theta - (theta[0] - traj.t)
    assert np.abs(turned).max() < 1e-6
    coupler = traj.column("h0.theta")
    assert np.abs(coupler - coupler[0]).max() < 1e-6  # the coupler only translates
    assert np.abs(traj.column("v1.theta") - traj.column("v0.theta")).max() < 1e-6


def test_a_slider_crank_swings_through_its_dead_centres():
    """Released from rest at 1 rad under gravity, the crank swings through the positions
    where crank and rod are collinear (the dead centres: the slider's speed is zero there
    whatever the crank's); energy is conserved to 1e-8 across them. The rows stay independent
    there, so no singular position is listed (the run watches for them between its steps:
    analysis/singular_watch.py)."""
    system = mb.load(ROOT / "models" / "mechanisms" / "slider_crank.yaml")
    traj = mb.simulate(system, 5.0)
    assert traj.status == "completed" and traj.stats["singular_positions"] == []
    theta_crank, theta_rod = traj.column("crank.theta"), traj.column("rod.theta")
    collinear = np.sin(theta_rod - theta_crank)  # the cross product of the crank's and the rod's directions
    assert np.count_nonzero(np.diff(np.sign(collinear))) >= 2
    assert traj.energy_drift < 1e-8


def crossing(gap, rate, t_end=0.01):
    """The N = 2 bars started ``gap`` rad before their horizontal position turning at
    ``rate``, simulated for t_end at the default tolerance: (trajectory, the largest error of
    v0's angle from the exact one-degree-of-freedom motion J ψ̈ = K sin ψ)."""
    N, psi0 = 2, math.pi / 2 - gap
    system = mb.loads(ref.n_four_bar_yaml(N), name="n_four_bar_2")
    q0, qd0 = ref.n_four_bar_state(system.coordinates, N, psi0, rate)
    traj = mb.simulate(system, t_end, q0=q0, qd0=qd0, dt=t_end / 2)
    J, K = ref.n_four_bar_constants(N)
    exact = solve_ivp(lambda t, y: (y[1], K / J * math.sin(y[0])), (0.0, t_end), (psi0, rate), method="DOP853",
                      rtol=1e-13, atol=1e-13, t_eval=traj.t).y[0]
    return traj, np.abs(-traj.column("v0.theta") - exact).max()


def test_a_crossing_of_a_singular_position_keeps_the_requested_tolerance():
    """Started 1e-4 rad before the horizontal position at 3 rad/s, the N = 2 bars cross it
    at the default rtol 1e-10 in a few dozen evaluations, on the exact motion to 1e-12 and
    with no span relaxed: near it the drift rule's motion of planar bodies (a diagonal M)
    is the KKT solution on the kept rows' row space (equations._definite_solution), whose
    accuracy does not degrade as σ falls."""
    traj, error = crossing(1e-4, 3.0)
    assert traj.status == "completed" and not traj.stats["relaxed_spans"]
    assert traj.stats["evaluations"] < 100
    assert error < 1e-12
    assert traj.max_residual < 1e-10


def test_a_span_that_crawls_near_a_singular_position_is_integrated_again_at_a_looser_tolerance(monkeypatch):
    """Near a singular position the stages' accelerations carry noise of about |q̇| ψ / σ²
    (ψ the velocity drift, σ → 0 the smallest singular value of A), which DOP853 at the
    default rtol = 1e-10 chases with ever smaller steps. Started 1e-3 rad before the
    horizontal position at 0.3 rad/s (a slow crossing, long in the zone where σ is small),
    the first 5 ms crawl: that span is integrated again at RELAXED_RTOL and listed in
    stats["relaxed_spans"], and the bars still follow the exact motion (to 1e-9: the
    relaxed tolerance). The compiled kernels waited for (MBSYNTH_COMPILED=wait): the crawl is
    the kernel-projected run's (its first step, which has no measure behind it to plan
    from); the KKT path's least-squares stages pass this crossing without one."""
    monkeypatch.setenv("MBSYNTH_COMPILED", "wait")
    traj, error = crossing(1e-3, 0.3)
    assert traj.status == "completed"
    relaxed = traj.stats["relaxed_spans"]
    assert [(span["t_from"], span["rtol"]) for span in relaxed] == [(0.0, RELAXED_RTOL)]
    assert traj.stats["evaluations"] < 2000
    assert error < 1e-9
    assert traj.max_residual < 1e-10


def test_a_span_that_crawls_still_at_the_loosest_tolerance_stops_naming_the_rows(monkeypatch):
    """The crawl above with the loosest tolerance lowered to the run's own (no loosening
    exists: relaxed once, the crossing passes, the kernel leaving its ill-conditioned stages
    to the exact drift rule) and the count it may crawl there (STUCK_CALLS) to 50: the run
    stops within the bound with a SimulationError naming the nearly dependent rows, the
    rows before it kept (no loop without progress)."""
    monkeypatch.setenv("MBSYNTH_COMPILED", "wait")
    monkeypatch.setattr(cut, "RELAXED_MAX", INTEGRATION_RTOL)
    monkeypatch.setattr(derivative, "STUCK_CALLS", 50)
    with pytest.raises(mb.SimulationError) as err:
        crossing(1e-3, 0.3)
    assert "the steps crawl near a singular position of the constraints (50 evaluations of this interval at the " \
           "loosest tolerance; nearly dependent rows ground0[x]" in str(err.value)
    assert err.value.trajectory.t.tolist() == [0.0] and "ground0[x]" in err.value.constraints


def test_crossings_at_a_tight_tolerance_are_stepped_across_on_the_exact_motion(monkeypatch):
    """N = 2 for 4 s through its first four singular positions at rtol = atol = 1e-12: a
    tolerance at which stages near a crossing see the drift of rounding amplified (ε/σ³) and
    the integrator crawled. The run plans one step across each (crossing.py: its stages at
    least 0.13 of the step from it, put on the constraints first): no span relaxed, and B0
    within 1e-11 m of the exact one-degree-of-freedom motion, its energy kept to 1e-10 J. The
    kernel's projection puts the stages on the constraints: its kernels waited for."""
    monkeypatch.setenv("MBSYNTH_COMPILED", "wait")
    system = mb.loads(ref.n_four_bar_yaml(2), name="n_four_bar_2")
    traj = mb.simulate(system, 4.0, dt=0.1, rtol=1e-12, atol=1e-12)
    assert traj.status == "completed" and not traj.stats["relaxed_spans"]
    assert len(ref.n_four_bar_singular_times(2, 4.0)) == 4
    theta = traj.column("v0.theta")
    bx, by = traj.column("v0.x") - 0.5 * np.sin(theta), traj.column("v0.y") + 0.5 * np.cos(theta)
    xr, yr = ref.n_four_bar_reference(traj.t, 2)
    assert np.hypot(bx - xr, by - yr).max() < 1e-11
    assert np.abs(traj.energy - traj.energy[0]).max() < 1e-10


def test_short_output_intervals_pass_the_crossings_without_a_crawl():
    """N = 2 at 1 ms outputs through its first two singular positions (t = 0.714, 1.228 s).
    Near the second, the rows whose velocity terms vanish with the bars flat made the
    relative drift read up to a thousand times its size; the spans between projections
    shrank to 5e-10 s and stayed there (tolerances.DRIFT_FLOOR). B0 follows the exact
    one-degree-of-freedom motion (benchmarks/iftomm_reference.py)."""
    crossings = ref.n_four_bar_singular_times(2, 1.3)
    traj = mb.simulate(mb.loads(ref.n_four_bar_yaml(2), name="n_four_bar_2"), 1.3, dt=0.001)
    assert traj.status == "completed" and len(traj.stats["singular_positions"]) == len(crossings) == 2
    for entry, t in zip(traj.stats["singular_positions"], crossings):
        assert entry["t_from"] - 1e-5 <= t <= entry["t_to"] + 1e-5, (entry, t)
    theta = traj.column("v0.theta")
    bx, by = traj.column("v0.x") - 0.5 * np.sin(theta), traj.column("v0.y") + 0.5 * np.cos(theta)
    xr, yr = ref.n_four_bar_reference(traj.t, 2)
    assert np.hypot(bx - xr, by - yr).max() < 1e-5
    assert traj.max_residual < 1e-10


def test_rows_that_do_not_change_start_no_search(monkeypatch):
    """The clamped strip (models/flexible/cantilever.yaml with 20 modes: its rows, the clamp
    and the unit norm, the same at every state) gives ratios σ_r/σ₁ equal but for the SVD's
    rounding: no end is a dip, and the run searches for none (each search costs 120 SVDs)."""
    searches = []
    original = SingularWatch._bottom

    def counted(self):
        searches.append(self.ends[1][0])
        return original(self)
    monkeypatch.setattr(SingularWatch, "_bottom", counted)
    run = mb.simulate(mb.loads(model_text(20), name="strip_20"), 0.1)
    assert run.status == "completed" and len(run.t) > 100
    assert searches == []
