"""The files a command writes, by one rule for every output flag of every command
(mbsynth/cli/outputs.py), and what the command says when it cannot finish them, tested
with the user's own command lines in a fresh process:

- an output that cannot be written is refused before the run (exit 2, the flag, the path
  and why), for every output flag; its suffix is read in any case (``run.NPZ``);
- Ctrl-C says of each output what was left of it; --debug adds the traceback to every
  failure's one line;
- a run's .npz records its model and parameters, and ``view --trajectory`` draws it with them.

A failure at a chosen point of a command (Ctrl-C there, a full disk, a bug) comes from
HOOKED: the command run as ``python -m mbsynth.cli`` does, with one function of mbsynth
wrapped to send the process a real SIGINT, or raise, when it is called."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from tests.helpers.processes import HANG

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.view import viewer

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE3 = ROOT / "models" / "paper" / "example3_two_masses.yaml"
AUTO = ROOT / "models" / "paper" / "example3_m1_zero_auto.yaml"  # modes --equilibrium: one mode
# a pendulum of length L drawn as a dot: what a run with --set L=4 looks like differs
PENDULUM = """\
name: rod
parameters: {L: 1.0, g: 9.81}
parts:
  bob:
    type: lagrangian
    coordinates: [x, y]
    T: 0.5*(x_dot**2 + y_dot**2)
    V: g*y
    frames: {dot: {position: [x, y, 0], geometry: {sphere: 0.1}}}
constraints:
  - {name: rod, holonomic: bob.x**2 + bob.y**2 - L**2}
initial: {bob.x: L, bob.y: 0}
"""
# two rows no position meets: no consistent initial state (SolveError)
CONTRADICTION = ("parts:\n  a: {type: lagrangian, coordinates: [x], T: 0.5*x_dot**2, V: 0}\n"
                 "constraints:\n  - {name: here, holonomic: a.x}\n  - {name: there, holonomic: a.x - 1}\n")
HOOKED = """\
import importlib, os, runpy, signal, sys
module, name, action = sys.argv[1:4]
owner = importlib.import_module(module)
*path, attribute = name.split(".")
for part in path:
    owner = getattr(owner, part)
real = getattr(owner, attribute)
def hooked(*args, **kwargs):
    if action == "interrupt":
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C, here
    elif action == "disk full":
        raise OSError(28, "No space left on device")
    elif action == "bug":
        raise ZeroDivisionError("a bug here")
    return real(*args, **kwargs)
