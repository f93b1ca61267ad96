"""
The paper's example 3: a massless node between two springs
==========================================================

Two masses and two springs, modelled as two parts joined by the connection
constraint q1 = x1 + d, (5.32). The unconstrained mass matrix (5.33) is singular whatever
the masses. With the first mass removed (m1 = 0, case 5.2) the rank of [M; A] drops and
the missing equation is the force balance of the massless node, (5.40):
k1 (x1 − l10) = k2 (q2 − l20). ``balances: auto`` derives it from the null space of [M; A]
and appends it; the motion is then (5.47), unique by Result 3.

The node follows the mass m2 through the springs in series: with
s = (x1 − l10) + (q2 − l20),

.. math:: m_2 \\ddot s = -\\frac{k_1 k_2}{k_1 + k_2} s,
   \\qquad x_1 - l_{10} = \\frac{k_2}{k_1 + k_2} s, \\qquad q_2 - l_{20} = \\frac{k_1}{k_1 + k_2} s,

a harmonic oscillator we compare the simulation with.
"""

# %%
# The model and its verdict
# -------------------------
# ``models/paper/example3_m1_zero_auto.yaml`` is example 3 with ``m1: 0.0`` and
# ``balances: auto``. ``mbsynth check`` prints the same report.
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mbsynth as mb
from mbsynth.cli.check import format_check
from mbsynth.analysis.diagnose import diagnose

MODELS = Path("../../models")  # sphinx-gallery runs each script in its own folder
system = mb.load(MODELS / "paper" / "example3_m1_zero_auto.yaml")
print(format_check(diagnose(system), "example3_m1_zero_auto.yaml"))

# %%
# The accelerations against the closed form (5.47)
# ------------------------------------------------
q, qd = system.initial_state()
p = system.parameters
k1, k2, m2 = p["k1"], p["k2"], p["m2"]
s0 = (q[0] - p["l10"]) + (q[2] - p["l20"])
closed_form = np.array([-k1 * k2**2 * s0, -k1 * k2**2 * s0, -(k1**2) * k2 * s0]) / (m2 * (k1 + k2) ** 2)
qdd = system.motion(0.0, q, qd).qdd
print("q̈ from (2.15):      ", qdd)
print("q̈ closed form (5.47):", closed_form)
assert np.allclose(qdd, closed_form, rtol=1e-10, atol=0)

# %%
# Motion over four seconds
# ------------------------
# The node x1 and the spring length q2 against the oscillator above (the model starts
# at rest, so s(t) = s0 cos ωt).
traj = mb.simulate(system, 4.0, dt=1 / 30)
omega = np.sqrt(k1 * k2 / ((k1 + k2) * m2))
s = s0 * np.cos(omega * traj.t)
x1 = p["l10"] + k2 / (k1 + k2) * s
q2 = p["l20"] + k1 / (k1 + k2) * s
error = max(np.abs(traj.column("body1.x1") - x1).max(), np.abs(traj.column("body2.q2") - q2).max())
print(f"ω = {omega:.6f} rad/s; largest difference from the closed form {error:.1e} m")
assert error < 1e-8

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
top.plot(traj.t, traj.column("body1.x1"), label="x1 (massless node), simulated")
top.plot(traj.t, traj.column("body2.q2"), label="q2 (spring 2), simulated")
top.plot(traj.t, x1, "k:", label="closed form")
top.plot(traj.t, q2, "k:")
top.set_ylabel("m")
top.legend(loc="upper right", fontsize="small")
bottom.semilogy(traj.t, np.abs(traj.column("body1.x1") - x1) + 1e-18, label="|x1 − closed form|")
bottom.semilogy(traj.t, traj.residual_position + 1e-18, label="constraint residual")
bottom.set_xlabel("t [s]")
bottom.legend(fontsize="small")
fig.suptitle("example 3, m1 = 0: the node follows m2 through its balance (5.40)")
fig.tight_layout()

# %%
# The scene in the viewer
# -----------------------
# ``mb.viewer.to_html`` writes the animation as one self-contained page that plays
# offline: :download:`example3_m1_zero.html </gallery/example3_m1_zero.html>`. Below, a
# still of it taken with headless Chromium (``mbsynth.view.screenshot``, as
# ``scripts/readme_pictures.py`` takes the README's pictures; ``scripts/install-chromium.sh``
# installs Chromium). Without Chromium the masses' positions are drawn instead.
from mbsynth.view.screenshot import show_still

page = mb.viewer.to_html(system, traj, Path("example3_m1_zero.html"))
fig, ax = plt.subplots(figsize=(7, 5))
if not show_still(ax, page, Path("example3_m1_zero.png"), budget_ms=1500):
    ax.plot(traj.t, traj.column("body1.x1") + p["d"] / 2, label="mass 1 (massless)")
    ax.plot(traj.t, traj.column("body2.q1") + traj.column("body2.q2") + p["d"] / 2, label="mass 2")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("x [m]")
    ax.legend()
    ax.set_title("Chromium is not installed: positions instead of the viewer's picture")
