"""The compiled path of the motion (2.14): linear-time assembly and solve in numba. A Data
(model/data.py) takes its Engine from here; this package reads the model only through its
parts' and joints' attributes (layout.py) and imports nothing of model/.

    layout.py      a System as index and number arrays (tree of bodies, loops, the rest)
    codegen.py     one compiled function for every expression the kernels do not cover (and
                   the printing and loading of generated modules, structures.py's too)
    bodies.py      rigid-body blocks and the change of variables to (r̈, α)
    rate_rows.py   rows of joints between rigid bodies, directly in (r̈, α)
    joints.py      joint rows of A and b over q̈, differentiated by hand (particles, loops)
    assembly.py    one state's blocks
    tree.py        the tree's elimination in articulated form (null spaces, rigid transports)
    eigen.py       small symmetric eigendecomposition (the loops' Schur system)
    kernel.py      the whole evaluation and its checks
    engine.py      a Template per model structure, an Engine per parameter values: motion, motion_batch
    rows.py        φ, φ̇ of the kernel's rows and its nodes' energies (simulate's rows)
    projection.py  states put back on the constraints by the kernel, in the mass metric
    threads.py     the threads compiled kernels share (motion_batch, projections)
    background.py  building Templates off the caller's thread; MBSYNTH_COMPILED
    worker.py      the daemon thread such builds run on, and what leaving Python does to them
    structures.py  a numba kernel per shared structure of constraint or part expressions
    grouped.py     the instances of one structure evaluated together (model/evaluation.py)
    ahead.py       a cold compile's largest parts in helper processes, on the other core
    cache.py       where compiled code is kept

Importing this package does not import numba (``mbsynth check`` never needs it).
"""

from .background import TemplateSlot, compile_ahead, compiled, engine_for, template

__all__ = ["TemplateSlot", "compile_ahead", "compiled", "engine_for", "template"]
