"""What sampled control costs: a UR5 run with a PD controller sampled every 10 ms against the
same run with constant (zero) torques, and against a sampled law that returns those
constant torques (the cost of sampling alone: the same motion, 200 restarts).

The controller writes its torques into the run's Data at each sample (``Data.set_parameters``:
no System is built during the run); the integrator restarts at each sample, where the
torques jump. The runs are timed in the same process, alternating, best of ``--repeats``;
the ratio is what sampled control costs on top of the dynamics.

    .venv/bin/python benchmarks/controlled_run.py [--repeats 5] [--t-end 2]

writes ``benchmarks/controlled_run_results.md``.
"""

import argparse
import platform
import time
from datetime import date
from pathlib import Path

import numpy as np

import mbsynth as mb

TARGET = np.array([0.3, -0.6, 0.8, -0.2, 0.0, 0.0])
BANDWIDTH, DAMPING = 2 * np.pi * 1.0, 1.0  # each joint's closed loop: 1 Hz, critically damped
CONTROL_DT = 0.01


def pd_law(system):
    """PD towards TARGET, gains from the joint-space inertia there (as examples/pd_arm_payload.py)."""
    import pinocchio as pin
    from mbsynth.robots.build import robot_files
    model = pin.buildModelFromUrdf(robot_files()["ur5"])
    inertia = np.diag(pin.crba(model, model.createData(), TARGET))
    kp, kd = inertia * BANDWIDTH**2, 2 * DAMPING * inertia * BANDWIDTH
    names = [n.removeprefix("tau_") for n in system.parameters if n.startswith("tau_")]

    def law(t, values):
        return {f"tau_{name}": kp[i] * (TARGET[i] - values[name].position[0]) - kd[i] * values[name].rate[0]
                for i, name in enumerate(names)}
    return law


def timed(run):
    started = time.perf_counter()
    trajectory = run()
    return time.perf_counter() - started, trajectory


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--t-end", type=float, default=2.0)
    args = parser.parse_args()
    system = mb.from_robot("ur5")
    law = pd_law(system)
    zero = {name: 0.0 for name in system.parameters if name.startswith("tau_")}
    runs = {"constant torques": lambda: mb.simulate(system, args.t_end),
            "the same torques, sampled every 10 ms": lambda: mb.simulate(system, args.t_end,
                                                                         controller=lambda t, v: zero,
                                                                         control_dt=CONTROL_DT),
            "PD sampled every 10 ms": lambda: mb.simulate(system, args.t_end, controller=law, control_dt=CONTROL_DT)}
    for run in runs.values():
        run()  # compile or load everything first
    best = {name: (np.inf, None) for name in runs}
    for _ in range(args.repeats):
        for name, run in runs.items():
            seconds, trajectory = timed(run)
            if seconds < best[name][0]:
                best[name] = (seconds, trajectory)
    base = best["constant torques"][0]
    lines = [f"# Sampled control on the UR5 ({args.t_end:g} s)", "",
             f"`benchmarks/controlled_run.py --repeats {args.repeats} --t-end {args.t_end:g}` on "
             f"{platform.node()} ({platform.machine()}, {platform.python_version()}), {date.today()}: "
             "best of the repeats, the runs alternating in one process.", "",
             "| run | seconds | evaluations | steps | ratio |", "|---|---:|---:|---:|---:|"]
    for name, (seconds, trajectory) in best.items():
        lines.append(f"| {name} | {seconds:.4f} | {trajectory.stats['evaluations']} | {trajectory.stats['steps']} "
                     f"| {seconds / base:.2f}× |")
    text = "\n".join(lines) + "\n"
    print(text)
    (Path(__file__).with_name("controlled_run_results.md")).write_text(text)


if __name__ == "__main__":
    main()
