"""The command line of every ``mbsynth`` command, in argparse only (no model code is
imported here: ``parser()`` is cheap, and the CLI reference is generated from it)."""

import argparse
import importlib
import math
from collections.abc import Sequence

from ..core.errors import ModelError
from ..core.tolerances import INTEGRATION_ATOL, INTEGRATION_RTOL, VALIDATION_RTOL


# The exit status of every command (main maps what a command raises onto it): the one table
# the CLI reference, ``mbsynth --help`` and each command's --help print (exit_status).
OK, VERDICT, BAD_INPUT, BUG, INTERRUPTED, CLOSED_OUTPUT = 0, 1, 2, 3, 130, 141
EXIT_CODES = {
    OK: "success",
    VERDICT: "a verdict (the command ran, and its answer needs attention)",
    BAD_INPUT: "bad input: a usage error, a bad flag value, a file that cannot be read or written, a model "
               "error (the message names the file and line, part, parameter or value at fault)",
    BUG: "an internal error, a bug in mbsynth (please report it; --debug shows where)",
    INTERRUPTED: "interrupted (Ctrl-C); the message says where the output so far is, or that none was written",
    CLOSED_OUTPUT: "the reader of the printed output closed it early (as in '| head'; 128 + SIGPIPE, as for "
                   "any Unix command): nothing more is printed",
}
VERDICTS = {  # what exit 1 means for each command (none: the command has no verdict)
    "check": "a force balance is missing (the motion is not unique beyond free directions), a part's angles "
             "are at their singular position, or no motion exists at the initial state",
    "simulate": "the run had to stop (its output up to there is kept)",
    "sweep": "a run failed (its row holds the error)",
    "view": "the simulation had to stop (the motion up to there is drawn)",
    "validate": "a relative error exceeds --tolerance, or no comparison is possible",
    "modes": "no rest state (the state is not at rest, q̈ ≠ 0 at q̇ = 0; with --equilibrium: no static "
             "equilibrium is found, or the one found is not isolated; with --steady: the motion is not steady; "
             "rows that prescribe a motion)",
    "robots": None,
}


def exit_status(command=None):
    """The exit-status table as one paragraph: for ``command``, its verdict (exit 1) spelled out."""
    rows = []
    for code, meaning in EXIT_CODES.items():
        if code == VERDICT and command is not None:
            if VERDICTS[command] is None:
                continue
            meaning = f"{meaning}: {VERDICTS[command]}"
        rows.append(f"{code} {meaning}")
    return "Exit status: " + "; ".join(rows) + "."


def parser():
    """The full ``mbsynth`` ArgumentParser; ``args.command`` names the command module."""
    top = ArgumentParser(prog="mbsynth", description="The ``mbsynth`` command.", epilog=exit_status())
    top.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    commands = top.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in (_check, _simulate, _sweep, _view, _validate, _modes, _robots):
        command = add(commands)
        command.epilog = exit_status(command.prog.rsplit(" ", 1)[1])
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    return top


def _model_argument(command):
    """The model file and ``--set NAME=VALUE`` (repeatable): parameter values over the file's."""
    command.add_argument("model", help="model file (YAML)")
    command.add_argument("--set", action="append", type=_assignment, default=[], metavar="NAME=VALUE",
                         help="a parameter's value instead of the model file's (repeatable; parameters defined "
                              "by expressions of it, initial values written with it and what the file builds "
                              "from it, such as a flexible body's FE model, follow)")


def _assignment(text):
    """(name, value) of NAME=VALUE, VALUE a real number."""
    name, sep, value = text.partition("=")
    try:
        number = float(value)
    except ValueError:
        number = None
    if not sep or not name.strip() or number is None or not math.isfinite(number):
        raise argparse.ArgumentTypeError(f"{text!r}: write NAME=VALUE with a finite number, e.g. v=4.6")
    return name.strip(), number


def model_of(args):
    """The System of ``args.model`` built with the ``--set`` values (ModelError naming an
    unknown parameter)."""
    from ..io import load
    return load(args.model, parameters=dict(args.set))


def _check(commands):
    check = commands.add_parser(
        "check", help="is the motion of a model unique? (Result 3 at the initial state)",
        description="Report the ranks of M, A and [M; A] at the model's initial state, whether the "
                    "motion is unique, each indeterminate direction and the force balance that "
                    "would close it (the motion is determined where only free directions remain). "
                    "A model with joints gets its accelerations as joint accelerations (a revolute "
                    "joint's angle, a prismatic joint's displacement, ...: the time derivatives of "
                    "the joints' rates) and the joints each indeterminate direction moves. A model "
                    "made of model files (type: model) gets the tree of its substructures: each one's "
                    "coordinates, rows of the constraints wholly inside it and degrees of freedom.")
    _model_argument(check)
    check.add_argument("--json", action="store_true",
                       help="print one JSON object (both 'qdd', per coordinate, and 'joints'; "
                            "'substructures': the tree, every copy its own entry)")
    check.add_argument("--coordinates", choices=("joints", "maximal"), default="joints",
                       help="report accelerations per joint (default, where the model has joints) or per "
                            "coordinate of the parts ('maximal')")
    check.add_argument("--t-end", type=float, default=1.0,
                       help="the run's length [s] for the stiffness check (default 1): where the highest "
                            "frequency of the flexible parts gives more periods than that check allows, "
                            "an implicit method (--method Radau) is suggested")
    return check


