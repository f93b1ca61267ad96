"""Start-up cost of mbsynth in fresh processes: `import mbsynth` and `mbsynth check` (issue 20).

    .venv/bin/python benchmarks/startup.py [--runs 5] [--baseline DIR_OR_COMMIT] [--out FILE]

Each command runs --runs times, each in a fresh interpreter; the table gives the medians of
its wall time and of its CPU time (user + system: less sensitive to a shared machine's
load), and which of the heavy libraries it left loaded (one more run, not timed). Beside
mbsynth's commands: the interpreter's start (`python -c pass`), `import numpy` (the floor
of `import mbsynth`) and `import sympy` (model loading needs sympy: the floor of any
`mbsynth check`). `mbsynth check` runs as the console script does (`mbsynth.cli.main`).

--baseline runs the same commands on other code (a checkout's folder, or a commit of this
repository extracted to a temporary folder), first on PYTHONPATH, alternating with this
checkout's, and adds its medians and the ratios: compare figures within one table, the
machines are shared and noisy. The table goes to benchmarks/startup_results.md unless --out.
"""

import argparse
import io
import os
import platform
import resource
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
    """Wall and CPU (user + system) time [s] of one fresh ``python -c code args`` in ``repo``,
    and with probe the heavy modules it loaded."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(repo), os.environ.get("PYTHONPATH")])))
    argv = [sys.executable, "-c", PROBE, code, *args] if probe else [sys.executable, "-c", code, *args]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    result = subprocess.run(argv, cwd=repo, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            check=False)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode not in (0, 1):  # check answers 1 for a verdict that needs attention
        raise RuntimeError(f"{code} {' '.join(args)} failed ({result.returncode}): {result.stderr[-2000:]}")
    heavy = [line.split()[1:] for line in result.stderr.splitlines() if line.startswith("HEAVY")]
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return wall, cpu, heavy[-1] if heavy else []


def measure(repos, label, code, argv, runs):
    """``label`` and, per repo, (median wall time, median CPU time, heavy modules), the runs
    alternating between the repos so that each sees the same load."""
    for repo in repos:
        run(repo, code, argv)  # warm the file system and the compiled caches
    times = [[] for _ in repos]
    for _ in range(runs):
        for repo, measured in zip(repos, times):
            measured.append(run(repo, code, argv)[:2])
    results = [(statistics.median(w for w, _ in t), statistics.median(c for _, c in t),
                run(repo, code, argv, probe=True)[2]) for repo, t in zip(repos, times)]
    print(f"{label}: {results}", flush=True)
    return label, results


def table(rows, baseline):
    """The markdown table: per repo wall and CPU medians and the heavy modules; with a
    baseline, its figures and the ratios baseline / this."""
    head = ["command", "wall [s]", "CPU [s]", "heavy modules loaded"]
    if baseline:
        head += ["baseline wall [s]", "baseline CPU [s]", "baseline heavy modules", "baseline / this (wall, CPU)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---:" if "[s]" in h else "---" for h in head) + "|"]
    for label, results in rows:
        cells = [f"`{label}`"]
        for wall, cpu, heavy in results:
            cells += [f"{wall:.3f}", f"{cpu:.3f}", ", ".join(heavy) or "—"]
        if baseline:
            (wall, cpu, _), (base_wall, base_cpu, _) = results
            cells.append(f"{base_wall / wall:.1f}×, {base_cpu / cpu:.1f}×")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="fresh processes per command (default 5)")
    parser.add_argument("--baseline", help="a checkout's folder or a commit to compare with, in the same run")
    parser.add_argument("--out", type=Path, default=HERE / "startup_results.md", help="the results table")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        repos = [HERE.parent] + ([baseline_folder(args.baseline, Path(folder))] if args.baseline else [])
        rows = [measure(repos, *command, args.runs) for command in COMMANDS]
    lines = ["# Start-up", "",
             f"`benchmarks/startup.py --runs {args.runs}{f' --baseline {args.baseline}' if args.baseline else ''}` "
             f"on {platform.node()} ({platform.processor() or platform.machine()}, {os.cpu_count()} cores), Python "
             f"{platform.python_version()}, {time.strftime('%Y-%m-%d')}: this checkout ({_commit(HERE.parent)})"
             + (f" against {args.baseline}, runs alternating" if args.baseline else "")
             + ". A fresh process for every run, caches warm; medians of the runs.", "",
             *table(rows, args.baseline)]
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def baseline_folder(baseline, folder):
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
