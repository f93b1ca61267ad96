"""The generated reference pages (docs/_ext/mbsynth_reference.py) cover what they describe:
every ``mbsynth`` command and flag of the argparse parsers, every key of the loader's
schema. (The site itself is built by ``make docs``, in CI after the tests.)"""

import argparse
import importlib.util
import re
from pathlib import Path

import pytest

from mbsynth.cli.parsers import parser
from mbsynth.io.schema import SECTIONS

EXTENSION = Path(__file__).parent.parent / "docs" / "_ext" / "mbsynth_reference.py"


@pytest.fixture(scope="module")
def reference():
    spec = importlib.util.spec_from_file_location("mbsynth_reference", EXTENSION)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _commands():
    top = parser()
    action = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices


def test_cli_page_has_every_command_and_flag(reference):
    page = reference.cli_page()
    commands = _commands()
    assert {"check", "simulate", "validate", "view", "modes", "robots", "sweep"} <= set(commands)  # DESIGN.md
    for name, sub in commands.items():
        section = page.split(f"## `mbsynth {name}`", 1)[1].split("\n## ", 1)[0]
        for action in sub._actions:
            if action.help == argparse.SUPPRESS or isinstance(action, argparse._HelpAction):
                continue
            for flag in action.option_strings or [action.metavar or action.dest]:
                assert f"- `{flag}" in section, (name, flag)


def test_model_file_page_has_every_section_and_key(reference):
    page = reference.model_files_page()
    for section in SECTIONS.values():
        body = page.split(f"## `{section.name}`\n", 1)[1].split("\n## ", 1)[0]
        for key in section.keys:
            row = next((line for line in body.splitlines() if line.startswith(f"| `{key.name}` |")), None)
            assert row is not None, (section.name, key.name)
            assert ("**required**" in row) == key.required, (section.name, key.name)
            assert f"`{key.example}`" in row.replace("\\|", "|"), (section.name, key.name)


def test_every_reference_to_a_section_is_a_section():
    """The sections' texts name others as *name*: each must exist (the page links them)."""
    for section in SECTIONS.values():
        texts = [section.text] + [f"{key.type} {key.meaning}" for key in section.keys]
        for name in re.findall(r"\*([a-z_]+)\*", " ".join(texts)):
            assert name in SECTIONS, (section.name, name)
