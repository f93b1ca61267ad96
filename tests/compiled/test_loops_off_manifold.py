"""The compiled kernel at states off the constraint manifold of models with loops (an
integrator's stages): its Schur step follows the drift rule of core/equations.py
(kernel.motion's ``drift``), so loops of kernel joints integrate on the compiled path.

References: the KKT path's drift rule (equations.py, an SVD of all the rows), the exact
one-degree-of-freedom motion of the N-four-bar (benchmarks/iftomm_reference.py) through its
singular positions, and energy conservation.
"""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.compiled import kernel, layout, staged
from mbsynth.compiled.engine import Engine

ROOT = Path(__file__).resolve().parents[2]
from benchmarks import iftomm_reference as ref

LOOPS = ["bricard.yaml", "bennett.yaml", "sarrus.yaml", "four_bar_3d.yaml"]


def rigid_n_four_bar(N, L=1.0, m=1.0):
    """The IFToMM A02 N-four-bar of iftomm_reference.n_four_bar_yaml built of rigid bodies
    (7 coordinates each) on revolute joints about z: in space every loop is
    over-constrained (dependent rows on the whole manifold), and at the horizontal
    positions N more rows become dependent (singular positions). The bars' own axial
    inertia is a hundredth of the transverse one (the motion is planar: it does not enter)."""
    small, rod = m * L**2 / 1200, m * L**2 / 12
    lines = [f"name: rigid_n_four_bar_{N}", f"parameters: {{L: {L!r}, m: {m!r}, g: 9.81, speed: 1.0}}",
             "gravity: [0, -g, 0]", "world:", "  frames:"]
    lines += [f"    p{i}: {{position: [{i}*L, 0, 0]}}" for i in range(N + 1)]
    lines.append("parts:")
    for i in range(N + 1):
        lines.append(f"  v{i}: {{type: rigid_body, mass: m, inertia: [{rod}, {small}, {rod}], "
                     "frames: {bottom: {position: [0, -L/2, 0]}, top: {position: [0, L/2, 0]}}, "
                     f"initial: {{position: [{i}*L, L/2, 0], velocity: [speed/2, 0, 0], "
                     "angular_velocity: [0, 0, -speed/L]}}")
    for i in range(N):
        lines.append(f"  h{i}: {{type: rigid_body, mass: m, inertia: [{small}, {rod}, {rod}], "
                     "frames: {left: {position: [-L/2, 0, 0]}, right: {position: [L/2, 0, 0]}}, "
                     f"initial: {{position: [{i}*L + L/2, L, 0], velocity: [speed, 0, 0]}}}}")
    lines.append("joints:")
    lines += [f"  - {{name: ground{i}, type: revolute, parent: world.p{i}, child: v{i}.bottom}}" for i in range(N + 1)]
    for i in range(N):
        lines.append(f"  - {{name: left{i}, type: revolute, parent: v{i}.top, child: h{i}.left}}")
        lines.append(f"  - {{name: right{i}, type: revolute, parent: v{i + 1}.top, child: h{i}.right}}")
    return "\n".join(lines) + "\n"


def drifted(system, rng, size):
    """A state of ``system`` on its manifold in motion (0.3 s into its run), then moved off it
    by ``size`` (relative, random directions) in positions and velocities."""
    trajectory = mb.simulate(system, 0.3, dt=0.3)
    q, qd = trajectory.q[-1], trajectory.qd[-1]
    return (q + size * max(np.abs(q).max(), 1.0) * rng.standard_normal(q.size),
            qd + size * np.abs(qd).max() * rng.standard_normal(qd.size))


@pytest.mark.parametrize("name", LOOPS)
def test_off_the_manifold_the_kernel_gives_the_drift_rules_motion(name):
    """At stages 1e-9 off the manifold the kernel serves the motion (loops of kernel joints
    only) and it is the KKT drift rule's to O(drift): both are least-squares motions, in
    different metrics, of rows the drift made inconsistent."""
    system = mb.load(ROOT / "models" / "mechanisms" / name)
    data = system.data()
    engine = data.engine
    assert engine is not None and engine.closes_loops
    rng = np.random.default_rng(7)
    for _ in range(5):
        q, qd = drifted(system, rng, 1e-9)
        compiled = engine.motion(0.0, q, qd, None, True)
        assert compiled is not None  # served by the kernel, not handed to the KKT path
        exact = data._kkt_motion(0.0, q, qd, "kkt", None, True)
        scale = np.abs(exact.qdd).max()
        assert np.abs(compiled.qdd - exact.qdd).max() <= 1e-6 * scale


