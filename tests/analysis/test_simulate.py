"""Motion over time against exact solutions and conservation laws; drift control;
consistent initial states; output that survives interruptions and failures."""

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.core.kinematics import quaternion_matrix
from mbsynth.analysis.projection import consistent_initial_state
from mbsynth.analysis.simulate import simulate
from mbsynth.analysis.trajectory import load_trajectory

ROOT = Path(__file__).resolve().parents[2]
PAPER = ROOT / "models" / "paper"
RIGID = ROOT / "models" / "rigid"


def modal_solution(M, K, u0, v0, t):
    """u(t) of M ü + K u = 0 from the generalized eigenproblem K φ = ω² M φ."""
    w2, phi = scipy.linalg.eigh(K, M)
    w = np.sqrt(w2)
    a, b = phi.T @ M @ u0, phi.T @ M @ v0  # modal coordinates (φᵀMφ = I)
    return (phi @ (a[:, None] * np.cos(np.outer(w, t)) + (b / w)[:, None] * np.sin(np.outer(w, t)))).T


def test_example3_matches_the_exact_modal_solution_over_10_s():
    """Case 5.1 in mass coordinates u1 = x̄1, u2 = x̄1 + q̄2 (the displacement of m2):
    m1 ü1 = −k1 u1 + k2 (u2 − u1), m2 ü2 = −k2 (u2 − u1)."""
    system = mb.load(PAPER / "example3_two_masses.yaml")
    p = system.parameters
    traj = simulate(system, 10.0)
    x1bar = traj.q[:, 0] - p["l10"]
    u = np.column_stack([x1bar, x1bar + traj.q[:, 2] - p["l20"]])
    M = np.diag([p["m1"], p["m2"]])
    K = np.array([[p["k1"] + p["k2"], -p["k2"]], [-p["k2"], p["k2"]]])
    v0 = np.array([traj.qd[0, 0], traj.qd[0, 0] + traj.qd[0, 2]])
    exact = modal_solution(M, K, u[0], v0, traj.t)
    assert np.abs(u - exact).max() < 1e-8
    np.testing.assert_allclose(traj.q[:, 1] - traj.q[:, 0], p["d"], atol=1e-12)  # the connection (5.32)


def test_massless_node_closed_by_auto_balance_equals_series_spring():
    """Case 5.2 (m1 = 0, balances: auto): m2 oscillates on k1 k2/(k1 + k2) (springs in series)."""
    system = mb.load(PAPER / "example3_m1_zero_auto.yaml")
    p = system.parameters
    traj = simulate(system, 5.0)
    u = traj.q[:, 0] - p["l10"] + traj.q[:, 2] - p["l20"]  # displacement of m2 from rest
    v = traj.qd[:, 0] + traj.qd[:, 2]
    w = np.sqrt(p["k1"] * p["k2"] / (p["k1"] + p["k2"]) / p["m2"])
    exact = u[0] * np.cos(w * traj.t) + v[0] / w * np.sin(w * traj.t)
    assert np.abs(u - exact).max() < 1e-8
    assert traj.max_residual < 1e-10  # the balance (5.40) holds along the motion


def test_spatial_double_pendulum_conserves_energy_and_constraints_for_20_s():
    system = mb.load(RIGID / "double_pendulum_spatial.yaml")
    traj = simulate(system, 20.0)
    assert traj.status == "completed"
    assert traj.energy_drift < 1e-6
    assert traj.max_residual < 1e-8
    assert np.ptp(traj.column("link2.y")) > 0.1  # it really leaves the x-z plane
    assert set(traj.stats["initial_changes"]) == {"link1.x_dot", "link2.x_dot", "link2.y_dot"}


def angular_momentum(traj, J):
    """World angular momentum R(u) J ω_body at every output time (ω_body = 2 E(u) u̇)."""
    out = []
    for u, ud in zip(traj.q[:, 3:], traj.qd[:, 3:]):
        w, x, y, z = u
        E = np.array([[-x, w, z, -y], [-y, -z, w, x], [-z, y, -x, w]])
        out.append(quaternion_matrix(u) @ J @ (2 * E @ ud))
    return np.array(out)


def test_tennis_racket_flips_and_keeps_energy_and_angular_momentum():
    system = mb.load(RIGID / "tennis_racket.yaml")
    traj = simulate(system, 20.0)
    p = system.parameters
    L = angular_momentum(traj, np.diag([p["a"], p["b"], p["c"]]))
    assert np.abs(L - L[0]).max() < 1e-8 * np.linalg.norm(L[0])
    assert traj.energy_drift < 1e-8
    body_y_world = np.array([quaternion_matrix(u)[:, 1] for u in traj.q[:, 3:]])
    assert body_y_world[:, 1].min() < -0.9  # the intermediate axis turned over (Dzhanibekov)


def test_rolling_disk_keeps_rolling_steadily_for_20_s():
    """Steady circular rolling (models/rolling/rolling_disk.yaml): rolling without slip
    is ideal, so the energy stays; the lean, hence the centre's height, stays constant."""
    traj = simulate(mb.load(ROOT / "models" / "rolling" / "rolling_disk.yaml"), 20.0)
    assert traj.energy_drift < 1e-8 and traj.max_residual < 1e-8
    assert np.ptp(traj.column("disk.z")) < 1e-8
    assert np.ptp(traj.column("disk.x")) > 0.05  # it does go round


def test_baumgarte_keeps_drift_small_without_projection():
    system = mb.load(RIGID / "double_pendulum_spatial.yaml")
    q, qd, _ = consistent_initial_state(system)
    loose = dict(q0=q, qd0=qd, rtol=1e-5, atol=1e-5, dt=0.5)  # a coarse run, so that drift shows
    free = simulate(system, 20.0, stabilization="none", **loose)
    held = simulate(system, 20.0, stabilization="baumgarte", **loose)
    assert free.max_residual > 1e-5
    assert held.max_residual < free.max_residual / 10


