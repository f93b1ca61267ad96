"""The examples run end to end: the UR5 drawing a circle, its servo multipliers against
Pinocchio's rnea, and the PD-controlled UR5 holding a payload, its PD torques against the
torques of inverse statics (the README's joint-space tour); the walk through the paper's
example 3 that `make run` shows, and the commands it suggests next."""

import importlib.util
import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # each example whole: a UR5's seconds of motion, the demo and its commands

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def example(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_ur5_circle_torques_equal_rnea(tmp_path):
    """Inverse dynamics by constraints: the servo multipliers along the drawn circle are the
    joint torques of pin.rnea on the same joint trajectory."""
    assert example("ur5_circle").main(str(tmp_path / "circle.png")) < 1e-9
    assert (tmp_path / "circle.png").stat().st_size > 10_000


def test_pd_arm_comes_to_rest_where_its_torques_hold_it(tmp_path):
    """After 4 s of sampled PD control the UR5 rests where the PD torques equal the static
    torques read off servo rows (inverse statics); the payload's remaining swing on its
    undamped spring keeps them apart by about 1 %."""
    assert example("pd_arm_payload").main(str(tmp_path / "pd.png")) < 0.03
    assert (tmp_path / "pd.png").stat().st_size > 10_000


def test_the_walk_through_example_3_suggests_commands_that_run_as_printed():
    """`make run` (examples/paper_example3.py) ends with commands to try next: each runs as
    printed, from the folder it was run in, and exits 0."""
    root = EXAMPLES.parent
    (root / "out" / "example3.png").unlink(missing_ok=True)  # made again by the suggested run
    done = subprocess.run([sys.executable, str(EXAMPLES / "paper_example3.py")], cwd=root, capture_output=True,
                          text=True, timeout=240, env={**os.environ, "MPLBACKEND": "agg"})
    assert done.returncode == 0, done.stderr[-3000:]
    suggested = done.stdout.split("\nNext, from this folder:", 1)[1].splitlines()[1:]
    assert len(suggested) == 2 and all(line.startswith("  ") for line in suggested)
    outputs = []
    for line in suggested:
        ran = subprocess.run(shlex.split(line), cwd=root, capture_output=True, text=True, timeout=240)
        assert ran.returncode == 0, f"{line}: {ran.stderr[-2000:]}"
        outputs.append(ran.stdout)
    assert "motion: unique" in outputs[0] and (root / "out" / "example3.png").stat().st_size > 10_000
