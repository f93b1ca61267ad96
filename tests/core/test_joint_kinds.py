"""The table of joint kinds (core/joint_kinds.py) against the textbook count of each joint's
freedoms, and its records against themselves. That every consumer reads it alike is held
by tests driven by the table: the compiled rows against the sympy rows for every kind
(tests/compiled/test_fast.py), the joint values of every kind that has them
(tests/model/test_joint_values.py)."""

import pytest

from mbsynth.core.joint_kinds import (COMPONENT, D, DISTANCE, DOT, FRICTION_KINDS, JOINT_KINDS, KINDS, MAX_ROWS,
                                      URDF_KINDS, ZB)

# the relative freedoms each joint leaves between two rigid bodies (any kinematics text)
FREEDOMS = {"fixed": 0, "revolute": 1, "prismatic": 1, "cylindrical": 2, "universal": 2, "spherical": 3,
            "distance": 5, "free": 6}


@pytest.mark.parametrize("name", list(KINDS))
def test_a_kind_holds_six_minus_its_freedoms_in_rows(name):
    kind = KINDS[name]
    assert kind.name == name
    assert len(kind.rows) == 6 - FREEDOMS[name]
    assert len(set(kind.labels)) == len(kind.labels)
    for _, operation, first, second in kind.rows:
        if operation == COMPONENT:
            assert first == D and 0 <= second < 3
        elif operation == DOT:
            assert D <= first <= ZB and D <= second <= ZB and first != second
        else:
            assert (operation, first, second) == (DISTANCE, D, D)


@pytest.mark.parametrize("name", [k for k in KINDS if KINDS[k].rates])
def test_a_kind_with_values_has_a_rate_per_freedom(name):
    """One rate (and acceleration) per freedom, one position at least (a free joint's
    quaternion has four entries for three freedoms); a joint that turns has an angle."""
    kind = KINDS[name]
    assert len(kind.rates) == len(kind.accelerations) == FREEDOMS[name]
    assert len(kind.angles) == len(kind.positions) >= FREEDOMS[name]
    assert sum(kind.angles) >= kind.turns


def test_the_lists_read_from_the_table():
    assert JOINT_KINDS == ("fixed", "revolute", "prismatic", "cylindrical", "spherical", "universal", "distance")
    assert "free" in KINDS and "free" not in JOINT_KINDS  # a floating root's values, no constraint
    assert MAX_ROWS == 6
    assert set(URDF_KINDS) == {"fixed", "revolute", "continuous", "prismatic"}
    assert URDF_KINDS["continuous"] == "revolute"
    assert all(FREEDOMS[URDF_KINDS[u]] <= 1 for u in URDF_KINDS)  # URDF's own one-axis joints


@pytest.mark.parametrize("name", FRICTION_KINDS)
def test_friction_opposes_a_free_motion_and_its_load_rows_are_rows_of_the_kind(name):
    kind = KINDS[name]
    assert kind.friction.rate in [f"{m}_rate" for m in kind.motions]
    assert set(kind.friction.load_rows) <= set(kind.labels)
    assert len(kind.motions) == FREEDOMS[name] == 1  # friction along a joint's one motion


def test_free_motions_and_their_efforts():
    assert {k: KINDS[k].motions for k in JOINT_KINDS if KINDS[k].motions} == {
        "revolute": ("angle",), "prismatic": ("displacement",), "cylindrical": ("angle", "displacement")}
    assert {k: KINDS[k].effort for k in JOINT_KINDS if KINDS[k].effort} == {"revolute": "torque", "prismatic": "force"}
