"""One ``motion()`` from Python in one compiled call (Engine.motion_into: Data.motion,
Data.acceleration).

``motion_into`` copies the state into the rows of a new block, evaluates the model's generated
function and flexible parts there (staged.evaluate) and the kernel (kernel.motion_rates,
through its function pointer, so that this small function compiles once for every model and
holds no copy of the kernel), and writes q̈ and Qc into the block's other rows. Its arguments
are arrays and numbers alone, the Engine's first: ``single`` binds them (functools.partial,
no Python frame per call).
"""

import functools

import numpy as np
from numba import njit, typeof

from . import kernel
from .bodies import OPTIONS
from .packing import fields, view1
from .pointers import address
from .staged import _kernel_rates, evaluate, evaluation_of, rates_signature
from .assembly import Work

WORK = fields(Work)
STATE, RATE, ACCELERATION, FORCE = range(4)  # the rows of ``motion_into``'s block: q, q̇, q̈, Qc (model/data.py
# reads row 2 as q̈ without importing this module, which would load scipy with numba's function types)
WRONG_SIZE = -1  # ``motion_into``'s status for a state that is not of n entries


@njit(**OPTIONS)
def motion_into(calls, p, gen, own_meta, own_ints, own_floats, own_index, LI, LF, LX, WI, WF, WX, mode, general, t,
                q, qd, block):
    """kernel.motion's (status, residual) at (t, q, q̇) with block's rows ← (q, q̇, q̈, Qc):
    the state copied first and evaluated there (the copy is what a Motion's λ and residual
    are read at), q̈ and Qc written only on OK. calls: the addresses of the generated
    function, the flexible parts' fill and kernel.motion_rates for ``general`` (two each);
    p, gen, own_*: staged.evaluation_of's. (WRONG_SIZE, 0) for a state not of the block's
    width, the block left as it was."""
    n = block.shape[1]
    if q.shape[0] != n or qd.shape[0] != n:
        return WRONG_SIZE, 0.0
    qc, qdc, qdd_out, Qc_out = block[STATE], block[RATE], block[ACCELERATION], block[FORCE]
    for c in range(n):
        qc[c] = q[c]
        qdc[c] = qd[c]
    evaluate(t, qc, qdc, (calls[0], calls[1], calls[2], calls[3], p, gen, own_meta, own_ints, own_floats, own_index))
    none = qc[:0]
    status, residual = _kernel_rates(calls[4], calls[5], general)(qc, qdc, gen, none, LI, LF, LX, WI, WF, WX, mode,
                                                                  -1.0, general, own_ints[:0], none)
    if status == kernel.OK:
        qdd, Qc = view1(WF, WX, WORK.qdd), view1(WF, WX, WORK.Qc)
        for c in range(n):
            qdd_out[c] = qdd[c]
            Qc_out[c] = Qc[c]
    return status, residual


def single(engine):
    """``motion_into`` with one Engine's arguments bound, a callable of (t, q, q̇, block)
    (the caller holds the Engine's lock); it keeps the code its addresses point into."""
    evaluation, keep = evaluation_of(engine, engine.gen)
    generated_c, generated_jit, fill_c, fill_jit, p, gen, own_meta, own_ints, own_floats, own_index = evaluation
    kernel_c, kernel_jit = address(kernel.motion_rates, rates_signature(typeof(engine.general)))
    calls = np.array([generated_c, generated_jit, fill_c, fill_jit, kernel_c, kernel_jit], dtype=np.int64)
    bound = functools.partial(motion_into, calls, p, gen, own_meta, own_ints, own_floats, own_index, *engine.buffers,
                              engine.mode, engine.general)
    bound.keep = keep
    return bound
