"""Declared outputs: expressions, joint values, frame positions and velocities,
reactions and energies, against the pendulum's closed forms and System's own answers."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.model.outputs import OutputEvaluator

PENDULUM = Path("models/joints/driven_pendulum.yaml").read_text() + """
outputs:
  angle: hinge.angle
  swing_speed: L*hinge.rate
  bottom: {position: rod.bottom}
  bottom_velocity: {velocity: rod.bottom}
  hinge_torque: {reaction: hinge.torque}
  hinge_rows: {reaction: hinge.multipliers}
  kinetic: {energy: kinetic}
"""
PENDULUM = PENDULUM.replace("      top: {position: [0, 0, L/2], axis: [0, 1, 0]}",
                            "      top: {position: [0, 0, L/2], axis: [0, 1, 0]}\n      bottom: {position: [0, 0, -L/2]}")


def test_outputs_match_the_closed_forms():
    system = mb.loads(PENDULUM)
    p = system.parameters
    L = p["L"]
    trajectory = mb.simulate(system, 0.6, dt=0.3)
    t, q, qd = trajectory.t[-1], trajectory.q[-1], trajectory.qd[-1]
    evaluator = OutputEvaluator(system)
    assert evaluator.names == ["angle", "swing_speed", "bottom[x]", "bottom[y]", "bottom[z]", "bottom_velocity[x]",
                               "bottom_velocity[y]", "bottom_velocity[z]", "hinge_torque[x]", "hinge_torque[y]",
                               "hinge_torque[z]", "hinge_rows[0]", "hinge_rows[1]", "hinge_rows[2]",
                               "hinge_rows[3]", "hinge_rows[4]", "kinetic"]
    row = dict(zip(evaluator.names, evaluator.evaluate(t, q, qd)))
    theta, rate = row["angle"], row["swing_speed"] / L
    # the rod hangs from the pivot at the origin, turned by θ about y: its bottom at L (−sin θ, 0, −cos θ)
    assert [row[f"bottom[{a}]"] for a in "xyz"] == pytest.approx([-L * np.sin(theta), 0, -L * np.cos(theta)], abs=1e-9)
    velocity = [row[f"bottom_velocity[{a}]"] for a in "xyz"]
    assert velocity == pytest.approx([-L * np.cos(theta) * rate, 0, L * np.sin(theta) * rate], abs=1e-9)
    assert row["kinetic"] == pytest.approx(p["m"] * L**2 / 3 * rate**2 / 2, rel=1e-9)
    tau = p["tau0"] + p["A"] * np.sin(p["w"] * t) - p["c"] * rate  # what the hinge transmits about its axis
    assert row["hinge_torque[z]"] == pytest.approx(tau, rel=1e-9)
    reaction = system.reactions(t, q, qd)["hinge"]
    assert [row[f"hinge_rows[{i}]"] for i in range(5)] == pytest.approx(list(reaction.multipliers), rel=1e-12)


@pytest.mark.parametrize("spec, message", [
    ("{reaction: hinge.speed}", "'.torque' or '.multipliers', not '.speed'"),
    ("{reaction: nowhere.force}", "unknown joint or constraint 'nowhere'"),
    ("{reaction: rod.unit_quaternion.force}", "is no joint"),
    ("{energy: heat}", "energy is one of kinetic, potential, total"),
    ("{position: rod.nose}", "'rod' has no frame 'nose'"),
    ("{position: rod.top, energy: total}", "exactly one of"),
    ("hinge.angel", "hinge.angel"),
])
def test_bad_outputs_are_named(spec, message):
    text = Path("models/joints/driven_pendulum.yaml").read_text() + f"outputs:\n  bad: {spec}\n"
    with pytest.raises(mb.ModelError, match=r"outputs\.bad") as err:
        mb.loads(text)
    assert message in str(err.value)


def test_sweep_metrics_use_joint_values():
    from mbsynth.studies.sweep import Metric
    system = mb.load("models/joints/driven_pendulum.yaml")
    trajectory = mb.simulate(system, 0.4, dt=0.1)
    found = Metric("max:hinge.angle").evaluate(system, trajectory)
    angles = [system.joint_values(t, q, qd)["hinge"].position[0] for t, q, qd in
              zip(trajectory.t, trajectory.q, trajectory.qd)]
    assert found == pytest.approx(max(angles), rel=1e-12)


def test_outputs_recorded_along_a_run_and_in_files(tmp_path):
    """simulate records the declared outputs at every output time; .npz and .csv keep them."""
    system = mb.loads(PENDULUM)
    L = system.parameters["L"]
    trajectory = mb.simulate(system, 0.4, dt=0.1, out=tmp_path / "run.npz")
    assert trajectory.output_names[:2] == ("angle", "swing_speed")
    angle, bottom_x = trajectory.column("angle"), trajectory.column("bottom[x]")
    assert np.allclose(bottom_x, -L * np.sin(angle), rtol=0, atol=1e-9)
    for t, q, qd, row in zip(trajectory.t, trajectory.q, trajectory.qd, trajectory.outputs):
        assert row[0] == pytest.approx(system.joint_values(t, q, qd)["hinge"].position[0], abs=1e-12)
    trajectory.save(tmp_path / "run.csv")
    for path in (tmp_path / "run.npz", tmp_path / "run.csv"):
        loaded = mb.load_trajectory(path)
        assert loaded.output_names == trajectory.output_names
        assert np.allclose(loaded.outputs, trajectory.outputs, rtol=1e-15, atol=0)


def test_sampled_controller_holds_the_static_balance():
    """A PD law in Python on the joint values (sampled every 10 ms, held in between) settles
    the rod where it balances gravity: kp (θ − target) = −m g (L/2) sin θ."""
    from scipy.optimize import brentq
    text = Path("models/joints/pd_pendulum.yaml").read_text()
    text = text.replace("target: 0.5}", "target: 0.5, tau: 0.0}")
    text = text.replace("actuation: -kp*(hinge.angle - target) - kd*hinge.rate", "actuation: tau")
    system = mb.loads(text)
    calls = []

    def law(t, values):
        calls.append(t)
        return {"tau": -50.0 * (values["hinge"].position[0] - 0.5) - 10.0 * values["hinge"].rate[0]}

    trajectory = mb.simulate(system, 6.0, dt=0.5, controller=law, control_dt=0.01)
    assert len(calls) == 600 and calls[:2] == pytest.approx([0.0, 0.01])
    (theta,), (rate,), _ = system.joint_values(trajectory.t[-1], trajectory.q[-1], trajectory.qd[-1])["hinge"]
    balance = brentq(lambda x: 50.0 * (x - 0.5) + 9.81 * 0.5 * np.sin(x), 0.0, 1.0)
    assert theta == pytest.approx(balance, abs=1e-6) and abs(rate) < 1e-5
    with pytest.raises(mb.ModelError, match=r"controller at t = 0: model '.*' has no parameter\(s\) \['torque'\]"):
        mb.simulate(system, 0.1, controller=lambda t, v: {"torque": 1.0})
    with pytest.raises(mb.ModelError, match=r"controller at t = 0: .*non-finite values for parameter\(s\) \['tau'\]"):
        mb.simulate(system, 0.1, controller=lambda t, v: {"tau": float("nan")})


@pytest.mark.parametrize("name", ["energy", "t"])
def test_an_output_named_like_a_built_in_column_is_refused_at_its_line(tmp_path, name):
    """A trajectory file has the columns t, the coordinates, their _dot, energy, then the
    outputs: an output named ``energy`` would write a second ``energy`` column (pandas
    reads it as ``energy.1``), so it is refused at load, with its file and line."""
    text = Path("models/joints/driven_pendulum.yaml").read_text() + f"outputs:\n  angle: hinge.angle\n  {name}: 1\n"
    model = tmp_path / "clash.yaml"
    model.write_text(text)
    with pytest.raises(mb.ModelError) as err:
        mb.load(model)
    line = text.splitlines().index(f"  {name}: 1") + 1
    assert str(err.value).startswith(f"{model}:{line}: at outputs.{name}: output name '{name}'"), str(err.value)


def test_an_output_that_is_not_finite_is_written_with_one_warning(tmp_path, caplog):
    """``1/hinge.angle`` at the hinge's start (angle 0) is inf: written as it is, and said
    once (the output and the time), not once per row."""
    text = Path("models/joints/pd_pendulum.yaml").read_text() + (
        "outputs:\n  inverse: 1/hinge.angle\n  twice: 2*hinge.angle\n")
    text = text.replace("target: 0.5}", "target: 0.5, rest: 0.0}").replace("kp*(hinge.angle - target)",
                                                                           "kp*(hinge.angle - target)*(1 - rest)")
    system = mb.loads(text)
    out = tmp_path / "run.csv"
    with caplog.at_level("WARNING", logger="mbsynth.model.outputs"):
        mb.simulate(system.with_parameters(rest=1.0), 0.2, dt=0.05, out=out)  # no torque: it hangs at angle 0
    warned = [r.getMessage() for r in caplog.records if r.name == "mbsynth.model.outputs"]
    assert len(warned) == 1 and warned[0].startswith("output 'inverse' is not finite at t = 0: inf"), warned
    saved = mb.load_trajectory(out)
    assert np.isinf(saved.column("inverse")).all() and np.all(saved.column("twice") == 0)  # every row inf, one word
