"""The paper's loop models in mbsynth, in Exudyn and against exact or hand-written equations (issue 44).

    .venv/bin/python benchmarks/loops.py [--quick] [--limit S] [--repeats R] [--only NAME,...]

Problems (``--only``: four_bar_2, four_bar_40, bricard, cart_pole, andrews, tennis):

- ``four_bar_2``, ``four_bar_40``: the IFToMM A02 N-four-bar, N = 2 and 40, 20 s, outputs
  every 0.1 s. mbsynth runs ``n_four_bar_yaml(N)`` (benchmarks/iftomm_reference.py: planar
  bodies, revolute joints); Exudyn runs the same mechanism written here with its own 2D
  items (``exudyn_four_bar``: NodeRigidBody2D / ObjectRigidBody2D bars of 1 m and 1 kg,
  inertia m L²/12 about the centre, RevoluteJoint2D between MarkerBodyPosition points,
  gravity 9.81 along −y as LoadMassProportional, the same initial velocities: every
  vertical bar turning at −1 rad/s, its centre at 0.5 m/s along +x, the horizontal bars
  translating at 1 m/s). Error: the largest distance of the point B0 (the first vertical
  bar's top) from the exact one-degree-of-freedom motion (``n_four_bar_reference`` at
  1e-13) over the 201 outputs. The reference cost: that exact ODE (J ψ'' = K sin ψ) in
  solve_ivp, DOP853 at rtol = atol = 1e-10, with its dense output at the 201 times.
- ``bricard``: A04, Bricard's overconstrained loop (models/mechanisms/bricard.yaml), 10 s.
  Exudyn: the same five 1 m, 1 kg bricks (``exudyn_bricard``: rigid bodies with Euler
  parameters at their centres, local x along the rod, inertia m(L² + a²)/12 across and
  m 2a²/12 along, a = 0.1 m), five revolute joints and, for the sixth, a generic joint
  that leaves the rotation about x free (as Exudyn's TestModels/bricardMechanism.py does:
  its solver needs the redundant row gone), the dense linear solver told to ignore a
  singular Jacobian. No closed form: the error is the distance of point P3 (link3's end
  at (1, −1, 1) at the start) at 10 s from mbsynth's run at rtol = atol = 1e-12; Exudyn's
  finest run is shown against it (the two codes' best answers agree to that figure).
  mbsynth with 20 and with 10,000 outputs at the default tolerance (their cost ratio from
  RATIO_ROUNDS alternating rounds, best of each), and a ladder of tolerances; whether it logs "not unique" at each. Matched accuracy: for each Exudyn run,
  the cheapest mbsynth run of the ladder whose error is at most Exudyn's.
- ``cart_pole``: a cart (1 g, on a spring of 10 N/m) carrying a pole (1 kg, its centre
  0.5 m from the pivot, 1/12 kg m² about it), one ``type: lagrangian`` part in the two
  coordinates (x, θ) (``CART_POLE``), released at θ = 1 rad, 10 s, 1001 outputs, against
  its closed-form Lagrange equations (2×2 solved by Cramer's rule) in solve_ivp at the
  same tolerance (DOP853, rtol = atol = 1e-10, t_eval at the 1001 times). Error: the
  largest |Δx|, |Δθ| over the outputs from the same ODE at 1e-13.
- ``andrews``: Andrews' squeezer (models/mechanisms/andrews.yaml), 0.03 s, 501 outputs,
  against the IVP test set's index-1 equations (``end_to_end.andrews_by_hand``:
  [[M, Gᵀ], [G, 0]] (q̈, λ) = (f, −(G q̇)_q q̇) solved by numpy at every evaluation) in
  solve_ivp at the same tolerance; both against the test set's angles at 0.03 s
  (``ANDREWS_T003``).
- ``tennis``: the tennis-racket flip (models/rigid/tennis_racket.yaml), 20 s at the
  default tolerance: the body-axis angular velocity at 20 s (ω = 2 vec(ū ⊗ u̇) of the
  Euler parameters) against Euler's equations in solve_ivp at rtol = atol = 1e-13, and
  Euler's equations at mbsynth's default tolerance beside it.

mbsynth: ``simulate`` with DOP853, rtol = atol as stated (default 1e-10), after a short
warm-up run of the same system (kernel compilation and model building are not timed);
a run that passes ``--limit`` seconds is stopped by an alarm and given up (the table says so).
Exudyn 1.13 (PyPI ``exudyn``, the ``benchmark`` extras): ``SolveDynamic`` with its
default implicit generalized-α (spectral radius 0.9, modified Newton, default
tolerances), a fixed number of steps, no solution file; ``Assemble`` not timed. A step
count whose run the time per step of the previous one predicts to exceed ``--limit`` is
not run. Every wall time is the best of ``--repeats`` runs (one for a run over 30 s), in
this one process, the codes in turn. Writes benchmarks/loops_results.md (``--quick``: a
reduced set, printed only).
"""

import argparse
import datetime
import logging
import math
import os
import platform
import signal
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("MBSYNTH_COMPILED", "wait")  # the compiled kernels, not the KKT path while they build

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import exudyn as exu  # noqa: E402
import exudyn.utilities as eu  # noqa: E402
from exudyn.itemInterface import (LoadMassProportional, MarkerBodyMass, MarkerBodyPosition, NodeRigidBody2D,  # noqa: E402
                                  ObjectGround, ObjectRigidBody2D, RevoluteJoint2D)

import mbsynth as mb  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
import iftomm_reference as ref  # noqa: E402

