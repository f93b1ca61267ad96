"""``mbsynth check MODEL``: is the motion unique? (Result 3 at the initial state)"""

import json
import os
import re

from ..analysis.diagnose import diagnose
from ..analysis.stiffness import suggestion
from ..compiled.background import default_path_as
from .parsers import model_of
from ..core.tolerances import CHECK_RESIDUAL_TOL


def run(args):
    # a handful of evaluations at one state: the KKT path, no kernels to compile (a path the
    # user set with MBSYNTH_COMPILED is kept)
    with default_path_as("kkt"):
        system = model_of(args)
        report = diagnose(system)
    stiff = suggestion(system, args.t_end)
    if args.json:
        print(json.dumps({**report.to_dict(), "stiff": stiff}, indent=2))
    else:
        print(format_check(report, args.model, args.coordinates))
        if stiff is not None:
            print(format_stiff(stiff, args.t_end))
    return 0 if report.consistent and not report.suggested_constraints and not report.angle_singularities else 1


def format_stiff(stiff, t_end):
    """The line suggesting an implicit method (analysis/stiffness.py)."""
    return (f"  stiff: highest frequency {stiff['omega']:.4g} rad/s (part {stiff['part']}), {stiff['periods']:.0f} "
            f"periods in {t_end:g} s (> {stiff['threshold']}): an explicit method's steps follow that mode; "
            f"where it is quasi-static, simulate with --method {stiff['method']}, which steps over it")


def format_check(report, path, coordinates="joints"):
    """The human-readable ``mbsynth check`` report; ``coordinates``: "joints" reports the
    accelerations and free directions per joint where the model has joints, "maximal" per
    coordinate of the parts."""
    in_joints = coordinates == "joints" and bool(report.joints)
    lines = [f"model {report.model} ({path})",
             f"  coordinates n = {report.n}, constraints m = {report.m}",
             f"  rank M = {report.rank_M}, rank A = {report.rank_A}, "
             f"rank [M; A] = {report.rank_Mhat} of {report.n}"]
    lines += _format_substructures(report, path)
    for balance in report.appended_balances:
        lines.append(f"  balances: auto appended {balance['constraint']}: {balance['equation']}")
    if report.unique:
        lines.append("  motion: unique (Result 3)")
    else:
        lines.append(f"  motion: NOT unique, {report.n - report.rank_Mhat} indeterminate direction(s)")
        for singular in report.angle_singularities:
            lines.append(f"    direction {_format_direction(singular['direction'])}")
            lines.append(f"      {singular['message']}")
        for balance, moved in zip(report.balances, report.free_joints or [{}] * len(report.balances)):
            lines.append(f"    direction {_format_direction(balance['direction'])}")
            if in_joints and moved:
                lines.append(f"      moves joint(s) {', '.join(moved)}")
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
    elif in_joints:
        accelerations = ", ".join(f"{joint}.{name} = {x:.6g}" for joint, j in report.joints.items()
                                  for name, x in zip(j["accelerations"], j["acceleration"]))
        lines.append(f"  joint accelerations at the initial state{'' if report.unique else ' (η = 0)'}: "
                     f"{accelerations or 'none (no joint moves)'}")
    else:
        accelerations = ", ".join(f"{c} = {x:.6g}" for c, x in report.qdd.items())
        lines.append(f"  accelerations at the initial state{'' if report.unique else ' (η = 0)'}: {accelerations}")
    if report.gaps:
        touching = [name for name, gap in report.gaps.items() if gap["gap"] <= CHECK_RESIDUAL_TOL]
        lines.append("  limits and contacts (gap, e): " + ", ".join(
            f"{name} {gap['gap']:.6g} (e = {gap['restitution']:g})" for name, gap in report.gaps.items()))
        lines.append(f"  touching at the initial state: {', '.join(touching) or 'none'}")
    violated = [name for name, r in report.constraint_residuals.items()
                if any(v is not None and abs(v) > CHECK_RESIDUAL_TOL for v in r.values())]
    if violated:
        lines.append(f"  warning: the initial state violates {', '.join(violated)}")
    return "\n".join(lines)


def _format_balance(balance):
    """The lines of a balance that is needed: what it is physically where that is known,
    and the equation, its numbers rounded (balances.readable)."""
    effort = balance["effort"]
    advice = "(add it as a constraint, or set 'balances: auto')"
    if effort is None:
        return [f"      balance needed: {balance['readable']}  {advice}"]
    value = "0 at this state, not at every state" if effort["value"] == 0 else f"{effort['value']:.6g} ≠ 0"
    return [f"      balance needed: {effort['name']}: {value}; it must vanish:",
            f"        {balance['readable']}  {advice}"]


def _format_direction(direction):
    return "(" + ", ".join(f"{c}: {x:+.4g}" for c, x in direction.items()) + ")"


def _format_substructures(report, path):
    """The tree of the model files the model is made of, the whole model at its root: each
    one's coordinates, constraint rows and degrees of freedom; alike consecutive copies
    (``cell[0]`` … ``cell[39]``) on one line."""
    if not report.substructures:
        return []
    folder = os.path.dirname(os.path.abspath(path))
    lines = ["  substructures (coordinates, rows of the constraints wholly inside, degrees of freedom = "
             "coordinates − rank of those rows):",
             f"    {report.model}: {_counts(report.n, report.m, report.n - report.rank_A)}"]

    def add(entries, depth, shown=lambda name: name):
        for run in _runs(entries):
            first, file = run[0], os.path.relpath(run[0]["file"], folder)
            counts = _counts(first["coordinates"], first["rows"], first["degrees_of_freedom"])
            if len(run) == 1:
                name = shown(first["name"])
                lines.append(f"{'  ' * depth}{name}: {file}, {counts}")
            else:
                base, start = _copy(first["name"])
                name = shown(f"{base}[{start}…{_copy(run[-1]['name'])[1]}]")
                lines.append(f"{'  ' * depth}{name}: {len(run)} copies of {file}, each {counts}")
            add(first["children"], depth + 1, lambda child, name=name, inside=first["name"]: name + child[len(inside):])

    add(report.substructures, 3)
    return lines


def _runs(entries):
    """``entries`` split into runs of consecutive copies (``name[k]``, ``name[k + 1]``, …)
    alike in file and counts, their own included substructures too."""
    runs = []
    for entry in entries:
        if runs and _follows(runs[-1][-1], entry):
            runs[-1].append(entry)
        else:
            runs.append([entry])
    return runs


def _follows(before, entry):
    (base, k), (base_next, k_next) = _copy(before["name"]), _copy(entry["name"])
    return base is not None and base == base_next and k_next == k + 1 and _alike(before, entry)


def _alike(a, b):
    """Same file and counts, and alike included substructures (named alike after the prefix)."""
    keys = ("file", "coordinates", "rows", "degrees_of_freedom")
    return (all(a[key] == b[key] for key in keys) and len(a["children"]) == len(b["children"])
            and all(x["name"][len(a["name"]):] == y["name"][len(b["name"]):] and _alike(x, y)
                    for x, y in zip(a["children"], b["children"])))


def _copy(name):
    """(name without its copy index, the index) of a copy ``cell[3]``; (None, None) otherwise."""
    match = re.fullmatch(r"(.*)\[(\d+)\]", name)
    return (match[1], int(match[2])) if match else (None, None)


def _counts(coordinates, rows, freedom):
    return (f"{coordinates} coordinate{'s' * (coordinates != 1)}, {rows} row{'s' * (rows != 1)}, "
            f"{freedom} DOF")
