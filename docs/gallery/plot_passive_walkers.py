"""
Passive walkers down a slope
============================

Two walkers that gravity alone drives down a slope, through impacts and contacts that stick
(``contacts:`` with ``friction:``; see "Limits, contacts and impacts" in the guide).

**McGeer's rimless wheel** (``models/contact/rimless_wheel.yaml``): a hub of mass m on
eight massless spokes of length l, 2α = π/4 apart, on a slope γ. The mass at the hub makes
M singular (no inertia about it); the stance foot's rows close it. In stance the hub is an
inverted pendulum about the stance foot, so ω² + 2 (g/l) cos φ is kept from φ = γ − α to
γ + α; at each plastic impact the angular momentum about the new foot is kept but for the
part of the hub's velocity along the new spoke, ω⁺ = cos 2α ω⁻. Its step-to-step map
ω⁺ₖ₊₁ = cos 2α (ω⁺ₖ² + 4 (g/l) sin α sin γ)^½ has the fixed point ω⁺* = cos 2α (4 (g/l)
sin α sin γ)^½ / sin 2α, which the wheel approaches by a factor cos² 2α = 1/2 per step.

**The simplest walking model** (Garcia, Chatterjee, Ruina & Coleman 1998;
``models/contact/simplest_walker.yaml``): a hip mass on two massless legs with feet of mass
β = 10⁻⁶ of it, at γ = 0.009 in the paper's units. Each step is run in two parts: the swing
foot passes through the slope near mid-stance (foot scuffing, which the paper ignores), so
its contact sits below the slope until the swing leg has passed the stance leg. Started off
its period-one gait, the walker settles onto it (its step-to-step eigenvalues are
−0.19 ± 0.56i).
"""

# %%
# The rimless wheel
# -----------------
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mbsynth as mb

MODELS = Path("../../models/contact")  # sphinx-gallery runs each script in its own folder
wheel = mb.load(MODELS / "rimless_wheel.yaml", parameters={"w0": 1.3})
p = wheel.parameters
g, l, gamma, alpha = p["g"], p["l"], p["gamma"], p["alpha"]
gain = 4 * g / l * np.sin(alpha) * np.sin(gamma)
steady = np.cos(2 * alpha) * np.sqrt(gain) / np.sin(2 * alpha)
roll = mb.simulate(wheel, 5.0, dt=0.005, rtol=1e-12, atol=1e-12)
impacts = [ev.t for ev in roll.events if ev.kind == "impact"]

# ω⁺ after each impact, read from the stance after it through the kept ω² + 2 (g/l) cos φ
found, expected = [], [p["w0"]]
for k, t in enumerate(impacts, start=1):
    row = np.searchsorted(roll.t, t, side="right") + 1
    phi = -2 * k * alpha - roll.q[row, 2]
    kept = roll.qd[row, 2] ** 2 + 2 * g / l * np.cos(phi)
    found.append(np.sqrt(kept - 2 * g / l * np.cos(gamma - alpha)))
    expected.append(np.cos(2 * alpha) * np.sqrt(expected[-1] ** 2 + gain))
print(f"{len(impacts)} steps; ω⁺ after each: {np.round(found, 6)}; steady ω⁺* = {steady:.6f} rad/s")
print(f"largest departure from the step-to-step map: {np.abs(np.array(found) - expected[1:]).max():.1e} rad/s")
assert np.abs(np.array(found) - expected[1:]).max() < 1e-8

fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(roll.t, -roll.qd[:, 2], label="ω = −θ̇ (mbsynth)")
ax.axhline(steady, color="k", ls="--", lw=0.8, label="ω⁺* (step-to-step map)")
ax.axhline(steady / np.cos(2 * alpha), color="grey", ls=":", lw=0.8, label="ω⁻* = ω⁺* / cos 2α")
ax.plot(impacts, found, "o", ms=4, label="ω⁺ after each impact")
ax.set_xlabel("t [s]")
ax.set_ylabel("ω [rad/s]")
ax.legend(loc="lower right")

# %%
# The wheel in the viewer: :download:`rimless_wheel.html </gallery/rimless_wheel.html>`;
# from the command line, ``mbsynth view models/contact/rimless_wheel.yaml --t-end 5``.
from mbsynth.view.screenshot import show_still

