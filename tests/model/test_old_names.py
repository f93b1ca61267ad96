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


def test_mbsynth_fast_is_read_where_mbsynth_compiled_is_not_set(monkeypatch):
    from mbsynth.compiled import background
    monkeypatch.delenv("MBSYNTH_COMPILED", raising=False)
    monkeypatch.setenv("MBSYNTH_FAST", "off")
    assert background.default_path() == "kkt"
    monkeypatch.setenv("MBSYNTH_COMPILED", "on")  # the variable's name wins over its old one
    assert background.default_path() == "compiled"
    monkeypatch.setenv("MBSYNTH_COMPILED", "sometimes")
    with pytest.raises(ValueError, match=r"^MBSYNTH_COMPILED must be one of \('on', 'off'\), got 'sometimes'$"):
        background.default_path()
    monkeypatch.delenv("MBSYNTH_COMPILED")
    monkeypatch.setenv("MBSYNTH_FAST", "sometimes")
    with pytest.raises(ValueError, match=r"^MBSYNTH_FAST must be one of"):
        background.default_path()


def test_method_fast_is_the_old_name_of_kkt(pendulum):
    data = pendulum.data(path="kkt")
    q, qd = pendulum.initial_state()
    with pytest.warns(DeprecationWarning, match=r"method='fast' is the old name of method='kkt'"):
        old = data.motion(0.0, q, qd, method="fast")
    assert old.qdd.tolist() == data.motion(0.0, q, qd, method="kkt").qdd.tolist()
    with pytest.raises(ValueError, match=r"method must be one of \['kkt', 'reference'\]"):
        data.motion(0.0, q, qd, method="quick")


def test_a_data_has_parameter_values_in_the_models_order_and_parameters_by_name(pendulum):
    data = pendulum.data(path="kkt")
    data.set_parameters({"m2": 0.5})
    assert list(pendulum.parameters) == ["m1", "m2", "L1", "L2", "r", "g"]
    assert data.parameter_values.tolist() == [1.0, 0.5, 1.0, 0.7, 0.03, 9.81]
    assert data.parameters == {"m1": 1.0, "m2": 0.5, "L1": 1.0, "L2": 0.7, "r": 0.03, "g": 9.81}
    assert not hasattr(data, "p")  # one name for the array
