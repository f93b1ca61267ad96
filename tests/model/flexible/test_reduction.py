"""Craig–Bampton and free-interface reductions of the strip: the fixed-interface modes of a
beam held at both ends are the clamped–clamped beam's (analytic), the reduced clamped–free
beam's frequencies converge from above to the full FE model's as modes are added (lumped,
singular M too), a tip load's static deflection is PL³/3EI whatever the number of modes,
and the free-interface modes are the free–free beam's."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse

from tests.helpers.flexible_beams import CLAMPED_FREE, FREE_FREE, LENGTH, STRIP, euler_bernoulli, plane_share, strip, truss
from mbsynth.core.errors import ModelError
from mbsynth.model.flexible.matrices import fe_model
from mbsynth.model.flexible.reduction import craig_bampton, free_interface, normal_modes

N = 60  # elements


def finite_frequencies(M, K):
    """ω of a small reduced model; M may be singular (lumped: the tip's rotations carry no
    mass), its infinite ω dropped."""
    lam = scipy.linalg.eigvals(K, M)
    return np.sqrt(np.sort(lam[np.isfinite(lam)].real))


def test_fixed_interface_modes_are_the_clamped_clamped_beams():
    """Held at both ends (the interface), the beam's modes are clamped–clamped ones, whose
    βL are the free–free beam's; the basis is M-orthonormal there and K-orthogonal to the
    constraint modes, and η's interface columns are the interface nodes' DOFs."""
    fe = strip(100)
    reduced = craig_bampton(fe, [0, 100], count=12)
    full = reduced.basis[:, reduced.modes]
    xy = reduced.frequencies[plane_share(fe.mass, full, "xy") > 0.5][:3]
    np.testing.assert_allclose(xy, euler_bernoulli(FREE_FREE, STRIP["Iz"]), rtol=1e-6)
    m, k = reduced.modes, len(reduced.frequencies)
    np.testing.assert_allclose(reduced.mass[m, m], np.eye(k), atol=1e-10)
    np.testing.assert_allclose(reduced.stiffness[m, m], np.diag(reduced.frequencies**2), rtol=1e-9,
                               atol=1e-9 * reduced.frequencies.max() ** 2)
    assert np.abs(reduced.stiffness[:12, m]).max() < 1e-9 * np.abs(reduced.stiffness).max()
    for position, node in enumerate((0, 100)):
        rows, columns = reduced.node_rows(node), reduced.interface_columns(node)
        np.testing.assert_array_equal(columns, np.arange(6 * position, 6 * position + 6))
        expected = np.zeros((6, reduced.size))
        expected[:, columns] = np.eye(6)
        np.testing.assert_array_equal(reduced.basis[rows], expected)


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_craig_bampton_converges_to_the_full_model_as_modes_are_added(mass):
    """Interface at the root and the tip, root then held: each of the first five clamped–free
    frequencies approaches the unreduced FE model's from above (Rayleigh–Ritz), never
    worse for more modes, within 1e-6 (the first three) with 32 modes. Lumped: M singular."""
    fe = strip(N, mass=mass)
    free = np.arange(6, fe.size)
    exact, _ = normal_modes(fe.mass[free][:, free], fe.stiffness[free][:, free], count=5)
    errors = []
    for count in (0, 4, 8, 16, 32):
        reduced = craig_bampton(fe, [0, N], count=count).hold(0)
        errors.append(finite_frequencies(reduced.mass, reduced.stiffness)[:5] / exact - 1)
    errors = np.array(errors)
    assert np.all(errors > -1e-10)
    assert np.all(np.diff(errors, axis=0) < 1e-10)
    assert errors[-1, :3].max() < 1e-6 and errors[0, 0] > 1e-3


@pytest.mark.parametrize("theory, extra", [("euler_bernoulli", {}), ("timoshenko", dict(shear_factor=5 / 6))])
@pytest.mark.parametrize("count", [0, 8])
def test_a_tip_load_deflects_the_reduced_beam_as_the_closed_form(theory, extra, count):
    """Root held (``hold``), a force P along y at the tip: the tip's deflection is PL³/3EI
    (+ PL/κGA) and its rotation PL²/2EI, exactly (constraint modes are static solutions)."""
    fe = strip(N, theory=theory, **extra)
    reduced = craig_bampton(fe, [0, N], count=count).hold(0)
    np.testing.assert_array_equal(reduced.interface_columns(N), np.arange(6))
    load = np.zeros(reduced.size)
    load[1] = P = 3.0
    u = np.linalg.solve(reduced.stiffness, load)
    E, I, G = STRIP["E"], STRIP["Iz"], STRIP["E"] / (2 * (1 + STRIP["nu"]))
    shear = P * LENGTH / (extra["shear_factor"] * G * STRIP["area"]) if extra else 0.0
    np.testing.assert_allclose(u[[1, 5]], [P * LENGTH**3 / (3 * E * I) + shear, P * LENGTH**2 / (2 * E * I)], rtol=1e-8)
    np.testing.assert_allclose(reduced.basis[reduced.node_rows(N)] @ u, u[:6], rtol=1e-15)
    assert not reduced.basis[reduced.node_rows(0)].any()


def test_modes_by_frequency_are_every_mode_up_to_it():
    """max_frequency past the first batch of eigsh: the modes are the count-chosen ones
    up to that frequency, no more, no fewer."""
    fe = strip(N)
    by_count = craig_bampton(fe, [0, N], count=40).frequencies
    cut = (by_count[29] + by_count[30]) / 2 / (2 * np.pi)
    by_frequency = craig_bampton(fe, [0, N], max_frequency=cut).frequencies
    np.testing.assert_allclose(by_frequency, by_count[:30], rtol=1e-10)


def test_free_interface_modes_are_the_free_beams():
    fe = strip(100)
    with_rigid = free_interface(fe, [0, 100], count=8)
    assert np.all(with_rigid.frequencies[:6] < 1e-4 * with_rigid.frequencies[6])  # rounding of K
    flexible = free_interface(fe, [0, 100], count=8, rigid=False)
    np.testing.assert_allclose(flexible.frequencies[:2], with_rigid.frequencies[6:], rtol=1e-9)
    xy = flexible.frequencies[plane_share(fe.mass, flexible.basis, "xy") > 0.5][:3]
    np.testing.assert_allclose(xy, euler_bernoulli(FREE_FREE, STRIP["Iz"]), rtol=1e-6)
    np.testing.assert_allclose(flexible.mass, np.eye(8), atol=1e-10)
    with pytest.raises(ModelError, match=re.escape("node 100 has no coordinates of its own in this free_interface")):
        flexible.interface_columns(100)


def test_bad_reductions_are_refused():
    fe = strip(4)
    with pytest.raises(ModelError, match="choose the modes by count or by max_frequency"):
        craig_bampton(fe, [0], count=2, max_frequency=10.0)
    with pytest.raises(ModelError, match=re.escape("node 5 is not one of its 5 nodes (0..4)")):
        craig_bampton(fe, [0, 5], count=2)
    with pytest.raises(ModelError, match=re.escape("interface nodes [0, 0] repeat a node")):
        craig_bampton(fe, [0, 0], count=2)
    with pytest.raises(ModelError, match="K \\+ s M is singular for every s"):
        free_interface(strip(4, mass="lumped"), count=2)  # the twist about the axis: no mass, no stiffness


def test_an_interface_that_leaves_a_rigid_motion_is_refused():
    """A truss of point masses (3 DOFs per node) held at one node still turns about it, held
    at two about their line: K_ii is singular (exactly, or to rounding); three nodes hold it."""
    fe = truss()
    for interface in ([0], [0, 1]):
        with pytest.raises(ModelError, match=re.escape(f"with the interface nodes {interface} held, the stiffness is singular")):
            craig_bampton(fe, interface, count=2)
    assert craig_bampton(fe, [0, 1, 2], count=2).size == 11


@pytest.mark.parametrize("elements", [3, 30])  # 18 DOFs: the dense solver; 180: eigsh
def test_a_singular_lumped_mass_gives_the_statically_condensed_modes(elements):
    """Clamped–free with lumped mass (rotations massless): the modes are those of the
    classical static condensation, K* = K_tt − K_tr K_rr⁻¹ K_rt against the translation
    masses; all 3 × elements of them finite, no more."""
    fe = strip(elements, mass="lumped")
    free = np.arange(6, fe.size)
    M, K = fe.mass[free][:, free].toarray(), fe.stiffness[free][:, free].toarray()
    t = np.diag(M) > 0
    condensed = K[np.ix_(t, t)] - K[np.ix_(t, ~t)] @ np.linalg.solve(K[np.ix_(~t, ~t)], K[np.ix_(~t, t)])
    exact = np.sqrt(scipy.linalg.eigh(condensed, M[np.ix_(t, t)], eigvals_only=True))
    count = 3 * elements if elements == 3 else 8
    omega, shapes = normal_modes(M, K, count=count)
    np.testing.assert_allclose(omega, exact[:count], rtol=1e-9)
    np.testing.assert_allclose(shapes.T @ M @ shapes, np.eye(count), atol=1e-10)
    if elements == 3:
        with pytest.raises(ModelError, match="10 modes asked for, but the mass matrix gives only 9 finite ones"):
            normal_modes(M, K, count=10)


ROUND = dict(Iy=STRIP["Iz"])  # a round strip: each bending frequency twice, once per plane


@pytest.mark.parametrize("elements, mesh", [(10, 4e-5), (60, 1e-7)])  # 60 interior DOFs: dense; 360: eigsh
def test_a_round_beams_equal_modes_come_whole_in_the_section_planes(elements, mesh):
    """Clamped at node 0, a round strip's fixed-interface modes come in pairs at the clamped–free
    Euler–Bernoulli frequencies (to the mesh's error); each pair's basis is fixed: its first shape bends the strip in
    the section's xy plane, the second in xz, each positive where it moves most, whatever
    basis the solver gave (another eigsh start: the same shapes). A count that would split a
    pair is refused; max_frequency takes pairs whole."""
    fe = strip(elements, **ROUND)
    reduced = craig_bampton(fe, [0], count=4)
    shapes = reduced.basis[:, reduced.modes]
    np.testing.assert_allclose(reduced.frequencies, np.repeat(euler_bernoulli(CLAMPED_FREE[:2], STRIP["Iz"]), 2),
                               rtol=mesh)
    np.testing.assert_allclose(plane_share(fe.mass, shapes, "xy"), [1, 0, 1, 0], atol=1e-9)
    energy = np.sqrt(fe.mass.diagonal())[:, None] * shapes  # the sign: + where √M_jj |φ_j| is largest
    assert np.all(shapes[np.argmax(np.abs(energy), axis=0), range(4)] > 0)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("mbsynth.model.flexible.reduction.START_SEED", 12345)
        again = craig_bampton(fe, [0], count=4).basis[:, reduced.modes]
    np.testing.assert_allclose(again, shapes, atol=1e-7 * np.abs(shapes).max())
    with pytest.raises(ModelError, match=re.escape("3 modes would split modes 3 to 4, which share the frequency "
                                                   f"{reduced.frequencies[2] / (2 * np.pi):.6g}"
                                                   " Hz (a repeated mode, as a round section's two bending planes): "
                                                   "ask for 2 or 4 modes")):
        craig_bampton(fe, [0], count=3)
    cut = reduced.frequencies[2] * (1 + 1e-6) / (2 * np.pi)  # just above the second pair, halfway into its rounding
    assert len(craig_bampton(fe, [0], max_frequency=cut).frequencies) == 4


def test_free_interface_gives_every_mode_asked_for_or_refuses():
    """A free strip of 2 elements has 18 finite modes, 6 of them rigid-body ones: 12 flexible
    modes asked for are 12 given (the dense solver's, as scipy's generalized eigh finds them),
    13 are refused. On eigsh's side (n − 2 modes at most) too many are refused by that limit."""
    fe = strip(2)
    flexible = free_interface(fe, count=12, rigid=False)
    exact = np.sqrt(scipy.linalg.eigh(fe.stiffness.toarray(), fe.mass.toarray(), eigvals_only=True)[6:])
    np.testing.assert_allclose(flexible.frequencies, exact, rtol=1e-9)
    with pytest.raises(ModelError, match="13 modes asked for, but the mass matrix gives only 12 finite ones besides "
                                         "the rigid-body ones"):
        free_interface(fe, count=13, rigid=False)
    with pytest.raises(ModelError, match=re.escape("120 modes asked for, but eigsh finds only 118 besides the "
                                                   "rigid-body ones (at most n − 2 = 124 modes)")):
        free_interface(strip(20), count=120, rigid=False)


def test_a_2000_element_beam_reduces_in_seconds_to_the_closed_form():
    """Craig–Bampton of a clamped round strip of 2,000 elements (12,006 DOFs; its ω² span 10¹⁴):
    the first three bending pairs at the Euler–Bernoulli frequencies to 1e-5 (rounding of the
    stiff matrix: ~1e-5), within the test's time limit."""
    fe = strip(2000, **ROUND)
    reduced = craig_bampton(fe, [0], count=6)
    np.testing.assert_allclose(reduced.frequencies, np.repeat(euler_bernoulli(CLAMPED_FREE, STRIP["Iz"]), 2),
                               rtol=1e-5)
    np.testing.assert_allclose(plane_share(fe.mass, reduced.basis[:, reduced.modes], "xy"), [1, 0] * 3, atol=1e-9)


def test_an_unconnected_piece_is_refused():
    """Two strips in one FE model, the interface on the first only: the second is free with the
    interface held, which Craig–Bampton refuses (its rigid-body geometry is stopped, the piece
    is not)."""
    one, two = strip(4), strip(4)
    both = fe_model(scipy.sparse.block_diag([one.mass, two.mass]), scipy.sparse.block_diag([one.stiffness, two.stiffness]),
                    np.vstack([one.nodes, two.nodes + [0.0, 1.0, 0.0]]))
    with pytest.raises(ModelError, match=re.escape("with the interface nodes [0] held, the stiffness is singular")):
        craig_bampton(both, [0], count=2)


def test_a_round_beams_reductions_are_the_same_in_two_processes():
    """A pinned round strip's free-interface modes (pairs kept whole) and its Craig–Bampton
    reduction, on eigsh's side: byte for byte the same bases and frequencies in two processes."""
    script = ("import hashlib; from tests.helpers.flexible_beams import strip, STRIP; "
              "from mbsynth.model.flexible.reduction import craig_bampton, free_interface; "
              "fe = strip(60, Iy=STRIP['Iz']); "
              "rs = [free_interface(fe, [0], count=4, rigid=False), craig_bampton(fe, [0, 60], count=6)]; "
              "print([(len(r.frequencies), hashlib.sha256(r.basis.tobytes() + r.frequencies.tobytes()).hexdigest()) "
              "for r in rs])")
    root = Path(__file__).resolve().parents[3]  # the repository: tests.helpers and this mbsynth
    runs = [subprocess.Popen([sys.executable, "-c", script], cwd=root, stdout=subprocess.PIPE, text=True)
            for _ in range(2)]
    outs = [run.communicate(timeout=120)[0] for run in runs]
    assert all(run.returncode == 0 for run in runs)
    assert outs[0] == outs[1] and "(4, " in outs[0] and "(6, " in outs[0]


def test_a_beam_finer_than_double_precision_resolves_is_refused_in_seconds():
    """100,008 DOFs: 16,667 Euler–Bernoulli elements spread ω² over 10¹⁸, past the rounding
    level of K; Craig–Bampton refuses them with that reason (from Rayleigh's bound, before any
    eigen-solve). As many Timoshenko elements (ω² spread ∝ elements²) reduce, to the same beam
    of 1,000 elements within 1e-5 (rounding: 2e-6)."""
    with pytest.raises(ModelError, match=re.escape("its lowest mode, ω² ≤ 206 (rad/s)², is at the rounding level of K")
                       + ".*Euler–Bernoulli beam's ω² spread grows as elements⁴"):
        craig_bampton(strip(16667, **ROUND), [0], count=2)
    timoshenko = dict(ROUND, theory="timoshenko", shear_factor=5 / 6)
    fine = craig_bampton(strip(16667, **timoshenko), [0], count=2).frequencies
    np.testing.assert_allclose(fine, craig_bampton(strip(1000, **timoshenko), [0], count=2).frequencies, rtol=1e-5)
