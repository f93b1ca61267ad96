"""Where one ``motion()`` on a robot spends its time, against ``pinocchio.aba``, in one process.

    PYTHONPATH=. .venv/bin/python benchmarks/robot_motion_breakdown.py [--rounds R]

For talos (floating base) and the UR5 of example-robot-data, at one state drawn in
Pinocchio's coordinates and mapped to mbsynth's (robots/twin.py), caches warm:

- the layers from Python: ``System.motion`` (finds the model's default Data), ``Data.motion``
  (picks the path), ``Data.acceleration`` (q̈ alone into the Data's own array, as ``aba``
  writes ``data.ddq``: no Motion, nothing allocated), ``Engine.motion_copied`` (compiled/engine.py: one compiled call, single.py,
  that copies the state, evaluates the generated function and the kernel; the ``Motion``),
  ``Engine.motion`` (the generated function and the kernel in two calls, on copies made
  before: Baumgarte's shifts, a drifted model with loops), the Engine's lean entry for an integrator's stage
  (``Stages.rates`` of compiled/staged.py as ``simulate``'s stages call it: ẏ in the
  integrator's form, analysis/velocity_form.py), and ``kernel.motion`` called alone from Python;
- the Python → numba call alone: an empty njit function with kernel.motion's argument count,
  called with the same arguments, and the generated function's own call (codegen.py);
- the ``Motion`` made from the kernel's results (core/equations.py) and the per-call check
  of the state (``System._state``);
- each stage of kernel.motion (compiled/kernel.py, assembly.py, tree.py) alone with the same
  arrays: kernel.motion's source is rewritten so that the statement calling the stage runs
  K times in a numba loop after the statements before it ran once; the stage costs
  (time(K) − time(0)) / K. "the rest" is kernel.motion in a numba loop less the stages;
- ``motion_batch`` of BATCH states, per state;
- the same robot with each welded link (a fixed joint to its parent) merged into its nearest
  link on a movable joint (``from_robot(..., merge_fixed=True)``: fewer bodies and
  coordinates, the dynamics of the movable joints unchanged, as Pinocchio merges them):
  ``Data.motion``, kernel.motion in a numba loop and each of its stages, whose difference
  from the robot as it is, over the welded links, is what a welded link costs each stage.
  Its q̈, mapped to Pinocchio's v̇, is compared with ``aba`` on the robot as it is.

The machine is shared by several processes: every figure is the minimum over ROUNDS rounds
in which the callables of a robot take turns (a round times a sample of SAMPLE_S of each), so
load hits all of them alike; ratios are to ``aba``'s minimum in the same rounds. The layers
from Python take their turns apart from the numba loops (each group with ``aba``): taking
turns with those loops, whose arrays push theirs out of the caches, the first layer after
them read up to a third slower than in a loop of its own. Writes
benchmarks/robot_motion_breakdown_results.md.
"""

import argparse
import ast
import datetime
import inspect
import os
import platform
import textwrap
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from numba import njit

import mbsynth as mb
from mbsynth.analysis.velocity_form import VelocityForm
from mbsynth.compiled import kernel
from mbsynth.compiled.engine import EMPTY
from mbsynth.core.equations import Motion
from mbsynth.robots.twin import Twin
from mbsynth.robots.validate import sample_pinocchio_state

HERE = Path(__file__).resolve().parent
ROBOTS = [("talos", True), ("ur5", False)]
ROUNDS, SAMPLE_S, REPEAT, BATCH = 100, 1e-2, 20, 1024  # rounds, seconds a sample lasts, stage runs per loop
FIXED_ROWS = 6  # a node hung by six rows: welded to its parent
BATCH_SAMPLE_S = 1e-2  # a batch's sample: one batch, or as many aba calls as last as long
# stage label → the function kernel.motion's statement calls (the first such statement on the
# full path, after ``generated``: the REUSED shortcut before it is not a robot's call)
STAGES = {
    "generated outputs into Q, C (assembly.generated)": "generated",
    "body blocks (assembly.nodes)": "nodes",
    "mass scaling (assembly.divide_masses)": "divide_masses",
    "joint rows (assembly.tree_rows)": "tree_rows",
    "transports (assembly.transports)": "transports",
    "tree right side (assembly.tree_rhs)": "tree_rhs",
    "elimination (tree.factor)": "factor",
    "solve (tree.solve)": "solve",
    "recovery of q̈, Qc (kernel._recover)": "_recover",
    "residual check (kernel._residual; per call only where checked)": "_residual",
    "finiteness check (kernel._finite)": "_finite",
}


