"""Whole simulations against Pinocchio's ``aba`` or equations by hand, inside scipy's ``solve_ivp``.

    MBSYNTH_COMPILED=wait .venv/bin/python benchmarks/end_to_end.py [--rounds R] [--simulations-only] [--out FILE]

Each case runs ``mb.simulate(system, t_end, q0=, qd0=)`` with DOP853, rtol = atol = 1e-10
and 501 output rows, against ``solve_ivp(f, (0, t_end), (q, v), method="DOP853",
rtol=1e-10, atol=1e-10, t_eval=501 times)`` with f = (q̇, pin.aba(q, v, 0)) on the same
model, zero torques, under gravity:

- the UR5 of example-robot-data, fixed base, falling 2 s from its zero joint angles at
  rest; Pinocchio's model from the URDF, mbsynth's ``from_robot("ur5")`` as a user calls
  it (its initial state made consistent by ``simulate``);
- talos, floating (a free-flyer root), 2 s from its neutral pose with the base at rest and
  joint rates drawn in ±0.5 rad/s (seed 7): it falls and flails; then the same with its
  welded links merged into their parents (``from_robot(..., merge_fixed=True)``), from the
  same state;
- the spatial pendulum chain of 100 links (benchmarks/fast_dynamics.py), 1 s from joint
  angles in ±0.3 rad and rates in ±0.5 rad/s;
- Andrews' squeezer (models/mechanisms/andrews.yaml: IFToMM A03, the IVP test set's
  ``andrews``), 0.03 s from the test set's initial state, against the test set's index-1
  equations written by hand in numpy (``andrews_by_hand``: what one writes without
  mbsynth) instead of Pinocchio; the table's energy is less the motor's work.

Talos and the chain use Pinocchio's model of the mbsynth System (``twin.Twin``: talos's own URDF
model with a free-flyer root, the chain's joints) and start both codes from the same state
(``Twin.to_maximal`` of Pinocchio's); the table gives the largest difference of their final
positions of the bodies. Each figure is the best of ``--rounds`` runs, the two codes alternating;
the ratio is to Pinocchio's time in the same run. mbsynth runs twice a round: as a user
gets it, the projections of the output rows a step passed split among the cores
(mbsynth/compiled/threads.py), and on one thread, as Pinocchio runs. Also: the evaluations of the right-hand
side, and for mbsynth the largest position residual of the outputs and the spread of the
total energy (zero for the exact motion). Model building is not timed in that table; the
second table times it, each figure in a fresh process (best of ``--rounds``): ``import
mbsynth``; ``mb.from_robot`` of the UR5 and of talos (the call, sympy and the rest loaded
on the way) with the caches warm, then with its first ``System.motion`` (the compiled
engine built from numba's cache), then with the derivation cache off
(``MBSYNTH_DERIVATION_CACHE=off``: every derivation done again; numba's cache warm); and
``mbsynth check models/robots/ur5_payload.yaml`` end to end (the whole process); once,
``from_robot("talos")`` and its first motion with no caches at all, waiting while numba
compiles the kernels (``MBSYNTH_COMPILED=wait``; by default the KKT path answers meanwhile);
Pinocchio's ``buildModelFromUrdf`` for scale. A third table splits talos's run into its steps
and its rows: both codes with FEW_OUTPUTS + 1 output rows and with OUTPUTS + 1. Writes
benchmarks/end_to_end_results.md (or ``--out``).

Beside Pinocchio, on the robots and the chain: MuJoCo's ``mj_forward`` on the same model
(benchmarks/mujoco_twin.py: Pinocchio's model written as MJCF, its qacc equal to aba's to
1e-11) in the same solve_ivp, the MJCF built inside the timing; and for the UR5 and the
chain, Exudyn's kinematic tree with its own DOPRI5 at the same tolerances, no step longer
than an output interval (benchmarks/exudyn_tree.py; one run: on the chain it takes about
20 s). Their Δx: the largest distance between a joint's origin at their final configuration
and at Pinocchio's; the count for Exudyn is its accepted steps.
"""

import argparse
import datetime
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MBSYNTH_COMPILED", "wait")  # the compiled kernels, not the KKT path while they build

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import mbsynth as mb  # noqa: E402
import mbsynth.compiled.threads as threads  # noqa: E402
from exudyn_tree import ExudynTree  # noqa: E402
from fast_dynamics import chain_yaml  # noqa: E402
from mbsynth.robots.build import robot_files  # noqa: E402
from mbsynth.robots.twin import Twin  # noqa: E402
from mujoco_twin import MujocoTwin  # noqa: E402

