"""``python -m mbsynth.fast``: compile the fast path's kernels into the cache ahead of use."""

import time

import numpy as np

from . import cache


def main():
    started = time.perf_counter()
    from . import background
    from ..io import loads
    for text in WARM_MODELS:
        system = loads(text, "warm-up")
        engine = background.build(system)
        q, qd = system.initial_state()
        engine.motion_batch(np.zeros(2), np.array([q, q]), np.array([qd, qd]))
        correction = engine.correction()
        if correction is not None:  # simulate's rows and corrections
            correction(q, qd)
    print(f"mbsynth fast path compiled into {cache.cache_dir()} in {time.perf_counter() - started:.1f} s")


# A body on a spherical joint with a particle on a rod, without and with a loop (a second,
# redundant hinge) and a generated force: every kernel runs, and the correction's (the
# kernel at rest, the compiled rows) on the tree.
WARM_TREE = """
name: warm_up
gravity: [0, 0, -9.81]
subsystems:
  link: {type: rigid_body, mass: 1.0, inertia: [0.1, 0.1, 0.02], frames: {top: {position: [0, 0, 0.5]}},
         initial: {angular_velocity: [0.1, 0.2, 0.3]}}
  bob: {type: particle, mass: 0.5, initial: {position: [0, 0, -0.5]}}
joints:
  - {name: pivot, type: spherical, parent: world, child: link.top}
  - {name: rod, type: distance, parent: link, child: bob, length: 0.5}
"""
WARM_MODELS = [WARM_TREE + """  - {name: again, type: spherical, parent: world, child: link.top}
forces:
  - {name: push, type: force, at: bob, value: ["sin(t)", 0, 0]}
""", WARM_TREE]

if __name__ == "__main__":
    main()
