"""mb.compose builds in Python what a model file composes: the same System (coordinates,
initial state, motion) as the file with the same entries."""

import numpy as np
import pytest

import mbsynth as mb

PENDULUM = """\
parameters: {L: 1.0, m: 1.0, angle: 0.3}
world: {frames: {pin: {}}}
parts:
  bob: {type: particle, mass: m, initial: {position: [L*sin(angle), 0, -L*cos(angle)]}}
joints:
  - {name: rod, type: distance, parent: world.pin, child: bob, length: L}
ports: {tip: bob}
"""

TOP = """\
parameters: {g: 9.81, L0: 0.5}
gravity: [0, 0, -g]
parts:
  first: {type: model, file: pendulum.yaml, parameters: {L: L0, angle: 0.2}}
  second: {type: model, file: pendulum.yaml, parameters: {L: 2*L0}, placement: {position: [1, 0, 0], rpy: [0, 0, 0.5]}}
forces:
  - {type: spring, between: [first.tip, second.bob], stiffness: 10, rest_length: 1}
"""


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "pendulum.yaml").write_text(PENDULUM)
    (tmp_path / "top.yaml").write_text(TOP)
    return tmp_path


def test_compose_gives_the_system_of_the_file(folder):
    from_file = mb.load(folder / "top.yaml")
    composed = mb.compose(
        {"first": mb.substructure("pendulum.yaml", parameters={"L": "L0", "angle": 0.2}),
         "second": mb.substructure("pendulum.yaml", parameters={"L": "2*L0"},
                                   placement={"position": [1, 0, 0], "rpy": [0, 0, 0.5]})},
        parameters={"g": 9.81, "L0": 0.5}, gravity=[0, 0, "-g"], folder=folder,
        forces=[{"type": "spring", "between": ["first.tip", "second.bob"], "stiffness": 10, "rest_length": 1}])
    assert composed.coordinates == from_file.coordinates
    q, qd = from_file.initial_state()
    q2, qd2 = composed.initial_state()
    np.testing.assert_array_equal(q, q2)
    np.testing.assert_array_equal(qd, qd2)
    np.testing.assert_array_equal(composed.motion(0.0, q, qd).qdd, from_file.motion(0.0, q, qd).qdd)
    # the placed copy: its pin 1 m along x, its bob swung in the plane turned 0.5 rad about z
    L, angle = 1.0, 0.3
    expected = np.array([1 + L * np.sin(angle) * np.cos(0.5), L * np.sin(angle) * np.sin(0.5), -L * np.cos(angle)])
    i = composed.coordinates.index("second.bob.x")
    np.testing.assert_allclose(q2[i:i + 3], expected, atol=1e-15)


def test_compose_refuses_a_key_no_model_file_has(folder):
    with pytest.raises(mb.ModelError, match="unknown model key"):
        mb.compose({"a": {"type": "particle", "mass": 1}}, folder=folder, gravitee=[0, 0, 1])
