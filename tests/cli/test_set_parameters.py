"""``--set NAME=VALUE`` on check, simulate, view and modes: a parameter's value over the
model file's, with the initial values written with it following; bad input exits 2."""

import json
from pathlib import Path

import numpy as np
import pytest

from mbsynth.cli import main

MODELS = Path(__file__).resolve().parents[2] / "models"
BICYCLE = str(MODELS / "rolling" / "bicycle.yaml")
TABLE_2_AT_4 = np.sort_complex([-12.15861426576450, -1.42944427361326, 0.41325331521125 - 3.07910818603206j,
                                0.41325331521125 + 3.07910818603206j])  # Meijaard et al. 2007, Table 2


def test_modes_of_the_bicycle_at_another_speed(capsys):
    assert main(["modes", BICYCLE, "--steady", "--set", "v=4", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    values = np.array([complex(*x) for x in result["eigenvalues"]])
    assert np.abs(np.sort_complex(values[values != 0]) - TABLE_2_AT_4).max() < 1e-8
    assert not result["stable"]  # below the weave speed


def test_a_kick_is_not_steady_and_a_run_keeps_the_energy(capsys):
    assert main(["modes", BICYCLE, "--steady", "--set", "kick=0.1"]) == 1
    assert "does not move steadily" in capsys.readouterr().err
    assert main(["simulate", BICYCLE, "--set", "v=4.6", "--set", "kick=0.5", "--t-end", "0.5", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["status"] == "completed" and summary["energy_drift"] < 1e-9


def test_an_unknown_parameter_exits_2_naming_it(capsys):
    assert main(["check", BICYCLE, "--set", "vv=4"]) == 2
    assert "has no parameter(s) ['vv']" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["v=abc", "v", "=4", "v=nan"])
def test_a_bad_assignment_is_a_usage_error(capsys, value):
    with pytest.raises(SystemExit) as stop:  # argparse's usage line and message, exit 2
        main(["check", BICYCLE, "--set", value])
    assert stop.value.code == 2
    assert "argument --set" in capsys.readouterr().err
