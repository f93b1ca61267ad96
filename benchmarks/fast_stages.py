"""Where the time of one fast evaluation goes: each stage of ``kernel.motion`` and the Python
around it. Writes benchmarks/fast_stages_results.md.

A stage's cost is measured by running it REPEAT more times inside the kernel: the source of
``kernel.motion`` is rewritten (ast) so that one top-level statement sits in a loop, each
variant is compiled beside an unchanged copy, and the stage costs (variant − copy) / REPEAT.
Timed in a numba loop of CALLS calls, variants and copy in interleaved rounds, best of each:
every variant is compiled in this process, so inlining into the loop biases all alike, and
the difference is the stage's own time with the rest of the kernel warm around it. "Python
around the kernel" is System.motion less kernel.motion, both called from Python (argument
checks, the generated function, the lock, copies, the Motion).

    .venv/bin/python benchmarks/fast_stages.py [ur5 talos 100 ...]
"""

import ast
import inspect
import os
import platform
import sys
import textwrap
import time
from datetime import date
from pathlib import Path

import numpy as np
from numba import njit

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from fast_dynamics import best, chain_case, robot_case  # noqa: E402

from mbsynth.compiled import engine_for, kernel  # noqa: E402

REPEAT, CALLS, ROUNDS = 10, 2000, 7
# stage label → the kernel function its statement calls (solve: with the copy of its right side)
STAGES = {
    "body blocks (bodies.nodes)": "nodes",
    "joint rows (assembly.tree_rows)": "tree_rows",
    "transports (assembly.transports)": "transports",
    "elimination (tree.factor)": "factor",
    "solve (tree.solve)": "solve",
    "recovery of q̈, Qc (kernel._recover)": "_recover",
    "residual check (kernel._residual)": "_residual",
}


def _calls(statement):
    return {node.func.id for node in ast.walk(statement)
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)}


def _stage_lines(body, function):
    """Indices of the top-level statements of kernel.motion that make the stage calling
    ``function`` (solve: the copy of its right side before it, which it overwrites)."""
    for index, statement in enumerate(body):
        if function in _calls(statement):
            if function == "solve" and "_copy" in _calls(body[index - 1]):
                return index - 1, index + 1
            return index, index + 1
    raise SystemExit(f"fast_stages: kernel.motion no longer calls {function}; update STAGES")


def _repeated(statements, function):
    """The statements as a loop of REPEAT runs: an ``if`` that calls ``function`` in its test
    (``if ... f(...) >= 0: return``) as that test alone; one that calls it in a branch
    whole, so that the branch this Layout takes runs."""
    body = []
    for statement in statements:
        if isinstance(statement, ast.If) and function in _calls(statement.test):
            test = statement.test
            statement = ast.Expr(test.left if isinstance(test, ast.Compare) else test)
        body.append(statement)
    return ast.For(target=ast.Name("_again", ast.Store()),
                   iter=ast.Call(ast.Name("range", ast.Load()), [ast.Constant(REPEAT)], []), body=body, orelse=[])


def variant(span=None, called=None):
    """A numba loop of kernel.motion's source, with the statements in ``span`` (the stage
    calling the function named ``called``) repeated."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(kernel.motion.py_func)))
    function = tree.body[0]
    function.decorator_list = []
    if span is not None:
        start, stop = span
        function.body[start:stop] = [_repeated(function.body[start:stop], called)]
    ast.fix_missing_locations(tree)
    namespace = dict(vars(kernel))
    exec(compile(tree, "<fast_stages>", "exec"), namespace)
    motion = njit(namespace["motion"])

    @njit
    def loop(count, q, qd, gen, bshift, LI, LF, LX, WI, WF, WX, mode, general):
        for _ in range(count):
            motion(q, qd, gen, bshift, LI, LF, LX, WI, WF, WX, mode, general)
    return loop


def profile(label):
    case = chain_case(int(label)) if label.isdigit() else robot_case(label, label in ("talos", "solo12"))
    engine = engine_for(case.system)
    q, v = case.draw(np.random.default_rng(0))
    qm, qdm = case.to_maximal(q, v)
    args = (qm, qdm, engine.gen, np.zeros(0), *engine.buffers, kernel.CHECKED, engine.general)
    body = ast.parse(textwrap.dedent(inspect.getsource(kernel.motion.py_func))).body[0].body
    loops = {None: variant()}
    for name, function in STAGES.items():
        loops[name] = variant(_stage_lines(body, function), function)
    times = {name: [] for name in loops}
    for name, loop in loops.items():
        loop(1, *args)
    for _ in range(ROUNDS):
        for name, loop in loops.items():
            started = time.perf_counter()
            loop(CALLS, *args)
            times[name].append((time.perf_counter() - started) / CALLS)
    whole = min(times.pop(None))
    stages = {name: max(0.0, (min(t) - whole) / REPEAT) for name, t in times.items()}
    from_python = best(lambda: kernel.motion(*args))
    system_motion = best(lambda: case.system.motion(0.0, qm, qdm))
    return case, whole, stages, system_motion - from_python, system_motion


def main():
    labels = sys.argv[1:] or ["ur5", "talos", "100"]
    results = [profile(label) for label in labels]
    lines = ["# Where the time of one fast evaluation goes", "",
             f"{date.today()}, {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
             f"Python {platform.python_version()}; written by `benchmarks/fast_stages.py` (see its docstring: "
             f"each stage repeated {REPEAT} more times inside the kernel, in a numba loop). µs per evaluation.", "",
             "| stage | " + " | ".join(case.label for case, *_ in results) + " |",
             "|---|" + "---:|" * len(results)]
    for name in STAGES:
        lines.append(f"| {name} | " + " | ".join(f"{stages[name] * 1e6:.2f}" for _, _, stages, _, _ in results) + " |")
    lines.append("| the rest (views, scaling, right side) | " + " | ".join(
        f"{(whole - sum(stages.values())) * 1e6:.2f}" for _, whole, stages, _, _ in results) + " |")
    lines.append("| **kernel.motion in a numba loop** | " + " | ".join(
        f"**{whole * 1e6:.2f}**" for _, whole, _, _, _ in results) + " |")
    lines.append("| Python around the kernel | " + " | ".join(
        f"{python * 1e6:.2f}" for *_, python, _ in results) + " |")
    lines.append("| **System.motion from Python** | " + " | ".join(
        f"**{total * 1e6:.2f}**" for *_, total in results) + " |")
    lines.append("")
    text = "\n".join(lines)
    (HERE / "fast_stages_results.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
