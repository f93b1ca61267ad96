"""The tree path of mbsynth.fast against the reference (2.14) on every robot of
example-robot-data that mbsynth and Pinocchio load, with a floating base; writes
benchmarks/fast_robots_results.md.

    .venv/bin/python benchmarks/fast_all_robots.py [--samples 3] [--only ur5 talos ...]

At each state (Pinocchio's random configuration and velocity, mapped to maximal
coordinates) the Engine's answer must exist and agree with ``method="reference"`` to 1e-10
relative, or — where (2.14) finds the motion not unique — the Engine must decline (its
checks hand such states to the exact treatment). Rows are written after every robot, so an
interrupted run keeps what it measured.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import datetime  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from mbsynth import robots  # noqa: E402
from mbsynth.errors import ModelError  # noqa: E402
from mbsynth.fast import engine_for  # noqa: E402
from mbsynth.twin import Twin  # noqa: E402
from mbsynth.validate import robot_table, sample_pinocchio_state  # noqa: E402

HERE = Path(__file__).resolve().parent
RTOL = 1e-10


def check(name, samples, rng):
    """(bodies, worst relative difference, states compared, states declined, note)."""
    try:
        system = robots.from_robot(name, floating=True)
    except ModelError as err:
        return None, None, 0, 0, f"refused by mbsynth: {str(err).splitlines()[0][:80]}"
    engine = engine_for(system, wait=True)
    twin = Twin(system)
    worst, compared, declined = 0.0, 0, 0
    for _ in range(samples):
        qm, qdm = twin.to_maximal(*sample_pinocchio_state(twin, rng))
        ref = system.motion(0.0, qm, qdm, method="reference")
        fast = engine.motion(0.0, qm, qdm)
        if not ref.unique:
            assert fast is None, f"{name}: the Engine answered where (2.14) finds no unique motion"
            declined += 1
            continue
        assert fast is not None, f"{name}: the Engine declined a state with a unique motion"
        worst = max(worst, np.linalg.norm(fast.qdd - ref.qdd) / max(np.linalg.norm(ref.qdd), 1e-300))
        compared += 1
    assert worst <= RTOL, f"{name}: {worst:.1e} from (2.14)"
    return len(system.subsystems), worst, compared, declined, ""


def write(rows, path):
    lines = ["# The tree path (mbsynth.fast) against (2.14) on every robot", "",
             f"{datetime.date.today()}, {platform.machine()}, Python {platform.python_version()}; written by "
             "`benchmarks/fast_all_robots.py` (floating base). *difference*: the largest relative difference "
             f"of q̈ from `method=\"reference\"` (must be ≤ {RTOL:g}); *declined*: states where (2.14) finds the "
             "motion not unique and the Engine, rightly, gives no answer.", "",
             "| robot | bodies | states | difference | declined | note |", "|---|---:|---:|---:|---:|---|"]
    for name, (bodies, worst, compared, declined, note) in rows.items():
        lines.append(f"| {name} | {bodies if bodies is not None else '—'} | {compared} | "
                     f"{'—' if worst is None or not compared else f'{worst:.1e}'} | {declined} | {note} |")
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
            rows[name] = (None, None, 0, 0, "Pinocchio does not load it")
            continue
        started = time.perf_counter()
        rows[name] = check(name, args.samples, rng)
        print(f"{name}: {rows[name]} ({time.perf_counter() - started:.1f} s)", flush=True)
        write(rows, HERE / "fast_robots_results.md")
    write(rows, HERE / "fast_robots_results.md")


if __name__ == "__main__":
    main()
