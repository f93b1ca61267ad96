"""A controller's values as the model takes them (System.resolved_parameters, through
Data.set_parameters at each sample): a real number, or a real array of one element taken
as its scalar — the natural first try, ``-2*jv["hinge"].position`` (a joint's position is an
array) — while a string (even "3"), a complex number, a boolean or an array of another
size is refused naming the parameter, as a ControlError that keeps the rows run so far."""

import numpy as np
import pytest

import mbsynth as mb

MODEL = """
name: pendulum
parameters: {m: 1.0, L: 1.0, g: 9.81, tau0: 0.0}
gravity: [0, 0, -g]
world: {frames: {pivot: {axis: [0, 1, 0]}}}
parts:
  rod:
    type: rigid_body
    mass: m
    inertia: [m*L**2/12, m*L**2/12, 0.001]
    frames: {top: {position: [0, 0, L/2], axis: [0, 1, 0]}}
    initial: {position: [-L/2*sin(0.3), 0, -L/2*cos(0.3)], rpy: [0, 0.3, 0]}
joints:
  - {name: hinge, type: revolute, parent: world.pivot, child: rod.top, actuation: tau0}
"""


def test_a_one_element_array_is_its_scalar():
    """The run with ``{"tau0": -2*jv["hinge"].position}`` (an array of shape (1,)) is the
    run with the same law written on its float, to the last bit."""
    system = mb.loads(MODEL)
    array = mb.simulate(system, 0.2, controller=lambda t, jv: {"tau0": -2 * jv["hinge"].position}, control_dt=0.05)
    number = mb.simulate(system, 0.2, controller=lambda t, jv: {"tau0": -2 * float(jv["hinge"].position[0])},
                         control_dt=0.05)
    assert np.array_equal(array.q, number.q) and array.t[-1] == pytest.approx(0.2)
    free = mb.simulate(system, 0.2)
    assert not np.allclose(array.q[-1], free.q[-1], atol=1e-6)  # the law acted


@pytest.mark.parametrize("value, got", [
    ("3", "the string '3'"),
    (1 + 0.5j, r"the complex number \(1\+0\.5j\)"),
    (np.array([0.1, 0.2]), r"an array of shape \(2,\)"),
    (True, "the boolean True"),
])
def test_a_value_that_is_no_real_number_is_refused_naming_the_parameter(value, got):
    system = mb.loads(MODEL)
    with pytest.raises(mb.ModelError, match=rf"controller at t = 0\.1: .*parameter 'tau0' takes a real number .*"
                                            rf"got {got}") as err:
        mb.simulate(system, 0.2, controller=lambda t, jv: {"tau0": value if t > 0.05 else 0.0}, control_dt=0.1)
    assert err.value.trajectory.t[-1] == pytest.approx(0.1)  # the rows before the sample are kept
    with pytest.raises(mb.ModelError, match=rf"parameter 'tau0' takes a real number .*got {got}"):
        system.data().set_parameters({"tau0": value})
