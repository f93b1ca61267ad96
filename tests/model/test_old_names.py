"""Python names under their old words: each still works, with a DeprecationWarning that
names the new one."""

from pathlib import Path

import pytest

import mbsynth as mb

MODELS = Path(__file__).parents[2] / "models"


@pytest.fixture(scope="module")
def pendulum():
    return mb.load(MODELS / "rigid" / "double_pendulum_3d.yaml")


def test_system_connectors_is_the_old_name_of_constraints(pendulum):
    with pytest.warns(DeprecationWarning, match=r"System\.connectors is the old name of System\.constraints"):
        old = pendulum.connectors
    assert old is pendulum.constraints
    assert [c.name for c in old] == ["link1.unit_quaternion", "link2.unit_quaternion", "shoulder", "elbow"]