LONG = 30.0           # s: a run this long is timed once
RATIO_ROUNDS = 9      # alternating rounds of two runs whose cost ratio is a target
DEFAULT = 1e-10       # simulate's default rtol = atol
GRAVITY = 9.81


# ----------------------------------------------------------------------------- timing

class OverLimit(BaseException):
    """Raised by the alarm of a run that passes --limit (a BaseException, as KeyboardInterrupt
    is, so that no ``except Exception`` on the way turns it into a failed step)."""


def over_limit(signum, frame):
    signal.setitimer(signal.ITIMER_REAL, 1.0)  # again in 1 s should a C callback swallow this one
    raise OverLimit()


class NotUnique(logging.Handler):
    """Counts mbsynth's log records that say the motion was not unique."""

    def __init__(self):
        super().__init__(level=logging.DEBUG)
        self.count = 0

    def emit(self, record):
        self.count += "not unique" in record.getMessage()


def best(run, repeats):
    """run() -> dict with "wall": the first run's dict, "wall" the best of ``repeats`` runs
    (one when a run takes over LONG s or did not complete), "runs" how many."""
    entry = run()
    entry["runs"] = 1
    while entry["runs"] < repeats and entry["wall"] < LONG and entry["ok"]:
        entry["wall"] = min(entry["wall"], run()["wall"])
        entry["runs"] += 1
    return entry


def warm(system, t_end):
    """One short run: compiles (or loads) the kernels before anything is timed."""
    mb.simulate(system, t_end, dt=t_end)


def simulate(system, t_end, dt, rtol, limit, measure):
    """One mbsynth run: wall time of ``simulate``, its counters, ``measure(trajectory)``
    (the error), the "not unique" log records, the status (given up past ``limit`` s)."""
    catch = NotUnique()
    logger = logging.getLogger("mbsynth")
    logger.addHandler(catch)
    reached = [0.0]
    traj, status = None, "completed"
    previous = signal.signal(signal.SIGALRM, over_limit)
    started = time.perf_counter()
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        traj = mb.simulate(system, t_end, dt=dt, rtol=rtol, atol=rtol, progress=lambda t: reached.__setitem__(0, t))
    except OverLimit:
        status = f"given up after {limit:.0f} s (--limit), its last output at t = {reached[0]:.3g} s"
    except mb.SimulationError as err:
        status, traj = f"stopped: {err}", err.trajectory
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        logger.removeHandler(catch)
    wall = time.perf_counter() - started
    entry = dict(wall=wall, ok=status == "completed", status=status, not_unique=catch.count, steps=None,
                 evaluations=None, relaxed=None, error=math.nan)
    if traj is not None:
        entry.update(steps=traj.stats["steps"], evaluations=traj.stats["evaluations"],
                     relaxed=len(traj.stats.get("relaxed_spans", [])))
        if status == "completed":
            entry["error"] = measure(traj)
            entry["trajectory"] = traj
    return entry


def alternating_ratio(first, second, rounds):
    """wall(second) / wall(first), each the best of ``rounds`` runs taken in alternation (the
    machine's drift during the rounds falls on both alike)."""
    walls = [[], []]
    for _ in range(rounds):
        for run, wall in zip((first, second), walls):
            wall.append(run()["wall"])
    return min(walls[1]) / min(walls[0])


def reference_ode(rhs, y0, t_end, times, rtol):
    """solve_ivp(DOP853, rtol = atol) through ``times``: (solution, wall)."""
    started = time.perf_counter()
    sol = solve_ivp(rhs, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=rtol, t_eval=times)
    return sol, time.perf_counter() - started


def exudyn_settings(t_end, steps, dense=False, sensor_period=None):
    settings = exu.SimulationSettings()
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.numberOfSteps = steps
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.active = sensor_period is not None
    if sensor_period is not None:
        settings.solution.sensors.writePeriod = sensor_period
    settings.linearSolver.solverType = exu.LinearSolverType.EigenDense if dense else exu.LinearSolverType.EigenSparse
    settings.linearSolver.ignoreSingularJacobian = dense
    return settings


def solve_exudyn(mbs, settings, measure):
    """One Exudyn run: wall time of SolveDynamic, its counters, ``measure(mbs)``."""
    started = time.perf_counter()
    status = "completed"
    try:
        mbs.SolveDynamic(settings)
    except Exception as err:  # noqa: BLE001 - Exudyn raises its own C++ exception types
        status = f"failed: {type(err).__name__}: {str(err).strip()[:120]}"
    wall = time.perf_counter() - started
    it = mbs.sys["dynamicSolver"].it
    end = settings.timeIntegration.endTime
    if status == "completed" and abs(it.currentTime - end) > 1e-9 * end:
        status = "failed"
    if status != "completed":
        status += f" at t = {it.currentTime:.4g} s"
    entry = dict(wall=wall, ok=status == "completed", status=status, steps=it.currentStepIndex,
                 newton=it.newtonStepsCount, jacobians=it.newtonJacobiCount, error=math.nan)
    if entry["ok"]:
        entry["error"] = measure(mbs)
    return entry


