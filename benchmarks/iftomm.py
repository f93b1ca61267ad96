"""The field's benchmark problems through ``mbsynth.simulate``, against independent references (issue 18).

    PYTHONPATH=. .venv/bin/python benchmarks/iftomm.py [--quick] [--only NAME,...] [--out FILE]

Problems (models in models/mechanisms/, references in benchmarks/iftomm_reference.py,
which uses no mbsynth):

- ``pendulum`` — IFToMM/LIM A01, the simple pendulum (1 kg, 1 m, released horizontal),
  10 s: the bob against the exact solution (Jacobi's sn; González et al., Multibody
  System Dynamics 16 (2006) 179-190 for the problem).
- ``n_four_bar_2``, ``n_four_bar_40`` — A02, the N-four-bar mechanism through its
  singular (horizontal) positions, N = 2 and N = 40 (n_four_bar.yaml: N cells of
  four_bar_cell.yaml), 20 s: the point B0 against the exact
  one-degree-of-freedom motion J psi'' = K sin psi (scipy DOP853, rtol = atol = 1e-13).
- ``andrews`` — A03 and the IVP test set's ``andrews``, 0.03 s: the seven angles against
  the test set's reference (andrews.f, SOLN; Mazzia & Magherini, release 2.4). Energy
  balance with the motor's work mom (beta - beta0).
- ``bricard`` — A04, Bricard's over-constrained loop, 10 s: energy conservation and the
  loop closure measured from the bodies' coordinates (no published number was found in
  the sources searched for the benchmark's point P3 at 10 s; P3 at the end is printed).
- ``bennett`` — Bennett's spatial 4R loop under gravity, 10 s: energy and loop closure.
- ``sarrus`` — Sarrus' linkage on a spring, 5 s: energy and the plate's pure translation.
- ``pendulum_1km`` — the simple pendulum with L = 1000 m in SI units, 120 s: the bob
  against the exact solution, the rod constraint relative to L^2.
- ``flyball`` — A05, the stiff flyball governor (springs of 8e5 N/m and dampers of
  4e4 N s/m in place of its coupler rods), 10 s: the slider's height s against the
  four-coordinate Lagrange equations written by hand (the library's own time history was
  not found in the sources searched); energy against E(0) minus the dampers' work.
- ``slider_crank_3d`` — the IFToMM library's spatial rigid slider-crank, 5 s: the
  slider's x against the crank angle's one equation written by hand, and against the
  library's published solution (M. González) every 0.1 s.
- ``bicycle`` — the Whipple bicycle benchmark (Meijaard, Papadopoulos, Ruina & Schwab,
  Proc. R. Soc. A 463 (2007), models/rolling/bicycle.yaml) at 4.6 m/s, kicked to a lean
  rate of 0.005 rad/s, 10 s: the rear frame's lean against the benchmark's linearized
  equations with the matrices it prints (its eq. 5.4); and mb.linearize's eigenvalues
  against its Table 2 and its weave and capsize speeds (notes).

Columns: *reference quantity* and its *reference value* at the end of the run, the
*mbsynth value* there, *error* (the largest over all output times where the reference
is a trajectory), *energy drift* (max |E(t) - E(0)| over max(|E(0)|, max kinetic energy)),
*max residual* (mbsynth's own largest position or velocity constraint residual),
*wall s* (``simulate`` alone, model building excluded). A run that stops gets its
failure message and the values up to the last good state.

Writes benchmarks/iftomm_results.md (``--quick``: shortened runs, printed, no file
unless ``--out`` is given). With ``--only``, an existing results file keeps its other
rows and notes: the problems run replace their own rows (or are added after the others)
and a line under the header says which rows were run again, when and how.
"""

import argparse
import datetime
import math
import os
import platform
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import mbsynth as mb

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
MODELS = ROOT / "models" / "mechanisms"
sys.path.insert(0, str(HERE))
import iftomm_reference as ref  # noqa: E402


@dataclass
class Problem:
    name: str
    title: str
    build: object             # () -> System
    t_end: float
    dt: float
    quick_t_end: float
    quick_dt: float
    quantity: str
    evaluate: object          # (system, trajectory) -> (reference value str, mbsynth value str, error float, notes)
    energy: object = None     # (system, trajectory) -> drift, when the plain energy is not conserved


@dataclass
class Result:
    problem: Problem
    t_end: float
    status: str = "completed"
    reference: str = "—"
    value: str = "—"
    error: float = float("nan")
    drift: float = float("nan")
    residual: float = float("nan")
    wall: float = float("nan")
    notes: list = field(default_factory=list)
    trajectory: object = None


