"""Motion through singular positions (issue 18): where the constraint rows become dependent
for an instant (a parallelogram's change points, where the degrees of freedom jump from 1
to 2) the motion keeps its velocity and its branch; where they stay independent (a
slider-crank's dead centres) the motion passes with its energy. References: closed forms and
conservation laws, no mbsynth."""

import sys
from pathlib import Path

import numpy as np

import mbsynth as mb

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
import iftomm_reference as ref  # noqa: E402


def test_a_parallelogram_turns_through_its_change_points_at_constant_rate():
    """Two 1 m cranks 1 m apart joined by a 1 m coupler, no gravity, the cranks turning at
    1 rad/s: on the parallelogram branch the coupler only translates, so the kinetic
    energy is J θ̇²/2 with a constant J and θ = θ₀ − t exactly. Every half turn the bars
    are collinear (rank A drops by one, the anti-parallelogram branch meets this one); the
    motion must stay on its branch: 10 s cross the change points three times (at t = π/2,
    3π/2, 5π/2)."""
    system = mb.loads(ref.n_four_bar_yaml(1, g=0.0), name="parallelogram")
    traj = mb.simulate(system, 10.0)
    assert traj.status == "completed"
    assert traj.stats["singular_positions"]  # at least one crossing came near enough to be listed
    theta = np.unwrap(traj.column("v0.theta"))
    turned = theta - (theta[0] - traj.t)
    assert np.abs(turned).max() < 1e-6
    coupler = traj.column("h0.theta")
    assert np.abs(coupler - coupler[0]).max() < 1e-6  # the coupler only translates
    assert np.abs(traj.column("v1.theta") - traj.column("v0.theta")).max() < 1e-6


def test_a_slider_crank_swings_through_its_dead_centres():
    """Released from rest at 1 rad under gravity, the crank swings through the positions
    where crank and rod are collinear (the dead centres: the slider's speed is zero there
    whatever the crank's); energy is conserved to 1e-8 across them."""
    system = mb.load(ROOT / "models" / "mechanisms" / "slider_crank.yaml")
    traj = mb.simulate(system, 5.0)
    assert traj.status == "completed"
    theta_crank, theta_rod = traj.column("crank.theta"), traj.column("rod.theta")
    collinear = np.sin(theta_rod - theta_crank)  # the cross product of the crank's and the rod's directions
    assert np.count_nonzero(np.diff(np.sign(collinear))) >= 2
    assert traj.energy_drift < 1e-8
