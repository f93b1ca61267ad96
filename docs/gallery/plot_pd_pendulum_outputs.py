"""
Outputs and a PD controller
===========================

``models/joints/pd_pendulum.yaml``: a rod hinged at its top, driven by a PD law written
on the joint's own values, ``actuation: -kp*(hinge.angle - target) - kd*hinge.rate``. It
settles where the law balances gravity, kp (θ − target) = −m g (L/2) sin θ.

Named outputs are evaluated along the run and kept with the trajectory (and in its
.npz/.csv files): here the hinge angle, the hinge's reaction force on the rod and the
kinetic energy, added to the model's text under ``outputs:``. At rest the hinge carries
the rod's weight: the load's magnitude is m g.

The same law can instead be a Python function of the joint values, sampled every 10 ms
and held in between (``simulate(controller=..., control_dt=...)``), as a digital
controller would: here it also moves the target from 0.5 to 0.2 rad at t = 3 s.
"""

# %%
# The law in the model file, with outputs
# ---------------------------------------
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq

import mbsynth as mb

MODELS = Path("../../models")  # sphinx-gallery runs each script in its own folder
text = (MODELS / "joints" / "pd_pendulum.yaml").read_text()
outputs = """
outputs:
  angle: hinge.angle
  load: {reaction: hinge.force}
  kinetic: {energy: kinetic}
"""
system = mb.loads(text + outputs, name="pd_pendulum with outputs")
traj = mb.simulate(system, 6.0, dt=0.02)
print("outputs:", ", ".join(traj.output_names))

p = system.parameters
m, g, L, kp = p["m"], p["g"], p["L"], p["kp"]


def rest_angle(target):
    return brentq(lambda x: kp * (x - target) + m * g * L / 2 * np.sin(x), -np.pi / 2, np.pi / 2)


load = np.stack([traj.column(f"load[{c}]") for c in "xyz"], axis=1)
print(f"final angle {traj.column('angle')[-1]:.9f} rad, balance {rest_angle(p['target']):.9f} rad; "
      f"hinge load {np.linalg.norm(load[-1]):.6f} N, m g = {m * g:.6f} N")
assert abs(traj.column("angle")[-1] - rest_angle(p["target"])) < 1e-7
assert abs(np.linalg.norm(load[-1]) - m * g) < 1e-6

# %%
# The law in Python, sampled every 10 ms
# --------------------------------------
# The model's actuation becomes a parameter ``tau`` that the controller sets.
sampled = mb.loads(text.replace("target: 0.5}", "target: 0.5, tau: 0.0}")
                   .replace("actuation: -kp*(hinge.angle - target) - kd*hinge.rate", "actuation: tau"),
                   name="pd_pendulum, sampled")


def controller(t, values):
    theta, rate = values["hinge"].position[0], values["hinge"].rate[0]
    target = 0.5 if t < 3.0 else 0.2
    return {"tau": -kp * (theta - target) - p["kd"] * rate}


run = mb.simulate(sampled, 6.0, dt=0.02, controller=controller, control_dt=0.01)
angle = np.array([sampled.joint_values(t, q, qd)["hinge"].position[0] for t, q, qd in zip(run.t, run.q, run.qd)])
print(f"sampled law: {angle[-1]:.6f} rad at t = 6 s, balance for target 0.2: {rest_angle(0.2):.6f} rad")
assert abs(angle[-1] - rest_angle(0.2)) < 1e-5

fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.8))
left.plot(traj.t, traj.column("angle"), label="law in the model (output 'angle')")
left.plot(run.t, angle, label="sampled law in Python, target → 0.2 at 3 s")
for target in (0.5, 0.2):
    left.axhline(rest_angle(target), color="k", ls=":", lw=0.8)
left.set_xlabel("t [s]")
left.set_ylabel("hinge angle [rad]")
left.legend(fontsize="x-small")
right.plot(traj.t, np.linalg.norm(load, axis=1), label="|hinge load| (output 'load')")
right.axhline(m * g, color="k", ls=":", lw=0.8, label="m g")
right.plot(traj.t, traj.column("kinetic"), label="kinetic energy [J] (output 'kinetic')")
right.set_xlabel("t [s]")
right.legend(fontsize="x-small")
fig.tight_layout()
