"""Impacts, joint limits and contacts (analysis/impacts.py, analysis/impulse.py) against
independent closed forms: a ball bouncing to rest, a pendulum striking a stop (its exact
motion by elliptic integrals), Newton's cradle, and impacts of bodies with a singular M (a
massless link, a quaternion body) against the classical impulse equations worked by hand."""

from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipk, ellipkinc

import mbsynth as mb
from mbsynth.analysis.impulse import velocity_jump
from mbsynth.analysis.trajectory import load_trajectory
from mbsynth.core.errors import SolveError
from mbsynth.core.tolerances import INTEGRATION_ATOL, REST_HOP

MODELS = Path(__file__).resolve().parents[2] / "models" / "contact"


def _ball_closed_form(h0, r, g, e, count):
    """The times of the first ``count`` impacts of a ball dropped from rest (centre at h0)
    and the apex heights of its centre after each, with the accumulation time."""
    t1 = np.sqrt(2 * (h0 - r) / g)
    v = g * t1 * e ** np.arange(count)  # the speed at each impact
    times = t1 + np.concatenate([[0.0], np.cumsum(2 * e * v[:-1] / g)])
    return times, r + (e * v) ** 2 / (2 * g), t1 + 2 * e * g * t1 / (g * (1 - e))


def test_ball_bounces_at_the_closed_form_times_and_rests_at_the_accumulation_point(tmp_path):
    h0, r, g, e = 1.0, 0.05, 9.81, 0.5
    system = mb.load(MODELS / "bouncing_ball.yaml")
    out = tmp_path / "ball.npz"
    traj = mb.simulate(system, 2.0, out=str(out))
    impacts = [ev for ev in traj.events if ev.kind == "impact"]
    times, apex, t_rest = _ball_closed_form(h0, r, g, e, len(impacts))
    assert np.abs(np.array([ev.t for ev in impacts]) - times).max() < 1e-10
    # the impulses: m (1 + e) v at each impact, the last brought to rest (e = 0)
    v = g * times[0] * e ** np.arange(len(impacts))
    impulses = np.array([ev.impulse for ev in impacts])
    assert np.abs(impulses[:-1] - 0.2 * (1 + e) * v[:-1]).max() < 1e-10
    assert abs(impulses[-1] - 0.2 * v[-1]) < 1e-10
    # the apex heights, read at the apex times of the first flights
    for k in range(3):
        t_apex = times[k] + e * v[k] / g
        z = mb.simulate(system, t_apex).q[-1, 2]
        assert abs(z - apex[k]) < 1e-10
    # it rests where the hop it would make falls below the run's position accuracy: within
    # the flights left, 2 v/(g (1 - e)) for the rebound speed v of a hop of REST_HOP atol
    rest = [ev for ev in traj.events if ev.kind == "contact"]
    assert len(rest) == 1 and rest[0].t == impacts[-1].t
    v_rest = np.sqrt(2 * g * REST_HOP * INTEGRATION_ATOL)
    assert 0 < t_rest - rest[0].t < 2 * v_rest / (g * (1 - e)) + 1e-12
    after = traj.t > rest[0].t
    assert np.abs(traj.q[after, 2] - r).max() < 1e-12 and np.abs(traj.qd[after]).max() < 1e-12
    # the events in the .npz
    saved = load_trajectory(out)
    assert [(ev.t, ev.name, ev.kind, ev.impulse) for ev in saved.events] == \
        [(ev.t, ev.name, ev.kind, ev.impulse) for ev in traj.events]


def _stop_time(theta0, hi, L, g):
    """The time a rod (I = m L²/3 about its top) released at rest from theta0 < 0 takes to
    reach the angle hi: θ̈ = −ω² sin θ, ω² = 3g/(2L), by the elliptic integral of the first kind."""
    w, k = np.sqrt(3 * g / (2 * L)), np.sin(-theta0 / 2)
    return (ellipkinc(np.arcsin(np.sin(hi / 2) / k), k * k) + ellipk(k * k)) / w, w


def test_pendulum_strikes_an_elastic_stop_at_the_exact_time_and_keeps_its_energy():
    system = mb.load(MODELS / "pendulum_stop.yaml", parameters={"e": 1.0})
    t1, _ = _stop_time(-0.8, 0.3, 0.8, 9.81)
    traj = mb.simulate(system, 3.5 * t1, rtol=1e-13, atol=1e-13)
    assert [(ev.name, ev.kind) for ev in traj.events] == [("hinge.upper", "impact")] * 2
    assert abs(traj.events[0].t - t1) < 1e-10
    assert abs(traj.events[1].t - 3 * t1) < 1e-10  # back to the release angle and again: symmetric
    assert np.ptp(traj.energy) < 1e-10 * abs(traj.energy).max()
    assert traj.outputs[:, 0].max() < 0.3 + 1e-10


