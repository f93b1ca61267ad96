"""The fast kernel of the working tree against the same kernel at a git revision, in one process.

On a shared machine the time of one evaluation moves by 10–20 % between processes and
minutes, more than most changes to the kernel; two builds timed in separate runs cannot be
compared. This script puts the revision's package beside the working tree's (``git archive``
into ``<cache>/ab/<commit>/mbsynth_<commit>``, compiled once into its own numba cache),
calls both kernels from Python on the same state with the same buffers and mode, as
System.motion does, in interleaved rounds, and prints both times and their ratio (new / old: below 1 is
faster), with the largest difference of the two q̈. Not from a numba loop: a loop compiled
in the process that compiled the kernel can inline it and hoist its views out of the loop,
which made one build look 15 % faster than it runs when loaded from the cache.

    .venv/bin/python benchmarks/fast_ab.py [--rev HEAD~1] [ur5 talos 100 ...]

Robots by name (example-robot-data; talos and solo12 with a floating base), chains by their
number of links. The revision must pack the Layout and Work as the working tree does (the
same fields): else the script says so and stops.
"""

import argparse
import importlib
import io
import shutil
import subprocess
import sys
import tarfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fast_dynamics import best, chain_case, robot_case  # noqa: E402

from mbsynth.compiled import cache, engine_for, kernel  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
ROUNDS = 15


def package_at(rev):
    """The kernel module of the package at ``rev``, imported as ``mbsynth_<commit>``."""
    commit = subprocess.run(["git", "rev-parse", "--short=12", rev], cwd=ROOT, capture_output=True, text=True,
                            check=True).stdout.strip()
    name = f"mbsynth_{commit}"
    home = cache.cache_dir() / "ab" / commit
    if not (home / name).exists():
        shutil.rmtree(home / "partial", ignore_errors=True)  # left by an interrupted run
        archive = subprocess.run(["git", "archive", commit, "mbsynth"], cwd=ROOT, capture_output=True,
                                 check=True).stdout
        with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
            tar.extractall(home / "partial", filter="data")
        (home / "partial" / "mbsynth").rename(home / name)
        (home / "partial").rmdir()
    sys.path.insert(0, str(home))
    folder = "compiled" if (home / name / "compiled").is_dir() else "fast"  # the compiled path's folder then
    return commit, importlib.import_module(f"{name}.{folder}.kernel")


def same_packing(old):
    """Whether the old kernel reads the Layout and Work fields the working tree packs."""
    return [list(f.__members__) for f in (old.LAYOUT, old.WORK)] == \
        [list(f.__members__) for f in (kernel.LAYOUT, kernel.WORK)]


def _call_tail(module, engine):
    """The arguments after the Work of a kernel's ``motion``: the mode motion() calls it in
    (engine.py: a rigid tree's residual is checked when read, not per call) where it takes
    one, its ``drift`` where it takes that (−1: on the manifold), then its ``general`` where
    it takes that."""
    mode = (engine.mode,) if hasattr(module, "CHECKED") else ()
    drift = (-1.0,) if hasattr(module, "NEAR_SINGULAR") else ()
    return mode + drift + ((engine.general,) if hasattr(module, "GENERAL") else ())


def compare(label, old, new):
    case = chain_case(int(label)) if label.isdigit() else robot_case(label, label in ("talos", "solo12"))
    engine = engine_for(case.system)
    q, v = case.draw(np.random.default_rng(0))
    qm, qdm = case.to_maximal(q, v)
    args = {module: (qm, qdm, engine.gen, np.zeros(0), *engine.buffers, *_call_tail(module, engine))
            for module in (old, new)}
    results = []
    for module in (old, new):
        module.motion(*args[module])
        results.append(engine.W.qdd.copy())
    times = {old: [], new: []}
    for _ in range(ROUNDS):
        for module in (old, new):
            times[module].append(best(lambda: module.motion(*args[module]), seconds=0.2))
    before, after = min(times[old]), min(times[new])
    paired = np.median(np.array(times[new]) / np.array(times[old]))
    return (f"| {label} | {before * 1e6:.2f} | {after * 1e6:.2f} | {after / before:.3f} | {paired:.3f} | "
            f"{np.abs(results[0] - results[1]).max():.1e} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rev", default="HEAD", help="the git revision to compare with (default HEAD)")
    parser.add_argument("systems", nargs="*", default=["ur5", "talos", "100"])
    args = parser.parse_args()
    commit, old = package_at(args.rev)
    if not same_packing(old):
        sys.exit(f"fast_ab: {args.rev} ({commit}) packs a different Layout or Work than the working tree; "
                 "its kernel cannot read these buffers")
    print(f"kernel.motion µs per call from Python, {commit} against the working tree, best of {ROUNDS} "
          "interleaved rounds\n")
    print("| system | old | new | new / old | median of paired rounds | largest q̈ difference |")
    print("|---|---:|---:|---:|---:|---:|")
    for label in args.systems:
        print(compare(label, old, kernel), flush=True)


if __name__ == "__main__":
    main()
