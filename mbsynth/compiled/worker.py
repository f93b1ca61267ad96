"""A daemon thread that runs tasks one after another, started with the first task: the
compiled path's builds off the caller's thread (background.py's Templates, structures.py's
kernels); and what leaving Python does to them.

A daemon: the interpreter does not wait for a build at exit. But a thread still inside
LLVM (numba's compiler) while the exiting process destroys LLVM's globals aborts the
process (an LLVM assertion, a segmentation fault), and a numba compilation cannot be
interrupted. So at exit (``atexit``, after the other threads are joined) the Workers start
no more tasks (the queued ones start again in the next process that needs them), and the
exit waits for the compilation in progress, if any, and then keeps numba's compiler lock:
the wait is at most one function's compilation, and no thread of the process enters LLVM
after it (one that tries waits on the lock until the process ends). Ctrl-C during the wait
ends the process at once with status 130, without running LLVM's destructors.
"""

import atexit
import os
import queue
import sys
import threading
import time

_workers = []  # every Worker made, closed at exit
INTERRUPTED = 130  # the exit status of a process ended by Ctrl-C (128 + SIGINT), as the CLI's
POLL = 0.01  # seconds between looks at a numba import in progress at exit


class Worker:
    """Runs ``run(*task)`` for each task submitted, in order, on a thread named ``name``;
    ``drop(*task)`` for each task that will not run (leaving Python), when given."""

    def __init__(self, name, run, drop=None):
        self.name, self.run, self.drop = name, run, drop
        self.tasks = queue.Queue()
        self.thread = None
        self.lock = threading.Lock()
        self.closed = False  # leaving Python: no task starts any more
        _workers.append(self)

    def submit(self, *task):
        with self.lock:
            if not self.closed:
                self.tasks.put(task)
                if self.thread is None:
                    self.thread = threading.Thread(target=self._work, name=self.name, daemon=True)
                    self.thread.start()
                return
        self._dropped([task])

    def close(self):
        """Drop the tasks not started and start none any more."""
        with self.lock:
            self.closed = True
            with self.tasks.mutex:
                dropped = list(self.tasks.queue)
                self.tasks.queue.clear()
        self._dropped(dropped)

    def _dropped(self, tasks):
        if self.drop is not None:
            for task in tasks:
                self.drop(*task)

    def _work(self):
        while True:
            self.run(*self.tasks.get())


def _at_exit():
    """Close every Worker, then wait for numba's compilation in progress and hold its lock
    until the process ends (module docstring)."""
    for worker in _workers:
        worker.close()
    try:
        lock = _compiler_lock()
        if lock is not None:
            lock.acquire()  # released by the end of the process
    except KeyboardInterrupt:  # Ctrl-C during the wait: leave now, past LLVM's destructors (os._exit runs none)
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(INTERRUPTED)


def _compiler_lock():
    """numba's compiler lock; None when numba is not imported. While a thread imports numba
    its module is in sys.modules before the lock is made: wait for it (importing it here
    too could deadlock the two imports)."""
    while "numba" in sys.modules:
        lock = getattr(sys.modules.get("numba.core.compiler_lock"), "global_compiler_lock", None)
        if lock is not None:
            return lock
        time.sleep(POLL)
    return None


atexit.register(_at_exit)
