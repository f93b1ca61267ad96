"""The ``mbsynth`` command.

Exit codes: one table, ``parsers.EXIT_CODES`` (0 success, 1 a verdict, 2 bad input, 3 a
bug, 130 interrupted), printed by every command's --help and the CLI reference. A
command returns 0 or its verdict (1); ``main`` maps what it raises: ``NoEquilibrium``
(no rest state) 1, a ModelError, SolveError or OSError 2, Ctrl-C 130, stdout closed by
its reader 141 (quietly, as any Unix command), anything else 3.
Every error is one readable line on stderr, or ``{"error": ...}`` on stdout with
``--json``; ``--debug`` adds the traceback.

    parsers.py   the command line of every command: ``parser()`` (argparse only)
    report.py    what every command shares in its output: errors, progress
    check.py, simulate.py, sweep.py, view.py, validate.py, robots.py
                 one module per command: ``run(args)`` and its report

``main`` imports only the module of the command it runs, so ``mbsynth check`` loads no
pandas, dask, matplotlib, meshcat or pinocchio.
"""

import argparse
import importlib
import json
import os
import select
import sys
from pathlib import Path

from ..core.errors import ModelError, NoEquilibrium, SolveError
from ..analysis.trajectory import output_file
from .parsers import BAD_INPUT, BUG, CLOSED_OUTPUT, INTERRUPTED, VERDICT, UsageError, parser
from .report import fail

__all__ = ["main", "parser"]


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = parser().parse_args(argv)
    except UsageError as err:
        if "--json" not in argv:
            argparse.ArgumentParser.error(err.parser, err.message)  # usage on stderr, exit 2
        print(json.dumps({"error": f"{err.parser.prog}: {err.message}"}))
        return BAD_INPUT
    before = _out_state(args)
    try:
        code = importlib.import_module(f"{__name__}.{args.command}").run(args)
        sys.stdout.flush()  # a reader that closed the pipe is found here, not at exit
        return code
    except NoEquilibrium as err:
        return fail(args, err, VERDICT)
    except BrokenPipeError as err:
        if _stdout_closed():
            return CLOSED_OUTPUT
        return fail(args, err, BAD_INPUT)
    except (ModelError, SolveError, OSError) as err:
        return fail(args, err, BAD_INPUT)
    except KeyboardInterrupt:
        return fail(args, f"interrupted{_kept_output(args, before)}", INTERRUPTED)
    except Exception as err:  # noqa: BLE001  (a bug: say so in one line, not a traceback)
        return fail(args, f"internal error, a bug in mbsynth ({type(err).__name__}: {err}); "
                          "--debug shows where", BUG)


def _stdout_closed():
    """Whether stdout's reader has gone (``mbsynth robots | head``): then stdout is pointed
    at /dev/null, so that nothing more is written there, not even at exit."""
    try:
        poll = select.poll()
        poll.register(sys.stdout.fileno(), select.POLLOUT)
        closed = any(events & select.POLLERR for _, events in poll.poll(0))  # a pipe with no reader
    except (AttributeError, OSError, ValueError):  # no poll() here, or stdout has no file descriptor
        return False
    if closed:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return closed


def _out_file(args):
    """Where the command's --out goes while it runs (None: no --out): a sweep's table in
    place, a run's trajectory in ``output_file`` (FILE.partial for a CSV)."""
    if not getattr(args, "out", None):
        return None
    return Path(output_file(args.out, completed=False) if args.command == "simulate" else args.out)


def _out_state(args):
    """What identifies the file at ``_out_file`` now (inode, mtime, size); None where there is none."""
    try:
        stat = _out_file(args).stat()
    except (AttributeError, OSError):
        return None
    return stat.st_ino, stat.st_mtime_ns, stat.st_size


def _kept_output(args, before):
    """What an interrupted command left of its --out, as the end of its message: where the
    output so far is when the file changed since ``before`` (``_out_state`` at the start),
    else that nothing was written."""
    path = _out_file(args)
    if path is None:
        return ""
    now = _out_state(args)
    if now is None:
        return f"; nothing was written to {path}"
    return f"; the output so far is in {path}" if now != before else f"; nothing was written ({path} is as it was)"
