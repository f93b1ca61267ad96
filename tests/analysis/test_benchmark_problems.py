"""The field's benchmark problems run to the end and meet independent references.

IFToMM/LIM A01 (simple pendulum), A02 (N-four-bar through its singular positions), A03 /
the IVP test set's `andrews`, A04 (Bricard's over-constrained loop), A05 (the stiff
flyball governor), the IFToMM library's spatial rigid slider-crank, Bennett's and
Sarrus' over-constrained linkages and a 1 km pendulum in SI units. The references are in
benchmarks/iftomm_reference.py and use no mbsynth: Jacobi's elliptic functions for the
pendulum, the N-four-bar's exact one-degree-of-freedom equation integrated by scipy at
1e-13, the test set's published angles at 0.03 s, energy conservation, the joints'
gaps computed from the bodies' coordinates with quaternions written out there, the
flyball governor's and the spatial slider-crank's equations in their own few coordinates
written by hand, and the slider-crank library's published solution.

They fail on a solver that stops at, or mis-steps through, a configuration where the
dependent rows change (Bricard, the N-four-bar) or that judges consistency with an
absolute tolerance (the 1 km pendulum). Output intervals
are coarse to keep each run short (drift control projects between them as needed);
accuracy is `simulate`'s default (DOP853, rtol = atol = 1e-10).
"""

import functools
import math
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.analysis.diagnose import diagnose

ROOT = Path(__file__).resolve().parents[2]
MECHANISMS = ROOT / "models" / "mechanisms"
from benchmarks import iftomm_reference as ref

load = functools.cache(lambda name: mb.load(MECHANISMS / name))


def b0(traj, bar="v0"):
    """The top B0 of the first vertical bar (frame `top` at (0, L/2) of ``bar``, L = 1): v0 of
    n_four_bar_yaml, cell[0].v of the bundled n_four_bar.yaml."""
    theta = traj.column(f"{bar}.theta")
    return traj.column(f"{bar}.x") - 0.5 * np.sin(theta), traj.column(f"{bar}.y") + 0.5 * np.cos(theta)


def energy_change(traj):
    """max |E(t) − E(0)| relative to max(|E(0)|, the largest kinetic energy)."""
    assert np.all(np.isfinite(traj.energy))
    return traj.energy_drift


# --- the models are what they claim ------------------------------------------------------


@pytest.mark.parametrize("name, n, dependent", [
    ("simple_pendulum.yaml", 2, 0),
    ("pendulum_1km.yaml", 2, 0),
    ("andrews.yaml", 7, 0),
    ("n_four_bar.yaml", 15, 0),
    ("bricard.yaml", 35, 1),     # Grübler 0, mobility 1: one dependent joint row
    ("bennett.yaml", 21, 3),     # Grübler -2, mobility 1
    ("sarrus.yaml", 35, 1),      # Grübler 0, mobility 1
    ("flyball_governor.yaml", 34, 0),
    ("slider_crank_3d.yaml", 21, 0),
])
def test_model_verdicts(name, n, dependent):
    d = diagnose(load(name))
    assert d.unique and d.n == n and d.rank_Mhat == n
    assert d.m - d.rank_A == dependent


def test_degrees_of_freedom():
    """One degree of freedom each: n minus the rank of A."""
    for name in ("simple_pendulum.yaml", "andrews.yaml", "n_four_bar.yaml", "bricard.yaml", "bennett.yaml",
                 "sarrus.yaml"):
        d = diagnose(load(name))
        assert d.n - d.rank_A == 1, name


def test_n_four_bar_generator_is_consistent_as_written():
    """N = 40 written out flat starts on its constraints (the bundled n_four_bar.yaml, built
    of cells, is compared with these flat models in tests/io/test_composed_four_bar.py)."""
    system = mb.loads(ref.n_four_bar_yaml(40), name="n_four_bar_40")
    assert len(system.coordinates) == 3 * 81
    q, qd = system.initial_state()
    phi, psi = system.constraint_residuals(0.0, q, qd)
    assert np.abs(phi).max() < 1e-14 and np.abs(psi).max() < 1e-14   # consistent as written


def test_flyball_and_slider_crank_3d_degrees_of_freedom():
    """The flyball governor: shaft angle, slider height and two rod angles; the spatial
    slider-crank: the crank angle (the universal joint fixes the rod's spin)."""
    for name, dof in (("flyball_governor.yaml", 4), ("slider_crank_3d.yaml", 1)):
        d = diagnose(load(name))
        assert d.n - d.rank_A == dof, name


