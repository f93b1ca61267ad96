"""``mbsynth validate ROBOT_OR_MODEL``: mbsynth's joint accelerations against Pinocchio's."""

import json
import time

from ..core.errors import ModelError
from ..io import load
from ..robots.validate import validate_robot, validate_system
from .parsers import check_flags


def run(args):
    if args.samples < 1:
        raise ModelError("--samples must be at least 1")
    check_flags(args, positive=("--tolerance",))
    options = {"samples": args.samples, "seed": args.seed, "tolerance": args.tolerance}
    if args.target.endswith((".yaml", ".yml")):
        if args.merge_fixed:
            raise ModelError("--merge-fixed is for a robot name or URDF file; in a model file give the robot "
                             "entry 'merge_fixed: true'")
        started = time.perf_counter()
        system = load(args.target)
        results = [validate_system(system, build_s=time.perf_counter() - started, **options)]
    else:
        results = validate_robot(args.target, merge_fixed=args.merge_fixed, **options)
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
             f"{'joints':>9} {'reactions':>9} {'loops':>15} {'build s':>8} {'motion ms':>9}  result"]
    for r in results:
        lines.append(f"  {r.base:<9} {r.nv:>4} {r.samples:>7} {r.max_abs_error:>14.3e} {r.max_rel_error:>14.3e} "
                     f"{figure(r.joint_error):>9} {figure(r.reaction_error):>9} {loop_figure(r):>15} "
                     f"{r.build_s:>8.2f} {r.motion_ms:>9.2f}  {'passed' if r.passed else 'FAILED'}")
        if r.note:
            lines.append(f"    {r.note}")
    lines.append("  joints: joint values against Pinocchio's (q, v, v̇); reactions: joint wrenches against rnea's "
                 "data.f (relative; '-': a model with loops or other force elements); loops: loop joints' "
                 "wrenches against constraintDynamics' lambda_c (relative; '-': no loops), on the components "
                 "that are unique ('k free': k components of a redundant loop's wrench are not, and are left out)")
    return "\n".join(lines)


def figure(x):
    """A relative error in a table; '-' for NaN (not compared)."""
    return "-" if x != x else f"{x:.1e}"


def loop_figure(r):
    """The loop reactions' error, and how many wrench components a redundant loop leaves free."""
    return figure(r.loop_reaction_error) + (f" ({r.loop_free} free)" if r.loop_free else "")
