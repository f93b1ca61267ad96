"""``mbsynth simulate`` of a model with contacts: its summary counts the run's events, and
the .npz it writes keeps them."""

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