def test_slider_crank_3d_starts_as_the_benchmark_states():
    """Crank straight up, B = A + (0, 0, l1), C = (0.2, 0, 0), the rod's x along BC and the
    cross's rod axis (frame C's z, the rod's y) perpendicular to the rail (x) and to BC."""
    system = load("slider_crank_3d.yaml")
    q, qd = system.initial_state()
    r_crank, R_crank = ref.body_pose(system.coordinates, q, "crank")
    r_rod, R_rod = ref.body_pose(system.coordinates, q, "rod")
    B = r_crank + R_crank @ (0, 0, 0.04)
    np.testing.assert_allclose(B, (0, 0.1, 0.2), atol=1e-15)
    np.testing.assert_allclose(r_rod - R_rod @ (0.15, 0, 0), B, atol=1e-15)
    np.testing.assert_allclose(r_rod + R_rod @ (0.15, 0, 0), (0.2, 0, 0), atol=1e-15)
    assert abs(R_rod[0, 1]) < 1e-15     # the rod's y axis has no x component
    index = {c: i for i, c in enumerate(system.coordinates)}
    assert qd[index["slider.x"]] == pytest.approx(0.24, abs=1e-14)


def test_bricard_initial_loop_is_closed():
    system = load("bricard.yaml")
    q, _ = system.initial_state()
    gap, axis = ref.loop_gaps(system.coordinates, q, ref.BRICARD_JOINTS)
    assert gap < 1e-15 and axis < 1e-15


# --- the references are right --------------------------------------------------------------


def test_pendulum_reference_small_amplitude_and_energy():
    L, g = 2.0, 9.81
    assert ref.pendulum_period(L, g, 1e-4) == pytest.approx(2 * math.pi * math.sqrt(L / g), rel=1e-8)
    t = np.linspace(0, 5, 201)
    x, y = ref.pendulum_exact(t, L, g, 1.0)
    assert np.allclose(x**2 + y**2, L**2, rtol=1e-14)
    # energy from finite differences of the closed form
    h = 1e-6
    xp, yp = ref.pendulum_exact(t + h, L, g, 1.0)
    xm, ym = ref.pendulum_exact(t - h, L, g, 1.0)
    v2 = ((xp - xm) ** 2 + (yp - ym) ** 2) / (2 * h) ** 2
    E = 0.5 * v2 + g * y
    assert np.abs(E - E[0]).max() < 1e-6 * g * L


def test_n_four_bar_reference_conserves_energy_and_crosses_singularities():
    J, K = ref.n_four_bar_constants(2)
    assert (J, K) == pytest.approx((3.0, 9.81 * 3.5))
    times = ref.n_four_bar_singular_times(2, 20.0)
    assert times[0] == pytest.approx(0.714, abs=1e-3) and len(times) == 20
    t = np.linspace(0, 20, 2001)
    x, y = ref.n_four_bar_reference(t, 2)
    assert np.allclose(x**2 + y**2, 1.0, atol=1e-12)


def test_slider_crank_3d_reference_meets_the_published_solution():
    """The crank angle's equation written by hand against the IFToMM library's published
    solution (M. González, slider x every 0.1 s for 5 s, printed to 9 digits): within
    1e-4 m over the 5 s (7.0e-5 m), 2e-6 m at 0.1 s (1.8e-6 m; the published solution's
    own accuracy)."""
    published = ref.SLIDER_CRANK_3D_PUBLISHED
    x, theta = ref.slider_crank_3d_reference(published[:, 0])
    assert x[0] == pytest.approx(0.2, abs=1e-15) and theta[0] == 0
    error = np.abs(x - published[:, 1])
    assert error.max() < 1e-4 and error[1] < 2e-6


# --- the runs ------------------------------------------------------------------------------


def test_simple_pendulum_a01_against_exact_motion():
    traj = mb.simulate(load("simple_pendulum.yaml"), 10.0, dt=0.1)
    assert traj.status == "completed"
    x, y = ref.pendulum_exact(traj.t, 1.0, 9.81, math.pi / 2)
    assert np.max(np.hypot(traj.column("bob.x") - x, traj.column("bob.y") - y)) < 1e-6
    assert energy_change(traj) < 1e-8


def assert_follows_the_one_dof_reference(traj, N, bar="v0"):
    """B0 (the top of ``bar``) within the benchmark's 1e-3 m of the exact motion; energy kept to 1e-6."""
    assert traj.status == "completed"
    bx, by = b0(traj, bar)
    xr, yr = ref.n_four_bar_reference(traj.t, N)
    assert np.max(np.hypot(bx - xr, by - yr)) < 1e-3
    assert energy_change(traj) < 1e-6


def test_n_four_bar_2_follows_the_one_dof_reference_for_20_s():
    """B0 within 1e-3 m of the exact motion over 20 s: 20 passes through the horizontal
    (singular) positions, each of which must be crossed, not bounced off."""
    assert_follows_the_one_dof_reference(mb.simulate(load("n_four_bar.yaml"), 20.0), 2, "cell[0].v")