HERE = Path(__file__).resolve().parent
T_END, OUTPUTS, TOL = 2.0, 500, 1e-10
FEW_OUTPUTS = 10  # the rows table's short run: one row per 0.2 s
CHAIN_T_END = 1.0  # the 100-link chain's run (its motion costs ~0.4 ms an evaluation)
ANDREWS_T_END = 0.03  # the test set's interval
ANDREWS = HERE.parent / "models" / "mechanisms" / "andrews.yaml"
SEED = 7


class Case:
    """One simulation timed in both codes: the mbsynth System, the reference code's
    right-hand side ``rhs(t, y)`` and start ``y0`` (its first ``nq`` entries positions), and
    mbsynth's start: with a ``twin`` (twin.Twin), (q, q̇) of Pinocchio's (q, v) by forward
    kinematics (``Twin.to_maximal``); without, mbsynth's own initial state made consistent
    by ``simulate`` (as a user calls it). ``gap(reference's final y[:nq], mbsynth's final
    q)``: how far apart the two codes end (None: not comparable); ``energy(traj)``: what
    the exact motion keeps (the total energy, less the work of a drive). ``others``: further
    codes on the same problem, (name, runs, run) with run(reference's final positions)
    giving (seconds, count, how far its end lies from the reference's), run ``runs`` times
    (None: ``--rounds``)."""

    def __init__(self, name, system, code, rhs, y0, nq, twin=None, t_end=T_END, gap=None, energy=None, others=()):
        self.name, self.system, self.code, self.rhs, self.y0, self.nq = name, system, code, rhs, y0, nq
        self.twin, self.t_end, self.others = twin, t_end, others
        self.start = {} if twin is None else dict(zip(("q0", "qd0"), twin.to_maximal(y0[:nq], y0[nq:])))
        self.gap = gap or (lambda *_: None)
        self.energy = energy or (lambda traj: traj.energy)


def pinocchio_case(name, system, model, q, v, twin=None, t_end=T_END, exudyn=False):
    """A Case against (q̇, pin.aba) of ``model``, with MuJoCo's forward dynamics of the same
    model in the same integrator (benchmarks/mujoco_twin.py) and, with ``exudyn``, Exudyn's
    kinematic tree with its own DOPRI5 (benchmarks/exudyn_tree.py, fixed base only: one run,
    it is slow on the chain)."""
    def mujoco_run(expected):
        started = time.perf_counter()
        mj = MujocoTwin(model)
        sol = integrate(mj.rhs(), mj.state(q, v), t_end)
        seconds = time.perf_counter() - started
        return seconds, sol.nfev, frame_distance(model, mj.configuration(sol.y[:mj.nq, -1]), expected)

    def exudyn_run(expected):
        seconds, steps, reached = ExudynTree(model).run(q, v, t_end, TOL, steps=OUTPUTS)
        return seconds, f"{steps} steps", frame_distance(model, reached, expected)
    agreement = MujocoTwin(model).check(np.random.default_rng(SEED))
    if agreement > 1e-9:
        raise AssertionError(f"{name}: MuJoCo's qacc differs from aba by {agreement:.1e} (relative)")
    others = [("MuJoCo", None, mujoco_run)] + ([("Exudyn", 1, exudyn_run)] if exudyn else [])
    return Case(name, system, "Pinocchio", pinocchio_rhs(model), np.concatenate([q, v]), model.nq, twin, t_end,
                gap=None if twin is None else lambda reached, ours: body_distance(twin, reached, ours), others=others)


def rows_lines(case, rounds):
    """The table of what output rows cost on ``case``: its run with FEW_OUTPUTS + 1 rows and
    with OUTPUTS + 1, each code's best of ``rounds`` (the runs alternating), and the cost of
    each row more."""
    best = {}
    for _ in range(rounds):
        for outputs in (FEW_OUTPUTS, OUTPUTS):
            for code, run in (("Pinocchio", lambda: _seconds(integrate, case.rhs, case.y0, case.t_end, outputs)),
                              ("mbsynth, one thread", lambda: mbsynth_run(case, 1, outputs)[0])):
                best[code, outputs] = min(best.get((code, outputs), np.inf), run())
    lines = ["| code | %d rows (s) | %d rows (s) | each row more (µs) |" % (FEW_OUTPUTS + 1, OUTPUTS + 1),
             "|---|---:|---:|---:|"]
    for code in ("Pinocchio", "mbsynth, one thread"):
        few, many = best[code, FEW_OUTPUTS], best[code, OUTPUTS]
        lines.append(f"| {code} | {few:.4f} | {many:.4f} | {1e6 * (many - few) / (OUTPUTS - FEW_OUTPUTS):.1f} |")
    return lines


