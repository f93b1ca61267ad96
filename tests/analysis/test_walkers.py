"""Passive walkers on a slope against their step-to-step maps.

McGeer's rimless wheel (models/contact/rimless_wheel.yaml; McGeer 1990, "Passive dynamic
walking"): all its mass m at the hub, spokes of length l 2α apart, slope γ. Derived here:
in stance the hub is an inverted pendulum about the stance foot, φ the stance spoke's
angle off the vertical, so ω² + 2 (g/l) cos φ is kept from φ = γ − α (just after an
impact) to φ = γ + α (the next foot touches):

    ω⁻² = ω⁺² + 2 (g/l) (cos(γ − α) − cos(γ + α)) = ω⁺² + 4 (g/l) sin α sin γ.

At the plastic impact the new foot sticks and the old one lifts off; the impulse passes
through the new foot, so the angular momentum m l² ω about it is kept but for the part of
the hub's velocity along the new spoke, which is 2α from the old: ω⁺ = cos(2α) ω⁻ (with I
= 0 the impulse is along the new spoke: |Λ_t| / Λ_n = tan α). The step-to-step map is
ω⁺ₖ₊₁ = cos 2α (ω⁺ₖ² + 4 (g/l) sin α sin γ)^½, its fixed point ω⁺* = cos 2α (4 (g/l) sin α
sin γ)^½ / sin 2α, its slope there cos² 2α.
"""

from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

import mbsynth as mb

MODELS = Path(__file__).resolve().parents[2] / "models" / "contact"
WHEEL = MODELS / "rimless_wheel.yaml"
G, L, GAMMA, SPOKES = 9.81, 1.0, 0.1, 8
ALPHA = np.pi / SPOKES


def _wheel_map(w):
    return np.cos(2 * ALPHA) * np.sqrt(w**2 + 4 * G / L * np.sin(ALPHA) * np.sin(GAMMA))


W_STEADY = np.cos(2 * ALPHA) * np.sqrt(4 * G / L * np.sin(ALPHA) * np.sin(GAMMA)) / np.sin(2 * ALPHA)


def _wheel_steps(w0, steps):
    """The run from w0 just after an impact on foot0 through ``steps`` impacts: (the rate
    ω⁺ just after each impact from the first on, the impacts' events). ω⁺ is read from a
    row in the stance after it by the stance's kept ω² + 2 (g/l) cos φ."""
    system = mb.load(WHEEL, parameters={"w0": w0})
    t_end = 0.75 * (steps + 0.5)
    traj = mb.simulate(system, t_end, dt=0.01, rtol=1e-12, atol=1e-12)
    impacts = [ev for ev in traj.events if ev.kind == "impact"]
    assert [ev.name for ev in impacts[:steps]] == [f"foot{k + 1}" for k in range(steps)]
    found = []
    for k, ev in enumerate(impacts[:steps], start=1):
        row = np.searchsorted(traj.t, ev.t, side="right") + 1
        theta, omega = traj.q[row, 2], -traj.qd[row, 2]
        phi = -2 * k * ALPHA - theta
        kept = omega**2 + 2 * G / L * np.cos(phi)
        found.append(np.sqrt(kept - 2 * G / L * np.cos(GAMMA - ALPHA)))
    return np.array(found), traj


def test_rimless_wheel_started_at_the_fixed_point_rolls_at_the_steady_speed():
    """From ω⁺* every step starts at ω⁺* again, to 1e-8, and takes the same time; each foot
    sticks where it lands, its impulse along its spoke (|Λ_t| / Λ_n = tan α)."""
    found, traj = _wheel_steps(W_STEADY, 3)
    assert np.abs(found - W_STEADY).max() < 1e-8
    times = [0.0] + [ev.t for ev in traj.events if ev.kind == "impact"]
    assert np.ptp(np.diff(times)) < 1e-8
    for ev in traj.events:
        if ev.kind == "impact":
            tangential = next(e for e in traj.events if e.t == ev.t and e.name == ev.name and e.kind == "stick")
            assert abs(tangential.impulse / ev.impulse - np.tan(ALPHA)) < 1e-10


def test_rimless_wheel_off_its_fixed_point_follows_the_step_to_step_map_towards_it():
    """From ω⁺ = 1.3 each step's ω⁺ is the map of the one before, to 1e-8, and the distance
    to ω⁺* shrinks by about the map's slope cos² 2α = 1/2 per step."""
    w0 = 1.3
    found, _ = _wheel_steps(w0, 3)
    expected = [_wheel_map(w0)]
    for _ in range(2):
        expected.append(_wheel_map(expected[-1]))
    assert np.abs(found - expected).max() < 1e-8
    gaps = np.abs(np.r_[w0, found] - W_STEADY)
    assert (gaps[1:] / gaps[:-1] < 0.6).all() and (gaps[1:] / gaps[:-1] > np.cos(2 * ALPHA) ** 2 * 0.9).all()


# The simplest walking model (models/contact/simplest_walker.yaml; Garcia, Chatterjee, Ruina &
# Coleman 1998), in the paper's units and at its slope γ = 0.009. Its period-one gait: the
# stance angle θ and rate θ̇ just after a heel strike that the step returns, as published
# with the paper's simulation code (M. Garcia, 1998: "initial conditions gam=0.009 long step
# to 1e-10"): the stable, long-step gait. The code's comment gives the eigenvalues of the
# step-to-step map's Jacobian there as −0.19121 ± 0.55633i, a finite-difference estimate
# that the paper's own equations (β = 0: θ̈ = sin(θ − γ), φ̈ = θ̈ + sin φ (θ̇² − cos(θ − γ)),
# heel strike at φ = 2θ with θ < 0: θ⁺ = −θ⁻, θ̇⁺ = cos 2θ⁻ θ̇⁻) integrated to 1e-13 here
# (``_paper_step``) give as −0.19010 ± 0.55760i: the published values hold to 2e-3 only.
WALKER = MODELS / "simplest_walker.yaml"
W_GAMMA = 0.009
PUBLISHED_GAIT = np.array([0.20031090049483, -0.19983247291764])
PUBLISHED_EIGENVALUES = np.array([-0.19120868949940 + 0.55633363687106j, -0.19120868949940 - 0.55633363687106j])
SWING, STEP_END = 2.6, 4.2  # a time after mid-stance with the swing foot above the slope; one after the heel strike
_SLOPE = np.array([np.cos(W_GAMMA), -np.sin(W_GAMMA)])  # down the slope
_NORMAL = np.array([np.sin(W_GAMMA), np.cos(W_GAMMA)])