def test_pendulum_stopped_by_a_plastic_stop_swings_back_from_rest():
    system = mb.load(MODELS / "pendulum_stop.yaml", parameters={"e": 0.0})
    t1, w = _stop_time(-0.8, 0.3, 0.8, 9.81)
    half = 2 * ellipk(np.sin(0.15) ** 2) / w  # half the period of a swing of amplitude 0.3
    traj = mb.simulate(system, t1 + half, rtol=1e-12, atol=1e-12)
    assert [(ev.name, ev.kind) for ev in traj.events] == [("hinge.upper", "impact")]
    assert abs(traj.events[0].t - t1) < 1e-10
    angle = system.joint_values(traj.t[-1], traj.q[-1], traj.qd[-1])["hinge"]
    assert abs(angle[0] + 0.3) < 1e-9 and abs(angle[1]) < 1e-9


def _cradle(count, gap, speed):
    """Newton's cradle of ``count`` balls on the x axis (no gravity), e = 1, touching but the
    first, which comes at ``speed`` from ``gap`` away."""
    r = 0.1
    x = [0.0] + [gap + 2 * r * k for k in range(1, count)]
    balls = "\n".join(f"  b{k}: {{type: particle, mass: m, initial: {{position: [{x[k]!r}, 0, 0]"
                      + (f", velocity: [{speed!r}, 0, 0]" if k == 0 else "") + "}}" for k in range(count))
    contacts = "\n".join(f"  - {{name: c{k}, type: spheres, between: [b{k}, b{k + 1}], radius: [r, r], restitution: 1}}"
                         for k in range(count - 1))
    return mb.loads(f"name: cradle\nparameters: {{m: 0.3, r: {r}}}\nparts:\n{balls}\ncontacts:\n{contacts}\n")


@pytest.mark.parametrize("count", [3, 5])
def test_newtons_cradle_passes_the_velocity_down_the_row(count):
    gap, speed = 0.05, 1.3
    system = _cradle(count, gap, speed)
    traj = mb.simulate(system, 0.2)
    assert [ev.name for ev in traj.events] == [f"c{k}" for k in range(count - 1)]  # sequential, one instant
    assert all(abs(ev.t - gap / speed) < 1e-12 for ev in traj.events)
    vx = traj.qd[-1, 0::3]
    assert np.abs(vx - np.r_[np.zeros(count - 1), speed]).max() < 1e-12
    m = 0.3
    assert abs(m * vx.sum() - m * speed) < 1e-12 and abs(0.5 * m * (vx**2).sum() - 0.5 * m * speed**2) < 1e-12


def test_a_jump_is_the_classical_impulse_solution_with_a_massless_link():
    """A bob on a massless link (a rigid body of zero mass and inertia: M singular) that
    strikes the ground while swinging: the impulse is P = −(1 + e) m v_n / (1 − (n·r̂)²),
    the ground's and the link's impulses solving the bob's momentum balance."""
    m, L, theta, w0, e = 1.2, 0.9, 0.4, -2.0, 0.7
    s, c = float(np.sin(theta)), float(np.cos(theta))
    text = f"""
name: link_strike
parameters: {{m: {m}, L: {L}, s: {s!r}, c: {c!r}, w0: {w0}}}
world: {{frames: {{pivot: {{axis: [0, 1, 0]}}}}}}
parts:
  link:
    type: rigid_body
    mass: 0
    inertia: [0, 0, 0]
    frames: {{top: {{position: [0, 0, L/2], axis: [0, 1, 0]}}, bottom: {{position: [0, 0, -L/2]}}}}
    initial: {{position: [-L/2*s, 0, -L/2*c], rpy: [0, {theta!r}, 0], velocity: [-L/2*c*w0, 0, L/2*s*w0],
               angular_velocity: [0, w0, 0]}}
  bob:
    type: particle
    mass: m
    initial: {{position: [-L*s, 0, -L*c], velocity: [-L*c*w0, 0, L*s*w0]}}
joints:
  - {{name: pin, type: revolute, parent: world.pivot, child: link.top}}
  - {{name: hook, type: spherical, parent: link.bottom, child: bob}}
contacts:
  - {{name: floor, type: plane, child: bob, ground: -L*c, restitution: {e}}}
"""
    system = mb.loads(text)
    assert np.linalg.matrix_rank(system.evaluate(0.0, *system.initial_state()).M) < system.n  # M singular
    traj = mb.simulate(system, 1e-3)
    (impact,) = [ev for ev in traj.events if ev.kind == "impact"]
    r_hat = np.array([-s, 0.0, -c])
    v = L * w0 * np.array([-c, 0.0, s])
    n = np.array([0.0, 0.0, 1.0])
    assert impact.t == 0.0
    assert abs(impact.impulse - (-(1 + e) * m * (n @ v) / (1 - (n @ r_hat) ** 2))) < 1e-10


