"""Every command exits by the one table of mbsynth.cli.parsers (0 success, 1 a verdict, 2 bad
input, 3 a bug, 130 interrupted, 141 output closed), tested command by command with the
user's own command lines; each command's --help ends with its row of the table, and the
CLI reference prints the same table."""

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import pytest

from mbsynth.cli import main
from mbsynth.cli import check as check_command
from mbsynth.cli import simulate as simulate_command
from mbsynth.cli.parsers import EXIT_CODES, VERDICTS, exit_status, parser

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"
EXAMPLE3 = MODELS / "paper" / "example3_two_masses.yaml"
# x'' = 4 x³ from x = 1: the state runs away before t = 1 (the run has to stop), a dot to draw
RUNAWAY = ("parts:\n  a:\n    type: lagrangian\n    coordinates: [x]\n    T: 0.5*x_dot**2\n    V: -x**4\n"
           "    frames: {dot: {position: [x, 0, 0], geometry: {sphere: 0.1}}}\ninitial: {a.x: 1.0}\n")
# a constant force and nothing to balance it: no rest anywhere
NO_REST = "parts:\n  a: {type: lagrangian, coordinates: [x], T: 0.5*x_dot**2, V: x}\n"


def run(capsys, *words):
    code = main([str(w) for w in words])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def runaway(tmp_path):
    path = tmp_path / "runaway.yaml"
    path.write_text(RUNAWAY)
    return path


def test_every_commands_help_ends_with_its_row_of_the_table(capsys):
    top = parser()
    commands = next(a for a in top._actions if a.dest == "command").choices
    assert set(commands) == set(VERDICTS)
    for name in commands:
        with pytest.raises(SystemExit) as done:
            main([name, "--help"])
        assert done.value.code == 0
        text = " ".join(capsys.readouterr().out.split())
        assert text.endswith(" ".join(exit_status(name).split())), name
        for code in (0, 2, 3, 130, 141):
            assert f" {code} {EXIT_CODES[code].split()[0]}" in text, (name, code)
        assert ("; 1 a verdict" in text) == (VERDICTS[name] is not None), name


def test_the_cli_reference_prints_the_same_table():
    spec = importlib.util.spec_from_file_location("mbsynth_reference", ROOT / "docs" / "_ext" / "mbsynth_reference.py")
    reference = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(reference)
    page = reference.cli_page()
    table = page.split("## Exit status", 1)[1].split("\n(cli-", 1)[0]
    for code in EXIT_CODES:
        assert f"\n| {code} | " in table, code
    for name in VERDICTS:
        assert f"\n| `{name}` | " in table, name
        section = page.split(f"## `mbsynth {name}`", 1)[1].split("\n(cli-", 1)[0]
        assert section.strip().endswith(reference._escape(exit_status(name))), name


# --- check: 0 determined, 1 a balance missing, 2 bad input, 3 a bug

def test_check(capsys, tmp_path, monkeypatch):
    assert run(capsys, "check", MODELS / "paper" / "example1_wheel.yaml")[0] == 0
    open_model = tmp_path / "open.yaml"  # example 3 with m1 = 0 and no balance (5.40)
    open_model.write_text(EXAMPLE3.read_text().replace("m1: 1.5", "m1: 0.0"))
    code, out, _ = run(capsys, "check", open_model)
    assert code == 1 and "balance needed" in out
    code, out, _ = run(capsys, "check", tmp_path / "missing.yaml", "--json")
    assert code == 2 and "missing.yaml" in json.loads(out)["error"]
    monkeypatch.setattr(check_command, "diagnose", lambda system: 1 / 0)
    code, _, err = run(capsys, "check", EXAMPLE3)
    assert code == 3 and err.startswith("error: internal error, a bug in mbsynth (ZeroDivisionError")


# --- simulate: 0 completed, 1 the run had to stop, 2 bad input, 3 a bug

def test_simulate(capsys, tmp_path, runaway, monkeypatch):
    assert run(capsys, "simulate", EXAMPLE3, "--t-end", "0.1")[0] == 0
    code, out, _ = run(capsys, "simulate", runaway, "--t-end", "2", "--out", tmp_path / "run.npz", "--json")
    summary = json.loads(out)
    assert code == 1 and summary["status"] == "failed" and 0.5 < summary["t_end"] < 1.0
    assert run(capsys, "simulate", EXAMPLE3, "--t-end", "-1")[0] == 2
    monkeypatch.setattr(simulate_command, "simulate", lambda *args, **kwargs: [][0])
    code, out, _ = run(capsys, "simulate", EXAMPLE3, "--t-end", "0.1", "--json")
    assert code == 3 and "IndexError" in json.loads(out)["error"]


