"""Compiled Templates built on the worker thread; MBSYNTH_COMPILED; the default path.

numba compiles the kernels once per machine and keeps them on disk (cache.py); a cold
compile takes minutes, loading a warm cache well under a second. ``python -m
mbsynth.cli.compile_ahead`` compiles ahead (``make install`` runs it).

A model's path is chosen when its Data is made (model/data.py): "compiled" or "kkt",
by default ``default_path()`` — "compiled", or "kkt" where ``MBSYNTH_COMPILED=off`` (the
environment's choice) or inside ``default_path_as("kkt")`` (a command that evaluates a
handful of states). On the compiled path ``template`` builds the Template of the model's
structure (layout, generated function, compilation: engine.py) on the worker thread and
waits for it, once per structure (``TemplateSlot``, kept in the one cache, core/memo.py),
so the path never depends on what a background build happens to have finished.

The worker is a daemon thread (worker.py): leaving Python waits only for the numba
compilation in progress (one interrupted would abort the process); a build asked for
while Python exits is refused (the KKT path serves).
"""

import contextlib
import contextvars
import logging
import os
import threading
from concurrent.futures import Future

from . import ahead, cache
from .worker import Worker

log = logging.getLogger(__name__)
VARIABLE = "MBSYNTH_COMPILED"  # the environment's choice of the default path
OLD_VARIABLE = "MBSYNTH_FAST"  # its old name, read where VARIABLE is not set
MODES = ("on", "off")  # VARIABLE: the compiled path where it covers a model, or never
LEGACY_MODES = {"wait": "on", "background": "on"}  # earlier names of "on", still accepted
_ENVIRON_KEYS = tuple((name, os.environ.encodekey(name)) for name in (VARIABLE, OLD_VARIABLE))  # ``given``


class TemplateSlot:
    """The Template of one structure: its Future, once submitted to the worker."""

    def __init__(self):
        self.future, self.submitted = Future(), False


_lock = threading.Lock()
_default_path = contextvars.ContextVar("default_path", default=None)  # ``default_path_as``


@contextlib.contextmanager
def default_path_as(path):
    """``default_path()`` is ``path`` inside the block where MBSYNTH_COMPILED is not set (a
    command that evaluates a handful of states has no use for compiling kernels)."""
    token = _default_path.set(path)
    try:
        yield
    finally:
        _default_path.reset(token)


def given():
    """(name, text) of the environment's choice: MBSYNTH_COMPILED, else OLD_VARIABLE (its
    old name); (MBSYNTH_COMPILED, None) where neither is set. Read from the dict behind
    ``os.environ`` (what its ``get`` reads): ``get`` of a name not set raises and catches a
    KeyError inside, a microsecond each, and every ``System.motion`` asks."""
    environ = os.environ._data
    for name, key in _ENVIRON_KEYS:
        value = environ.get(key)
        if value is not None:
            return name, os.environ.decodevalue(value)
    return VARIABLE, None


def mode(value=None):
    """MBSYNTH_COMPILED (or ``value``, its text): "on" (unset: the default) or "off"."""
    name, value = given() if value is None else (VARIABLE, value)
    value = LEGACY_MODES.get(value, value or "on")
    if value not in MODES:
        raise ValueError(f"{name} must be one of {MODES}, got {value!r}")
    return value


def default_path():
    """The path of a Data made without one: "kkt" where MBSYNTH_COMPILED=off, else the
    ``default_path_as`` block's where MBSYNTH_COMPILED is unset, else "compiled"."""
    text = given()[1]
    if text is not None and mode() == "off":  # unset: "on" (``mode``), without reading it again
        return "kkt"
    block = _default_path.get()
    return block if text is None and block is not None else "compiled"


def template(system, slot):
    """The compiled Template of ``system``'s structure, built now if it is not yet (in
    ``slot``, its TemplateSlot); None where MBSYNTH_COMPILED=off, its build failed, or the
    kernels cover no part of the model."""
    if mode() == "off":
        return None
    future = _submit(system, slot)
    if future.exception() is not None:  # logged by the worker; the KKT path serves (the error is not
        return None  # raised here: its traceback would keep this frame, and the System, with the future)
    return future.result()


def engine_for(system):
    """The compiled Engine of ``system`` at its parameter values (its structure's Template
    built now if it is not yet), or None (``template``): a compiled-path Data's engine."""
    return system.data(path="compiled").engine


def compile_ahead(variant):
    """Start compiling the kernel's largest parts for ``variant`` ("rigid_tree" or
    "general": ahead.VARIANTS) in helper processes now, when the kernels are not compiled and
    the compiled path is on: a caller about to build a System of that variant (a robot: a rigid
    tree) lets them run beside its derivation."""
    if mode() != "off" and not compiled():
        ahead.start(ahead.VARIANTS[variant])


def compiled():
    """Whether the kernels are compiled: the cache on disk says so (a speed matter alone:
    ``ahead.start`` compiles their largest parts in helper processes when they are not)."""
    return cache.compiled_mark().exists()


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
    from .engine import Template
    built = Template.build(system)
    if built is None:
        return None
    if not compiled():
        ahead.start(built.general)  # the kernel's largest parts, alongside (none if started already)
    built.engine(system.parameter_values).warm(*system.initial_state())
    if not compiled():
        try:
            cache.compiled_mark().touch()
        except OSError:  # a cache that cannot be written: the next process compiles ahead again
            pass
    return built


def build(system):
    """A compiled, warmed Engine for ``system``, or None when the kernels cover none of its parts."""
    built = _build(system)
    return None if built is None else built.engine(system.parameter_values)


_worker = Worker("mbsynth-compile", _build_task, drop=_refuse)