def _fmt(v):
    return "(" + ", ".join(f"{x:.10g}" for x in np.atleast_1d(v)) + ")"


# --- the problems ------------------------------------------------------------------------


def _pendulum_eval(system, traj):
    p = system.parameters if hasattr(system, "parameters") else {}
    L, g, theta0 = (float(p.get(k, d)) for k, d in (("L", 1.0), ("g", 9.81), ("theta0", math.pi / 2)))
    x, y = traj.column("bob.x"), traj.column("bob.y")
    xr, yr = ref.pendulum_exact(traj.t, L, g, theta0)
    err = float(np.max(np.hypot(x - xr, y - yr)))
    rod = float(np.max(np.abs(x**2 + y**2 - L**2)) / L**2)
    notes = [f"exact period {ref.pendulum_period(L, g, theta0):.12g} s", f"max |x^2 + y^2 - L^2| / L^2 = {rod:.2e}"]
    return _fmt((xr[-1], yr[-1])), _fmt((x[-1], y[-1])), err, notes


def _four_bar_eval(N):
    def evaluate(system, traj):
        x, y = traj.column("cell[0].v.x"), traj.column("cell[0].v.y")
        theta = traj.column("cell[0].v.theta")
        bx, by = x - 0.5 * np.sin(theta), y + 0.5 * np.cos(theta)   # the top of cell 0's v (frame at (0, L/2))
        xr, yr = ref.n_four_bar_reference(traj.t, N)
        err = float(np.max(np.hypot(bx - xr, by - yr)))
        singular = ref.n_four_bar_singular_times(N, float(traj.t[-1]) if traj.t.size else 0.0)
        notes = [f"{len(singular)} singular positions passed (first at t = {singular[0]:.6g} s)" if len(singular)
                 else "no singular position reached"]
        relaxed = traj.stats.get("relaxed_spans", [])
        if relaxed:
            notes.append(f"{len(relaxed)} spans near them integrated again at a looser tolerance (the default "
                         f"crawled there): rtol up to {max(e['rtol'] for e in relaxed):.0e}, "
                         f"{sum(e['t_to'] - e['t_from'] for e in relaxed):.3g} s of the run")
        return _fmt((xr[-1], yr[-1])), _fmt((bx[-1], by[-1])), err, notes
    return evaluate


def _andrews_eval(system, traj):
    values = np.array([traj.column(f"sq.{c}")[-1] for c in ref.ANDREWS_COORDINATES])
    notes = []
    if abs(traj.t[-1] - 0.03) < 1e-12:
        err = float(np.max(np.abs(values - ref.ANDREWS_T003)))
        reference = _fmt(ref.ANDREWS_T003)
    else:
        err, reference = float("nan"), "(reference at 0.03 s only)"
    return reference, _fmt(values), err, notes


def _andrews_energy(system, traj):
    beta = traj.column("sq.beta")
    E = traj.energy - ref.ANDREWS_MOM * (beta - beta[0])
    scale = max(abs(E[0]), float(np.max(np.abs(traj.kinetic))))
    return float(np.max(np.abs(E - E[0])) / scale) if scale else 0.0


def _loop_eval(joints, point=None):
    def evaluate(system, traj):
        gaps = [ref.loop_gaps(system.coordinates, q, joints) for q in traj.q]
        gap = max(g[0] for g in gaps)
        axis = max(g[1] for g in gaps)
        notes = [f"largest axis misalignment |z_A x z_B| = {axis:.2e}"]
        if point is not None and traj.q.size:
            body, offset = point
            r, R = ref.body_pose(system.coordinates, traj.q[-1], body)
            notes.append(f"point {body}+{offset} at t = {traj.t[-1]:.6g} s: {_fmt(r + R @ np.asarray(offset, float))}")
        return "0", f"{gap:.3e}", gap, notes
    return evaluate


BENNETT_JOINTS = None   # read from the model file on first use


