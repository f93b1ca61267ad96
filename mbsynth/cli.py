"""The ``mbsynth`` command.

Exit codes: 0 success; 1 a verdict that needs attention (``check``: the model needs
a balance it does not have, or admits no motion at its initial state; a run that had
to stop); 2 a usage or model error, a bad flag value, a file that cannot be read or
written; 3 an internal error (a bug: please report it); 130 interrupted (Ctrl-C; a
run's output so far is kept). Every error is one readable line on stderr, or
``{"error": ...}`` on stdout with ``--json``; ``--debug`` adds the traceback.
"""

import argparse
import json
import math
import sys
import time
import traceback
from pathlib import Path

from .diagnose import diagnose
from .errors import ModelError, SimulationError, SolveError
from .io import load
from .plot import plot_trajectory
from .simulate import STABILIZATIONS, simulate
from .trajectory import load_trajectory, output_file


INTEGRATORS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")  # scipy solve_ivp's methods
PLOT_FORMATS = (".png", ".pdf", ".svg")


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = _parser().parse_args(argv)
    except _UsageError as err:
        if "--json" not in argv:
            argparse.ArgumentParser.error(err.parser, err.message)  # usage on stderr, exit 2
        print(json.dumps({"error": f"{err.parser.prog}: {err.message}"}))
        return 2
    try:
        return args.run(args)
    except (ModelError, SolveError, OSError) as err:
        return _fail(args, err, 2)
    except KeyboardInterrupt:
        kept = f"; the output so far is in {_kept_output(args)}" if getattr(args, "out", None) else ""
        return _fail(args, f"interrupted{kept}", 130)
    except Exception as err:  # noqa: BLE001  (a bug: say so in one line, not a traceback)
        return _fail(args, f"internal error, a bug in mbsynth ({type(err).__name__}: {err}); "
                           "--debug shows where", 3)


def _kept_output(args):
    """Where an interrupted command left its --out: a sweep's table in place, a run's
    trajectory in ``output_file`` (FILE.partial for a CSV)."""
    return output_file(args.out, completed=False) if args.command == "simulate" else args.out


def _fail(args, error, code):
    """Report ``error`` in one line (stderr, or JSON on stdout with --json); return ``code``."""
    if args.debug and isinstance(error, BaseException):
        traceback.print_exc()
    message = " ".join(str(error).split("\n"))
    if getattr(args, "json", False):
        print(json.dumps({"error": message}))
    else:
        print(f"error: {message}", file=sys.stderr)
    return code


def _check_flags(args, positive=(), outputs=()):
    """ModelError for a flag given a value the command cannot use: each of ``positive``
    must be a positive finite number; each of ``outputs`` (flag, suffixes) must be a
    path in an existing folder, ending in one of the suffixes."""
    for flag in positive:
        value = getattr(args, flag.lstrip("-").replace("-", "_"))
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ModelError(f"{flag} must be a positive number, got {value}")
    for flag, suffixes in outputs:
        value = getattr(args, flag.lstrip("-").replace("-", "_"))
        if value is None:
            continue
        if Path(value).suffix.lower() not in suffixes:
            raise ModelError(f"{flag} {value}: the file must end in {', '.join(suffixes)}")
        if not Path(value).parent.is_dir():
            raise ModelError(f"{flag} {value}: the folder {Path(value).parent} does not exist")


class _UsageError(Exception):
    """A command line argparse cannot read (``parser``: the command's, for its usage)."""

    def __init__(self, parser, message):
        super().__init__(message)
        self.parser, self.message = parser, message


class _ArgumentParser(argparse.ArgumentParser):
    """argparse that raises _UsageError instead of exiting, so that main can answer
    with --json's {"error": ...} object."""

    def error(self, message):
        raise _UsageError(self, message)


