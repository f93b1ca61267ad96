"""The implicit method for stiff models (method="Radau" on the continuous run loop, given
the Jacobian of the motion through the compiled kernel): against closed forms, against the
converged answer of a flexible part, its refusals, and ``check``'s suggestion of it."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.special

import mbsynth as mb
from mbsynth.analysis.stiffness import highest_frequency

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "model" / "flexible"))
from test_flexible_pendulum import pendulum_yaml  # noqa: E402

# two masses on soft springs to the ground, joined by a stiff spring: ω = 0.77 and 1118 rad/s
MASSES, SOFT, STIFF = (1.0, 4.0), (1.0, 2.0), 1e6
DOP853_REACH = 5.96  # DOP853's stability bound on the imaginary axis, h ω (its tableau's R(iy))


def two_masses():
    """The model started on its slow mode alone; (system, ω_slow, the mode's shape, ω_fast)."""
    M = np.diag(MASSES)
    K = np.array([[SOFT[0] + STIFF, -STIFF], [-STIFF, SOFT[1] + STIFF]])
    w2, shapes = scipy.linalg.eigh(K, M)
    shape = shapes[:, 0] / shapes[0, 0]
    text = f"""
name: two_masses
parameters: {{ma: {MASSES[0]}, mb: {MASSES[1]}, ka: {SOFT[0]}, kb: {SOFT[1]}, K: {STIFF}}}
parts:
  pair:
    type: lagrangian
    coordinates: [a, b]
    T: 0.5*ma*a_dot**2 + 0.5*mb*b_dot**2
    V: 0.5*ka*a**2 + 0.5*kb*b**2 + 0.5*K*(a - b)**2
initial: {{pair.a: {float(shape[0])!r}, pair.b: {float(shape[1])!r}}}
"""
    return mb.loads(text), np.sqrt(w2[0]), shape, np.sqrt(w2[1])


def test_radau_follows_the_slow_mode_of_a_stiff_pair_in_steps_an_explicit_pair_could_not_take():
    system, slow, shape, fast = two_masses()
    t_end = 10.0
    run = mb.simulate(system, t_end, dt=0.5, method="Radau", rtol=1e-8, atol=1e-8)
    assert run.status == "completed"
    assert np.abs(run.q - np.outer(np.cos(slow * run.t), shape)).max() < 1e-7
    # an explicit pair needs at least fast · t_end / DOP853_REACH steps (~1,900) to stay stable
    assert run.stats["steps"] < fast * t_end / DOP853_REACH / 5
    assert run.stats["jacobians"] >= 1


def test_radau_swings_a_pendulum_as_its_elliptic_closed_form():
    """The IFToMM A01 pendulum from horizontal: sin(φ/2) = k sn(K(k) − t √(g/L); k)."""
    system = mb.load(ROOT / "models" / "mechanisms" / "simple_pendulum.yaml")
    run = mb.simulate(system, 2.0, dt=0.1, method="Radau", rtol=1e-9, atol=1e-9)
    k = np.sin(np.pi / 4)
    sn = scipy.special.ellipj(scipy.special.ellipk(k**2) - run.t * np.sqrt(9.81), k**2)[0]
    phi = 2 * np.arcsin(k * sn)
    assert np.abs(run.column("bob.x") + np.sin(phi)).max() < 1e-7
    assert np.abs(run.column("bob.y") + np.cos(phi)).max() < 1e-7
    assert np.abs(run.energy - run.energy[0]).max() < 1e-7 * 9.81  # its energy kept (L-stable, yet accurate)
    assert run.residual_position.max() < 1e-12  # on the rod at every row: the projection as for DOP853


def test_radau_brings_the_flexible_pendulums_tip_within_1e_6_m_of_the_converged_answer():
    system = mb.loads(pendulum_yaml(8), name="flexible_pendulum")
    t_end = 0.1

    def tip(method, rtol):
        run = mb.simulate(system, t_end, dt=t_end / 2, method=method, rtol=rtol, atol=rtol)
        return np.array([run.column("tip[x]")[-1], run.column("tip[y]")[-1]]), run

    converged, _ = tip("DOP853", 1e-11)
    found, run = tip("Radau", 3e-5)
    assert np.linalg.norm(found - converged) < 1e-6
    assert run.stats["jacobians"] >= 1 and run.residual_position.max() < 1e-10


def test_a_loose_explicit_run_of_the_flexible_pendulum_is_held_by_its_stability_not_by_the_drift():
    """The pendulum's rows keep their rank, so its steps may drift by the rtol between
    projections (integration.drift_target): at rtol 1e-3 DOP853 takes fewer than three times
    the steps its stability needs on the 866 rad/s mode (ω t / DOP853_REACH; held to a drift
    of 1e-9 it would take about five), its tip within 1e-7 m of the converged answer, every output row on
    the constraints."""
    system = mb.loads(pendulum_yaml(8), name="flexible_pendulum")
    t_end = 0.2
    omega, _ = highest_frequency(system)

    def tip(rtol):
        run = mb.simulate(system, t_end, dt=t_end / 2, rtol=rtol, atol=rtol)
        return np.array([run.column("tip[x]")[-1], run.column("tip[y]")[-1]]), run

    converged, _ = tip(1e-11)
    found, run = tip(1e-3)
    assert run.stats["steps"] < 3 * omega * t_end / DOP853_REACH
    assert np.linalg.norm(found - converged) < 1e-7
    assert run.residual_position.max() < 1e-12


def test_an_implicit_method_refuses_coulomb_friction_and_says_why():
    system = mb.load(ROOT / "models" / "joints" / "slider_friction.yaml")
    with pytest.raises(mb.ModelError, match="Coulomb friction at .*no Jacobian"):
        mb.simulate(system, 0.1, method="Radau")


def test_an_implicit_method_refuses_a_controller_and_says_why():
    system, *_ = two_masses()
    with pytest.raises(mb.ModelError, match="controller's forces jump at every sample"):
        mb.simulate(system, 0.1, method="BDF", controller=lambda t, joints: {})


def test_the_cli_refuses_radau_for_coulomb_friction_with_exit_2_and_one_line():
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "simulate", "models/joints/slider_friction.yaml",
                           "--t-end", "0.1", "--method", "Radau"], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 2
    assert "Coulomb friction" in done.stderr and "no Jacobian" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_check_suggests_radau_where_the_highest_frequency_makes_explicit_steps_crawl(tmp_path):
    path = tmp_path / "flexible_pendulum.yaml"
    path.write_text(pendulum_yaml(8))
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(path)], cwd=ROOT, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    line = [x for x in done.stdout.splitlines() if "stiff:" in x]
    # 865.56 rad/s: the beam's fourth fixed-interface bending frequency (benchmarks/flexible_results.md, Exudyn's alike)
    assert line and "865.6 rad/s (part rod), 138 periods in 1 s" in line[0] and "--method Radau" in line[0]
    short = subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(path), "--t-end", "0.5", "--json"],
                           cwd=ROOT, capture_output=True, text=True)
    assert json.loads(short.stdout)["stiff"] is None  # 69 periods: not stiff for a run that short
