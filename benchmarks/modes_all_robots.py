"""The linearization of every example-robot-data robot (fixed base) held at rest by
gravity-compensating torques, against Pinocchio's `computeABADerivatives`; writes a table.

    .venv/bin/python benchmarks/modes_all_robots.py [--samples 3] [--only ur5 panda ...] [--limit-links N]

Per robot (smallest first) and random configuration: τ = rnea(q, 0, 0) as its tau_*
parameters, `mbsynth.linearize` at rest in maximal coordinates (every link a rigid body in
7 coordinates), and the eigenvalues of its A against those of [[0, I], [∂v̇/∂q, ∂v̇/∂v]],
matched one to one and compared in s² (validate_modes.eigenvalue_error); B, mapped to the model's
coordinates, against S M⁻¹ (mbsynth/robots/validate_modes.py). "first s" includes deriving and
compiling the block functions; "linearize s" is a later call at another configuration.
Writes benchmarks/modes_results.md after every robot, so an interrupted run keeps what it
measured. BLAS runs single-threaded (see validate_all_robots.py).
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from mbsynth.core.errors import ModelError, SolveError  # noqa: E402
from mbsynth.robots.build import fix_base, from_robot  # noqa: E402
from mbsynth.robots.validate import robot_table  # noqa: E402
from mbsynth.robots.validate_modes import validate_modes  # noqa: E402

HERE = Path(__file__).resolve().parent
TOLERANCE = 1e-6  # relative, as issue 21 asks


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=3)
    parser.add_argument("--only", nargs="*", help="robot names (default: all that Pinocchio loads)")
    parser.add_argument("--limit-links", type=int, default=None, help="skip robots with more links")
    parser.add_argument("--out", default=str(HERE / "modes_results.md"))
    args = parser.parse_args()
    robots = sorted((links, name) for name, _, links, _, loads in robot_table() if loads)
    if args.only:
        robots = [(links, name) for links, name in robots if name in args.only]
    if args.limit_links:
        robots = [(links, name) for links, name in robots if links <= args.limit_links]
    args.total = len(robots)
    rows, started = [], time.perf_counter()
    for links, name in robots:
        began = time.perf_counter()
        try:
            system = fix_base(from_robot(name, floating=True))
            build = time.perf_counter() - began
            rows.append((name, links, build, validate_modes(system, samples=args.samples, label=name), ""))
        except (ModelError, SolveError) as err:
            rows.append((name, links, time.perf_counter() - began, None, str(err)))
        write(args, rows, time.perf_counter() - started)


def write(args, rows, elapsed):
    results = [r for *_, r, _ in rows if r is not None]
    passed = [r for r in results if r.eigenvalue_error <= TOLERANCE and r.input_error <= TOLERANCE]
    lines = ["# Linearization of robots against Pinocchio", "",
             f"`benchmarks/modes_all_robots.py --samples {args.samples}` on {platform.node()} "
             f"({platform.processor() or platform.machine()}, {os.cpu_count()} cores), {time.strftime('%Y-%m-%d')}, "
             f"{elapsed / 60:.1f} min in all; {len(rows)} of {args.total} robots (fixed base, smallest first).", "",
             f"Each robot held at rest by τ = rnea(q, 0, 0) at {args.samples} random configurations: eigenvalues s "
             "of mbsynth's A (linearize, tangent space of the maximal coordinates) against those of "
             "[[0, I], [∂v̇/∂q, ∂v̇/∂v]] from `pinocchio.computeABADerivatives`, and B (per unit joint torque, "
             f"mapped to the model's coordinates) against S M⁻¹: {len(passed)} of {len(results)} robots within "
             f"{TOLERANCE:.0e} relative. Eigenvalues are compared in s², relative to max |s|² "
             "(at least 1 s⁻²): a zero-stiffness direction (a vertical joint axis) has a double zero eigenvalue "
             "that a rounding error δ splits into ±√δ, while s² moves by δ (mbsynth/robots/validate_modes.py).", "",
             "| robot | links | nv | eigenvalues rel error | B rel error | build s | first linearize s | "
             "linearize s | result |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, links, build, r, note in rows:
        if r is None:
            lines.append(f"| {name} | {links} | - | - | - | {build:.1f} | - | - | refused: {note[:200]} |")
            continue
        ok = r.eigenvalue_error <= TOLERANCE and r.input_error <= TOLERANCE
        lines.append(f"| {name} | {links} | {r.nv} | {r.eigenvalue_error:.1e} | {r.input_error:.1e} | {build:.1f} | "
                     f"{r.first_s:.1f} | {r.linearize_s:.2f} | {'passed' if ok else '**failed**'} |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    name, links, build, r, note = rows[-1]
    print(f"{name}: " + (f"eig {r.eigenvalue_error:.1e}, B {r.input_error:.1e}, first {r.first_s:.1f} s"
                         if r else f"refused: {note}"), flush=True)


if __name__ == "__main__":
    main()
