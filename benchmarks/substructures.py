"""Loading N copies of a one-part lagrangian cell: derived and compiled once per file, not per copy.

    .venv/bin/python benchmarks/substructures.py [--copies 1000] [--runs 3] [--out FILE]

The cell is models/substructures/pendulum_cell.yaml (a pendulum given by its energies in
Cartesian coordinates and a rod constraint). ``composed_model`` writes the model of N copies
of it as the issue asks, one ``type: model`` entry with ``count: N`` (copy i's parameters its
own, ``cell[i].m``, its start angle spread by ``index``); ``flat_model`` writes the same
copies as one flat file (part ``pend`` of copy i is ``cell_i_pend``, its parameter ``m_i``),
measured beside it.
Each load runs in a fresh interpreter with the disk derivation cache off
(``MBSYNTH_DERIVATION_CACHE=off``: every sympy derivation is done in that process; numba's
kernels compiled at install stay warm); the table gives the median wall and CPU time of
``mb.load`` for 1 and for N copies and their ratios (at most 5 is the issue's bar), then the
time to build the compiled path of the N-copy model and to simulate it briefly on that path
(asserted taken).
The table goes to benchmarks/substructures_results.md unless --out.
"""

import argparse
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CELL = ROOT / "models" / "substructures" / "pendulum_cell.yaml"
SIM_T_END = 0.5  # [s] of simulated motion: a quarter of the cell's small-swing period
# loads, then simulates the model at argv[1] when argv[2] is "simulate"; prints a JSON line
PROBE = """\
import json, sys, time
import mbsynth as mb
wall, cpu = time.perf_counter(), time.process_time()
system = mb.load(sys.argv[1])
out = {"load": time.perf_counter() - wall, "load_cpu": time.process_time() - cpu, "coordinates": len(system.coordinates)}
if sys.argv[2] == "simulate":
    started = time.perf_counter()
    data = system.data()
    out["compiled"] = data.engine is not None
    out["build"] = time.perf_counter() - started
    started = time.perf_counter()
    result = mb.simulate(system, %r)
    out["simulate"] = time.perf_counter() - started
    out["steps"] = len(result.t)
print(json.dumps(out))
""" % SIM_T_END


def renamed(text, names):
    """``text`` (an expression or a name) with each whole identifier in ``names`` replaced
    by its new name (a dotted reference ``part.x`` is renamed at its part)."""
    return re.sub(r"(?<![\w.])[A-Za-z_]\w*", lambda m: names.get(m.group(0), m.group(0)), str(text))


def copy_names(cell, i):
    """{cell name: copy i's name}: its parts and its parameters."""
    names = {p: f"cell_{i}_{p}" for p in cell["parts"]}
    names.update({p: f"{p}_{i}" for p in cell["parameters"]})
    return names


def flat_model(count, cell_path=CELL):
    """The flat model file (a dict) of ``count`` copies of the cell: copy i's parts and
    parameters renamed (``copy_names``), its initial angle theta0_i spread over the copies."""
    cell = yaml.safe_load(Path(cell_path).read_text())
    model = {"name": f"{cell['name']}_x{count}", "parameters": {}, "parts": {}, "constraints": [],
             "initial": {}}
    for i in range(count):
        names = copy_names(cell, i)
        for key, value in cell["parameters"].items():
            model["parameters"][names[key]] = value
        model["parameters"][names["theta0"]] = round(0.1 + 0.4 * i / max(count - 1, 1), 6)
        for part, spec in cell["parts"].items():
            model["parts"][names[part]] = {k: ([renamed(x, names) for x in v] if k == "coordinates" else
                                                    renamed(v, names) if k in ("T", "V") else v)
                                                for k, v in spec.items()}
        for constraint in cell.get("constraints", []):
            model["constraints"].append({k: f"cell_{i}_{v}" if k == "name" else renamed(v, names)
                                         for k, v in constraint.items()})
        model["initial"].update({renamed(k, names): renamed(v, names) for k, v in cell.get("initial", {}).items()})
    return model


def composed_model(count, cell_path=CELL):
    """The model file (a dict) of ``count`` copies of the cell as one ``type: model`` entry."""
    spread = f"0.1 + 0.4*index/{max(count - 1, 1)}"
    return {"name": f"pendulum_cell_x{count}", "parameters": {"N": count},
            "parts": {"cell": {"type": "model", "file": str(cell_path), "count": "N",
                                    "parameters": {"theta0": spread}}}}


def run(path, simulate=False):
    """One fresh interpreter loading (and simulating) the model at ``path``, cold derivation cache."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])),
               MBSYNTH_DERIVATION_CACHE="off", **({"MBSYNTH_COMPILED": "wait"} if simulate else {}))
    result = subprocess.run([sys.executable, "-c", PROBE, str(path), "simulate" if simulate else "load"],
                            cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    if result.returncode:
        raise RuntimeError(f"loading {path} failed: {result.stderr[-3000:]}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--copies", type=int, default=1000)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--out", type=Path, default=HERE / "substructures_results.md")
    args = parser.parse_args(argv)
    cases = [("composed", 1, composed_model), ("composed", args.copies, composed_model),
             ("flat", args.copies, flat_model)]
    with tempfile.TemporaryDirectory() as folder:
        paths = {}
        for kind, count, write in cases:
            paths[kind, count] = Path(folder) / f"{kind}_{count}.yaml"
            paths[kind, count].write_text(yaml.safe_dump(write(count), sort_keys=False))
        runs = {case: [run(path) for _ in range(args.runs)] for case, path in paths.items()}
        simulated = run(paths["composed", args.copies], simulate=True)
    if not simulated["compiled"]:
        raise SystemExit(f"the {args.copies}-copy model did not take the compiled path")
    median = {case: {key: statistics.median(r[key] for r in found) for key in ("load", "load_cpu")}
              for case, found in runs.items()}
    one = median["composed", 1]
    rows = [f"| model file | copies | coordinates | load wall [s] | ratio | load CPU [s] | ratio |",
            "|---|---:|---:|---:|---:|---:|---:|"]
    for kind, count, _ in cases:
        m = median[kind, count]
        rows.append(f"| {kind} | {count} | {2 * count} | {m['load']:.2f} | {m['load'] / one['load']:.2f} | "
                    f"{m['load_cpu']:.2f} | {m['load_cpu'] / one['load_cpu']:.2f} |")
    text = "\n".join([
        "# Substructures: N copies of one lagrangian cell", "",
        "`benchmarks/substructures.py`: `mb.load` of a model of N copies of",
        f"`{CELL.relative_to(ROOT)}` (each copy with parameters of its own; `composed`: one",
        "`type: model` entry with `count: N`; `flat`: the same copies written out), each load in a fresh",
        "interpreter after `import mbsynth` (so it includes importing sympy and the loader) with the",
        "disk derivation cache off (`MBSYNTH_DERIVATION_CACHE=off`: every sympy derivation is done in",
        f"that process); medians of {args.runs} runs; ratios to one composed copy (the bar: at most 5×).", "",
        *rows, "",
        f"The {args.copies}-copy model on the compiled path (asserted): its Template built and its generated",
        f"function compiled (`system.data()`, MBSYNTH_COMPILED=wait) in {simulated['build']:.1f} s, then",
        f"`mb.simulate` for {SIM_T_END} s of motion in {simulated['simulate']:.2f} s ({simulated['steps']} recorded steps).", "",
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()};",
        "shared with other work: compare figures within one table, CPU times are the steadier.", ""])
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
