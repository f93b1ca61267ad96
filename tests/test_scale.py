"""Tolerances are relative (issue 18): the same mechanism in millimetres, metres or
kilometres, with masses in grams or tonnes, completes and moves alike after rescaling time.

Lengths ×s with g fixed scale time by √s (Froude similarity); masses scale no motion. The
references use no mbsynth: the pendulum's exact motion (Jacobi's sn) and the N-four-bar's
exact one-degree-of-freedom motion (benchmarks/iftomm_reference.py).
"""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
import iftomm_reference as ref  # noqa: E402

SCALES = [(1e-3, 1.0), (1.0, 1e-3), (1.0, 1e3), (1e3, 1.0), (1e3, 1e3)]  # (length ×, mass ×)


@pytest.mark.parametrize("length, mass", SCALES)
def test_pendulum_at_any_scale(length, mass):
    system = mb.load(ROOT / "models" / "mechanisms" / "simple_pendulum.yaml").with_parameters(L=length, m=mass)
    unit = math.sqrt(length)  # the time scale √(L/g) relative to L = 1 m
    traj = mb.simulate(system, 3.0 * unit)
    assert traj.status == "completed"
    x, y = ref.pendulum_exact(traj.t / unit, 1.0, 9.81, math.pi / 2)
    error = np.hypot(traj.column("bob.x") / length - x, traj.column("bob.y") / length - y)
    assert error.max() < 1e-6
    rod = traj.column("bob.x") ** 2 + traj.column("bob.y") ** 2 - length**2
    assert np.abs(rod).max() < 1e-10 * length**2


@pytest.mark.parametrize("length, mass", [(1e-3, 1e3), (1e3, 1e-3)])
def test_n_four_bar_through_its_singular_position_at_any_scale(length, mass):
    unit = math.sqrt(length)
    system = mb.loads(ref.n_four_bar_yaml(1, L=length, m=mass, v0=unit), name="n_four_bar_1")
    traj = mb.simulate(system, 1.5 * unit)  # the first singular position is near t = 0.7 √L
    assert traj.status == "completed" and traj.stats["singular_positions"]
    theta = traj.column("v0.theta")
    bx = (traj.column("v0.x") - 0.5 * length * np.sin(theta)) / length
    by = (traj.column("v0.y") + 0.5 * length * np.cos(theta)) / length
    xr, yr = ref.n_four_bar_reference(traj.t / unit, 1)
    assert np.hypot(bx - xr, by - yr).max() < 1e-5  # of L; the benchmark asks 1e-3