def test_a_jump_is_the_classical_impulse_solution_for_a_quaternion_body():
    """A free rigid body (quaternion coordinates: M singular along the quaternion's norm)
    strikes the ground at a corner: P = −(1 + e) v_n / (1/m + n·((J⁻¹(r × n)) × r)) (Brach),
    v⁺ = v + P n / m."""
    m, e = 1.3, 0.6
    J_body = np.array([[0.30, 0.04, -0.02], [0.04, 0.22, 0.05], [-0.02, 0.05, 0.41]])
    corner = np.array([0.2, -0.1, -0.15])
    system = mb.loads(f"""
name: corner_strike
parts:
  body:
    type: rigid_body
    mass: {m}
    inertia: {J_body.tolist()}
    frames: {{corner: {{position: {corner.tolist()}}}}}
    initial: {{position: [0, 0, 1], rpy: [0.3, -0.4, 1.1], velocity: [0.2, 0.1, -1.5],
               angular_velocity: [0.5, 4.0, 0.5]}}
contacts:
  - {{name: floor, type: plane, child: body.corner, ground: 0, restitution: {e}}}
""")
    q, qd = system.initial_state()
    quaternion = q[3:7]
    R = _rotation(quaternion)
    r = R @ corner
    ground = float(1.0 + r[2])  # the plane through the corner at the start
    system = mb.loads(system.source.replace("ground: 0", f"ground: {ground!r}"))
    v, omega = np.array([0.2, 0.1, -1.5]), np.array([0.5, 4.0, 0.5])
    n = np.array([0.0, 0.0, 1.0])
    J = R @ J_body @ R.T
    v_n = n @ (v + np.cross(omega, r))
    P = -(1 + e) * v_n / (1 / m + n @ np.cross(np.linalg.solve(J, np.cross(r, n)), r))
    traj = mb.simulate(system, 1e-3)
    (impact,) = traj.events
    assert impact.t == 0.0 and abs(impact.impulse - P) < 1e-10 * abs(P)
    assert np.abs(traj.qd[-1, :3] - (v + P * n / m)).max() < 1e-10  # no force after: momentum stays


def _rotation(quaternion):
    w, x, y, z = quaternion / np.linalg.norm(quaternion)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_a_jump_that_is_not_unique_names_its_free_coordinates():
    """Result 3 for impacts: a massless coordinate no row reaches (M = diag(m, 0), the
    contact on the first) has no post-impact velocity: SolveError names it."""
    with pytest.raises(SolveError, match="not unique.*free in b") as caught:
        velocity_jump(np.diag([2.0, 0.0]), np.array([-1.0, 0.3]), np.array([[1.0, 0.0]]), np.array([0.5]),
                      coordinates=["a", "b"], constraints=["floor"])
    assert list(caught.value.coordinates) == ["b"]


def test_a_jump_with_a_massless_coordinate_held_by_a_row_is_unique():
    """M = diag(m, 0), the massless coordinate tied to the first (q₂ = q₁): Result 3 holds
    and the jump is Newton's law on the first, −e v, carried by both."""
    e, v = 0.4, -1.5
    jump = velocity_jump(np.diag([2.0, 0.0]), np.array([v, v]), np.array([[1.0, -1.0], [1.0, 0.0]]),
                         np.array([0.0, -e * v]))
    assert np.abs(jump.qd - [-e * v, -e * v]).max() < 1e-14
    assert abs(jump.impulses[1] - 2.0 * (1 + e) * -v) < 1e-12


