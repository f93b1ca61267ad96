"""A whole simulation against Pinocchio's ``aba`` inside scipy's ``solve_ivp``, in one process.

    MBSYNTH_FAST=wait .venv/bin/python benchmarks/end_to_end.py [--rounds R] [--out FILE]

The UR5 of example-robot-data (fixed base, zero torques, from its zero joint angles and at
rest) falls for 2 s under gravity: ``mb.simulate(mb.from_robot("ur5"), 2.0)`` with DOP853,
rtol = atol = 1e-10 and 501 output rows, against ``solve_ivp(f, (0, 2), y0,
method="DOP853", rtol=1e-10, atol=1e-10, t_eval=501 times)`` with f = (v, pin.aba(q, v, 0))
on the same URDF. mbsynth runs twice: as a user calls it (the model's initial state made
consistent first: ``projection.consistent_initial_state``) and from that consistent state
given as q0, q̇0 (the integration alone). Each figure is the best of ``--rounds`` runs, the three simulations
alternating within a round; ratios are to Pinocchio's time in the same run. Also: the
evaluations of the right-hand side, and for mbsynth the largest position residual of the
outputs and the spread of the total energy (zero for the exact motion). Model building is
not timed in that table; the second table times it, each figure in a fresh process (best
of ``--rounds``): ``import mbsynth``; ``mb.from_robot`` of the UR5 and of talos (the call,
sympy and the rest loaded on the way) with the caches warm, then with its first
``System.motion`` (the compiled engine built from numba's cache), then with the derivation
cache off (``MBSYNTH_DERIVATION_CACHE=off``: every derivation done again; numba's cache
warm); and ``mbsynth check models/robots/ur5_payload.yaml`` end to end (the whole process);
Pinocchio's ``buildModelFromUrdf`` for scale. Writes benchmarks/end_to_end_results.md (or
``--out``).
"""

import argparse
import datetime
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("MBSYNTH_FAST", "wait")  # the compiled kernels, not the KKT path while they build

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import mbsynth as mb  # noqa: E402
from mbsynth.robots import robot_files  # noqa: E402

HERE = Path(__file__).resolve().parent
T_END, OUTPUTS, TOL = 2.0, 500, 1e-10


def pinocchio_run(model, data):
    """(seconds, evaluations) of the UR5's fall with aba inside solve_ivp."""
    tau = np.zeros(model.nv)

    def f(_, y):
        q, v = y[:model.nq], y[model.nq:]
        return np.concatenate([v, pin.aba(model, data, q, v, tau)])

    y0 = np.concatenate([pin.neutral(model), np.zeros(model.nv)])
    started = time.perf_counter()
    sol = solve_ivp(f, (0.0, T_END), y0, method="DOP853", rtol=TOL, atol=TOL,
                    t_eval=np.linspace(0.0, T_END, OUTPUTS + 1))
    return time.perf_counter() - started, sol.nfev


def mbsynth_run(system, **settings):
    """(seconds, evaluations, largest position residual, energy spread) of mb.simulate."""
    started = time.perf_counter()
    traj = mb.simulate(system, T_END, method="DOP853", rtol=TOL, atol=TOL, **settings)
    seconds = time.perf_counter() - started
    return seconds, traj.stats["evaluations"], float(traj.residual_position.max()), float(np.ptp(traj.energy))


TIMED = "import time, sys; t = time.perf_counter(); {code}; print(time.perf_counter() - t)"
BUILDS = {  # what is timed in a fresh process: (code, settings)
    "import mbsynth": ("import mbsynth", {}),
    "from_robot(\"ur5\")": ("import mbsynth as mb; t = time.perf_counter(); mb.from_robot('ur5')", {}),
    "from_robot(\"talos\")": ("import mbsynth as mb; t = time.perf_counter(); mb.from_robot('talos')", {}),
    "from_robot(\"ur5\") and its first motion": (
        "import mbsynth as mb; t = time.perf_counter(); s = mb.from_robot('ur5'); s.motion(0.0, *s.initial_state())",
        {}),
    "from_robot(\"talos\") and its first motion": (
        "import mbsynth as mb; t = time.perf_counter(); s = mb.from_robot('talos'); s.motion(0.0, *s.initial_state())",
        {}),
    "from_robot(\"ur5\"), derivation cache off": (
        "import mbsynth as mb; t = time.perf_counter(); mb.from_robot('ur5')", {"MBSYNTH_DERIVATION_CACHE": "off"}),
    "from_robot(\"talos\"), derivation cache off": (
        "import mbsynth as mb; t = time.perf_counter(); mb.from_robot('talos')", {"MBSYNTH_DERIVATION_CACHE": "off"}),
}
CHECK = ["-m", "mbsynth", "check", "models/robots/ur5_payload.yaml"]
USER_ENV = {k: v for k, v in os.environ.items() if k != "MBSYNTH_FAST"}  # as a user runs them (set above)