@pytest.mark.parametrize("name", LOOPS)
def test_on_the_manifold_the_kernel_still_judges_consistency(name):
    """A state 1e-5 off the manifold asked for without ``drift`` is judged as on it: the
    dropped directions' right side contradicts the rows, and the kernel hands it to the
    exact path (None) rather than give a least-squares motion."""
    system = mb.load(ROOT / "models" / "mechanisms" / name)
    engine = system.data().engine
    q, qd = drifted(system, np.random.default_rng(1), 1e-5)
    assert engine.motion(0.0, q, qd) is None
    assert engine.motion(0.0, q, qd, None, True) is not None


def rigid_n_four_bar_state(system, N, psi, psi_dot, L=1.0):
    """(q, q̇) of ``rigid_n_four_bar`` with every vertical bar at psi from the upward vertical
    (clockwise: a turn of −psi about z) turning at psi' (iftomm_reference.n_four_bar_state's
    motion, with unit quaternions)."""
    index = {name: k for k, name in enumerate(system.coordinates)}
    q, qd = np.zeros(system.n), np.zeros(system.n)
    s, c, half = np.sin(psi), np.cos(psi), psi / 2
    for i in range(N + 1):
        for name, value, rate in (("x", i * L + L / 2 * s, L / 2 * c * psi_dot), ("y", L / 2 * c, -L / 2 * s * psi_dot),
                                  ("qw", np.cos(half), -np.sin(half) * psi_dot / 2),
                                  ("qz", -np.sin(half), -np.cos(half) * psi_dot / 2)):
            q[index[f"v{i}.{name}"]], qd[index[f"v{i}.{name}"]] = value, rate
    for i in range(N):
        for name, value, rate in (("x", i * L + L / 2 + L * s, L * c * psi_dot), ("y", L * c, -L * s * psi_dot),
                                  ("qw", 1.0, 0.0)):
            q[index[f"h{i}.{name}"]], qd[index[f"h{i}.{name}"]] = value, rate
    return q, qd


def test_near_a_singular_position_the_kernel_leaves_the_stage_to_the_exact_drift_rule(tmp_path):
    """The rigid N-four-bar 1e-6 rad before its horizontal position, 1e-12 off the manifold:
    the nearly dependent direction of the rows is the singular position's, not the drift's,
    so the kernel hands the stage on (None); the KKT drift rule names the rows and gives the
    exact one-degree-of-freedom acceleration there."""
    path = tmp_path / "rigid_n_four_bar.yaml"
    path.write_text(rigid_n_four_bar(2))
    system = mb.load(path)
    data = system.data()
    engine = data.engine
    psi, psi_dot = np.pi / 2 - 1e-6, 2.0
    q, qd = rigid_n_four_bar_state(system, 2, psi, psi_dot)
    rng = np.random.default_rng(5)
    q, qd = q + 1e-12 * rng.standard_normal(q.size), qd + 1e-12 * rng.standard_normal(q.size)
    assert engine.motion(0.0, q, qd, None, True) is None
    motion = data.motion(0.0, q, qd, drift=True)
    assert motion.singular
    J, K = ref.n_four_bar_constants(2)
    psi_ddot = K / J * np.sin(psi)
    x_ddot = 0.5 * (np.cos(psi) * psi_ddot - np.sin(psi) * psi_dot**2)  # v0's centre
    assert motion.qdd[system.coordinates.index("v0.x")] == pytest.approx(x_ddot, rel=1e-6)


