"""`mbsynth simulate` reports the change of T + V beyond the work of dampers and other
forces that derive from no potential as the energy drift, and that work itself; where a
model's energy changes in ways a run does not account, it says so instead of "drift"."""

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from mbsynth.analysis.trajectory import load_trajectory

MODELS = Path(__file__).resolve().parents[2] / "models"


def simulate(*args):
    return subprocess.run([sys.executable, "-m", "mbsynth.cli", "simulate", *map(str, args)],
                          capture_output=True, text=True, timeout=600)


def test_damped_cantilever_reports_its_dissipation_not_drift(tmp_path):
    """The strip's modal damping takes 14 % of its energy in 0.5 s: that is the work of
    strip, and the drift left is the integrator's (rtol 1e-10)."""
    out = tmp_path / "run.npz"
    run = simulate(MODELS / "flexible" / "cantilever.yaml", "--t-end", "0.5", "--out", out)
    assert run.returncode == 0, run.stderr
    line = re.search(r"relative energy drift (\S+) after the work of strip \((\S+) J\)", run.stdout)
    assert line, run.stdout
    drift, work = float(line[1]), float(line[2])
    saved = load_trajectory(out)
    lost = saved.energy[-1] - saved.energy[0]  # the energy balance, from the file's T + V
    assert lost < -0.1 * saved.energy[0]
    assert work == pytest.approx(lost, rel=2e-3) and drift < 1e-6


def test_json_gives_the_work_and_what_is_not_accounted(tmp_path):
    """A PD law's work is accounted (drift at the integrator's level); Coulomb friction's is
    not (its force depends on q̈): the run says "energy not conserved" and names it."""
    pd = simulate(MODELS / "joints" / "pd_pendulum.yaml", "--t-end", "0.5", "--json")
    summary = json.loads(pd.stdout)
    assert pd.returncode == 0 and summary["working_forces"] == ["hinge.actuation"]
    assert summary["unaccounted_work"] == [] and summary["energy_drift"] < 1e-6 and summary["work"] > 0.1
    friction = simulate(MODELS / "joints" / "slider_friction.yaml", "--t-end", "0.5")
    assert friction.returncode == 0
    assert "energy not conserved: the work of slide is not accounted" in friction.stdout
    assert "drift" not in friction.stdout
