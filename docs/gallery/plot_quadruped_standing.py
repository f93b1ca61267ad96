"""
A quadruped standing on its feet
================================

Solo12 (example-robot-data), a floating base on four legs of three joints each, stands on
the ground: each foot is a point contact with Coulomb friction (``contacts:``), and each
joint is held at its standing angle by a servo row (``holonomic: solo_FL_HFE.angle − 0.8``),
so the robot is one rigid body resting on four points — a statically indeterminate stand.
Its motion is unique all the same (Result 3 of the paper: the accelerations are, the
contact forces need not be): the run picks the smallest set of feet that holds with
λ ≥ 0 (``analysis/impacts.py``), sticking within the friction cones (``analysis/cones.py``),
and the robot stays at rest. Whatever feet carry it, their normal forces add up to its
weight m g, and their friction forces to zero: checked below.
"""

# %%
# The model: the robot, four foot contacts and twelve servo rows
# --------------------------------------------------------------
import matplotlib.pyplot as plt
import numpy as np
import pinocchio as pin

import mbsynth as mb
from mbsynth.robots.twin import Twin

FEET = ("FL", "FR", "HL", "HR")
STANCE = {"HAA": (0.0, 0.0, 0.0, 0.0), "HFE": (0.8, 0.8, -0.8, -0.8), "KFE": (-1.6, -1.6, 1.6, 1.6)}
contacts = "\n".join(f"  - {{name: {f}, type: plane, child: solo_{f}_FOOT.link, ground: h, friction: 0.8}}"
                     for f in FEET)
outputs = "\n".join(f"  {f}: {{contact: {f}.force}}" for f in FEET)
servos = "\n".join(f"  - {{name: hold_{f}_{j}, holonomic: solo_{f}_{j}.angle - ({angles[k]})}}"
                   for j, angles in STANCE.items() for k, f in enumerate(FEET))
text = f"""name: solo_standing
parameters: {{h: -1.0}}
gravity: [0, 0, -9.81]
parts:
  solo: {{type: robot, robot: solo12, floating: true}}
contacts:
{contacts}
outputs:
{outputs}
"""
# loaded with the ground below the feet (h = −1), then set on it at the standing pose
free = mb.loads(text).with_parameters(h=0.0)
standing = mb.loads(text + "constraints:\n" + servos + "\n").with_parameters(h=0.0)

# %%
# The standing pose, from Pinocchio's model of the same URDF: the base lowered until the
# feet touch z = 0; its maximal coordinates through the robot's twin (the robot alone)
robot = pin.buildModelFromUrdf(standing.robots[0].description.path, pin.JointModelFreeFlyer())
frames = robot.createData()
q = np.r_[0, 0, 0, 0, 0, 0, 1.0, [STANCE[j][k] for k in range(4) for j in ("HAA", "HFE", "KFE")]]
pin.framesForwardKinematics(robot, frames, q)
q[2] -= np.mean([frames.oMf[robot.getFrameId(f"{f}_FOOT")].translation[2] for f in FEET])
q0, qd0 = Twin(free).to_maximal(q, np.zeros(robot.nv))

# %%
# Standing for a while
# --------------------
run = mb.simulate(standing, 0.3, q0=q0, qd0=qd0, dt=0.01)
held = sorted({ev.name for ev in run.events if ev.kind == "contact"})
weight = pin.computeTotalMass(robot) * 9.81
normal = np.array([run.column(f) for f in FEET]).T  # a column per foot
print(f"feet held: {held}; their normal forces at rest: { {f: round(float(x), 4) for f, x in zip(FEET, normal[-1])} } N")
print(f"total {normal[-1].sum():.10f} N against m g = {weight:.10f} N; "
      f"largest drift of the base {np.abs(run.q[:, :3] - run.q[0, :3]).max():.1e} m")
assert abs(normal[-1].sum() - weight) <= 1e-9 * weight
assert np.abs(run.q[:, :3] - run.q[0, :3]).max() < 1e-9

fig, ax = plt.subplots(figsize=(7, 3.5))
for k, f in enumerate(FEET):
    ax.plot(run.t, normal[:, k], label=f"foot {f}")
ax.plot(run.t, normal.sum(axis=1), "k--", label="sum")
ax.axhline(weight, color="grey", lw=0.8, ls=":", label="m g")
ax.set_xlabel("t [s]")
ax.set_ylabel("normal force [N]")
ax.set_title("Solo12 standing: the feet that carry it, and their sum")
ax.legend(loc="center right")
plt.show()