def exudyn_ladder(build, step_counts, t_end, limit, repeats, log):
    """Exudyn at each step count in turn (a fresh model each run); a count whose run the
    previous run's time per step predicts to exceed ``limit`` is skipped, and so are the
    finer ones after a failure."""
    rows, previous = [], None
    for steps in step_counts:
        if previous is not None:
            predicted = previous["wall"] / max(previous["steps"], 1) * steps
            if not previous["ok"] or predicted > limit:
                why = "not run: the coarser run failed" if not previous["ok"] else \
                    f"not run: predicted {predicted:.0f} s > --limit {limit:.0f} s"
                rows.append(dict(setting=steps, h=t_end / steps, ok=False, status=why, wall=math.nan, runs=0,
                                 steps=None, newton=None, jacobians=None, error=math.nan))
                continue
        entry = best(lambda: solve_exudyn(*build(steps)), repeats)
        entry.update(setting=steps, h=t_end / steps)
        log(f"    Exudyn h = {t_end / steps:.2e}: error {entry['error']:.2e}, {entry['wall']:.3f} s, {entry['status']}")
        rows.append(entry)
        previous = entry
    return rows


def mbsynth_ladder(system, t_end, dt, rtols, limit, repeats, measure, log):
    rows = []
    for rtol in rtols:
        entry = best(lambda: simulate(system, t_end, dt, rtol, limit, measure), repeats)
        entry.update(setting=rtol)
        log(f"    mbsynth rtol {rtol:.0e}, dt {dt:g}: error {entry['error']:.2e}, {entry['wall']:.3f} s, "
            f"{entry['steps']} steps, {entry['evaluations']} evaluations, {entry['relaxed']} relaxed, "
            f"{entry['not_unique']} 'not unique', {entry['status']}")
        rows.append(entry)
    return rows


# ----------------------------------------------------------------------------- A02: the N-four-bar

FOUR_BAR_T, FOUR_BAR_DT = 20.0, 0.1


def exudyn_four_bar(N, steps, t_end, measure):
    """The N-four-bar of ``n_four_bar_yaml`` in Exudyn's 2D items, in its initial state as the
    reference configuration; returns (mbs, settings, error): error(mbs) is ``measure`` of
    B0's sensor rows (t, x, y), every FOUR_BAR_DT."""
    p = ref.N_FOUR_BAR
    L, m, v0 = p["L"], p["m"], p["v0"]
    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddObject(ObjectGround())

    def bar(centre, velocity):
        node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=centre, initialVelocities=velocity))
        body = mbs.AddObject(ObjectRigidBody2D(mass=m, inertia=m * L**2 / 12, nodeNumber=node))
        mass = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
        mbs.AddLoad(LoadMassProportional(markerNumber=mass, loadVector=[0, -p["g"], 0]))
        return body

    def hinge(first, at_first, second, at_second):
        markers = [mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=point))
                   for b, point in ((first, at_first), (second, at_second))]
        mbs.AddObject(RevoluteJoint2D(markerNumbers=markers))

    vertical = [bar([i * L, L / 2, 0], [v0 / 2, 0, -v0 / L]) for i in range(N + 1)]
    horizontal = [bar([i * L + L / 2, L, 0], [v0, 0, 0]) for i in range(N)]
    for i in range(N + 1):
        hinge(ground, [i * L, 0, 0], vertical[i], [0, -L / 2, 0])
    for i in range(N):
        hinge(vertical[i], [0, L / 2, 0], horizontal[i], [-L / 2, 0, 0])
        hinge(vertical[i + 1], [0, L / 2, 0], horizontal[i], [L / 2, 0, 0])
    sensor = mbs.AddSensor(eu.SensorBody(bodyNumber=vertical[0], localPosition=[0, L / 2, 0],
                                         outputVariableType=exu.OutputVariableType.Position,
                                         storeInternal=True, writeToFile=False))
    mbs.Assemble()
    return mbs, exudyn_settings(t_end, steps, sensor_period=FOUR_BAR_DT), \
        lambda done: measure(done.GetSensorStoredData(sensor)[:, :3])


def b0_error(N):
    """measure(rows (t, x, y) of B0) -> the largest distance from the exact motion."""
    def measure(rows):
        x, y = ref.n_four_bar_reference(rows[:, 0], N)
        return float(np.max(np.hypot(rows[:, 1] - x, rows[:, 2] - y)))
    return measure


def b0_rows(traj, L=1.0):
    """(t, x, y) of B0, the top of bar v0 (its frame (0, L/2))."""
    theta = traj.column("v0.theta")
    return np.column_stack([traj.t, traj.column("v0.x") - L / 2 * np.sin(theta),
                            traj.column("v0.y") + L / 2 * np.cos(theta)])


def four_bar(N, args, log):
    quick = args.quick
    log(f"N-four-bar N = {N}")
    times = np.linspace(0.0, FOUR_BAR_T, round(FOUR_BAR_T / FOUR_BAR_DT) + 1)
    measure = b0_error(N)
    exact_x, exact_y = ref.n_four_bar_reference(times, N)

    def exact_run():
        started = time.perf_counter()
        x, y = ref.n_four_bar_reference(times, N, rtol=DEFAULT, atol=DEFAULT)
        wall = time.perf_counter() - started
        return dict(wall=wall, ok=True, error=float(np.max(np.hypot(x - exact_x, y - exact_y))))
    exact = best(exact_run, max(args.repeats, 5))  # milliseconds: more repeats cost nothing
    log(f"    exact 1-DOF ODE: {exact['wall'] * 1e3:.2f} ms, error {exact['error']:.1e}")
    system = mb.loads(ref.n_four_bar_yaml(N), name=f"n_four_bar_{N}")
    warm(system, 0.1)
    rtols = ([1e-8, DEFAULT] if quick else [1e-6, 1e-8, DEFAULT, 1e-12]) if N == 2 else [1e-6, DEFAULT]
    mbsynth = mbsynth_ladder(system, FOUR_BAR_T, FOUR_BAR_DT, rtols, args.limit, args.repeats,
                             lambda traj: measure(b0_rows(traj)), log)
    counts = ([20000] if quick else [10000, 40000, 160000]) if N == 2 else [10000, 40000]
    exudyn_four_bar(N, 100, 0.1, measure)  # Exudyn's first model built before its timing
    exudyn = exudyn_ladder(lambda steps: exudyn_four_bar(N, steps, FOUR_BAR_T, measure), counts, FOUR_BAR_T,
                           args.limit, args.repeats, log)
    return dict(name=f"four_bar_{N}", N=N, exact=exact, mbsynth=mbsynth, exudyn=exudyn)


