"""
The Whipple bicycle: stability of upright rolling
=================================================

The benchmark bicycle of Meijaard, Papadopoulos, Ruina and Schwab (Proc. R. Soc. A 463,
2007, doi 10.1098/rspa.2007.1857), written as it is built: four rigid bodies (the rear
wheel, the rear frame with its rider, the front frame and the front wheel), three
revolute joints and two wheels rolling without slipping (``models/rolling/bicycle.yaml``,
its two wheels one file, ``bicycle_wheel.yaml``, included as ``rear`` and ``front``; no
hand-derived equations). Each body turns by angles z, x, y (``rotation: zxy``), so a
wheel's spin angle is cyclic and rolling upright at speed v is a steady motion.

``mb.linearize`` takes the model about that motion in independent coordinates and
independent speeds (the slip rows leave three: forward, lean and steer rates). Its
eigenvalues are the motion's stability exponents: the four of the benchmark's lean and
steer (weave, capsize, castering) and six exact zeros (position, heading, wheel angles,
forward speed). Between the weave speed and the capsize speed the bicycle is
self-stable.
"""

# %%
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import scipy.linalg
from scipy.optimize import brentq

import mbsynth as mb

bicycle = mb.load(Path("..", "..", "models", "rolling", "bicycle.yaml"))
R_REAR = bicycle.parameters["rR"]


def exponents(v):
    """The non-zero eigenvalues of upright rolling at v (m/s), from the rear wheel's spin rate."""
    q, qd = mb.steady_motion(bicycle, {"rear.wheel.angle_y": v / R_REAR})
    values = mb.linearize(bicycle, 0.0, q, qd).eigenvalues
    return values[values != 0]


# the paper's Table 2 at 5 m/s, and its weave and capsize speeds
table_2 = np.sort_complex([-14.07838969279822, -0.32286642900409,
                           -0.77534188219585 - 4.46486771378823j, -0.77534188219585 + 4.46486771378823j])
print("eigenvalues at 5 m/s:", np.round(np.sort_complex(exponents(5.0)), 10))
assert np.abs(np.sort_complex(exponents(5.0)) - table_2).max() < 1e-8


def least_stable(v):
    return exponents(v).real.max()


weave, capsize = brentq(least_stable, 4.0, 5.0, xtol=1e-12), brentq(least_stable, 5.5, 7.0, xtol=1e-12)
print(f"self-stable from {weave:.10f} to {capsize:.10f} m/s")
assert abs(weave - 4.29238253634111) < 1e-7 and abs(capsize - 6.02426201538837) < 1e-7

# %%
# Eigenvalues against speed
# -------------------------
# As the paper's figure 3: real parts (solid) and imaginary parts (dotted) of the four
# exponents from 0 to 10 m/s. The weave pair turns stable at the weave speed, the capsize
# exponent turns unstable at the capsize speed.
speeds = np.linspace(0.0, 10.0, 101)
values = np.array([np.sort_complex(exponents(v)) for v in speeds])
fig, ax = plt.subplots(figsize=(7, 5))
ax.plot(speeds, values.real, "k.", markersize=3)
ax.plot(speeds, np.abs(values.imag), "b.", markersize=2)
for v in (weave, capsize):
    ax.axvline(v, color="grey", linewidth=0.8)
ax.axvspan(weave, capsize, color="green", alpha=0.1, label="self-stable")
ax.set_ylim(-10, 10)
ax.set_xlabel("forward speed v [m/s]")
ax.set_ylabel("eigenvalue [1/s]: real (black), |imaginary| (blue)")
ax.legend(loc="lower left")

# %%
# A lean kick at a self-stable speed
# ----------------------------------
# At 4.6 m/s the bicycle is self-stable. Kicked sideways (every body leaning at 0.5 rad/s
# about the line through the wheels' contact points, so the wheels still roll), the full
# nonlinear model recovers: it steers into the fall and rights itself. For a small kick the
# run follows the linearization's prediction exp(A t) x₀.
q0, qd0 = mb.steady_motion(bicycle, {"rear.wheel.angle_y": 4.6 / R_REAR})
index = {c: i for i, c in enumerate(bicycle.coordinates)}


def kicked(rate):
    """The model file's initial velocities at 4.6 m/s with its parameter ``kick`` = rate: every
    body turning at that rate about the ground's x axis."""
    return bicycle.with_parameters(v=4.6, kick=rate).initial_state()[1]


lean, steer = index["rear_frame.angle_x"], index["front_frame.angle_z"]
run = mb.simulate(bicycle, 10.0, q0=q0, qd0=kicked(0.5), dt=0.01)
small = mb.simulate(bicycle, 6.0, q0=q0, qd0=kicked(0.005), dt=0.05)
lin = mb.linearize(bicycle, 0.0, q0, qd0)
x0 = np.linalg.lstsq(lin.state_map, np.concatenate([np.zeros(bicycle.n), kicked(0.005) - qd0]), rcond=None)[0]
predicted = np.array([lin.state_map @ (scipy.linalg.expm(lin.A * t) @ x0) for t in small.t])
gap = np.abs(small.q[:, lean] - q0[lean] - predicted[:, lean]).max()
print(f"largest lean {np.abs(run.q[:, lean]).max():.3f} rad, {np.abs(run.q[-1, lean]):.2e} rad after 10 s; "
      f"small kick against the linear prediction: {gap:.1e} rad of {np.abs(predicted[:, lean]).max():.1e}")
assert np.abs(run.q[-100:, lean]).max() < 0.1 * np.abs(run.q[:, lean]).max()
assert gap < 1e-2 * np.abs(predicted[:, lean]).max()

fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(run.t, run.q[:, lean], label="lean (rear frame)")
ax.plot(run.t, run.q[:, steer] - run.q[:, index["rear_frame.angle_z"]], label="front frame's heading - rear's")
ax.set_xlabel("t [s]")
ax.set_ylabel("[rad]")
ax.legend()

# %%
# The recovery in the viewer
# --------------------------
# The model file declares no geometry: the viewer draws the wheels from the rolling
# contacts and each body as rods from its centre of mass to its joints, and its camera
# follows the bicycle. The animation: :download:`bicycle_kick.html </gallery/bicycle_kick.html>`;
# from the command line, ``mbsynth view models/rolling/bicycle.yaml --set v=4.6 --set kick=0.5 --t-end 10``.
from mbsynth.view.screenshot import show_still

page = mb.viewer.to_html(bicycle, run, Path("bicycle_kick.html"))
fig, ax = plt.subplots(figsize=(7, 5))
if not show_still(ax, page, Path("bicycle_kick.png"), budget_ms=400):
    ax.plot(run.q[:, index["rear.wheel.x"]], run.q[:, index["rear.wheel.y"]])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("Chromium is not installed: the rear contact's track instead of the viewer's picture")