def _seconds(function, *args):
    started = time.perf_counter()
    function(*args)
    return time.perf_counter() - started


def frame_distance(model, q, other):
    """The largest distance between a joint's origin at two configurations of ``model``."""
    data, positions = model.createData(), []
    for config in (q, other):
        pin.forwardKinematics(model, data, config)
        positions.append(np.array([data.oMi[i].translation for i in range(1, model.njoints)]))
    return float(np.linalg.norm(positions[0] - positions[1], axis=1).max())


def ur5_case():
    model = pin.buildModelFromUrdf(robot_files()["ur5"])
    return pinocchio_case("UR5, fixed base, falling from rest", mb.from_robot("ur5"), model, pin.neutral(model),
                          np.zeros(model.nv), exudyn=True)


def talos_cases(rng):
    """talos as it is, and with its welded links merged (``merge_fixed=True``) from the same
    state against the same reference (MuJoCo once, with the first)."""
    twin = Twin(mb.from_robot("talos", floating=True))
    rates = np.concatenate([np.zeros(6), rng.uniform(-0.5, 0.5, twin.model.nv - 6)])  # the base at rest
    whole = pinocchio_case("talos, floating, joint rates in ±0.5 rad/s", twin.system, twin.model,
                           pin.neutral(twin.model), rates, twin)
    merged = Twin(mb.from_robot("talos", floating=True, merge_fixed=True))
    welded = len(merged.system.robots[0].description.welded)
    return whole, Case(f"talos as above, its {welded} welded links merged (`merge_fixed=True`)", merged.system,
                       "Pinocchio", whole.rhs, whole.y0, whole.nq, merged,
                       gap=lambda reached, ours: body_distance(merged, reached, ours))


def chain_case(rng, count=100):
    twin = Twin(mb.loads(chain_yaml(count), name=f"chain_{count}"))
    angles, rates = rng.uniform(-0.3, 0.3, count), rng.uniform(-0.5, 0.5, count)
    return pinocchio_case(f"chain of {count} links, angles in ±0.3 rad, rates in ±0.5 rad/s", twin.system,
                          twin.model, angles, rates, twin, t_end=CHAIN_T_END, exudyn=True)


def andrews_case():
    """Andrews' squeezer (IFToMM A03, the IVP test set's ``andrews``), 0.03 s from the test
    set's initial state, against its equations written by hand (``andrews_by_hand``)."""
    system = mb.load(ANDREWS)
    rhs, y0, names = andrews_by_hand(ANDREWS.read_text())
    assert list(system.coordinates) == [f"sq.{c}" for c in names]
    beta, mom = names.index("beta"), system.parameters["mom"]
    return Case("Andrews' squeezer, 7 angles, 6 loop rows, driven", system, "by hand", rhs, y0, len(names),
                t_end=ANDREWS_T_END, gap=lambda reached, ours: float(np.abs(reached - ours).max()),
                energy=lambda traj: traj.energy - mom * (traj.q[:, beta] - traj.q[0, beta]))


