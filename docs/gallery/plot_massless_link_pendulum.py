"""
A pendulum on a massless link
=============================

A particle hangs from a fixed pivot on a rigid link of zero mass and zero inertia
(``models/mechanisms/massless_link.yaml``): the link is a ``rigid_body`` in its own seven
coordinates, joined to the world and to the bob by spherical joints. Its mass-matrix
block is zero, which the singular-mass equation (2.14) takes as it is. One direction is
left indeterminate — the link spinning about its own axis — and it is *free*: no force
acts along it, so no balance is needed and η = 0 gives it no acceleration.

The bob must move as a spherical pendulum of length L. We give it a sideways velocity
and compare with an independent integration of that pendulum in Cartesian coordinates,
``r̈ = g − λ r`` with ``λ = (ṙ·ṙ + r·g)/L²`` (the rod's tension per unit mass, from
d²/dt² (r·r) = 0), done with scipy alone.
"""

# %%
# The model, with a sideways push
# -------------------------------
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import mbsynth as mb
from mbsynth.analysis.diagnose import diagnose

MODELS = Path("../../models")  # sphinx-gallery runs each script in its own folder
text = (MODELS / "mechanisms" / "massless_link.yaml").read_text()
start = "initial: {position: ['-L*sin(0.3)*cos(0.5)'"
assert start in text
system = mb.loads(text.replace(start, "initial: {velocity: [-1.3, -0.7, 0], position: ['-L*sin(0.3)*cos(0.5)'"),
                  name="massless_link, pushed")
report = diagnose(system)
print(f"rank [M; A] = {report.rank_Mhat} of {report.n}; indeterminate directions: {len(report.indeterminate)}")
print("the free direction:", ", ".join(f"{k} {v:+.3g}" for k, v in report.indeterminate[0].items()))

# %%
# Three seconds of motion against the spherical pendulum
# ------------------------------------------------------
traj = mb.simulate(system, 3.0, dt=0.02)
p = system.parameters
L, g = p["L"], np.array([0.0, 0.0, -p["g"]])
pivot = np.array([0.0, 0.0, 2.0])
bob = [system.coordinates.index(f"bob.{c}") for c in "xyz"]
r0, v0 = traj.q[0, bob] - pivot, traj.qd[0, bob]


def spherical_pendulum(t, y):
    r, v = y[:3], y[3:]
    tension = (v @ v + r @ g) / L**2
    return np.concatenate([v, g - tension * r])


reference = solve_ivp(spherical_pendulum, (0, 3.0), np.concatenate([r0, v0]), t_eval=traj.t,
                      method="DOP853", rtol=1e-12, atol=1e-12)
r = traj.q[:, bob] - pivot
error = np.linalg.norm(r - reference.y[:3].T, axis=1)
print(f"largest distance from the reference path: {error.max():.1e} m")
print(f"rod length held to {np.abs(np.linalg.norm(r, axis=1) - L).max():.1e} m; "
      f"relative energy drift {traj.energy_drift:.1e}")
assert error.max() < 1e-7 and traj.energy_drift < 1e-9

fig = plt.figure(figsize=(9, 4))
top = fig.add_subplot(1, 2, 1)
top.plot(r[:, 0], r[:, 1], label="bob, mbsynth")
top.plot(reference.y[0], reference.y[1], "k:", label="spherical pendulum, scipy")
top.set_aspect("equal")
top.set_xlabel("x [m]")
top.set_ylabel("y [m]")
top.set_title("seen from above", fontsize="medium")
top.legend(fontsize="small")
right = fig.add_subplot(1, 2, 2)
right.semilogy(traj.t, error + 1e-18, label="distance from the reference")
right.semilogy(traj.t, np.abs(traj.energy - traj.energy[0]) + 1e-18, label="|E − E(0)| [J]")
right.set_xlabel("t [s]")
right.legend(fontsize="small")
fig.tight_layout()
