"""Coulomb friction at impacts (analysis/impulse.py's Rough) against the classical impulse
solution of a slender rod striking the ground on one end, and the model file's refusals."""

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.core.errors import EventError, ModelError

M_ROD, L, E = 0.8, 1.2, 0.5
BETA = 0.6  # the rod's axis (body z) turned by β about y from the vertical: z_body = (sin β, 0, cos β)


def _rod(mu, u, w, omega):
    """A slender rod (I = m L²/12 across, a thin cylinder's small inertia along) touching the
    ground z = 0 with its lower end, its centre moving at (u, 0, −w), turning at ω about y;
    no gravity, so its motion after the impact is a free flight at the post-impact velocities."""
    c = float((L / 2) * np.cos(BETA))
    return mb.loads(f"""
name: rod_strike
parameters: {{m: {M_ROD}, L: {L}, e: {E}, mu: {mu}}}
parts:
  rod:
    type: rigid_body
    mass: m
    inertia: [m*L**2/12, m*L**2/12, m*0.01**2/2]
    frames: {{tip: {{position: [0, 0, -L/2]}}}}
    initial: {{position: [0, 0, {c!r}], rpy: [0, {BETA}, 0], velocity: [{u}, 0, {-w}],
               angular_velocity: [0, {omega}, 0]}}
contacts:
  - {{name: floor, type: plane, child: rod.tip, restitution: e, friction: mu}}
""")


def _classical(mu, u, w, omega):
    """The impulse (P_x, P_z) at the end and the mode, for a slender rod (Goldsmith 1960;
    Brach 1989). With r = −(L/2)(sin β, 0, cos β) from the centre to the end, the end's
    velocity is v_c = v + ω × r, so v_cx = v_x + ω r_z, v_cz = v_z − ω r_x, and an impulse
    P at the end changes it by m Δv = P, I Δω = r_z P_x − r_x P_z:

        Δv_c = K P,  K = [[1/m + r_z²/I, −r_x r_z/I], [−r_x r_z/I, 1/m + r_x²/I]].

    Newton's law: Δv_cz = −(1 + e) v_cz⁻. Stick: Δv_cx = −v_cx⁻, P = K⁻¹(−v_cx⁻, −(1 + e) v_cz⁻),
    valid while |P_x| ≤ μ P_z. Otherwise slip throughout: P_x = −μ s P_z with s the sign of
    the slip v_cx⁻, and (K_zz − μ s K_zx) P_z = −(1 + e) v_cz⁻."""
    I = M_ROD * L**2 / 12
    r_x, r_z = -(L / 2) * np.sin(BETA), -(L / 2) * np.cos(BETA)
    v_cx, v_cz = u + omega * r_z, -w - omega * r_x
    K = np.array([[1 / M_ROD + r_z**2 / I, -r_x * r_z / I], [-r_x * r_z / I, 1 / M_ROD + r_x**2 / I]])
    P = np.linalg.solve(K, [-v_cx, -(1 + E) * v_cz])
    if abs(P[0]) <= mu * P[1]:
        mode = "stick"
    else:
        assert np.sign(P[0]) == -np.sign(v_cx)  # the impulse sticking needs opposes the slip
        s = np.sign(v_cx)
        P_z = -(1 + E) * v_cz / (K[1, 1] - mu * s * K[1, 0])
        P, mode = np.array([-mu * s * P_z, P_z]), "slip"
    v = np.array([u, -w]) + P / M_ROD
    return P, mode, v, omega + (r_z * P[0] - r_x * P[1]) / I


def _angular_velocity(q, qd):
    """ω (world) of the quaternion (w, x, y, z) and its rate: the vector part of 2 q̇ q*."""
    w, v = q[0], q[1:]
    wd, vd = qd[0], qd[1:]
    return 2 * (w * vd - wd * v - np.cross(vd, v))


@pytest.mark.parametrize("mu, expected", [(0.9, "stick"), (0.1, "slip"), (0.0, None)])
def test_rod_striking_on_one_end_gets_the_classical_impulse(mu, expected):
    u, w, omega = 0.5, 2.0, 1.5
    P, mode, v, omega_after = _classical(mu, u, w, omega)
    if expected is not None:
        assert mode == expected
    traj = mb.simulate(_rod(mu, u, w, omega), 1e-3)
    impact = [ev for ev in traj.events if ev.kind == "impact"]
    assert [(ev.t, ev.name) for ev in impact] == [(0.0, "floor")]
    assert abs(impact[0].impulse - P[1]) < 1e-10 * abs(P[1])
    tangential = [ev for ev in traj.events if ev.kind in ("stick", "slip")]
    if mu > 0:
        assert [(ev.name, ev.kind) for ev in tangential] == [("floor", mode)]
        assert abs(tangential[0].impulse - abs(P[0])) < 1e-10 * abs(P[1])
    else:
        assert not tangential and abs(P[0]) < 1e-15 * abs(P[1])
    q, qd = traj.q[-1], traj.qd[-1]
    assert np.abs(qd[[0, 2]] - v).max() < 1e-10 and abs(qd[1]) < 1e-12
    assert np.abs(_angular_velocity(q[3:], qd[3:]) - [0, omega_after, 0]).max() < 1e-10


def test_a_rough_contact_that_comes_to_rest_sticks_where_it_landed():
    """A ball dropped 0.1 m with e = 0 and speed 0.3 along the ground lands at t = sqrt(0.2/g)
    with normal impulse sqrt(0.2 g); it needs tangential impulse 0.3 ≤ μ Λ_n, so it sticks
    through the impact, comes to rest, and sticks on the ground where it landed (x = 0.3 t)."""
    system = mb.loads("""name: rough_ball
gravity: [0, 0, -9.81]
parts:
  ball: {type: particle, mass: 1, initial: {position: [0, 0, 0.1], velocity: [0.3, 0, 0]}}
contacts:
  - {name: floor, type: plane, child: ball, friction: 0.5}
""")
    traj = mb.simulate(system, 1.0)
    t_land = np.sqrt(0.2 / 9.81)
    assert [ev.kind for ev in traj.events] == ["impact", "stick", "contact", "stick"]
    assert all(abs(ev.t - t_land) < 1e-10 for ev in traj.events)
    assert abs(traj.events[0].impulse - np.sqrt(0.2 * 9.81)) < 1e-10 and abs(traj.events[1].impulse - 0.3) < 1e-12
    assert np.abs(traj.q[-1] - [0.3 * t_land, 0, 0]).max() < 1e-10 and np.abs(traj.qd[-1]).max() < 1e-12


@pytest.mark.parametrize("entry, message", [
    ("friction: -0.2", "contacts[0].friction: friction must be ≥ 0, got -0.2"),
    ("friction: 0.3, radius: -0.1", "contacts[0].radius: a radius is ≥ 0, got -0.1"),
])
def test_bad_friction_is_refused_at_its_line(entry, message):
    text = f"""name: bad
parts:
  ball: {{type: particle, mass: 1, initial: {{position: [0, 0, 1]}}}}
contacts:
  - {{name: floor, type: plane, child: ball, {entry}}}
"""
    with pytest.raises(ModelError) as err:
        mb.loads(text)
    assert ":5: at " + message in str(err.value)
