"""Every model file in models/ runs: ``mbsynth check`` exits 0, a short ``mbsynth simulate``
exits 0, and ``mbsynth modes`` gives the modes where the model rests (with
``--equilibrium`` where it has an isolated equilibrium) or the verdict or refusal its
model calls for, by the exit-status table (1 a verdict, 2 a refusal), naming the reason.
Nothing is written to stderr but the one error line (no numpy warnings)."""

import json
from pathlib import Path

import pytest

from mbsynth.cli import main

MODELS = Path(__file__).resolve().parents[2] / "models"

# what `mbsynth modes` answers, per model: "rests" (exit 0 at the initial state),
# "equilibrium" (exit 0 with --equilibrium), "steady" (exit 0 with --steady), or (flags, exit status, a phrase of the message)
NOT_ISOLATED = "the equilibrium is not isolated"
NOT_UNIQUE = "the motion is not unique"
ACCELERATION_ROWS = "restrict accelerations only"
NOT_STEADY = "does not move steadily"
MODES = {
    "contact/bouncing_ball.yaml": ([], 1, "does not rest at this configuration"),  # dropped
    "contact/pendulum_stop.yaml": ([], 1, "does not rest at this configuration"),  # released from an angle
    "contact/newtons_cradle.yaml": ([], 1, "does not rest at this configuration"),  # the first ball pulled out
    "contact/block_on_slope.yaml": ([], 1, "does not rest at this configuration"),  # it slides down the slope
    "contact/rimless_wheel.yaml": ([], 2, NOT_UNIQUE),  # its mass at the hub: its turn is free with no foot held
    "contact/simplest_walker.yaml": ([], 1, "does not rest at this configuration"),  # it walks
    "contact/box_drop.yaml": ([], 1, "does not rest at this configuration"),  # dropped
    "contact/cone_pendulum.yaml": "rests",  # hanging (it starts swinging from there)
    "contact/box_on_four_corners.yaml": ([], 1, "does not rest at this configuration"),  # its weight on its corners
    "contact/crossed_capsules.yaml": "rests",  # no gravity: two free bodies, at rest anywhere (modes at q̇ = 0)
    "flexible/cantilever.yaml": "rests",
    "flexible/slider_crank.yaml": "equilibrium",  # the crank hanging, the rod sagging
    "flexible/spin_up_beam.yaml": "rests",  # at rest at t = 0, the hub held by its servo row
    "flexible/rotating_blade.yaml": "steady",  # spinning at Omega, turned by angles: the spin is cyclic
    "flexible/precessing_rotor.yaml": "rests",  # at rest at t = 0, its angles' rows at rest to second order there
    "forces/spring_part_chain.yaml": "equilibrium",
    "forces/spring_pendulum.yaml": (["--equilibrium"], 1, NOT_ISOLATED),  # the rod spins freely about itself
    "joints/cart_pole_servo.yaml": ([], 1, "rows ['servo'] prescribe a motion at t = 0"),
    "joints/driven_pendulum.yaml": "equilibrium",
    "joints/pd_pendulum.yaml": "equilibrium",
    "joints/slider_friction.yaml": ([], 2, "Coulomb friction at ['slide'] is not differentiable"),
    "legged/leg.yaml": (["--equilibrium"], 1, "no static equilibrium found"),  # a free leg falls for ever
    "legged/quadruped.yaml": ([], 1, "does not rest at this configuration"),  # it starts below its stance
    "mechanisms/andrews.yaml": "equilibrium",
    "mechanisms/bennett.yaml": "equilibrium",
    "mechanisms/bricard.yaml": "equilibrium",
    "mechanisms/double_pendulum_rods.yaml": "equilibrium",
    "mechanisms/flyball_governor.yaml": (["--equilibrium"], 1, NOT_ISOLATED),  # the shaft turns freely
    "mechanisms/four_bar.yaml": "equilibrium",
    "mechanisms/four_bar_3d.yaml": "equilibrium",
    "mechanisms/four_bar_cell.yaml": (["--equilibrium"], 1, NOT_ISOLATED),  # no gravity of its own: rests anywhere
    "mechanisms/massless_link.yaml": ([], 2, NOT_UNIQUE),  # the massless link's free spin
    "mechanisms/massless_rod.yaml": ([], 2, NOT_UNIQUE),
    "mechanisms/n_four_bar.yaml": "rests",
    "mechanisms/pendulum_1km.yaml": "equilibrium",
    "mechanisms/sarrus.yaml": "equilibrium",
    "mechanisms/simple_pendulum.yaml": "equilibrium",
    "mechanisms/slider_crank.yaml": "equilibrium",
    "mechanisms/slider_crank_3d.yaml": "equilibrium",  # the crank straight up (unstable)
    "paper/example1_wheel.yaml": (["--equilibrium"], 1, "no static equilibrium found"),  # it rolls down for ever
    "paper/example2_massless_particle.yaml": ([], 2, NOT_UNIQUE),
    "paper/example3_m1_zero.yaml": "equilibrium",
    "paper/example3_m1_zero_auto.yaml": "equilibrium",
    "paper/example3_m2_zero.yaml": ([], 2, ACCELERATION_ROWS),  # its balance is an acceleration-level row
    "paper/example3_m2_zero_auto.yaml": "equilibrium",
    "paper/example3_two_masses.yaml": "equilibrium",
    "rigid/double_pendulum_3d.yaml": "equilibrium",
    "rigid/double_pendulum_angles.yaml": "equilibrium",
    "rigid/double_pendulum_spatial.yaml": "rests",
    "rigid/double_pendulum_spatial_angles.yaml": "rests",
    "rigid/free_body.yaml": (["--equilibrium"], 1, "no static equilibrium found"),  # it falls for ever
    "rigid/solid_pendulum.yaml": "equilibrium",
    "rigid/tennis_racket.yaml": "rests",
    "robots/two_arms_bar.yaml": (["--equilibrium"], 1, NOT_ISOLATED),  # the wrists turn the hanging bar
    "robots/ur5_holding_bar.yaml": (["--equilibrium"], 1, NOT_ISOLATED),
    "robots/ur5_payload.yaml": (["--equilibrium"], 1, NOT_ISOLATED),  # the vertical shoulder axis
    "substructures/pendulum_cell.yaml": "equilibrium",  # one cell of benchmarks/substructures.py
    "rolling/bicycle.yaml": "steady",
    "rolling/bicycle_wheel.yaml": "steady",  # one wheel rolling upright alone: its lean oscillates
    "rolling/knife_edge.yaml": (["--steady"], 1, NOT_STEADY),  # its turning grows
    "rolling/rolling_disk.yaml": (["--steady"], 1, NOT_STEADY),  # a quaternion: the spin is not cyclic
    "rolling/turning_disk.yaml": "steady",
}