def fresh_seconds(code, settings):
    """Seconds ``code`` reports in a fresh interpreter (TIMED)."""
    result = subprocess.run([sys.executable, "-c", TIMED.format(code=code)], env={**USER_ENV, **settings},
                            capture_output=True, text=True, check=True, cwd=HERE.parent)
    return float(result.stdout.split()[-1])


def check_seconds():
    """Wall seconds of ``mbsynth check`` on the UR5 with a payload, the whole process."""
    started = time.perf_counter()
    subprocess.run([sys.executable, *CHECK], env=USER_ENV, capture_output=True, check=True, cwd=HERE.parent)
    return time.perf_counter() - started


def build_lines(rounds):
    """The table of model building, in fresh processes (best of ``rounds``; caches warmed first)."""
    for code, settings in BUILDS.values():
        fresh_seconds(code, {k: v for k, v in settings.items() if k != "MBSYNTH_DERIVATION_CACHE"})
    check_seconds()
    best = {name: min(fresh_seconds(*spec) for _ in range(rounds)) for name, spec in BUILDS.items()}
    best["mbsynth check ur5_payload.yaml (whole process)"] = min(check_seconds() for _ in range(rounds))
    started = time.perf_counter()
    pin.buildModelFromUrdf(robot_files()["talos"])
    best["Pinocchio buildModelFromUrdf(talos), in process"] = time.perf_counter() - started
    return ["| step, fresh process | seconds |", "|---|---:|"] + [f"| {k} | {v:.3f} |" for k, v in best.items()]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", default=str(HERE / "end_to_end_results.md"))
    args = parser.parse_args()
    model = pin.buildModelFromUrdf(robot_files()["ur5"])
    data = model.createData()
    system = mb.from_robot("ur5")
    warm = mb.simulate(system, 0.05)  # compile or load the kernels before timing
    runs = {"mbsynth simulate": {}, "mbsynth simulate, q0 and qd0 given": dict(q0=warm.q[0], qd0=warm.qd[0])}
    best = {"Pinocchio aba + solve_ivp": None, **{name: None for name in runs}}
    for _ in range(args.rounds):
        result = pinocchio_run(model, data)
        best["Pinocchio aba + solve_ivp"] = min(best["Pinocchio aba + solve_ivp"] or result, result)
        for name, settings in runs.items():
            result = mbsynth_run(system, **settings)
            best[name] = min(best[name] or result, result)
    reference = best["Pinocchio aba + solve_ivp"][0]
    lines = ["# End to end: UR5 falling 2 s, mbsynth against Pinocchio aba + solve_ivp", "",
             f"{datetime.date.today()} on {platform.node()} ({os.cpu_count()} cores, {platform.processor() or '?'}), "
             f"best of {args.rounds} alternating rounds, `benchmarks/end_to_end.py`. "
             f"DOP853, rtol = atol = {TOL:g}, {OUTPUTS + 1} outputs; model building not included.", "",
             "| run | seconds | × Pinocchio | evaluations | max residual φ | energy spread (J) |",
             "|---|---:|---:|---:|---:|---:|"]
    for name, values in best.items():
        seconds, evaluations = values[:2]
        extra = f"{values[2]:.1e} | {values[3]:.1e}" if len(values) > 2 else "– | –"
        lines.append(f"| {name} | {seconds:.3f} | {seconds / reference:.1f} | {evaluations} | {extra} |")
    lines += ["", "Building the model (numba's cache warm):", ""] + build_lines(args.rounds)
    text = "\n".join(lines) + "\n"
    Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
