"""When System.motion uses the fast path: Engines built off the caller's thread, shared and freed.

numba compiles the kernels once per machine and keeps them on disk (cache.py); a cold
compile takes tens of seconds, loading a warm cache well under a second. So that no call
waits for it, ``engine_for`` starts building a System's Template (layout, generated
function, compilation: engine.py) on a background thread the first time it is asked, and
answers None — use the KKT path — until it is ready. ``MBSYNTH_FAST`` changes this:
"background" (the default), "wait" (build on first use, blocking) or "off" (never use
the fast path). ``python -m mbsynth.fast`` (run by ``make install``) compiles ahead.

Each System has a slot here, held weakly: the System's Engine is freed with the System
(an Engine holds no reference to it), and a System never gets another's Engine. A System
made by ``share(parent, child)`` (``System.with_parameters``) shares its parent's Template,
built at most once for all of them; its own Engine costs no compilation.

A run must not switch from the KKT path to the tree path midway (its result would depend
on when a compilation finished): ``fix_path(system, run)`` decides once, for ``run`` (a
copy of ``system`` made for one run, ``System.for_run``), which path it takes throughout —
the Engine, waited for when the kernels are compiled (in this process or in the cache on
disk), else the KKT path.

The worker is a daemon thread: leaving Python never waits for a compilation; one cut
short starts again next time.
"""

import contextlib
import logging
import os
import queue
import threading
import weakref
from concurrent.futures import Future

from . import ahead, cache

log = logging.getLogger(__name__)
MODES = ("background", "wait", "off")


class _Shared:
    """The Template that Systems of one structure share: its Future, once submitted."""

    def __init__(self):
        self.future, self.submitted = Future(), False


class _Slot:
    """A System's place: the Template it shares, its own Engine once made, and whether its
    path is fixed (``fix_path``: then ``engine`` is the answer, None meaning KKT)."""

    def __init__(self, shared, engine=None, fixed=False):
        self.shared, self.engine, self.fixed = shared, engine, fixed


class _Slots:
    """Slots keyed by their System's identity, each forgotten when its System is collected.
    (A System is an unhashable dataclass: a WeakKeyDictionary cannot hold it, and two equal
    Systems must not be confused anyway.)"""

    def __init__(self):
        self._items = {}  # id(system) -> (weak reference to it, its slot)

    def get(self, system):
        item = self._items.get(id(system))
        return item[1] if item is not None and item[0]() is system else None

    def put(self, system, slot):
        key = id(system)

        def forget(ref):
            if self._items.get(key, (None,))[0] is ref:
                del self._items[key]
        self._items[key] = (weakref.ref(system, forget), slot)
        return slot


_slots = _Slots()
_lock = threading.Lock()
_tasks = queue.Queue()
_worker = None
_compiled = False  # an Engine has been warmed in this process: the kernels are compiled
_default_mode = "background"  # MBSYNTH_FAST when it is not set (``default_mode``)


@contextlib.contextmanager
def default_mode(value):
    """MBSYNTH_FAST taken as ``value`` inside the block where the user has not set it (a
    command that evaluates a handful of states has no use for compiling kernels)."""
    global _default_mode
    before, _default_mode = _default_mode, value
    try:
        yield
    finally:
        _default_mode = before


def mode():
    value = os.environ.get("MBSYNTH_FAST", _default_mode)
    if value not in MODES:
        raise ValueError(f"MBSYNTH_FAST must be one of {MODES}, got {value!r}")
    return value


def engine_for(system, wait=False):
    """The Engine of ``system`` when it is ready (``wait``: build it now), else None."""
    slot = _slots.get(system)
    if slot is not None and (slot.engine is not None or slot.fixed):
        return slot.engine
    if mode() == "off":
        return None
    slot = _slot(system)
    future = _submit(system, slot.shared)
    if not (wait or mode() == "wait" or future.done()):
        return None
    if future.exception() is not None:  # logged by the worker; the exact path serves (the error is not
        return None  # raised here: its traceback would keep this frame, and the System, with the future)
    template = future.result()
    return None if template is None else _engine(slot, template, system)


def share(parent, child):
    """Let ``child``, which differs from ``parent`` only in parameter values and initial
    state, share ``parent``'s Template (``System.with_parameters``)."""
    with _lock:
        _slots.put(child, _Slot(_slot(parent).shared))


def fix_path(system, run):
    """Fix the path of ``run``, a copy of ``system`` for one run: ``system``'s Engine —
    waiting for it when the kernels are compiled, in this process or on disk — or, when
    it is not ready and they are not, the KKT path throughout. Returns the Engine or None."""
    engine = engine_for(system, wait=compiled())
    with _lock:
        _slots.put(run, _Slot(_slot(system).shared, engine, fixed=True))
    return engine


def compile_ahead(variant):
    """Start compiling the kernel's largest parts for ``variant`` ("rigid_tree" or
    "general": ahead.VARIANTS) in helper processes now, when the kernels are not compiled and
    the fast path is on: a caller about to build a System of that variant (a robot: a rigid
    tree) lets them run beside its derivation."""
    if mode() != "off" and not compiled():
        ahead.start(ahead.VARIANTS[variant])


def compiled():
    """Whether the kernels are compiled: in this process, or in the cache on disk."""
    return _compiled or cache.compiled_mark().exists()


def _slot(system):
    slot = _slots.get(system)
    return slot if slot is not None else _slots.put(system, _Slot(_Shared()))


def _engine(slot, template, system):
    with _lock:
        if slot.engine is None:
            slot.engine = template.engine(system)
        return slot.engine


def _submit(system, shared):
    global _worker
    with _lock:
        if not shared.submitted:
            shared.submitted = True
            _tasks.put((system, shared))
            if _worker is None:
                _worker = threading.Thread(target=_work, name="mbsynth-compile", daemon=True)
                _worker.start()
        return shared.future


def _work():
    while True:
        _build_task(*_tasks.get())


def _build_task(system, shared):
    """Build ``shared``'s Template from ``system`` and give ``system`` its warmed Engine. The
    references to both are dropped before the result wakes anyone, who may then let them go."""
    name = system.name
    try:
        template, engine = _build(system)
        with _lock:
            slot = _slot(system)
            if slot.engine is None and not slot.fixed:
                slot.engine = engine  # warmed at this System's initial state
    except Exception as err:
        log.warning("model %s: the fast path is unavailable (%s: %s); using the KKT path",
                    name, type(err).__name__, err)
        failed, template, engine = err.with_traceback(None), None, None  # its frames would hold the System
    else:
        failed = None
    del system, engine
    if failed is not None:
        shared.future.set_exception(failed)
    else:
        shared.future.set_result(template)


def _build(system):
    """(Template, warmed Engine) of ``system``, or (None, None) when the kernels cover none
    of its parts."""
    global _compiled
    from .engine import Template
    template = Template.build(system)
    if template is None:
        return None, None
    engine = template.engine(system)
    if not compiled():
        ahead.start(template.general)  # the kernel's largest parts, alongside (none if started already)
    engine.warm(*system.initial_state())
    if not _compiled:
        _compiled = True
        try:
            cache.compiled_mark().touch()
        except OSError:  # a cache that cannot be written: runs on this machine start on KKT
            pass
    return template, engine


def build(system):
    """A compiled, warmed Engine for ``system``, or None when the kernels cover none of its parts."""
    return _build(system)[1]
