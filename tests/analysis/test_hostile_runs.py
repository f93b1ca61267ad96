"""Runs that cannot go on stop with a SimulationError saying when and where, the last good
state saved (a state that blows up, a step-size collapse, a state beyond MAX_STATE); output
files are written atomically: a failing writer or a killed run never leaves half a file
under the final name. (A NaN state and Ctrl-C are in test_simulate.py.)"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipj, ellipk

import mbsynth as mb
from mbsynth.analysis import trajectory
from mbsynth.core.tolerances import MAX_STATE
from mbsynth.analysis.simulate import simulate
from mbsynth.analysis.trajectory import Trajectory, TrajectoryWriter, load_trajectory, output_file


def one_coordinate(force, x0=0.0):
    return mb.loads(f"parts:\n  p: {{type: lagrangian, coordinates: [x], T: 0.5*x_dot**2, "
                    f"forces: {{x: '{force}'}}}}\ninitial: {{p.x: {x0}}}\n")


def stop(system, t_end, out, dt):
    with pytest.raises(mb.SimulationError) as err:
        simulate(system, t_end, out=out, dt=dt)
    saved = load_trajectory(output_file(out, completed=False))  # a CSV's rows stay in FILE.partial
    np.testing.assert_array_equal(saved.t, err.value.trajectory.t)
    np.testing.assert_array_equal(saved.q, err.value.trajectory.q)
    return err.value, saved


def test_a_state_that_blows_up_in_finite_time(tmp_path):
    """ẍ = x³, x(0) = 1, ẋ(0) = 0: x = 1/cn(t | m = ½), infinite at t* = K(½) = 1.854...
    The run stops just before t*, names p.x, and the saved rows follow the exact solution."""
    error, saved = stop(one_coordinate("x**3", 1.0), 3.0, tmp_path / "run.npz", 0.05)
    assert error.time == pytest.approx(ellipk(0.5), abs=1e-6) and error.coordinates == ("p.x",)
    assert f"t = {error.time:.9g}" in str(error) and "p.x" in str(error) and "step-size collapse" in str(error)
    assert saved.t[-1] == pytest.approx(1.85) and "failed" in saved.status
    np.testing.assert_allclose(saved.q[:, 0], 1 / ellipj(saved.t, 0.5)[1], rtol=1e-8)


def test_a_step_size_collapse_at_a_singular_force(tmp_path):
    """ẍ = 1/(1 − t)³ from rest: x = ½ (1/(1 − t) − 1 − t), singular at t = 1. The rows
    within the run's tolerances (rtol = atol = 1e-10 per step) of the exact x."""
    error, saved = stop(one_coordinate("1/(1 - t)**3"), 2.0, tmp_path / "run.csv", 0.01)
    assert 0.99 < error.time <= 1.0 and error.coordinates == ("p.x",)
    assert "step-size collapse" in str(error) and "last good state saved at t = 0.99" in str(error)
    assert saved.t[-1] == pytest.approx(0.99)
    np.testing.assert_allclose(saved.q[:, 0], 0.5 * (1 / (1 - saved.t) - 1 - saved.t), rtol=1e-8, atol=1e-10)


def test_a_state_beyond_max_state_stops_at_the_first_output_past_it(tmp_path):
    """ẍ = 1e11: x = 5e10 t² passes MAX_STATE = 1e12 at t = 4.47 (ẋ = 1e11 t only at
    t = 10); outputs every second."""
    error, saved = stop(one_coordinate("1e11"), 20.0, tmp_path / "run.npz", 1.0)
    assert MAX_STATE == 1e12 and error.time == pytest.approx(5.0) and error.coordinates == ("p.x",)
    assert "exploded" in str(error)
    np.testing.assert_allclose(saved.q[:, 0], 5e10 * saved.t**2, rtol=1e-9)
    assert saved.t[-1] == pytest.approx(4.0)


def chunk(t, x):
    return Trajectory(("p.x",), np.array([t]), np.array([[x]]), np.array([[0.0]]), np.array([0.0]),
                      np.array([0.0]), np.array([0.0]), np.array([0.0]))


