"""The run loop's drift control: how long a span of integration may be before the state is
put back on the constraints (after each step of a continuous run, projected by the kernel or
projected; between the output times of a cut one, projected).

The accelerations (2.14) satisfy the constraints at the acceleration level only, so positions
and velocities drift off them by the integration error. The stages of a span are only as good
as that drift (their motion is the drift rule's least-squares one where it explains an
inconsistency), so a span is kept short enough that the relative drift (projection.py's
``relative_drift``, or the kernel's) stays below DRIFT_TARGET (an implicit method's, or where
the rows keep their rank: the rtol where larger, integration.drift_target).
"""

import numpy as np
from ..core.tolerances import DRIFT_REDO, DRIFT_TARGET, REDO_MIN_SPAN



def next_cap(drift, taken, cap, room, interval, target=DRIFT_TARGET):
    """(redo, cap): after a span of length ``taken`` drifted by ``drift``, whether to integrate
    it again (at a quarter of its length: it drifted more than DRIFT_REDO × ``target`` and
    is longer than REDO_MIN_SPAN of the ``interval``), and the cap on the spans that follow —
    halved after a drift above ``target``, doubled after one below a hundredth of it, lifted
    (np.inf) once twice the cap reaches ``room``, else ``cap`` as it was (np.inf: none)."""
    if drift > DRIFT_REDO * target and taken > REDO_MIN_SPAN * interval:
        return True, taken / 4
    if drift > target:
        return False, taken / 2
    if drift < target / 100 and np.isfinite(cap):
        return False, np.inf if 2 * cap >= room else 2 * cap
    return False, cap