def _parser():
    parser = _ArgumentParser(prog="mbsynth", description=__doc__.splitlines()[0])
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
    check.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    check.set_defaults(run=run_check)

    sim = commands.add_parser(
        "simulate", help="integrate a model over time",
        description="Integrate the model from its initial state (made consistent with the constraints) "
                    "to --t-end, keeping the constraints by projection; print a summary.")
    sim.add_argument("model", help="model file (YAML)")
    sim.add_argument("--t-end", type=float, required=True, help="end time [s]")
    sim.add_argument("--dt", type=float, help="output interval [s] (default t_end/500)")
    sim.add_argument("--out", help="trajectory file (.npz or .csv), written as the run goes")
    sim.add_argument("--plot", help="figure of coordinates, energy drift and residuals (.png, .pdf, .svg)")
    sim.add_argument("--method", default="DOP853", help="scipy solve_ivp method (default DOP853)")
    sim.add_argument("--rtol", type=float, default=1e-10, help="relative tolerance (default 1e-10)")
    sim.add_argument("--atol", type=float, default=1e-10, help="absolute tolerance (default 1e-10)")
    sim.add_argument("--stabilization", choices=STABILIZATIONS, default="projection",
                     help="drift control (default projection)")
    sim.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    sim.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    sim.set_defaults(run=run_simulate)

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
    sw.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    sw.set_defaults(run=run_sweep)

    view = commands.add_parser(
        "view", help="see the motion: a live meshcat viewer or a self-contained HTML animation",
        description="Simulate the model (or read --trajectory) and draw its motion in meshcat: served live "
                    "on this machine (the URL is printed; Ctrl-C stops it), or with --html written as one "
                    "HTML file that plays offline in any browser.")
    view.add_argument("model", help="model file (YAML)")
    view.add_argument("--t-end", type=float, default=5.0, help="end time of the simulation [s] (default 5)")
    view.add_argument("--trajectory", metavar="FILE.npz", help="draw this saved trajectory instead of simulating")
    view.add_argument("--html", metavar="FILE.html", help="write the animation to this file instead of serving it")
    view.add_argument("--axes", action="store_true", help="draw a triad at every body and frame")
    view.add_argument("--joints", action="store_true", help="mark the frames of every joint")
    view.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    view.set_defaults(run=run_view)

    val = commands.add_parser(
        "validate", help="compare with Pinocchio: a robot (fixed and floating base) or a model file",
        description="Draw random states and joint torques (within the joint limits), compute mbsynth's "
                    "joint accelerations and Pinocchio's (aba, or constraintDynamics where loops are closed) "
                    "and print the largest differences. ROBOT_OR_MODEL is a robot name (see 'mbsynth robots'), "
                    "a URDF file, or a model file (.yaml) of rigid bodies and robots, compared with its "
                    "equivalent Pinocchio model. Exit 0 when every relative error is within the tolerance, "
                    "1 when one is not (or no comparison is possible), 2 on a model error.")
    val.add_argument("target", metavar="ROBOT_OR_MODEL", help="robot name, URDF file or model file")
    val.add_argument("--samples", type=int, default=20, help="random states per base (default 20)")
    val.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    val.add_argument("--tolerance", type=float, default=1e-9, help="largest relative error that passes (default 1e-9)")
    val.add_argument("--json", action="store_true", help="print one JSON object")
    val.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    val.set_defaults(run=run_validate)

    robots = commands.add_parser(
        "robots", help="the robots example-robot-data ships",
        description="List the robots of the example-robot-data package by the names 'mbsynth validate' and "
                    "type: robot accept, with their links, movable joints and whether Pinocchio loads them.")
    robots.add_argument("--json", action="store_true", help="print one JSON object")
    robots.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    robots.set_defaults(run=run_robots)
    return parser


def run_check(args):
    system = load(args.model)
    report = diagnose(system)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        print(format_check(report, args.model))
    return 0 if report.consistent and not report.suggested_constraints else 1


