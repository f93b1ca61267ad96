"""Every shell command the README and the docs show (a ``$ .venv/bin/mbsynth ...`` line, in
the tour, getting started, the guide and the tutorials) runs as shown and exits as the page
says, and every file they name exists.

A command runs in a folder of its own that holds the repository's ``models/`` and an empty
``out/`` (the folder ``make run`` makes, the first step of the README's quick start), from
the command line the page shows, made shorter where it would take long: ``--t-end`` at most
SHORT_T_END (``view`` too, whose default is 5 s), ``--samples`` 1, a swept range 2 values, a
sweep on one shared in-process Dask cluster (``--scheduler``, instead of starting one per
command; ``--workers`` dropped with it). Commands that differ only in what is shortened run
once. Not run, only their paths checked: ``view`` without ``--html`` (LIVE: it serves a
live viewer until Ctrl-C). Files a page asks its reader to make (MADE_BY_THE_READER) are made
as the page says. Every path named on these pages (``models/...``, ``tests/...``,
``benchmarks/...``, ...) exists.

Every ```python block of the README and of docs/*.md runs as shown, each in a fresh
process in that folder (the tutorials' blocks run in order, one namespace per page:
test_tutorials.py); a block that cannot run says why on its first line (NOT_RUN)."""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from mbsynth.cli import main

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted(p for p in (ROOT / "docs").glob("*.md") if p.name not in ("cli.md", "model-files.md")),
         *sorted((ROOT / "docs" / "tutorials").glob("*.md"))]  # cli.md, model-files.md: generated from the code
PROMPT = re.compile(r"^[ \t]*\$ ((?:[^\n]*\\\n)*[^\n]*)", re.M)  # a "$ " line and its "\" continuations
PROGRAM = ".venv/bin/mbsynth"
SHORT_T_END = 0.2
INPUTS = ("--samples", "--trajectory")  # flags whose value is a file read
OUTPUTS = ("--out", "--plot", "--html", "--trajectories")  # flags whose value is written
SUFFIXES = (".yaml", ".yml", ".urdf", ".csv", ".npz", ".parquet", ".png", ".pdf", ".svg", ".html")
EXAMPLE3 = ROOT / "models" / "paper" / "example3_two_masses.yaml"
MADE_BY_THE_READER = {  # getting-started: "example 3 with m1: 0.0, no extra constraint"
    "open_model.yaml": lambda: EXAMPLE3.read_text().replace("m1: 1.5", "m1: 0.0"),
}
VERDICTS_SHOWN = {"check open_model.yaml": 1}  # the page shows the verdict: NOT unique, no motion
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.S | re.M)
NOT_RUN = "# not run: "  # a block's first line that says why it cannot run as shown
SNIPPET_PAGES = [page for page in PAGES if page.parent.name != "tutorials"]  # the tutorials: test_tutorials.py
SNIPPET_TIMEOUT = 240  # seconds: a block runs in seconds; this bounds a hang
NAMED = re.compile(r"(?<![\w/.-])((?:models|benchmarks|examples|tests|mbsynth|docs|scripts)/[\w./*-]*[\w*])")


def shown_commands():
    """(page name, command words without the program) of every command line shown."""
    found = []
    for page in PAGES:
        for match in PROMPT.finditer(page.read_text()):
            words = shlex.split(match.group(1).replace("\\\n", " "), comments=True)
            found.append((page.relative_to(ROOT).as_posix(), words))
    return found


def live(words):
    """Whether the command line (the program first) serves a live viewer."""
    return words[1] == "view" and "--html" not in words


def shortened(words):
    """The command as the test runs it (see the module docstring)."""
    words = list(words)
    if words[0] == "view" and "--t-end" not in words:
        words += ["--t-end", str(SHORT_T_END)]
    for i, word in enumerate(words[:-1]):
        value = words[i + 1]
        if word == "--t-end":
            words[i + 1] = str(min(float(value), SHORT_T_END))
        elif word == "--samples" and value.isdigit():
            words[i + 1] = "1"
        elif word == "--param":
            name, _, spec = value.partition("=")
            start, stop, count = spec.split(":")
            words[i + 1] = f"{name}={start}:{stop}:{min(int(count), 2)}"
    if words[0] == "sweep" and "--workers" in words:
        at = words.index("--workers")
        del words[at:at + 2]
    return words


def paths(words):
    """(path, read) of every file a command line names: read (an input) or written."""
    named = []
    for i, word in enumerate(words[1:], start=1):
        flag = words[i - 1]
        if word.startswith("-") or flag in ("--param", "--metric") or not (word.endswith(SUFFIXES) or "/" in word):
            continue
        if flag in OUTPUTS:
            named.append((word, False))
        elif flag in INPUTS or not flag.startswith("-"):
            named.append((word, True))
    return named


COMMANDS = shown_commands()
TO_RUN = {}  # shortened command line -> the page that shows it first
for _page, _words in COMMANDS:
    if not live(_words):
        TO_RUN.setdefault(" ".join(shortened(_words[1:])), _page)


