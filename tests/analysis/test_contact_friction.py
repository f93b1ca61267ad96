"""Coulomb friction at a held contact (analysis/impacts.py: sliding as the non-ideal C
−μ λ_n Tᵀû, its slip's stop an event) against the closed forms of a block on a slope
(models/contact/block_on_slope.yaml): a = g(sin α − μ cos α) along the slope."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb

MODEL = Path(__file__).resolve().parents[2] / "models" / "contact" / "block_on_slope.yaml"
G = 9.81


def _down(alpha):
    return np.array([np.cos(alpha), 0.0, -np.sin(alpha)])  # the unit vector down the slope


@pytest.mark.parametrize("alpha, mu, v0", [(0.5, 0.3, 0.0), (0.5, 0.3, 0.7), (0.4, 0.0, 0.0)])
def test_block_slides_down_the_slope_at_the_closed_form_acceleration(alpha, mu, v0):
    """tan α > μ: from rest (or moving down) it slides, s = v0 t + ½ g(sin α − μ cos α) t²."""
    system = mb.load(MODEL, parameters={"alpha": alpha, "mu": mu, "v0": v0})
    traj = mb.simulate(system, 1.0, rtol=1e-12, atol=1e-12)
    assert [(ev.t, ev.kind) for ev in traj.events] == [(0.0, "contact")] + [(0.0, "slip")] * (mu > 0)
    a = G * (np.sin(alpha) - mu * np.cos(alpha))
    expected = np.outer(v0 * traj.t + 0.5 * a * traj.t**2, _down(alpha))
    assert np.abs(traj.q - expected).max() < 1e-10


def test_block_slowing_on_a_slope_stops_at_the_closed_form_time_where_it_would_stick():
    """tan α < μ with speed v0 down the slope: it decelerates at g(μ cos α − sin α) and its
    slip stops at t* = v0/(g(μ cos α − sin α)), found on the dense output; there it would
    stick, which the run refuses, naming the time and the contact."""
    alpha, mu, v0 = 0.3, 0.5, 1.0
    system = mb.load(MODEL, parameters={"alpha": alpha, "mu": mu, "v0": v0})
    with pytest.raises(mb.SimulationError) as err:
        mb.simulate(system, 1.0, rtol=1e-12, atol=1e-12)
    t_stop = v0 / (G * (mu * np.cos(alpha) - np.sin(alpha)))
    assert abs(err.value.time - t_stop) < 1e-10
    assert f"at t = {t_stop:.9g}, floor: a held contact with friction sticks here" in str(err.value)


def test_block_at_rest_where_tan_alpha_is_below_mu_is_refused_at_once():
    system = mb.load(MODEL, parameters={"alpha": 0.3, "mu": 0.5})
    with pytest.raises(mb.SimulationError, match="at t = 0, floor: a held contact with friction sticks here"):
        mb.simulate(system, 1.0)
