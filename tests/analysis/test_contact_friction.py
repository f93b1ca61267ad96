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


def _along(traj, alpha):
    """The block's displacement down the slope and its distance off the plane, per row."""
    normal = np.array([np.sin(alpha), 0.0, np.cos(alpha)])
    return traj.q @ _down(alpha), traj.q @ normal


def test_block_slowing_on_a_slope_sticks_at_the_closed_form_time_and_stays():
    """tan α < μ with speed v0 down the slope: it decelerates at g(μ cos α − sin α), its slip
    stops at t* = v0/(g(μ cos α − sin α)) (an event on the dense output), and from there it
    sticks: the block stays where it stopped, s* = v0²/(2 g(μ cos α − sin α))."""
    alpha, mu, v0 = 0.3, 0.5, 1.0
    system = mb.load(MODEL, parameters={"alpha": alpha, "mu": mu, "v0": v0})
    traj = mb.simulate(system, 1.0, rtol=1e-12, atol=1e-12)
    a = G * (mu * np.cos(alpha) - np.sin(alpha))
    t_stop = v0 / a
    kinds = [(ev.kind, ev.t) for ev in traj.events]
    assert [k for k, _ in kinds] == ["contact", "slip", "stick"]
    assert abs(kinds[2][1] - t_stop) < 1e-10
    s, off = _along(traj, alpha)
    tc = np.minimum(traj.t, t_stop)
    assert np.abs(s - (v0 * tc - 0.5 * a * tc**2)).max() < 1e-10
    assert np.abs(off).max() < 1e-12


def test_block_at_rest_where_tan_alpha_is_below_mu_sticks_for_a_long_run_without_crawling():
    """tan α < μ from rest: the held contact sticks (its slip rows held, |λ_t| = m g sin α ≤
    μ m g cos α) and the block stays where it is, to the rounding of gravity's motion over the
    run (ε g T²: the slip rows hold its velocity, its position is their integral); the
    velocity rows at rest are judged against the run's motion, not their own rounding, so a
    long run takes few steps."""
    t_end = 1000.0
    system = mb.load(MODEL, parameters={"alpha": 0.3, "mu": 0.5})
    traj = mb.simulate(system, t_end, rtol=1e-10, atol=1e-10)
    assert [(ev.t, ev.kind) for ev in traj.events] == [(0.0, "contact"), (0.0, "stick")]
    assert np.abs(traj.q).max() < np.finfo(float).eps * G * t_end**2
    assert np.abs(traj.qd).max() < np.finfo(float).eps * G * t_end
    assert traj.stats["steps"] < 100


@pytest.mark.parametrize("k", [4.0, -4.0])
def test_ramping_push_breaks_a_sticking_block_free_where_the_friction_cone_is_reached(k):
    """A force k t along the slope (up for k > 0) on a block at rest that sticks: the tangential
    force sticking needs, |k t − m g sin α|, reaches μ m g cos α at t* = m g (μ cos α ± sin α)/|k|
    (an event by root finding on μ λ_n − |λ_t|); from there it slides, m s̈ = |k| (t − t*) along
    the push, s = |k| (t − t*)³/(6 m)."""
    alpha, mu, m = 0.3, 0.5, 2.0
    system = mb.load(MODEL, parameters={"alpha": alpha, "mu": mu, "k": k, "m": m})
    traj = mb.simulate(system, 12.0, rtol=1e-12, atol=1e-12)
    t_slip = m * G * (mu * np.cos(alpha) + np.sign(k) * np.sin(alpha)) / abs(k)
    assert [(ev.t, ev.kind) for ev in traj.events][:2] == [(0.0, "contact"), (0.0, "stick")]
    assert [ev.kind for ev in traj.events[2:]] == ["slip"]
    assert abs(traj.events[2].t - t_slip) < 1e-10
    s, off = _along(traj, alpha)
    after = np.maximum(traj.t - t_slip, 0.0)
    assert np.abs(s + np.sign(k) * abs(k) * after**3 / (6 * m)).max() < 1e-9
    assert np.abs(off).max() < 1e-12


def test_contacts_that_switch_between_stick_and_slip_without_end_stop_the_run_naming_them():
    """A box on three sticking corners, its centre over the diagonal of two (k2, k3), turned
    about that diagonal: as it tips, the two held contacts share a tangential load that their
    rows do not determine (their split chosen in their cones, cones.py); where they break
    away, their slide (its acceleration zero at the onset) turns back within the first step
    and their cones hold again, over and over at that instant: the run stops naming them
    (no hang). Which of the two stops comes first — the cap on events at one instant, or the
    integrator's step collapsing in the modes of the last switch — rests on the last bits of
    the slide's onset, which differ between BLAS builds (OPENBLAS_CORETYPE)."""
    system = mb.loads("""name: tipping_box
parameters: {m: 1.0, a: 0.1, g: 9.81, mu: 0.5, w: 3.0}
gravity: [0, 0, -g]
parts:
  box:
    type: rigid_body
    mass: m
    inertia: [m*a**2/6, m*a**2/6, m*a**2/6]
    frames:
      c1: {position: [a/2, a/2, -a/2]}
      c2: {position: [-a/2, a/2, -a/2]}
      c3: {position: [a/2, -a/2, -a/2]}
    initial: {position: [0, 0, a/2], velocity: [-w*a/sqrt(8), -w*a/sqrt(8), 0],
              angular_velocity: [w/sqrt(2), -w/sqrt(2), 0]}
contacts:
  - {name: k1, type: plane, child: box.c1, friction: mu}
  - {name: k2, type: plane, child: box.c2, friction: mu}
  - {name: k3, type: plane, child: box.c3, friction: mu}
""")
    with pytest.raises(mb.SimulationError) as err:
        mb.simulate(system, 1.0, rtol=1e-10, atol=1e-10)
    message, events = str(err.value), err.value.trajectory.events
    assert "k2, k3: 100 events at this instant: held contacts switch between stick and slip without end" in message \
        or "k2, k3: the run cannot go on with these contacts held in their friction modes" in message
    assert [(ev.name, ev.kind) for ev in events[:4]] == \
        [("k2", "contact"), ("k3", "contact"), ("k2", "stick"), ("k3", "stick")]
    last = [ev for ev in events if ev.t == events[-1].t]
    assert events[-1].t > 0 and len(last) >= 90  # switching without end at one instant
    assert {ev.name for ev in last} == {"k2", "k3"} and {ev.kind for ev in last} == {"stick", "slip"}
