"""The threads the compiled kernels run in side by side (they release the GIL): THREADS,
one per core unless ``MBSYNTH_THREADS`` says how many (a sweep's worker processes take
one each, sweep.py), made on first use and shared by motion_batch (engine.py) and block
projections (compiled/projection.py)."""

import os
from concurrent.futures import ThreadPoolExecutor


def _count():
    given = os.environ.get("MBSYNTH_THREADS", "").strip()
    if not given:
        return os.cpu_count() or 1
    if not given.isdigit() or int(given) < 1:
        raise ValueError(f"MBSYNTH_THREADS must be a positive whole number, got {given!r}")
    return int(given)


THREADS = _count()

_threads, _owner = None, None  # the pool and the process that made it


def pool():
    """The shared ThreadPoolExecutor, THREADS threads: a new one in a process forked from the
    one that made it (a fork copies the pool but not its threads: work handed to it would
    wait forever)."""
    global _threads, _owner
    if _owner != os.getpid():
        _threads, _owner = ThreadPoolExecutor(THREADS, thread_name_prefix="mbsynth-batch"), os.getpid()
    return _threads