setattr(owner, attribute, hooked)
signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal, also in a test run in the background
sys.argv = ["mbsynth", *sys.argv[4:]]
runpy.run_module("mbsynth.cli", run_name="__main__", alter_sys=True)
"""


def mbsynth(*words, cwd=None):
    """``python -m mbsynth.cli WORDS`` run to its end: (exit status, stdout, stderr)."""
    result = subprocess.run([sys.executable, "-m", "mbsynth.cli", *map(str, words)], capture_output=True, text=True,
                            cwd=cwd, timeout=HANG, check=False)
    return result.returncode, result.stdout, result.stderr


def hooked(function, action, *words, cwd=None):
    """As ``mbsynth``, with ``function`` ("module:Name.attribute") doing ``action`` first
    when it is called (HOOKED)."""
    module, name = function.split(":")
    result = subprocess.run([sys.executable, "-c", HOOKED, module, name, action, *map(str, words)],
                            capture_output=True, text=True, cwd=cwd, timeout=HANG, check=False)
    return result.returncode, result.stdout, result.stderr


# --- --debug: the traceback on every failure path, and only with --debug

def _failures(folder):
    """(what fails, how to run it, exit status, the end of its one line), one per path of main."""
    (folder / "contradiction.yaml").write_text(CONTRADICTION)
    return [
        ("model error", (mbsynth, "check", folder / "missing.yaml"), 2, "missing.yaml: no such model file"),
        ("solve error", (mbsynth, "simulate", folder / "contradiction.yaml", "--t-end", "1"), 2,
         "(no change of the positions lowers it, to first or second order)"),
        ("OS error", (hooked, "mbsynth.view.plot:write_atomically", "disk full", "simulate", EXAMPLE3, "--t-end",
                      "0.1", "--plot", folder / "p.png"), 2, "No space left on device"),
        ("bug", (hooked, "mbsynth.cli.check:diagnose", "bug", "check", EXAMPLE3), 3,
         "(ZeroDivisionError: a bug here); --debug shows where"),
        ("interrupt", (hooked, "mbsynth.cli.check:diagnose", "interrupt", "check", EXAMPLE3), 130, "interrupted"),
    ]


@pytest.mark.parametrize("case", range(5), ids=["model error", "solve error", "OS error", "bug", "interrupt"])
def test_debug_prints_the_traceback_of_every_failure(tmp_path, case):
    """The same failure without and with --debug: one line, then the traceback (of the
    exception that made it, on stderr) and the same line."""
    name, (run, *words), status, ending = _failures(tmp_path)[case]
    head = words[:2] if run is hooked else []
    code, out, err = run(*head, *words[len(head):])
    assert code == status and out == "" and err.startswith("error: ") and err.endswith(f"{ending}\n"), (code, err)
    assert err.count("\n") == 1, err
    code, out, debug = run(*head, "--debug", *words[len(head):])
    assert code == status and debug.startswith("Traceback (most recent call last):\n"), (code, debug)
    assert debug.endswith("\n" + err), debug
    raised = {"model error": "ModelError", "solve error": "SolveError", "OS error": "OSError",
              "bug": "ZeroDivisionError", "interrupt": "KeyboardInterrupt"}[name]
    assert f"\n{raised}" in debug or f".{raised}: " in debug, debug


# --- every output flag is checked before the run

# (command line with {bad}: the output flag's path, that flag), each run long enough that a
# check after it would not end within the test's time
OUTPUT_FLAGS = [
    ("simulate {model} --t-end 1e5 --out {bad}.npz", "--out"),
    ("simulate {model} --t-end 1e5 --out {d}/run.npz --plot {bad}.png", "--plot"),
    ("view {model} --t-end 1e5 --html {bad}.html", "--html"),
    ("modes {auto} --equilibrium --html {bad}.html", "--html"),
    ("sweep {model} --param m1=1:2:2 --t-end 1e5 --workers 1 --out {bad}.csv", "--out"),
    ("sweep {model} --param m1=1:2:2 --t-end 1e5 --workers 1 --out {d}/o.csv --trajectories {bad}", "--trajectories"),
]


@pytest.mark.parametrize("line,flag", OUTPUT_FLAGS, ids=[f"{line.split()[0]} {flag}" for line, flag in OUTPUT_FLAGS])
@pytest.mark.parametrize("bad", ["the other kind", "/proc", "under a file"])
def test_an_output_that_cannot_be_written_is_refused_before_the_run(tmp_path, line, flag, bad):
    """The user's --plot, --html or --out naming a folder (--trajectories a file), a place
    in /proc or a path under a file: exit 2 at once, naming the flag, the path and why;
    nothing is written."""
    if bad == "/proc" and not Path("/proc/self").exists():
        pytest.skip("no /proc here")
    (tmp_path / "a_file").write_text("")
    base = {"the other kind": tmp_path / "out", "/proc": Path("/proc/out"),
            "under a file": tmp_path / "a_file" / "out"}[bad]
    words = line.format(model=EXAMPLE3, auto=AUTO, d=tmp_path, bad=base).split()
    path = Path(words[words.index(flag) + 1])
    takes_a_folder = flag == "--trajectories"
    if bad == "the other kind" and takes_a_folder:
        path.write_text("")
    elif bad == "the other kind":
        path.mkdir()
    why = {"the other kind": f"{path} is a file, not a folder" if takes_a_folder else f"{path} is a folder",
           "/proc": "no file can be created in /proc (No such file or directory)",
           "under a file": f"{tmp_path}/a_file is not a folder"}[bad]
    before = sorted(tmp_path.iterdir())
    code, out, err = mbsynth(*words)
    assert code == 2 and err == f"error: {flag} {path}: cannot be written there: {why}\n", (code, err)
    assert sorted(tmp_path.iterdir()) == before  # no run started: not even its --out


def test_an_output_folder_given_as_a_csv_leaves_no_partial_file(tmp_path):
    """`simulate --out d.csv` where d.csv is a folder: refused, and no d.csv.partial is made
    (by the command, or by mb.simulate given that path)."""
    (tmp_path / "d.csv").mkdir()
    code, _, err = mbsynth("simulate", EXAMPLE3, "--t-end", "0.1", "--out", tmp_path / "d.csv")
    folder = tmp_path / "d.csv"
    assert code == 2 and err == f"error: --out {folder}: cannot be written there: {folder} is a folder\n"
    with pytest.raises(mb.ModelError, match="d.csv is a folder"):
        mb.simulate(mb.load(EXAMPLE3), 0.1, out=tmp_path / "d.csv")
    assert [p.name for p in tmp_path.iterdir()] == ["d.csv"]


def test_an_output_suffix_is_read_in_any_case(tmp_path):
    """run.NPZ is an .npz file, p.PNG a PNG figure, run.CSV a CSV table, V.HTML a page;
    run.txt is none of them, refused with the suffixes the flag takes."""
    code, out, err = mbsynth("simulate", EXAMPLE3, "--t-end", "0.1", "--out", "run.NPZ", "--plot", "p.PNG",
                             cwd=tmp_path)
    assert code == 0 and "wrote run.NPZ" in out and "wrote p.PNG" in out, err
    saved = mb.load_trajectory(tmp_path / "run.NPZ")
    assert saved.t[-1] == pytest.approx(0.1) and saved.status == "completed"
    assert (tmp_path / "p.PNG").read_bytes().startswith(b"\x89PNG")
    code, out, err = mbsynth("simulate", EXAMPLE3, "--t-end", "0.1", "--out", "run.CSV", cwd=tmp_path)
    assert code == 0 and "wrote run.CSV" in out, err
    np.testing.assert_array_equal(mb.load_trajectory(tmp_path / "run.CSV").q, saved.q)
    code, out, err = mbsynth("view", EXAMPLE3, "--trajectory", "run.NPZ", "--html", "V.HTML", cwd=tmp_path)
    assert code == 0 and "<!DOCTYPE html>" in (tmp_path / "V.HTML").read_text(), err
    code, out, err = mbsynth("simulate", EXAMPLE3, "--t-end", "0.1", "--out", "run.txt", "--json", cwd=tmp_path)
    assert code == 2 and json.loads(out)["error"] == "--out run.txt: the file must end in .npz, .csv"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["V.HTML", "p.PNG", "run.CSV", "run.NPZ"]


# --- Ctrl-C: what was left of each output

def test_ctrl_c_in_view_html_says_nothing_was_written(tmp_path):
    """Ctrl-C while the page is made: exit 130, nothing written; an earlier page is as it was."""
    page = tmp_path / "v.html"
    code, _, err = hooked("mbsynth.view.viewer:MeshcatView.html", "interrupt",
                          "view", EXAMPLE3, "--t-end", "0.1", "--html", page)
    assert code == 130 and err == f"error: interrupted; nothing was written to {page}\n" and not page.exists()
    page.write_text("an earlier page")
    code, _, err = hooked("mbsynth.view.viewer:MeshcatView.html", "interrupt",
                          "view", EXAMPLE3, "--t-end", "0.1", "--html", page)
    assert code == 130 and err == f"error: interrupted; nothing was written ({page} is as it was)\n"
    assert page.read_text() == "an earlier page" and sorted(tmp_path.iterdir()) == [page]


def test_ctrl_c_in_modes_html_says_nothing_was_written(tmp_path):
    page = tmp_path / "modes.html"
    code, out, err = hooked("mbsynth.view.viewer:MeshcatView.html", "interrupt",
                            "modes", AUTO, "--equilibrium", "--html", page)
    assert code == 130 and err == f"error: interrupted; nothing was written to {page}\n" and not page.exists()
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_during_the_plot_names_each_output(tmp_path):
    """The run is done and in --out; Ctrl-C while the figure is drawn: both said."""
    out, plot = tmp_path / "run.npz", tmp_path / "p.png"
    code, _, err = hooked("mbsynth.view.plot:plot_trajectory", "interrupt",
                          "simulate", EXAMPLE3, "--t-end", "0.1", "--out", out, "--plot", plot)
    assert code == 130 and err == f"error: interrupted; the output so far is in {out}; nothing was written to {plot}\n"
    assert mb.load_trajectory(out).t[-1] == pytest.approx(0.1) and not plot.exists()


# --- a run's .npz records its model and parameters; view --trajectory draws with them

@pytest.fixture
def run_with_l4(tmp_path):
    """A pendulum model (L = 1 in its file) and a run of it made with --set L=4."""
    model = tmp_path / "rod.yaml"
    model.write_text(PENDULUM)
    code, _, err = mbsynth("simulate", model, "--set", "L=4", "--t-end", "0.2", "--out", "run.npz", cwd=tmp_path)
    assert code == 0, err
    return model, tmp_path / "run.npz"


def test_a_run_records_its_model_and_parameters(run_with_l4, tmp_path):
    model, run = run_with_l4
    saved = mb.load_trajectory(run)
    assert saved.model == "rod" and saved.model_file == str(model.resolve())
    assert saved.parameters == {"L": 4.0, "g": 9.81}
    np.testing.assert_allclose(np.hypot(saved.q[:, 0], saved.q[:, 1]), 4.0, rtol=1e-9)  # the run's rod is 4 m
    copy = tmp_path / "copy.npz"
    saved.save(copy)
    assert mb.load_trajectory(copy).parameters == saved.parameters


def test_view_draws_a_run_with_the_parameters_it_was_made_with(run_with_l4, tmp_path):
    """`view rod.yaml --trajectory run.npz` (the run had --set L=4): drawn with L = 4, a note
    on stderr; `--set L=4` too: no note; `--set L=3`: refused, naming both values."""
    model, run = run_with_l4
    code, out, err = mbsynth("view", model, "--trajectory", run, "--html", tmp_path / "v.html")
    assert code == 0 and err == (f"note: drawing {run} with the parameters it was run with, L=4 ({model} has L=1)\n")
    code, out, err = mbsynth("view", model, "--set", "L=4", "--trajectory", run, "--html", tmp_path / "v.html")
    assert code == 0 and err == "", err
    code, out, err = mbsynth("view", model, "--set", "L=3", "--trajectory", run, "--html", tmp_path / "v.html")
    assert code == 2 and err == (f"error: --trajectory {run} was run with L=4; --set L=3 differs: draw the run as it "
                                 "was made (leave that --set out) or give the run's values\n")


def test_the_drawn_model_has_the_runs_parameters(run_with_l4, tmp_path, monkeypatch, capsys):
    """What `view --trajectory` draws: the model with L = 4, not the file's L = 1."""
    model, run = run_with_l4
    drawn = []
    monkeypatch.setattr(viewer, "to_html", lambda system, traj, path, **options: drawn.append(system) or Path(path))
    assert main(["view", str(model), "--trajectory", str(run), "--html", str(tmp_path / "v.html")]) == 0
    assert drawn[0].parameters == {"L": 4.0, "g": 9.81}
    q, _ = drawn[0].initial_state()
    assert q.tolist() == [4.0, 0.0]  # the initial state written with L follows
