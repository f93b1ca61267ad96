"""The cycle collector and the import of mbsynth's layers.

Importing the model layer (sympy, scipy, numba and mbsynth's own modules) makes about
100,000 objects that the cycle collector tracks, and that live as long as the process:
modules, classes, functions, sympy's and numba's tables. While they are made, the collector
runs full collections that walk every one of them (three in a warm run's process), and every
later full collection walks them again: 0.2–0.3 s of a 1.5 s process. ``imported`` imports
a module with the collector paused and then freezes what is alive (``gc.freeze``): those
objects move to the permanent generation, which no collection walks. Reference counts
still free everything; only objects held in reference cycles at that moment (the caller's
too) are never collected, as at exit (leaving.py). Done once per process (not where the
caller froze objects himself), by the first public name imported on use
(``mbsynth.__getattr__``), by the command line, or by a caller (the tests' conftest): later
imports are plain.
"""

import gc
import importlib
import threading

_lock = threading.Lock()
_done = False  # whether this process has frozen the layer (gc.get_freeze_count walks the frozen objects: ms)


def imported(name):
    """``importlib.import_module(name)``; the first call in a process, where the caller froze
    nothing himself, pauses the collector for the import and freezes what is alive after it
    (module docstring)."""
    global _done
    if _done:
        return importlib.import_module(name)
    with _lock:
        if _done or gc.get_freeze_count():
            _done = True
            return importlib.import_module(name)
        enabled = gc.isenabled()
        gc.disable()
        try:
            return importlib.import_module(name)
        finally:
            gc.freeze()
            _done = True
            if enabled:
                gc.enable()