def run_simulate(args):
    _check_flags(args, positive=("--t-end", "--dt", "--rtol", "--atol"),
                 outputs=(("--out", (".npz", ".csv")), ("--plot", PLOT_FORMATS)))
    if args.method not in INTEGRATORS:
        raise ModelError(f"--method {args.method}: not one of {', '.join(INTEGRATORS)}")
    system = load(args.model)
    bar = ProgressBar(args.t_end) if sys.stderr.isatty() and not args.json else None
    started = time.perf_counter()
    try:
        traj = simulate(system, args.t_end, dt=args.dt, method=args.method, rtol=args.rtol, atol=args.atol,
                        stabilization=args.stabilization, out=args.out, progress=bar)
        error = None
    except SimulationError as err:
        traj, error = err.trajectory, str(err)
    finally:
        if bar:
            bar.close()
    summary = {"model": system.name, "t_end": float(traj.t[-1]) if traj.t.size else 0.0, "outputs": int(traj.t.size),
               "steps": traj.stats.get("steps"), "evaluations": traj.stats.get("evaluations"),
               "wall_time_s": round(time.perf_counter() - started, 3), "max_residual": traj.max_residual,
               "energy_drift": traj.energy_drift, "initial_changes": traj.stats.get("initial_changes", {}),
               "singular_positions": [{"t_from": float(e["t_from"]), "t_to": float(e["t_to"]), "rows": e["rows"]}
                                      for e in traj.stats.get("singular_positions", [])],
               "out": args.out and str(output_file(args.out, completed=error is None)), "plot": args.plot,
               "status": "completed" if error is None else "failed"}
    if error:
        summary["error"] = error
    if args.plot and traj.t.size:
        plot_trajectory(traj, args.plot, title=f"{system.name}")
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(format_summary(summary))
    if error and not args.json:
        print(f"error: {error}", file=sys.stderr)
    return 0 if error is None else 1


def run_sweep(args):
    from .sweep import parse_range, sweep

    _check_flags(args, positive=("--t-end", "--dt", "--workers"), outputs=(("--out", (".parquet", ".csv")),))
    params = dict(parse_range(p) for p in args.param) if args.param else None
    metrics = args.metric or ["energy_drift", "max_residual"]
    options = {} if args.dt is None else {"dt": args.dt}
    bar = _sweep_progress if sys.stderr.isatty() and not args.json else None
    started = time.perf_counter()
    table = sweep(args.model, params, args.t_end, samples=args.samples, metrics=metrics, out=args.out,
                  scheduler=args.scheduler, workers=args.workers, trajectories=args.trajectories,
                  progress=bar, **options)
    if bar:
        sys.stderr.write("\n")
    failed = int((table["status"] != "ok").sum())
    summary = {"runs": len(table), "failed": failed, "out": args.out,
               "wall_time_s": round(time.perf_counter() - started, 3)}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{summary['runs']} runs ({failed} failed) in {summary['wall_time_s']:.3g} s; results in {args.out}")
        for row in table[table["status"] != "ok"].head(5).itertuples():
            print(f"  failed {row.run_id}: {row.error}")
    return 0 if failed == 0 else 1


def run_view(args):
    from . import viewer

    _check_flags(args, positive=("--t-end",), outputs=(("--html", (".html",)),))
    system = load(args.model)
    status = 0
    if args.trajectory:
        traj = load_trajectory(args.trajectory)
    else:
        try:
            traj = simulate(system, args.t_end, dt=1 / viewer.FPS)
        except SimulationError as err:
            traj, status = err.trajectory, 1
            print(f"error: {err}; drawing the motion up to there", file=sys.stderr)
    options = {"axes": args.axes, "joints": args.joints}
    if args.html:
        path = viewer.to_html(system, traj, args.html, **options)
        print(f"wrote {path}: {system.name}, t = {traj.t[0]:.6g} to {traj.t[-1]:.6g} s")
    else:
        viewer.show(system, traj, **options)
    return status


def run_validate(args):
    from .validate import validate_robot, validate_system

    if args.samples < 1:
        raise ModelError("--samples must be at least 1")
    _check_flags(args, positive=("--tolerance",))
    options = {"samples": args.samples, "seed": args.seed, "tolerance": args.tolerance}
    if args.target.endswith((".yaml", ".yml")):
        started = time.perf_counter()
        system = load(args.target)
        results = [validate_system(system, build_s=time.perf_counter() - started, **options)]
    else:
        results = validate_robot(args.target, **options)
    passed = all(r.passed for r in results)
    if args.json:
        print(json.dumps({"robot": results[0].robot, "samples": args.samples,
                          "max_abs_error": max(r.max_abs_error for r in results),
                          "max_rel_error": max(r.max_rel_error for r in results), "passed": passed,
                          "tolerance": args.tolerance, "results": [r.to_dict() for r in results]}, indent=2))
    else:
        print(format_validation(results, args.target))
    return 0 if passed else 1


