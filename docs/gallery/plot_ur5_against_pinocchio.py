"""
A UR5 falling under gravity, against Pinocchio
==============================================

``mb.from_robot("ur5")`` decomposes the robot of example-robot-data into parts: every
link a rigid body in its own seven coordinates (centre of mass and unit quaternion),
every URDF joint a joint between frames on two links, the base welded to the world.
Unpowered (all ``tau_<joint>`` = 0) it falls from its zero configuration.

The reference is Pinocchio on Pinocchio's own model of the same URDF (its parser, not
mbsynth's): the articulated-body algorithm ``pinocchio.aba`` integrated with scipy.
mbsynth's joint angles are read off the links' coordinates by ``System.joint_values``
(along a run: ``mbsynth.model.joint_values.along``); its joint reactions by
``System.reactions``, compared with the joint wrenches ``data.f`` of ``pinocchio.rnea``.
"""

# %%
# Six tenths of a second of falling, twice
# ----------------------------------------
import matplotlib.pyplot as plt
import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

import mbsynth as mb
from mbsynth.model.joint_values import along

robot = mb.from_robot("ur5", floating=False)
print(f"{robot.name}: {len(robot.parts)} parts, n = {robot.n} coordinates, {len(robot.constraints)} constraints")
traj = mb.simulate(robot, 0.6, dt=0.02)
values = along(robot, traj.t, traj.q, traj.qd)

model = pin.buildModelFromUrdf(str(robot.robots[0].description.path))
data = model.createData()
joints = [model.names[i] for i in range(1, model.njoints)]


def falling(t, y):
    q, v = y[: model.nq], y[model.nq :]
    return np.concatenate([v, pin.aba(model, data, q, v, np.zeros(model.nv))])


reference = solve_ivp(falling, (0.0, 0.6), np.zeros(model.nq + model.nv), t_eval=traj.t, method="DOP853",
                      rtol=1e-11, atol=1e-11)
angles = np.stack([values[name].position[:, 0] for name in joints], axis=1)
error = np.abs(angles - reference.y[: model.nq].T).max()
print(f"largest joint-angle difference from Pinocchio over 0.6 s: {error:.1e} rad")
assert error < 1e-7

fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
for k, name in enumerate(joints):
    line, = left.plot(traj.t, angles[:, k], label=name)
    left.plot(traj.t, reference.y[k], ":", color="k")
left.set_xlabel("t [s]")
left.set_ylabel("joint angle [rad]")
left.set_title("mbsynth (lines), Pinocchio aba (dotted)", fontsize="medium")
left.legend(fontsize="x-small")
right.semilogy(traj.t, np.abs(angles - reference.y[: model.nq].T) + 1e-18)
right.set_xlabel("t [s]")
right.set_title("|mbsynth − Pinocchio| per joint [rad]", fontsize="medium")
fig.tight_layout()

# %%
# Joint reactions against ``rnea``
# --------------------------------
# At the last state, each joint's reaction — the wrench the parent link exerts on the
# child through the joint, at the child link's frame, in its axes — against Pinocchio's
# ``data.f`` after ``rnea(q, v, aba(q, v, 0))``.
t, q, qd = traj.t[-1], traj.q[-1], traj.qd[-1]
reactions = robot.reactions(t, q, qd)
pq, pv = reference.y[: model.nq, -1], reference.y[model.nq :, -1]
pin.rnea(model, data, pq, pv, pin.aba(model, data, pq, pv, np.zeros(model.nv)))
for i, name in enumerate(joints, start=1):
    ours = np.concatenate([reactions[name].force, reactions[name].torque])
    theirs = data.f[i].vector
    print(f"{name:20s} force {np.array2string(reactions[name].force, precision=3, suppress_small=True):28s} "
          f"differs from rnea by {np.abs(ours - theirs).max():.1e}")
    assert np.abs(ours - theirs).max() < 1e-6 * max(1.0, np.abs(theirs).max())

# %%
# The robot in the viewer
# -----------------------
# The offline animation: :download:`ur5_falling.html </gallery/ur5_falling.html>`; a still
# of it from headless Chromium (``mbsynth.view.screenshot``; without Chromium, the joint
# angles are drawn instead).
from pathlib import Path

from mbsynth.view.screenshot import show_still

page = mb.viewer.to_html(robot, traj, Path("ur5_falling.html"))
fig, ax = plt.subplots(figsize=(7, 5))
if not show_still(ax, page, Path("ur5_falling.png"), budget_ms=400):
    ax.plot(traj.t, angles)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("joint angle [rad]")
    ax.set_title("Chromium is not installed: joint angles instead of the viewer's picture")
