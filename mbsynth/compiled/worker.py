"""A daemon thread that runs tasks one after another, started with the first task: the
compiled path's builds off the caller's thread (background.py's Templates, structures.py's
kernels). A daemon: leaving Python never waits for a build; one cut short starts again next
time."""

import queue
import threading


class Worker:
    """Runs ``run(*task)`` for each task submitted, in order, on a thread named ``name``."""

    def __init__(self, name, run):
        self.name, self.run = name, run
        self.tasks = queue.Queue()
        self.thread = None
        self.lock = threading.Lock()

    def submit(self, *task):
        with self.lock:
            self.tasks.put(task)
            if self.thread is None:
                self.thread = threading.Thread(target=self._work, name=self.name, daemon=True)
                self.thread.start()

    def _work(self):
        while True:
            self.run(*self.tasks.get())
