"""Parameter values over a model's life: a value set stays set until it is set again, and a
parameter defined by an expression of others follows them (System.with_parameters,
Data.set_parameters). Reference: the paper's example 3 (two masses, two springs), whose
accelerations at the initial state are the springs' forces over the masses."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb

MODEL = Path(__file__).resolve().parents[2] / "models" / "paper" / "example3_two_masses.yaml"


def spring_accelerations(p, q):
    """(ẍ1, ÿ) at rest of example 3: body 1 pulled by k1 and k2, mass 2 at y = q1 + q2 by k2."""
    x1, q2 = q[0], q[2]
    f1 = -p["k1"] * (x1 - p["l10"]) + p["k2"] * (q2 - p["l20"])
    return f1 / p["m1"], -p["k2"] * (q2 - p["l20"]) / p["m2"]


def test_a_value_set_by_with_parameters_stays_through_a_later_change_of_another():
    """m1 set, then k1: the second System keeps m1's new value (a number in the file is
    no definition that takes it back) and its motion is that of both values."""
    system = mb.load(MODEL).with_parameters(m1=0.5).with_parameters(k1=50.0)
    assert system.parameters["m1"] == 0.5 and system.parameters["k1"] == 50.0
    q, qd = system.initial_state()
    qdd = system.motion(0.0, q, np.zeros_like(qd)).qdd
    x1_ddot, y_ddot = spring_accelerations(system.parameters, q)
    assert qdd[0] == pytest.approx(x1_ddot, rel=1e-12)
    assert qdd[1] + qdd[2] == pytest.approx(y_ddot, rel=1e-12)


def test_a_value_written_into_a_runs_data_stays_through_a_later_write_of_another():
    """A controller writes m1 at one sample and k1 at the next: m1 keeps its value."""
    system = mb.load(MODEL)
    data = system.data()
    data.set_parameters({"m1": 0.5})
    data.set_parameters({"k1": 50.0})
    values = dict(zip(system.parameters, data.parameter_values))
    assert values["m1"] == 0.5 and values["k1"] == 50.0


def test_a_defined_parameter_follows_the_ones_it_is_defined_by():
    system = mb.loads("parameters: {m: 2.0, R: 0.5, Ic: 0.5*m*R**2}\n"
                      "parts:\n  disk: {type: lagrangian, coordinates: [th], T: 0.5*Ic*th_dot**2}\n")
    assert system.with_parameters(m=4.0).with_parameters(R=1.0).parameters["Ic"] == pytest.approx(2.0)