def _calls(node):
    return {n.func.id for n in ast.walk(node) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}


def _kernel_source():
    tree = ast.parse(textwrap.dedent(inspect.getsource(kernel.motion.py_func)))
    function = tree.body[0]
    function.decorator_list = []
    return tree, function


def _split(body):
    """(the views before the full path, the full path's statements): the full path starts at
    the statement calling ``generated``; the REUSED shortcut before it is left out."""
    start = next(i for i, s in enumerate(body) if "generated" in _calls(s))
    prelude = [s for s in body[:start] if not (isinstance(s, ast.If) and "REUSED" in ast.unparse(s.test))]
    return prelude, body[start:]


def _stage_statement(statement, function):
    """The statement run K times: an ``if`` whose test calls the stage (``if factor(...) >= 0:
    return``) as its call alone; any other statement whole."""
    if isinstance(statement, ast.If) and function in _calls(statement.test):
        test = statement.test
        return ast.Expr(test.left if isinstance(test, ast.Compare) else test)
    if isinstance(statement, ast.If) and function == "_finite":  # ``if not _finite(...): return``
        return ast.Expr(statement.test.operand if isinstance(statement.test, ast.UnaryOp) else statement.test)
    return statement


def stage_loop(function):
    """kernel.motion's source as ``f(count, *arguments)``: the views, the full path's
    statements before the one calling ``function`` once, that statement ``count`` times
    (solve: with the copy of its right side before it, which it overwrites)."""
    tree, motion = _kernel_source()
    prelude, path = _split(motion.body)
    index = next(i for i, s in enumerate(path) if function in _calls(s))
    start = index - 1 if function == "solve" and "_copy" in _calls(path[index - 1]) else index  # y ← ry first
    repeated = ast.For(target=ast.Name("_again", ast.Store()), iter=ast.Call(ast.Name("range", ast.Load()),
                       [ast.Name("_count", ast.Load())], []),
                       body=[_stage_statement(s, function) for s in path[start:index + 1]], orelse=[])
    motion.body = prelude + path[:start] + [repeated, ast.parse("return OK, 0.0").body[0]]
    motion.args.args.insert(0, ast.arg("_count"))
    ast.fix_missing_locations(tree)
    namespace = dict(vars(kernel))
    exec(compile(tree, f"<stage {function}>", "exec"), namespace)
    return njit(namespace["motion"])


def whole_loop():
    """kernel.motion ``count`` times in a numba loop."""
    motion = kernel.motion

    @njit
    def loop(count, q, qd, gen, bshift, LI, LF, LX, WI, WF, WX, mode, drift, general):
        for _ in range(count):
            motion(q, qd, gen, bshift, LI, LF, LX, WI, WF, WX, mode, drift, general)
        return kernel.OK, 0.0
    return loop


def empty_call(count):
    """An njit function of ``count`` arguments returning kernel.motion's (status, residual)."""
    names = ", ".join(f"a{i}" for i in range(count))
    namespace = {}
    exec(f"def empty({names}):\n    return 0, 0.0\n", namespace)
    return njit(namespace["empty"])


def rounds(callables, rounds, seconds):
    """{label: the minimum over ``rounds`` of one call's mean time in a sample of about
    ``seconds``}, the callables taking turns within each round. Every sample lasts about
    as long (each callable's count of calls per sample is set from its first calls), so
    that each has the same chance of a quiet moment of the machine. Each sample follows one
    untimed call: the first calls after the other callables' samples are slower, their
    arrays and code pushed out of the caches (the turns' cost, not the call's)."""
    counts = {}
    for label, fn in callables.items():
        fn()
        once = np.inf
        for _ in range(3):
            started = time.perf_counter()
            fn()
            once = min(once, time.perf_counter() - started)
        counts[label] = max(1, int(seconds / max(once, 1e-8)))
    best = {label: np.inf for label in callables}
    for _ in range(rounds):
        for label, fn in callables.items():
            count = counts[label]
            fn()  # untimed: the first call after the others' samples pays for what they pushed out of the caches
            started = time.perf_counter()
            for _ in range(count):
                fn()
            best[label] = min(best[label], (time.perf_counter() - started) / count)
    return best