def andrews_by_hand(text):
    """What an engineer writes without mbsynth: the test set's index-1 form of Andrews'
    squeezer, [[M, Gᵀ], [G, 0]] (q̈, λ) = (f, γ) solved by numpy at every evaluation, with
    M = ∂²T/∂q̇², f = Q − ∂V/∂q + ∂T/∂q − (∂²T/∂q̇∂q) q̇, G = ∂g/∂q and γ = −(∂(G q̇)/∂q) q̇
    derived by sympy from the model file's T, V, loop rows g and parameters (the test
    set's M, ff and g of andrews.f), lambdified. Returns (rhs(t, y), y0, coordinate names)."""
    import sympy as sp
    import yaml
    spec = yaml.safe_load(text)
    part = spec["parts"]["sq"]
    names = part["coordinates"]
    q, qd = sp.symbols(names), sp.symbols([f"{c}_dot" for c in names])
    numbers = {sp.Symbol(k): v for k, v in spec["parameters"].items()}
    known = {str(x): x for x in (*q, *qd, *numbers)}  # gamma is an angle here, not Euler's function

    def read(text):
        return sp.sympify(str(text).replace("sq.", ""), locals=known).xreplace(numbers)
    T, V = read(part["T"]), read(part["V"])
    g = sp.Matrix([read(c["holonomic"]) for c in spec["constraints"]])
    Q = sp.Matrix([read(part["forces"].get(c, 0)) for c in names])
    rates = sp.Matrix(qd)
    M = sp.hessian(T, qd)
    momenta = sp.Matrix([T.diff(v) for v in qd])
    f = Q - sp.Matrix([V.diff(c) for c in q]) + sp.Matrix([T.diff(c) for c in q]) - momenta.jacobian(q) * rates
    G = g.jacobian(q)
    gamma = -(G * rates).jacobian(q) * rates
    n, m = len(names), g.shape[0]
    terms = sp.lambdify([q, qd], [M, f, G, gamma], "numpy")
    kkt, right = np.zeros((n + m, n + m)), np.zeros(n + m)

    def rhs(_, y):
        M_, f_, G_, gamma_ = terms(y[:n], y[n:])
        kkt[:n, :n], kkt[:n, n:], kkt[n:, :n] = M_, np.transpose(G_), G_
        right[:n], right[n:] = np.ravel(f_), np.ravel(gamma_)
        return np.concatenate([y[n:], np.linalg.solve(kkt, right)[:n]])
    y0 = np.array([float(spec["initial"][f"sq.{c}"]) for c in names] + [0.0] * n)
    return rhs, y0, names


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


def integrate(rhs, y0, t_end, outputs=OUTPUTS):
    """solve_ivp as every reference code is run: DOP853, TOL, ``outputs`` + 1 rows."""
    return solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=TOL, atol=TOL,
                     t_eval=np.linspace(0.0, t_end, outputs + 1))


def reference_run(case):
    """(seconds, evaluations, final positions) of the case's reference code inside solve_ivp."""
    started = time.perf_counter()
    sol = integrate(case.rhs, case.y0, case.t_end)
    return time.perf_counter() - started, sol.nfev, sol.y[:case.nq, -1]


def mbsynth_run(case, cores=None, outputs=OUTPUTS):
    """(seconds, evaluations, largest position residual, energy spread, final q) of
    mb.simulate with ``outputs`` + 1 rows; ``cores``: the threads its projections may take
    (default: one per core)."""
    default, threads.THREADS = threads.THREADS, cores or threads.THREADS
    try:
        started = time.perf_counter()
        traj = mb.simulate(case.system, case.t_end, dt=case.t_end / outputs, method="DOP853", rtol=TOL, atol=TOL,
                           **case.start)
        seconds = time.perf_counter() - started
    finally:
        threads.THREADS = default
    return (seconds, traj.stats["evaluations"], float(traj.residual_position.max()),
            float(np.ptp(case.energy(traj))), traj.q[-1])


def body_distance(twin, pinocchio_q, mbsynth_q):
    """The largest distance between the two codes' final positions of a body's reference
    point (``Twin.to_maximal`` of Pinocchio's q beside mbsynth's q; joint angles would differ
    by turns)."""
    reached = twin.to_maximal(pinocchio_q, np.zeros(twin.model.nv))[0]
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
COLD = ("from_robot(\"talos\") and its first compiled motion, no caches (numba compiles)",
        "import mbsynth as mb; t = time.perf_counter(); s = mb.from_robot('talos'); s.motion(0.0, *s.initial_state())")
CHECK = ["-m", "mbsynth", "check", "models/robots/ur5_payload.yaml"]
USER_ENV = {k: v for k, v in os.environ.items() if k != "MBSYNTH_COMPILED"}  # as a user runs them (set above)


def fresh_seconds(code, settings):
    """Seconds ``code`` reports in a fresh interpreter (TIMED)."""
    result = subprocess.run([sys.executable, "-c", TIMED.format(code=code)], env={**USER_ENV, **settings},
                            capture_output=True, text=True, check=True, cwd=HERE.parent)
    return float(result.stdout.split()[-1])


