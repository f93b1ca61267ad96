"""`mbsynth check` on the paper's models: ranks, verdicts and balances (Result 3)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from mbsynth.cli import main
from mbsynth.core.expressions import parse

MODELS = Path(__file__).resolve().parents[2] / "models" / "paper"


def check_json(capsys, path):
    code = main(["check", str(path), "--json"])
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("name, n, m, rank_M, rank_A", [
    ("example1_wheel.yaml", 2, 1, 1, 1),                 # (5.6), (5.10)
    ("example3_two_masses.yaml", 3, 1, 2, 1),            # (5.33), (5.35)
    ("example3_m1_zero.yaml", 3, 2, 1, 2),               # (5.42), (5.46)
    ("example3_m2_zero.yaml", 3, 2, 1, 2),               # (5.51), (5.55)
    ("example3_m1_zero_auto.yaml", 3, 2, 1, 2),
    ("example3_m2_zero_auto.yaml", 3, 2, 1, 2),
])
def test_unique_models(capsys, name, n, m, rank_M, rank_A):
    code, report = check_json(capsys, MODELS / name)
    assert code == 0
    assert (report["n"], report["m"], report["rank_M"], report["rank_A"], report["rank_Mhat"]) == (
        n, m, rank_M, rank_A, n)
    assert report["unique"] and report["indeterminate"] == [] and report["suggested_constraints"] == []
    assert report["consistent"]


def test_check_compiles_nothing_and_leaves_the_default_path_as_it_was(capsys, monkeypatch):
    """``check`` computes on the KKT path where the user left MBSYNTH_COMPILED unset, and only
    while it runs: the models simulated after it in the same process (as in this test
    session) still get the compiled path; a value the user set is kept."""
    from mbsynth.compiled import background
    monkeypatch.delenv("MBSYNTH_COMPILED", raising=False)
    seen = []  # Templates put to build
    monkeypatch.setattr(background, "_submit", lambda *args: seen.append("engine"))
    assert main(["check", str(MODELS.parent / "robots" / "ur5_payload.yaml")]) == 0
    assert "MBSYNTH_COMPILED" not in os.environ and background.default_path() == "compiled" and seen == []
    with background.default_path_as("kkt"):
        assert background.default_path() == "kkt"
        monkeypatch.setenv("MBSYNTH_COMPILED", "on")
        assert background.default_path() == "compiled"


def test_massless_particle_is_a_free_direction(capsys):
    code, report = check_json(capsys, MODELS / "example2_massless_particle.yaml")
    assert code == 0
    assert not report["unique"] and report["rank_Mhat"] == 2
    assert report["indeterminate"] == [{"particle.x": 1.0}]        # (5.23): η on x
    assert report["balances"] == [{"direction": {"particle.x": 1.0}, "free": True, "equation": None}]
    assert report["suggested_constraints"] == []


@pytest.mark.parametrize("mass, balance", [
    ("m1", lambda k1, k2, x1, q2: k1 * (x1 - 1.0) - k2 * (q2 - 0.8)),   # (5.40)
    ("m2", lambda k1, k2, x1, q2: k2 * (q2 - 0.8)),                     # (5.49)
])
def test_missing_balance_is_suggested(capsys, tmp_path, mass, balance):
    text = (MODELS / "example3_two_masses.yaml").read_text()
    text = text.replace(f"{mass}: {'1.5' if mass == 'm1' else '2.0'}", f"{mass}: 0.0")
    model = tmp_path / "open.yaml"
    model.write_text(text)
    code, report = check_json(capsys, model)
    assert code == 1 and not report["unique"] and report["rank_Mhat"] == 2
    (equation,) = report["suggested_constraints"]
    lhs, rhs = equation.split("=")
    assert rhs.strip() == "0"
    names = ["body1.x1", "body2.q1", "body2.q2", "k1", "k2", "l10", "l20", "d", "m1", "m2"]
    symbols = {name: sp.Symbol(name) for name in names}
    expr = parse(lhs, symbols).subs({symbols["k1"]: 100.0, symbols["k2"]: 60.0, symbols["l10"]: 1.0,
                                     symbols["l20"]: 0.8})
    x1, q2 = symbols["body1.x1"], symbols["body2.q2"]
    ratio = sp.simplify(expr / balance(100.0, 60.0, x1, q2))
    assert ratio.is_number and abs(float(ratio)) > 0


def test_text_report_and_console_script(tmp_path):
    result = subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(MODELS / "example1_wheel.yaml")],
                            capture_output=True, text=True, check=True)
    assert "rank M = 1, rank A = 1, rank [M; A] = 2 of 2" in result.stdout
    assert "motion: unique" in result.stdout


def test_model_error_is_one_line_and_exit_2(capsys, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**}\n")
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {bad}:2:") and "\n" not in err
    assert main(["check", str(bad), "--json"]) == 2
    assert "error" in json.loads(capsys.readouterr().out)


def test_simulate_names_the_singular_position_it_passed(capsys):
    """The N-four-bar (N = 2) comes horizontal, its rows dependent, when its one-degree-of-
    freedom motion J ψ̈ = K sin ψ from vertical at 1 m/s reaches ψ = π/2: t = 0.714356 s
    (benchmarks/iftomm_reference.py, scipy at 1e-13). The summary says so."""
    root = Path(__file__).resolve().parents[2]
    from benchmarks import iftomm_reference as ref
    import numpy as np

    assert main(["simulate", str(root / "models" / "mechanisms" / "n_four_bar.yaml"), "--t-end", "1", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    first = summary["singular_positions"][0]
    t = np.linspace(0.70, 0.73, 3001)
    x, _ = ref.n_four_bar_reference(t, 2)
    horizontal = t[np.argmax(x)]  # B0 farthest along +x: the bars horizontal
    assert first["t_from"] <= horizontal + 1e-5 and first["t_to"] >= horizontal - 1e-5
    assert "cell[0].ground[x]" in first["rows"]
    assert main(["simulate", str(root / "models" / "mechanisms" / "n_four_bar.yaml"), "--t-end", "1"]) == 0
    assert "passed near singular positions at t ≈ 0.7143" in capsys.readouterr().out


JOINT_MODELS = Path(__file__).resolve().parents[2] / "models"
LEAF = """
name: massless_leaf
gravity: [0, 0, -9.81]
world: {frames: {pivot: {axis: [0, 1, 0]}}}
parts:
  rod: {type: rigid_body, mass: 1.0, inertia: [0.1, 0.1, 0.01], initial: {position: [0, 0, -0.5]},
        frames: {top: {position: [0, 0, 0.5], axis: [0, 1, 0]}, bottom: {position: [0, 0, -0.5], axis: [0, 1, 0]}}}
  leaf: {type: rigid_body, mass: 0, inertia: [0, 0, 0], initial: {position: [0, 0, -1.2]},
         frames: {top: {position: [0, 0, 0.2], axis: [0, 1, 0]}}}
