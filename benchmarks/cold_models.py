"""A new model's first run, and its runs after: this checkout against a baseline.

    .venv/bin/python benchmarks/cold_models.py --baseline DIR [--out FILE]

For each model below, in a fresh process with an empty mbsynth cache (no derivations, no
generated code: a model this machine has not seen) but the compiled path's kernels in
numba's cache (as ``make install`` leaves them): ``mbsynth.load`` and a first
``simulate`` of 0.01 s (CPU seconds, user + system of the process: less sensitive to a
shared machine's load); then, in the same process, the best of five ``simulate`` runs of
0.5 s (CPU seconds). The baseline (a checkout's folder, e.g. a ``git worktree``) runs
the same, alternating with this checkout, each with a numba cache of its own. Compare the
figures within one table: the machines are shared and noisy. The table goes to
benchmarks/cold_models_results.md unless --out.
"""

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
MODELS = ["mechanisms/slider_crank_3d.yaml", "mechanisms/four_bar_3d.yaml", "rolling/bicycle.yaml",
          "mechanisms/bricard.yaml", "mechanisms/andrews.yaml"]
PROBE = """\
import sys, time
import mbsynth as mb
path = sys.argv[1]
model = mb.load(path)
mb.simulate(model, 0.01)
first = time.process_time()
best = min((lambda t0: (mb.simulate(model, 0.5), time.process_time() - t0)[1])(time.process_time()) for _ in range(5))
print(first, best)
"""


def measure(repo, model, numba_cache):
    """(CPU s of the fresh process up to the end of its first run, CPU s of the best later 0.5 s run)."""
    env = dict(os.environ, PYTHONPATH=str(repo), NUMBA_CACHE_DIR=str(numba_cache),
               MBSYNTH_CACHE_DIR=tempfile.mkdtemp(prefix="mbsynth-cold-"))
    out = subprocess.run([sys.executable, "-c", PROBE, str(repo / "models" / model)], cwd=repo, env=env,
                         capture_output=True, text=True, check=True).stdout.split()
    return tuple(map(float, out))


def warm_kernels(repo, numba_cache):
    """The compiled path's kernels of ``repo`` into ``numba_cache`` (``make install``'s step)."""
    env = dict(os.environ, PYTHONPATH=str(repo), NUMBA_CACHE_DIR=str(numba_cache))
    subprocess.run([sys.executable, "-m", "mbsynth.cli.compile_ahead"], cwd=repo, env=env, check=True,
                   capture_output=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", required=True, help="a checkout's folder to compare with")
    parser.add_argument("--out", default=str(HERE / "cold_models_results.md"))
    args = parser.parse_args()
    started = time.perf_counter()
    trees = {"this": HERE.parent, "baseline": Path(args.baseline).resolve()}
    caches = {name: Path(tempfile.mkdtemp(prefix=f"numba-{name}-")) for name in trees}
    for name, repo in trees.items():
        warm_kernels(repo, caches[name])
    rows = []
    for model in MODELS:
        found = {name: measure(repo, model, caches[name]) for name, repo in trees.items()}
        rows.append((model, found))
        print(model, found, flush=True)
    commit = lambda repo: subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=repo, capture_output=True,  # noqa: E731
                                         text=True).stdout.strip()
    lines = [
        "# A new model's first run, and its runs after",
        "",
        f"`benchmarks/cold_models.py --baseline {args.baseline}` on {platform.node()} ({platform.machine()}, "
        f"{os.cpu_count()} cores), Python {platform.python_version()}, {time.strftime('%Y-%m-%d')}: this checkout "
        f"({commit(trees['this'])}) against {commit(trees['baseline'])}, in {time.perf_counter() - started:.0f} s. "
        "CPU seconds. *first*: a fresh process with an empty mbsynth cache and the kernels of `make install`, "
        "from its start through `load` and `simulate(model, 0.01)`; *later*: the best of five "
        "`simulate(model, 0.5)` in that process.",
        "",
        "| model | first, this | first, baseline | later, this | later, baseline | later, this / baseline |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for model, found in rows:
        (f1, b1), (f2, b2) = found["this"], found["baseline"]
        lines.append(f"| {model} | {f1:.1f} | {f2:.1f} | {b1:.3f} | {b2:.3f} | {b1 / b2:.2f} |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
