"""`mbsynth modes MODEL --campbell NAME=START:STOP:COUNT`: the spinning blade's
(models/flexible/rotating_blade.yaml) frequencies swept over its spin rate, each mode
followed by its shape, and where they meet the order lines f = kΩ/2π, against the closed
form of Southwell's ω² = ω₀² + K Ω² (Ω = ω₀/√(k² − K)) and the converged rotating cantilever
(tests/helpers/rotating_beam.py); the image written. Bad input: one line, exit 2."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize

from tests.helpers.rotating_beam import reference

MODELS = Path(__file__).resolve().parents[2] / "models"
BLADE = MODELS / "flexible" / "rotating_blade.yaml"
SOUTHWELL = {"flap": 1.193, "lag": 0.193}


def modes(*args):
    return subprocess.run([sys.executable, "-m", "mbsynth.cli", "modes", *map(str, args)],
                          capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    """(the JSON, the image's path) of the blade swept over Omega = 0 … 12 rad/s, 25 values."""
    image = tmp_path_factory.mktemp("campbell") / "campbell.png"
    done = modes(BLADE, "--steady", "--campbell", "Omega=0:12:25", "--orders", "2", "--plot", image, "--json")
    assert done.returncode == 0 and done.stderr == "", done.stderr
    return json.loads(done.stdout), image


def test_the_diagram_is_written(swept):
    result, image = swept
    assert image.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and image.stat().st_size > 10_000
    assert result["values"] == pytest.approx(np.linspace(0, 12, 25).tolist())
    assert len(result["frequencies_hz"]) == 25 and result["orders"] == 2


@pytest.mark.parametrize("branch, plane, order", [(1, "flap", 2), (2, "lag", 1), (2, "lag", 2)])
def test_the_crossings_are_where_the_rotating_frequency_meets_the_order_line(swept, branch, plane, order):
    """Mode 1 (flapwise) and mode 2 (lead-lag, which mode 1 overtakes near 7 rad/s: followed
    by its shape, not its rank) meet kP once each, at the Ω of the converged rotating
    cantilever's ω(Ω) = kΩ to 2e-3 and of Southwell's closed form ω₀/√(k² − K) to 1e-2 (its
    lead-lag 1P crossing, at 2.2 times the flapwise ω₀, is 0.75 % late: Southwell's form
    strays as Ω grows)."""
    result, _ = swept
    found = [c for c in result["crossings"] if c["branch"] == branch and c["order"] == order]
    assert len(found) == 1, result["crossings"]
    exact = scipy.optimize.brentq(lambda w: reference(w, plane) - order * w, 0.1, 12.0)
    closed = reference(0.0, plane) / np.sqrt(order ** 2 - SOUTHWELL[plane])
    assert found[0]["rate"] == pytest.approx(exact, rel=2e-3)
    assert found[0]["rate"] == pytest.approx(closed, rel=1e-2)
    assert found[0]["frequency_hz"] == pytest.approx(order * found[0]["rate"] / (2 * np.pi), rel=1e-12)


def test_the_flapwise_mode_never_meets_1P(swept):
    """ω² = ω₀² + 1.193 Ω² > Ω² for every Ω: no 1P crossing of the flapwise branch, which stays
    the lowest at Ω = 0 and rises above the lead-lag one."""
    result, _ = swept
    assert not [c for c in result["crossings"] if c["branch"] == 1 and c["order"] == 1]
    flap, lag = np.array(result["frequencies_hz"])[:, :2].T
    assert flap[0] < lag[0] and flap[-1] > lag[-1]


@pytest.mark.parametrize("model, flags, phrase", [
    (BLADE, ["--campbell", "Spin=0:12:25"], "'Spin' is none of its parameters"),
    (BLADE, ["--campbell", "Omega=0:12:1"], "an empty range"),
    (BLADE, ["--campbell", "Omega=5:1:10"], "an empty range"),
    (BLADE, ["--campbell", "Omega=0:12"], "expected NAME=START:STOP:COUNT"),
    (BLADE, ["--plot", "c.png"], "give --campbell"),
    (BLADE, ["--orders", "2"], "--orders belongs to a Campbell diagram"),
    (MODELS / "rolling" / "rolling_disk.yaml", ["--campbell", "m=1:2:3"], "at m = 1: model 'rolling_disk' does not "
                                                                           "move steadily"),
    (MODELS / "rolling" / "rolling_disk.yaml", ["--campbell", "Omega=1:2:3"], "built into the model"),
])
def test_bad_input_is_one_line_and_exit_2(model, flags, phrase, tmp_path):
    done = modes(model, *flags)
    assert done.returncode == 2, done.stderr
    assert phrase in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
