"""When System.motion uses the fast path: an Engine per System, built off the caller's thread.

numba compiles the kernels once per machine and keeps them on disk (cache.py); a cold
compile takes tens of seconds, loading a warm cache well under a second. So that no call
waits for it, ``engine_for`` starts building a System's Engine (layout, generated
function, compilation) on a background thread the first time it is asked, and answers
None — use the KKT path — until the Engine is ready. ``MBSYNTH_FAST`` changes this:
"background" (the default), "wait" (build on first use, blocking) or "off" (never use
the fast path). ``python -m mbsynth.fast`` (run by ``make install``) compiles ahead.

The worker is a daemon thread: leaving Python never waits for a compilation; one cut
short starts again next time.
"""

import logging
import os
import queue
import threading
import weakref
from concurrent.futures import Future

log = logging.getLogger(__name__)
MODES = ("background", "wait", "off")

_engines = {}  # id(system) -> Future of its Engine (None when the fast path does not apply)
_ready = {}  # id(system) -> its Engine, once built (the quick answer)
_lock = threading.Lock()
_tasks = queue.Queue()
_worker = None


def mode():
    value = os.environ.get("MBSYNTH_FAST", "background")
    if value not in MODES:
        raise ValueError(f"MBSYNTH_FAST must be one of {MODES}, got {value!r}")
    return value


def engine_for(system, wait=False):
    """The Engine of ``system`` when it is ready (``wait``: build it now), else None."""
    engine = _ready.get(id(system))
    if engine is not None:
        return engine
    setting = mode()
    if setting == "off":
        return None
    future = _engines.get(id(system))
    if future is None:
        future = _submit(system)
    if not (wait or setting == "wait" or future.done()):
        return None
    try:
        return future.result()
    except Exception:  # logged by the worker; the exact path serves
        return None


def _submit(system):
    global _worker
    with _lock:
        key = id(system)
        if key not in _engines:
            _engines[key] = Future()
            weakref.finalize(system, _forget, key)
            _tasks.put((weakref.ref(system), _engines[key]))
            if _worker is None:
                _worker = threading.Thread(target=_work, name="mbsynth-compile", daemon=True)
                _worker.start()
        return _engines[key]


def _forget(key):
    _engines.pop(key, None)
    _ready.pop(key, None)


def _work():
    while True:
        ref, future = _tasks.get()
        system = ref()
        if system is None or not future.set_running_or_notify_cancel():
            continue
        try:
            engine = build(system)
            if engine is not None:
                _ready[id(system)] = engine
            future.set_result(engine)
        except Exception as err:
            log.warning("model %s: the fast path is unavailable (%s: %s); using the KKT path",
                        system.name, type(err).__name__, err)
            future.set_exception(err)
        del system


def build(system):
    """A compiled Engine for ``system``, or None when the kernels cover none of its parts."""
    from .engine import Engine
    engine = Engine.build(system)
    if engine is not None:
        engine.warm()
    return engine
