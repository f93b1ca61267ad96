"""A PD-controlled UR5 holding a payload: a control law in Python on joint values.

Run it with `.venv/bin/python examples/pd_arm_payload.py [picture.png]` (about a minute).

1. The model: models/robots/ur5_payload.yaml — the UR5 of example-robot-data, every link a
   rigid body, with a 2 kg payload hanging from its flange by a spring. Each arm joint is
   driven by a parameter ``tau_arm_<joint>``.
2. The controller: ``mb.simulate(system, t_end, controller=f)`` calls ``f(t, joint_values)``
   every ``control_dt`` (here the output interval, 20 ms) and holds the torques it returns
   until the next call (sampled control, zero-order hold). Each joint gets a PD torque
   towards a target pose.
3. The arm swings from its zero pose towards the target and settles where the PD torques
   balance gravity (a PD law without gravity compensation keeps an offset). The check:
   the torques that hold the settled arm at rest — the multipliers of servo rows on every
   joint angle (inverse statics by constraints, reactions.py) — equal the PD torques.
"""

import sys
from pathlib import Path

import numpy as np

import mbsynth as mb
from mbsynth.constraint import Connector
from mbsynth.joint_values import along, constraint_symbols

MODEL = Path(__file__).resolve().parent.parent / "models" / "robots" / "ur5_payload.yaml"
JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint")
TARGET = np.array([0.3, -0.6, 0.8, -0.2, 0.0, 0.0])
KP, KD = 400.0, 60.0  # N m / rad, N m s / rad
T_END = 4.0


def static_torques(system, names, t, q):
    """The joint torques that hold ``system`` at rest at the positions q: the multipliers
    of one servo row per joint angle (inverse statics by constraints, reactions.py)."""
    joints = {c.name: c for c in system.constraints}
    angles = system.joint_values(t, q, np.zeros(system.n))
    servos = [Connector.holonomic(f"{name}_servo", [constraint_symbols(joints[name])["angle"]
                                                    - angles[name].position[0]],
                                  system.q_symbols, system.qd_symbols, system.parameter_symbols) for name in names]
    held = system.with_constraints(servos)
    at_rest = np.zeros(system.n)
    reactions = held.reactions(t, q, at_rest, held.motion(t, q, at_rest))
    return np.array([reactions[f"{name}_servo"].multipliers[0] for name in names])


def main(picture="pd_arm_payload.png"):
    system = mb.load(MODEL)
    names = [f"arm_{j}" for j in JOINTS]

    def controller(t, values):
        return {f"tau_{name}": KP * (target - values[name].position[0]) - KD * values[name].rate[0]
                for name, target in zip(names, TARGET)}

    trajectory = mb.simulate(system, T_END, dt=0.02, controller=controller, rtol=1e-8, atol=1e-8)
    joints = along(system, trajectory.t, trajectory.q, trajectory.qd)
    t, q, qd = trajectory.t[-1], trajectory.q[-1], trajectory.qd[-1]
    final = np.array([joints[name].position[-1, 0] for name in names])
    print(f"after {T_END:g} s: joint angles {np.round(final, 4)} (targets {TARGET}), largest joint rate "
          f"{max(abs(joints[n].rate[-1, 0]) for n in names):.1e} rad/s, constraint residual "
          f"{trajectory.max_residual:.1e}")
    applied = np.array(list(controller(t, system.joint_values(t, q, qd)).values()))
    held = static_torques(system, names, t, q)
    print("PD torques at the end (N m):    " + ", ".join(f"{x:+8.3f}" for x in applied))
    print("static torques, servo rows (N m): " + ", ".join(f"{x:+8.3f}" for x in held))
    print(f"the arm has settled where its PD torques hold it: largest difference {np.abs(applied - held).max():.1e} N m")
    draw(picture, trajectory, joints, names)
    return np.abs(applied - held).max()


def draw(picture, trajectory, joints, names):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(figsize=(8, 4))
    for name, target in zip(names, TARGET):
        line, = axes.plot(trajectory.t, joints[name].position[:, 0], label=name.removeprefix("arm_"))
        axes.axhline(target, color=line.get_color(), linestyle=":", linewidth=0.8)
    axes.set(xlabel="t (s)", ylabel="joint angle (rad)", title="UR5 with a payload, PD towards a pose (dotted)")
    axes.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(picture, dpi=90)
    print(f"wrote {picture}")


if __name__ == "__main__":
    main(*sys.argv[1:])