def test_the_rigid_n_four_bar_passes_its_singular_positions_on_the_exact_motion(tmp_path):
    """The N-four-bar (N = 2) of rigid bodies, over-constrained in space, 8 s through eight
    horizontal (singular) positions at the default tolerance, every stage served by the
    kernel: the top B0 of the first bar within 1e-8 m of the exact one-degree-of-freedom
    motion, no span integrated again more loosely."""
    path = tmp_path / "rigid_n_four_bar.yaml"
    path.write_text(rigid_n_four_bar(2))
    system = mb.load(path)
    statuses = set()
    # motion() (Engine._solved): (status, residual); a stage's ẏ: status; a compiled step: ACCEPTED where the kernel
    # served every stage, else the step is taken again on the Python path, whose stages are counted
    originals = Engine._solved, staged.rates, staged.step

    def counted(self, *args):
        found = originals[0](self, *args)
        statuses.add(int(found[0]))
        return found

    def counted_stage(*args):
        status = originals[1](*args)
        statuses.add(int(status))
        return status

    def counted_step(*args):
        found = originals[2](*args)
        if found[0] == staged.ACCEPTED:
            statuses.add(kernel.OK)
        return found
    Engine._solved, staged.rates, staged.step = counted, counted_stage, counted_step
    try:
        trajectory = mb.simulate(system, 8.0, dt=0.05)
    finally:
        Engine._solved, staged.rates, staged.step = originals
    assert trajectory.status == "completed" and not trajectory.stats["relaxed_spans"]
    assert len(ref.n_four_bar_singular_times(2, 8.0)) == 8
    assert kernel.OK in statuses and statuses <= {kernel.OK, kernel.NEAR_SINGULAR}
    x, y = ref.n_four_bar_reference(trajectory.t, 2)
    u = trajectory.q[:, system.coordinates.index("v0.qw"):][:, :4]
    theta = 2 * np.arctan2(u[:, 3], u[:, 0])  # the bar's turn about z
    bx = trajectory.column("v0.x") - 0.5 * np.sin(theta)
    by = trajectory.column("v0.y") + 0.5 * np.cos(theta)
    assert np.hypot(bx - x, by - y).max() <= 1e-8


@pytest.mark.parametrize("rtol", [1e-4, 1e-5, 1e-6])
def test_bricard_at_loose_tolerances_completes_unique_and_conserves_energy(rtol):
    """Bricard's loop at loose tolerances (long trial steps whose stages stray far off the
    manifold: their derivative is NaN, and the integrator takes the step again shorter):
    the run completes, its motion unique throughout (no spurious "not unique"), its energy
    within 1e-6 of its start (relative) and the loop closed."""
    system = mb.load(ROOT / "models" / "mechanisms" / "bricard.yaml")
    trajectory = mb.simulate(system, 10.0, dt=0.5, rtol=rtol, atol=rtol)
    assert trajectory.status == "completed" and not trajectory.stats["non_unique"]
    assert trajectory.energy_drift < 1e-6
    assert trajectory.max_residual < 1e-12


def test_a_model_of_extra_coordinates_keeps_its_stages_where_no_direction_is_nearly_dependent():
    """Andrews' squeezer (one energy-defined part, seven angles, six loop rows: extra
    coordinates and rows only) 1e-9 off the manifold: the Schur eigenvalues and the mass's
    condition certify that every direction of the rows is far from dependent, so the drift
    rule keeps them all and the kernel serves the stage, with the KKT path's motion (the same
    equations, solved another way: to rounding, 1e-9 relative)."""
    system = mb.load(ROOT / "models" / "mechanisms" / "andrews.yaml")
    data = system.data()
    engine = data.engine
    rng = np.random.default_rng(11)
    q0, qd0 = system.initial_state()
    for _ in range(5):
        q = q0 + 1e-9 * rng.standard_normal(q0.size)
        qd = qd0 + 1e-9 * rng.standard_normal(q0.size)
        compiled = engine.motion(0.0, q, qd, None, True)
        assert compiled is not None
        exact = data._kkt_motion(0.0, q, qd, "kkt", None, True)
        assert np.abs(compiled.qdd - exact.qdd).max() <= 1e-9 * np.abs(exact.qdd).max()


