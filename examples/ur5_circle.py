"""A UR5 draws a circle with its tool: inverse kinematics and inverse dynamics by constraints.

Run it with `.venv/bin/python examples/ur5_circle.py [picture.png]` (about a minute).

1. The tool path as a constraint. The UR5 of example-robot-data (every link a rigid body)
   gets one more constraint: its tool frame (``tool0``) held at a point that runs round a
   10 cm circle in 2 s, with the tool's orientation kept — six rows, as many as the arm
   has joints. The arm then has no freedom left: the motion (2.14) is the inverse
   kinematics, and the simulation gives the joint angles along the path
   (``System.joint_values``).
2. The joint torques as multipliers (Udwadia's servo constraints). The same arm with each
   joint's angle prescribed by a row ``joint.angle − θ(t)`` and no torques applied: the
   multiplier of each such row is the torque about that joint that makes the motion
   (``System.reactions``, reactions.py). Evaluated at the drawing's motion, they are the
   motor torques that would draw the circle without the tool constraint — checked here
   against Pinocchio's ``rnea``.
3. A picture: the tool's path and the six torques over time.
"""

import sys
import time

import numpy as np
import pinocchio as pin
import sympy as sp

import mbsynth as mb
from mbsynth.model.constraints.joints import joint_equations
from mbsynth.model.constraints.base import Constraint
from mbsynth.analysis.projection import project_velocities
from mbsynth.robots.build import LINK_FRAME
from mbsynth.symbolic.derive import T_SYMBOL
from mbsynth.robots.twin import Twin

RADIUS, PERIOD = 0.10, 2.0  # m, s
START = np.array([0.0, -1.2, 1.6, -1.97, -1.57, 0.0])  # joint angles: elbow up, tool pointing down


def tool_path_constraint(system, tool, p0, R0):
    """Six rows holding the tool frame at p0 + r (cos ωt − 1, sin ωt, 0) with axes R0."""
    w = 2 * sp.pi / PERIOD
    target = sp.Matrix(p0) + RADIUS * sp.Matrix([sp.cos(w * T_SYMBOL) - 1, sp.sin(w * T_SYMBOL), 0])
    p, R = tool.pose(tool.frames[LINK_FRAME])
    phis, labels = joint_equations("fixed", target, sp.Matrix(R0), p, R)
    return Constraint.holonomic("tool_path", phis, system.q_symbols, system.qd_symbols, system.parameter_symbols,
                               row_labels=labels)


def servo_rows(system, joints):
    """One row ``joint.angle`` per joint: its multiplier is the torque about the joint."""
    by_name = {c.name: c for c in system.constraints}
    return [Constraint.holonomic(f"{name}_servo", [by_name[name].angle], system.q_symbols, system.qd_symbols,
                                system.parameter_symbols) for name in joints]


def main(picture="ur5_circle.png"):
    arm = mb.from_robot("ur5")
    twin = Twin(arm)
    joints = [c.name for c in twin.coordinates]
    q0, _ = twin.to_maximal(START, np.zeros(twin.model.nv))
    tool = next(p for p in arm.parts if p.name == "tool0")
    at_start = dict(zip(arm.q_symbols, q0))
    p0, R0 = (np.array(x.xreplace(at_start), dtype=float) for x in tool.pose(tool.frames[LINK_FRAME]))
    drawing = arm.with_constraints([tool_path_constraint(arm, tool, p0, R0)])
    qd0 = project_velocities(drawing, 0.0, q0, np.zeros(arm.n))  # the tool starts moving along the circle
    started = time.perf_counter()
    trajectory = mb.simulate(drawing, PERIOD, q0=q0, qd0=qd0, dt=PERIOD / 40, rtol=1e-9, atol=1e-9)
    print(f"drew the circle in {time.perf_counter() - started:.1f} s; largest constraint residual "
          f"{trajectory.max_residual:.1e}")

    servoed = arm.with_constraints(servo_rows(arm, joints))
    angles, torques, worst = [], [], 0.0
    for t, q, qd in zip(trajectory.t, trajectory.q, trajectory.qd):
        motion = drawing.motion(t, q, qd)
        angles.append([v.position[0] for v in drawing.joint_values(t, q, qd).values()])
        reactions = servoed.reactions(t, q, qd, motion)
        tau = np.array([reactions[f"{name}_servo"].multipliers[0] for name in joints])
        qp, v, a = twin.to_pinocchio(q, qd, motion.qdd)
        reference = pin.rnea(twin.model, twin.data, qp, v, a)
        worst = max(worst, np.abs(tau - reference).max() / np.abs(reference).max())
        torques.append(tau)
    print(f"servo multipliers against Pinocchio's rnea: largest relative difference {worst:.1e}")
    print("joint torques at t = 0 (N m): " + ", ".join(f"{n} {x:+.2f}" for n, x in zip(joints, torques[0])))
    draw(picture, trajectory, np.array(angles), np.array(torques), joints, tool, drawing)
    return worst


def draw(picture, trajectory, angles, torques, joints, tool, system):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    index = [system.coordinates.index(f"tool0.{c}") for c in ("x", "y")]
    fig, (path, angle_axes, torque_axes) = plt.subplots(1, 3, figsize=(15, 4.2))
    path.plot(trajectory.q[:, index[0]], trajectory.q[:, index[1]], ".-")
    path.set(xlabel="x (m)", ylabel="y (m)", title="tool0 (its centre of mass)", aspect="equal")
    for name, series in zip(joints, np.unwrap(angles, axis=0).T):
        angle_axes.plot(trajectory.t, series, label=name)
    angle_axes.set(xlabel="t (s)", ylabel="rad", title="joint angles (inverse kinematics)")
    for name, series in zip(joints, torques.T):
        torque_axes.plot(trajectory.t, series, label=name)
    torque_axes.set(xlabel="t (s)", ylabel="N m", title="joint torques (servo multipliers)")
    torque_axes.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(picture, dpi=90)
    print(f"wrote {picture}")


if __name__ == "__main__":
    main(*sys.argv[1:])
