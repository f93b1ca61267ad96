"""
A slider-crank
==============

``models/mechanisms/slider_crank.yaml``: crank OB = a about the origin, connecting rod
BC = b, a slider C on a rail at height e (a prismatic joint), gravity along −y, released
from rest with the crank at 1 rad. Three planar bodies, three revolute joints and a
prismatic one: one degree of freedom, and a closed loop through the world.

The joints' own values (``System.joint_values``, along a run ``mbsynth.model.joint_values.along``)
give the crank angle θ and the slider's displacement; the loop's geometry gives the
slider's position in closed form, x(θ) = a cos θ + √(b² − (e − a sin θ)²), and the run
must conserve energy. The reactions (``System.reactions``) give the rail's load on the
slider.
"""

# %%
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mbsynth as mb
from mbsynth.model.joint_values import along

MODELS = Path("../../models")  # sphinx-gallery runs each script in its own folder
system = mb.load(MODELS / "mechanisms" / "slider_crank.yaml")
traj = mb.simulate(system, 3.0, dt=0.01)
values = along(system, traj.t, traj.q, traj.qd)
theta = values["ground_O"].position[:, 0]  # the crank angle (both frames along the world's axes at θ = 0)
p = system.parameters
a, b, e = p["a"], p["b"], p["e"]
x_exact = a * np.cos(theta) + np.sqrt(b**2 - (e - a * np.sin(theta)) ** 2)
x_sim = traj.column("slider.x")
print(f"largest |x − x(θ)| = {np.abs(x_sim - x_exact).max():.1e} m; relative energy drift {traj.energy_drift:.1e}")
assert np.abs(x_sim - x_exact).max() < 1e-9 and traj.energy_drift < 1e-8, (np.abs(x_sim - x_exact).max(), traj.energy_drift)

# %%
# The rail's reaction on the slider
# ---------------------------------
# In the child frame's axes (the guide frame: x along the rail); across the rail it holds
# the slider up against gravity and the rod's push.
rail = np.array([system.reactions(t, q, qd)["rail"].force for t, q, qd in zip(traj.t, traj.q, traj.qd)])

fig, (left, mid, right) = plt.subplots(1, 3, figsize=(11, 3.4))
left.plot(traj.t, np.degrees(theta))
left.set_xlabel("t [s]")
left.set_ylabel("crank angle θ [°]")
mid.plot(np.degrees(theta), x_sim, label="slider, mbsynth")
mid.plot(np.degrees(theta), x_exact, "k:", label="a cos θ + √(b² − (e − a sin θ)²)")
mid.set_xlabel("θ [°]")
mid.set_ylabel("slider x [m]")
mid.legend(fontsize="x-small")
right.plot(traj.t, rail[:, 0], label="along x")
right.plot(traj.t, rail[:, 1], label="along y")
right.set_xlabel("t [s]")
right.set_ylabel("rail force on slider [N]")
right.legend(fontsize="small")
fig.tight_layout()
