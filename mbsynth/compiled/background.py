"""Compiled Templates built off the caller's thread; MBSYNTH_FAST.

numba compiles the kernels once per machine and keeps them on disk (cache.py); a cold
compile costs far more than loading a warm cache. So that no call waits for it,
``template(system)`` starts building the Template of the System's structure (layout,
generated function, compilation: engine.py) on a background thread the first time it is
asked, and answers None — use the KKT path — until it is ready.
``MBSYNTH_FAST`` changes this: "background" (the default), "wait" (build on first use,
blocking) or "off" (never use the compiled path). ``python -m mbsynth.cli.compile_ahead``
(run by ``make install``) compiles ahead.

A Template is kept in the ``TemplateSlot`` of the System's structure (``System.shared``:
the Systems that differ only in parameter values share it), built at most once for all
of them. A Data (data.py) decides with ``compiled()`` whether a run waits for it.

The worker is a daemon thread (worker.py): leaving Python waits only for the numba
compilation in progress (one interrupted would abort the process); a build not finished
starts again next time, and one asked for while Python exits is refused (the KKT path).
"""

import contextlib
import logging
import os
import threading
from concurrent.futures import Future

from . import ahead, cache
from .worker import Worker

log = logging.getLogger(__name__)
MODES = ("background", "wait", "off")


class TemplateSlot:
    """The Template of one structure: its Future, once submitted to the worker."""

    def __init__(self):
        self.future, self.submitted = Future(), False


_lock = threading.Lock()
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


def template(system, wait=False):
    """The compiled Template of ``system``'s structure when it is ready (``wait``: build it
    now), else None: not ready, MBSYNTH_FAST=off, its build failed, or the kernels cover
    no part of the model."""
    if mode() == "off":
        return None
    future = _submit(system, system.shared.compiled)
    if not (wait or mode() == "wait" or future.done()):
        return None
    if future.exception() is not None:  # logged by the worker; the exact path serves (the error is not
        return None  # raised here: its traceback would keep this frame, and the System, with the future)
    return future.result()


def engine_for(system, wait=False):
    """The compiled Engine of ``system`` at its parameter values, when its Template is ready
    (``wait``: build it now), else None (``template``)."""
    found = template(system, wait)
    return None if found is None else found.engine(system.parameter_values)


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


def _submit(system, slot):
    with _lock:
        if not slot.submitted:
            slot.submitted = True
            _worker.submit(system, slot)
        return slot.future


def _build_task(system, slot):
    """Build ``slot``'s Template from ``system``. The references to both are dropped before
    the result wakes anyone, who may then let them go."""
    name = system.name
    try:
        built = _build(system)
    except Exception as err:
        if not _worker.closed:  # else Python is exiting: what failed is the exit's doing
            log.warning("model %s: the compiled path is unavailable (%s: %s); using the KKT path",
                        name, type(err).__name__, err)
        failed, built = err.with_traceback(None), None  # its frames would hold the System
    else:
        failed = None
    del system
    if failed is not None:
        slot.future.set_exception(failed)
    else:
        slot.future.set_result(built)


def _refuse(system, slot):
    """A build that will not run: Python is exiting (worker.py)."""
    slot.future.set_exception(RuntimeError(f"model {system.name}: not built, Python is exiting"))


def _build(system):
    """The Template of ``system``, its first Engine warmed at the initial state, or None when
    the kernels cover none of its parts."""
    global _compiled
    from .engine import Template
    built = Template.build(system)
    if built is None:
        return None
    if not compiled():
        ahead.start(built.general)  # the kernel's largest parts, alongside (none if started already)
    built.engine(system.parameter_values).warm(*system.initial_state())
    if not _compiled:
        _compiled = True
        try:
            cache.compiled_mark().touch()
        except OSError:  # a cache that cannot be written: runs on this machine start on KKT
            pass
    return built


def build(system):
    """A compiled, warmed Engine for ``system``, or None when the kernels cover none of its parts."""
    built = _build(system)
    return None if built is None else built.engine(system.parameter_values)


_worker = Worker("mbsynth-compile", _build_task, drop=_refuse)
