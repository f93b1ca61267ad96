"""A PD-controlled UR5 holding a payload: a control law in Python on joint values.

Run it with `.venv/bin/python examples/pd_arm_payload.py [picture.png]` (about a minute).

1. The model: models/robots/ur5_payload.yaml — the UR5 of example-robot-data, every link a
   rigid body, with a 2 kg payload hanging from its flange by a spring. Each arm joint is
   driven by a parameter ``tau_arm_<joint>``.
2. The controller: ``mb.simulate(system, t_end, controller=f)`` calls ``f(t, joint_values)``
   every ``control_dt`` and holds the torques it returns until the next call (sampled
   control, zero-order hold). Here each joint gets a PD torque towards a target pose,
   plus the static torque that holds the arm and its payload there — computed by mbsynth
   itself: the multipliers of servo rows on every joint angle at rest at the target
   (inverse statics by constraints, reactions.py).
3. The arm swings from its zero pose to the target and settles; the payload bobs on its
   spring. At the end the joints sit at their targets and the applied torques equal the
   static ones.
"""

import sys

import numpy as np

import mbsynth as mb
from mbsynth.constraint import Connector
from mbsynth.joint_values import constraint_symbols
from mbsynth.projection import project_positions

MODEL = "models/robots/ur5_payload.yaml"
JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint")
TARGET = np.array([0.3, -0.6, 0.8, -0.2, 0.0, 0.0])
KP, KD = 400.0, 60.0  # N m / rad, N m s / rad


def static_torques(system, names, target):
    """The joint torques that hold ``system`` at rest with its joints at ``target``: the
    multipliers of one servo row per joint angle (inverse statics by constraints)."""
    joints = {c.name: c for c in system.constraints}
    servos = [Connector.holonomic(f"{name}_servo", [constraint_symbols(joints[name])["angle"] - angle],
                                  system.q_symbols, system.qd_symbols, system.parameter_symbols)
              for name, angle in zip(names, target)]
    held = system.with_constraints(servos)
    q = project_positions(held, 0.0, system.initial_state()[0])  # the arm at the target, the payload hanging
    at_rest = np.zeros(system.n)
    for _ in range(50):  # let the payload settle on its spring: repeat until nothing accelerates
        motion = held.motion(0.0, q, at_rest)
        if np.abs(motion.qdd).max() < 1e-9:
            break
        q = _settle_payload(held, q, motion)
    reactions = held.reactions(0.0, q, at_rest, motion)
    return np.array([reactions[f"{name}_servo"].multipliers[0] for name in names])


def _settle_payload(system, q, motion):
    """One Newton step of the hanging payload towards rest: its drop under its own
    acceleration, q̈ / ω² with ω² of the spring (k / m)."""
    return project_positions(system, 0.0, q + motion.qdd / (400.0 / 2.0))


def main(picture="pd_arm_payload.png"):
    system = mb.load(MODEL)
    names = [f"arm_{j}" for j in JOINTS]
    hold = static_torques(system, names, TARGET)
    print("static torques at the target (N m): " + ", ".join(f"{j} {x:+.2f}" for j, x in zip(JOINTS, hold)))

    def controller(t, values):
        return {f"tau_{name}": KP * (target - values[name].position[0]) - KD * values[name].rate[0] + h
                for name, target, h in zip(names, TARGET, hold)}

    trajectory = mb.simulate(system, 3.0, dt=0.02, controller=controller, rtol=1e-8, atol=1e-8)
    from mbsynth.joint_values import along
    joints = along(system, trajectory.t, trajectory.q, trajectory.qd)
    final = np.array([joints[name].position[-1, 0] for name in names])
    print(f"after 3 s: largest joint error {np.abs(final - TARGET).max():.2e} rad, "
          f"largest joint rate {max(abs(joints[n].rate[-1, 0]) for n in names):.2e} rad/s, "
          f"constraint residual {trajectory.max_residual:.1e}")
    draw(picture, trajectory, joints, names)
    return np.abs(final - TARGET).max()


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
