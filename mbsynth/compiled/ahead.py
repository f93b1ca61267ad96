"""The kernel's largest parts compiled in helper processes, alongside this one.

numba compiles on one thread per process (its compiler lock), and a cold compile of
``kernel.motion`` with everything it calls spends most of its time in a few callees. When
the cache holds no kernels yet (background.compiled()), ``start`` launches helper processes
(``python -m mbsynth.compiled.ahead GROUP VARIANT...``), each compiling one of GROUPS, for
the argument types ``motion`` hands those functions in each variant, into numba's on-disk
cache, while this process compiles the model's generated function; ``finish`` lets them
finish, and compiling ``motion`` then loads them from the cache (Engine.warm). A caller that
knows the variant of a System it is about to build (a robot is a rigid tree) may start them
earlier, beside the derivation (background.compile_ahead). The groups are balanced for two
cores. A helper that fails costs time only: numba compiles whatever the cache lacks.

Each function is named with the types of its arguments in a short notation: ``f2`` a
C-contiguous 2-d float64 array, ``i1`` a 1-d int64 array, ``c1`` a 1-d complex128 array, ``(...)`` a tuple, ``int64``,
``float64`` and ``boolean`` scalars, ``general`` the type of ``motion``'s last argument for the variant
(kernel.RIGID_TREE: none; kernel.GENERAL: bool). ``test_fast`` checks that they are the
types ``motion`` passes.
"""

import importlib
import logging
import os
import subprocess
import sys
import threading
from pathlib import Path

log = logging.getLogger(__name__)

TOPOLOGY = "(i1 i1 i1 i1 i1 i1 i1)"
FACTORED = "(f3 f3 f3 f3 f3 f3 f2 f2 f2)"
GROUPS = (
    (("tree", "factor", f"{TOPOLOGY} f3 f2 f2 {FACTORED} f2 i1"),
     ("kernel", "_residual", f"{TOPOLOGY} i1 (i1 i1 i1 i1) f2 f3 f2 f2 f2 f1 f1 f1 f1 f1 f2 f2 f1 "
                             "(i1 i1 i1 i1 i1 i1) f2 f1"),
     ("kernel", "_recover", "f1 i1 i1 f1 f3 i1 i1 f1 f1 f4 f1 f1 f2 i1 i1 f1 float64 f1 f1")),
    (("tree", "solve", f"{TOPOLOGY} {FACTORED} f1 f1 boolean"),
     ("assembly", "tree_rows", "f1 f1 f1 i1 i1 i1 i1 i1 i1 f1 f1 f4 (i3 i1 i2 i2 f3 f4 f1 i2) i1 (f3 f3 f2 f2 f1) "
                               "f2 f2 f1 f1 general"),
     ("assembly", "nodes", "f1 f1 f1 i1 i1 f1 f2 f3 i1 f1 f1 f3 f2 f1 f1 f1 f4"),
     ("assembly", "transports", "f1 i1 i1 i1 i1 i1 f3 f4 f2")),
)
SEGMENTS = "(i1 i1 i1 i1)"
GENERAL_ONLY = (  # what a rigid tree's motion leaves out, per group
    (("kernel", "_close", f"{TOPOLOGY} {SEGMENTS} f2 {FACTORED} f2 f2 f1 f1 f1 f1 f1 f1 f1 f2 f2 f1 f1 f1 boolean float64"),),
    (("assembly", "extra_rows", "f1 f1 f1 f1 i1 i1 f1 f1 f4 (i3 i1 i2 i2 f3 f4 f1 i2) i1 i2 i1 i1 i1 "
                                f"{SEGMENTS} i1 i1 (f3 f3 f2 f2 f1) f2 f2 f1 f1 f2"),),
)
# the kernels of parts that evaluate their own M and Q (flexible.py), one for every model: compiled
# with the others by ``python -m mbsynth.cli.compile_ahead`` (``compile_parts``), else at first use
PARTS = (
    ("flexible", "fill", "f1 f1 f1 int64 int64 int64 int64 i1 f2 f1 f2 f2 f4"),
    ("flexible", "fill_rows", "f2 f2 f2 int64 int64 int64 int64 i1 f2 f1 f2 f2 f4"),
    ("flexible", "equations", "f1 f1 f1 i1 f2 f1 f2 f2 f4 f2 f1 f2 f1"),
    ("flexible", "equations", "c1 c1 c1 i1 f2 f1 f2 f2 f4 c2 c1 c2 c1"),  # complex: a linearization's complex step
)
VARIANTS = {"rigid_tree": None, "general": True}  # kernel.RIGID_TREE, kernel.GENERAL
TIMEOUT = 600  # seconds a helper may take before it is stopped
_started = set()  # the variants whose helpers this process has started
_running = []  # those helpers, until ``finish``
_lock = threading.Lock()
HELPER = "MBSYNTH_AHEAD_HELPER"  # set in a helper's environment


