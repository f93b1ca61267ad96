"""
A four-bar loop with a massless coupler
=======================================

The crank-rocker of ``models/mechanisms/four_bar.yaml`` (three planar bodies, four
revolute joints closing one loop: 9 coordinates, 8 rows of A, one degree of freedom), with
the coupler's mass and inertia set to zero by ``System.with_parameters(m2=0, I2=0)``.
The coupler's block of M vanishes, yet [M; A] keeps full column rank — both its ends
are pinned — so the motion is unique (Result 3) and (2.14) gives it directly.

Two independent checks: the mechanism's energy is conserved (no friction), and the
rocker follows the crank as the loop's geometry demands: C lies on the circle of
radius b about B = a(cos θ, sin θ) and on the circle of radius c about D = (d, 0).
"""

# %%
# The verdict with and without the coupler's mass
# -----------------------------------------------
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mbsynth as mb
from mbsynth.analysis.diagnose import diagnose
from mbsynth.model.joint_values import along

MODELS = Path("../../models")  # sphinx-gallery runs each script in its own folder
heavy = mb.load(MODELS / "mechanisms" / "four_bar.yaml")
system = heavy.with_parameters(m2=0.0, I2=0.0)
for label, s in (("coupler of 1.2 kg", heavy), ("massless coupler", system)):
    r = diagnose(s)
    print(f"{label}: rank M = {r.rank_M}, rank A = {r.rank_A}, rank [M; A] = {r.rank_Mhat} of {r.n}, "
          f"unique: {r.unique}")

# %%
# Four seconds from rest
# ----------------------
traj = mb.simulate(system, 4.0, dt=0.01)
p = system.parameters
a, b, c, d = p["a"], p["b"], p["c"], p["d"]
crank = along(system, traj.t, traj.q, traj.qd)["ground_O"].position[:, 0]  # the crank starts upright: θ = π/2
B = a * np.stack([np.cos(crank), np.sin(crank)], axis=1)
# C: the intersection of the circles |C − B| = b and |C − D| = c on the upper branch
D = np.array([d, 0.0])
BD = D - B
dist = np.linalg.norm(BD, axis=1)
along_BD = (b**2 - c**2 + dist**2) / (2 * dist)
height = np.sqrt(b**2 - along_BD**2)
unit = BD / dist[:, None]
normal = np.stack([-unit[:, 1], unit[:, 0]], axis=1)
C_exact = B + along_BD[:, None] * unit + height[:, None] * normal

i = {name: system.coordinates.index(name) for name in ("rocker.x", "rocker.y", "rocker.theta")}
th = traj.q[:, i["rocker.theta"]]
C_sim = np.stack([traj.q[:, i["rocker.x"]] + c / 2 * np.cos(th), traj.q[:, i["rocker.y"]] + c / 2 * np.sin(th)], axis=1)
loop_error = np.linalg.norm(C_sim - C_exact, axis=1).max()
print(f"crank turned {np.degrees(crank.max() - crank.min()):.1f}°; C off the loop's geometry by at most "
      f"{loop_error:.1e} m; relative energy drift {traj.energy_drift:.1e}")
assert loop_error < 1e-9 and traj.energy_drift < 1e-8, (loop_error, traj.energy_drift)

fig, (left, right) = plt.subplots(1, 2, figsize=(9, 3.8))
left.plot(traj.t, np.degrees(crank), label="crank angle θ")
left.plot(traj.t, np.degrees(np.arctan2(C_sim[:, 1], C_sim[:, 0] - d)), label="rocker angle")
left.set_xlabel("t [s]")
left.set_ylabel("degrees")
left.legend(fontsize="small")
right.semilogy(traj.t, np.linalg.norm(C_sim - C_exact, axis=1) + 1e-18, label="|C − C(θ)| [m]")
right.semilogy(traj.t, np.abs(traj.energy - traj.energy[0]) + 1e-18, label="|E − E(0)| [J]")
right.set_xlabel("t [s]")
right.legend(fontsize="small")
fig.suptitle("four-bar with a massless coupler")
fig.tight_layout()