def test_a_failing_npz_writer_leaves_the_last_complete_checkpoint(tmp_path, monkeypatch):
    """np.savez writes half its file, then fails (a full disk): the file under the final
    name is still the complete checkpoint before, and no temporary file is left."""
    out = tmp_path / "run.npz"
    writer = TrajectoryWriter(out, ("p.x",), checkpoint_seconds=0)
    writer.append(chunk(0.0, 1.0))
    real = trajectory.np.savez

    def half_then_fail(path, **arrays):
        real(path, **arrays)
        with open(path, "r+b") as f:
            f.truncate(os.path.getsize(path) // 2)
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(trajectory.np, "savez", half_then_fail)
    with pytest.raises(OSError):
        writer.append(chunk(0.1, 2.0))
    saved = load_trajectory(out)
    assert saved.t.tolist() == [0.0] and saved.q.tolist() == [[1.0]]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.npz"]


class _FailingFile:
    """A text file whose writes fail half-way from the ``fail_at``-th one on."""

    def __init__(self, file, fail_at):
        self.file, self.fail_at, self.writes = file, fail_at, 0

    def write(self, text):
        self.writes += 1
        if self.writes >= self.fail_at:
            self.file.write(text[:len(text) // 2])
            self.file.flush()
            raise OSError(28, "No space left on device")
        return self.file.write(text)

    def __getattr__(self, name):
        return getattr(self.file, name)


def test_a_csv_row_cut_short_by_a_failed_write_is_not_kept(tmp_path):
    out = tmp_path / "run.csv"
    writer = TrajectoryWriter(out, ("p.x",))
    writer.append(chunk(0.0, 1.0))
    writer._csv_file = _FailingFile(writer._csv_file, fail_at=1)
    writer._csv = trajectory.csv.writer(writer._csv_file)
    with pytest.raises(OSError):
        writer.append(chunk(0.1, 2.0))
    writer.close()
    partial = tmp_path / "run.csv.partial"  # the run did not complete
    saved = load_trajectory(partial)
    assert saved.t.tolist() == [0.0] and saved.q.tolist() == [[1.0]]
    assert partial.read_text().endswith("\n") and not out.exists()


RUNNER = """\
import sys
import mbsynth as mb
from mbsynth.analysis.simulate import simulate
system = mb.loads("parts:\\n  p: {type: lagrangian, coordinates: [x], T: 0.5*x_dot**2, V: 0.5*x**2}\\n"
                  "initial: {p.x: 1}\\n")
simulate(system, 1e3, dt=1e-3, out=sys.argv[1])
"""


@pytest.mark.parametrize("suffix", [".npz", ".csv"])
def test_a_killed_run_never_leaves_half_a_file_under_the_final_name(tmp_path, suffix):
    """SIGKILL in the middle of a long run (after an NPZ checkpoint or some CSV rows): the
    final name holds a complete trajectory (NPZ) or is absent, the rows kept in FILE.partial
    (CSV); the rows kept follow x = cos t."""
    out = tmp_path / f"run{suffix}"
    written = out if suffix == ".npz" else tmp_path / "run.csv.partial"
    process = subprocess.Popen([sys.executable, "-c", RUNNER, str(out)])
    try:
        deadline = time.monotonic() + 60
        first = None
        while time.monotonic() < deadline:
            stamp = written.stat().st_mtime_ns if written.exists() else None
            first = first or stamp
            if stamp and stamp != first and written.stat().st_size > 200:  # rewritten at least once
                break
            time.sleep(0.05)
        process.send_signal(signal.SIGKILL)
    finally:
        process.wait()
    assert process.returncode == -signal.SIGKILL
    if suffix == ".npz":
        saved = load_trajectory(out)
        assert saved.t.size > 1 and "running" in saved.status
    else:
        assert not out.exists()
        lines = written.read_text().splitlines()
        complete = [line for line in lines[1:] if line.count(",") == lines[0].count(",")][:-1]
        data = np.array([[float(x) for x in line.split(",")] for line in complete])
        saved = Trajectory(("p.x",), data[:, 0], data[:, 1:2], data[:, 2:3], data[:, 3], *[data[:, 3]] * 3)
    assert saved.t.size > 1
    np.testing.assert_allclose(saved.q[:, 0], np.cos(saved.t), atol=1e-8)


def test_output_that_cannot_fit_in_memory_is_refused_before_the_run(tmp_path):
    """10¹² + 1 rows of a 1-coordinate model, 8 bytes × (2·1 + 7) each (t, q, q̇, energies,
    power, residuals and the output time): 72 TB, refused before anything is written."""
    system = mb.loads("parts:\n  p: {type: lagrangian, coordinates: [x], T: 0.5*x_dot**2, V: 0.5*x**2}\n")
    out = tmp_path / "big.npz"
    with pytest.raises(mb.ModelError, match=r"1,000,000,000,001 output rows would take 72 TB") as caught:
        simulate(system, 1e6, dt=1e-6, out=out)
    assert f"nothing was written to {out}" in str(caught.value) and list(tmp_path.iterdir()) == []


def test_the_command_line_refuses_output_that_cannot_fit_with_exit_2(tmp_path):
    out = tmp_path / "big.npz"
    done = subprocess.run([sys.executable, "-m", "mbsynth", "simulate", "models/mechanisms/simple_pendulum.yaml",
                           "--t-end", "1e6", "--dt", "1e-6", "--out", str(out)], capture_output=True, text=True,
                          timeout=300, cwd=Path(__file__).parents[2])
    assert done.returncode == 2 and "output rows would take" in done.stderr and not out.exists()


def test_a_row_is_bounded_when_every_entry_is_within_max_state():
    """continuous._bounded per row, against the entries themselves: a row with one entry
    beyond MAX_STATE (either sign), a NaN or an infinity anywhere is not bounded."""
    from mbsynth.analysis.continuous import _bounded
    states = np.random.default_rng(2).uniform(-1.0, 1.0, (4, 11)) * MAX_STATE
    states[1, 7] = -1.5 * MAX_STATE
    states[2, 0] = np.nan
    states[3, 10] = np.inf
    assert _bounded(states).tolist() == [True, False, False, False]
    assert _bounded(np.full((1, 5), MAX_STATE)).tolist() == [True]