# ----------------------------------------------------------------------------- A04: Bricard

BRICARD_T = 10.0
BRICARD = ROOT / "models" / "mechanisms" / "bricard.yaml"
BRICARD_P3 = ("link3", (0.0, 0.0, 0.5))  # link3's end at the joint P3 (its frame, from the centre)


def exudyn_bricard(steps, t_end, measure):
    """Bricard's mechanism of models/mechanisms/bricard.yaml in Exudyn: each link a rigid body
    at its centre, its local x along the rod (so P3 is link3's local (L/2, 0, 0)); returns
    (mbs, settings, error): error(mbs) is ``measure`` of P3 at the end."""
    L, a, m, g = 1.0, 0.1, 1.0, GRAVITY
    rods = [((L / 2, 0, 0), np.eye(3)), ((L, -L / 2, 0), eu.RotationMatrixZ(-math.pi / 2)),
            ((L, -L, L / 2), eu.RotationMatrixY(-math.pi / 2)), ((L / 2, -L, L), eu.RotationMatrixZ(math.pi)),
            ((0, -L / 2, L), eu.RotationMatrixZ(math.pi / 2))]
    inertia = eu.RigidBodyInertia(m, np.diag([m * 2 * a**2 / 12, m * (L**2 + a**2) / 12, m * (L**2 + a**2) / 12]))
    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.CreateGround()
    links = [mbs.CreateRigidBody(referencePosition=list(centre), referenceRotationMatrix=R, inertia=inertia,
                                 gravity=[0, -g, 0]) for centre, R in rods]
    points = [(0, 0, 0), (L, 0, 0), (L, -L, 0), (L, -L, L), (0, -L, L), (0, 0, L)]
    axes = [(0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0)]
    chain = [ground] + links
    for i in range(5):
        mbs.CreateRevoluteJoint(itemNumbers=[chain[i], chain[i + 1]], position=list(points[i]), axis=list(axes[i]),
                                useGlobalFrame=True, show=False)
    mbs.CreateGenericJoint(itemNumbers=[links[4], ground], position=list(points[5]), constrainedAxes=[1, 1, 1, 0, 1, 1],
                           useGlobalFrame=True, show=False)
    mbs.Assemble()
    return mbs, exudyn_settings(t_end, steps, dense=True), \
        lambda done: measure(np.array(done.GetObjectOutputBody(links[2], exu.OutputVariableType.Position,
                                                               localPosition=[L / 2, 0, 0])))


def mbsynth_p3(traj):
    """P3 at the trajectory's last row."""
    body, offset = BRICARD_P3
    r, R = ref.body_pose(traj.coordinates, traj.q[-1], body)
    return r + R @ np.asarray(offset)


def bricard(args, log):
    quick = args.quick
    log("Bricard")
    system = mb.load(BRICARD)
    warm(system, 0.05)
    reference = simulate(system, BRICARD_T, BRICARD_T / 20, 1e-12, args.limit, lambda traj: 0.0)
    if not reference["ok"]:
        raise RuntimeError(f"Bricard's reference run did not complete: {reference['status']}")
    p3 = mbsynth_p3(reference["trajectory"])
    log(f"    reference (rtol 1e-12): P3 = {p3}, {reference['wall']:.2f} s")

    def measure(point):
        return float(np.linalg.norm(point - p3))

    def error(traj):
        return measure(mbsynth_p3(traj))
    rtols = [1e-6, 1e-8, DEFAULT] if quick else [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, DEFAULT, 1e-11, 1e-12]
    ladder = mbsynth_ladder(system, BRICARD_T, BRICARD_T / 20, rtols, args.limit, args.repeats, error, log)
    outputs = mbsynth_ladder(system, BRICARD_T, BRICARD_T / 10000, [DEFAULT], args.limit, args.repeats, error, log)
    ratio = alternating_ratio(lambda: simulate(system, BRICARD_T, BRICARD_T / 20, DEFAULT, args.limit, error),
                              lambda: simulate(system, BRICARD_T, BRICARD_T / 10000, DEFAULT, args.limit, error),
                              RATIO_ROUNDS) if outputs[0]["ok"] else math.nan
    log(f"    10,000 outputs over 20, alternating rounds: {ratio:.2f}x")
    counts = [10000, 20000] if quick else [10000, 40000, 200000]
    exudyn_bricard(100, 0.01, measure)
    exudyn = exudyn_ladder(lambda steps: exudyn_bricard(steps, BRICARD_T, measure), counts, BRICARD_T,
                           args.limit, args.repeats, log)
    return dict(name="bricard", reference=reference, p3=p3, mbsynth=ladder, outputs=outputs[0], outputs_ratio=ratio,
                exudyn=exudyn)