def argument_types(spec, general):
    """The numba types of the arguments ``spec`` names (module docstring)."""
    from numba import typeof, types
    tokens = spec.replace("(", " ( ").replace(")", " ) ").split()

    def parse(at):
        token = tokens[at]
        if token == "(":
            items, at = [], at + 1
            while tokens[at] != ")":
                item, at = parse(at)
                items.append(item)
            return types.Tuple(items) if len(set(items)) > 1 else types.UniTuple(items[0], len(items)), at + 1
        if token == "general":
            return typeof(general), at + 1
        if token in ("int64", "float64", "boolean"):
            return getattr(types, token), at + 1
        dtype = {"i": types.int64, "f": types.float64, "c": types.complex128}[token[0]]
        return types.Array(dtype, int(token[1:]), "C"), at + 1

    found, at = [], 0
    while at < len(tokens):
        item, at = parse(at)
        found.append(item)
    return tuple(found)


def functions(group, general):
    """(dispatcher, argument types) of each function of GROUPS[group] (and GENERAL_ONLY[group]
    for kernel.GENERAL)."""
    for module, name, spec in GROUPS[group] + (GENERAL_ONLY[group] if general is not None else ()):
        yield getattr(importlib.import_module(f"{__package__}.{module}"), name), argument_types(spec, general)


def compile_group(group, variants):
    """Compile GROUPS[group] for each of ``variants`` (keys of VARIANTS) into numba's cache
    (a function whose types two variants share, once)."""
    for variant in variants:
        for dispatcher, types in functions(group, VARIANTS[variant]):
            dispatcher.compile(types)


def compile_parts():
    """Compile PARTS into numba's cache (load them where it holds them)."""
    for module, name, spec in PARTS:
        getattr(importlib.import_module(f"{__package__}.{module}"), name).compile(argument_types(spec, None))


def start(*generals):
    """Helper processes compiling every group for each of ``generals`` (values of
    ``motion``'s ``general``) but those this process started helpers for before. numba's
    cache directory is this process's (cache.configure). A helper starts none."""
    with _lock:
        variants = [name for name, value in VARIANTS.items() if value in generals and name not in _started]
        if not variants or os.environ.get(HELPER):
            return []
        _started.update(variants)
        helpers = [helper for group in range(len(GROUPS)) for helper in spawn(__name__, str(group), *variants)]
        _running.extend(helpers)
        return helpers


def finish():
    """Wait for every helper ``start`` started in this process (none left: at once)."""
    with _lock:
        helpers = list(_running)
        _running.clear()
    wait(helpers)


def spawn(module, *args):
    """[the helper process ``python -m module args``] with this process's numba cache
    directory (cache.configure) and this copy of mbsynth first on its path, or [] when it
    cannot start."""
    from . import cache
    cache.configure()
    package_root = str(Path(__file__).resolve().parents[2])
    env = {**os.environ, HELPER: "1",
           "PYTHONPATH": os.pathsep.join(filter(None, [package_root, os.environ.get("PYTHONPATH")]))}
    try:
        return [subprocess.Popen([sys.executable, "-m", module, *args], env=env, stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)]
    except OSError as err:
        log.info("no helper process to compile the kernels ahead (%s)", err)
        return []


def wait(helpers):
    """Let ``helpers`` finish (stopped after TIMEOUT); a failure is logged, not raised."""
    for helper in helpers:
        try:
            _, err = helper.communicate(timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            helper.kill()
            _, err = helper.communicate()
        if helper.returncode:
            log.info("a helper compiling the kernels ahead failed (%s): %s", helper.returncode,
                     err.decode(errors="replace")[-2000:])


if __name__ == "__main__":
    compile_group(int(sys.argv[1]), sys.argv[2:])
