"""``System.motion_batch`` against ``pinocchio.aba`` per state, as a distribution over rounds.

    MBSYNTH_COMPILED=wait .venv/bin/python benchmarks/motion_batch.py [--rounds R] [--count B]

For the UR5 (fixed base) and talos (floating) of example-robot-data: B states (default
1024) drawn in Pinocchio's coordinates and mapped to mbsynth's by forward kinematics
(benchmarks/fast_dynamics.py's robot cases). Each round times ``motion_batch`` over all B
states (a loop of about 0.3 s; one thread per core) and then ``aba`` on one state (a loop
of about 0.2 s, one thread), and keeps their ratio per state; rounds alternate the two, so
load from other tenants of a shared machine hits both within a round. The table gives the
median ratio over R rounds (default 15), its quartiles, and the best round's. The
per-state times are each code's median. Writes benchmarks/motion_batch_results.md.
"""

import argparse
import datetime
import os
import platform
from pathlib import Path

os.environ.setdefault("MBSYNTH_COMPILED", "wait")  # the compiled kernels, not the KKT path while they build

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from fast_dynamics import best, robot_case  # noqa: E402

HERE = Path(__file__).resolve().parent
ROBOTS = [("ur5", False), ("talos", True)]


def batch_rounds(case, rng, count, rounds):
    """[(motion_batch seconds per state, aba seconds)] per round for ``case``
    (fast_dynamics.Case), the two alternating."""
    states = [case.to_maximal(*case.draw(rng)) for _ in range(count)]
    q, qd = np.array([s[0] for s in states]), np.array([s[1] for s in states])
    times = np.zeros(count)
    case.system.motion_batch(times[:8], q[:8], qd[:8])  # the engine and its threads' buffers
    qa, va = case.draw(rng)
    tau = np.zeros(case.model.nv)
    return [(best(lambda: case.system.motion_batch(times, q, qd), seconds=0.3, repeats=1) / count,
             best(lambda: pin.aba(case.model, case.data, qa, va, tau), seconds=0.2, repeats=1))
            for _ in range(rounds)]


def summary(label, results):
    """A table row: the medians of each code's time and of the per-round ratio, its quartiles, the best."""
    batch, aba = np.array(results).T
    ratio = batch / aba
    low, median, high = np.percentile(ratio, [25, 50, 75])
    return (f"| {label} | {len(ratio)} | {np.median(batch) * 1e6:.1f} | {np.median(aba) * 1e6:.1f} | "
            f"**{median:.2f}** | {low:.2f} – {high:.2f} | {ratio.min():.2f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--count", type=int, default=1024)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    lines = ["# motion_batch against aba, per state", "",
             f"{datetime.date.today()} on {platform.node()} ({os.cpu_count()} cores, "
             f"{platform.processor() or platform.machine()}), Pinocchio {pin.__version__}; "
             f"`benchmarks/motion_batch.py`: {args.count} states per batch (one thread per core), aba on one "
             f"thread, the two alternating in {args.rounds} rounds; the ratio is per round.", "",
             "| robot | rounds | batch µs/state (median) | aba µs (median) | ratio, median | quartiles | best round |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for name, floating in ROBOTS:
        case = robot_case(name, floating)
        lines.append(summary(case.label, batch_rounds(case, rng, args.count, args.rounds)))
        print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    (HERE / "motion_batch_results.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