def _walker_step(system, x, beta):
    """The step-to-step map (θ, θ̇) → (θ, θ̇) just after the next heel strike, by two runs.
    Foot scuffing: near mid-stance the swing foot passes through the slope (from φ = 2θ
    with θ > 0 until φ = 0), which the paper ignores; the run to SWING has the swing foot's
    contact drop_b below the slope, the run on from there (the foot above the slope again,
    the stance leg past the normal, θ < 0) has it on the slope, so only the heel strike
    counts. After it foot b stands where it struck, 2 l sin θ⁺ from foot a; θ̇⁺ is read at
    STEP_END from the new stance's kept θ̇²/2 + cos(θ − γ) (the hip an inverted pendulum
    about the stance foot, β → 0)."""
    first = system.with_parameters(theta=x[0], theta_dot=x[1], beta=beta, drop_b=0.5)
    swing = mb.simulate(first, SWING, dt=SWING, rtol=1e-12, atol=1e-12)
    strike = mb.simulate(first.with_parameters(drop_b=0.0), STEP_END, t0=SWING, q0=swing.q[-1], qd0=swing.qd[-1],
                         dt=STEP_END - SWING, rtol=1e-12, atol=1e-12)
    assert [(ev.name, ev.kind) for ev in strike.events if ev.kind in ("impact", "release")] == \
        [("heel_b", "impact"), ("heel_a", "release")]
    q, qd = strike.q[-1], strike.qd[-1]
    stance, hip, v = q[6:8], q[0:2], qd[0:2]
    theta = np.arcsin(np.linalg.norm(stance) / 2)
    r = hip - stance
    now = np.arctan2(-(r @ _SLOPE), r @ _NORMAL)
    rate = -(v @ _SLOPE) * np.cos(now) - (v @ _NORMAL) * np.sin(now)
    return np.array([theta, -np.sqrt(rate**2 + 2 * np.cos(now - W_GAMMA) - 2 * np.cos(theta - W_GAMMA))])


def _paper_step(x):
    """The same map from the paper's equations of motion (β = 0) and heel-strike map."""
    def motion(t, y):
        theta, phi, theta_dot, _ = y
        return [theta_dot, y[3], np.sin(theta - W_GAMMA),
                np.sin(theta - W_GAMMA) + np.sin(phi) * (theta_dot**2 - np.cos(theta - W_GAMMA))]

    def strike(t, y):
        return y[1] - 2 * y[0] if y[0] < 0 else -1.0
    strike.terminal, strike.direction = True, 1
    theta, theta_dot = x
    y0 = [theta, 2 * theta, theta_dot, theta_dot * (1 - np.cos(2 * theta))]
    y = solve_ivp(motion, (0, 10), y0, method="DOP853", rtol=1e-13, atol=1e-13, events=strike).y_events[0][0]
    return np.array([-y[0], np.cos(2 * y[0]) * y[2]])


def _jacobian(step, x, h=1e-5):
    """∂step/∂x at x by central differences."""
    return np.column_stack([(step(x + d) - step(x - d)) / (2 * h) for d in np.eye(2) * h])


def _gait(step, x, J):
    """The period-one gait by Newton's method on step(x) − x, the step's Jacobian J held (a
    chord iteration)."""
    for _ in range(30):
        dx = np.linalg.solve(J - np.eye(2), x - step(x))
        x = x + dx
        if np.abs(dx).max() < 1e-11:
            return x
    raise AssertionError(f"no period-one gait found near {x}")


def test_simplest_walker_period_one_gait_and_its_stability_as_published():
    """Newton's search through mbsynth runs from (0.2, −0.2) finds the period-one gait. The
    paper's model is the limit β = m/M → 0 of foot over hip mass, taken from β and 2β (the
    gait is smooth in β: 2 x(β) − x(2β) is x(0) to O(β²)): the published gait to 1e-10.
    The eigenvalues of the map's Jacobian there (central differences of runs at rtol 1e-12,
    at β = 1e-6): those of the paper's equations to 1e-4, the published ones to 2e-3; the
    gait is stable."""
    beta = 1e-6
    system = mb.load(WALKER)
    guess = np.array([0.2, -0.2])

    def step(x, beta=beta):
        return _walker_step(system, x, beta)

    near = _gait(step, guess, _jacobian(step, guess))
    J = _jacobian(step, near)
    gait = 2 * near - _gait(lambda x: step(x, 2 * beta), near, J)
    assert np.abs(gait - PUBLISHED_GAIT).max() < 1e-10
    eigenvalues = np.sort_complex(np.linalg.eigvals(J))
    paper = np.sort_complex(np.linalg.eigvals(_jacobian(_paper_step, PUBLISHED_GAIT)))
    assert np.abs(eigenvalues - paper).max() < 1e-4
    assert np.abs(eigenvalues - np.sort_complex(PUBLISHED_EIGENVALUES)).max() < 2e-3
    assert np.abs(eigenvalues).max() < 1