# ----------------------------------------------------------------------------- small models

CART_POLE = """\
# A cart of almost no mass on a spring, carrying a pole: two coordinates, one energy-defined part.
name: cart_pole_light
parameters: {M: 0.001, m: 1.0, l: 0.5, I: 0.0833333333333333, k: 10.0, g: 9.81}
parts:
  cp:
    type: lagrangian
    coordinates: [x, theta]
    T: 0.5*(M + m)*x_dot**2 + m*l*cos(theta)*x_dot*theta_dot + 0.5*(m*l**2 + I)*theta_dot**2
    V: 0.5*k*x**2 - m*g*l*cos(theta)
initial: {cp.x: 0.0, cp.theta: 1.0}
"""
CART_POLE_PARAMETERS = dict(M=0.001, m=1.0, l=0.5, I=0.0833333333333333, k=10.0, g=9.81)
CART_POLE_T, CART_POLE_OUTPUTS = 10.0, 1000


def cart_pole_rhs(M, m, l, I, k, g):
    """f(t, (x, θ, ẋ, θ̇)) of Lagrange's equations of CART_POLE:
    (M + m) ẍ + m l cos θ θ̈ = m l sin θ θ̇² − k x,  m l cos θ ẍ + (m l² + I) θ̈ = −m g l sin θ."""
    a, d = M + m, m * l**2 + I

    def rhs(_, y):
        x, theta, xd, thetad = y
        s, c = math.sin(theta), math.cos(theta)
        b = m * l * c
        f1, f2 = m * l * s * thetad * thetad - k * x, -m * g * l * s
        det = a * d - b * b
        return (xd, thetad, (d * f1 - b * f2) / det, (a * f2 - b * f1) / det)
    return rhs


def cart_pole(args, log):
    log("cart-pole (lagrangian, near-massless cart)")
    times = np.linspace(0.0, CART_POLE_T, CART_POLE_OUTPUTS + 1)
    rhs = cart_pole_rhs(**CART_POLE_PARAMETERS)
    y0 = (0.0, 1.0, 0.0, 0.0)
    truth, _ = reference_ode(rhs, y0, CART_POLE_T, times, 1e-13)

    def hand():
        sol, wall = reference_ode(rhs, y0, CART_POLE_T, times, DEFAULT)
        return dict(wall=wall, ok=sol.success, evaluations=sol.nfev,
                    error=float(np.abs(sol.y[:2] - truth.y[:2]).max()))
    closed = best(hand, args.repeats)
    system = mb.loads(CART_POLE, name="cart_pole_light")
    warm(system, 0.1)

    def error(traj):
        return float(np.abs(np.column_stack([traj.column("cp.x"), traj.column("cp.theta")]) - truth.y[:2].T).max())
    run = mbsynth_ladder(system, CART_POLE_T, CART_POLE_T / CART_POLE_OUTPUTS, [DEFAULT], args.limit,
                         args.repeats, error, log)[0]
    log(f"    closed form: {closed['wall']:.4f} s, error {closed['error']:.1e}")
    return dict(name="cart_pole", reference=closed, mbsynth=run)


ANDREWS = ROOT / "models" / "mechanisms" / "andrews.yaml"
ANDREWS_T, ANDREWS_OUTPUTS = 0.03, 500


def andrews(args, log):
    from end_to_end import andrews_by_hand  # the test set's index-1 equations by hand (pinocchio imported there)
    log("Andrews' squeezer")
    rhs, y0, names = andrews_by_hand(ANDREWS.read_text())
    times = np.linspace(0.0, ANDREWS_T, ANDREWS_OUTPUTS + 1)

    def hand():
        sol, wall = reference_ode(rhs, y0, ANDREWS_T, times, DEFAULT)
        return dict(wall=wall, ok=sol.success, evaluations=sol.nfev,
                    error=float(np.abs(sol.y[:len(names), -1] - ref.ANDREWS_T003).max()))
    hand()  # lambdify's first calls
    by_hand = best(hand, args.repeats)
    system = mb.load(ANDREWS)
    warm(system, 0.001)
    columns = [f"sq.{c}" for c in ref.ANDREWS_COORDINATES]

    def error(traj):
        return float(np.abs(np.array([traj.column(c)[-1] for c in columns]) - ref.ANDREWS_T003).max())
    run = mbsynth_ladder(system, ANDREWS_T, ANDREWS_T / ANDREWS_OUTPUTS, [DEFAULT], args.limit, args.repeats,
                         error, log)[0]
    log(f"    by hand: {by_hand['wall']:.4f} s, error {by_hand['error']:.1e}")
    return dict(name="andrews", reference=by_hand, mbsynth=run)


# ----------------------------------------------------------------------------- the tennis racket

TENNIS = ROOT / "models" / "rigid" / "tennis_racket.yaml"
TENNIS_T = 20.0


def euler_rhs(inertia):
    """Euler's equations of a torque-free body in its principal axes: I ω̇ = (I ω) × ω."""
    inertia = np.asarray(inertia, dtype=float)

    def rhs(_, w):
        return np.cross(inertia * w, w) / inertia
    return rhs


def body_rate(u, ud):
    """ω in the body's axes from Euler parameters u = (w, x, y, z) and their rates: 2 vec(ū ⊗ u̇)."""
    w, v = u[0], u[1:]
    wd, vd = ud[0], ud[1:]
    return 2 * (w * vd - wd * v - np.cross(v, vd))


