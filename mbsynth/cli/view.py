"""``mbsynth view MODEL``: the motion in a live meshcat viewer or a self-contained HTML file."""

import sys

from ..view import viewer
from ..core.errors import SimulationError
from ..analysis.simulate import simulate
from ..analysis.trajectory import load_trajectory
from .parsers import check_flags, model_of


def run(args):
    check_flags(args, positive=("--t-end", "--deformation-scale"), outputs=(("--html", (".html",)),))
    system = model_of(args)
    status = 0
    if args.trajectory:
        traj = load_trajectory(args.trajectory)
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
