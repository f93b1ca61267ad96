"""Every error a user can cause on the command line exits non-zero with one readable line
on stderr (a traceback only with --debug); with --json, stdout is one JSON object
{"error": ...} even then. Argparse's own usage errors keep exit 2."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from tests.helpers.processes import HANG, ended_within, meshcat_servers, needs_proc, readline_within, running

from mbsynth.cli import simulate as simulate_command
from mbsynth.cli import main
from mbsynth.analysis.trajectory import load_trajectory

ROOT = Path(__file__).resolve().parents[2]
MODEL = str(ROOT / "models" / "paper" / "example3_two_masses.yaml")


@pytest.fixture
def files(tmp_path):
    """Paths a user might give by mistake."""
    (tmp_path / "folder.yaml").mkdir()
    (tmp_path / "picture.png").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)))
    (tmp_path / "table.csv").write_text("a,b\n1,2\n")
    (tmp_path / "bad.yaml").write_text("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**}\n")
    (tmp_path / "a_file").write_text("")
    return tmp_path


# (command line with {d} for the folder of ``files``, whether it has --json)
BAD_INPUT = ["{d}/missing.yaml", "{d}/folder.yaml", "{d}/picture.png", "{d}/table.csv", "{d}/bad.yaml"]
COMMANDS = {
    "check": ("check {model}", True),
    "simulate": ("simulate {model} --t-end 1", True),
    "sweep": ("sweep {model} --param m1=1:2:2 --t-end 1 --out {d}/out.csv --workers 1", True),
    "view": ("view {model} --t-end 0.1 --html {d}/out.html", False),
    "validate": ("validate {model} --samples 2", True),
}
BAD_FLAGS = [
    "simulate {m} --t-end -1", "simulate {m} --t-end 0", "simulate {m} --t-end nan", "simulate {m} --t-end 1 --dt -0.1",
    "simulate {m} --t-end 1 --dt 0", "simulate {m} --t-end 1 --rtol -1", "simulate {m} --t-end 1 --atol 0",
    "simulate {m} --t-end 1 --method nosuch", "simulate {m} --t-end 1 --out {d}/nofolder/run.npz",
    "simulate {m} --t-end 1 --out {d}/a_file/run.npz", "simulate {m} --t-end 1 --out {d}/run.txt",
    "simulate {m} --t-end 1 --out /proc/run.npz", "simulate {m} --t-end 0.1 --plot {d}/nofolder/p.png",
    "simulate {m} --t-end 0.1 --plot {d}/p.xyz",
    "sweep {m} --param m1 --t-end 1 --out {d}/o.csv", "sweep {m} --param m1=1:2:0 --t-end 1 --out {d}/o.csv",
    "sweep {m} --param nosuch=1:2:2 --t-end 1 --out {d}/o.csv", "sweep {m} --param m1=1:2:2 --t-end -1 --out {d}/o.csv",
    "sweep {m} --param m1=1:2:2 --t-end 1 --out {d}/nofolder/o.csv",
    "sweep {m} --param m1=1:2:2 --t-end 1 --out {d}/o.txt",
    "sweep {m} --samples {d}/missing.csv --t-end 1 --out {d}/o.csv",
    "sweep {m} --param m1=1:2:2 --t-end 1 --out {d}/o.csv --workers 0",
    "view {m} --t-end -1 --html {d}/v.html", "view {m} --t-end 0.1 --html {d}/nofolder/v.html",
    "view {m} --trajectory {d}/missing.npz --html {d}/v.html",
    "view {m} --trajectory {d}/picture.png --html {d}/v.html",
    "view {m} --trajectory {d}/table.csv --html {d}/v.html",
    "validate {m} --samples 0", "validate {m} --samples 2 --tolerance -1", "validate nosuch_robot",
]


def run(capsys, line):
    code = main(line.split())
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(code, out, err):
    assert code == 2, (code, out, err)  # a user's error (3 would be a bug caught at the top)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err


def assert_json_error(code, out, err):
    assert code == 2, (code, out, err)
    data = json.loads(out)
    assert isinstance(data["error"], str) and data["error"] and "\n" not in data["error"]
    assert "Traceback" not in err


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize("model", BAD_INPUT, ids=lambda m: m.split("/")[-1])
def test_bad_model_files(capsys, files, command, model):
    template, has_json = COMMANDS[command]
    line = template.format(model=model.format(d=files), d=files)
    assert_one_line_error(*run(capsys, line))
    if has_json:
        assert_json_error(*run(capsys, line + " --json"))


@pytest.mark.parametrize("line", BAD_FLAGS)
def test_bad_flag_values_and_unwritable_outputs(capsys, files, line):
    line = line.format(m=MODEL, d=files)
    assert_one_line_error(*run(capsys, line))
    if not line.startswith("view"):
        assert_json_error(*run(capsys, line + " --json"))


def test_debug_shows_the_traceback(capsys, files):
    code, _, err = run(capsys, f"--debug check {files}/bad.yaml")
    assert code == 2 and "Traceback" in err and err.strip().splitlines()[-1].startswith("error: ")


def test_usage_errors_stay_argparse_exit_2(capsys):
    for line in ("simulate", "simulate model.yaml", "simulate model.yaml --t-end abc", "nosuch"):
        with pytest.raises(SystemExit) as exit_:
            main(line.split())
        assert exit_.value.code == 2
        assert "usage:" in capsys.readouterr().err


@pytest.mark.parametrize("line", ["simulate {m} --t-end abc", "sweep {m} --param m1=1:2:2 --t-end 1 --out o.csv "
                                  "--workers two", "check {m} --nosuch", "check"])
def test_usage_errors_with_json_are_one_json_object(capsys, line):
    code, out, err = run(capsys, line.format(m=MODEL) + " --json")
    assert_json_error(code, out, err)
    assert "usage:" not in err and json.loads(out)["error"].startswith("mbsynth")


def test_ctrl_c_keeps_the_output_and_exits_130(capsys, tmp_path, monkeypatch):
    """Ctrl-C in the middle of a run: one line, exit 130 (128 + SIGINT), the rows computed
    so far in --out, JSON with --json."""
    real = simulate_command.simulate

    def interrupted(*args, **kwargs):
        def progress(t):
            if t > 0.5:
                raise KeyboardInterrupt
        return real(*args, **dict(kwargs, progress=progress))

    monkeypatch.setattr(simulate_command, "simulate", interrupted)
    out = tmp_path / "run.npz"
    code, stdout, err = run(capsys, f"simulate {MODEL} --t-end 1 --out {out}")
    assert code == 130 and err.strip().count("\n") == 0 and "interrupted" in err and str(out) in err
    saved = load_trajectory(out)
    assert 0.5 < saved.t[-1] < 0.51 and np.all(np.diff(saved.t) > 0)
    code, stdout, err = run(capsys, f"simulate {MODEL} --t-end 1 --out {out} --json")
    assert code == 130 and "interrupted" in json.loads(stdout)["error"]
    out = tmp_path / "run.csv"  # an interrupted CSV run keeps its rows in FILE.partial, and says so
    code, stdout, err = run(capsys, f"simulate {MODEL} --t-end 1 --out {out}")
    assert code == 130 and err.strip().endswith(f"the output so far is in {out}.partial") and not out.exists()
    assert 0.5 < load_trajectory(f"{out}.partial").t[-1] < 0.51


@needs_proc
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL], ids=lambda s: s.name)
def test_the_live_viewer_and_its_meshcat_server_end_together(signum):
    """``mbsynth view`` serving a model: SIGINT (Ctrl-C) or SIGTERM stops it, exit 130, one
    line; after any of them, SIGKILL of the viewer included, its meshcat server ends too.
    The viewer starts with SIGINT at its default, as a terminal's foreground command does: a
    test run started in the background of a shell (``make test &``) ignores SIGINT, and a
    Python child keeps an inherited SIG_IGN."""
    process = subprocess.Popen([sys.executable, "-m", "mbsynth.cli", "view", MODEL, "--t-end", "0.2"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    servers = []
    try:
        line = readline_within(process.stdout, HANG)
        assert "meshcat viewer of" in line, (line, process.poll())  # serving now
        servers = meshcat_servers(process.pid)
        assert len(servers) == 1, servers
        process.send_signal(signum)
        _, err = process.communicate(timeout=HANG)
        assert ended_within(servers[0], HANG), servers
    finally:
        process.kill()
        process.wait()
        for pid, started in servers:
            if running(pid, started):
                os.kill(pid, signal.SIGKILL)
    if signum == signal.SIGKILL:
        assert process.returncode == -signal.SIGKILL
    else:
        assert process.returncode == 130 and err.strip() == "error: interrupted", (process.returncode, err)


def test_the_installed_command_prints_one_line_without_traceback(files):
    result = subprocess.run([sys.executable, "-m", "mbsynth.cli", "simulate", MODEL, "--t-end", "-1"],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: --t-end")


def test_an_unknown_plot_var_is_refused_before_the_run(capsys, tmp_path, monkeypatch):
    """The user's `--plot-vars bob.q` (the pendulum's coordinates are bob.x, bob.y): exit 2
    with the names it has, and no run (simulate is never called)."""
    monkeypatch.setattr(simulate_command, "simulate", lambda *args, **kwargs: pytest.fail("the run started"))
    pendulum = ROOT / "models" / "mechanisms" / "simple_pendulum.yaml"
    code, out, err = run(capsys, f"simulate {pendulum} --t-end 1 --plot {tmp_path}/p.png --plot-vars bob.x bob.q")
    assert code == 2 and err == ("error: --plot-vars bob.q: model 'simple_pendulum' has no such coordinate, "
                                 "velocity or output; its coordinates: bob.x, bob.y (velocities: each with _dot); "
                                 "it declares no outputs\n")
    assert not (tmp_path / "p.png").exists()


def test_plot_vars_without_plot_is_refused(capsys, monkeypatch):
    monkeypatch.setattr(simulate_command, "simulate", lambda *args, **kwargs: pytest.fail("the run started"))
    code, out, err = run(capsys, f"simulate {MODEL} --t-end 1 --plot-vars body1.x1 --json")
    assert code == 2 and "give the figure's file with --plot FILE.png too" in json.loads(out)["error"]


def test_plot_vars_draws_coordinates_velocities_and_outputs(capsys, tmp_path):
    """Each kind of name --plot-vars takes is drawn (the figure is written, exit 0)."""
    model = tmp_path / "outputs.yaml"
    model.write_text(Path(MODEL).read_text() + "outputs:\n  stretch: body2.q2 - body2.q1\n")
    code, _, err = run(capsys, f"simulate {model} --t-end 0.1 --plot {tmp_path}/p.png "
                               "--plot-vars body1.x1 body1.x1_dot stretch")
    assert code == 0 and (tmp_path / "p.png").stat().st_size > 0, err
