"""Leaving Python without its last garbage collections.

When a process ends, CPython's finalization collects garbage over every object still
alive: a process that loaded sympy and numba spends 0.2–0.5 s there, a third of a warm
run's whole process. ``skip_final_collections`` has ``gc.freeze`` run at exit, after the
atexit handlers registered later (they run in reverse order: numba's compile lock, the
user's own): the objects alive then move to the permanent generation, which those
collections do not walk. Everything is still released by its reference counts; only
objects held in reference cycles are left to the end of the process, whose ``__del__``
CPython never promised at exit.
"""

import atexit
import gc


def skip_final_collections():
    """Register ``gc.freeze`` to run at exit (module docstring)."""
    atexit.register(gc.freeze)