def _bennett_joints(system):
    """The joint frames of models/mechanisms/bennett.yaml, from its parameters."""
    a, b, alpha, beta = 0.5, 0.5 * math.sin(math.pi / 3) / math.sin(math.pi / 6), math.pi / 6, math.pi / 3
    z = (0, 0, 1)
    return [
        ((None, (0, 0, 0), z), ("link1", (-a / 2, 0, 0), (0, math.sin(alpha), math.cos(alpha)))),
        (("link1", (a / 2, 0, 0), z), ("link2", (-b / 2, 0, 0), (0, math.sin(beta), math.cos(beta)))),
        (("link2", (b / 2, 0, 0), z), ("link3", (-a / 2, 0, 0), (0, math.sin(alpha), math.cos(alpha)))),
        ((None, (-b, 0, 0), (0, math.sin(beta), math.cos(beta))), ("link3", (a / 2, 0, 0), z)),
    ]


def _bennett_eval(system, traj):
    return _loop_eval(_bennett_joints(system))(system, traj)


def _sarrus_eval(system, traj):
    x, y = traj.column("top.x"), traj.column("top.y")
    qx, qy, qz = (traj.column(f"top.{c}") for c in ("qx", "qy", "qz"))
    drift = float(np.max(np.hypot(x, y)))
    turn = float(np.max(2 * np.arcsin(np.clip(np.sqrt(qx**2 + qy**2 + qz**2), 0, 1))))
    z = traj.column("top.z")
    notes = [f"plate height between {z.min():.4f} and {z.max():.4f} m", f"largest plate rotation {turn:.2e} rad"]
    return "0", f"{max(drift, turn):.3e}", max(drift, turn), notes


def _unwrapped_angle(qw, qaxis):
    """The angle of rotations about one fixed axis from their quaternions (w, axis part)."""
    return np.unwrap(2 * np.arctan2(qaxis, qw))


def _flyball_eval(system, traj):
    s = traj.column("slider.z")
    r = ref.flyball_reference(traj.t)
    qw, qz = traj.column("shaft.qw"), traj.column("shaft.qz")
    omega = 2 * (qw * traj.column("shaft.qz_dot") - qz * traj.column("shaft.qw_dot"))
    err = float(np.max(np.abs(s - r["s"])))
    notes = [f"slider between {s.min():.4f} and {s.max():.4f} m; shaft at t_end: {omega[-1]:.10g} rad/s "
             f"(reference {r['phi_dot'][-1]:.10g}), max |omega - reference| = "
             f"{np.max(np.abs(omega - r['phi_dot'])):.2e} rad/s",
             f"dampers' work by t_end {r['W'][-1]:.6g} J (reference); the library's own s(t) was not found "
             "in the sources searched: the reference is the four-coordinate equations in iftomm_reference.py"]
    return _fmt((r["s"][-1], r["phi_dot"][-1])), _fmt((s[-1], omega[-1])), err, notes


def _flyball_energy(system, traj):
    """max |E(t) - E(0) + W(t)| over max(|E(0)|, max kinetic energy), W the reference's
    dissipated work: the energy balance with the dampers."""
    W = ref.flyball_reference(traj.t)["W"]
    E = traj.energy
    scale = max(abs(E[0]), float(np.max(np.abs(traj.kinetic))))
    return float(np.max(np.abs(E - E[0] + W)) / scale) if scale else 0.0


def _slider_crank_3d_eval(system, traj):
    x = traj.column("slider.x")
    xr, theta_r = ref.slider_crank_3d_reference(traj.t)
    theta = _unwrapped_angle(traj.column("crank.qw"), traj.column("crank.qx"))
    err = float(np.max(np.abs(x - xr)))
    published = ref.SLIDER_CRANK_3D_PUBLISHED
    at = [(i, k) for k, tp in enumerate(published[:, 0])
          for i in np.flatnonzero(np.isclose(traj.t, tp, atol=1e-9))]
    notes = [f"crank angle at t_end {theta[-1]:.10g} rad (reference {theta_r[-1]:.10g}), max |theta - reference| = "
             f"{np.max(np.abs(theta - theta_r)):.2e} rad"]
    if at:
        rows, cols = map(list, zip(*at))
        notes.append(f"the library's published solution (González) at {len(at)} times to {published[cols[-1], 0]:g} s: "
                     f"mbsynth within {np.max(np.abs(x[rows] - published[cols, 1])):.2e} m of it, the reference "
                     f"equation within {np.max(np.abs(xr[rows] - published[cols, 1])):.2e} m")
    return _fmt(xr[-1]), _fmt(x[-1]), err, notes


