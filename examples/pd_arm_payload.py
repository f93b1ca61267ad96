"""A PD-controlled UR5 holding a payload: a control law in Python on joint values.

Run it with `.venv/bin/python examples/pd_arm_payload.py [picture.png]` (about a minute; tests/test_examples.py runs it).

1. The model: models/robots/ur5_payload.yaml — the UR5 of example-robot-data, every link a
   rigid body, with a 2 kg payload hanging from its flange by a spring. Each arm joint is
   driven by a parameter ``tau_arm_<joint>``.
2. The controller: ``mb.simulate(system, t_end, controller=f)`` calls ``f(t, joint_values)``
   every ``control_dt`` (here 10 ms) and holds the torques it returns until the next call
   (sampled control, zero-order hold). Each joint gets a PD torque towards a target pose,
   its gains scaled by the joint's inertia (1 Hz, critically damped).
3. The arm swings from its zero pose towards the target and comes to rest where the PD
   torques balance gravity (a PD law without gravity compensation keeps an offset), the
   payload still swinging a little on its undamped spring. The check: the torques that
   hold the arm at rest there — the multipliers of servo rows on every joint angle
   (inverse statics by constraints, reactions.py) — equal the PD torques, to within what
   the payload's swing still asks of the joints.
"""

import sys
from pathlib import Path

import numpy as np

import mbsynth as mb
from mbsynth.model.constraints.base import Constraint
from mbsynth.model.joint_values import along, constraint_symbols

MODEL = Path(__file__).resolve().parent.parent / "models" / "robots" / "ur5_payload.yaml"
JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint")
TARGET = np.array([0.3, -0.6, 0.8, -0.2, 0.0, 0.0])
BANDWIDTH, DAMPING = 2 * np.pi * 1.0, 1.0  # each joint's closed loop: 1 Hz, critically damped
CONTROL_DT = 0.01  # s: the controller's sample time (zero-order hold)
T_END = 4.0


def gains():
    """PD gains per joint from the arm's joint-space inertia at the target (the diagonal of
    Pinocchio's crba): kp = I ω², kd = 2 ζ I ω. Equal gains on every joint would make the
    light wrist's sampled loop unstable (kd·dt/I ≫ 1 with a 10 ms hold)."""
    import pinocchio as pin
    from mbsynth.robots.build import robot_files
    model = pin.buildModelFromUrdf(robot_files()["ur5"])
    inertia = np.diag(pin.crba(model, model.createData(), TARGET))
    return inertia * BANDWIDTH**2, 2 * DAMPING * inertia * BANDWIDTH


def static_torques(system, names, t, q):
    """The joint torques that hold ``system`` at rest at the positions q: the multipliers
    of one servo row per joint angle (inverse statics by constraints, reactions.py)."""
    joints = {c.name: c for c in system.constraints}
    angles = system.joint_values(t, q, np.zeros(system.n))
    servos = [Constraint.holonomic(f"{name}_servo", [constraint_symbols(joints[name])["angle"]
                                                    - angles[name].position[0]],
                                  system.q_symbols, system.qd_symbols, system.parameter_symbols) for name in names]
    held = system.with_constraints(servos)
    at_rest = np.zeros(system.n)
    reactions = held.reactions(t, q, at_rest, held.motion(t, q, at_rest))
    return np.array([reactions[f"{name}_servo"].multipliers[0] for name in names])


def main(picture="pd_arm_payload.png"):
    system = mb.load(MODEL)
    names = [f"arm_{j}" for j in JOINTS]
    kp, kd = gains()

    def controller(t, values):
        return {f"tau_{name}": kp[i] * (TARGET[i] - values[name].position[0]) - kd[i] * values[name].rate[0]
                for i, name in enumerate(names)}

    trajectory = mb.simulate(system, T_END, dt=0.02, controller=controller, control_dt=CONTROL_DT,
                             rtol=1e-8, atol=1e-8)
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
    relative = np.abs(applied - held).max() / np.abs(held).max()
    print(f"the arm rests where its PD torques hold it: largest difference {np.abs(applied - held).max():.1e} N m "
          f"({relative:.1%} of the largest torque)")
    draw(picture, trajectory, joints, names)
    return relative


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