def tennis(args, log):
    log("tennis racket")
    system = mb.load(TENNIS)
    p = system.parameters
    rhs = euler_rhs([p["a"], p["b"], p["c"]])
    q0, qd0 = system.initial_state()
    w0 = body_rate(q0[3:7], qd0[3:7])
    truth, _ = reference_ode(rhs, w0, TENNIS_T, [TENNIS_T], 1e-13)
    final = truth.y[:, -1]

    def euler():
        sol, wall = reference_ode(rhs, w0, TENNIS_T, [TENNIS_T], DEFAULT)
        return dict(wall=wall, ok=sol.success, evaluations=sol.nfev, error=float(np.linalg.norm(sol.y[:, -1] - final)))
    same = best(euler, args.repeats)
    warm(system, 0.1)

    def error(traj):
        return float(np.linalg.norm(body_rate(traj.q[-1, 3:7], traj.qd[-1, 3:7]) - final))
    run = mbsynth_ladder(system, TENNIS_T, TENNIS_T / 500, [DEFAULT], args.limit, args.repeats, error, log)[0]
    log(f"    Euler's equations at 1e-10: error {same['error']:.1e}, {same['evaluations']} evaluations")
    return dict(name="tennis", w0=w0, final=final, reference=same, mbsynth=run)


# ----------------------------------------------------------------------------- the report

def seconds(entry):
    """Best wall time, with the number of runs it is the best of."""
    if entry is None or not entry.get("runs") or math.isnan(entry["wall"]):
        return "—"
    value = f"{entry['wall']:.4f}" if entry["wall"] < 1 else f"{entry['wall']:.2f}"
    return value + ("" if entry["runs"] == 1 and entry["wall"] >= LONG else f" ({entry['runs']})")


def number(value, style=".1e"):
    return "—" if value is None or (isinstance(value, float) and math.isnan(value)) else format(value, style)


def times(value):
    """A ratio as '1,234×' or '0.12×'."""
    return "—" if value is None or math.isnan(value) else f"{value:,.0f}×" if value >= 10 else f"{value:.2g}×"


def verdict(ok):
    return "**met**" if ok else "**not met**"


def mbsynth_row(problem, entry, reference=None, setting=None):
    ratio = entry["wall"] / reference if reference and entry["ok"] else math.nan
    notes = [] if entry["ok"] else [entry["status"]]
    if entry.get("relaxed"):
        notes.append(f"{entry['relaxed']} relaxed spans")
    if entry.get("not_unique"):
        notes.append(f"logs 'not unique' ({entry['not_unique']}×)")
    label = setting or f"DOP853, rtol = atol = {entry['setting']:.0e}"
    return (f"| {problem} | mbsynth | {label} | {number(entry['steps'], 'd')} steps, "
            f"{number(entry['evaluations'], 'd')} evaluations | {number(entry['error'])} | {seconds(entry)} | "
            f"{times(ratio)} | {'; '.join(notes)} |")


def exudyn_row(problem, entry, reference=None):
    ratio = entry["wall"] / reference if reference and entry["ok"] else math.nan
    counters = f"{entry['steps']} steps, {entry['newton']} Newton it., {entry['jacobians']} Jacobians" \
        if entry["steps"] is not None else "—"
    return (f"| {problem} | Exudyn | generalized-α, h = {entry['h']:.2e} s | {counters} | {number(entry['error'])} | "
            f"{seconds(entry)} | {times(ratio)} | {'' if entry['ok'] else entry['status']} |")


HEAD = ["| problem | code | setting | steps / evaluations | error | wall s (runs) | × reference | notes |",
        "|---|---|---|---|---:|---:|---:|---|"]


def four_bar_lines(res):
    N, exact = res["N"], res["exact"]
    name = f"N-four-bar N = {N}"
    lines = [f"### {name}, 20 s, outputs every 0.1 s", "",
             "*error*: the largest distance of B0 from the exact motion over the 201 outputs (m); "
             "*× reference*: wall time over the exact 1-DOF ODE's.", ""] + HEAD
    lines.append(f"| {name} | exact 1-DOF ODE | solve_ivp DOP853, rtol = atol = 1e-10 | — | {exact['error']:.1e} | "
                 f"{seconds(exact)} | 1× | the reference cost |")
    lines += [mbsynth_row(name, e, exact["wall"]) for e in res["mbsynth"]]
    lines += [exudyn_row(name, e, exact["wall"]) for e in res["exudyn"]]
    return lines + [""]