def _bicycle_eval(system, traj):
    """The lean against the benchmark's linearized equations; in the notes, mb.linearize's
    eigenvalues against Table 2 and its weave and capsize speeds."""
    from scipy.optimize import brentq
    v, kick = system.parameters["v"], system.parameters["kick"]
    lean = traj.column("rear_frame.angle_x")
    reference = ref.whipple_linear_lean(traj.t, v, kick)
    err = float(np.max(np.abs(lean - reference)))
    bicycle = mb.load(ROOT / "models" / "rolling" / "bicycle.yaml")

    def exponents(speed):
        moving = bicycle.with_parameters(v=speed)
        values = mb.linearize(moving, 0.0, *moving.initial_state()).eigenvalues
        return np.sort_complex(values[values != 0])

    started = time.perf_counter()
    table_2 = max(float(np.abs(exponents(speed) - np.sort_complex(values)).max())
                  for speed, values in ref.WHIPPLE_TABLE_2.items())
    weave = brentq(lambda speed: exponents(speed).real.max(), 4.0, 5.0, xtol=1e-12)
    capsize = brentq(lambda speed: exponents(speed).real.max(), 5.5, 7.0, xtol=1e-12)
    spent = time.perf_counter() - started
    notes = [f"largest lean {np.max(np.abs(reference)):.3e} rad; the gap to the linear equations is the model's "
             "own nonlinearity (third order in the kick, the bicycle being symmetric left to right: it falls "
             "1000-fold when the kick falls 10-fold)",
             f"mb.linearize about upright rolling: eigenvalues at 4, 5 and 10 m/s within {table_2:.1e} of the "
             f"paper's Table 2; weave speed {weave:.12f} m/s ({abs(weave - ref.WHIPPLE_WEAVE_SPEED):.1e} off), "
             f"capsize speed {capsize:.12f} m/s ({abs(capsize - ref.WHIPPLE_CAPSIZE_SPEED):.1e} off); "
             f"{spent:.2f} s for these (brentq to 1e-12 m/s)"]
    return _fmt(reference[-1]), _fmt(lean[-1]), err, notes


def problems():
    return [
        Problem("pendulum", "A01 simple pendulum (1 m, from horizontal)",
                lambda: mb.load(MODELS / "simple_pendulum.yaml"), 10.0, 0.02, 1.0, 0.02,
                "bob (x, y) at t_end [m]; error: max over outputs", _pendulum_eval),
        Problem("n_four_bar_2", "A02 N-four-bar, N = 2",
                lambda: mb.load(MODELS / "n_four_bar.yaml"), 20.0, 0.05, 1.5, 0.05,
                "B0 (x, y) at t_end [m]; error: max over outputs", _four_bar_eval(2)),
        Problem("n_four_bar_40", "A02 N-four-bar, N = 40",
                lambda: mb.load(MODELS / "n_four_bar.yaml", parameters={"N": 40}), 20.0, 0.1, 0.8, 0.1,
                "B0 (x, y) at t_end [m]; error: max over outputs", _four_bar_eval(40)),
        Problem("andrews", "A03 / IVP test set: Andrews' squeezer",
                lambda: mb.load(MODELS / "andrews.yaml"), 0.03, 0.001, 0.03, 0.003,
                "(beta, theta, gamma, phi, delta, omega, epsilon) at 0.03 s [rad]; error: max abs",
                _andrews_eval, _andrews_energy),
        Problem("bricard", "A04 Bricard's mechanism",
                lambda: mb.load(MODELS / "bricard.yaml"), 10.0, 0.05, 0.5, 0.05,
                "loop gap: max joint point distance over outputs [m]",
                _loop_eval(ref.BRICARD_JOINTS, point=("link3", (0, 0, 0.5)))),
        Problem("bennett", "Bennett's linkage under gravity",
                lambda: mb.load(MODELS / "bennett.yaml"), 10.0, 0.05, 0.5, 0.05,
                "loop gap: max joint point distance over outputs [m]", _bennett_eval),
        Problem("sarrus", "Sarrus' linkage on a spring",
                lambda: mb.load(MODELS / "sarrus.yaml"), 5.0, 0.05, 0.5, 0.05,
                "plate: max horizontal drift [m] / rotation [rad]", _sarrus_eval),
        Problem("pendulum_1km", "simple pendulum, L = 1000 m (SI)",
                lambda: mb.load(MODELS / "pendulum_1km.yaml"), 120.0, 1.0, 10.0, 1.0,
                "bob (x, y) at t_end [m]; error: max over outputs", _pendulum_eval),
        Problem("flyball", "A05 stiff flyball governor",
                lambda: mb.load(MODELS / "flyball_governor.yaml"), 10.0, 0.05, 1.0, 0.05,
                "(slider height s [m], shaft rate [rad/s]) at t_end; error: s, max over outputs",
                _flyball_eval, _flyball_energy),
        Problem("slider_crank_3d", "IFToMM spatial rigid slider-crank",
                lambda: mb.load(MODELS / "slider_crank_3d.yaml"), 5.0, 0.01, 0.5, 0.01,
                "slider x at t_end [m]; error: max over outputs (the published solution: notes)",
                _slider_crank_3d_eval),
        Problem("bicycle", "Whipple bicycle benchmark, 4.6 m/s, lean kick 0.005 rad/s",
                lambda: mb.load(ROOT / "models" / "rolling" / "bicycle.yaml").with_parameters(v=4.6, kick=0.005),
                10.0, 0.05, 1.0, 0.05,
                "lean at t_end [rad] against the benchmark's linearized equations; error: max over outputs",
                _bicycle_eval),
    ]