PENDULUM = """\
parameters: {m: 1.0, L: 2.0, g: 9.81}
parts:
  bob: {type: lagrangian, coordinates: [x, y], T: 0.5*m*(x_dot**2 + y_dot**2), V: m*g*y}
constraints:
  - {name: rod, holonomic: bob.x**2 + bob.y**2 - L**2}
"""


def test_partial_initial_state_is_completed_keeping_what_the_model_sets():
    system = mb.loads(PENDULUM + "initial: {bob.x: 1.2, bob.y: -1.6, bob.y_dot: 0.6}\n")
    q, qd, changes = consistent_initial_state(system)
    np.testing.assert_allclose([q[0], q[1], qd[1]], [1.2, -1.6, 0.6], atol=0)  # set by the model
    np.testing.assert_allclose(qd[0], 0.8, atol=1e-12)  # x ẋ + y ẏ = 0
    assert set(changes) == {"bob.x_dot"}


def test_a_state_slightly_off_moves_all_but_the_fixed_values():
    system = mb.loads(PENDULUM + "initial: {bob.x: 1.2, bob.y: -1.5, bob.y_dot: 0.6}\n"
                                 "initial_fixed: [bob.x, bob.y_dot]\n")
    q, qd, changes = consistent_initial_state(system)
    np.testing.assert_allclose(q, [1.2, -1.6], atol=1e-12)  # on the circle, nearest the given y
    np.testing.assert_allclose(qd, [0.8, 0.6], atol=1e-12)
    assert set(changes) == {"bob.y", "bob.x_dot"}


def test_impossible_initial_state_is_refused():
    system = mb.loads(PENDULUM + "initial: {bob.x: 3.0}\ninitial_fixed: [bob.x]\n")  # |x| > L
    with pytest.raises(mb.SolveError, match="no consistent initial state exists .keeping bob.x.*rod"):
        consistent_initial_state(system)


@pytest.mark.parametrize("suffix", [".npz", ".csv"])
def test_interrupted_run_keeps_a_readable_partial_output(tmp_path, suffix):
    system = mb.load(PAPER / "example3_two_masses.yaml")
    out = tmp_path / f"run{suffix}"

    def interrupt(t):
        if t > 5.0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        simulate(system, 10.0, out=out, progress=interrupt)
    kept = out if suffix == ".npz" else tmp_path / "run.csv.partial"  # a CSV keeps its final name for complete runs
    assert sorted(tmp_path.iterdir()) == [kept]
    saved = load_trajectory(kept)
    assert 5.0 < saved.t[-1] < 5.1 and saved.q.shape == (saved.t.size, 3)
    full = simulate(system, 10.0)
    np.testing.assert_allclose(saved.q, full.q[:saved.t.size], atol=1e-12)
    if suffix == ".npz":
        assert saved.status.startswith("interrupted at t = 5.")


def test_a_failed_csv_run_leaves_no_file_under_the_final_name(tmp_path):
    """The README: the final name holds a complete file or nothing. A run that fails (a
    force NaN after t = 1) over an earlier complete run.csv: its rows are in run.csv.partial
    and the earlier run's file is gone (it is not this run's output)."""
    out = tmp_path / "run.csv"
    out.write_text("t,p.x,p.x_dot,energy\n0.0,0.0,0.0,0.0\n")
    system = mb.loads("parts:\n  p: {type: lagrangian, coordinates: [x], T: 0.5*x_dot**2, "
                      "forces: {x: sqrt(1 - t)}}\n")
    with pytest.raises(mb.SimulationError):
        simulate(system, 2.0, out=out, dt=0.01)
    assert not out.exists()
    saved = load_trajectory(tmp_path / "run.csv.partial")
    assert saved.t[-1] == pytest.approx(1.0) and saved.q[-1, 0] == pytest.approx(0.4, rel=1e-8)
    simulate(system, 0.5, out=out, dt=0.01)
    assert sorted(tmp_path.iterdir()) == [out] and load_trajectory(out).t[-1] == 0.5


def test_a_state_that_becomes_nan_stops_with_the_last_good_state_saved(tmp_path):
    """A force sqrt(1 − t) is NaN after t = 1: the run stops there, saying when and where."""
    system = mb.loads("parts:\n  p: {type: lagrangian, coordinates: [x], T: 0.5*x_dot**2, "
                      "forces: {x: sqrt(1 - t)}}\n")
    out = tmp_path / "run.npz"
    with pytest.raises(mb.SimulationError) as err:
        simulate(system, 2.0, out=out, dt=0.01)
    assert 1.0 <= err.value.time <= 1.02 and "p.x" in str(err.value)
    saved = load_trajectory(out)
    assert saved.t[-1] == pytest.approx(1.0) and "failed" in saved.status
    np.testing.assert_allclose(saved.q[-1, 0], 0.4, rtol=1e-8)  # x(1) = 2/3 − 4/15 (twice ∫ sqrt(1 − s))


def test_cli_simulate_writes_files_and_a_json_summary(tmp_path, capsys):
    out, plot = tmp_path / "e3.npz", tmp_path / "e3.png"
    code = main(["simulate", str(PAPER / "example3_two_masses.yaml"), "--t-end", "2", "--out", str(out),
                 "--plot", str(plot), "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert code == 0 and summary["status"] == "completed" and summary["max_residual"] < 1e-12
    with np.load(out) as data:
        assert list(data["coordinates"]) == ["body1.x1", "body2.q1", "body2.q2"]
        assert data["q"].shape == (501, 3) and data["t"][-1] == 2.0
    assert plot.stat().st_size > 10_000
