"""Finding and waiting for processes through /proc: the tests of commands that start
servers (the live viewer's meshcat server) and must end them."""

import threading
import time
from pathlib import Path

import pytest

HANG = 120  # seconds: only bounds a hang, never waited out by a passing test

needs_proc = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="finds processes through /proc")


def readline_within(stream, seconds):
    """The next line of ``stream``, or "" when none comes within ``seconds``."""
    lines = []
    reader = threading.Thread(target=lambda: lines.append(stream.readline()), daemon=True)
    reader.start()
    reader.join(seconds)
    return lines[0] if lines else ""


def proc_stat(pid):
    """Fields 3 (state) onwards of /proc/PID/stat; None when there is no such process."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None


def meshcat_servers(parent):
    """(pid, start time) of each meshcat server whose parent is process ``parent``."""
    found = []
    for entry in Path("/proc").iterdir():
        stat = proc_stat(entry.name) if entry.name.isdigit() else None
        try:
            if stat and int(stat[1]) == parent and b"zmqserver" in (entry / "cmdline").read_bytes():
                found.append((int(entry.name), stat[19]))
        except OSError:  # it ended meanwhile
            pass
    return found


def running(pid, started):
    """Whether the process (pid, start time) still runs: not gone, not a zombie."""
    stat = proc_stat(pid)
    return stat is not None and stat[19] == started and stat[0] not in "ZX"


def ended_within(server, seconds):
    """Whether the process (pid, start time) ends within ``seconds``."""
    deadline = time.monotonic() + seconds
    while running(*server):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True
