"""Coulomb friction at a sphere against a plane (io/unilateral.py: the contact point's
velocity v + ω × (−r n) in the slip rows) against the closed forms of a solid sphere
(I = 2/5 m r²): sliding with spin on the ground, and striking it at an angle."""

import numpy as np
import pytest

import mbsynth as mb

M, R, G = 2.0, 0.1, 9.81


def _ball(v0, w0, mu, *, z=R, vz=0.0, e=0.0, g=G):
    """A solid sphere of radius R with its centre at height z moving at (v0, 0, vz), turning
    at w0 about y, against the ground z = 0."""
    return mb.loads(f"""
name: sliding_ball
parameters: {{m: {M}, r: {R}, mu: {mu}, g: {g}, e: {e}}}
gravity: [0, 0, -g]
parts:
  ball:
    type: rigid_body
    mass: m
    inertia: [2*m*r**2/5, 2*m*r**2/5, 2*m*r**2/5]
    initial: {{position: [0, 0, {z}], velocity: [{v0}, 0, {vz}], angular_velocity: [0, {w0}, 0]}}
contacts:
  - {{name: floor, type: plane, child: ball, radius: r, friction: mu, restitution: e}}
""")


def _spin(q, qd):
    """ω_y of the ball turning about y only: 2 (q_w q̇_y − q̇_w q_y), its quaternion (w, x, y, z)."""
    return 2 * (q[..., 3] * qd[..., 5] - qd[..., 3] * q[..., 5])


@pytest.mark.parametrize("v0, w0, mu", [(1.0, 0.0, 0.3), (1.0, -5.0, 0.3), (1.0, 25.0, 0.5), (-0.4, 2.0, 0.2)])
def test_a_sliding_sphere_follows_the_closed_form_until_its_slip_ends(v0, w0, mu):
    """The contact point's slip u = v − r ω decelerates at 7/2 μ g (friction −μ m g sign u
    on the centre, its moment μ m g r sign u about y over I = 2/5 m r²) and ends at
    t* = 2 |u0| / (7 μ g); up to there v = v0 − s μ g t, ω = w0 + s 5 μ g t / (2 r), s = sign u0
    (from rest and no spin: t* = 2 v0 / (7 μ g), and rolling follows at 5/7 v0)."""
    u0 = v0 - R * w0
    s, t_star = np.sign(u0), 2 * abs(u0) / (7 * mu * G)
    traj = mb.simulate(_ball(v0, w0, mu), 0.99 * t_star, rtol=1e-12, atol=1e-12)
    assert [(ev.t, ev.kind) for ev in traj.events] == [(0.0, "contact"), (0.0, "slip")]
    t = traj.t
    assert np.abs(traj.q[:, 0] - (v0 * t - s * mu * G * t**2 / 2)).max() < 1e-10
    assert np.abs(traj.qd[:, 0] - (v0 - s * mu * G * t)).max() < 1e-10
    assert np.abs(_spin(traj.q, traj.qd) - (w0 + s * 5 * mu * G * t / (2 * R))).max() < 1e-9
    assert np.abs(traj.q[:, 2] - R).max() < 1e-10
    slip = traj.qd[-1, 0] - R * _spin(traj.q[-1], traj.qd[-1])
    assert slip == pytest.approx(u0 - s * 3.5 * mu * G * t[-1], abs=1e-10)


@pytest.mark.parametrize("vx, w0, mu, e", [(0.5, 0.0, 0.5, 0.6), (2.0, 0.0, 0.2, 0.6), (1.0, -8.0, 0.3, 1.0),
                                           (0.3, 10.0, 0.4, 0.0)])
def test_a_sphere_striking_the_ground_at_an_angle_meets_the_impulse_closed_form(vx, w0, mu, e):
    """A sphere striking at (vx, 0, −vz) with spin w0 about y (no gravity): the normal impulse
    P_n = m (1 + e) vz (Newton's law); its contact point's slip u = vx − r w0 changes by
    Δu = P_t/m + r² P_t / I = 7/2 P_t/m, so sticking needs P_t = −2/7 m u, taken where
    |P_t| ≤ μ P_n; otherwise it slips through the impact, P_t = −μ P_n sign u (Brach)."""
    vz = 1.5
    P_n, u = M * (1 + e) * vz, vx - R * w0
    P_t, mode = -2 / 7 * M * u, "stick"
    if abs(P_t) > mu * P_n:
        P_t, mode = -mu * P_n * np.sign(u), "slip"
    z0 = R + 0.1 * vz  # it strikes at t = 0.1
    traj = mb.simulate(_ball(vx, w0, mu, z=z0, vz=-vz, e=e, g=0.0), 0.15, rtol=1e-12, atol=1e-12)
    impacts = [ev for ev in traj.events if ev.kind in ("impact", mode)]
    assert [ev.kind for ev in impacts[:2]] == ["impact", mode]
    assert impacts[0].t == pytest.approx(0.1, abs=1e-12)
    assert impacts[0].impulse == pytest.approx(P_n, rel=1e-10)
    assert impacts[1].impulse == pytest.approx(abs(P_t), rel=1e-10, abs=1e-12)
    after = traj.t > 0.1
    assert np.abs(traj.qd[after, 0] - (vx + P_t / M)).max() < 1e-10
    assert np.abs(traj.qd[after, 2] - e * vz).max() < 1e-10
    assert np.abs(_spin(traj.q[after], traj.qd[after]) - (w0 - 5 * P_t / (2 * M * R))).max() < 1e-9
