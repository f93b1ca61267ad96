"""Every bundled flexible model gives the same answers in two processes: `mbsynth modes --json`
and `mbsynth simulate`'s trajectory. The slider-crank's rod and the spin-up beam are round
(Iy = Iz): each bending frequency is repeated, and its modes' basis is the reduction's fixed
one, not one that a random start vector or rounding picks (model/flexible/reduction.py). The
two processes of a command run side by side, byte for byte: a process's path (compiled
or KKT) is fixed when its Data is made, never by when a background compilation finishes
(model/data.py)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow  # four processes per model (two fresh runs alike, in make test: test_engine_reuse.py)

MODELS = Path(__file__).resolve().parents[2] / "models" / "flexible"
# model: (the modes command's flags: at rest as written, or the rest found from it; a short run's end time)
RUNS = {"cantilever": ([], "0.02"), "slider_crank": (["--equilibrium"], "0.005"), "spin_up_beam": ([], "0.05")}


@pytest.mark.parametrize("model", sorted(RUNS))
def test_two_processes_give_the_same_modes_and_run(model, tmp_path):
    flags, t_end = RUNS[model]
    path = str(MODELS / f"{model}.yaml")
    cli = [sys.executable, "-m", "mbsynth.cli"]
    modes = _side_by_side([[*cli, "modes", path, *flags, "--json"]] * 2)
    _side_by_side([[*cli, "simulate", path, "--t-end", t_end, "--out", str(tmp_path / f"run{k}.npz")] for k in range(2)])
    first = json.loads(modes[0])
    assert len(first["modes"]) > 0
    assert modes[0] == modes[1]
    runs = [np.load(tmp_path / f"run{k}.npz") for k in range(2)]
    assert sorted(runs[0].files) == sorted(runs[1].files)
    for name in runs[0].files:
        np.testing.assert_array_equal(runs[0][name], runs[1][name], err_msg=name)


def _side_by_side(commands):
    """The stdout of each command, run at the same time; each must exit 0."""
    runs = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE) for command in commands]
    results = [run.communicate(timeout=280) for run in runs]
    for run, (_, err) in zip(runs, results):
        assert run.returncode == 0, err.decode()
    return [out for out, _ in results]

