"""Model-file keys under their old names: read as the key itself; both names in one file
refused at the old one's line; messages name the key by its name."""

import re
import warnings
from pathlib import Path

import pytest

import mbsynth as mb

MODEL = Path(__file__).parents[2] / "models" / "rigid" / "double_pendulum_3d.yaml"


def test_a_file_with_subsystems_loads_equal_to_the_file_with_parts():
    text = MODEL.read_text()
    assert re.search(r"^parts:", text, re.M)
    old = re.sub(r"^parts:", "subsystems:", text, flags=re.M)
    folder = MODEL.parent
    assert mb.loads(old, name="m.yaml", folder=folder) == mb.loads(text, name="m.yaml", folder=folder)


def test_parts_and_subsystems_in_one_file_are_refused_at_the_old_key():
    text = ("name: both\nparts:\n  a: {type: particle, mass: 1}\n"
            "subsystems:\n  b: {type: particle, mass: 1}\n")
    with pytest.raises(mb.ModelError, match=r"^both\.yaml:4: at subsystems: 'subsystems' is the old name "
                                            r"of 'parts' \(line 2\); give one of them$"):
        mb.loads(text, name="both.yaml")


def test_a_message_about_an_old_key_names_it_parts():
    with pytest.raises(mb.ModelError, match=r"^m\.yaml:3: at parts\.a\.type: unknown part type 'rigid'"):
        mb.loads("name: m\nsubsystems:\n  a: {type: rigid}\n", name="m.yaml")


def test_compose_takes_subsystems_as_the_old_name_of_parts():
    parts = {"a": {"type": "particle", "mass": 1}}
    with pytest.warns(DeprecationWarning, match=r"compose\(subsystems=\) is the old name of compose\(parts=\)"):
        old = mb.compose(subsystems=parts)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert mb.compose(parts) == old


AUTO = Path(__file__).parents[2] / "models" / "paper" / "example3_m1_zero_auto.yaml"


def test_a_file_with_closure_auto_loads_equal_to_the_file_with_balances_auto():
    text = AUTO.read_text()
    assert re.search(r"^balances: auto$", text, re.M)
    old = re.sub(r"^balances: auto$", "closure: auto", text, flags=re.M)
    new, aliased = mb.loads(text, name="m.yaml"), mb.loads(old, name="m.yaml")
    assert aliased == new
    assert [b.constraint for b in aliased.appended_balances] == ["balance_1"]


def test_closure_and_balances_in_one_file_are_refused_at_the_old_key():
    text = "name: both\nbalances: auto\nparts:\n  a: {type: particle, mass: 1}\nclosure: none\n"
    with pytest.raises(mb.ModelError, match=r"^both\.yaml:5: at closure: 'closure' is the old name of 'balances' "
                                            r"\(line 2\); give one of them$"):
        mb.loads(text, name="both.yaml")


def test_a_message_about_closure_names_it_balances():
    with pytest.raises(mb.ModelError, match=r"^m\.yaml:2: at balances: expected 'auto' or 'none', got 'sometimes'$"):
        mb.loads("name: m\nclosure: sometimes\nparts:\n  a: {type: particle, mass: 1}\n", name="m.yaml")


def test_compose_takes_closure_as_the_old_name_of_balances():
    parts = {"a": {"type": "particle", "mass": 1}}
    with pytest.warns(DeprecationWarning, match=r"compose\(closure=\) is the old name of compose\(balances=\)"):
        old = mb.compose(parts, closure="auto")
    assert old == mb.compose(parts, balances="auto")
    with pytest.raises(mb.ModelError, match=r"balances= and its old name closure= given both"), \
            pytest.warns(DeprecationWarning):
        mb.compose(parts, closure="auto", balances="auto")