# the models whose three commands take longest (robots, legs, a governor's equilibrium
# search, flexible bodies, two capsules' gap derived and compiled): run by `make test-slow` and CI
SLOW = {"contact/crossed_capsules.yaml", "flexible/slider_crank.yaml", "flexible/spin_up_beam.yaml", "legged/leg.yaml",
        "legged/quadruped.yaml", "mechanisms/flyball_governor.yaml", "robots/two_arms_bar.yaml",
        "robots/ur5_holding_bar.yaml", "robots/ur5_payload.yaml"}


def test_every_model_file_is_listed():
    assert sorted(str(p.relative_to(MODELS)) for p in MODELS.rglob("*.yaml")) == sorted(MODES)
    assert SLOW <= set(MODES)


def run(capsys, *args):
    code = main([*args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.slow) if name in SLOW else name
                                  for name in sorted(MODES)])
def test_model_checks_simulates_and_gives_its_modes(capsys, name):
    path = str(MODELS / name)
    code, out, err = run(capsys, "check", path, "--json")
    assert code == 0 and json.loads(out)["error"] is None, err
    code, out, err = run(capsys, "simulate", path, "--t-end", "0.01", "--dt", "0.005", "--json")
    assert code == 0 and err == "", err
    assert json.loads(out)["status"] == "completed"
    expected = MODES[name]
    if expected in ("rests", "equilibrium", "steady"):
        flag = {"rests": [], "equilibrium": ["--equilibrium"], "steady": ["--steady"]}[expected]
        code, out, err = run(capsys, "modes", path, "--json", *flag)
        assert code == 0 and err == "", err
        result = json.loads(out)
        if expected == "steady":  # each eigenvalue is a mode's (two for a complex pair) or a zero of a cyclic direction
            assert result["steady_motion"] and result["modes"]
            assert len(result["eigenvalues"]) == result["zero_eigenvalues"] + sum(
                2 if m["eigenvalue"][1] else 1 for m in result["modes"])
        else:
            assert result["modes"] and len(result["modes"]) >= result["degrees_of_freedom"] / 2
    else:
        flags, status, phrase = expected
        code, out, err = run(capsys, "modes", path, *flags)
        assert code == status and out == ""
        assert err.count("\n") == 1 and phrase in err, err  # one line: no warnings before it