def _simulate(commands):
    sim = commands.add_parser(
        "simulate", help="integrate a model over time",
        description="Integrate the model from its initial state (made consistent with the constraints) "
                    "to --t-end, keeping the constraints by projection; print a summary.")
    _model_argument(sim)
    sim.add_argument("--t-end", type=float, required=True, help="end time [s]")
    sim.add_argument("--dt", type=float, help="output interval [s] (default t_end/500)")
    sim.add_argument("--out", help="trajectory file (.npz or .csv), written as the run goes")
    sim.add_argument("--plot", help="figure (.png, .pdf, .svg) of the joint coordinates (or the model's outputs, "
                                    "or --plot-vars), kinetic and potential energy, and the constraint residuals")
    sim.add_argument("--plot-vars", nargs="+", metavar="NAME",
                     help="what the figure's top panel draws (with --plot): coordinates (part.c), velocities "
                          "(part.c_dot), outputs; a name the model lacks is refused before the run")
    sim.add_argument("--method", default="DOP853",
                     help="scipy solve_ivp method (default DOP853; Radau for a stiff model, as `check` suggests)")
    sim.add_argument("--rtol", type=float, default=INTEGRATION_RTOL,
                     help=f"relative tolerance (default {INTEGRATION_RTOL:g})")
    sim.add_argument("--atol", type=float, default=INTEGRATION_ATOL,
                     help=f"absolute tolerance (default {INTEGRATION_ATOL:g})")
    sim.add_argument("--stabilization", choices=_Deferred("mbsynth.analysis.simulate", "STABILIZATIONS"), metavar="KIND",
                     default="projection", help="drift control: %(choices)s (default projection)")
    sim.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    return sim


def _sweep(commands):
    sw = commands.add_parser(
        "sweep", help="a parameter study: many simulations on Dask",
        description="Simulate the model for every combination of the --param ranges (or every row of "
                    "--samples) on a Dask cluster (a local one by default, or --scheduler), one result "
                    "row per run. Restarting with the same --out skips the runs already done.")
    sw.add_argument("model", help="model file (YAML)")
    grid = sw.add_mutually_exclusive_group(required=True)
    grid.add_argument("--param", action="append", metavar="NAME=START:STOP:COUNT", help="a swept parameter")
    grid.add_argument("--samples", metavar="FILE.csv", help="one run per row; columns are parameter names")
    sw.add_argument("--t-end", type=float, required=True, help="end time of every run [s]")
    sw.add_argument("--out", required=True, help="results table (.parquet or .csv)")
    sw.add_argument("--metric", action="append", metavar="M",
                    help="energy_drift, max_residual, or AGG:expression with AGG final|max|min|mean "
                         "(repeatable; default energy_drift and max_residual)")
    sw.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler (default: a local cluster)")
    sw.add_argument("--workers", type=int, help="local workers (default: one per core; not with --scheduler)")
    sw.add_argument("--trajectories", metavar="DIR",
                    help="also save each run's trajectory as DIR/<run_id>.npz (on this machine)")
    sw.add_argument("--dt", type=float, help="output interval of each run [s]")
    sw.add_argument("--json", action="store_true", help="print a summary as one JSON object")
    return sw


def _view(commands):
    view = commands.add_parser(
        "view", help="see the motion: a live meshcat viewer or a self-contained HTML animation",
        description="Simulate the model (or read --trajectory) and draw its motion in meshcat: served live "
                    "on this machine (the URL is printed; Ctrl-C stops it), or with --html written as one "
                    "HTML file that plays offline in any browser.")
    _model_argument(view)
    view.add_argument("--t-end", type=float, default=5.0, help="end time of the simulation [s] (default 5)")
    view.add_argument("--trajectory", metavar="FILE.npz", help="draw this saved trajectory instead of simulating")
    view.add_argument("--html", metavar="FILE.html", help="write the animation to this file instead of serving it")
    view.add_argument("--axes", action="store_true", help="draw a triad at every body and frame")
    view.add_argument("--joints", action="store_true", help="mark the frames of every joint")
    view.add_argument("--deformation-scale", type=float, default=1.0, metavar="K",
                      help="draw flexible bodies' elastic displacements K times as large (the drawing only; "
                           "default 1)")
    camera = view.add_mutually_exclusive_group()
    camera.add_argument("--follow", dest="follow", action="store_const", const=True, default=None,
                        help="the camera follows the model's centre of mass (default: when it travels further "
                             "than the model's size)")
    camera.add_argument("--no-follow", dest="follow", action="store_const", const=False,
                        help="the camera stays on the box that holds the whole motion")
    return view


