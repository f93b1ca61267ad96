"""The command line on a model with contacts: ``mbsynth simulate``'s summary counts the
run's events, and the .npz it writes keeps them; ``mbsynth check`` lists the gaps and the
ones touching at the initial state."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from mbsynth.analysis.trajectory import load_trajectory
from mbsynth.core.tolerances import INTEGRATION_ATOL, REST_HOP

BALL = Path(__file__).resolve().parents[2] / "models" / "contact" / "bouncing_ball.yaml"


def test_the_bouncing_ball_counts_its_impacts_to_rest(tmp_path):
    out = tmp_path / "ball.npz"
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "simulate", str(BALL), "--t-end", "2", "--json",
                           "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    # rebounds at e^j v1 (v1 = √(2 g (h0 − r))) while the hop they make is above REST_HOP atol,
    # then one impact that brings it to rest
    g, e, v1 = 9.81, 0.5, np.sqrt(2 * 9.81 * (1.0 - 0.05))
    rebounds = int(np.floor(np.log(np.sqrt(2 * g * REST_HOP * INTEGRATION_ATOL) / v1) / np.log(e)))
    assert summary["events"] == {"impact": rebounds + 1, "contact": 1, "release": 0}
    kinds = [ev.kind for ev in load_trajectory(out).events]
    assert kinds == ["impact"] * (rebounds + 1) + ["contact"]
    text = subprocess.run([sys.executable, "-m", "mbsynth.cli", "simulate", str(BALL), "--t-end", "2"],
                          capture_output=True, text=True, timeout=300).stdout
    assert f"events: {rebounds + 1} impacts, 1 contact, 0 releases" in text


def test_check_lists_the_gaps_and_those_touching(tmp_path):
    path = tmp_path / "resting.yaml"
    path.write_text(BALL.read_text().replace("position: [0, 0, h0]", "position: [0, 0, r]"))
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(path)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert "limits and contacts (gap, e): floor 0 (e = 0.5)" in done.stdout
    assert "touching at the initial state: floor" in done.stdout
    report = json.loads(subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(BALL), "--json"],
                                       capture_output=True, text=True, timeout=300).stdout)
    assert report["gaps"] == {"floor": {"kind": "contact", "gap": 0.95, "rate": 0.0, "restitution": 0.5}}