page = mb.viewer.to_html(wheel, roll, Path("rimless_wheel.html"))
fig, ax = plt.subplots(figsize=(7, 5))
if not show_still(ax, page, Path("rimless_wheel.png"), budget_ms=400):
    ax.plot(roll.q[:, 0], roll.q[:, 1])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Chromium is not installed: the hub's path instead of the viewer's picture")

# %%
# The simplest walker
# -------------------
# Each step starts just after a heel strike on foot a at the origin, at the stance angle θ
# (off the slope normal) and rate θ̇ (the legs at φ = 2θ, φ̇ = θ̇ (1 − cos 2θ)); it ends
# just after foot b strikes. The next step starts from θ⁺ (foot b stands 2 l sin θ⁺ from
# foot a) and θ̇⁺ (read from the new stance's kept θ̇²/2 + cos(θ − γ)).
walker = mb.load(MODELS / "simplest_walker.yaml")
w_gamma = walker.parameters["gamma"]
slope = np.array([np.cos(w_gamma), -np.sin(w_gamma)])
normal = np.array([np.sin(w_gamma), np.cos(w_gamma)])
SWING, END = 2.6, 4.2  # past mid-stance, the swing foot above the slope; past the heel strike


def step(theta, theta_dot):
    """One step from (θ, θ̇): its rows up to the heel strike, foot b's place, (θ⁺, θ̇⁺)."""
    first = walker.with_parameters(theta=theta, theta_dot=theta_dot, drop_b=0.5)
    swing = mb.simulate(first, SWING, dt=0.05, rtol=1e-12, atol=1e-12)
    on = mb.simulate(first.with_parameters(drop_b=0.0), END, t0=SWING, q0=swing.q[-1], qd0=swing.qd[-1], dt=0.05,
                     rtol=1e-12, atol=1e-12)
    strike = next(ev.t for ev in on.events if ev.kind == "impact")
    q, qd = on.q[-1], on.qd[-1]
    foot, hip, v = q[6:8], q[0:2], qd[0:2]
    after = np.arcsin(np.linalg.norm(foot) / 2)
    r = hip - foot
    now = np.arctan2(-(r @ slope), r @ normal)
    rate = -(v @ slope) * np.cos(now) - (v @ normal) * np.sin(now)
    rate_after = -np.sqrt(rate**2 + 2 * np.cos(now - w_gamma) - 2 * np.cos(after - w_gamma))
    rows = np.vstack([swing.q, on.q[1:][on.t[1:] <= strike]])
    return rows, foot, np.array([after, rate_after])


state, offset, gait = np.array([0.2, -0.2]), np.zeros(2), [np.array([0.2, -0.2])]
fig, ax = plt.subplots(figsize=(9, 3.5))
for k in range(10):
    rows, foot, state = step(*state)
    for i in range(0, len(rows), 6):
        hip, fa, fb = (rows[i, j:j + 2] + offset for j in (0, 3, 6))
        ax.plot([fa[0], hip[0], fb[0]], [fa[1], hip[1], fb[1]], color=f"C{k % 2}", lw=0.6, alpha=0.6)
    offset = offset + foot
    gait.append(state)
gait = np.array(gait)
print("θ⁺, θ̇⁺ after each step:\n", np.round(gait, 8))
published = np.array([0.20031090049483, -0.19983247291764])
print(f"distance to the published gait: first {np.abs(gait[0] - published).max():.1e}, "
      f"last {np.abs(gait[-1] - published).max():.1e} (O(β) = 1e-6 at β = 1e-6)")
assert np.abs(gait[-1] - published).max() < 0.05 * np.abs(gait[0] - published).max()
x = np.linspace(-0.5, offset[0] + 0.5, 2)
ax.plot(x, -np.tan(w_gamma) * x, color="k", lw=1)
ax.set_aspect("equal")
ax.set_xlabel("x")
ax.set_ylabel("y")
ax.set_title("ten steps of the simplest walker (every 0.3 time units), γ = 0.009")

fig, ax = plt.subplots(figsize=(5, 4))
ax.plot(gait[:, 0], gait[:, 1], "o-", ms=4, label="after each heel strike")
ax.plot(*published, "k+", ms=12, label="published period-one gait")
ax.set_xlabel("θ⁺")
ax.set_ylabel("θ̇⁺")
ax.legend()