def test_n_four_bar_40_follows_the_one_dof_reference(monkeypatch):
    """N = 40 (243 coordinates, its Schur step banded) through its first four singular
    positions at the default tolerance: each crossed by a planned step (the run measures
    how near its rows are to losing rank at every step's end: compiled/least_direction.py)
    and listed within 1e-3 s of its time with rows along x (the flat bars' dependency), no
    span relaxed, B0 within 1e-7 m of the exact motion. benchmarks/loops.py runs the
    benchmark's 20 s. The compiled kernels waited for (MBSYNTH_COMPILED=wait): without them the
    run projects each step and lists the crossings its stages come near."""
    monkeypatch.setenv("MBSYNTH_COMPILED", "wait")
    system = mb.loads(ref.n_four_bar_yaml(40), name="n_four_bar_40")
    traj = mb.simulate(system, 4.0, dt=0.1)
    assert_follows_the_one_dof_reference(traj, 40)
    assert not traj.stats["relaxed_spans"]
    crossings = ref.n_four_bar_singular_times(40, 4.0)
    listed = traj.stats["singular_positions"]
    assert len(listed) == len(crossings) == 4
    for entry, t in zip(listed, crossings):
        assert entry["t_from"] - 1e-3 <= t <= entry["t_to"] + 1e-3, (entry, t)
        assert entry["rows"] and all(row.endswith("[x]") for row in entry["rows"])  # the bars lie along x
    bx, by = b0(traj)
    xr, yr = ref.n_four_bar_reference(traj.t, 40)
    assert np.max(np.hypot(bx - xr, by - yr)) < 1e-7


def test_andrews_against_the_ivp_test_set():
    traj = mb.simulate(load("andrews.yaml"), 0.03, dt=0.003)
    assert traj.status == "completed" and traj.t[-1] == pytest.approx(0.03, abs=1e-15)
    angles = np.array([traj.column(f"sq.{c}")[-1] for c in ref.ANDREWS_COORDINATES])
    np.testing.assert_allclose(angles, ref.ANDREWS_T003, rtol=1e-7, atol=1e-8)
    # energy balance: the motor's torque mom does work mom (beta - beta0)
    beta = traj.column("sq.beta")
    E = traj.energy - ref.ANDREWS_MOM * (beta - beta[0])
    assert np.abs(E - E[0]).max() < 1e-7 * np.abs(traj.kinetic).max()


def test_bricard_10_s_conserves_energy_and_keeps_the_loop_closed():
    system = load("bricard.yaml")
    traj = mb.simulate(system, 10.0, dt=0.5)
    assert traj.status == "completed"
    assert energy_change(traj) < 1e-8
    gaps = [ref.loop_gaps(system.coordinates, q, ref.BRICARD_JOINTS) for q in traj.q]
    assert max(g[0] for g in gaps) < 1e-10 and max(g[1] for g in gaps) < 1e-10
    assert traj.max_residual < 1e-10


def test_bennett_conserves_energy_and_keeps_the_loop_closed():
    system = load("bennett.yaml")
    traj = mb.simulate(system, 3.0, dt=0.25)
    assert traj.status == "completed"
    assert energy_change(traj) < 1e-8
    a, b = 0.5, 0.5 * math.sin(math.pi / 3) / math.sin(math.pi / 6)
    sa, ca, sb, cb = math.sin(math.pi / 6), math.cos(math.pi / 6), math.sin(math.pi / 3), math.cos(math.pi / 3)
    z = (0, 0, 1)
    joints = [((None, (0, 0, 0), z), ("link1", (-a / 2, 0, 0), (0, sa, ca))),
              (("link1", (a / 2, 0, 0), z), ("link2", (-b / 2, 0, 0), (0, sb, cb))),
              (("link2", (b / 2, 0, 0), z), ("link3", (-a / 2, 0, 0), (0, sa, ca))),
              ((None, (-b, 0, 0), (0, sb, cb)), ("link3", (a / 2, 0, 0), z))]
    gaps = [ref.loop_gaps(system.coordinates, q, joints) for q in traj.q]
    assert gaps[0][0] < 1e-14
    assert max(g[0] for g in gaps) < 1e-10 and max(g[1] for g in gaps) < 1e-10
    moved = np.abs(traj.q[-1] - traj.q[0]).max()
    assert moved > 0.1   # it does move


def test_sarrus_plate_translates_and_energy_is_conserved():
    traj = mb.simulate(load("sarrus.yaml"), 2.0, dt=0.25)
    assert traj.status == "completed"
    assert energy_change(traj) < 1e-8
    assert np.abs(traj.column("top.x")).max() < 1e-10 and np.abs(traj.column("top.y")).max() < 1e-10
    for c in ("qx", "qy", "qz"):
        assert np.abs(traj.column(f"top.{c}")).max() < 1e-10
    z = traj.column("top.z")
    assert 0.05 < z.min() < 0.55 and z.max() == pytest.approx(0.6, abs=1e-9)


