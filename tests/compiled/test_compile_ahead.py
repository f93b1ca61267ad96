"""``python -m mbsynth.cli.compile_ahead`` (the compile step of ``make install``) says why it compiles,
then what it compiles and how far it is, one line per stage on stderr; on a warm cache it
says that the kernels are compiled already and only loads them."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from mbsynth.cli import compile_ahead
from mbsynth.compiled import background

ROOT = Path(__file__).resolve().parents[2]
STAGE = re.compile(r"^mbsynth: \[(\d+)/(\d+)\] \S")


@pytest.mark.slow  # a fresh process that loads every kernel (compiles them all on a cold cache)
@pytest.mark.timeout(900)  # a cold cache compiles for minutes (the command's own point); a warm one loads in seconds
def test_compiling_ahead_says_what_and_how_far():
    cold = not background.compiled()
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli.compile_ahead"], cwd=ROOT, capture_output=True, text=True,
                          timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stderr.splitlines()
    if cold:
        assert lines[0].startswith("mbsynth: compiling the compiled path's kernels once (about 2-3 minutes")
        assert "every later run loads them from the cache" in lines[0]
    else:
        assert lines[0].startswith("mbsynth: the compiled path's kernels are compiled already (")
    stages = [tuple(map(int, m.groups())) for m in map(STAGE.match, lines[1:]) if m]
    count = len(compile_ahead.WARM_MODELS) + 2 + cold  # each warm-up model, the rigid tree, the flexible parts
    assert stages == [(k, count) for k in range(1, count + 1)] and len(lines) == count + 1
    assert lines[-1].startswith(f"mbsynth: [{count}/{count}] the flexible parts' kernel")
    assert done.stdout.startswith("mbsynth: the compiled path's kernels compiled into ")
