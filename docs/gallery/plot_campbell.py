"""
Campbell diagram: a spinning blade
==================================

A uniform cantilever blade (``models/flexible/rotating_blade.yaml``: 10 m, flapwise
EI = 1.4e4 N m², lead-lag four times that, ρA = 1.2 kg/m, 6 Craig–Bampton modes, centrifugal
stiffening) is clamped at the hub axis and driven about the world z axis at the rate
``Omega``. Its frame turns by the angles ``xyz``, the spin last: the spin angle is cyclic,
so the spinning blade is a steady motion and ``mb.modes(..., steady=True)`` gives its
frequencies. ``mb.campbell`` sweeps the spin rate, follows each mode by its shape (MAC)
and marks where a mode meets the order lines f = kΩ/2π.

The flapwise frequency rises as Southwell's ω² ≈ ω₀² + 1.193 Ω², the lead-lag one as
ω₀² + 0.193 Ω²; the flapwise branch overtakes the lead-lag one near 7 rad/s and, as
1.193 > 1, never meets 1P.
"""

# %%
from pathlib import Path

import numpy as np

import mbsynth as mb
from mbsynth.analysis.campbell import figure, format_campbell

blade = mb.load(Path("../../models/flexible/rotating_blade.yaml"))  # sphinx-gallery runs in its own folder
result = mb.campbell(blade, "Omega", np.linspace(0.0, 12.0, 25), orders=3)
print(format_campbell(result))

# %%
# Southwell's coefficients against the swept frequencies
# -------------------------------------------------------
# (Southwell's form is a first-order estimate: flapwise it lies 3e-3 above the converged
# rotating cantilever at Ω = ω₀; tests/model/flexible/test_rotating_blade.py.)
rates = result.values
for branch, name, K in ((0, "flapwise", 1.193), (1, "lead-lag", 0.193)):
    omega = 2 * np.pi * result.frequencies[:, branch]
    southwell = np.sqrt(omega[0] ** 2 + K * rates ** 2)
    print(f"{name}: Southwell's form within {np.max(np.abs(southwell / omega - 1)):.2e} up to "
          f"{rates[-1]:g} rad/s")

drawing = figure(result, top=2.5)  # the two lowest modes and the order lines