# --- running -----------------------------------------------------------------------------


def run(problem, quick=False, log=print):
    t_end = problem.quick_t_end if quick else problem.t_end
    dt = problem.quick_dt if quick else problem.dt
    result = Result(problem, t_end)
    try:
        system = problem.build()
    except Exception as err:   # a model that does not load is a result too
        result.status = f"model failed to load: {type(err).__name__}: {err}"
        return result
    started = time.perf_counter()
    traj = None
    try:
        traj = mb.simulate(system, t_end, dt=dt)
    except mb.SimulationError as err:
        result.status = f"stopped: {err}"
        traj = err.trajectory
    except mb.SolveError as err:   # e.g. no consistent initial state
        result.status = f"failed: SolveError: {err}"
    except Exception as err:
        result.status = f"failed: {type(err).__name__}: {err}"
        log(traceback.format_exc())
    result.wall = traj.stats.get("wall_time", time.perf_counter() - started) if traj is not None else \
        time.perf_counter() - started
    if traj is None or traj.t.size == 0:
        return result
    result.trajectory = traj
    if result.status != "completed":
        result.notes.append(f"last good state at t = {traj.t[-1]:.9g} s")
    try:
        result.reference, result.value, result.error, notes = problem.evaluate(system, traj)
        result.notes.extend(notes)
        result.drift = problem.energy(system, traj) if problem.energy else traj.energy_drift
        result.residual = traj.max_residual
    except Exception as err:
        result.notes.append(f"evaluation failed: {type(err).__name__}: {err}")
    return result


def table(results):
    lines = ["| problem | t_end s | reference quantity | reference value | mbsynth value | error | energy drift "
             "| max residual | wall s | status |",
             "|---|---:|---|---|---|---:|---:|---:|---:|---|"]
    for r in results:
        status = r.status.replace("|", "/").replace("\n", " ")
        lines.append(f"| {r.problem.title} | {r.t_end:g} | {r.problem.quantity} | {r.reference} | {r.value} | "
                     f"{r.error:.2e} | {r.drift:.2e} | {r.residual:.2e} | {r.wall:.3g} | {status} |")
    notes = [f"- {r.problem.title}: " + "; ".join(r.notes) for r in results if r.notes]
    return "\n".join(lines) + ("\n\nNotes:\n\n" + "\n".join(notes) if notes else "") + "\n"


TITLE = "# mbsynth on the IFToMM/LIM benchmark problems and the IVP test set's `andrews` (issue 18)"
REFERENCES = ("References (benchmarks/iftomm_reference.py, no mbsynth inside): the pendulum's exact motion (Jacobi's "
              "sn), the N-four-bar's exact one-degree-of-freedom motion (scipy DOP853 at 1e-13), the IVP test set's "
              "Andrews angles at 0.03 s (andrews.f, SOLN), for the over-constrained loops energy conservation "
              "and the joints' gaps computed from the bodies' coordinates, for the flyball governor its "
              "four-coordinate Lagrange equations written by hand (scipy DOP853 at 1e-12; the library's own s(t) "
              "was not found), and for the spatial slider-crank its crank angle's equation written by hand (DOP853 "
              "at 1e-13) beside the library's published solution (M. González; the IFToMM benchmark's "
              "Spatial_rigid_slider-crank_mechanism_Gonzalez.txt as copied in jgerstmayr/EXUDYN "
              "docs/verification/Slidercrank3DiftommBenchmark/), and for the Whipple bicycle the linearized "
              "equations with the matrices its benchmark paper prints (Meijaard et al. 2007, eq. 5.4; DOP853 at "
              "1e-13) and that paper's Table 2 and self-stable speeds. `simulate` with its defaults (DOP853, "
              "rtol = atol = 1e-10, projection at each output time); *error* is the largest over all output times "
              "where the reference is a trajectory; *energy drift* relative to max(|E(0)|, max kinetic energy) "
              "(Andrews: with the motor's work subtracted); *max residual*: mbsynth's own largest constraint "
              "residual; *wall s*: `simulate` alone; the flyball governor's energy drift is E(t) - E(0) plus the "
              "dampers' work.")


