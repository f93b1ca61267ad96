"""``mbsynth view MODEL``: the motion in a live meshcat viewer or a self-contained HTML file."""

import sys

from ..view import viewer
from ..core.errors import ModelError, SimulationError
from ..analysis.simulate import simulate
from ..analysis.trajectory import load_trajectory
from ..io import load
from .outputs import Output
from .parsers import check_flags, model_of

OUTPUTS = (Output("--html", (".html",)),)


def run(args):
    check_flags(args, positive=("--t-end", "--deformation-scale"))
    system = model_of(args)
    status = 0
    if args.trajectory:
        traj = load_trajectory(args.trajectory)
        system = as_run(args, system, traj)
    else:
        try:
            traj = simulate(system, args.t_end, dt=1 / viewer.FPS)
        except SimulationError as err:
            traj, status = err.trajectory, 1
            print(f"error: {err}; drawing the motion up to there", file=sys.stderr)
    options = {"axes": args.axes, "joints": args.joints, "follow": args.follow,
               "deformation_scale": args.deformation_scale}
    if args.html:
        path = viewer.to_html(system, traj, args.html, **options)
        print(f"wrote {path}: {system.name}, t = {traj.t[0]:.6g} to {traj.t[-1]:.6g} s")
    else:
        def ready(url):  # the line that says the page is served
            print(f"meshcat viewer of {system.name}: {url}  (Ctrl-C stops it)", flush=True)

        viewer.show(system, traj, ready=ready, **options)
    return status


def as_run(args, system, traj):
    """The model ``system`` (``args.model`` with --set) as the run ``traj`` was made: with
    the parameter values its file records (an .npz: analysis.trajectory) where they differ,
    said on stderr. ModelError where --set gives one of them another value, or the run
    has parameters the model lacks."""
    if tuple(traj.coordinates) != tuple(system.coordinates):
        return system  # another model's run: refused by the drawing, naming the coordinates
    unknown = sorted(set(traj.parameters) - set(system.parameters))
    if unknown:
        raise ModelError(f"--trajectory {args.trajectory}: a run of model '{traj.model}' with parameter(s) "
                         f"{', '.join(unknown)}, which {args.model} does not have")
    differ = {name: value for name, value in traj.parameters.items() if value != system.parameters[name]}
    if not differ:
        return system
    given = dict(args.set)
    conflict = sorted(set(differ) & set(given))
    if conflict:
        raise ModelError(f"--trajectory {args.trajectory} was run with {_values(traj.parameters, conflict)}; "
                         f"--set {_values(given, conflict)} differs: draw the run as it was made (leave that "
                         "--set out) or give the run's values")
    print(f"note: drawing {args.trajectory} with the parameters it was run with, "
          f"{_values(differ, sorted(differ))} ({args.model} has {_values(system.parameters, sorted(differ))})",
          file=sys.stderr)
    return load(args.model, parameters={**given, **differ})


def _values(values, names):
    """``name=value`` for each of ``names``, as --set takes them."""
    return ", ".join(f"{name}={values[name]:.12g}" for name in names)
