"""`mbsynth modes` says whether the state it linearizes about keeps itself: the verdict of
the exponent with the largest real part, beside the zero eigenvalues of the cyclic
directions, each named; `--equilibrium` ends at a stable rest even from a maximum; the
"not steady" advice speaks of quaternions only where the model has them."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"
from benchmarks import iftomm_reference as ref

BICYCLE = MODELS / "rolling" / "bicycle.yaml"


def modes(*args):
    return subprocess.run([sys.executable, "-m", "mbsynth.cli", "modes", *map(str, args)],
                          capture_output=True, text=True, timeout=600)


def benchmark_exponents(v):
    """The Whipple bicycle's exponents at speed v from the benchmark's linear equations
    (Meijaard et al. 2007, eq. 5.4: det(s² M + s v C1 + g K0 + v² K2) = 0, the printed matrices)."""
    M, C1 = ref.WHIPPLE_M, ref.WHIPPLE_C1
    K = 9.81 * ref.WHIPPLE_K0 + v * v * ref.WHIPPLE_K2
    companion = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), -v * np.linalg.solve(M, C1)]])
    return np.linalg.eigvals(companion)


@pytest.mark.slow  # the bicycle's steady motion and its exponents in a fresh process (in-process: test_rolling_stability.py)
def test_upright_rolling_at_5_m_s_is_stable():
    """Inside the benchmark's self-stable range (4.29 to 6.02 m/s): every exponent beyond the
    six zeros decays; the capsize mode (Table 2: −0.32286642900409) is the slowest."""
    assert ref.WHIPPLE_WEAVE_SPEED < 5.0 < ref.WHIPPLE_CAPSIZE_SPEED
    run = modes(BICYCLE, "--steady", "--set", "v=5", "--json")
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)
    verdict = result["verdict"]
    assert verdict["kind"] == "stable" and result["stable"]
    assert complex(*verdict["eigenvalue"]) == pytest.approx(-0.32286642900409, abs=1e-8)
    assert result["modes"][verdict["mode"] - 1]["kind"] == "overdamped"
    assert result["zero_eigenvalues"] == len(result["cyclic"]) == 6
    # the heading: the rear wheel's yaw with another body's (which one is the partition's choice)
    heading = [c for c in result["cyclic"] if c.startswith("rear.wheel.angle_z + ")]
    assert len(heading) == 1 and heading[0].endswith(".angle_z"), result["cyclic"]


@pytest.mark.slow  # as at 5 m/s
def test_upright_rolling_at_2_m_s_is_unstable():
    """Below the weave speed the weave grows: the verdict names it, with the exponent the
    benchmark's equations give."""
    run = modes(BICYCLE, "--steady", "--set", "v=2")
    assert run.returncode == 0, run.stderr
    text = run.stdout
    assert "about its steady motion" in text and "3 independent speeds" in text
    expected = max(benchmark_exponents(2.0), key=lambda s: (s.real, s.imag))
    assert expected.real > 0
    verdict = text.splitlines()[-1]
    assert verdict.startswith("verdict: unstable: mode ") and "grows" in verdict
    exponent = complex(verdict.split("s = ")[1].split(" ")[0].replace("j", "j"))
    assert exponent == pytest.approx(expected, rel=1e-5)
    zeros = next(line for line in text.splitlines() if line.startswith("zero eigenvalues"))
    assert zeros.startswith("zero eigenvalues: 6,") and len(zeros.split(": ")[-1].split(", ")) == 6


def test_equilibrium_started_at_the_top_comes_down_to_the_stable_rest():
    """The simple pendulum released exactly upright (theta0 = π) rests there, at a maximum;
    --equilibrium promises a stable rest: the hanging one, a vibration of √(g/L)."""
    run = modes(MODELS / "mechanisms" / "simple_pendulum.yaml", "--equilibrium", "--set", f"theta0={np.pi!r}",
                "--json")
    assert run.returncode == 0, run.stderr
    result = json.loads(run.stdout)
    assert result["q"]["bob.y"] == pytest.approx(-1.0, abs=1e-9)
    assert [m["kind"] for m in result["modes"]] == ["vibration"]
    assert result["modes"][0]["frequency_hz"] == pytest.approx(np.sqrt(9.81) / (2 * np.pi), rel=1e-9)
    assert result["stable"] and result["verdict"]["kind"] == "neutral"  # undamped: neither grows nor decays


def test_pd_pendulum_rest_is_stable():
    run = modes(MODELS / "joints" / "pd_pendulum.yaml", "--equilibrium")
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[-1].startswith("verdict: stable: every mode decays; the slowest, mode ")


@pytest.mark.parametrize("model, quaternion", [("knife_edge", None),
                                               ("rolling_disk", "disk is turned by a quaternion")])
def test_not_steady_advice_names_quaternions_only_where_there_are(model, quaternion):
    run = modes(MODELS / "rolling" / f"{model}.yaml", "--steady")
    assert run.returncode == 1 and run.stdout == ""
    assert "does not move steadily" in run.stderr
    if quaternion:
        assert quaternion in run.stderr
    else:
        assert "quaternion" not in run.stderr