def four_bar_figures(res):
    N, exact, runs = res["N"], res["exact"], {e["setting"]: e for e in res["mbsynth"]}
    default = runs.get(DEFAULT)
    figures = []
    if N == 40 and default is not None:
        ratio = default["wall"] / exact["wall"]  # a lower bound when the run was given up
        figures.append(f"N-four-bar N = 40, default tolerance: {'' if default['ok'] else 'over '}{times(ratio)} the "
                       f"exact ODE (target ≤ 300×, goal 30×): {verdict(default['ok'] and ratio <= 300)}"
                       + ("" if default["ok"] else f" ({default['status']})"))
        figures.append(f"N-four-bar N = 40, default tolerance: B0 within {number(default['error'])} m (target ≤ 1e-6 m): "
                       f"{verdict(default['error'] <= 1e-6)}; relaxed spans {number(default['relaxed'], 'd')} "
                       f"(target 0): {verdict(default['relaxed'] == 0 and default['ok'])}")
        coarse = next((e for e in res["exudyn"] if e["ok"]), None)
        if coarse is not None:
            figures.append(f"(Exudyn, h = {coarse['h']:.0e} s: {times(coarse['wall'] / exact['wall'])} the exact ODE "
                           f"for B0 within {coarse['error']:.1e} m)")
    if N == 2 and default is not None:
        figures.append(f"N-four-bar N = 2, default tolerance: B0 within {number(default['error'])} m (target ≤ 1e-8 m): "
                       f"{verdict(default['error'] <= 1e-8)}")
        ladder = [e for e in res["mbsynth"]]
        falls = all(b["error"] < a["error"] for a, b in zip(ladder, ladder[1:]))
        steps = [b["wall"] / a["wall"] for a, b in zip(ladder, ladder[1:])]
        figures.append("N-four-bar N = 2, errors along rtol " + ", ".join(f"{e['setting']:.0e}" for e in ladder) + ": "
                       + ", ".join(number(e["error"]) for e in ladder) + f" m (target: falling): {verdict(falls)}; "
                       "time of each run over the one before: " + ", ".join(times(s) for s in steps)
                       + f" (target ≤ 3×): {verdict(all(s <= 3 for s in steps))}")
    return figures


def bricard_lines(res):
    name = "Bricard"
    default = next(e for e in res["mbsynth"] if e["setting"] == DEFAULT)
    lines = [f"### {name} (A04), 10 s", "",
             f"*error*: the distance of P3 at 10 s from mbsynth's run at rtol = atol = 1e-12 "
             f"(P3 = ({', '.join(f'{x:.12f}' for x in res['p3'])}) m); *× reference*: wall time over mbsynth's "
             "at the default tolerance with 20 outputs.", ""] + HEAD
    lines += [mbsynth_row(name, e, default["wall"], f"DOP853, rtol = atol = {e['setting']:.0e}, 20 outputs")
              for e in res["mbsynth"]]
    lines.append(mbsynth_row(name, res["outputs"], default["wall"],
                             f"DOP853, rtol = atol = {DEFAULT:.0e}, 10,000 outputs"))
    lines += [exudyn_row(name, e, default["wall"]) for e in res["exudyn"]]
    return lines + [""]


def bricard_figures(res):
    many, ratio = res["outputs"], res["outputs_ratio"]
    figures = [f"Bricard, 10,000 outputs: {ratio:.2f}× the cost of 20 outputs, best of {RATIO_ROUNDS} alternating "
               f"rounds each (target ≤ 2×): {verdict(ratio <= 2)}"]
    flagged = [e for e in res["mbsynth"] + [many] if e["not_unique"]]
    figures.append("Bricard, 'not unique' logged at " +
                   (", ".join(f"rtol {e['setting']:.0e}" for e in flagged) if flagged else "no run") +
                   " of rtol " + ", ".join(f"{e['setting']:.0e}" for e in res["mbsynth"]) +
                   f" and the 10,000-output run (target: none): {verdict(not flagged)}")
    for e in res["exudyn"]:
        if not e["ok"]:
            continue
        match = min((m for m in res["mbsynth"] if m["ok"] and m["error"] <= e["error"]), key=lambda m: m["wall"],
                    default=None)
        if match is None:
            figures.append(f"Bricard at Exudyn's h = {e['h']:.2g} s (P3 within {e['error']:.1e} m): no mbsynth run of "
                           "the ladder is as accurate")
            continue
        share = match["wall"] / e["wall"]
        figures.append(f"Bricard at Exudyn's h = {e['h']:.2g} s (P3 within {e['error']:.1e} m, {e['wall']:.3g} s): "
                       f"mbsynth at rtol {match['setting']:.0e} ({match['error']:.1e} m, {match['wall']:.3g} s) takes "
                       f"{times(share)} Exudyn's time (target ≤ 1×, goal ⅓): {verdict(share <= 1)}")
    return figures


def convergence(label, against, rows):
    """A check line: Exudyn's errors and their observed order in h (2 for generalized-α
    converging to ``against``: then both codes simulate the same system)."""
    done = [e for e in rows if e["ok"]]
    if not done:
        return []
    orders = [math.log(a["error"] / b["error"]) / math.log(a["h"] / b["h"]) for a, b in zip(done, done[1:])]
    return [f"{label}: Exudyn's error against {against} at h = " + ", ".join(f"{e['h']:.1e}" for e in done) + " s: " +
            ", ".join(f"{e['error']:.1e}" for e in done) + " m" +
            (f"; observed order in h {', '.join(f'{o:.2f}' for o in orders)} (generalized-α: 2)" if orders else "")]


def small_lines(res, name, title, reference_label, setting, error):
    lines = [f"### {title}", "", f"*error*: {error}", ""] + HEAD
    r = res["reference"]
    lines.append(f"| {name} | {reference_label} | solve_ivp DOP853, rtol = atol = 1e-10 | {r['evaluations']} evaluations | "
                 f"{r['error']:.1e} | {seconds(r)} | 1× | |")
    lines.append(mbsynth_row(name, res["mbsynth"], r["wall"], setting))
    return lines + [""]