def test_pendulum_1km_runs_120_s_with_the_rod_held():
    """SI units at the kilometre scale: the rod constraint x² + y² − L² (its terms of size
    L² = 1e6 m²) held to 1e-10 L² for two periods, the bob on the exact motion."""
    L = 1000.0
    traj = mb.simulate(load("pendulum_1km.yaml"), 120.0, dt=2.0)
    assert traj.status == "completed" and traj.t[-1] == pytest.approx(120.0)
    x, y = traj.column("bob.x"), traj.column("bob.y")
    assert np.abs(x**2 + y**2 - L**2).max() <= 1e-10 * L**2
    xr, yr = ref.pendulum_exact(traj.t, L, 9.81, 0.3)
    assert np.max(np.hypot(x - xr, y - yr)) < 1e-6 * L
    assert energy_change(traj) < 1e-8


def test_flyball_governor_follows_its_four_coordinate_equations():
    """A05, 1 s of the stiff flyball governor (dampers' fast mode about -7e3 1/s) at the
    default tolerance: the slider's height and the shaft's rate on the Lagrange equations
    written by hand, and the energy E(t) = E(0) minus the dampers' work."""
    traj = mb.simulate(load("flyball_governor.yaml"), 1.0, dt=0.05)
    assert traj.status == "completed"
    r = ref.flyball_reference(traj.t)
    assert np.max(np.abs(traj.column("slider.z") - r["s"])) < 1e-9
    assert traj.column("slider.z").max() > 0.7         # the slider does swing up
    qw, qz = traj.column("shaft.qw"), traj.column("shaft.qz")
    omega = 2 * (qw * traj.column("shaft.qz_dot") - qz * traj.column("shaft.qw_dot"))
    assert np.max(np.abs(omega - r["phi_dot"])) < 1e-9
    E = traj.energy
    assert np.max(np.abs(E - E[0] + r["W"])) < 1e-9 * abs(E[0])


def test_slider_crank_3d_follows_the_crank_equation_and_the_published_solution():
    """The IFToMM spatial slider-crank, 1 s: the slider on the crank angle's equation, and
    within the published solution's own 5e-5 m of it at its 0.1 s samples."""
    traj = mb.simulate(load("slider_crank_3d.yaml"), 1.0, dt=0.1)
    assert traj.status == "completed"
    x = traj.column("slider.x")
    xr, _ = ref.slider_crank_3d_reference(traj.t)
    assert np.max(np.abs(x - xr)) < 1e-9
    published = ref.SLIDER_CRANK_3D_PUBLISHED[:11]
    np.testing.assert_allclose(traj.t, published[:, 0], atol=1e-12)
    assert np.max(np.abs(x - published[:, 1])) < 5e-5
    assert energy_change(traj) < 1e-8


def test_only_merges_its_rows_into_an_existing_table(tmp_path):
    """--only with an existing results file: the problem run replaces its own row and
    note, every other row stays, and one line says which rows were run again."""
    from benchmarks import iftomm
    out = tmp_path / "results.md"
    old = (ROOT / "benchmarks" / "iftomm_results.md").read_text()
    out.write_text(old)
    iftomm.main(["--quick", "--only", "pendulum", "--out", str(out)])
    text = out.read_text()
    _, old_rows, _ = iftomm._table_parts(old)
    _, rows, notes = iftomm._table_parts(text)
    title = "A01 simple pendulum (1 m, from horizontal)"
    assert list(rows) == list(old_rows) and len(rows) > 1
    assert all(rows[t] == old_rows[t] for t in rows if t != title)
    assert rows[title].startswith(f"| {title} | 1 |") and rows[title] != old_rows[title]
    assert f"rows {title} run again by" in text and "iftomm.py --quick --only pendulum`" in text
    assert sum(n.startswith(f"- {title}: ") for n in notes) == 1
    iftomm.main(["--quick", "--only", "pendulum", "--out", str(out)])     # again: one line says so
    assert out.read_text().count(f"rows {title} run again by") == 1


def test_benchmark_script_quick_writes_its_table(tmp_path):
    """benchmarks/iftomm.py --quick on three problems: a table row each, a failure
    reported in its row rather than raised."""
    from benchmarks import iftomm
    out = tmp_path / "results.md"
    results = iftomm.main(["--quick", "--only", "pendulum,andrews,pendulum_1km", "--out", str(out)])
    text = out.read_text()
    assert [r.problem.name for r in results] == ["pendulum", "andrews", "pendulum_1km"]
    for r in results:
        assert r.problem.title in text
    pendulum, andrews = results[0], results[1]
    assert pendulum.status == "completed" and pendulum.error < 1e-6
    assert andrews.status == "completed" and andrews.error < 1e-6
