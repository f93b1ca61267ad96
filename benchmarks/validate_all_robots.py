"""`mbsynth validate` for every robot of example-robot-data that Pinocchio loads, fixed and
floating base, and for the model files of robots and loops; writes a results table.

    .venv/bin/python benchmarks/validate_all_robots.py [--samples 20] [--only ur5 panda four_bar_3d ...] [--out FILE]

Each robot is built once (floating; the fixed base adds a weld), so "build s" is the time
to derive and compile every part, joint and torque symbolically (sympy), shared by both
rows. "motion ms" is one evaluation of (2.14) by the dense KKT solve. BLAS runs single-threaded (OPENBLAS_NUM_THREADS=1): on a busy 2-core machine its
threads otherwise fight over the cores. Writes benchmarks/validate_results.md after every
robot, so an interrupted run keeps what it measured.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MBSYNTH_COMPILED", "wait")  # the production (compiled) path, not the KKT path while it builds

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from mbsynth.cli.validate import figure, loop_figure  # noqa: E402
from mbsynth.core.errors import ModelError, SolveError  # noqa: E402
from mbsynth.io import load  # noqa: E402
from mbsynth.robots.validate import Validation, robot_table, validate_robot, validate_system  # noqa: E402
from mbsynth.core.tolerances import VALIDATION_RTOL

HERE = Path(__file__).resolve().parent
MODELS = [*(HERE.parent / "models" / "mechanisms" / f"{name}.yaml" for name in ("four_bar_3d", "bennett")),
          *sorted((HERE.parent / "models" / "robots").glob("*.yaml"))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20)
    parser.add_argument("--only", nargs="*", help="robot names or model file stems (default: every robot that "
                                                  "Pinocchio loads and every model file)")
    parser.add_argument("--out", default=str(HERE / "validate_results.md"))
    args = parser.parse_args()
    robots = sorted((links, name) for name, _, links, _, loads in robot_table() if loads)  # small first
    if args.only:
        robots = [(links, name) for links, name in robots if name in args.only]
    args.total = len(robots)
    rows, started = [], time.perf_counter()
    for _, name in robots:
        try:
            rows += [(name, r) for r in validate_robot(name, samples=args.samples)]
        except (ModelError, SolveError) as err:
            rows.append((name, Validation(name, "-", 0, 0, args.samples, float("nan"), float("nan"), False,
                                          VALIDATION_RTOL, 0.0, 0.0, str(err))))
        write(args, rows, time.perf_counter() - started)
    for path in MODELS:
        if not args.only or path.stem in args.only:
            began = time.perf_counter()
            system = load(path)
            rows.append((str(path.relative_to(HERE.parent)),
                         validate_system(system, samples=args.samples, build_s=time.perf_counter() - began)))
            write(args, rows, time.perf_counter() - started)


def comparable(r):
    """Whether a row compares two answers: not a refused file, not a robot on which
    Pinocchio returns NaN and mbsynth finds no unique motion."""
    both_undefined = r.note.startswith("Pinocchio returns NaN") and "mbsynth:" in r.note
    return r.base != "-" and not (both_undefined and not r.passed)


def brief(note, limit=300):
    return note if len(note) <= limit else note[:limit] + " …"


def write(args, rows, elapsed):
    compared = [(n, r) for n, r in rows if comparable(r)]
    passed = sum(r.passed for _, r in compared)
    worst = max((r.max_rel_error for _, r in rows if r.passed), default=0.0)
    lines = ["# mbsynth against Pinocchio", "",
             f"`benchmarks/validate_all_robots.py --samples {args.samples}` on {platform.node()} "
             f"({platform.processor() or platform.machine()}, {os.cpu_count()} cores), {time.strftime('%Y-%m-%d')}, "
             f"{elapsed / 60:.1f} min in all; {len({n for n, r in rows if r.base != 'model'})} of {args.total} robots "
             "(smallest first).", "",
             f"Joint accelerations v̇ of mbsynth (every link a rigid body in 7 coordinates, (2.14)) against "
             f"`pinocchio.aba` (`constraintDynamics` for loops) at {args.samples} random states and torques "
             f"each: {passed} of {len(compared)} comparisons pass the relative tolerance {VALIDATION_RTOL:.0e}; the largest "
             f"relative error among them is {worst:.1e}. Not compared: {len(rows) - len(compared)} row(s) — files "
             "whose data no rigid body has (mbsynth refuses them by link; Pinocchio does not check), and robots "
             "with massless links on which `pinocchio.aba` returns NaN while mbsynth names the indeterminate "
             "directions (a torque on them has no motion at all).", "",
             "In joint space, at the same states: `joint_values` against Pinocchio's (q, v, v̇) joint by joint "
             "(\"joints\", relative to 1 + max |v|, |v̇|), and each joint's `reactions` wrench against `data.f` of "
             "`rnea` (\"reactions\", relative to its largest entry; \"-\" for models with loops or force elements "
             "other than the joint torques), and each loop-closing joint's wrench against the one of "
             "`constraintDynamics`' `lambda_c` (\"loops\", relative to its largest entry; \"-\" for models without "
             "loops). A redundant loop (a planar four-bar in space) carries a wrench that is not unique: any "
             "self-stress of the loop may be added, and the two solvers pick different ones, so only the components "
             "no self-stress changes are compared; \"(k free)\" says how many of a joint's six are left out. "
             "All count towards the result.", "",
             "| robot or model | bodies | base | nv | max rel error | max abs error | joints | reactions | loops "
             "| build s | motion ms | result |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, r in rows:
        if not comparable(r):
            result = f"{'refused' if r.base == '-' else 'not comparable'}: {brief(r.note)}"
        else:
            result = "passed" if r.passed else f"**failed**: {brief(r.note)}" if r.note else "**failed**"
        lines.append(f"| {name} | {r.links} | {r.base} | {r.nv} | {r.max_rel_error:.1e} | {r.max_abs_error:.1e} "
                     f"| {figure(r.joint_error)} | {figure(r.reaction_error)} | {loop_figure(r)} | {r.build_s:.1f} "
                     f"| {r.motion_ms:.2f} "
                     f"| {result} |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    name, r = rows[-1]
    print(f"{name} {r.base}: rel {r.max_rel_error:.1e}, build {r.build_s:.1f} s, {'passed' if r.passed else 'FAILED ' + r.note}",
          flush=True)


if __name__ == "__main__":
    main()
