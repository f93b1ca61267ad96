"""The table of joint kinds (core/joint_kinds.py) against the textbook count of each joint's
freedoms, its records against themselves, the row operations' φ̇ against φ differenced, and
the import-time checks refusing a table that lacks an entry. That every consumer reads it
alike is held by tests driven by the table: the compiled rows, φ and φ̇ against the sympy
rows for every kind (tests/compiled/test_fast.py), the joint values of every kind that has
them (tests/model/test_joint_values.py), the efforts along every kind's free motions
(tests/model/test_joint_efforts.py)."""

import numpy as np
import pytest

from mbsynth.core import joint_kinds
from mbsynth.core.joint_kinds import (COINCIDENT, COMPONENT, D, DISTANCE, DOT, EFFORTS, FRICTION_KINDS, JOINT_KINDS,
                                      KINDS, MAX_ROWS, OPERATIONS, URDF_KINDS, ZB, FrictionRate, JointKind,
                                      KindTableError, Row, check_kinds, check_operations, check_table)
from mbsynth.model import joint_values
from mbsynth.model.joint_forces import MOTIONS

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


@pytest.mark.parametrize("code", range(len(OPERATIONS)))
def test_an_operations_rate_is_the_derivative_of_its_phi(code):
    """Along x(t) = x0 + t ẋ, w(t) = w0 + t ẇ (seeded), the spec's φ̇ equals φ's central
    difference (φ is at most quadratic in t here: the difference is exact up to rounding)."""
    spec, rng = OPERATIONS[code], np.random.default_rng(61 + code)
    x0, xd, w0, wd = rng.standard_normal((4, 3))
    length, h = 0.7, 1e-3
    for k in (range(3) if spec.second == "component" else [None]):
        def phi(t):
            x = x0 + t * xd
            w = k if k is not None else x if code == DISTANCE else w0 + t * wd
            return spec.phi(x, w, length)
        w, w_rate = (k, None) if k is not None else (x0, xd) if code == DISTANCE else (w0, wd)
        difference = (phi(h) - phi(-h)) / (2 * h)
        assert spec.rate(x0, xd, w, w_rate, length) == pytest.approx(difference, rel=1e-9, abs=1e-12)


def test_an_interpreter_lacking_an_operation_is_refused():
    with pytest.raises(KindTableError, match=r"^new interpreter does not evaluate the row operation\(s\) distance "):
        check_operations("new interpreter", (COMPONENT, DOT))
    with pytest.raises(KindTableError, match=r"^stale interpreter names row operation code\(s\) \[3\]"):
        check_operations("stale interpreter", (COMPONENT, DOT, DISTANCE, 3))
    check_operations("complete interpreter", (DISTANCE, DOT, COMPONENT))  # any order


# a kind each of whose records lacks one thing every consumer needs, with the message's gist
INCOMPLETE = [
    (JointKind("pin", COINCIDENT), "does not state whether the compiled path takes it"),
    (JointKind("pin", (), compiled=True), "is compiled but has no rows"),
    (JointKind("pin", COINCIDENT, turns=True, compiled=True), "has free motions but no joint values"),
    (JointKind("pin", COINCIDENT, positions=("a",), rates=("r",), accelerations=(), angles=(True,), compiled=True),
     "one acceleration per rate"),
    (JointKind("pin", COINCIDENT + (Row("w", 7, D, D),), compiled=False), "row 'w' has no operation 7"),
    (JointKind("pin", COINCIDENT, positions=("a",), rates=("r",), accelerations=("c",), angles=(True,), turns=True,
               friction=FrictionRate("angle_rate", ("nowhere",)), compiled=True), "takes friction along"),
]


@pytest.mark.parametrize("kind, message", INCOMPLETE, ids=[m for _, m in INCOMPLETE])
def test_a_kind_lacking_an_entry_is_refused(kind, message):
    table = {**KINDS, "pin": kind}
    with pytest.raises(KindTableError, match=f"joint kind 'pin' .*{message}"):
        check_kinds(table)
    check_kinds(KINDS)  # the table itself passes (it is checked at import alike)


def test_a_motion_without_an_effort_is_refused(monkeypatch):
    """A kind moving along a motion no effort acts along (EFFORTS, from which
    joint_forces.MOTIONS is made)."""
    monkeypatch.setattr(joint_kinds, "EFFORTS", {"displacement": "force"})
    with pytest.raises(KindTableError, match="joint kind 'revolute' has no effort along its motion 'angle'"):
        check_kinds({"revolute": KINDS["revolute"]})


def test_a_consumer_table_lacking_a_kind_is_refused():
    """joint_values.VALUES with a kind left out, or with values its record does not name,
    is refused by the check its module runs at import."""
    complete = joint_values.VALUES
    check_table("joint values", complete, agrees=joint_values.values_agree)
    lacking = {k: v for k, v in complete.items() if k != "universal"}
    with pytest.raises(KindTableError, match="^joint values: has no entry for the joint kind 'universal'"):
        check_table("joint values", lacking, agrees=joint_values.values_agree)
    silent = {**complete, "revolute": joint_values.NO_VALUES}  # the chain's old `return [], []`
    with pytest.raises(KindTableError, match="'revolute': joint values where the record names none, or none"):
        check_table("joint values", silent, agrees=joint_values.values_agree)
    with pytest.raises(KindTableError, match="has an entry for 'helical', which is no joint kind"):
        check_table("joint values", {**complete, "helical": joint_values.NO_VALUES})
    # the efforts read a kind's free motions from its first joint values (joint_values.free_motions)
    swapped = {**KINDS, "cylindrical": KINDS["cylindrical"]._replace(positions=("displacement", "angle"))}
    with pytest.raises(KindTableError, match="'cylindrical': its free motions as its first positions"):
        check_table("joint values", complete, kinds=swapped, agrees=joint_values.values_agree)


@pytest.mark.parametrize("name", list(KINDS))
def test_every_kind_has_values_efforts_and_a_compiled_statement(name):
    """What each consumer reads of a kind is there: its joint values' formulas (a kind
    with rates), an effort along each free motion, a stated ``compiled``."""
    kind = KINDS[name]
    assert (joint_values.VALUES[name].expressions is not None) == bool(kind.rates)
    assert all(MOTIONS[EFFORTS[m]][0] == m for m in kind.motions)
    assert kind.compiled is (name != "free")
