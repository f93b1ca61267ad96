"""What reusing the compiled path saves: ``with_parameters`` + first motion, and a small sweep.

    .venv/bin/python benchmarks/engine_reuse.py [--models M.yaml ... chain:N] [--runs 6] [--repeats 5]

In one process, the kernels compiled before anything is timed, MBSYNTH_COMPILED=wait (every
motion on the tree path), for each model (``chain:N``: N links of ``chain_yaml`` of
fast_dynamics.py), its first parameter m scaled by a random factor in [0.9, 1.1]:

- *reuse*: ``base.with_parameters(m=…)`` and its first ``motion``: the new System shares
  base's Template (mbsynth.compiled.engine), only the Layout's numbers are evaluated;
- *no reuse*: the same, on a copy of that System without the ``with_parameters`` lineage
  (``dataclasses.replace``), which builds its own Template (layout, generated source,
  warm-up), as every ``with_parameters`` System did before; the compiled generated module
  is shared by its hash either way, so neither pays numba;
- *sweep* (``--sweep-model``): ``--runs`` simulations of 0.2 s (outputs every 0.02 s), the
  body of ``sweep.run_one``, each way.

Times are medians of ``--repeats`` rounds, the two ways alternating; compare the ratios,
measured in the same run (the machine is shared and noisy). Writes
benchmarks/engine_reuse_results.md.
"""

import argparse
import os
import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

os.environ["MBSYNTH_COMPILED"] = "wait"

import numpy as np  # noqa: E402

import mbsynth as mb  # noqa: E402
from mbsynth.compiled import engine_for  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from fast_dynamics import chain_yaml  # noqa: E402

MODELS = ["models/rolling/rolling_disk.yaml", "models/robots/ur5_payload.yaml", "models/robots/two_arms_bar.yaml",
          "chain:20"]
WAYS = {"reuse": lambda system: system, "no reuse": lambda system: replace(system)}


def load(spec):
    if spec.startswith("chain:"):
        return mb.loads(chain_yaml(int(spec[6:])), name=spec)
    return mb.load(ROOT / spec)


def first_motion(base, way, m):
    """Seconds from ``with_parameters`` to the first motion's answer, and that answer's method."""
    started = time.perf_counter()
    system = WAYS[way](base.with_parameters(m=m))
    q, qd = system.initial_state()
    motion = system.motion(0.0, q, qd)
    return time.perf_counter() - started, motion.method


def sweep(base, way, values):
    started = time.perf_counter()
    for m in values:
        traj = mb.simulate(WAYS[way](base.with_parameters(m=m)), 0.2, dt=0.02)
        assert traj.status == "completed", traj.status
    return time.perf_counter() - started


def measure(spec, repeats, rng):
    started = time.perf_counter()
    base = load(spec)
    loaded = time.perf_counter() - started
    started = time.perf_counter()
    engine_for(base)
    built = time.perf_counter() - started
    m = base.parameters["m"]
    first = {way: [] for way in WAYS}
    for _ in range(repeats):
        for way in WAYS:
            seconds, method = first_motion(base, way, m * rng.uniform(0.9, 1.1))
            assert method == "tree (Baraff)", method
            first[way].append(seconds)
    return base, loaded, built, {w: float(np.median(t)) for w, t in first.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=MODELS)
    parser.add_argument("--sweep-model", default=MODELS[0])
    parser.add_argument("--runs", type=int, default=6)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    engine_for(load("chain:2"))  # the kernels, compiled or loaded
    lines = ["# Engine reuse", "",
             f"`{' '.join(['benchmarks/engine_reuse.py'] + sys.argv[1:])}` on {platform.node()} "
             f"({platform.processor() or platform.machine()}, {os.cpu_count()} cores), {time.strftime('%Y-%m-%d')}. "
             "Load: `mb.load`; first engine: the model's Template and Engine (numba's cache warm, generated code "
             f"compiled or loaded); with_parameters + first motion: median of {args.repeats}, each way.", "",
             "| model | n | load [s] | first engine [s] | with_parameters + first motion: reuse [s] | no reuse [s] "
             "| ratio |", "|---|---:|---:|---:|---:|---:|---:|"]
    for spec in args.models:
        base, loaded, built, first = measure(spec, args.repeats, rng)
        lines.append(f"| {base.name} | {base.n} | {loaded:.2f} | {built:.2f} | {first['reuse']:.4f} | "
                     f"{first['no reuse']:.4f} | {first['no reuse'] / first['reuse']:.1f}× |")
        print(lines[-1], flush=True)
    base = load(args.sweep_model)
    engine_for(base)
    values = base.parameters["m"] * rng.uniform(0.9, 1.1, args.runs)
    swept = {way: sweep(base, way, values) for way in reversed(WAYS)}
    lines += ["", f"Sweep: {args.runs} runs of {base.name} (0.2 s, outputs every 0.02 s) at other values of m.", "",
              "| way | total [s] | per run [s] |", "|---|---:|---:|"]
    lines += [f"| {way} | {t:.2f} | {t / args.runs:.3f} |" for way, t in swept.items()]
    lines.append(f"| ratio no reuse / reuse | {swept['no reuse'] / swept['reuse']:.2f}× | |")
    (HERE / "engine_reuse_results.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
