"""The algorithms compute at a Data's parameter values: mb.linearize, mb.equilibrium,
mb.modes, mb.steady_motion and mode_motion handed a Data with ``set_parameters`` give what
they give for the model built with those values (``with_parameters``), and not what they
give for the model's own values; so does the Data's initial state."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.analysis.modes import mode_motion
from tests.helpers.compare import rel

MODELS = Path(__file__).resolve().parents[2] / "models"
SAME = 1e-10  # the Data and the rebuilt model compute alike: only rounding may differ


def _both(path, values):
    """(the model, a Data of it set to ``values``, the model built with ``values``)."""
    system = mb.load(MODELS / path)
    data = system.data()
    data.set_parameters(values)
    return system, data, system.with_parameters(**values)


@pytest.mark.parametrize("values", [{"k": 160.0}, {"L": 0.9, "c": 1.5}])
def test_linearize_at_a_datas_parameters(values):
    """A spring pendulum linearized about its (moving) initial state: the spring's
    stiffness and the rod's length change A."""
    system, data, changed = _both("forces/spring_pendulum.yaml", values)
    state = system.initial_state()
    found, expected, default = (mb.linearize(x, 0.0, *state).A for x in (data, changed, system))
    assert rel(found, expected) < SAME
    assert rel(default, expected) > 1e-3


def test_a_datas_initial_state_follows_its_parameters():
    """Initial values written with parameters (the pendulum's bob at L, θ0) are taken at the
    Data's values, as ``with_parameters`` takes them."""
    system, data, changed = _both("mechanisms/simple_pendulum.yaml", {"L": 2.0, "theta0": 0.3})
    for found, expected in zip(data.initial_state(), changed.initial_state()):
        assert np.array_equal(found, expected)
    assert np.allclose(data.initial_state()[0], [-2.0 * np.sin(0.3), -2.0 * np.cos(0.3)], rtol=0, atol=1e-15)
    assert np.allclose(system.initial_state()[0], [-1.0, 0.0], rtol=0, atol=1e-15)


def test_equilibrium_at_a_datas_parameters():
    """A pendulum of length L rests at (0, −L): the Data's length, not the model's (from
    the initial state, at the Data's values as well)."""
    system, data, changed = _both("mechanisms/simple_pendulum.yaml", {"L": 2.0})
    found, expected, default = (mb.equilibrium(x) for x in (data, changed, system))
    assert rel(found, expected) < SAME
    assert np.abs(found - [0.0, -2.0]).max() < 1e-8
    assert np.abs(default - [0.0, -1.0]).max() < 1e-8


@pytest.mark.parametrize("values", [{"g": 4.0}, {"L": 0.5}, {"g": 20.0, "L": 3.0}])
def test_modes_at_a_datas_parameters(values):
    """A pendulum of length L under g at rest at the bottom swings at √(g/L)."""
    system, data, changed = _both("mechanisms/simple_pendulum.yaml", values)
    g, L = (changed.parameters[name] for name in ("g", "L"))
    bottom = [0.0, -L]
    found, expected, default = (mb.modes(x, bottom, equilibrium=True) for x in (data, changed, system))
    assert rel(found.linearization.A, expected.linearization.A) < SAME
    assert 2 * np.pi * found.modes[0].frequency == pytest.approx(np.sqrt(g / L), rel=1e-9)
    assert 2 * np.pi * default.modes[0].frequency == pytest.approx(np.sqrt(9.81), rel=1e-9)
    shown, made = (mode_motion(x, found, 0) for x in (data, changed))
    assert rel(shown.q, made.q) < SAME
    assert np.abs(np.hypot(shown.q[:, 0], shown.q[:, 1]) - L).max() < 1e-9 * L  # on the Data's rod


@pytest.mark.parametrize("values", [{"g": 5.0}, {"m": 3.0, "g": 15.0}])
def test_steady_motion_at_a_datas_parameters(values):
    """A disk turning at Ω with the lean of its initial state: the spin that makes the
    circle steady is the model file's closed form at the Data's values."""
    system, data, changed = _both("rolling/turning_disk.yaml", values)
    q0 = system.initial_state()[0]
    rates = {"disk.angle_z": 2.0, "disk.angle_z2": 0.0}
    found, expected, default = (mb.steady_motion(x, rates, q=q0, solve=["disk.angle_z2_dot"])[1]
                                for x in (data, changed, system))
    assert rel(found, expected) < SAME
    spin = system.coordinates.index("disk.angle_z2")
    assert found[spin] == pytest.approx(changed.parameters["spin"], rel=1e-9)
    assert default[spin] == pytest.approx(system.parameters["spin"], rel=1e-9)
    assert abs(changed.parameters["spin"] - system.parameters["spin"]) > 1e-3 * abs(system.parameters["spin"])


