"""Leaving Python (core/leaving.py): ``gc.freeze`` runs at exit after the handlers
registered later, so the finalization's collections skip what the process made."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = """\
import atexit, gc, sys
atexit.register(lambda: print("after", gc.get_freeze_count() > 0))  # registered first: runs last
import mbsynth
atexit.register(lambda: print("before", gc.get_freeze_count()))  # a user's handler: runs before the freeze
print("alive", gc.get_freeze_count())
"""


def test_the_objects_alive_at_exit_are_frozen_after_the_users_own_handlers():
    out = subprocess.run([sys.executable, "-c", SCRIPT], cwd=ROOT, capture_output=True, text=True, check=True,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert out.stdout.split("\n")[:3] == ["alive 0", "before 0", "after True"]