def _validate(commands):
    val = commands.add_parser(
        "validate", help="compare with Pinocchio: a robot (fixed and floating base) or a model file",
        description="Draw random states and joint torques (within the joint limits), compute mbsynth's "
                    "joint accelerations and Pinocchio's (aba, or constraintDynamics where loops are closed) "
                    "and print the largest differences; in joint space too: the joint values against "
                    "Pinocchio's (q, v, v̇) and each joint's reaction (the wrench its parent exerts on its child, "
                    "at the child link frame, in its axes) against data.f of rnea, and each loop-closing "
                    "joint's reaction against constraintDynamics' lambda_c (where a loop is redundant, only the "
                    "components of its wrench that are unique). "
                    "ROBOT_OR_MODEL is a robot name (see 'mbsynth robots'), "
                    "a URDF file, or a model file (.yaml) of rigid bodies and robots, compared with its "
                    "equivalent Pinocchio model.")
    val.add_argument("target", metavar="ROBOT_OR_MODEL", help="robot name, URDF file or model file")
    val.add_argument("--samples", type=int, default=20, help="random states per base (default 20)")
    val.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    val.add_argument("--tolerance", type=float, default=VALIDATION_RTOL,
                     help=f"largest relative error that passes (default {VALIDATION_RTOL:g})")
    val.add_argument("--merge-fixed", action="store_true",
                     help="a robot (not a model file) with each link on a fixed joint merged into its parent "
                          "(from_robot's merge_fixed)")
    val.add_argument("--json", action="store_true", help="print one JSON object")
    return val


def _modes(commands):
    modes = commands.add_parser(
        "modes", help="natural frequencies, damping ratios and mode shapes about a rest state or a steady motion",
        description="Linearize the model about its initial configuration at rest (or, with --equilibrium, a "
                    "stable rest found from it; with --steady, about its initial motion, a steady one) in "
                    "independent coordinates of its constraints' tangent space and independent speeds of its "
                    "non-holonomic rows, massless parts closed by their balances, and print one row per mode: "
                    "frequency, damping ratio, kind (vibration, overdamped, unstable, free) and the "
                    "joints (or coordinates) that move most.")
    _model_argument(modes)
    modes.add_argument("--equilibrium", action="store_true",
                       help="first find a stable rest from the initial state: a minimum of the potential on "
                            "the constraints that steps down from it reach (mb.equilibrium; a start at a maximum "
                            "or saddle is left along its steepest way down)")
    modes.add_argument("--steady", action="store_true",
                       help="linearize about the model's initial motion, a steady one (a bicycle rolling upright, a "
                            "disk rolling in a circle: only cyclic coordinates move, at constant rates): its "
                            "eigenvalues are the motion's stability exponents, and the verdict (stable, unstable "
                            "or neutral) names the one with the largest real part")
    modes.add_argument("--json", action="store_true", help="print one JSON object")
    modes.add_argument("--html", metavar="FILE.html",
                       help="write an HTML page animating each mode in meshcat (a selector per mode)")
    modes.add_argument("--campbell", metavar="NAME=START:STOP:COUNT",
                       help="a Campbell diagram: sweep the spin-rate parameter NAME (rad/s; the initial state "
                            "follows it, e.g. initial: {blade.angle_z_dot: Omega}) over COUNT values, linearize "
                            "each steady motion, follow each mode by its shape and list where it meets the "
                            "order lines f = kΩ/2π (implies --steady)")
    modes.add_argument("--orders", type=int, metavar="K",
                       help="with --campbell: the order lines 1P … KP (default 4)")
    modes.add_argument("--plot", metavar="FILE.png",
                       help="with --campbell: write the diagram as an image (.png, .svg or .pdf)")
    return modes


def _robots(commands):
    robots = commands.add_parser(
        "robots", help="the robots example-robot-data ships",
        description="List the robots of the example-robot-data package by the names 'mbsynth validate' and "
                    "type: robot accept, with their links, movable joints and whether Pinocchio loads them.")
    robots.add_argument("--json", action="store_true", help="print one JSON object")
    return robots


def check_flags(args, positive=()):
    """ModelError for a flag given a value the command cannot use: each of ``positive``
    must be a positive finite number (output flags: outputs.py)."""
    for flag in positive:
        value = getattr(args, flag.lstrip("-").replace("-", "_"))
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ModelError(f"{flag} must be a positive number, got {value}")


class UsageError(Exception):
    """A command line argparse cannot read (``parser``: the command's, for its usage)."""

    def __init__(self, parser, message):
        super().__init__(message)
        self.parser, self.message = parser, message


class ArgumentParser(argparse.ArgumentParser):
    """argparse that raises UsageError instead of exiting, so that main can answer
    with --json's {"error": ...} object."""

    def error(self, message):
        raise UsageError(self, message)


class _Deferred(Sequence):
    """A tuple of choices defined in a module that is imported only when argparse reads
    them: to check a value given on the command line, or to print help (the argument
    needs a metavar, which argparse would otherwise build from the choices at once)."""

    def __init__(self, module, name):
        self.module, self.name = module, name

    def __getitem__(self, index):
        return getattr(importlib.import_module(self.module), self.name)[index]

    def __len__(self):
        return len(getattr(importlib.import_module(self.module), self.name))
