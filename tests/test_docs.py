"""The generated reference pages (docs/_ext/mbsynth_reference.py) cover what they describe:
every ``mbsynth`` command and flag of the argparse parsers, every key of the loader's
schema. The site's math typesets offline: MathJax is served from the site's own _static,
never from a CDN, and no display formula puts a tag where MathJax refuses it. (The site
itself is built by ``make docs``, in CI after the tests; ``make docs`` then runs this file
again, so the checks of the built pages run there.)"""

import argparse
import importlib.util
import re
from pathlib import Path

import pytest

from mbsynth.cli.parsers import parser
from mbsynth.io.part_types import SECTIONS

DOCS = Path(__file__).parent.parent / "docs"
EXTENSION = DOCS / "_ext" / "mbsynth_reference.py"
SITE = DOCS / "_build" / "html"


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


def _conf():
    """docs/conf.py's settings, as Sphinx reads them."""
    namespace = {"__file__": str(DOCS / "conf.py")}
    exec(compile((DOCS / "conf.py").read_text(), str(DOCS / "conf.py"), "exec"), namespace)
    return namespace


def test_mathjax_is_configured_from_the_site():
    conf = _conf()
    assert "sphinx.ext.mathjax" in conf["extensions"]
    assert "sphinx-mathjax-offline" in conf["extensions"]  # copies MathJax into _static/mathjax
    path = conf["mathjax_path"]
    assert "://" not in path and not path.startswith("//"), path
    assert path.startswith("mathjax/"), path


def test_tagged_display_math_is_not_wrapped_in_split():
    """Sphinx wraps a $$ block holding a line break (``\\\\``) in ``split``, where MathJax
    typesets ``\\tag`` as an error: such a formula is written as ``\\begin{equation*}``."""
    offenders = []
    for page in sorted(DOCS.rglob("*.md")):
        if "_build" in page.parts:
            continue
        for block in re.findall(r"^\$\$\n(.*?)^\$\$", page.read_text(), flags=re.S | re.M):
            if "\\tag" in block and "\\\\" in block:
                offenders.append((page.name, block.strip()[:60]))
    assert not offenders, offenders


def _script_sources(html):
    return re.findall(r"<script\b[^>]*\bsrc=\"([^\"]+)\"", html)


@pytest.mark.skipif(not (SITE / "theory.html").exists(), reason="the site is not built (make docs)")
def test_built_site_loads_mathjax_locally():
    pages = sorted(SITE.rglob("*.html"))
    with_math = 0
    for page in pages:
        html = page.read_text(encoding="utf-8", errors="replace")
        assert "cdn.jsdelivr" not in html and "mathjax@" not in html.lower(), page
        for src in _script_sources(html):
            if "mathjax" not in src.lower():
                continue
            assert "://" not in src and not src.startswith("//"), (page, src)
            assert (page.parent / src.split("?")[0]).is_file(), (page, src)
            with_math += 1
    theory = (SITE / "theory.html").read_text(encoding="utf-8")
    assert any("mathjax" in src.lower() for src in _script_sources(theory))
    assert with_math >= 1
    assert (SITE / "_static" / "mathjax" / "tex-chtml.js").is_file()
    fonts = SITE / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2"
    assert any(fonts.glob("*.woff"))  # the fonts MathJax's CommonHTML output loads beside it


def test_the_guides_layout_names_every_module():
    """The guide's "Layout" section is the tree: every module of the package is named there
    (a package's __init__ by its folder)."""
    guide = (DOCS / "guide.md").read_text()
    layout = guide[guide.index("## Layout"):]
    package = DOCS.parent / "mbsynth"
    unnamed = [str(path.relative_to(package)) for path in sorted(package.rglob("*.py"))
               if (path.parent.name + "/" if path.name == "__init__.py" else path.name) not in layout]
    assert unnamed == []