def run_line(argv, what="written by"):
    """Date, machine, versions and the command that ran (``what`` it did)."""
    quick = " " + " ".join(argv) if argv else ""
    return (f"{datetime.date.today().isoformat()}, {platform.platform()}, {platform.machine()}, {os.cpu_count()} "
            f"cores, Python {platform.python_version()}, mbsynth {getattr(mb, '__version__', '?')}; {what} "
            f"`PYTHONPATH=. .venv/bin/python benchmarks/iftomm.py{quick}`.")


def header(argv):
    return f"{TITLE}\n\n{run_line(argv)}\n\n{REFERENCES}\n\n"


def _table_parts(text):
    """(the text before the table, its rows keyed by problem title, the notes lines)."""
    head, mark, rest = text.partition("| problem |")
    lines = (mark + rest).splitlines()
    rows = {}
    for line in lines[2:]:
        if not line.startswith("| "):
            break
        rows[line[2:].split(" | ")[0]] = line
    notes = [line for line in lines if line.startswith("- ")]
    return head, rows, notes


def merge(old, results, argv):
    """The results file text ``old`` with the rows and notes of ``results`` in place of
    their own (added after the others when new), its run lines kept and a line added saying
    which rows were run again, when and how (replacing earlier such lines of no other
    rows); the title and references as they are now."""
    head, rows, notes = _table_parts(old)
    if not rows:
        return header(argv) + table(results)
    _, new_rows, new_notes = _table_parts(table(results))
    rows.update(new_rows)                      # replaced in place, new ones last
    paragraphs = head.strip().split("\n\n")

    def superseded(line):          # an earlier rerun of no rows but these
        rerun = line.partition("; rows ")[2].partition(" run again by")[0]
        return bool(rerun) and set(rerun.split("; ")) <= set(new_rows)
    runs = "\n".join(line for line in (paragraphs[1] if len(paragraphs) > 1 else "").splitlines()
                     if not superseded(line))
    again = run_line(argv, f"rows {'; '.join(new_rows)} run again by")

    def note_of(title, pool):
        return next((n for n in pool if n.startswith(f"- {title}: ")), None)
    merged_notes = [note_of(t, new_notes) if t in new_rows else note_of(t, notes) for t in rows]
    merged_notes = [n for n in merged_notes if n]
    lines = table([]).splitlines()[:2] + list(rows.values())
    return (f"{TITLE}\n\n{runs}\n{again}\n\n{REFERENCES}\n\n" + "\n".join(lines)
            + ("\n\nNotes:\n\n" + "\n".join(merged_notes) if merged_notes else "") + "\n")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="shortened runs; print, no file unless --out")
    parser.add_argument("--only", default="", help="comma-separated problem names (default: all)")
    parser.add_argument("--out", default=None, help="the results file (default benchmarks/iftomm_results.md)")
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser.parse_args(argv)
    chosen = [p for p in problems() if not args.only or p.name in args.only.split(",")]
    if not chosen:
        parser.error(f"no problem named {args.only!r}; names: {', '.join(p.name for p in problems())}")
    results = []
    for problem in chosen:
        print(f"{problem.name} ...", flush=True)
        r = run(problem, quick=args.quick)
        print(f"  {r.status[:300]}; error {r.error:.2e}, drift {r.drift:.2e}, residual {r.residual:.2e}, "
              f"{r.wall:.3g} s", flush=True)
        results.append(r)
    shown = [a for i, a in enumerate(argv) if a != "--out" and (i == 0 or argv[i - 1] != "--out")]
    text = header(shown) + table(results)
    print(text)
    out = args.out or (None if args.quick else HERE / "iftomm_results.md")
    if out is not None:
        out = Path(out)
        out.write_text(merge(out.read_text(), results, shown) if args.only and out.exists() else text)
    return results


if __name__ == "__main__":
    main()