def test_near_a_singular_position_a_planar_loop_leaves_the_stage_to_the_exact_drift_rule(tmp_path):
    """The planar N-four-bar (N = 2: planar bodies, extra coordinates only) 1e-3 rad from its
    horizontal position is served by the kernel off the manifold; 1e-7 rad from it, where a
    direction of the rows is nearly dependent, the certificate fails and
    the stage goes to the exact drift rule, which names the rows and gives the exact
    one-degree-of-freedom acceleration."""
    path = tmp_path / "n_four_bar.yaml"
    path.write_text(ref.n_four_bar_yaml(2))
    system = mb.load(path)
    data = system.data()
    engine = data.engine
    J, K = ref.n_four_bar_constants(2)
    rng = np.random.default_rng(3)
    for gap, served in ((1e-3, True), (1e-7, False)):
        psi, psi_dot = np.pi / 2 - gap, 2.0
        q, qd = ref.n_four_bar_state(system.coordinates, 2, psi, psi_dot)
        q, qd = q + 1e-13 * rng.standard_normal(q.size), qd + 1e-13 * rng.standard_normal(q.size)
        assert (engine.motion(0.0, q, qd, None, True) is not None) == served
        motion = data.motion(0.0, q, qd, drift=True)
        assert bool(motion.singular) != served
        psi_ddot = K / J * np.sin(psi)
        x_ddot = 0.5 * (np.cos(psi) * psi_ddot - np.sin(psi) * psi_dot**2)
        assert motion.qdd[system.coordinates.index("v0.x")] == pytest.approx(x_ddot, rel=1e-6)


def test_a_large_planar_loop_is_served_by_the_banded_schur_step(tmp_path):
    """The planar N-four-bar with N = 12 (25 planar bodies: 75 extra coordinates, 74 rows, a
    Schur system beyond layout.DENSE_SCHUR_MAX) gets a banded Schur matrix (banded.py). On the
    manifold the kernel's acceleration is the exact one-degree-of-freedom motion's, 1 rad and
    1e-3 rad from the horizontal position alike (the KKT path's SVD loses digits near it: its
    q̈ there is held to 1e-6 only); the kernel's projection puts a state 1e-9 off the
    manifold back on it to rounding; 1e-9 off the manifold 1 rad from it the kernel serves the
    stage with the KKT drift rule's motion; 1e-7 rad from it, where a direction of the rows is
    nearly dependent, the certificate fails and the stage goes to the exact drift rule."""
    N = 12
    path = tmp_path / "n_four_bar.yaml"
    path.write_text(ref.n_four_bar_yaml(N))
    system = mb.load(path)
    data = system.data()
    engine = data.engine
    assert engine is not None and engine.L.band_width.size == 1
    assert engine.L.x_coord.size + engine.L.xrow_row.size > layout.DENSE_SCHUR_MAX
    projection = engine.projection()  # extra_projection.py, through the banded step
    q, qd = ref.n_four_bar_state(system.coordinates, N, 0.5, 2.0)
    rng = np.random.default_rng(4)
    on = projection(0.0, q + 1e-9 * rng.standard_normal(q.size), qd + 1e-9 * rng.standard_normal(q.size))
    phi, psi = system.constraint_residuals(0.0, on.q, on.qd)
    assert np.abs(phi).max() < 1e-14 and np.abs(psi).max() < 1e-13
    J, K = ref.n_four_bar_constants(N)
    rng = np.random.default_rng(5)
    for gap, served, agree in ((1.0, True, 1e-9), (1e-3, True, 1e-6), (1e-7, False, None)):
        psi, psi_dot = np.pi / 2 - gap, 2.0
        q, qd = ref.n_four_bar_state(system.coordinates, N, psi, psi_dot)
        if served:
            on = engine.motion(0.0, q, qd)
            assert on is not None
            psi_ddot = K / J * np.sin(psi)
            x_ddot = 0.5 * (np.cos(psi) * psi_ddot - np.sin(psi) * psi_dot**2)
            assert on.qdd[system.coordinates.index("v0.x")] == pytest.approx(x_ddot, rel=1e-9)
            exact = data._kkt_motion(0.0, q, qd, "reference", None, False)
            assert np.abs(on.qdd - exact.qdd).max() <= agree * np.abs(exact.qdd).max()
        q, qd = q + 1e-9 * rng.standard_normal(q.size), qd + 1e-9 * rng.standard_normal(q.size)
        stage = engine.motion(0.0, q, qd, None, True)
        assert (stage is not None) == served
        if served:
            exact = data._kkt_motion(0.0, q, qd, "reference", None, True)
            assert np.abs(stage.qdd - exact.qdd).max() <= agree * np.abs(exact.qdd).max()
