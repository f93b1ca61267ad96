"""The ``mbsynth`` command.

Exit codes: 0 success; 1 a verdict that needs attention (``check``: the model needs
a balance it does not have, or admits no motion at its initial state; a run that had
to stop); 2 a usage or model error, a bad flag value, a file that cannot be read or
written; 3 an internal error (a bug: please report it); 130 interrupted (Ctrl-C; a
run's output so far is kept). Every error is one readable line on stderr, or
``{"error": ...}`` on stdout with ``--json``; ``--debug`` adds the traceback.

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
import sys

from ..core.errors import ModelError, SolveError
from ..analysis.trajectory import output_file
from .parsers import UsageError, parser
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
        return 2
    try:
        return importlib.import_module(f"{__name__}.{args.command}").run(args)
    except (ModelError, SolveError, OSError) as err:
        return fail(args, err, 2)
    except KeyboardInterrupt:
        kept = f"; the output so far is in {_kept_output(args)}" if getattr(args, "out", None) else ""
        return fail(args, f"interrupted{kept}", 130)
    except Exception as err:  # noqa: BLE001  (a bug: say so in one line, not a traceback)
        return fail(args, f"internal error, a bug in mbsynth ({type(err).__name__}: {err}); "
                          "--debug shows where", 3)


def _kept_output(args):
    """Where an interrupted command left its --out: a sweep's table in place, a run's
    trajectory in ``output_file`` (FILE.partial for a CSV)."""
    return output_file(args.out, completed=False) if args.command == "simulate" else args.out