def test_an_interrupted_run_says_whether_it_wrote_anything(capsys, tmp_path, monkeypatch):
    """Ctrl-C before the run began (here: while the model loads): nothing was written, and
    it says so; an earlier run's file is left as it was, and said to be."""
    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(simulate_command, "model_of", interrupted)
    out = tmp_path / "run.npz"
    code, _, err = run(capsys, "simulate", EXAMPLE3, "--t-end", "1", "--out", out)
    assert code == 130 and err == f"error: interrupted; nothing was written to {out}\n" and not out.exists()
    out.write_bytes(b"an earlier run")
    code, stdout, _ = run(capsys, "simulate", EXAMPLE3, "--t-end", "1", "--out", out, "--json")
    assert code == 130 and json.loads(stdout)["error"] == f"interrupted; nothing was written ({out} is as it was)"
    assert out.read_bytes() == b"an earlier run"


# --- sweep: 0 every run ok, 1 a run failed, 2 bad input

def test_sweep(capsys, tmp_path, scheduler):
    common = ("--t-end", "0.2", "--dt", "0.05", "--scheduler", scheduler)
    assert run(capsys, "sweep", EXAMPLE3, "--param", "m1=1:2:2", "--out", tmp_path / "ok.csv", *common)[0] == 0
    code, out, _ = run(capsys, "sweep", EXAMPLE3, "--param", "m1=-1:1:2", "--out", tmp_path / "bad.csv", *common)
    assert code == 1 and "1 failed" in out and "not positive semi-definite" in out
    code, out, _ = run(capsys, "sweep", EXAMPLE3, "--param", "nosuch=1:2:2", "--out", tmp_path / "o.csv", *common,
                       "--json")
    assert code == 2 and "no parameter(s) ['nosuch']" in json.loads(out)["error"]


# --- view: 0 drawn, 1 the simulation had to stop (drawn up to there), 2 bad input

def test_view(capsys, tmp_path, runaway):
    assert run(capsys, "view", EXAMPLE3, "--t-end", "0.1", "--html", tmp_path / "ex3.html")[0] == 0
    code, out, err = run(capsys, "view", runaway, "--t-end", "2", "--html", tmp_path / "runaway.html")
    assert code == 1 and "drawing the motion up to there" in err and (tmp_path / "runaway.html").exists()
    assert run(capsys, "view", EXAMPLE3, "--t-end", "0.1", "--html", tmp_path / "v.txt")[0] == 2


# --- validate: 0 within the tolerance, 1 beyond it, 2 no Pinocchio twin

def test_validate(capsys):
    pd_pendulum = MODELS / "joints" / "pd_pendulum.yaml"
    assert run(capsys, "validate", pd_pendulum, "--samples", "2")[0] == 0
    code, out, _ = run(capsys, "validate", pd_pendulum, "--samples", "2", "--tolerance", "1e-300", "--json")
    assert code == 1 and json.loads(out)["passed"] is False
    code, _, err = run(capsys, "validate", EXAMPLE3, "--samples", "2")
    assert code == 2 and "has no equivalent Pinocchio model" in err


# --- modes: 0 at rest, 1 no rest state (also with --json), 2 bad input

def test_modes(capsys, tmp_path):
    code, out, _ = run(capsys, "modes", MODELS / "paper" / "example3_m1_zero_auto.yaml", "--equilibrium", "--json")
    assert code == 0 and len(json.loads(out)["modes"]) == 1
    pendulum = MODELS / "mechanisms" / "simple_pendulum.yaml"  # released at 90°: not at rest
    for json_flag in ((), ("--json",)):
        code, out, err = run(capsys, "modes", pendulum, *json_flag)
        message = json.loads(out)["error"] if json_flag else err
        assert code == 1 and "does not rest" in message, (code, out, err)
    no_rest = tmp_path / "pushed.yaml"
    no_rest.write_text(NO_REST)
    code, out, _ = run(capsys, "modes", no_rest, "--equilibrium", "--json")
    assert code == 1 and "no static equilibrium" in json.loads(out)["error"]
    assert run(capsys, "modes", pendulum, "--html", tmp_path / "modes.txt")[0] == 2


# --- robots: 0; a reader that closes the output early: 141, quietly

def test_robots(capsys):
    assert run(capsys, "robots", "--json")[0] == 0


def test_a_closed_output_exits_141_without_a_word():
    process = subprocess.Popen([sys.executable, "-m", "mbsynth.cli", "check", str(MODELS / "paper" / "example1_wheel.yaml")],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    process.stdout.close()  # as `| head` does once it has its lines
    err = process.stderr.read()
    assert process.wait(timeout=120) == 141 and err == b""
