"""1 s of the spatial pendulum chain in mbsynth and in Exudyn, at matched accuracy (issue 7).

    .venv/bin/python benchmarks/exudyn_chain.py [--quick]

The system: N = 10 and N = 100 links of length 0.5 m and mass 1 kg on revolute joints
whose axes alternate x, y, x, ... (``chain_yaml`` of benchmarks/fast_dynamics.py), the
first joint at the world origin, gravity −9.81 z. Both codes use redundant (maximal)
coordinates with Euler parameters: mbsynth 7 per link and the Udwadia–Phohomsiri
equation, Exudyn (``pip install exudyn``, the ``benchmark`` extras) one NodeRigidBodyEP /
ObjectRigidBody per link (``MainSystem.CreateRigidBody``), revolute joints
(``CreateRevoluteJoint``) and gravity as a mass-proportional load.

The initial state: joint angles and rates drawn once (seeded) and mapped to both models
by forward kinematics (``PinocchioChain.to_maximal``): the same positions, rotations,
velocities and angular velocities. Exudyn gets that state as its *reference*
configuration: CreateRigidBody converts ``initialAngularVelocity`` to Euler-parameter
rates with the reference rotation, not with the initial one, so an initial rotation on
top of a straight reference would give the wrong angular velocities.

Accuracy: the error of a run is the largest difference of the links' centre-of-mass
positions at t = 1 s from a reference run, mbsynth with DOP853 at rtol = atol = 1e-12
(its own error is estimated against rtol = atol = 1e-11). That the two codes simulate
the same system is checked separately: Exudyn at its two finest step sizes, and their
Richardson extrapolation (generalized-α is second order), against the reference.

Timing, for each accuracy target (1e-4 and 1e-7 m): each code gets the cheapest setting
of its ladder whose error is at most the target. mbsynth: ``simulate`` with DOP853,
rtol = atol from 1e-3 down in half decades, one output interval (``dt = 1``: the state is
projected on the constraints at t = 1 s only). Exudyn: ``SolveDynamic`` with its default
implicit generalized-α solver (spectral radius 0.9, modified Newton, default tolerances),
the sparse linear solver (EigenSparse), no solution file, a fixed number of steps
(doubling from a start, or jumping to the number the h² law predicts, then bisecting back
to within 25 % of the fewest that meet the target). The wall time is
the best of 3 runs (1 for a run over 30 s) of ``simulate`` / ``SolveDynamic`` alone
(building the model, mbsynth's kernel compilation and Exudyn's ``Assemble`` are not
timed). An Exudyn setting
whose run the h² law predicts to take longer than ``--limit`` seconds is not run: the
table then shows Exudyn's finest run (less accurate than the target, so its time is a
lower bound, and the ratio an upper one). Also timed: mbsynth with 100 output intervals (``dt = 0.01``, a
projection and a record at each), at the 1e-7 setting.

Writes benchmarks/exudyn_results.md (``--quick``: N = 10 only, printed, no file).
"""

import argparse
import datetime
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import exudyn as exu
import exudyn.utilities as eu

import mbsynth as mb
from mbsynth.compiled import engine_for

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from fast_dynamics import LENGTH, MASS, PinocchioChain, axis, chain_yaml  # noqa: E402

T_END = 1.0
GRAVITY = [0.0, 0.0, -9.81]
INERTIA = np.diag([MASS * LENGTH**2 / 12, MASS * LENGTH**2 / 12, MASS * LENGTH**2 / 40])
TARGETS = (1e-4, 1e-7)
RTOLS = [10.0 ** (-k / 2) for k in range(6, 21)]  # 1e-3 ... 1e-10
REPEATS = 3
LONG = 30.0  # s: a run this long is timed once
SEED = 7


# ----------------------------------------------------------------------------- the state

class State:
    """One initial state of the N-chain in both codes' terms (world axes throughout)."""

    def __init__(self, count, seed=SEED):
        rng = np.random.default_rng(seed)
        self.angles = rng.uniform(-0.3, 0.3, count)  # joint angles, rad
        self.rates = rng.uniform(-0.5, 0.5, count)   # joint rates, rad/s
        chain = PinocchioChain(count)
        self.q, self.qd = chain.to_maximal(self.angles, self.rates)  # mbsynth: 7 per link
        pin.forwardKinematics(chain.model, chain.data, self.angles, self.rates)
        self.rotations = [chain.data.oMi[i + 1].rotation.copy() for i in range(count)]
        self.omegas = [R @ chain.data.v[i + 1].angular for i, R in enumerate(self.rotations)]
        self.centres = self.q.reshape(-1, 7)[:, :3]
        self.velocities = self.qd.reshape(-1, 7)[:, :3]


