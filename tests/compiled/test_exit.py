"""Leaving Python while a compilation runs on another thread (worker.py): the process waits
for the numba compilation in progress and exits cleanly — status 0, no LLVM assertion —
whatever its compile threads are doing; builds not started are dropped; Ctrl-C during the
wait ends it at once."""

import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LINES = 600  # the compiled function's length: its compilation takes seconds, far longer than twice STARTED
STARTED = 0.3  # seconds the script gives its thread to enter the compilation before it exits
HEAVY = "import math\nfrom numba import njit\n\n\n@njit(cache=True)\ndef f(x):\n    y = 0.0\n" + "".join(
    f"    y += math.sin(x * {i}.5) * math.cos(y + {i})\n" for i in range(LINES)) + "    return y\n"
CRASHES = ("Assertion", "Fatal Python error", "Segmentation fault", "Aborted")


def run(script, env=None, cwd=ROOT):
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(script)], cwd=cwd, capture_output=True,
                          text=True, timeout=240, env=env)
    for crash in CRASHES:
        assert crash not in done.stderr, done.stderr[-3000:]
    assert done.returncode == 0, done.stderr[-3000:]
    return done


@pytest.mark.implementation
def test_exit_during_a_compilation_waits_for_it(tmp_path):
    """A Worker's thread is inside numba's compiler when the script ends: the exit lets
    that compilation finish (its machine code reaches the cache) instead of destroying LLVM
    under it."""
    (tmp_path / "heavy.py").write_text(HEAVY)
    cache = tmp_path / "cache"
    env = {"PATH": "/usr/bin:/bin", "NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": f"{ROOT}:{tmp_path}"}
    run(f"""
        import time
        from mbsynth.compiled.worker import Worker
        from heavy import f
        Worker("compile", f.compile).submit("float64(float64)")
        time.sleep({STARTED})
        """, env=env, cwd=tmp_path)
    assert list(cache.rglob("heavy.f-*.nbi")), "the compilation in progress at exit was cut short"


@pytest.mark.parametrize("attempt", [1, 2])
def test_a_script_that_ends_while_its_model_compiles_exits_cleanly(attempt):
    """The user's case: a System's first motion starts its compiled build in the background
    (MBSYNTH_COMPILED=background) and the script ends at once: exit status 0, nothing on stderr."""
    done = run("""
        import mbsynth as mb
        system = mb.load("models/rigid/double_pendulum_spatial.yaml")
        q, qd = system.initial_state()
        print(system.motion(0.0, q, qd).unique)
        """)
    assert (done.stdout, done.stderr) == ("True\n", "")


def test_a_build_asked_for_while_python_exits_is_refused():
    """After mbsynth's exit hook (an atexit function registered before mbsynth is imported
    runs after it) a build is not started, and waiting for it answers None (the KKT path)
    at once instead of waiting forever."""
    done = run("""
        import atexit

        def late():
            from mbsynth.compiled import background
            print(background.template(system, background.TemplateSlot()))

        atexit.register(late)
        import mbsynth as mb
        system = mb.load("models/rigid/double_pendulum_spatial.yaml")
        """)
    assert (done.stdout, done.stderr) == ("None\n", "")


@pytest.mark.implementation
def test_ctrl_c_while_the_exit_waits_ends_the_process_at_once(tmp_path):
    """Ctrl-C while the exit waits for a compilation: the process ends at once with status
    130 (interrupted), still without an LLVM abort, and prints nothing more."""
    (tmp_path / "heavy.py").write_text(HEAVY)
    env = {"PATH": "/usr/bin:/bin", "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": f"{ROOT}:{tmp_path}"}
    script = textwrap.dedent(f"""
        import time
        from mbsynth.compiled.worker import Worker
        from heavy import f
        Worker("compile", f.compile).submit("float64(float64)")
        time.sleep({STARTED})
        print("leaving", flush=True)
        """)
    process = subprocess.Popen([sys.executable, "-c", script], cwd=tmp_path, env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    assert process.stdout.readline() == "leaving\n"
    time.sleep(STARTED)  # in the exit's wait
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert (process.returncode, out, err) == (130, "", "")
