"""
The heavy top in quaternion coordinates
=======================================

A symmetric top (Lagrange's top) on a fixed point: a ``rigid_body`` in seven
coordinates — its centre of mass and a unit quaternion (w, x, y, z) — held at its tip
by a spherical joint to the world. Four numbers for three rotational degrees of freedom:
the body's rotational mass block 4EᵀJE (the paper's rigid-body example) is singular, of
rank 3, and the unit-norm row the body adds itself closes it, so [M; A] has full rank.

Nothing dissipates, so three quantities must stay constant: the energy, the angular
momentum about the vertical through the fixed point, and the spin about the top's own
axis (its two equal moments make it a Lagrange top). The quaternion's norm must stay 1;
drift control puts the state back onto the constraints (unit norm included) at every
accepted step of the integrator and every output row (a tree: the compiled kernel does it).
"""

# %%
from textwrap import dedent

import matplotlib.pyplot as plt
import numpy as np

import mbsynth as mb

top = mb.loads(dedent("""
    name: heavy_top
    parameters: {m: 0.5, l: 0.1, A: 2.0e-3, C: 0.8e-3, g: 9.81, tilt: 0.3, spin: 60.0}
    gravity: [0, 0, -g]
    parts:
      top:
        type: rigid_body
        mass: m
        inertia: [A, A, C]                 # about the centre of mass; z is the symmetry axis
        frames: {tip: {position: [0, 0, -l]}}
        initial:
          position: [l*sin(tilt), 0, l*cos(tilt)]
          rpy: [0, tilt, 0]
          angular_velocity: [spin*sin(tilt), 0, spin*cos(tilt)]   # world axes: about the top's own axis
    joints:
      - {name: pivot, type: spherical, parent: world, child: top.tip}
    """))
print("coordinates:", ", ".join(top.coordinates))
traj = mb.simulate(top, 2.0, dt=0.005)

# %%
# The invariants along the run
# ----------------------------
# From the coordinates alone: R(u) from the quaternion, ω_body = 2 (ū ⊗ u̇) (its vector
# part), the angular momentum about the fixed point H = R J_tip ω_body.
p = top.parameters
m, l, A, C = p["m"], p["l"], p["A"], p["C"]
J_tip = np.diag([A + m * l**2, A + m * l**2, C])
u, ud = traj.q[:, 3:7], traj.qd[:, 3:7]


def rotation(w, x, y, z):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def body_rate(u, ud):
    w, v = u[0], -u[1:]  # conjugate of u, times u̇
    return 2 * (w * ud[1:] + ud[0] * v + np.cross(v, ud[1:]))


omega = np.array([body_rate(a, b) for a, b in zip(u, ud)])
H_z = np.array([(rotation(*a) @ J_tip @ w)[2] for a, w in zip(u, omega)])
axis_z = np.array([rotation(*a)[2, 2] for a in u])
norm_error = np.abs(np.linalg.norm(u, axis=1) - 1)
drifts = {"energy": traj.energy_drift, "vertical angular momentum": np.abs(H_z - H_z[0]).max() / abs(H_z[0]),
          "spin ω3": np.abs(omega[:, 2] - omega[0, 2]).max() / abs(omega[0, 2]), "|u| − 1": norm_error.max()}
for name, value in drifts.items():
    print(f"relative drift of {name}: {value:.1e}")
assert max(drifts.values()) < 1e-8

fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.8))
left.plot(traj.t, np.degrees(np.arccos(axis_z)))
left.set_xlabel("t [s]")
left.set_ylabel("tilt of the axis [°]")
left.set_title("nutation", fontsize="medium")
right.semilogy(traj.t, np.abs(traj.energy - traj.energy[0]) / abs(traj.energy[0]) + 1e-18, label="energy")
right.semilogy(traj.t, np.abs(H_z - H_z[0]) / abs(H_z[0]) + 1e-18, label="vertical angular momentum")
right.semilogy(traj.t, norm_error + 1e-18, label="|u| − 1")
right.set_xlabel("t [s]")
right.set_title("relative drift", fontsize="medium")
right.legend(fontsize="small")
fig.tight_layout()