joints:
  - {name: shoulder, type: revolute, parent: world.pivot, child: rod.top}
  - {name: wrist, type: revolute, parent: rod.bottom, child: leaf.top}
"""


def test_check_reports_joint_accelerations(capsys):
    """driven_pendulum.yaml at rest at θ0 = 0.6: θ̈ = (−m g (L/2) sin θ0 + τ0)/(m L²/3)."""
    path = JOINT_MODELS / "joints" / "driven_pendulum.yaml"
    assert main(["check", str(path)]) == 0
    text = capsys.readouterr().out
    m, L, g, tau0, theta0 = 1.2, 0.8, 9.81, 0.4, 0.6
    expected = (-m * g * L / 2 * np.sin(theta0) + tau0) / (m * L**2 / 3)
    line = next(x for x in text.splitlines() if "joint accelerations" in x)
    assert float(line.split("hinge.acceleration = ")[1]) == pytest.approx(expected, rel=1e-5)
    assert main(["check", str(path), "--coordinates", "maximal"]) == 0
    assert "rod.qw = " in capsys.readouterr().out
    assert main(["check", str(path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["joints"]["hinge"]["acceleration"][0] == pytest.approx(expected, rel=1e-9)
    assert len(report["qdd"]) == 7


def test_check_names_the_joint_a_free_direction_turns(capsys, tmp_path):
    path = tmp_path / "leaf.yaml"
    path.write_text(LEAF)
    main(["check", str(path)])
    text = capsys.readouterr().out
    assert "1 indeterminate direction" in text and "moves joint(s) wrist" in text
    main(["check", str(path), "--json"])
    report = json.loads(capsys.readouterr().out)
    assert list(report["free_joints"][0]) == ["wrist"]


def test_simulate_plots_joints_and_names_the_work(capsys, tmp_path):
    picture = tmp_path / "pd.png"
    assert main(["simulate", str(JOINT_MODELS / "joints" / "pd_pendulum.yaml"), "--t-end", "0.5",
                 "--plot", str(picture)]) == 0
    text = capsys.readouterr().out
    assert picture.stat().st_size > 10_000
    assert "relative energy drift" in text and "after the work of hinge.actuation" in text
    assert main(["simulate", str(JOINT_MODELS / "mechanisms" / "simple_pendulum.yaml"), "--t-end", "0.5"]) == 0
    assert "relative energy drift" in capsys.readouterr().out


def test_modes_of_the_pd_pendulum(capsys, tmp_path):
    """Linearized about its rest angle θ*, the PD pendulum obeys I s² + kd s + kp + m g (L/2) cos θ* = 0
    (I = m L²/3): two overdamped modes; --html writes a page with one frame per mode."""
    from scipy.optimize import brentq
    page = tmp_path / "modes.html"
    assert main(["modes", str(JOINT_MODELS / "joints" / "pd_pendulum.yaml"), "--equilibrium", "--json",
                 "--html", str(page)]) == 0
    report = json.loads(capsys.readouterr().out)
    rest = brentq(lambda x: 50.0 * (x - 0.5) + 9.81 * 0.5 * np.sin(x), 0.0, 1.0)
    expected = np.sort(np.roots([1 / 3, 10.0, 50.0 + 9.81 * 0.5 * np.cos(rest)]).real)
    found = np.sort([m["eigenvalue"][0] for m in report["modes"]])
    assert found == pytest.approx(expected, rel=1e-8)
    assert [m["kind"] for m in report["modes"]] == ["overdamped", "overdamped"]
    assert page.read_text().count("<iframe") == 2
