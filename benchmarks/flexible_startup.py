"""Load plus the first 0.1 s of a 20-mode Craig–Bampton beam, each in a new process (issue 62).

    .venv/bin/python benchmarks/flexible_startup.py [--runs 3] [--modes 20] [--baseline REV] [--out FILE]

The model: models/flexible/cantilever.yaml (a steel strip of 40 beam elements clamped at
node 0, four node frames, an output at the tip) with MODES fixed-interface modes instead of
four, its first mode struck. Each run is a fresh interpreter doing ``mb.load`` and
``mb.simulate(model, 0.1)`` (default path and integrator), timed inside (load, simulate) and
outside (the whole process, interpreter start included).

- cold: MBSYNTH_CACHE_DIR an empty temporary folder (no derivation, no generated code of any
  model) and NUMBA_CACHE_DIR a fresh copy of the compiled kernels as ``python -m
  mbsynth.cli.compile_ahead`` (``make install``) leaves them: a model never seen, on an
  installed mbsynth;
- warm: the same folders again, as the cold run left them;
- beside them, models/rigid/solid_pendulum.yaml the same way with warm caches: the floor of
  any run (interpreter, imports, the kernels' loading); and ``mbsynth simulate
  models/flexible/cantilever.yaml --t-end 1`` with warm caches.

--baseline REV (a commit of this repository or a checkout's folder) adds, in every run beside
the warm beam, models/mechanisms/simple_pendulum.yaml (a rigid pendulum both codes have) the
same way with warm caches on that code and on this one: a reference measured in the same
run, so that a figure stated against another code's process (issue 62 states its 1.5 s beside
a rigid pendulum's 1.7 s of its day) is read as a ratio rather than across machines. The
baseline's kernels and its model's caches are built first, in folders of their own.

Figures are medians of --runs (each cold run on new folders); on a shared machine the CPU time
(user + system) is the steadier figure. Writes
benchmarks/flexible_startup_results.md unless --out.
"""

import argparse
import datetime
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
MODEL = ROOT / "models" / "flexible" / "cantilever.yaml"
CLI = ["simulate", str(MODEL), "--t-end", "1"]  # the bundled 4-mode strip, 1 s, as a user types it
RIGID = ROOT / "models" / "rigid" / "solid_pendulum.yaml"  # the floor: a rigid pendulum's whole process
SHARED = Path("models") / "mechanisms" / "simple_pendulum.yaml"  # a rigid pendulum every baseline has
CHILD = """\
import gc, sys, time
collecting = [0.0, 0.0]  # the start of the collection under way, the time in collections so far
def timed(phase, info):
    if phase == "start":
        collecting[0] = time.perf_counter()
    else:
        collecting[1] += time.perf_counter() - collecting[0]
gc.callbacks.append(timed)
started = time.perf_counter()
import mbsynth as mb
model = mb.load(sys.argv[1])
loaded = time.perf_counter()
run = mb.simulate(model, 0.1)
done = time.perf_counter()
assert run.status == "completed", run.status
print(f"{loaded - started:.3f} {done - loaded:.3f} {collecting[1]:.3f} {len(run.t)}")
"""

# µs per call on benchmarks/flexible.py's pinned pendulum (8 modes), best of 7 rounds, warm caches
PER_CALL = """\
import sys, time
import numpy as np
sys.path.insert(0, "benchmarks")
import mbsynth as mb
from flexible import pendulum_yaml
from mbsynth.compiled import flexible
from mbsynth.model.data import Data
system = mb.loads(pendulum_yaml(8), name="flexible_pendulum")
q, qd = system.initial_state()
engine = Data(system, "compiled").engine
y = np.concatenate([q, qd])
part = system.parts[0]
n = len(part.q)
M, Q, Mnu, nu = np.zeros((n, n)), np.zeros(n), np.zeros((n - 1, n - 1)), np.zeros(n - 1)
g = part.gravity_at(0.0, system.parameter_values)
arrays = part.kernel_arrays[:6]  # (axes, W, s0, K, D, S): what equations reads
def best(f, count):
    f()
    rounds = []
    for _ in range(7):
        started = time.perf_counter()
        for _ in range(count):
            f()
        rounds.append((time.perf_counter() - started) / count * 1e6)
    return min(rounds)
assert engine.stages().rates(0.0, y) is not None
print(best(lambda: flexible.equations(q[:n], qd[:n], g, *arrays, M, Q, Mnu, nu), 20000),
      best(lambda: engine.motion(0.0, q, qd), 5000), best(lambda: engine.stages().rates(0.0, y), 5000))
"""


