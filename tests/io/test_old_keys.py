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
