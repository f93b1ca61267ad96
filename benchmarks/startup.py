"""Start-up cost of mbsynth in fresh processes: `import mbsynth` and `mbsynth check` (issue 20).

    .venv/bin/python benchmarks/startup.py [--runs 5] [--baseline DIR_OR_COMMIT] [--out FILE]

Each command runs --runs times, each in a fresh interpreter, and the median and the fastest
wall times are reported beside the plain interpreter start (`python -c pass`), `import
numpy` (the floor of `import mbsynth`) and `import sympy` (model loading needs sympy: the
floor of any `mbsynth check`).
`mbsynth check` runs as the console script does (`mbsynth.cli.main`). The last column lists
which of the heavy libraries the command left loaded (one more run, not timed).
--baseline runs the same commands on other code (a checkout's folder, or a commit of this
repository, extracted to a temporary folder), first on PYTHONPATH, alternating with this
checkout's, and adds its medians and the ratio: compare figures within one table, the
machines are shared and noisy. The table is written to
benchmarks/startup_results.md unless --out.
"""

import argparse
import io
import os
import platform
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
HEAVY = ("pandas", "dask", "matplotlib", "meshcat", "pinocchio", "numba", "sympy", "scipy.linalg",
         "scipy.integrate")
MAIN = "import sys; from mbsynth.cli import main; sys.exit(main(sys.argv[1:]))"  # the console script
COMMANDS = [
    ("python -c pass", "pass", []),
    ("import numpy", "import numpy", []),
    ("import sympy", "import sympy", []),
    ("import mbsynth", "import mbsynth", []),
    ("mbsynth check models/paper/example3_m1_zero.yaml", MAIN, ["check", "models/paper/example3_m1_zero.yaml"]),
    ("mbsynth check models/robots/ur5_payload.yaml", MAIN, ["check", "models/robots/ur5_payload.yaml"]),
]
# Runs CODE (argv[1]) as `python -c CODE ARGS...` would, then names the heavy modules it loaded.
PROBE = f"""\
import atexit, sys
atexit.register(lambda: sys.stderr.write("HEAVY " + " ".join(m for m in {HEAVY!r} if m in sys.modules) + "\\n"))
code, sys.argv = sys.argv[1], ["-c", *sys.argv[2:]]
exec(compile(code, "<string>", "exec"), {{"__name__": "__main__"}})
"""


def run(repo, code, args, probe=False):
    """Wall time [s] of one fresh ``python -c code args`` in ``repo`` (and, with probe, the
    heavy modules it loaded)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(repo), os.environ.get("PYTHONPATH")])))
    argv = [sys.executable, "-c", PROBE, code, *args] if probe else [sys.executable, "-c", code, *args]
    started = time.perf_counter()
    result = subprocess.run(argv, cwd=repo, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            check=False)
    elapsed = time.perf_counter() - started
    if result.returncode not in (0, 1):  # check answers 1 for a verdict that needs attention
        raise RuntimeError(f"{code} {' '.join(args)} failed ({result.returncode}): {result.stderr[-2000:]}")
    heavy = [line.split()[1:] for line in result.stderr.splitlines() if line.startswith("HEAVY")]
    return elapsed, heavy[-1] if heavy else []


def measure(repos, label, code, argv, runs):
    """(label, medians, fastest times, heavy modules), one entry per repo, the runs alternating
    between the repos so that each sees the same load."""
    for repo in repos:
        run(repo, code, argv)  # warm the file system and the compiled caches
    times = [[] for _ in repos]
    for _ in range(runs):
        for repo, measured in zip(repos, times):
            measured.append(run(repo, code, argv)[0])
    heavy = [run(repo, code, argv, probe=True)[1] for repo in repos]
    print(f"{label}: medians {', '.join(f'{statistics.median(t):.3f}' for t in times)} s", flush=True)
    return label, [statistics.median(t) for t in times], [min(t) for t in times], heavy


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="fresh processes per command (default 5)")
    parser.add_argument("--baseline", help="a checkout's folder or a commit to compare with, in the same run")
    parser.add_argument("--out", type=Path, default=HERE / "startup_results.md", help="the results table")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        repos = [HERE.parent] + ([_baseline(args.baseline, Path(folder))] if args.baseline else [])
        rows = [measure(repos, *command, args.runs) for command in COMMANDS]
    lines = ["# Start-up", "",
             f"`benchmarks/startup.py --runs {args.runs}{f' --baseline {args.baseline}' if args.baseline else ''}` "
             f"on {platform.node()} ({platform.processor() or platform.machine()}, {os.cpu_count()} cores), Python "
             f"{platform.python_version()}, {time.strftime('%Y-%m-%d')}: this checkout ({_commit(HERE.parent)})"
             + (f" against {args.baseline}, runs alternating" if args.baseline else "")
             + ". A fresh process for every run; caches warm.", ""]
    if args.baseline:
        lines += ["| command | median [s] | fastest [s] | heavy modules loaded | baseline median [s] | "
                  "baseline fastest [s] | baseline heavy modules | baseline / this |", "|---|---:|---:|---|---:|---:|---|---:|"]
        lines += [f"| `{label}` | {median[0]:.3f} | {fastest[0]:.3f} | {', '.join(heavy[0]) or '—'} | {median[1]:.3f} | "
                  f"{fastest[1]:.3f} | {', '.join(heavy[1]) or '—'} | {median[1] / median[0]:.1f}× |"
                  for label, median, fastest, heavy in rows]
    else:
        lines += ["| command | median [s] | fastest [s] | heavy modules loaded |", "|---|---:|---:|---|"]
        lines += [f"| `{label}` | {median[0]:.3f} | {fastest[0]:.3f} | {', '.join(heavy[0]) or '—'} |"
                  for label, median, fastest, heavy in rows]
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def _baseline(baseline, folder):
    """The folder of the baseline's code: ``baseline`` itself if it is a folder, else that
    commit of this repository extracted into ``folder``."""
    if Path(baseline).is_dir():
        return Path(baseline).resolve()
    archive = subprocess.run(["git", "-C", str(HERE.parent), "archive", "--format=tar", baseline],
                             capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(folder, filter="data")
    return folder


def _commit(repo):
    result = subprocess.run(["git", "-C", str(repo), "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                            check=False)
    return f"commit {result.stdout.strip()}" if result.returncode == 0 else str(repo)


if __name__ == "__main__":
    main()