def model_text(modes):
    """cantilever.yaml with ``modes`` fixed-interface modes, the first struck."""
    text = MODEL.read_text()
    text = text.replace("modes: 4}", f"modes: {modes}}}")
    rates = ", ".join(["0.05"] + ["0"] * (modes - 1))
    return text.replace("amplitude_rates: [0.05, 0, 0, 0]", f"amplitude_rates: [{rates}]")


def child_environment(root=ROOT, **variables):
    """The environment of a timed process of the code in ``root``: this one's with
    ``variables``, without PYTHONDONTWRITEBYTECODE (set in some sandboxes: every process would
    compile the sources whose bytecode is stale, where a user's installation keeps it)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    return dict(env, PYTHONPATH=str(root), **variables)


def installed_kernels():
    """The folder of numba's cache holding the compiled kernels of this checkout (compiled by
    ``python -m mbsynth.cli.compile_ahead`` first where it holds none)."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "MBSYNTH_CACHE_DIR")}
    env["PYTHONPATH"] = str(ROOT)
    subprocess.run([sys.executable, "-m", "mbsynth.cli.compile_ahead"], env=env, cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    found = subprocess.run([sys.executable, "-c", "import os; from mbsynth.compiled import cache; cache.configure(); "
                            "print(os.environ['NUMBA_CACHE_DIR'])"], env=env, cwd=ROOT, check=True,
                           capture_output=True, text=True)
    return Path(found.stdout.strip())


def compile_ahead(root, cache, numba):
    """Compile the kernels of the code in ``root`` into these folders, as its ``make install``
    does (its compile-ahead command: ``mbsynth.cli.compile_ahead``, or ``mbsynth.compiled``
    in older code)."""
    module = "mbsynth.cli.compile_ahead" if (root / "mbsynth" / "cli" / "compile_ahead.py").exists() else \
        "mbsynth.compiled"
    env = child_environment(root, MBSYNTH_CACHE_DIR=str(cache), NUMBA_CACHE_DIR=str(numba))
    subprocess.run([sys.executable, "-m", module], env=env, cwd=root, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)


def command(arguments, cache, numba):
    """(process wall, its CPU time [s]) of ``python -m mbsynth <arguments>`` in a new process."""
    env = child_environment(MBSYNTH_CACHE_DIR=str(cache), NUMBA_CACHE_DIR=str(numba))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mbsynth", *arguments], env=env, cwd=ROOT, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def timed(path, cache, numba, root=ROOT, **variables):
    """(process wall, its CPU time (user + system, its helpers included), load, simulate, the
    cycle collector's share of load and simulate [s], output rows) of one new process of the
    code in ``root`` (``variables`` added to its environment)."""
    env = child_environment(root, MBSYNTH_CACHE_DIR=str(cache), NUMBA_CACHE_DIR=str(numba), **variables)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", CHILD, str(path)], env=env, cwd=root, capture_output=True, text=True,
                         check=False)
    if out.returncode:
        raise RuntimeError(f"{path} on {root} failed ({out.returncode}): {out.stderr[-3000:]}")
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    load, simulate, collections, rows = out.stdout.split()
    return wall, cpu, float(load), float(simulate), float(collections), int(rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--modes", type=int, default=20)
    parser.add_argument("--out", default=str(HERE / "flexible_startup_results.md"))
    parser.add_argument("--baseline", help="a commit or a checkout's folder: its rigid pendulum in the same runs")
    args = parser.parse_args()
    kernels = installed_kernels()
    cold, warm, shared, base = [], [], [], []
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        path = scratch / f"beam_{args.modes}_modes.yaml"
        path.write_text(model_text(args.modes))
        if args.baseline:
            sys.path.insert(0, str(HERE))
            from startup import baseline_folder

            base_root = baseline_folder(args.baseline, scratch / "baseline")
            base_caches = scratch / "baseline_cache", scratch / "baseline_numba"
            compile_ahead(base_root, *base_caches)
            for variables in ({"MBSYNTH_FAST": "wait"}, {}, {}):  # its model's kernels, then its default path's
                timed(base_root / SHARED, *base_caches, base_root, **variables)
        for k in range(args.runs):
            cache, numba = scratch / f"cache{k}", scratch / f"numba{k}"
            cache.mkdir()
            shutil.copytree(kernels, numba)
            cold.append(timed(path, cache, numba))
            warm.append(timed(path, cache, numba))
            print(f"run {k + 1}: cold {cold[-1][0]:.2f} s ({cold[-1][1]:.2f} s CPU), warm {warm[-1][0]:.2f} s "
                  f"({warm[-1][1]:.2f} s CPU)", flush=True)
            if args.baseline:
                timed(ROOT / SHARED, cache, numba)  # its model's caches filled
                shared.append(timed(ROOT / SHARED, cache, numba))
                base.append(timed(base_root / SHARED, *base_caches, base_root))
                print(f"  {SHARED}: {shared[-1][0]:.2f} s here, {base[-1][0]:.2f} s on {args.baseline}", flush=True)
        timed(RIGID, cache, numba)  # its model's caches filled
        rigid = [timed(RIGID, cache, numba) for _ in range(args.runs)]
        command(CLI, cache, numba)
        cli = [command(CLI, cache, numba) for _ in range(args.runs)]
    rows = [("cold (model caches empty, kernels as installed)", cold), ("warm (the same caches again)", warm),
            ("rigid pendulum (models/rigid/solid_pendulum.yaml), warm", rigid)]
    if args.baseline:
        rows += [(f"rigid pendulum ({SHARED}), warm, each run beside the warm beam", shared),
                 (f"the same pendulum on {args.baseline}, warm, each run beside the warm beam", base)]
    lines = [f"# Load + first 0.1 s of a {args.modes}-mode Craig–Bampton beam, new process",
             "",
             f"`benchmarks/flexible_startup.py --runs {args.runs} --modes {args.modes}"
             f"{f' --baseline {args.baseline}' if args.baseline else ''}`, "
             f"{datetime.date.today()}, {platform.machine()}, {os.cpu_count()} cores (shared: compare within one "
             "table), "
             f"Python {platform.python_version()}. Median of {args.runs} runs; the model is "
             "models/flexible/cantilever.yaml with its modes raised (40 elements, clamped at node 0, four node frames, "
             "an output at the tip); `mb.load` then `mb.simulate(model, 0.1)` on the default path. Load and simulate: "
             "wall time inside the process (interpreter start and imports of mbsynth's floors included in load); "
             "of which in the cycle collector's collections (gc.callbacks; core/collection.py freezes the model "
             "layer's objects after its import).",
             "",
             "| caches | process wall [s] | process CPU [s] | load [s] | simulate 0.1 s [s] | of which collections [s] "
             "| output rows |",
             "|---|---|---|---|---|---|---|"]
    for name, found in rows:
        medians = [statistics.median(x[i] for x in found) for i in range(4)]
        collections = statistics.median(x[4] for x in found)
        lines.append(f"| {name} | " + " | ".join(f"{m:.2f}" for m in medians) + f" | {collections:.3f} | "
                     f"{found[0][5]} |")
    if args.baseline:
        ratio = statistics.median(w[0] / b[0] for w, b in zip(warm, base))
        lines += ["", f"The warm beam's process over {args.baseline}'s rigid pendulum process, each pair from one run, "
                  f"median of {args.runs}: **{ratio:.2f}** (issue 62's target, 1.5 s where a rigid pendulum's process "
                  "took 1.7 s: 0.88)."]
    lines += ["", f"`mbsynth simulate models/flexible/cantilever.yaml --t-end 1` (4 modes), a new process with warm "
              f"caches, median of {args.runs}: {statistics.median(x[0] for x in cli):.2f} s wall, "
              f"{statistics.median(x[1] for x in cli):.2f} s CPU."]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    kernel, motion, stage = map(float, subprocess.run([sys.executable, "-c", PER_CALL], env=env, cwd=ROOT, check=True,
                                                      capture_output=True, text=True).stdout.split())
    lines += ["", "Per call on benchmarks/flexible.py's pinned pendulum (8 modes, 15 coordinates), best of 7 rounds: "
              f"the part's kernel (compiled/flexible.py `equations`, M and Q) {kernel:.1f} µs; `Engine.motion` "
              f"(the compiled path's motion(), the part's kernel included) {motion:.1f} µs; `Stages.rates` "
              f"(an integrator's stage, off the manifold) {stage:.1f} µs."]
    text = "\n".join(lines) + "\n"
    print(text)
    Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
