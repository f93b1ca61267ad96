"""Sticking contacts that share a load their rows do not determine (statically indeterminate
friction, analysis/cones.py): the group sticks while some split of the forces lies in every
exact Coulomb cone, against the closed forms of a box on four corners."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.analysis.cones import Cone, Shared
from mbsynth.model.reactions import indeterminate, multipliers

MODEL = Path(__file__).resolve().parents[2] / "models" / "contact" / "box_on_four_corners.yaml"
G = 9.81


def test_a_box_on_four_corners_below_tan_alpha_mu_stays_at_rest():
    """tan α < μ: the four (three held, the fourth touching) sticking corners share the load
    down the slope, m g sin α, which their rows leave free; the minimum-norm split puts one
    corner outside its cone, another split holds them all, so the box stays where it is."""
    system = mb.load(MODEL, parameters={"alpha": 0.3, "mu": 0.5})
    traj = mb.simulate(system, 20.0, rtol=1e-10, atol=1e-10)
    assert {ev.kind for ev in traj.events} == {"contact", "stick"}
    assert np.abs(traj.q - traj.q[0]).max() < 1e-10
    assert np.abs(traj.qd).max() < 1e-10


@pytest.mark.parametrize("moved", [1e-16, 3e-15, 1e-14])
def test_the_box_at_rest_stays_there_from_states_moved_by_rounding(moved):
    """The same box from its initial q moved by rounding: a run at rest has velocities of
    rounding (1e-24 to 1e-12), which neither lift a touching corner nor make its dependent
    rows (three corners' nine, on seven velocities) look unmet after the velocity step; the
    box stays where it is, its corners stuck."""
    system = mb.load(MODEL, parameters={"alpha": 0.3, "mu": 0.5})
    q0, qd0 = system.initial_state()
    traj = mb.simulate(system, 20.0, rtol=1e-10, atol=1e-10, q0=q0 + moved * np.cos(1.7 * np.arange(q0.size)), qd0=qd0)
    assert {ev.kind for ev in traj.events} == {"contact", "stick"}
    assert np.abs(traj.q - traj.q[0]).max() < 1e-10
    assert np.abs(traj.qd).max() < 1e-10


def test_a_box_on_four_corners_above_tan_alpha_mu_slides_down_as_a_whole():
    """tan α > μ: the group breaks away at t = 0 and slides without turning, its centre as
    a block's, x = ½ g (sin α − μ cos α) t²: the corners' friction adds up to μ m g cos α
    whatever the split of the normal forces. Its slips start along the load's push (from
    the minimum-norm forces they would turn the box)."""
    alpha, mu = 0.5, 0.3
    system = mb.load(MODEL, parameters={"alpha": alpha, "mu": mu})
    traj = mb.simulate(system, 1.0, rtol=1e-10, atol=1e-10)
    assert {ev.kind for ev in traj.events} == {"contact", "slip"}
    assert {ev.t for ev in traj.events} == {0.0}
    a = G * (np.sin(alpha) - mu * np.cos(alpha))
    assert np.abs(traj.q[:, 0] - 0.5 * a * traj.t**2).max() < 1e-9
    assert np.abs(traj.qd[:, 0] - a * traj.t).max() < 1e-9
    assert np.abs(traj.q[:, 1:3] - traj.q[0, 1:3]).max() < 1e-10
    assert np.abs(traj.q[:, 4:]).max() < 1e-10  # the quaternion's vector part: no turning


@pytest.mark.slow  # about a minute: the slide's first milliseconds take thousands of steps (docstring)
def test_a_pushed_box_sticks_up_to_mu_m_g_then_slides_as_a_block():
    """A push k t along x on level ground: the corners stick until k t = μ m g (s* reaches
    zero with no acceleration yet: the slide starts along the push), then the box moves as
    a block, x = k (t − t_b)³ / 6m. (Held at first on a diagonal pair, the least set, it
    tips onto a third corner as the push begins, in its first millisecond.) Within
    the first milliseconds of the slide the slip is slow and its direction stiff (a yaw
    perturbation's rate grows as μ g / |slip|): explicit steps crawl there, and the closed
    form holds to 1e-8 in x and ẋ."""
    m, mu, k = 2.0, 0.3, 100.0
    t_b = mu * m * G / k
    system = mb.load(MODEL, parameters={"alpha": 0.0, "mu": mu, "k": k})
    traj = mb.simulate(system, t_b + 0.14, rtol=1e-10, atol=1e-10)
    first_slip = min(ev.t for ev in traj.events if ev.kind == "slip" and ev.t > 0.1 * t_b)
    assert abs(first_slip - t_b) < 1e-9
    after = np.maximum(traj.t - t_b, 0.0)
    assert np.abs(traj.q[:, 0] - k * after**3 / (6 * m)).max() < 1e-8
    assert np.abs(traj.qd[:, 0] - k * after**2 / (2 * m)).max() < 1e-8
    assert np.abs(traj.q[:, 4:]).max() < 1e-10


def _table(push, mu, m=2.0, a=0.2, b=0.1, h=0.05):
    """Shared forces of a table (legs at (±a/2, ±b/2), centre of mass h above the floor)
    pushed along x at its centre of mass: its rows are each foot's normal and two tangents
    on the body's six motions (force; moment about the centre of mass)."""
    rows, cones = [], []
    for x, y in [(a / 2, b / 2), (-a / 2, b / 2), (a / 2, -b / 2), (-a / 2, -b / 2)]:
        r = np.array([x, y, -h])
        start = len(rows)
        rows += [np.concatenate([d, np.cross(r, d)]) for d in np.eye(3)[[2, 0, 1]]]
        cones.append(Cone(start, (start + 1, start + 2), mu))
    A = np.array(rows)
    load = np.array([push, 0.0, -m * G, 0.0, 0.0, 0.0])  # the floor's forces hold the push and the weight
    lam = multipliers(A, -load)[0]
    return Shared(lam, indeterminate(A), cones, [], m * G), A, load


def test_a_pushed_table_sticks_up_to_mu_m_g_and_its_friction_equals_the_push():
    """Breakaway at push = μ m g (the closed form, whatever the legs' split): s* < 0 below it
    (though the minimum-norm split already has the rear legs outside their cones), > 0 above;
    the split chosen holds the table (Aᵀλ = −load: total friction = −push, normals = m g)."""
    mu, m = 0.5, 2.0
    below, A, load = _table(0.99 * mu * m * G, mu)
    assert below.violation(below.lam) > 0  # the minimum-norm split breaks a leg
    s, lam = below.margin()
    assert s < 0
    assert below.violation(lam) <= 1e-9 * m * G
    assert np.abs(A.T @ lam + load).max() < 1e-9 * m * G
    assert abs(sum(lam[c.tangential[0]] for c in below.cones) + 0.99 * mu * m * G) < 1e-9 * m * G
    assert abs(sum(lam[c.normal] for c in below.cones) - m * G) < 1e-9 * m * G
    assert _table(1.01 * mu * m * G, mu)[0].margin()[0] > 0
    assert abs(_table(mu * m * G, mu)[0].margin()[0]) < 1e-8 * m * G

