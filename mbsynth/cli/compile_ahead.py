"""``python -m mbsynth.cli.compile_ahead`` (run by ``make install``): compile the compiled path's
kernels (mbsynth.compiled) into the cache ahead of use, on warm-up models read as model files
(hence here, on the floor that may read them).

On two cores: first the kernel's largest parts for both variants of ``kernel.motion`` in
helper processes (ahead.py); then the rigid tree's entry points (motion_rates, the kernel's
one entry from outside compiled code; motion_rows; the projection) in a helper (``python -m
mbsynth.cli.compile_ahead rigid``) while this process compiles the general ones; then each
warm-up model here, loading what is missing from the cache (all of it, unless a helper
failed); then the flexible parts' kernel (ahead.PARTS). Each stage says on stderr what it
compiles and how far it is (``[k/N]``); when the cache holds the kernels already, it says so
and only loads them.
"""

import os
import sys
import time

import numpy as np

from ..compiled import cache, row_fit

COLD_TIME = "about 2-3 minutes on 2 cores"  # measured: `make install` on a 2-core machine
WARM_RUN = 0.01  # [s] of each warm-up model's run: a few steps, every function of the run loop called


def warm(texts):
    """Build each model's Engine and run every kernel entry point on it; then a short run of it,
    so that the run loop's own numba functions (analysis/dop853.py's dense output,
    velocity_form.py) are in the cache too, not compiled by a user's first run."""
    from ..analysis.simulate import simulate
    from ..compiled import background
    from ..io import loads
    for text in texts:
        system = loads(text, "warm-up")
        engine = background.build(system)
        q, qd = system.initial_state()
        engine.motion_batch(np.zeros(2), np.array([q, q]), np.array([qd, qd]))
        engine.stages().rates(0.0, np.concatenate([q, qd]))  # simulate's stages (staged.py)
        system.data("compiled").constraint_arrays(0.0, q, qd)  # the shared structures' tape (tape.run)
        projection = engine.projection()
        if projection is not None:  # simulate's rows and projections, one by one and fitted (row_fit.py)
            projection(0.0, q, qd)
            count = row_fit.MIN_ROWS
            projection.block(np.zeros(count), np.tile(q, (count, 1)), np.tile(qd, (count, 1)),
                             np.arange(1, count + 1) / count)
        simulate(system, WARM_RUN)


def main():
    started = time.perf_counter()
    if sys.argv[1:] == ["rigid"]:  # the helper compiling the rigid tree's entry points
        warm([WARM_RIGID])
        return
    from ..compiled import ahead, background, kernel
    cold = not background.compiled()
    where = os.environ.get("NUMBA_CACHE_DIR") or cache.cache_dir()
    if cold:
        say(f"compiling the compiled path's kernels once ({COLD_TIME}); every later run loads them "
            f"from the cache ({where}) in about a second instead of compiling for tens of seconds")
    else:
        say(f"the compiled path's kernels are compiled already ({where}): loading them to check (seconds)")
    stages = ([("the kernel's largest parts, in helper processes", None)] if cold else []) + [
        (f"the general kernel on warm-up model {k} of {len(WARM_MODELS)}", text)
        for k, text in enumerate(WARM_MODELS, start=1)] + [("the rigid tree's kernel", WARM_RIGID),
                                                            ("the flexible parts' kernel", PARTS)]
    rigid = []
    for k, (what, text) in enumerate(stages, start=1):
        say(f"[{k}/{len(stages)}] {what} ({time.perf_counter() - started:.0f} s so far)")
        if text is None:
            ahead.start(kernel.RIGID_TREE, kernel.GENERAL)
            ahead.finish()
            rigid = ahead.spawn(__spec__.name, "rigid")  # beside the general models
            continue
        if text is PARTS:
            ahead.compile_parts()
            continue
        if text is WARM_RIGID:
            ahead.wait(rigid)
        warm([text])
    print(f"mbsynth: the compiled path's kernels compiled into {where} in {time.perf_counter() - started:.1f} s")


PARTS = "parts"  # the stage that compiles ahead.PARTS


def say(line):
    """A line of progress, on stderr."""
    print(f"mbsynth: {line}", file=sys.stderr, flush=True)


# A body on a spherical joint with a particle on a rod, without and with a loop (a second,
# redundant hinge) and a generated force: every kernel runs, and the projection's (the
# kernel at rest, the compiled rows) on the tree.
WARM_TREE = """
name: warm_up
gravity: [0, 0, -9.81]
parts:
  link: {type: rigid_body, mass: 1.0, inertia: [0.1, 0.1, 0.02], frames: {top: {position: [0, 0, 0.5]}},
         initial: {angular_velocity: [0.1, 0.2, 0.3]}}
  bob: {type: particle, mass: 0.5, initial: {position: [0, 0, -0.5]}}
joints:
  - {name: pivot, type: spherical, parent: world, child: link.top}
  - {name: rod, type: distance, parent: link, child: bob, length: 0.5}
"""
# Two bodies on a revolute and a fixed joint: a rigid tree (kernel.RIGID_TREE).
WARM_RIGID = """
name: warm_up_rigid
gravity: [0, 0, -9.81]
world: {frames: {pivot: {position: [0, 0, 0], axis: [1, 0, 0]}}}
parts:
  upper: {type: rigid_body, mass: 1.0, inertia: [0.1, 0.1, 0.02], frames: {top: {position: [0, 0, 0.5],
          axis: [1, 0, 0]}, low: {position: [0, 0, -0.5]}}, initial: {angular_velocity: [0.3, 0, 0]}}
  lower: {type: rigid_body, mass: 0.5, inertia: [0.05, 0.05, 0.01], frames: {top: {position: [0, 0, 0.3]}}}
joints:
  - {name: hinge, type: revolute, parent: world.pivot, child: upper.top}
  - {name: weld, type: fixed, parent: upper.low, child: lower.top}
"""
WARM_PLANAR = """name: warm_planar
parts:
  rod: {type: planar_body, mass: 1.0, inertia: 0.1, frames: {end: {position: [-0.5, 0, 0]}}, initial: {position: [0.5, 0]}}
joints:
  - {name: pin, type: revolute, parent: world, child: rod.end}
"""  # extra coordinates alone: compiled/extra_projection.py and the run's singular watch
WARM_MODELS = [WARM_TREE + """  - {name: again, type: spherical, parent: world, child: link.top}
forces:
  - {name: push, type: force, at: bob, value: ["sin(t)", 0, 0]}
""", WARM_TREE, WARM_PLANAR]  # kernel.GENERAL

if __name__ == "__main__":
    main()
