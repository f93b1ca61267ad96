"""Joint limits and contacts in a model file (io/unilateral.py): what they build, and each
bad input refused with the file, the line and the key, also on the command line (exit 2,
one line)."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb

MODELS = Path(__file__).resolve().parents[2] / "models" / "contact"

PENDULUM = """name: stop
parameters: {{m: 1.0, L: 0.8}}
gravity: [0, 0, -9.81]
world: {{frames: {{pivot: {{axis: [0, 1, 0]}}}}}}
parts:
  rod:
    type: rigid_body
    mass: m
    inertia: [0.05, 0.05, 0.001]
    frames: {{top: {{position: [0, 0, L/2], axis: [0, 1, 0]}}}}
    initial: {{position: [-L/2*sin(0.2), 0, -L/2*cos(0.2)], rpy: [0, 0.2, 0]}}
joints:
  - {{name: hinge, type: {kind}, parent: world.pivot, child: rod.top, {limits}}}
"""

BALL = """name: ball
parameters: {{m: 1.0, r: 0.1}}
parts:
  ball: {{type: particle, mass: m, initial: {{position: [0, 0, {z}]}}}}
  other: {{type: particle, mass: m, initial: {{position: [0, 0, 1]}}}}
contacts:
  - {contact}
"""


def test_limits_and_contacts_build_their_gaps():
    system = mb.loads(PENDULUM.format(kind="revolute", limits="limits: [-0.5, 0.4], restitution: 0.3"))
    assert [(u.name, u.kind, u.restitution_at(system, system.parameter_values)) for u in system.unilaterals] == \
        [("hinge.lower", "limit", 0.3), ("hinge.upper", "limit", 0.3)]
    q, qd = system.initial_state()
    gaps = [u.row.residuals(0.0, q, qd, system.parameter_values)[0][0] for u in system.unilaterals]
    assert np.allclose(gaps, [0.2 + 0.5, 0.4 - 0.2], atol=1e-12)  # angle − lo, hi − angle at the angle 0.2
    ball = mb.loads(BALL.format(z=0.5, contact="{name: floor, type: plane, child: ball, radius: r, ground: -0.2, "
                                               "normal: [0, 0, 2]}"))
    q, qd = ball.initial_state()
    assert abs(ball.unilaterals[0].row.residuals(0.0, q, qd, ball.parameter_values)[0][0] - 0.6) < 1e-14
    assert len(ball.constraint_names) == 0  # a gap is no row until it holds


BAD = [
    (PENDULUM.format(kind="revolute", limits="limits: [-0.5, 0.4], restitution: -0.1"), 13,
     "restitution must be between 0 and 1, got -0.1"),
    (PENDULUM.format(kind="revolute", limits="limits: [-0.5, 0.4], restitution: 1.5"), 13,
     "restitution must be between 0 and 1, got 1.5"),
    (PENDULUM.format(kind="revolute", limits="limits: [0.4, -0.5]"), 13, "lo = 0.4 is above hi = -0.5"),
    (PENDULUM.format(kind="revolute", limits="restitution: 0.5"), 13, "restitution needs limits"),
    (PENDULUM.format(kind="cylindrical", limits="limits: [0, 1]"), 13, "a cylindrical joint takes no limits"),
    (PENDULUM.format(kind="spherical", limits="limits: [0, 1]"), 13, "at joints[0].limits: expected a mapping"),
    (PENDULUM.format(kind="revolute", limits="limits: [-0.5, 0.1]"), 13,
     "the initial state penetrates 'hinge.upper' by 0.1"),
    (BALL.format(z=0.05, contact="{name: floor, type: plane, child: ball, radius: r}"), 7,
     "the initial state penetrates 'floor' by 0.05"),
    (BALL.format(z=0.5, contact="{name: floor, type: plane, child: rock, radius: r}"), 7, "unknown part 'rock'"),
    (BALL.format(z=0.5, contact="{name: floor, type: plane, child: ball, radius: -1}"), 7, "a radius is ≥ 0"),
    (BALL.format(z=0.5, contact="{name: floor, type: plane, child: ball, normal: [0, 0, 0]}"), 7,
     "the plane's normal is zero"),
    (BALL.format(z=0.5, contact="{name: floor, type: cone, child: ball}"), 7, "a contact's type is one of plane"),
    (BALL.format(z=0.5, contact="{name: c, type: spheres, between: [ball, ball], radius: [r, r]}"), 7,
     "the two spheres must be on two parts"),
    (BALL.format(z=0.5, contact="{name: c, type: spheres, between: [ball, other], radius: [r, 0.6]}"), 7,
     "the initial state penetrates 'c' by 0.2"),
    ("name: disc\nparts:\n  disc: {type: planar_body, mass: 1.0, inertia: 0.1, initial: {position: [0, 1]}}\n"
     "contacts:\n  - {name: floor, type: plane, child: disc}\n", 5,  # the normal z, across the disc's x-y plane
     "contact 'floor': its gap 0 changes with no coordinate"),
]


@pytest.mark.parametrize("text, line, message", BAD)
def test_bad_input_is_refused_naming_the_file_and_line(text, line, message):
    with pytest.raises(mb.ModelError) as caught:
        mb.loads(text, name="case.yaml")
    assert str(caught.value).startswith(f"case.yaml:{line}:") and message in str(caught.value), str(caught.value)


def test_the_command_line_refuses_a_bad_restitution_with_one_line(tmp_path):
    path = tmp_path / "stop.yaml"
    path.write_text(BAD[1][0])
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "simulate", str(path), "--t-end", "1"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "stop.yaml:13:" in done.stderr
    assert "restitution must be between 0 and 1, got 1.5" in done.stderr


def test_a_run_with_contacts_needs_an_explicit_runge_kutta_method():
    system = mb.loads(BALL.format(z=0.5, contact="{name: floor, type: plane, child: ball, radius: r}"))
    with pytest.raises(ValueError, match="limits or contacts: its run needs an explicit Runge–Kutta method"):
        mb.simulate(system, 0.1, method="Radau")


def test_restitution_follows_the_parameters_and_is_refused_outside_0_1():
    system = mb.load(MODELS / "pendulum_stop.yaml")
    assert system.unilaterals[0].restitution_at(system, system.parameter_values) == 1.0
    half = system.with_parameters(e=0.5)
    assert [u.restitution_at(half, half.parameter_values) for u in half.unilaterals] == [0.5, 0.5]
    assert half.unaccounted_work() == ["hinge.lower", "hinge.upper"]  # impacts that lose energy
    with pytest.raises(mb.ModelError, match="the restitution of 'hinge.lower' is 2 at these parameter values"):
        mb.simulate(system.with_parameters(e=2.0), 0.1)



def test_the_limits_of_a_for_entrys_joints_may_use_its_name():
    path = Path(__file__).resolve().parents[2] / "models" / "mechanisms" / "n_four_bar.yaml"
    text = path.read_text().replace("    child: cell[i].right\n", "    child: cell[i].right\n    limits: [-1 - i, 1 + i]\n")
    system = mb.loads(text, folder=path.parent, parameters={"N": 3})
    q, qd = system.initial_state()
    gaps = {u.name: u.row.residuals(0.0, q, qd, system.parameter_values)[0][0] for u in system.unilaterals}
    assert list(gaps) == ["right[0].lower", "right[0].upper", "right[1].lower", "right[1].upper"]
    assert np.allclose(list(gaps.values()), [1, 1, 2, 2], atol=1e-12)  # the bars start square: angle 0


def test_a_run_from_a_state_that_penetrates_is_refused_saying_by_how_much():
    system = mb.load(MODELS / "bouncing_ball.yaml")  # r = 0.05
    with pytest.raises(mb.ModelError, match=r"the state at t = 0 penetrates 'floor' by 0.02 \(gaps must be ≥ 0\)"):
        mb.simulate(system, 0.1, q0=[0.0, 0.0, 0.03])