def format_validation(results, target):
    """The ``mbsynth validate`` table: one row per base."""
    first = results[0]
    lines = [f"{first.robot} ({target}): {first.links} bodies, against Pinocchio "
             f"(relative tolerance {first.tolerance:.0e})",
             f"  {'base':<9} {'nv':>4} {'samples':>7} {'max abs error':>14} {'max rel error':>14} "
             f"{'build s':>8} {'motion ms':>9}  result"]
    for r in results:
        lines.append(f"  {r.base:<9} {r.nv:>4} {r.samples:>7} {r.max_abs_error:>14.3e} {r.max_rel_error:>14.3e} "
                     f"{r.build_s:>8.2f} {r.motion_ms:>9.2f}  {'passed' if r.passed else 'FAILED'}")
        if r.note:
            lines.append(f"    {r.note}")
    return "\n".join(lines)


def run_robots(args):
    from .validate import robot_table

    rows = robot_table()
    if args.json:
        print(json.dumps({"robots": [{"name": n, "urdf": p, "links": k, "movable_joints": j, "pinocchio": ok}
                                     for n, p, k, j, ok in rows]}, indent=2))
        return 0
    if not rows:
        print("no robots: install the example-robot-data package")
        return 0
    print(f"{'robot':<28} {'links':>5} {'joints':>6}  pinocchio  urdf")
    for name, path, links, joints, ok in rows:
        print(f"{name:<28} {links:>5} {joints:>6}  {'loads' if ok else 'FAILS':<9}  {'/'.join(path.split('/')[-3:])}")
    return 0


def _sweep_progress(done, failed, total, eta):
    sys.stderr.write(f"\r{done}/{total} runs done, {failed} failed, ~{eta:.0f} s left ")
    sys.stderr.flush()


def format_summary(s):
    lines = [f"model {s['model']}: simulated to t = {s['t_end']:.6g} s ({s['status']})",
             f"  {s['steps']} steps, {s['evaluations']} evaluations of (2.14), {s['wall_time_s']:.3g} s wall time",
             f"  max constraint residual {s['max_residual']:.3g}, relative energy drift {s['energy_drift']:.3g}"]
    for name, (given, new) in s["initial_changes"].items():
        lines.append(f"  initial {name}: {given:.9g} -> {new:.9g} (made consistent)")
    if s["singular_positions"]:
        times = ", ".join(f"{e['t_from']:.6g}" for e in s["singular_positions"][:8])
        more = len(s["singular_positions"]) - 8
        rows = sorted({r for e in s["singular_positions"] for r in e["rows"]})
        lines.append(f"  passed near singular positions at t ≈ {times}{f' and {more} more' if more > 0 else ''} "
                     f"(nearly dependent rows: {', '.join(rows[:6])}{', ...' if len(rows) > 6 else ''})")
    for key in ("out", "plot"):
        if s[key]:
            lines.append(f"  wrote {s[key]}")
    return "\n".join(lines)


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
                lines += _format_balance(balance)
        if report.state_dependent:
            lines.append("    note: these directions depend on the state; the balances hold only "
                         "where the null space keeps this form")
    condition = "infinite" if report.condition is None else f"{report.condition:.3g}"
    margin = "" if report.verdict_margin is None else f", verdict margin {report.verdict_margin:.3g}"
    lines.append(f"  condition number of the equilibrated [M; A] = {condition} "
                 f"(rank tolerance {report.rank_tolerance:g} × σ_max{margin})")
    lines += [f"  warning: {warning}" for warning in report.warnings]
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


def _format_balance(balance):
    """The lines of a balance that is needed: what it is physically where that is known,
    and the equation, its numbers rounded (closure.readable)."""
    effort = balance["effort"]
    advice = "(add it as a constraint, or set 'closure: auto')"
    if effort is None:
        return [f"      balance needed: {balance['readable']}  {advice}"]
    value = "0 at this state, not at every state" if effort["value"] == 0 else f"{effort['value']:.6g} ≠ 0"
    return [f"      balance needed: {effort['name']}: {value}; it must vanish:",
            f"        {balance['readable']}  {advice}"]


def _format_direction(direction):
    return "(" + ", ".join(f"{c}: {x:+.4g}" for c, x in direction.items()) + ")"


if __name__ == "__main__":
    sys.exit(main())
