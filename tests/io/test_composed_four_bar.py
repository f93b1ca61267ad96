"""The bundled N-four-bar (models/mechanisms/n_four_bar.yaml: N copies of the cell file
four_bar_cell.yaml, joined by one ``for:`` joint entry) is the IFToMM A02 model written out
flat by benchmarks/iftomm_reference.n_four_bar_yaml(N), coordinate for coordinate by name,
and follows the benchmark's exact one-degree-of-freedom motion."""

import csv
import functools
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "models" / "mechanisms" / "n_four_bar.yaml"
from benchmarks import iftomm_reference as ref


@functools.cache
def composed_and_flat(N):
    """(composed System, flat System, order): ``flat`` coordinate ``order[k]`` is the
    composed one's k-th (cell i's bars v, h are the flat v{i}, h{i}; the top file's v is v{N})."""
    composed = mb.load(MODEL, parameters={"N": N})
    flat = mb.loads(ref.n_four_bar_yaml(N), name=f"n_four_bar_{N}")
    names = {f"cell[{i}].{bar}.{c}": f"{bar}{i}.{c}" for i in range(N) for bar in "vh" for c in ("x", "y", "theta")}
    names.update({f"v.{c}": f"v{N}.{c}" for c in ("x", "y", "theta")})
    assert sorted(names) == sorted(composed.coordinates) and sorted(names.values()) == sorted(flat.coordinates)
    return composed, flat, [flat.coordinates.index(names[c]) for c in composed.coordinates]


@pytest.mark.parametrize("N", [2, 10, 40])
def test_the_composed_n_four_bar_starts_as_the_flat_one(N):
    composed, flat, order = composed_and_flat(N)
    q, qd = composed.initial_state()
    qf, qdf = flat.initial_state()
    assert np.array_equal(q, qf[order]) and np.array_equal(qd, qdf[order])
    qdd, qddf = composed.motion(0.0, q, qd).qdd, flat.motion(0.0, qf, qdf).qdd
    assert np.abs(qdd - qddf[order]).max() < 1e-12
    assert len(composed.constraints) == len(flat.constraints) == 3 * N + 1  # N + 1 ground pivots, 2 N pins


@pytest.mark.parametrize("N", [2, 10])
def test_the_composed_n_four_bar_moves_as_the_flat_one(N):
    """Through the same 0.3 s at rtol = atol = 1e-10: the same state at the end to 1e-10."""
    composed, flat, order = composed_and_flat(N)
    a = mb.simulate(composed, 0.3, dt=0.1, rtol=1e-10, atol=1e-10)
    b = mb.simulate(flat, 0.3, dt=0.1, rtol=1e-10, atol=1e-10)
    assert a.status == b.status == "completed"
    assert np.abs(a.q[-1] - b.q[-1][order]).max() < 1e-10
    assert np.abs(a.qd[-1] - b.qd[-1][order]).max() < 1e-10


def test_the_composed_40_four_bar_follows_the_one_dof_reference():
    """N = 40 through its first singular (horizontal) position: B0, the top of cell 0's
    vertical bar, within 1e-7 m of the exact motion J ψ̈ = K sin ψ (as the IFToMM test of
    the flat model, tests/analysis/test_benchmark_problems.py)."""
    system, _, _ = composed_and_flat(40)
    t_end = 1.0
    crossings = ref.n_four_bar_singular_times(40, t_end)
    assert len(crossings) == 1
    traj = mb.simulate(system, t_end, dt=0.05)
    assert traj.status == "completed"
    theta = traj.column("cell[0].v.theta")
    bx, by = traj.column("cell[0].v.x") - 0.5 * np.sin(theta), traj.column("cell[0].v.y") + 0.5 * np.cos(theta)
    xr, yr = ref.n_four_bar_reference(traj.t, 40)
    assert np.max(np.hypot(bx - xr, by - yr)) < 1e-7
    assert len(traj.stats["singular_positions"]) == 1


def test_simulate_sets_the_number_of_cells(tmp_path):
    """``mbsynth simulate n_four_bar.yaml --set N=10``: N is built in at load (a fixed
    parameter), so --set loads the file again: 10 cells and the last bar's pivot at x = 10 L."""
    out = tmp_path / "run.csv"
    result = subprocess.run([sys.executable, "-m", "mbsynth.cli", "simulate", str(MODEL), "--set", "N=10",
                             "--t-end", "0.02", "--out", str(out)], capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 0 and result.stderr == "", result.stderr
    assert "model n_four_bar: simulated to t = 0.02 s (completed)" in result.stdout
    with out.open() as f:
        rows = csv.DictReader(f)
        first = next(rows)
    assert "cell[9].h.theta" in first and "cell[10].v.x" not in first
    assert float(first["v.x"]) == 10.0 and float(first["cell[9].v.x"]) == 9.0
