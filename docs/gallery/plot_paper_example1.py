"""
The wheel on an incline (the paper's example 1)
===============================================

A wheel of mass ``m``, radius ``R`` and moment of inertia ``Ic`` rolls without slipping down
an incline of angle ``alpha``. Modelled in two coordinates, its angle ``theta`` and its
height ``y`` (positive down the slope's vertical), the unconstrained mass matrix (5.6) is
singular: nothing in the kinetic energy moves with ``y`` alone. The rolling constraint
(5.8), ``y = R theta sin(alpha)``, differentiated twice gives the row (5.10) of ``A``, and
:func:`mbsynth.constrained_acceleration` solves (2.14) with the singular ``M`` directly.

The figure sweeps the incline angle and compares mbsynth's accelerations with the paper's
closed form (5.17): ``theta'' = m g R sin(alpha) / (m R^2 + Ic)``.
"""

import matplotlib.pyplot as plt
import numpy as np

import mbsynth as mb

m, R, Ic, g = 2.0, 0.3, 0.09, 9.81
M = np.diag([m * R**2 + Ic, 0.0])  # (5.6): singular
Q = np.array([0.0, m * g])  # (5.7)
b = np.zeros(1)  # (5.11)

alphas = np.linspace(0.0, np.pi / 2, 31)
theta_dd, y_dd = [], []
for alpha in alphas:
    A = np.array([[-R * np.sin(alpha), 1.0]])  # (5.10)
    r = mb.constrained_acceleration(M, Q, A, b)
    assert r.unique  # Result 3: [M; A] has full column rank
    theta_dd.append(r.qdd[0])
    y_dd.append(r.qdd[1])

closed_theta = m * g * R * np.sin(alphas) / (m * R**2 + Ic)  # (5.17)
closed_y = m * g * (R * np.sin(alphas)) ** 2 / (m * R**2 + Ic)
print(f"largest difference from (5.17): {max(np.max(np.abs(theta_dd - closed_theta)), np.max(np.abs(y_dd - closed_y))):.2e}")

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.plot(np.degrees(alphas), closed_theta, color="0.7", lw=4, label=r"(5.17) $\ddot\theta$")
ax.plot(np.degrees(alphas), theta_dd, "o", ms=3, label=r"mbsynth $\ddot\theta$ [rad/s²]")
ax.plot(np.degrees(alphas), closed_y, color="0.85", lw=4, label=r"(5.17) $\ddot y$")
ax.plot(np.degrees(alphas), y_dd, "s", ms=3, label=r"mbsynth $\ddot y$ [m/s²]")
ax.set_xlabel("incline angle alpha [deg]")
ax.set_ylabel("acceleration")
ax.set_title("Example 1: a singular M, a unique motion")
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()