def test_a_resting_contact_holds_until_its_force_would_pull_and_then_releases():
    """A ball resting on the floor, lifted by a force k t: the floor holds it (λ = m g − k t)
    until t_r = m g / k, then it rises as z = r + k (t − t_r)³ / (6 m)."""
    m, r, g, k = 0.5, 0.1, 9.81, 3.0
    system = mb.loads(f"""
name: lift
parameters: {{m: {m}, r: {r}, g: {g}, k: {k}}}
gravity: [0, 0, -g]
parts:
  ball: {{type: particle, mass: m, initial: {{position: [0, 0, r]}}}}
forces:
  - {{name: lift, type: force, at: ball, value: [0, 0, k*t]}}
contacts:
  - {{name: floor, type: plane, child: ball, radius: r}}
""")
    traj = mb.simulate(system, 2.5)
    t_r = m * g / k
    assert [(ev.name, ev.kind) for ev in traj.events] == [("floor", "contact"), ("floor", "release")]
    assert traj.events[0].t == 0.0 and abs(traj.events[1].t - t_r) < 1e-12
    held = traj.t <= t_r
    assert np.abs(traj.q[held, 2] - r).max() < 1e-14
    risen = ~held
    assert np.abs(traj.q[risen, 2] - (r + k * (traj.t[risen] - t_r) ** 3 / (6 * m))).max() < 1e-10


def test_a_jump_left_free_by_a_massless_link_stops_the_run_naming_it():
    """The massless link of models/mechanisms/massless_link.yaml hangs between two spherical
    joints: its spin about itself is free (Result 3 fails for the jump as for the motion).
    Its bob strikes the ground: the run stops at the impact, naming the link's coordinates."""
    text = (Path(__file__).resolve().parents[2] / "models" / "mechanisms" / "massless_link.yaml").read_text()
    system = mb.loads(text + "contacts:\n  - {name: floor, type: plane, child: bob, "
                             "ground: 2 - L*cos(0.3)*cos(0.5) - 0.01}\n")
    with pytest.raises(mb.SimulationError, match=r"floor: the velocity jump of the impact is not unique .*Result 3"
                                                 r"\): free in link\.qw, link\.qx, link\.qy, link\.qz") as caught:
        mb.simulate(system, 1.0)
    t_hit = caught.value.time
    assert 0 < t_hit < 0.2 and caught.value.constraints == ("floor",)
    assert caught.value.coordinates == ("link.qw", "link.qx", "link.qy", "link.qz")


def test_a_slider_strikes_the_end_of_its_rail():
    """A block on a horizontal prismatic rail at speed v strikes its upper limit at
    (hi − x0)/v and comes back at e v."""
    v, hi, e = 0.8, 0.3, 0.5
    system = mb.loads(f"""
name: rail
world: {{frames: {{rail: {{axis: [1, 0, 0]}}}}}}
parts:
  block:
    type: rigid_body
    mass: 2.0
    inertia: [0.1, 0.1, 0.1]
    frames: {{slot: {{axis: [1, 0, 0]}}}}
    initial: {{velocity: [{v}, 0, 0]}}
joints:
  - {{name: slide, type: prismatic, parent: world.rail, child: block.slot, limits: [-1, {hi}], restitution: {e}}}
""")
    traj = mb.simulate(system, 1.0)
    (impact,) = traj.events
    assert impact.name == "slide.upper" and abs(impact.t - hi / v) < 1e-12
    assert abs(impact.impulse - 2.0 * (1 + e) * v) < 1e-10
    assert abs(traj.qd[-1, 0] + e * v) < 1e-12 and abs(traj.q[-1, 0] - (hi - e * v * (1.0 - hi / v))) < 1e-12


def test_a_hanging_cradle_strikes_at_the_quarter_periods_of_its_swing():
    """models/contact/newtons_cradle.yaml: the first ball, let go at theta0, strikes at a
    quarter period of its swing, K(k) √(L/g) (k = sin(theta0/2)); the third swings out and
    back and strikes again half a period later, the velocity passing back down the row."""
    system = mb.load(MODELS / "newtons_cradle.yaml")
    quarter = ellipk(np.sin(0.25) ** 2) * np.sqrt(0.3 / 9.81)
    traj = mb.simulate(system, 4 * quarter - 0.01, rtol=1e-12, atol=1e-12)
    assert [(ev.name, ev.kind) for ev in traj.events] == [("c01", "impact"), ("c12", "impact"),
                                                          ("c12", "impact"), ("c01", "impact")]
    times = np.array([ev.t for ev in traj.events])
    assert np.abs(times - quarter * np.array([1, 1, 3, 3])).max() < 1e-10
    assert np.ptp(traj.energy) < 1e-10 * abs(traj.energy).max()