def merged_robot(name, floating, names, q, v, a):
    """The robot with its welded links merged (``from_robot(..., merge_fixed=True)``): (Data,
    its state at Pinocchio's (q, v), the kernel's arguments, the largest difference of its v̇
    from ``a`` = aba on the robot as it is, whose Pinocchio joints are ``names``, its bodies, its n)."""
    system = mb.from_robot(name, floating=floating, merge_fixed=True)
    twin = Twin(system)
    assert list(twin.model.names) == names, "the merged robot's Pinocchio joints differ"
    qm, qdm = twin.to_maximal(q, v)
    data = system.data()
    motion = data.motion(0.0, qm, qdm)
    assert motion.method == "tree (Baraff)", motion.method
    error = float(np.abs(twin.to_pinocchio(qm, qdm, motion.qdd)[2] - a).max())
    engine = data.engine
    return data, (qm, qdm), (qm, qdm, engine.gen, EMPTY, *engine.buffers, engine.mode, -1.0, engine.general), \
        error, len(engine.L.node_kind), system.n


def robot(name, floating, loops, empty, args_rounds):
    system = mb.from_robot(name, floating=floating)
    twin = Twin(system)
    rng = np.random.default_rng(0)
    q, v = sample_pinocchio_state(twin, rng)
    qm, qdm = twin.to_maximal(q, v)
    tau = np.zeros(twin.model.nv)
    data = system.data()
    motion = data.motion(0.0, qm, qdm)
    assert motion.method == "tree (Baraff)", motion.method
    engine = data.engine
    a = pin.aba(twin.model, twin.data, q, v, tau)
    form = VelocityForm(system)
    y, stages = form.to_integrator(qm, qdm), engine.stages(form.starts)  # a stage as simulate hands it over
    args = (qm, qdm, engine.gen, EMPTY, *engine.buffers, engine.mode, -1.0, engine.general)  # as motion() calls it
    checked = (*args[:-3], kernel.CHECKED, *args[-2:])  # the stages: the residual check runs too
    W = engine.W
    gen_args = (0.0, qm, qdm, engine.p, engine.gen)
    layers = {
        "pinocchio.aba": lambda: pin.aba(twin.model, twin.data, q, v, tau),
        "System.motion": lambda: system.motion(0.0, qm, qdm),
        "Data.motion": lambda: data.motion(0.0, qm, qdm),
        "Data.acceleration (q̈ alone, into data.qdd)": lambda: data.acceleration(0.0, qm, qdm),
        "Engine.motion_copied (Data.motion's one call: single.py)": lambda: engine.motion_copied(0.0, qm, qdm),
        "Engine.motion (two calls: with Baumgarte's shifts, a drifted loop)": lambda: engine.motion(0.0, qm, qdm),
        "Stages.rates (the integrator's stage)": lambda: stages.rates(0.0, y),
        "kernel.motion from Python": lambda: kernel.motion(*args),
        f"empty njit call, {len(args)} arguments": lambda: empty(*args),
        "generated function (codegen)": (lambda: engine.module.evaluate(*gen_args)) if engine.module else None,
        "Motion from the results (copies of q̈, Qc)": lambda: Motion.made(W.qdd.copy(), True, engine.no_freedom,
                                                                          W.Qc.copy(), 0.0, "tree (Baraff)"),
        "state check (System._state)": lambda: system._state(qm, qdm),
    }
    layers = {k: f for k, f in layers.items() if f is not None}
    data_m, state_m, args_m, merged_error, merged_bodies, merged_n = merged_robot(name, floating, list(twin.model.names), q, v, a)
    layers["Data.motion, welded links merged (merge_fixed=True)"] = lambda: data_m.motion(0.0, *state_m)
    checked_m = (*args_m[:-3], kernel.CHECKED, *args_m[-2:])
    kernel_loops = {label: (lambda f=f, a=(args if label == "whole" else checked): f(REPEAT, *a))
                    for label, f in loops.items()}
    kernel_zero = {label: (lambda f=f: f(0, *checked)) for label, f in loops.items() if label != "whole"}
    merged_loops = {label: (lambda f=f: f(REPEAT, *checked_m)) for label, f in loops.items() if label != "whole"}
    merged_zero = {label: (lambda f=f: f(0, *checked_m)) for label, f in loops.items() if label != "whole"}
    callables = {"aba": layers["pinocchio.aba"], **{("K", k): f for k, f in kernel_loops.items()},
                 **{("0", k): f for k, f in kernel_zero.items()}, "merged": lambda: loops["whole"](REPEAT, *args_m),
                 **{("Km", k): f for k, f in merged_loops.items()}, **{("0m", k): f for k, f in merged_zero.items()}}
    # the layers from Python in rounds of their own: the numba loops' arrays, taking turns with them, pushed
    # theirs out of the caches (talos's System.motion read 73 µs there against 54 in a loop of its own)
    best = {**rounds(layers, args_rounds, SAMPLE_S), **rounds(callables, args_rounds, SAMPLE_S)}
    whole = best[("K", "whole")] / REPEAT
    stages = {label: max(0.0, (best[("K", label)] - best[("0", label)]) / REPEAT) for label in STAGES}
    merged_stages = {label: max(0.0, (best[("Km", label)] - best[("0m", label)]) / REPEAT) for label in STAGES}
    per_call = [label for label in STAGES if engine.mode == kernel.CHECKED or STAGES[label] != "_residual"]
    states = [twin.to_maximal(*sample_pinocchio_state(twin, rng)) for _ in range(BATCH)]
    Q, QD = np.array([s[0] for s in states]), np.array([s[1] for s in states])
    batch = rounds({"aba": layers["pinocchio.aba"], "batch": lambda: data.motion_batch(0.0, Q, QD)},
                   max(5, args_rounds // 20), BATCH_SAMPLE_S)
    qdd, _ = data.motion_batch(0.0, Q, QD)
    error = float(np.abs(qdd[0] - data.motion(0.0, Q[0], QD[0], method="reference").qdd).max())
    return dict(label=f"{name}{' (floating)' if floating else ''}", aba_kernel=best["aba"],
                bodies=len(engine.L.node_kind), n=system.n,
                welded=int(np.sum(engine.L.node_k == FIXED_ROWS)), joints=twin.model.njoints - 1,
                nv=twin.model.nv, layers={k: best[k] for k in layers}, whole=whole, stages=stages, per_call=per_call,
                batch=batch["batch"] / BATCH, batch_aba=batch["aba"], error=error, a=a,
                merged=best["merged"] / REPEAT, merged_error=merged_error, merged_bodies=merged_bodies,
                merged_n=merged_n, merged_stages=merged_stages)


def table(results, rounds_used):
    cpu = platform.processor() or platform.machine()
    lines = ["# Where one motion() on a robot spends its time", "",
             f"{datetime.date.today()}, {cpu}, {os.cpu_count()} cores (shared with other processes: every time "
             f"is the minimum over {rounds_used} rounds in which all callables of a robot take turns), Python "
             f"{platform.python_version()}, Pinocchio {pin.__version__}; written by "
             "`benchmarks/robot_motion_breakdown.py` (its docstring says how each row is measured). "
             "µs per call; × is the ratio to `pinocchio.aba` in the same rounds.", "",
             "| | " + " | ".join(f"{r['label']}: {r['bodies']} bodies, n = {r['n']}, nv = {r['nv']}" for r in results)
             + " |", "|---|" + "---:|" * len(results)]

    def row(label, values, ratio=True):
        cells = []
        for r, value in zip(results, values):
            aba = r["layers"]["pinocchio.aba"]
            cells.append(f"{value * 1e6:.2f}" + (f" ({value / aba:.2f}×)" if ratio else ""))
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    for label in results[0]["layers"]:
        row(label, [r["layers"].get(label, np.nan) for r in results], label != "pinocchio.aba")
    lines.append("| **kernel.motion in a numba loop** | " + " | ".join(
        f"**{r['whole'] * 1e6:.2f}** ({r['whole'] / r['aba_kernel']:.2f}× aba {r['aba_kernel'] * 1e6:.2f})"
        for r in results) + " |")
    for label in STAGES:
        row(f"&nbsp;&nbsp;{label}", [r["stages"][label] for r in results], False)
    row("&nbsp;&nbsp;the rest (views, branches)", [r["whole"] - sum(r["stages"][k] for k in r["per_call"])
                                                    for r in results], False)
    lines.append(f"| motion_batch of {BATCH} states, per state | " + " | ".join(
        f"{r['batch'] * 1e6:.2f} ({r['batch'] / r['batch_aba']:.2f}× aba {r['batch_aba'] * 1e6:.2f})"
        for r in results) + " |")
    lines.append("| **kernel.motion in a numba loop, welded links merged (merge_fixed=True)** | " + " | ".join(
        f"**{r['merged'] * 1e6:.2f}** ({r['merged'] / r['aba_kernel']:.2f}× aba {r['aba_kernel'] * 1e6:.2f})"
        for r in results) + " |")
    lines += ["", "Each stage on the robot as it is and with its welded links merged (the same loops), and what "
              "each welded link adds to it (the difference over the welded links):", "",
              "| stage | " + " | ".join(f"{r['label']}: as it is | merged | per welded link (ns)" for r in results)
              + " |", "|---|" + "---:|---:|---:|" * len(results)]
    for label in [*STAGES, "whole"]:
        cells = []
        for r in results:
            alone = r["whole"] if label == "whole" else r["stages"][label]
            merged = r["merged"] if label == "whole" else r["merged_stages"][label]
            cells.append(f"{alone * 1e6:.2f} | {merged * 1e6:.2f} | {(alone - merged) / r['welded'] * 1e9:.0f}")
        lines.append(f"| {'the whole kernel (a numba loop)' if label == 'whole' else label} | " + " | ".join(cells)
                     + " |")
    lines += ["", "Per body: " + "; ".join(
        f"{r['label']}: the kernel {r['whole'] / r['bodies'] * 1e9:.0f} ns on each of its {r['bodies']} bodies "
        f"({r['welded']} of them welded to their parent by a fixed joint, which Pinocchio merges into the parent's "
        f"inertia), aba {r['layers']['pinocchio.aba'] / r['joints'] * 1e9:.0f} ns on each of its {r['joints']} "
        "joints" for r in results) + ".", ""]
    lines += ["The kernel runs in the mode motion() calls it in (compiled/engine.py: a rigid tree's residual is "
              "checked when read, not per call); its residual check is timed alone all the same, and left out of "
              "the rest where it does not run per call. "
              "motion_batch runs one thread per core; aba is one call on one thread. Largest |q̈| difference "
              "of the batch's first state from `data.motion(..., method=\"reference\")`: " +
              ", ".join(f"{r['label']} {r['error']:.1e}" for r in results) + ".", "",
              "Welded links merged into their nearest link on a movable joint (`from_robot(..., "
              "merge_fixed=True)`, each merged link a frame of that link's body): " + "; ".join(
                  f"{r['label']} {r['merged_bodies']} bodies, n = {r['merged_n']}, its v̇ within "
                  f"{r['merged_error']:.1e} of aba on the robot as it is" for r in results) + ".", ""]
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=ROUNDS)
    options = parser.parse_args()
    loops = {"whole": whole_loop(), **{label: stage_loop(function) for label, function in STAGES.items()}}
    empty = empty_call(len(inspect.signature(kernel.motion.py_func).parameters))
    results = [robot(name, floating, loops, empty, options.rounds) for name, floating in ROBOTS]
    text = table(results, options.rounds)
    (HERE / "robot_motion_breakdown_results.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