# ----------------------------------------------------------------------------- mbsynth

def mbsynth_system(count):
    system = mb.loads(chain_yaml(count), name=f"chain_{count}")
    engine_for(system)  # compile (or load) the compiled path before anything is timed
    return system


def run_mbsynth(system, state, rtol, dt=T_END):
    """Centres of mass at T_END, wall time of ``simulate``, and its counters."""
    started = time.perf_counter()
    traj = mb.simulate(system, T_END, q0=state.q, qd0=state.qd, method="DOP853", rtol=rtol, atol=rtol, dt=dt)
    wall = time.perf_counter() - started
    assert traj.status == "completed", traj.status
    return traj.q[-1].reshape(-1, 7)[:, :3], wall, dict(steps=traj.stats["steps"], evaluations=traj.stats["evaluations"])


def motion_time(system, state):
    """Best time of one ``System.motion`` (the right-hand side) at the initial state."""
    best = math.inf
    for _ in range(5):
        started = time.perf_counter()
        for _ in range(20):
            system.motion(0.0, state.q, state.qd)
        best = min(best, (time.perf_counter() - started) / 20)
    return best


# ----------------------------------------------------------------------------- Exudyn

def exudyn_chain(count, state):
    """The chain in Exudyn, in the initial state as its reference configuration; returns
    (mbs, node numbers)."""
    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.CreateGround()
    inertia = eu.RigidBodyInertia(MASS, INERTIA)  # centre of mass at the node
    links = [mbs.CreateRigidBody(referencePosition=list(state.centres[i]), referenceRotationMatrix=state.rotations[i],
                                 initialVelocity=list(state.velocities[i]), initialAngularVelocity=list(state.omegas[i]),
                                 inertia=inertia, gravity=GRAVITY, returnDict=True)
             for i in range(count)]
    for i in range(count):
        parent = ground if i == 0 else links[i - 1]["bodyNumber"]
        R = state.rotations[i]
        mbs.CreateRevoluteJoint(itemNumbers=[parent, links[i]["bodyNumber"]],
                                position=list(state.centres[i] + R @ [0, 0, LENGTH / 2]), axis=list(R @ axis(i)),
                                useGlobalFrame=True)
    mbs.Assemble()
    return mbs, [link["nodeNumber"] for link in links]


def exudyn_settings(steps):
    settings = exu.SimulationSettings()
    settings.timeIntegration.endTime = T_END
    settings.timeIntegration.numberOfSteps = steps
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.active = False
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    return settings


def run_exudyn(count, state, steps):
    """Centres of mass at T_END, wall time of ``SolveDynamic``, and its counters."""
    mbs, nodes = exudyn_chain(count, state)
    settings = exudyn_settings(steps)
    started = time.perf_counter()
    mbs.SolveDynamic(settings)
    wall = time.perf_counter() - started
    it = mbs.sys["dynamicSolver"].it
    assert abs(it.currentTime - T_END) < 1e-9, it.currentTime
    centres = np.array([mbs.GetNodeOutput(n, exu.OutputVariableType.Position) for n in nodes])
    return centres, wall, dict(steps=it.currentStepIndex, newton=it.newtonStepsCount, jacobians=it.newtonJacobiCount)


# ----------------------------------------------------------------------------- matching

class Runs:
    """Runs of one code on one chain, kept by setting: error against the reference, the
    best wall time so far, the counters of the last run."""

    def __init__(self, run, reference):
        self.run, self.reference, self.done = run, reference, {}

    def __call__(self, setting, repeats=1):
        """Run ``setting`` until it has ``repeats`` runs (one only if a run takes over LONG s)."""
        entry = self.done.get(setting)
        while entry is None or (entry["runs"] < repeats and entry["wall"] < LONG):
            centres, wall, counters = self.run(setting)
            if entry is None:
                entry = dict(centres=centres, error=np.abs(centres - self.reference).max(), wall=wall, runs=0)
            entry.update(wall=min(wall, entry["wall"]), runs=entry["runs"] + 1, **counters)
            self.done[setting] = entry
            print(f"    {setting!r:>24}: error {entry['error']:.2e}, {wall:.3f} s, {counters}", flush=True)
        return entry


def match_mbsynth(runs, target):
    """The loosest rtol of the ladder whose error is at most ``target`` (None if none is)."""
    for rtol in RTOLS:
        if runs(rtol)["error"] <= target:
            return rtol
    return None


