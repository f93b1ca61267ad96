"""
Modes: a double pendulum and a massless node
============================================

``mb.modes`` linearizes the motion at rest on the constraints' tangent space — the null
space of the position rows' Jacobian, so redundant coordinates, quaternion norms and a
massless node fixed by its balance drop out by themselves — and returns natural
frequencies, damping ratios and mode shapes (``mb.linearize`` gives the matrices).

A double pendulum of two equal particles m on two massless rods of length l
(``distance`` joints), hanging at rest, has the closed-form frequencies
ω² = (2 ∓ √2) g/l, each twice (two planes of swing); in the slow mode the lower particle
swings 1 + √2 times as far as the upper one, in the fast mode 1 − √2 times. The paper's
example 3 with its massless node (m1 = 0, closed by its balance (5.40)) has one mode,
the mass m2 on the two springs in series: ω² = k1 k2 / ((k1 + k2) m2).
"""

# %%
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import mbsynth as mb
from mbsynth.analysis.modes import format_modes

double = mb.load(Path("../../models/mechanisms/double_pendulum_rods.yaml"))
result = mb.modes(double, equilibrium=True)  # the rest position found from the initial one
print(format_modes(result))

p = double.parameters
closed_form = np.sqrt(np.array([2 - np.sqrt(2)] * 2 + [2 + np.sqrt(2)] * 2) * p["g"] / p["l"]) / (2 * np.pi)
print("closed form [Hz]:", np.round(closed_form, 6))
assert np.allclose(result.frequencies, closed_form, rtol=1e-8)

# %%
# The massless node of example 3
# ------------------------------
MODELS = Path("../../models")  # sphinx-gallery runs each script in its own folder
node = mb.load(MODELS / "paper" / "example3_m1_zero_auto.yaml")
node_modes = mb.modes(node, equilibrium=True)
print(format_modes(node_modes))
q = node.parameters
omega = np.sqrt(q["k1"] * q["k2"] / ((q["k1"] + q["k2"]) * q["m2"]))
assert np.isclose(node_modes.frequencies[0], omega / (2 * np.pi), rtol=1e-8)

# %%
# Mode shapes against the closed form
# -----------------------------------
# Both shapes drawn in their plane of swing (linear displacements, exaggerated), and the
# frequencies beside the closed forms.
fig, (left, right) = plt.subplots(1, 2, figsize=(9, 5))
index = {c: double.coordinates.index(c) for c in double.coordinates}
for mode, ratio, color in ((result.modes[0], 1 + np.sqrt(2), "C0"), (result.modes[2], 1 - np.sqrt(2), "C1")):
    upper = mode.shape[[index["p1.x"], index["p1.y"]]]
    lower = mode.shape[[index["p2.x"], index["p2.y"]]]
    assert np.allclose(lower, ratio * upper, atol=1e-8 * np.abs(lower).max())
    upper, lower = upper.real, lower.real  # a swing in one plane (the pair's shapes may mix two)
    across = upper / np.linalg.norm(upper)  # the plane of swing
    a = 0.3 * p["l"] / np.abs(lower @ across)
    xs = [0.0, a * upper @ across, a * lower @ across]
    left.plot(xs, [0.0, -p["l"], -2 * p["l"]], "o-", color=color,
              label=f"{mode.frequency:.4f} Hz, lower/upper = {lower @ across / (upper @ across):+.4f}")
left.plot([0, 0, 0], [0, -p["l"], -2 * p["l"]], "o-", color="grey", alpha=0.4, label="at rest")
left.set_aspect("equal")
left.set_xlabel("across [m]")
left.set_ylabel("z [m]")
left.set_title("shapes; closed form 1 ± √2", fontsize="medium")
left.legend(fontsize="x-small", loc="upper center", bbox_to_anchor=(0.5, -0.18))

right.plot([0, 0], result.frequencies[[0, 2]], "o", ms=10, label="mb.modes")
right.plot([0, 0], closed_form[[0, 2]], "kx", ms=10, label="closed form")
right.plot([1], node_modes.frequencies[:1], "o", ms=10, color="C0")
right.plot([1], [omega / (2 * np.pi)], "kx", ms=10)
right.set_xticks([0, 1], ["double pendulum\n(slow, fast)", "example 3, m1 = 0"])
right.set_xlim(-0.5, 1.5)
right.set_ylabel("frequency [Hz]")
right.legend()
fig.tight_layout()
