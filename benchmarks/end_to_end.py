"""Whole simulations against Pinocchio's ``aba`` inside scipy's ``solve_ivp``, in one process.

    MBSYNTH_FAST=wait .venv/bin/python benchmarks/end_to_end.py [--rounds R] [--simulations-only] [--out FILE]

Each case runs ``mb.simulate(system, t_end, q0=, qd0=)`` with DOP853, rtol = atol = 1e-10
and 501 output rows, against ``solve_ivp(f, (0, t_end), (q, v), method="DOP853",
rtol=1e-10, atol=1e-10, t_eval=501 times)`` with f = (q̇, pin.aba(q, v, 0)) on the same
model, zero torques, under gravity:

- the UR5 of example-robot-data, fixed base, falling 2 s from its zero joint angles at
  rest; Pinocchio's model from the URDF, mbsynth's ``from_robot("ur5")`` as a user calls
  it (its initial state made consistent by ``simulate``);
- talos, floating (a free-flyer root), 2 s from its neutral pose with the base at rest and
  joint rates drawn in ±0.5 rad/s (seed 7): it falls and flails;
- the spatial pendulum chain of 100 links (benchmarks/fast_dynamics.py), 1 s from joint
  angles in ±0.3 rad and rates in ±0.5 rad/s.

The last two use Pinocchio's model of the mbsynth System (``twin.Twin``: talos's own URDF
model with a free-flyer root, the chain's joints) and start both codes from the same state
(``Twin.to_maximal`` of Pinocchio's); the table gives the largest difference of their final
positions of the bodies. Each figure is the best of ``--rounds`` runs, the two codes alternating;
the ratio is to Pinocchio's time in the same run. Also: the evaluations of the right-hand
side, and for mbsynth the largest position residual of the outputs and the spread of the
total energy (zero for the exact motion). Model building is not timed in that table; the
second table times it, each figure in a fresh process (best of ``--rounds``): ``import
mbsynth``; ``mb.from_robot`` of the UR5 and of talos (the call, sympy and the rest loaded
on the way) with the caches warm, then with its first ``System.motion`` (the compiled
engine built from numba's cache), then with the derivation cache off
(``MBSYNTH_DERIVATION_CACHE=off``: every derivation done again; numba's cache warm); and
``mbsynth check models/robots/ur5_payload.yaml`` end to end (the whole process);
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
from fast_dynamics import chain_yaml  # noqa: E402
from mbsynth.robots import robot_files  # noqa: E402
from mbsynth.twin import Twin  # noqa: E402

HERE = Path(__file__).resolve().parent
T_END, OUTPUTS, TOL = 2.0, 500, 1e-10
CHAIN_T_END = 1.0  # the 100-link chain's run (its motion costs ~0.4 ms an evaluation)
SEED = 7


class Case:
    """One simulation timed in both codes: the mbsynth System, its Pinocchio model (the
    robot's URDF, or ``twin.Twin``), and the state both start from: Pinocchio's (q, v)
    and mbsynth's (q, q̇) of it by forward kinematics (``Twin.to_maximal``); no ``twin``:
    mbsynth's own initial state made consistent by ``simulate`` (as a user calls it)."""

    def __init__(self, name, system, model, q, v, twin=None, t_end=T_END):
        self.name, self.system, self.model, self.q, self.v, self.twin = name, system, model, q, v, twin
        self.start = {} if twin is None else dict(zip(("q0", "qd0"), twin.to_maximal(q, v)))
        self.t_end = t_end


def ur5_case():
    model = pin.buildModelFromUrdf(robot_files()["ur5"])
    return Case("UR5, fixed base, falling from rest", mb.from_robot("ur5"), model, pin.neutral(model),
                np.zeros(model.nv))


def talos_case(rng):
    twin = Twin(mb.from_robot("talos", floating=True))
    rates = np.concatenate([np.zeros(6), rng.uniform(-0.5, 0.5, twin.model.nv - 6)])  # the base at rest
    return Case("talos, floating, joint rates in ±0.5 rad/s", twin.system, twin.model, pin.neutral(twin.model),
                rates, twin)


def chain_case(rng, count=100):
    twin = Twin(mb.loads(chain_yaml(count), name=f"chain_{count}"))
    angles, rates = rng.uniform(-0.3, 0.3, count), rng.uniform(-0.5, 0.5, count)
    return Case(f"chain of {count} links, angles in ±0.3 rad, rates in ±0.5 rad/s", twin.system, twin.model,
                angles, rates, twin, t_end=CHAIN_T_END)


def pinocchio_rhs(model):
    """f(t, (q, v)) = (q̇, aba(q, v, 0)); q̇ = v, or for a free-flyer root (Pinocchio's
    (position, quaternion x y z w) and velocity in its own axes) Rv and ½ u ⊗ (0, ω)."""
    data, tau, nq = model.createData(), np.zeros(model.nv), model.nq
    if model.nq == model.nv:
        def f(_, y):
            q, v = y[:nq], y[nq:]
            return np.concatenate([v, pin.aba(model, data, q, v, tau)])
        return f
    if model.joints[1].shortname() != "JointModelFreeFlyer" or model.nq != model.nv + 1:
        raise ValueError("only a free-flyer root beside one-coordinate joints")

    def f(_, y):
        q, v = y[:nq], y[nq:]
        xyz, w, omega = q[3:6], q[6], v[3:6]
        R = pin.Quaternion(w, *xyz).toRotationMatrix()
        qd = np.concatenate([R @ v[:3], 0.5 * (w * omega + np.cross(xyz, omega)), [-0.5 * xyz @ omega], v[6:]])
        return np.concatenate([qd, pin.aba(model, data, q, v, tau)])
    return f


def pinocchio_run(case):
    """(seconds, evaluations, final q) of the case with aba inside solve_ivp."""
    f = pinocchio_rhs(case.model)
    started = time.perf_counter()
    sol = solve_ivp(f, (0.0, case.t_end), np.concatenate([case.q, case.v]), method="DOP853", rtol=TOL, atol=TOL,
                    t_eval=np.linspace(0.0, case.t_end, OUTPUTS + 1))
    return time.perf_counter() - started, sol.nfev, sol.y[:case.model.nq, -1]


def mbsynth_run(case):
    """(seconds, evaluations, largest position residual, energy spread, final q) of mb.simulate."""
    started = time.perf_counter()
    traj = mb.simulate(case.system, case.t_end, method="DOP853", rtol=TOL, atol=TOL, **case.start)
    seconds = time.perf_counter() - started
    return (seconds, traj.stats["evaluations"], float(traj.residual_position.max()), float(np.ptp(traj.energy)),
            traj.q[-1])


def disagreement(case, pinocchio_q, mbsynth_q):
    """The largest distance between the two codes' final positions of a body's reference
    point (``Twin.to_maximal`` of Pinocchio's q beside mbsynth's q; joint angles would differ
    by turns), or None when the case has no twin (the UR5 from its URDF)."""
    if case.twin is None:
        return None
    reached = case.twin.to_maximal(pinocchio_q, np.zeros(case.model.nv))[0]
    return float(np.linalg.norm((reached - mbsynth_q).reshape(-1, 7)[:, :3], axis=1).max())


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
    parser.add_argument("--simulations-only", action="store_true", help="skip the model-building table")
    parser.add_argument("--out", default=str(HERE / "end_to_end_results.md"))
    args = parser.parse_args()
    rng = np.random.default_rng(SEED)
    cases = [ur5_case(), talos_case(rng), chain_case(rng)]
    for case in cases:
        mb.simulate(case.system, 0.01, **case.start)  # compile or load the kernels before timing
    lines = ["# End to end: mbsynth against Pinocchio aba + solve_ivp", "",
             f"{datetime.date.today()} on {platform.node()} ({os.cpu_count()} cores, {platform.processor() or '?'}), "
             f"`benchmarks/end_to_end.py`. Each simulation: DOP853, rtol = atol = {TOL:g}, {OUTPUTS + 1} outputs, "
             f"zero torques, gravity; mbsynth's `simulate` (a projection onto the constraints at every output) "
             f"against `solve_ivp` of (q̇, `pin.aba`) on the same model; best of {args.rounds} rounds, the two "
             "alternating, the ratio to Pinocchio's time in the same run. *Δx*: the largest distance between the "
             "two codes' final positions of a body (m), both from the same initial state. Model building not included.", "",
             "| system | s | code | seconds | × Pinocchio | evaluations | max residual φ | energy spread (J) | Δx (m) |",
             "|---|---:|---|---:|---:|---:|---:|---:|---:|"]
    for case in cases:
        pinocchio = mbsynth = None
        for _ in range(args.rounds):
            result = pinocchio_run(case)
            pinocchio = result if pinocchio is None or result[0] < pinocchio[0] else pinocchio
            result = mbsynth_run(case)
            mbsynth = result if mbsynth is None or result[0] < mbsynth[0] else mbsynth
        gap = disagreement(case, pinocchio[2], mbsynth[4])
        gap = "–" if gap is None else f"{gap:.1e}"
        lines += [f"| {case.name} | {case.t_end:g} | Pinocchio | {pinocchio[0]:.3f} | 1 | {pinocchio[1]} | – | – | – |",
                  f"| | | mbsynth | {mbsynth[0]:.3f} | {mbsynth[0] / pinocchio[0]:.1f} | {mbsynth[1]} | "
                  f"{mbsynth[2]:.1e} | {mbsynth[3]:.1e} | {gap} |"]
        print(lines[-2], lines[-1], sep="\n", flush=True)
    if not args.simulations_only:
        lines += ["", "Building the model (numba's cache warm):", ""] + build_lines(args.rounds)
    text = "\n".join(lines) + "\n"
    Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