def match_exudyn(runs, target, start, limit):
    """Few steps (a multiple of ``start``) whose error is at most ``target``: at least
    doubling, or jumping to what error ∝ h² predicts (plus 15 %). Returns (steps, None)
    or (None, why not)."""
    coarser = [s for s, entry in runs.done.items() if entry["error"] > target]
    steps = max(coarser, default=start)  # go on from the finest run that missed the target
    while True:
        entry = runs(steps)
        if entry["error"] <= target:
            return narrow(runs, target, max([s for s in coarser if s < steps], default=None), steps, start), None
        coarser.append(steps)
        needed = 1.15 * steps * math.sqrt(entry["error"] / target)
        following = max(2 * steps, start * math.ceil(needed / start))
        predicted = entry["wall"] / entry["steps"] * following  # per step taken (Newton failures halve steps)
        if predicted > limit:
            return None, (f"{following} steps needed by error ∝ h² (from {entry['error']:.1e} at {steps} steps), "
                          f"predicted {predicted:.0f} s > limit {limit:.0f} s")
        steps = following


def narrow(runs, target, missed, met, start):
    """Bisect (geometrically, in multiples of ``start``) between a step count that missed
    the target and one that met it, until they are within 25 %: a jump may overshoot."""
    while missed is not None and met > 1.25 * missed:
        middle = start * round(math.sqrt(missed * met) / start)
        if middle in (missed, met):
            break
        if runs(middle)["error"] <= target:
            met = middle
        else:
            missed = middle
    return met


# ----------------------------------------------------------------------------- one chain

def benchmark(count, targets, limit):
    print(f"chain N = {count}", flush=True)
    state = State(count)
    system = mbsynth_system(count)
    reference, ref_wall, ref_counters = run_mbsynth(system, state, 1e-12)
    check, _, _ = run_mbsynth(system, state, 1e-11)
    mbsynth = Runs(lambda rtol: run_mbsynth(system, state, rtol), reference)
    exudyn = Runs(lambda steps: run_exudyn(count, state, steps), reference)
    start = 100 if count <= 10 else 500
    result = dict(count=count, reference_self=np.abs(check - reference).max(), reference_wall=ref_wall,
                  reference_counters=ref_counters, rows=[], motion=motion_time(system, state))
    for target in targets:
        print(f"  target {target:.0e}", flush=True)
        rtol = match_mbsynth(mbsynth, target)
        steps, why = match_exudyn(exudyn, target, start, limit)
        m = mbsynth(rtol, REPEATS) if rtol is not None else None
        e = exudyn(steps, REPEATS) if steps is not None else None
        if e is None:  # its finest run, less accurate than the target, bounds its time from below
            steps = max(exudyn.done)
            e = exudyn(steps, REPEATS)
        result["rows"].append(dict(target=target, rtol=rtol, mbsynth=m, steps=steps, exudyn=e, why=why))
    last = next((r for r in reversed(result["rows"]) if r["rtol"] is not None), None)
    if last is not None:  # the cost of output: 100 output intervals, each projected and recorded
        outputs = Runs(lambda rtol: run_mbsynth(system, state, rtol, dt=0.01), reference)
        result["outputs"] = (last["rtol"], outputs(last["rtol"], REPEATS))
    result["crosscheck"] = crosscheck(exudyn, reference)
    return result


def crosscheck(exudyn, reference):
    """Exudyn's finest run and the one with half its steps, the Richardson
    extrapolation (x_h/2 + (x_h/2 − x_h)/3), each one's difference from the reference."""
    finest = max(exudyn.done)
    coarse = finest // 2
    exudyn(coarse)  # run only if the ladder did not
    x1, x2 = exudyn.done[coarse]["centres"], exudyn.done[finest]["centres"]
    extrapolated = x2 + (x2 - x1) / 3
    return dict(steps=finest, raw=np.abs(x2 - reference).max(), extrapolated=np.abs(extrapolated - reference).max())


# ----------------------------------------------------------------------------- the report

def seconds(value):
    return f"{value:.4f}" if value < 1 else f"{value:.2f}"


def wall(entry):
    """The best wall time, with the number of runs when it is not REPEATS."""
    return seconds(entry["wall"]) + ("" if entry["runs"] == REPEATS else " (1 run)" if entry["runs"] == 1
                                     else f" (best of {entry['runs']})")