def write(results, args, started):
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "mbsynth"], cwd=ROOT,
                           capture_output=True, text=True).stdout.strip()
    command = "MBSYNTH_COMPILED=wait .venv/bin/python benchmarks/loops.py" + "".join(f" {a}" for a in sys.argv[1:])
    lines = ["# Loops, energy-defined parts and singular positions: mbsynth, Exudyn and exact equations (issue 44)", "",
             f"{datetime.date.today()}, {platform.platform()}, {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} cores (shared), Python {platform.python_version()}, Exudyn {exu.config.Version()}, "
             f"mbsynth {getattr(mb, '__version__', '?')} at {commit}{' with uncommitted changes in mbsynth/' if dirty else ''}; "
             f"written by `{command}` (--limit {args.limit:.0f} s, --repeats {args.repeats}) in "
             f"{(time.perf_counter() - started) / 60:.1f} min.", "",
             "What each problem runs, and why the two codes simulate the same system: the docstring of "
             "benchmarks/loops.py. *wall s (runs)*: the best of that many runs of `simulate` / `SolveDynamic` / "
             "`solve_ivp` alone (model building, compilation, `Assemble` not timed; one run for a run over 30 s). "
             "Exudyn single-threaded (its default).", "", "## The issue's figures", ""]
    figures, body, checks = [], [], []
    for res in results:
        if res["name"].startswith("four_bar"):
            figures += four_bar_figures(res)
            body += four_bar_lines(res)
            checks += convergence(f"N-four-bar N = {res['N']}", "the exact motion", res["exudyn"])
            finest = min((e for e in res["mbsynth"] if e["ok"]), key=lambda e: e["error"], default=None)
            if finest is not None:
                checks.append(f"N-four-bar N = {res['N']}: mbsynth's most accurate run (rtol {finest['setting']:.0e}) "
                              f"within {finest['error']:.1e} m of the exact motion")
        elif res["name"] == "bricard":
            figures += bricard_figures(res)
            body += bricard_lines(res)
            checks += convergence("Bricard", "mbsynth's rtol 1e-12 run", res["exudyn"])
        elif res["name"] == "cart_pole":
            ratio = res["mbsynth"]["wall"] / res["reference"]["wall"]
            figures.append(f"Cart-pole (`type: lagrangian`, 2 coordinates), 10 s, 1001 outputs: {times(ratio)} its "
                           f"closed-form ODE (target ≤ 5×, goal 2×): {verdict(ratio <= 5)}")
            body += small_lines(res, "cart-pole", "Cart-pole with a near-massless cart (lagrangian), 10 s, 1001 "
                                "outputs", "closed-form ODE", "DOP853, rtol = atol = 1e-10, 1001 outputs",
                                "the largest |Δx| (m), |Δθ| (rad) over the outputs from the closed-form ODE at 1e-13.")
        elif res["name"] == "andrews":
            ratio = res["mbsynth"]["wall"] / res["reference"]["wall"]
            figures.append(f"Andrews' squeezer, 0.03 s: {times(ratio)} the hand-written index-1 equations "
                           f"(target ≤ 2×): {verdict(ratio <= 2)}")
            body += small_lines(res, "Andrews", "Andrews' squeezer (A03), 0.03 s, 501 outputs",
                                "index-1 equations by hand", "DOP853, rtol = atol = 1e-10, 501 outputs",
                                "the largest difference of the seven angles at 0.03 s from the IVP test set's "
                                "reference (rad).")
        elif res["name"] == "tennis":
            error = res["mbsynth"]["error"]
            figures.append(f"Tennis-racket flip, 20 s, default tolerance: ω within {number(error)} rad/s of Euler's "
                           f"equations (target ≤ 1e-7 rad/s): {verdict(error <= 1e-7)}; Euler's equations themselves "
                           f"at that tolerance: {res['reference']['error']:.1e} rad/s")
            body += small_lines(res, "tennis racket", "Tennis-racket flip, 20 s (ω0 = (" +
                                ", ".join(f"{w:g}" for w in res["w0"]) + ") rad/s in the body's axes)",
                                "Euler's equations", "DOP853, rtol = atol = 1e-10, 501 outputs",
                                "|ω(20 s) − ω_Euler(20 s)| in the body's axes (rad/s), ω_Euler from Euler's equations "
                                "at 1e-13 = (" + ", ".join(f"{w:.10g}" for w in res["final"]) + ").")
    lines += [f"- {f}" for f in figures] + ["", "## The runs", ""] + body
    lines += ["## Same system in both codes", ""] + [f"- {c}" for c in checks]
    text = "\n".join(lines) + "\n"
    print(text)
    if not args.quick:
        (HERE / "loops_results.md").write_text(text)


PROBLEMS = {"four_bar_2": lambda args, log: four_bar(2, args, log), "four_bar_40": lambda args, log: four_bar(40, args, log),
            "bricard": bricard, "cart_pole": cart_pole, "andrews": andrews, "tennis": tennis}
QUICK = ("four_bar_2", "bricard", "cart_pole", "andrews", "tennis")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a reduced set (no N = 40, short ladders), printed only")
    parser.add_argument("--limit", type=float, default=600.0, help="give up a run after this many seconds")
    parser.add_argument("--repeats", type=int, default=3, help="best of this many runs (one for a run over 30 s)")
    parser.add_argument("--only", default="", help="comma-separated problems: " + ", ".join(PROBLEMS))
    args = parser.parse_args()
    chosen = args.only.split(",") if args.only else list(QUICK if args.quick else PROBLEMS)
    unknown = [name for name in chosen if name not in PROBLEMS]
    if unknown:
        parser.error(f"no problem named {', '.join(unknown)}; names: {', '.join(PROBLEMS)}")
    started = time.perf_counter()
    results = []
    for name in chosen:
        results.append(PROBLEMS[name](args, lambda text: print(text, flush=True)))
    write(results, args, started)


if __name__ == "__main__":
    main()
