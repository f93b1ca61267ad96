"""The tree path of mbsynth.compiled on every robot of example-robot-data that mbsynth and
Pinocchio load, with a floating base, against Pinocchio's ``aba`` (the exact motion, as in
``mbsynth validate``); writes benchmarks/fast_robots_results.md.

    .venv/bin/python benchmarks/fast_all_robots.py [--samples 3] [--only ur5 talos ...]

At each state (Pinocchio's random configuration and velocity, mapped to maximal
coordinates) the Engine's answer must exist and agree with ``aba`` to core.tolerances.VALIDATION_RTOL
relative, or — where ``aba`` has no finite answer (massless links that a torque-free state
leaves indeterminate) — the Engine must decline (its checks hand such states to the exact
treatment). The difference from ``method="reference"`` is reported too: the literal
pseudo-inverse of (2.14) loses digits when masses span many orders of magnitude (robot
hands), where the tree path does not. Rows are written after every robot, so an
interrupted run keeps what it measured; the exit status is 1 if any robot fails.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import datetime  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from mbsynth.robots import build as robots  # noqa: E402
from mbsynth.core.errors import ModelError  # noqa: E402
from mbsynth.compiled import engine_for  # noqa: E402
from mbsynth.robots.twin import Twin  # noqa: E402
from mbsynth.robots.validate import robot_table, sample_pinocchio_state  # noqa: E402
from mbsynth.core.tolerances import VALIDATION_RTOL

HERE = Path(__file__).resolve().parent


def check(name, samples, rng):
    """(bodies, worst relative error against aba, worst relative difference from (2.14),
    states compared, states declined, note)."""
    try:
        system = robots.from_robot(name, floating=True)
    except ModelError as err:
        why = str(err).splitlines()[0].split(": ", 1)[-1].split(";")[0]  # without the file's path
        return None, None, None, 0, 0, f"refused by mbsynth: {why}"
    engine = engine_for(system)
    twin = Twin(system)
    worst = worst_ref = 0.0
    compared = declined = 0
    for _ in range(samples):
        q, v = sample_pinocchio_state(twin, rng)
        qm, qdm = twin.to_maximal(q, v)
        with np.errstate(all="ignore"):
            exact = twin.accelerations(q, v, np.zeros(twin.model.nv))
        fast = engine.motion(0.0, qm, qdm)
        if not np.all(np.isfinite(exact)):
            if fast is not None:
                return len(system.parts), None, None, compared, declined, "FAILED: answered where aba has none"
            declined += 1
            continue
        if fast is None:
            return len(system.parts), None, None, compared, declined, "FAILED: declined a determinate state"
        error = np.abs(twin.to_pinocchio(qm, qdm, fast.qdd)[2] - exact).max()
        worst = max(worst, error / max(np.abs(exact).max(), 1e-300))
        ref = system.motion(0.0, qm, qdm, method="reference").qdd
        worst_ref = max(worst_ref, np.linalg.norm(fast.qdd - ref) / max(np.linalg.norm(ref), 1e-300))
        compared += 1
    note = "" if worst <= VALIDATION_RTOL else "FAILED"
    return len(system.parts), worst, worst_ref, compared, declined, note


def write(rows, path):
    lines = ["# The tree path (mbsynth.compiled) against Pinocchio on every robot", "",
             f"{datetime.date.today()}, {platform.machine()}, Python {platform.python_version()}; written by "
             "`benchmarks/fast_all_robots.py` (floating base, zero torques). *error*: the largest joint "
             f"acceleration error of `Engine.motion` against Pinocchio's `aba`, relative to the largest (must be "
             f"≤ {VALIDATION_RTOL:g}); *vs (2.14)*: the relative difference of q̈ from `method=\"reference\"`; "
             "*declined*: states where `aba` has no finite answer and the Engine, rightly, gives none.", "",
             "| robot | bodies | states | error | vs (2.14) | declined | note |",
             "|---|---:|---:|---:|---:|---:|---|"]

    def number(x):
        return "—" if x is None else f"{x:.1e}"
    for name, (bodies, worst, worst_ref, compared, declined, note) in rows.items():
        lines.append(f"| {name} | {bodies if bodies is not None else '—'} | {compared} | "
                     f"{number(worst if compared else None)} | {number(worst_ref if compared else None)} | "
                     f"{declined} | {note} |")
    failed = [name for name, row in rows.items() if row[-1].startswith("FAILED")]
    lines += ["", f"{sum(r[3] for r in rows.values())} states compared over "
              f"{sum(1 for r in rows.values() if r[3])} robots; failures: {', '.join(failed) or 'none'}."]
    path.write_text("\n".join(lines) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=3)
    parser.add_argument("--only", nargs="*")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    rows = {}
    for name, _, _, _, loads in robot_table():
        if args.only and name not in args.only:
            continue
        if not loads:
            rows[name] = (None, None, None, 0, 0, "Pinocchio does not load it")
            continue
        started = time.perf_counter()
        rows[name] = check(name, args.samples, rng)
        print(f"{name}: {rows[name]} ({time.perf_counter() - started:.1f} s)", flush=True)
        write(rows, HERE / "fast_robots_results.md")
    write(rows, HERE / "fast_robots_results.md")
    return 1 if any(row[-1].startswith("FAILED") for row in rows.values()) else 0


if __name__ == "__main__":
    raise SystemExit(main())