def cold_seconds():
    """Seconds of COLD in a fresh process with empty caches (derivations and numba's machine
    code in a new directory) that waits for the compiled engine (MBSYNTH_COMPILED=wait) instead
    of answering with the KKT path while it compiles."""
    with tempfile.TemporaryDirectory() as empty:
        return fresh_seconds(COLD[1], {"MBSYNTH_CACHE_DIR": empty, "NUMBA_CACHE_DIR": str(Path(empty) / "numba"),
                                       "MBSYNTH_COMPILED": "wait"})


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
    best[COLD[0] + ", once"] = cold_seconds()
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
    cases = [ur5_case(), *talos_cases(rng), chain_case(rng), andrews_case()]
    for case in cases:
        mb.simulate(case.system, 0.01 * case.t_end, **case.start)  # compile or load the kernels before timing
    lines = ["# End to end: mbsynth against Pinocchio aba + solve_ivp, MuJoCo and Exudyn", "",
             f"{datetime.date.today()} on {platform.node()} ({os.cpu_count()} cores, {platform.processor() or '?'}), "
             f"`benchmarks/end_to_end.py`. Each simulation: DOP853, rtol = atol = {TOL:g}, {OUTPUTS + 1} outputs; "
             f"mbsynth's `simulate` (its state put back on the constraints at every accepted step and output row, "
             f"the rows of a step on every core; *one thread*: on one) "
             f"against `solve_ivp` of the reference code on the same model: (q̇, `pin.aba`) for the robots and "
             f"the chain (zero torques, gravity), and for Andrews' squeezer the IVP test set's index-1 equations "
             f"by hand (numpy, "
             f"`andrews_by_hand`); best of {args.rounds} rounds, the two alternating, the ratio to the reference's "
             "time in the same run; MuJoCo (`mj_forward` in the same `solve_ivp`) and Exudyn (its kinematic tree "
             "and its own DOPRI5) on the same models, their *Δx* the largest distance between a joint's origin at "
             "their end and at Pinocchio's. *Energy spread*: of the total energy (Andrews: less the motor's work), zero for "
             "the exact motion. *Δx*: how far apart the two codes end, from the same initial state: the largest "
             "distance between their final positions of a body (m; Andrews: of the angles, rad). The merged "
             "talos row runs the same reference call as the row above it, from the same state: its mbsynth "
             "seconds compare with that row's directly. Model building not included.", "",
             "| system | s | code | seconds | × reference | evaluations | max residual φ | energy spread (J) | Δx |",
             "|---|---:|---|---:|---:|---:|---:|---:|---:|"]
    for case in cases:
        reference = mbsynth = alone = None
        for _ in range(args.rounds):
            result = reference_run(case)
            reference = result if reference is None or result[0] < reference[0] else reference
            result = mbsynth_run(case)
            mbsynth = result if mbsynth is None or result[0] < mbsynth[0] else mbsynth
            result = mbsynth_run(case, cores=1)
            alone = result if alone is None or result[0] < alone[0] else alone
        gap = case.gap(reference[2], mbsynth[4])
        gap = "–" if gap is None else f"{gap:.1e}"
        lines += [f"| {case.name} | {case.t_end:g} | {case.code} | {reference[0]:.3f} | 1 | {reference[1]} | – | – "
                  "| – |",
                  f"| | | mbsynth | {mbsynth[0]:.3f} | {mbsynth[0] / reference[0]:.1f} | {mbsynth[1]} | "
                  f"{mbsynth[2]:.1e} | {mbsynth[3]:.1e} | {gap} |",
                  f"| | | mbsynth, one thread | {alone[0]:.3f} | {alone[0] / reference[0]:.1f} | {alone[1]} | "
                  f"{alone[2]:.1e} | {alone[3]:.1e} | – |"]
        for code, runs, run in case.others:
            seconds, count, distance = min((run(reference[2]) for _ in range(runs or args.rounds)),
                                           key=lambda r: r[0])
            lines.append(f"| | | {code} | {seconds:.3f} | {seconds / reference[0]:.1f} | {count} | – | – | "
                         f"{distance:.1e} |")
        print(*lines[-3 - len(case.others):], sep="\n", flush=True)
    talos = cases[1]
    lines += ["", f"What the output rows cost: {talos.name}, {talos.t_end:g} s, with {FEW_OUTPUTS + 1} rows and "
              f"with {OUTPUTS + 1} (best of {args.rounds} rounds, the runs alternating). mbsynth puts every row "
              f"back on the constraints (row_fit.py: a few projected exactly per step, the others through them, "
              f"each judged) and records its {talos.system.n} coordinates and rates; Pinocchio's rows are "
              f"solve_ivp's interpolant at {talos.y0.size} numbers (q, v).", ""] + rows_lines(talos, args.rounds)
    print(*lines[-4:], sep="\n", flush=True)
    if not args.simulations_only:
        lines += ["", "Building the model (numba's cache warm, but in the row that says otherwise):", ""] + build_lines(args.rounds)
    text = "\n".join(lines) + "\n"
    Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
