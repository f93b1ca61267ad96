"""System.motion_batch: q̈ at many states, in parallel.

Waits for the System's Engine (background.py, compiling it if need be: a batch is worth
it), evaluates every state with the tree kernels in threads (engine.py), and sends each
state they hand back (kernel.py's status), and every state of a model they do not cover,
through ``System.motion`` — the KKT path and the exact treatment. A state with no motion
raises SolveError naming its row.
"""

import numpy as np

from ..errors import SolveError
from .background import engine_for


def motion_batch(system, t, q, qd):
    """(qdd (B × n), unique (B,)) for states q, q̇ (B × n) at times t (a number or B)."""
    # no copy of states already in float64 rows (a copy of a large batch costs page faults, serially)
    q, qd = (np.atleast_2d(np.ascontiguousarray(x, dtype=float)) for x in (q, qd))
    if q.ndim != 2 or q.shape != qd.shape or q.shape[1] != system.n:
        raise ValueError(f"model '{system.name}' has {system.n} coordinates: q_batch and qd_batch must both "
                         f"have shape (B, {system.n}), got {q.shape} and {qd.shape}")
    count = q.shape[0]
    t = np.broadcast_to(np.asarray(t, dtype=float), (count,)).copy()
    engine = engine_for(system, wait=True)
    if engine is None:
        qdd, done = np.zeros((count, system.n)), np.zeros(count, dtype=bool)
    else:
        qdd, status = engine.motion_batch(t, q, qd)
        done = status == 0
    unique = done.copy()
    for row in np.flatnonzero(~done):
        try:
            motion = system.motion(t[row], q[row], qd[row])
        except SolveError as err:
            raise SolveError(f"state {row} of the batch: {err}", constraints=err.constraints,
                             coordinates=err.coordinates) from None
        qdd[row], unique[row] = motion.qdd, motion.unique
    return qdd, unique