def test_the_pages_show_commands():
    assert len(COMMANDS) >= 20 and any(live(words) for _, words in COMMANDS)
    assert {words[1] for _, words in COMMANDS} >= {"check", "simulate", "sweep", "view", "validate", "modes"}


@pytest.mark.parametrize("page, words", COMMANDS, ids=[" ".join(w[1:]) for _, w in COMMANDS])
def test_every_command_is_mbsynth_and_names_files_that_exist(page, words):
    assert words[0] == PROGRAM, f"{page}: a command the docs test cannot run: {' '.join(words)}"
    for path, read in paths(words[1:]):
        if read:
            assert (ROOT / path).is_file() or path in MADE_BY_THE_READER, f"{page}: {path} does not exist"
        else:
            assert Path(path).parent.as_posix() in (".", "out"), f"{page}: writes into a folder no step makes: {path}"


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """The reader's folder: the repository's models, the out/ of `make run`, their own files."""
    folder = tmp_path_factory.mktemp("reader")
    (folder / "models").symlink_to(ROOT / "models")
    (folder / "out").mkdir()
    for name, text in MADE_BY_THE_READER.items():
        (folder / name).write_text(text())
    return folder


@pytest.mark.slow  # every command the pages show, run: simulations, sweeps, robots' validations
@pytest.mark.parametrize("line", sorted(TO_RUN), ids=sorted(TO_RUN))
def test_every_command_runs_as_shown(line, workdir, request, monkeypatch, capsys):
    monkeypatch.chdir(workdir)
    monkeypatch.setenv("MPLBACKEND", "agg")
    words = shlex.split(line)
    if words[0] == "sweep":
        words += ["--scheduler", request.getfixturevalue("scheduler")]
    code = main(words)
    out, err = capsys.readouterr()
    assert code == VERDICTS_SHOWN.get(line, 0), f"{TO_RUN[line]}: mbsynth {line} exited {code}: {err or out}"


BUILT = "docs/_build"  # made by `make docs` (the pages say so), absent from a fresh clone


def test_every_path_the_pages_name_exists():
    missing = []
    for page in PAGES:
        for path in NAMED.findall(page.read_text()):
            if path.startswith(BUILT):
                continue
            if not (any(ROOT.glob(path)) if "*" in path else (ROOT / path).exists()):
                missing.append(f"{page.relative_to(ROOT)}: {path}")
    assert missing == []


def test_shortening_keeps_the_command():
    line = "sweep models/m.yaml --param k1=40:160:10 --t-end 8 --samples 5 --workers 2 --out out/r.csv"
    assert " ".join(shortened(line.split())) == (
        "sweep models/m.yaml --param k1=40:160:2 --t-end 0.2 --samples 1 --out out/r.csv")
    assert shortened(["view", "m.yaml", "--html", "v.html"])[-2:] == ["--t-end", "0.2"]
    assert paths(["simulate", "models/m.yaml", "--t-end", "1", "--out", "run.npz", "--plot", "out/p.png"]) == [
        ("models/m.yaml", True), ("run.npz", False), ("out/p.png", False)]


def shown_snippets():
    """(page name, number on the page, code) of every ```python block."""
    return [(page.relative_to(ROOT).as_posix(), k, code) for page in SNIPPET_PAGES
            for k, code in enumerate(BLOCK.findall(page.read_text()), start=1)]


SNIPPETS = shown_snippets()


def test_the_pages_show_python_blocks():
    assert {page for page, _, _ in SNIPPETS} >= {"README.md", "docs/api.md", "docs/guide.md"}


@pytest.mark.slow  # every block the pages show, each in a fresh interpreter
@pytest.mark.parametrize("page, number, code", SNIPPETS, ids=[f"{page}:{k}" for page, k, _ in SNIPPETS])
def test_every_python_block_runs_as_shown(page, number, code, workdir):
    if code.startswith(NOT_RUN):
        pytest.skip(f"{page}, block {number}: {code.splitlines()[0][len(NOT_RUN):]}")
    env = {**os.environ, "MPLBACKEND": "agg",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    done = subprocess.run([sys.executable, "-c", code], cwd=workdir, env=env, capture_output=True, text=True,
                          timeout=SNIPPET_TIMEOUT)
    assert done.returncode == 0, f"{page}, python block {number}:\n{done.stderr[-3000:]}"


def test_the_readme_states_what_the_quick_start_needs():
    """The README's quick start names what a fresh machine needs, as the project declares
    it: the Python of pyproject.toml's requires-python with venv (the Makefile's first
    step), make, the network, the disk, and Chromium installed by `make test` as root."""
    import tomllib
    readme = (ROOT / "README.md").read_text()
    quick_start = readme.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    oldest = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["requires-python"].removeprefix(">=")
    assert f"Python {oldest} or newer with its `venv` module" in quick_start
    assert "-m venv" in (ROOT / "Makefile").read_text() and "apt-get install" in (
        ROOT / "scripts" / "install-chromium.sh").read_text()
    for needed in ("`make`", "the network", "GB of disk", "Chromium", "scripts/install-chromium.sh", "minutes"):
        assert needed in quick_start, needed
