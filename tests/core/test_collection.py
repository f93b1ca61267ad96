"""The model layer's import (core/collection.py): the first public name imported on use
pauses the cycle collector and freezes what the import made; the collector then runs again,
and what is made later is collected as usual."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = """\
import gc, sys, weakref
collections = []
gc.callbacks.append(lambda phase, info: collections.append(info["generation"]) if phase == "start" else None)
gc.disable() if sys.argv[1] == "disabled" else None
import mbsynth as mb
print("before", gc.get_freeze_count())
made = len(collections)
load = mb.load
frozen = gc.get_freeze_count()
print("frozen", frozen)
print("collections", len(collections) - made)
print("enabled", gc.isenabled())
mb.simulate  # a second public name: imported plainly, nothing more frozen
print("again", gc.get_freeze_count() == frozen)

class Node:
    pass

a, b = Node(), Node()
a.other, b.other = b, a  # a cycle made after the freeze: collected as ever
ref = weakref.ref(a)
del a, b
gc.collect()
print("collected", ref() is None)
"""


def run(state):
    out = subprocess.run([sys.executable, "-c", SCRIPT, state], cwd=ROOT, capture_output=True, text=True, check=True,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)))
    return dict((line.split(" ", 1)[0], line.split(" ", 1)[1]) for line in out.stdout.splitlines())


def test_the_first_public_import_freezes_the_model_layer_without_collecting_and_restores_the_collector():
    found = run("enabled")
    assert found["before"] == "0"  # ``import mbsynth`` alone freezes nothing
    assert int(found["frozen"]) > 50_000  # sympy, scipy, numba and mbsynth's modules
    assert found["collections"] == "0"  # none while the layer was imported
    assert found["enabled"] == "True" and found["again"] == "True" and found["collected"] == "True"


def test_a_collector_the_caller_turned_off_stays_off():
    found = run("disabled")
    assert found["enabled"] == "False" and int(found["frozen"]) > 50_000
