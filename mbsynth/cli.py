"""The ``mbsynth`` command.

Exit codes: 0 success; 1 a verdict that needs attention (``check``: the model needs
a balance it does not have, or admits no motion at its initial state); 2 a usage or
model error (one readable line on stderr, or ``{"error": ...}`` with ``--json``).
"""

import argparse
import json
import sys
import traceback

from .diagnose import diagnose
from .errors import ModelError, SolveError
from .io import load


def main(argv=None):
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except (ModelError, SolveError, OSError) as err:
        if args.debug:
            traceback.print_exc()
        if getattr(args, "json", False):
            print(json.dumps({"error": str(err)}))
        else:
            print(f"error: {err}", file=sys.stderr)
        return 2


def _parser():
    parser = argparse.ArgumentParser(prog="mbsynth", description=__doc__.splitlines()[0])
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    check = commands.add_parser(
        "check", help="is the motion of a model unique? (Result 3 at the initial state)",
        description="Report the ranks of M, A and [M; A] at the model's initial state, whether the "
                    "motion is unique, each indeterminate direction and the force balance that "
                    "would close it. Exit 0 when the motion is determined or only free directions "
                    "remain, 1 when a balance is missing or no motion exists, 2 on a model error.")
    check.add_argument("model", help="model file (YAML)")
    check.add_argument("--json", action="store_true", help="print one JSON object")
    check.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)
    check.set_defaults(run=run_check)
    return parser


def run_check(args):
    system = load(args.model)
    report = diagnose(system)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        print(format_check(report, args.model))
    return 0 if report.consistent and not report.suggested_constraints else 1


def format_check(report, path):
    """The human-readable ``mbsynth check`` report."""
    lines = [f"model {report.model} ({path})",
             f"  coordinates n = {report.n}, constraints m = {report.m}",
             f"  rank M = {report.rank_M}, rank A = {report.rank_A}, "
             f"rank [M; A] = {report.rank_Mhat} of {report.n}"]
    for closure in report.closures:
        lines.append(f"  closure: auto appended {closure['constraint']}: {closure['equation']}")
    if report.unique:
        lines.append("  motion: unique (Result 3)")
    else:
        lines.append(f"  motion: NOT unique, {report.n - report.rank_Mhat} indeterminate direction(s)")
        for balance in report.balances:
            lines.append(f"    direction {_format_direction(balance['direction'])}")
            if balance["free"]:
                lines.append("      free: no force acts along it, its acceleration is arbitrary")
            else:
                lines.append(f"      balance needed: {balance['equation']}  "
                             "(add it as a constraint, or set 'closure: auto')")
        if report.state_dependent:
            lines.append("    note: these directions depend on the state; the balances hold only "
                         "where the null space keeps this form")
    if report.error:
        lines.append(f"  no motion at the initial state: {report.error}")
    else:
        accelerations = ", ".join(f"{c} = {x:.6g}" for c, x in report.qdd.items())
        lines.append(f"  accelerations at the initial state{'' if report.unique else ' (η = 0)'}: {accelerations}")
    violated = [name for name, r in report.constraint_residuals.items()
                if any(v is not None and abs(v) > 1e-9 for v in r.values())]
    if violated:
        lines.append(f"  warning: the initial state violates {', '.join(violated)}")
    return "\n".join(lines)


def _format_direction(direction):
    return "(" + ", ".join(f"{c}: {x:+.4g}" for c, x in direction.items()) + ")"


if __name__ == "__main__":
    sys.exit(main())
