"""The threads the compiled kernels run in side by side (they release the GIL): THREADS,
one per core unless ``MBSYNTH_THREADS`` says how many (a sweep's worker processes take
one each, sweep.py), made on first use and shared by motion_batch (engine.py) and block
corrections (correction.py)."""

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

_threads = None


def pool():
    """The shared ThreadPoolExecutor, THREADS threads."""
    global _threads
    if _threads is None:
        _threads = ThreadPoolExecutor(THREADS, thread_name_prefix="mbsynth-batch")
    return _threads