def test_simulate_at_a_datas_parameters():
    """A pendulum released from θ0 on a rod of length L, run in a Data set to both: its
    initial state, motion and recorded parameters are those of the model built with them;
    the Data runs on its own path only."""
    values = {"L": 2.0, "theta0": 0.5}
    system, data, changed = _both("mechanisms/simple_pendulum.yaml", values)
    found, expected, default = (mb.simulate(x, 0.5, dt=0.1) for x in (data, changed, system))
    assert rel(found.q, expected.q) < SAME and rel(found.qd, expected.qd) < SAME
    assert np.abs(np.hypot(found.q[:, 0], found.q[:, 1]) - 2.0).max() < 1e-9
    assert np.abs(default.q[:, 0] - found.q[:, 0]).max() > 0.1
    assert {name: found.parameters[name] for name in values} == values
    other = "kkt" if data.path == "compiled" else "compiled"
    with pytest.raises(ValueError, match=f"path='{other}': the Data given runs on its own path, '{data.path}'"):
        mb.simulate(data, 0.5, path=other)


SLIDER = """
name: slider
parameters: {m: 1.0, d: 0.5}
world:
  frames:
    rail: {position: [d, 0, 0], axis: [1, 0, 0]}
parts:
  block:
    type: rigid_body
    mass: m
    inertia: [0.1, 0.1, 0.1]
    frames:
      guide: {axis: [1, 0, 0]}
joints:
  - {name: slide, type: prismatic, parent: world.rail, child: block.guide}
initial: {block.x: 0.75}
"""


def test_joint_values_along_a_run_at_a_datas_parameters():
    """``along`` handed a Data reads the joints at its values: a block on a rail that starts
    at x = d slides the displacement x − d, so the same states give x − 0.6 for a Data set
    to d = 0.6, as the rebuilt model gives, and x − 0.5 for the model's own d."""
    from mbsynth.model.joint_values import along
    system = mb.loads(SLIDER)
    data = system.data()
    data.set_parameters({"d": 0.6})
    changed = system.with_parameters(d=0.6)
    q0, qd0 = system.initial_state()
    x = system.coordinates.index("block.x")
    q, qd = np.tile(q0, (3, 1)), np.tile(qd0, (3, 1))
    q[:, x] = [0.7, 0.8, 0.9]
    t = np.zeros(3)
    found, expected, default = (along(m, t, q, qd)["slide"].position[:, 0] for m in (data, changed, system))
    assert np.allclose(found, [0.1, 0.2, 0.3], rtol=0, atol=1e-12)
    assert rel(found, expected) < SAME
    assert np.allclose(default, [0.2, 0.3, 0.4], rtol=0, atol=1e-12)


def test_with_parameters_refuses_a_value_built_into_a_frame_at_load():
    """A frame's axis written with a parameter is a rotation computed at load: changing that
    parameter with ``with_parameters`` is refused naming the file's line (it would keep the
    old axis), while ``load(parameters=)`` builds the new one: the block slides down the
    steeper slope at g (sin α − μ cos α) (slider_friction.yaml)."""
    path = MODELS / "joints/slider_friction.yaml"
    with pytest.raises(mb.ModelError, match=r"'alpha' was built into the model .*slider_friction.yaml:\d+, key world.frames.slope.axis"):
        mb.load(path).with_parameters(alpha=0.7)
    steeper = mb.load(path, parameters={"alpha": 0.7})
    q, qd = steeper.initial_state()
    qdd = steeper.motion(0.0, q, qd).qdd
    x, z = (steeper.coordinates.index(f"block.{c}") for c in "xz")
    g, mu = 9.81, 0.3
    assert abs(np.hypot(qdd[x], qdd[z]) - g * (np.sin(0.7) - mu * np.cos(0.7))) < 1e-9


def test_a_parts_initial_position_written_with_parameters_follows_them():
    """A part's own ``initial: {position: ...}`` written with parameters is taken at the new
    values by ``with_parameters`` as by ``load(parameters=)`` (four_bar.yaml's crank centre
    at a/2)."""
    path = MODELS / "mechanisms/four_bar.yaml"
    a = mb.load(path).parameters["a"] * 1.1
    for found, expected in zip(mb.load(path).with_parameters(a=a).initial_state(),
                               mb.load(path, parameters={"a": a}).initial_state()):
        assert np.array_equal(found, expected)
