"""``mbsynth simulate MODEL --t-end T``: integrate a model, print a summary."""

import json
import sys
import time

from ..core.errors import ModelError, SimulationError
from ..analysis.simulate import simulate
from ..analysis.trajectory import output_file
from .outputs import Output, trajectory_output
from .parsers import check_flags, model_of
from .report import ProgressBar, on_terminal

INTEGRATORS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")  # scipy solve_ivp's methods
PLOT_FORMATS = (".png", ".pdf", ".svg")
OUTPUTS = (trajectory_output("--out"), Output("--plot", PLOT_FORMATS))


def run(args):
    check_flags(args, positive=("--t-end", "--dt", "--rtol", "--atol"))
    if args.method not in INTEGRATORS:
        raise ModelError(f"--method {args.method}: not one of {', '.join(INTEGRATORS)}")
    if args.plot_vars and not args.plot:
        raise ModelError(f"--plot-vars {' '.join(args.plot_vars)}: chooses what the figure draws; "
                         "give the figure's file with --plot FILE.png too")
    system = model_of(args)
    if args.plot_vars:
        check_plot_vars(system, args.plot_vars)
    bar = ProgressBar(args.t_end) if on_terminal(args) else None
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
               "energy_drift": traj.energy_drift, "working_forces": system.working_forces(),
               "work": float(traj.work[-1]) if traj.t.size else 0.0, "unaccounted_work": system.unaccounted_work(),
               "initial_changes": traj.stats.get("initial_changes", {}),
               "singular_positions": [{"t_from": float(e["t_from"]), "t_to": float(e["t_to"]), "rows": e["rows"]}
                                      for e in traj.stats.get("singular_positions", [])],
               "relaxed_spans": [{k: float(v) for k, v in e.items()} for e in traj.stats.get("relaxed_spans", [])],
               "events": {kind: sum(e.kind == kind for e in traj.events) for kind in ("impact", "contact", "release")},
               "out": args.out and str(output_file(args.out, completed=error is None)), "plot": args.plot,
               "status": "completed" if error is None else "failed"}
    if error:
        summary["error"] = error
    if args.plot and traj.t.size:
        from ..view.plot import plot_trajectory  # matplotlib: only for --plot

        plot_trajectory(traj, args.plot, title=f"{system.name}", system=system, names=args.plot_vars)
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(format_summary(summary))
    if error and not args.json:
        print(f"error: {error}", file=sys.stderr)
    return 0 if error is None else 1


def check_plot_vars(system, names):
    """ModelError naming each of ``names`` that is no coordinate (part.c), velocity
    (part.c_dot) or output column of ``system``, and those it has."""
    coordinates = system.coordinates
    outputs = [column for output in system.outputs for column in output.columns]
    known = {*coordinates, *(f"{c}_dot" for c in coordinates), *outputs}
    unknown = [name for name in names if name not in known]
    if unknown:
        raise ModelError(f"--plot-vars {' '.join(unknown)}: model '{system.name}' has no such coordinate, velocity "
                         f"or output; its coordinates: {', '.join(coordinates)} (velocities: each with _dot)"
                         + (f"; its outputs: {', '.join(outputs)}" if outputs else "; it declares no outputs"))


def format_summary(s):
    """The human-readable summary of a run."""
    lines = [f"model {s['model']}: simulated to t = {s['t_end']:.6g} s ({s['status']})",
             f"  {s['steps']} steps, {s['evaluations']} evaluations of (2.14), {s['wall_time_s']:.3g} s wall time",
             f"  max constraint residual {s['max_residual']:.3g}, " + _energy_line(s)]
    for name, (given, new) in s["initial_changes"].items():
        lines.append(f"  initial {name}: {given:.9g} -> {new:.9g} (made consistent)")
    if s["singular_positions"]:
        times = ", ".join(f"{e['t_from']:.6g}" for e in s["singular_positions"][:8])
        more = len(s["singular_positions"]) - 8
        rows = sorted({r for e in s["singular_positions"] for r in e["rows"]})
        lines.append(f"  passed near singular positions at t ≈ {times}{f' and {more} more' if more > 0 else ''} "
                     f"(nearly dependent rows: {', '.join(rows[:6])}{', ...' if len(rows) > 6 else ''})")
    if s["relaxed_spans"]:
        spans = s["relaxed_spans"]
        lines.append(f"  integrated at rtol up to {max(e['rtol'] for e in spans):.3g} near them: {len(spans)} "
                     f"span(s) of {sum(e['t_to'] - e['t_from'] for e in spans):.3g} s in all, the first from "
                     f"t = {spans[0]['t_from']:.6g} (the requested tolerance crawled there)")
    if any(s["events"].values()):
        lines.append("  events: " + ", ".join(f"{count} {kind}{'s' if count != 1 else ''}"
                                             for kind, count in s["events"].items()))
    for key in ("out", "plot"):
        if s[key]:
            lines.append(f"  wrote {s[key]}")
    return "\n".join(lines)


def _energy_line(s):
    """The relative change of T + V beyond the work of the forces that derive from no
    potential (dampers, actuation): "drift" only where that work is all accounted."""
    working, unaccounted = s["working_forces"], s["unaccounted_work"]
    accounted = [name for name in working if name not in unaccounted]
    work = f" after the work of {_names(accounted)} ({s['work']:.3g} J)" if accounted else ""
    if not unaccounted:
        return f"relative energy drift {s['energy_drift']:.3g}{work}"
    return (f"relative energy change {s['energy_drift']:.3g}{work}; energy not conserved: the work of "
            f"{_names(unaccounted)} is not accounted")


def _names(names, shown=4):
    """The first ``shown`` of ``names``, joined."""
    return ", ".join(names[:shown]) + (", ..." if len(names) > shown else "")
