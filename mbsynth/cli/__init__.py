"""The ``mbsynth`` command.

Exit codes: one table, ``parsers.EXIT_CODES`` (0 success, 1 a verdict, 2 bad input, 3 a
bug, 130 interrupted), printed by every command's --help and the CLI reference. A
command returns 0 or its verdict (1); ``main`` maps what it raises: ``NoEquilibrium``
(no rest state) 1, a ModelError, SolveError or OSError 2, Ctrl-C 130, stdout closed by
its reader 141 (quietly, as any Unix command), anything else 3.
Every error is one readable line on stderr, or ``{"error": ...}`` on stdout with
``--json``; ``--debug`` adds its traceback on stderr (an interruption's and a bug's too).
Every output flag is checked before the command runs, and an interrupted command says
what it left of each (outputs.py).

    parsers.py   the command line of every command: ``parser()`` (argparse only)
    report.py    what every command shares in its output: errors, progress
    outputs.py   the files a command writes: checked first, accounted for on Ctrl-C
    check.py, simulate.py, sweep.py, view.py, validate.py, robots.py
                 one module per command: ``run(args)`` and its report (``OUTPUTS``: its
                 output flags)
    compile_ahead.py
                 ``python -m mbsynth.cli.compile_ahead``: the compiled path's kernels compiled
                 ahead, on warm-up models (``make install``)

``main`` imports only the module of the command it runs, so ``mbsynth check`` loads no
pandas, dask, matplotlib, meshcat or pinocchio.
"""

import argparse
import json
import os
import select
import sys

from ..core import collection
from ..core.errors import ModelError, NoEquilibrium, SolveError
from .outputs import Outputs
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
    outputs = None
    try:
        command = collection.imported(f"{__name__}.{args.command}")
        outputs = Outputs(args, getattr(command, "OUTPUTS", ()))
        outputs.check()
        code = command.run(args)
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
    except KeyboardInterrupt as err:
        return fail(args, err, INTERRUPTED, "interrupted" + (outputs.left() if outputs else ""))
    except Exception as err:  # noqa: BLE001  (a bug: say so in one line, not a traceback)
        return fail(args, err, BUG, f"internal error, a bug in mbsynth ({type(err).__name__}: {err}); "
                                    "--debug shows where")


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
