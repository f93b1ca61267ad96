"""What every ``mbsynth`` command shares in its output: errors in one line (or one JSON
object with --json) and a progress bar on a terminal."""

import json
import sys
import time
import traceback


def fail(args, error, code, message=None):
    """Report the exception ``error`` in one line, ``message`` (default: the error's own),
    on stderr (JSON on stdout with --json), after its traceback with --debug; return ``code``."""
    if args.debug:
        traceback.print_exception(error)
    message = " ".join(str(error if message is None else message).split("\n"))
    if getattr(args, "json", False):
        print(json.dumps({"error": message}))
    else:
        print(f"error: {message}", file=sys.stderr)
    return code


def on_terminal(args):
    """Whether a command may draw progress on stderr: a terminal, and no --json."""
    return sys.stderr.isatty() and not getattr(args, "json", False)


class ProgressBar:
    """A one-line progress bar on stderr (only on a terminal)."""

    def __init__(self, t_end, width=40):
        self.t_end, self.width = t_end, width
        self.started = time.perf_counter()

    def __call__(self, t):
        done = min(max(t / self.t_end, 0.0), 1.0)
        filled = int(done * self.width)
        elapsed = time.perf_counter() - self.started
        left = elapsed * (1 - done) / done if done > 0 else float("nan")
        sys.stderr.write(f"\r[{'#' * filled}{'.' * (self.width - filled)}] t = {t:.4g} s, "
                         f"{elapsed:.1f} s elapsed, ~{left:.0f} s left ")
        sys.stderr.flush()

    def close(self):
        sys.stderr.write("\n")
