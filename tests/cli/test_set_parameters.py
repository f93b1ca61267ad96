"""``--set NAME=VALUE`` on check, simulate, view and modes: a parameter's value over the
model file's, with the initial values written with it and what the file builds from it at
load (a flexible body's FE model) following; bad input exits 2."""

import json
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.core.errors import ModelError

MODELS = Path(__file__).resolve().parents[2] / "models"
BICYCLE = str(MODELS / "rolling" / "bicycle.yaml")
CANTILEVER = str(MODELS / "flexible" / "cantilever.yaml")
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


def test_set_rebuilds_what_the_file_builds_from_a_parameter(capsys):
    """The cantilever's FE model is built from Iz at load: --set Iz=4e-9 builds it with the new
    value, so its first frequency doubles (ω ∝ √(EI), Iy = 4 Iz following), 2.28816 → 4.57631 Hz,
    the Euler–Bernoulli (βL)² √(EI/ρAL⁴). Changing Iz of the loaded System instead is refused,
    naming the file's line and key, not ignored."""
    assert main(["modes", CANTILEVER, "--set", "Iz=4e-9", "--json"]) == 0
    first = json.loads(capsys.readouterr().out)["modes"][0]["frequency_hz"]
    omega = 1.8751041**2 * np.sqrt(2.1e11 * 4e-9 / (7850 * 1e-4 * 2.0**4))
    assert abs(first - omega / (2 * np.pi)) < 1e-5 * first
    with pytest.raises(ModelError, match=r"parameter 'Iz' was built into the model .*cantilever.yaml:\d+"
                                         r", key parts\.strip\.beam\.I[yz]"):
        mb.load(CANTILEVER).with_parameters(Iz=4e-9)
    assert mb.load(CANTILEVER).with_parameters(L=2.0).parameters["L"] == 2.0  # an unchanged value is no change


def test_a_robots_torque_parameter_is_set_at_load_as_by_with_parameters():
    """A robot's torque parameters join the model after the file's own: loading with one of
    them set gives the motion that with_parameters gives (q̈ to 1e-12), and an unknown name is
    refused naming it."""
    path = MODELS / "robots" / "ur5_holding_bar.yaml"
    loaded = mb.load(path, parameters={"tau_arm_shoulder_lift_joint": 5.0})
    changed = mb.load(path).with_parameters(tau_arm_shoulder_lift_joint=5.0)
    q, qd = loaded.initial_state()
    expected = changed.motion(0.0, q, qd).qdd
    assert np.abs(expected - mb.load(path).motion(0.0, q, qd).qdd).max() > 1e-3  # the torque moves something
    np.testing.assert_allclose(loaded.motion(0.0, q, qd).qdd, expected, atol=1e-12 * np.abs(expected).max())
    with pytest.raises(ModelError, match=r"has no parameter\(s\) \['tau_nothing'\]"):
        mb.load(path, parameters={"tau_nothing": 1.0})