def table(results):
    lines = ["| system | target (m) | code | settings | steps / evaluations | error vs reference (m) | wall s | "
             "mbsynth / Exudyn |", "|---|---:|---|---|---|---:|---:|---:|"]
    for res in results:
        label = f"chain N = {res['count']}"
        for row in res["rows"]:
            m, e = row["mbsynth"], row["exudyn"]
            ratio = "—" if not m else f"**{m['wall'] / e['wall']:.3f}**" if not row["why"] else \
                f"**< {m['wall'] / e['wall']:.3f}**"
            if m:
                lines.append(f"| {label} | {row['target']:.0e} | mbsynth | DOP853, rtol = atol = {row['rtol']:.1e}, dt = 1 | "
                             f"{m['steps']} steps, {m['evaluations']} motion() | {m['error']:.1e} | "
                             f"{wall(m)} | {ratio} |")
            else:
                lines.append(f"| {label} | {row['target']:.0e} | mbsynth | no rtol ≥ 1e-10 reaches the target | — | — | — | — |")
            missed = f" — misses the target; not run finer: {row['why']}" if row["why"] else ""
            lines.append(f"| {label} | {row['target']:.0e} | Exudyn | generalized-α, h = 1/{row['steps']} s, "
                         f"sparse{missed} | {e['steps']} steps, {e['newton']} Newton it., {e['jacobians']} Jacobians | "
                         f"{e['error']:.1e} | {wall(e)} | {ratio} |")
        if "outputs" in res:
            rtol, o = res["outputs"]
            lines.append(f"| {label} | — | mbsynth | as above, rtol = {rtol:.1e}, but dt = 0.01 (100 outputs) | "
                         f"{o['steps']} steps, {o['evaluations']} motion() | {o['error']:.1e} | {wall(o)} | — |")
    return lines


def notes(results):
    lines = []
    for res in results:
        c = res["crosscheck"]
        r = res["rows"][-1]["mbsynth"]
        share = f"; of mbsynth's {seconds(r['wall'])} s at the {res['rows'][-1]['target']:.0e} setting, " \
                f"{r['evaluations']} × {res['motion'] * 1e6:.0f} µs (one `System.motion`) = " \
                f"{100 * r['evaluations'] * res['motion'] / r['wall']:.0f} % is the right-hand side" if r else ""
        lines.append(f"- chain N = {res['count']}: reference (rtol = 1e-12: {res['reference_counters']['steps']} steps, "
                     f"{seconds(res['reference_wall'])} s) against rtol = 1e-11: {res['reference_self']:.1e} m. "
                     f"Same system: Exudyn with {c['steps']} steps differs from it by {c['raw']:.1e} m, its Richardson "
                     f"extrapolation (with {c['steps'] // 2} steps) by {c['extrapolated']:.1e} m{share}.")
    return lines


def write(results, args, path):
    lines = ["# mbsynth against Exudyn: 1 s of the spatial pendulum chain", "",
             f"{datetime.date.today()}, {platform.platform()}, {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} cores (shared), Python {platform.python_version()}, Exudyn {exu.config.Version()}, "
             f"mbsynth {getattr(mb, '__version__', '?')}; written by `.venv/bin/python benchmarks/exudyn_chain.py"
             f"{' --quick' if args.quick else ''}` (limit {args.limit:.0f} s per Exudyn run).", "",
             "Links of 0.5 m and 1 kg on revolute joints about x, y, x, ... (`chain_yaml` of fast_dynamics.py), "
             f"gravity −9.81 z, from one initial state drawn once (seed {SEED}: joint angles in ±0.3 rad, rates in "
             "±0.5 rad/s) and mapped to both models by forward kinematics; both in maximal coordinates with Euler "
             "parameters. *error*: the largest difference of the links' centre-of-mass positions at t = 1 s from "
             "mbsynth at rtol = atol = 1e-12. Each code gets the cheapest setting of its ladder (mbsynth: rtol in "
             "half decades; Exudyn: number of steps, predicted from error ∝ h², then bisected to within 25 %) "
             "whose error is at most "
             "the target. *wall s*: best of 3 (1 for a run over 30 s) of `mbsynth.simulate` / `SolveDynamic` alone (model building, "
             "compilation and `Assemble` not timed); Exudyn single-threaded (its default), no solution file, "
             "EigenSparse; mbsynth with the fast (tree) path compiled beforehand, one output interval (the state is "
             "projected onto the constraints at t = 1 s). *< r*: Exudyn missed the target at its finest run, "
             "so the true ratio is below r.", ""]
    lines += table(results) + ["", "Checks:", ""] + notes(results) + [""]
    text = "\n".join(lines)
    print(text)
    if path is not None:
        path.write_text(text)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="N = 10 only, the 1e-4 target, print only")
    parser.add_argument("--limit", type=float, default=300.0, help="skip an Exudyn run predicted to take longer (s)")
    args = parser.parse_args()
    counts, targets = ([10], TARGETS[:1]) if args.quick else ([10, 100], TARGETS)
    results = []
    for count in counts:
        results.append(benchmark(count, targets, args.limit))
        if not args.quick:
            write(results, args, HERE / "exudyn_results.md")  # as it goes: N = 100 takes long
    if args.quick:
        write(results, args, None)


if __name__ == "__main__":
    main()
