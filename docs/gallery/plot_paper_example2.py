"""
The paper's example 2: a particle without mass
==============================================

Example 1 (a wheel rolling down an incline, described by its turning angle θ and its
drop y, joined by the rolling constraint y = R θ sin α) plus a particle of zero mass
moving along x, (5.18)–(5.21). Now [M; A] loses rank: the particle's direction is in
its null space. No force acts along it, so the balance wᵀ(Q + C) = 0 holds by itself
and the particle's acceleration is simply arbitrary, (5.23): ``mbsynth check`` calls
the direction *free*. With η = 0 in (2.14) the run gives it none, and the wheel
rolls exactly as in example 1, with the constant accelerations (5.17).
"""

# %%
# The verdict
# -----------
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mbsynth as mb
from mbsynth.cli.check import format_check
from mbsynth.analysis.diagnose import diagnose

MODELS = Path("../../models")  # sphinx-gallery runs each script in its own folder
system = mb.load(MODELS / "paper" / "example2_massless_particle.yaml")
report = diagnose(system)
print(format_check(report, "example2_massless_particle.yaml"))
assert not report.unique and report.rank_Mhat == 2

# %%
# The wheel's accelerations are those of example 1, (5.17)
# --------------------------------------------------------
# θ̈ = m g R sin α / (m R² + Ic), ÿ = R sin α θ̈.
p = system.parameters
m, R, Ic, g, alpha = p["m"], p["R"], p["Ic"], p["g"], p["alpha"]
theta_dd = m * g * R * np.sin(alpha) / (m * R**2 + Ic)
y_dd = R * np.sin(alpha) * theta_dd
q, qd = system.initial_state()
motion = system.motion(0.0, q, qd)
print("q̈ =", ", ".join(f"{c} = {v:.6g}" for c, v in zip(system.coordinates, motion.qdd)))
print(f"(5.17): θ̈ = {theta_dd:.6g}, ÿ = {y_dd:.6g}")
assert np.allclose(motion.qdd[:2], [theta_dd, y_dd], rtol=1e-12)
print("null space of [M; A] (the free direction):", motion.nullspace.ravel())

# %%
# Two seconds of motion
# ---------------------
# From rest, y(t) = ÿ t²/2; the particle stays where it is.
traj = mb.simulate(system, 2.0, dt=0.02)
y_exact = 0.5 * y_dd * traj.t**2
print(f"largest |y − ÿt²/2| = {np.abs(traj.column('wheel.y') - y_exact).max():.1e} m")
assert np.allclose(traj.column("wheel.y"), y_exact, atol=1e-9)

fig, (left, right) = plt.subplots(1, 2, figsize=(9, 3.6))
left.plot(traj.t, traj.column("wheel.y"), label="wheel.y, simulated")
left.plot(traj.t, y_exact, "k:", label="ÿ t²/2, (5.17)")
left.plot(traj.t, traj.column("particle.x"), label="particle.x (free, η = 0)")
left.set_xlabel("t [s]")
left.set_ylabel("m")
left.legend(fontsize="small")
sigma = np.linalg.svd(np.vstack([system.evaluate(0.0, q, qd).M, system.evaluate(0.0, q, qd).A]), compute_uv=False)
right.bar(range(1, len(sigma) + 1), sigma + 1e-17)
right.set_yscale("log")
right.set_xticks(range(1, len(sigma) + 1))
right.set_xlabel("singular value of [M; A]")
right.set_title("rank 2 of 3: one free direction", fontsize="medium")
fig.tight_layout()