def test_a_ball_bounces_to_rest_on_a_tilted_plane_and_slides_on_in_contact():
    """On a frictionless plane tilted by α the normal motion is the bouncing ball's under
    g cos α, the motion along the slope free fall under g sin α throughout: impacts do not
    touch it, and once the ball rests on the plane the held contact lets it slide."""
    g, r, e, alpha, d0 = 9.81, 0.05, 0.5, 0.3, 0.4  # d0: the centre's height above the plane
    n = np.array([np.sin(alpha), 0.0, np.cos(alpha)])
    along = np.array([np.cos(alpha), 0.0, -np.sin(alpha)])  # down the slope
    start = (d0 + r) * n
    system = mb.loads(f"""
name: slope
parameters: {{m: 0.2, r: {r}, g: {g}}}
gravity: [0, 0, -g]
parts:
  ball: {{type: particle, mass: m, initial: {{position: {start.tolist()}}}}}
contacts:
  - {{name: slope, type: plane, child: ball, radius: r, normal: {n.tolist()}, restitution: {e}}}
""")
    traj = mb.simulate(system, 2.0)
    impacts = [ev for ev in traj.events if ev.kind == "impact"]
    times, _, t_rest = _ball_closed_form(d0 + r, r, g * np.cos(alpha), e, len(impacts))
    assert np.abs(np.array([ev.t for ev in impacts]) - times).max() < 1e-10
    assert [ev.kind for ev in traj.events[len(impacts):]] == ["contact"]
    slide = (traj.q - start) @ along
    assert np.abs(slide - 0.5 * g * np.sin(alpha) * traj.t**2).max() < 1e-9
    after = traj.t > t_rest
    assert np.abs(traj.q[after] @ n - r).max() < 1e-12


def test_a_body_landing_flat_on_two_points_strikes_on_both_at_once():
    """A body falling flat (no rotation) onto two points at distances a and b either side of
    its centre: the two impacts are simultaneous, the complementarity problem's solution
    holds both (Newton's law at each): it rebounds at e v without turning, the impulses
    P₁ = m (1 + e) v b/(a + b), P₂ = m (1 + e) v a/(a + b) (their moments balance)."""
    m, a, b, v, e = 1.5, 0.3, 0.1, 2.0, 0.6
    system = mb.loads(f"""
name: plank
parts:
  plank:
    type: rigid_body
    mass: {m}
    inertia: [0.01, 0.08, 0.08]
    frames: {{left: {{position: [{-a}, 0, -0.02]}}, right: {{position: [{b}, 0, -0.02]}}}}
    initial: {{position: [0, 0, 0.22], velocity: [0, 0, {-v}]}}
contacts:
  - {{name: left, type: plane, child: plank.left, restitution: {e}}}
  - {{name: right, type: plane, child: plank.right, restitution: {e}}}
""")
    traj = mb.simulate(system, 0.2)
    impacts = {ev.name: ev for ev in traj.events}
    assert sorted(impacts) == ["left", "right"] and impacts["left"].t == impacts["right"].t
    assert abs(impacts["left"].t - 0.2 / v) < 1e-12
    assert abs(impacts["left"].impulse - m * (1 + e) * v * b / (a + b)) < 1e-10
    assert abs(impacts["right"].impulse - m * (1 + e) * v * a / (a + b)) < 1e-10
    assert np.abs(traj.qd[-1] - np.r_[0, 0, e * v, np.zeros(4)]).max() < 1e-10


def test_a_controller_that_lifts_a_resting_ball_releases_its_contact_at_the_sample():
    """Sampled control (its values jump at a sample): a force of 2 m g switched on at 0.5 s
    lifts a ball resting on the floor there, z = r + g (t − 0.5)²/2 after."""
    m, r, g = 0.5, 0.1, 9.81
    system = mb.loads(f"""
name: lift
parameters: {{m: {m}, r: {r}, g: {g}, F: 0.0}}
gravity: [0, 0, -g]
parts:
  ball: {{type: particle, mass: m, initial: {{position: [0, 0, r]}}}}
forces:
  - {{name: lift, type: force, at: ball, value: [0, 0, F]}}
contacts:
  - {{name: floor, type: plane, child: ball, radius: r}}
""")
    traj = mb.simulate(system, 1.0, dt=0.01, control_dt=0.25,
                       controller=lambda t, joints: {"F": 2 * m * g if t >= 0.5 else 0.0})
    assert [(ev.t, ev.kind) for ev in traj.events] == [(0.0, "contact"), (0.5, "release")]
    expected = np.where(traj.t > 0.5, r + g * (traj.t - 0.5) ** 2 / 2, r)
    assert np.abs(traj.q[:, 2] - expected).max() < 1e-12
