"""The beam generator against closed forms: its element matrices against the textbook's
(Przemieniecki's Timoshenko stiffness, the cubic Hermite consistent mass and geometric
stiffness), the analytic Euler–Bernoulli frequencies of free–free and clamped–free beams,
Timoshenko's frequencies of a simply supported stubby beam, the static tip deflection and
twist of a beam along a slanted axis, lumped and consistent mass converging to one
another, Euler's buckling load and the frequencies of a beam under tension."""

import re

import numpy as np
import pytest
import scipy.linalg

from tests.helpers.flexible_beams import CLAMPED_FREE, FREE_FREE, LENGTH, STRIP, euler_bernoulli, plane_modes, plane_share, strip
from mbsynth.core.errors import ModelError
from mbsynth.model.flexible.beam import _bending, beam, geometric_stiffness
from mbsynth.model.flexible.reduction import normal_modes


def test_bending_matrices_are_the_textbooks():
    """Przemieniecki (1968) for the Timoshenko stiffness with Φ; the cubic Hermite consistent
    mass ρAh/420 [156 22h 54 −13h; ...] for Φ = 0, no rotary inertia."""
    h, EI, phi = 0.7, 3.0, 0.4
    K, _ = _bending(h, EI, phi, 1.0, 0.0)
    expected = EI / ((1 + phi) * h**3) * np.array([
        [12, 6 * h, -12, 6 * h], [6 * h, (4 + phi) * h * h, -6 * h, (2 - phi) * h * h],
        [-12, -6 * h, 12, -6 * h], [6 * h, (2 - phi) * h * h, -6 * h, (4 + phi) * h * h]])
    np.testing.assert_allclose(K, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())
    _, M = _bending(h, EI, 0.0, 2.5, 0.0)
    expected = 2.5 * h / 420 * np.array([
        [156, 22 * h, 54, -13 * h], [22 * h, 4 * h * h, 13 * h, -3 * h * h],
        [54, 13 * h, 156, -22 * h], [-13 * h, -3 * h * h, -22 * h, 4 * h * h]])
    np.testing.assert_allclose(M, expected, rtol=1e-13, atol=1e-15)
    KG = geometric_stiffness(h, 1, 2.0).toarray()[np.ix_([1, 5, 7, 11], [1, 5, 7, 11])]
    expected = 2.0 / (30 * h) * np.array([
        [36, 3 * h, -36, 3 * h], [3 * h, 4 * h * h, -3 * h, -h * h],
        [-36, -3 * h, 36, -3 * h], [3 * h, -h * h, -3 * h, 4 * h * h]])
    np.testing.assert_allclose(KG, expected, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("plane, I", [("xy", STRIP["Iz"]), ("xz", STRIP["Iy"])])
def test_free_free_and_clamped_free_frequencies_are_euler_bernoullis(plane, I):
    """With 100 consistent elements the first three bending frequencies of each plane are
    the analytic ones to 1e-6 (the βL given to 8 digits carry ~1e-8); the free beam's six
    rigid-body modes come first at zero."""
    fe = strip(100)
    np.testing.assert_allclose(plane_modes(fe, [], plane, 3), euler_bernoulli(FREE_FREE, I), rtol=1e-6)
    np.testing.assert_allclose(plane_modes(fe, np.arange(6), plane, 3), euler_bernoulli(CLAMPED_FREE, I), rtol=1e-6)


def test_the_rigid_body_modes_of_a_free_beam_have_zero_frequency():
    fe = strip(40)
    omega, _ = normal_modes(fe.mass, fe.stiffness, count=7)
    first_bending = euler_bernoulli(FREE_FREE[0], STRIP["Iz"])
    assert np.all(omega[:6] < 1e-4 * first_bending)  # rounding of K
    np.testing.assert_allclose(omega[6], first_bending, rtol=1e-5)


def timoshenko_simply_supported(n, L, E, G, rho, A, I, kappa):
    """The lower root ω of (κGAk² − ρAω²)(EIk² + κGA − ρIω²) = (κGAk)², k = nπ/L: the
    simply supported Timoshenko beam (w = W sin kx, ψ = Ψ cos kx)."""
    k, a = n * np.pi / L, kappa * G * A
    c2, c1, c0 = rho * A * rho * I, -(rho * A * (E * I * k * k + a) + rho * I * a * k * k), a * E * I * k**4
    return np.sqrt((-c1 - np.sqrt(c1 * c1 - 4 * c2 * c0)) / (2 * c2))


def test_timoshenko_converges_to_the_closed_form_of_a_stubby_beam():
    """A 1 m beam of 0.1 m square section (shear and rotary inertia lower its first
    frequencies by 2 % and 6 %): simply supported, the first two frequencies converge to
    Timoshenko's closed form at second order (the element's shear strain is constant),
    within 1e-6 and 1e-5 at 160 elements."""
    L, E, nu, rho, b, kappa = 1.0, 2.1e11, 0.3, 7850.0, 0.1, 5 / 6
    A, I, G = b * b, b**4 / 12, E / (2 * (1 + nu))
    exact = np.array([timoshenko_simply_supported(n, L, E, G, rho, A, I, kappa) for n in (1, 2)])
    assert exact[0] < 0.99 * euler_bernoulli(np.pi, I, E, rho, A, L)
    errors = []
    for N in (40, 80, 160):
        fe = beam(L, N, area=A, Iy=I, Iz=2 * I, J=0.14 * b**4, E=E, nu=nu, density=rho,
                  theory="timoshenko", shear_factor=kappa)
        held = [0, 1, 2, 3, 6 * N + 1, 6 * N + 2]  # pinned ends, no axial or twist drift
        errors.append(plane_modes(fe, held, "xz", 2) / exact - 1)
    errors = np.array(errors)
    assert np.all(errors > 0)  # Ritz: from above
    np.testing.assert_allclose(errors[:-1] / errors[1:], 4.0, rtol=0.02)
    assert errors[-1, 0] < 1e-6 and errors[-1, 1] < 1e-5


def test_a_slender_timoshenko_beam_approaches_euler_bernoulli():
    """The strip and its sections scaled by ½ and ¼ (radius of gyration r/L = 1.6e-3 down
    to 4e-4): the Timoshenko frequencies lie below Euler–Bernoulli's by a shear and rotary
    projection of order (r/L)², a quarter per halving of r, while Euler–Bernoulli's stay
    the analytic ones to 1e-6."""
    gaps = []
    for s in (1.0, 0.5, 0.25):
        section = dict(area=STRIP["area"] * s**2, Iy=STRIP["Iy"] * s**4, Iz=STRIP["Iz"] * s**4, J=STRIP["J"] * s**4)
        exact = euler_bernoulli(CLAMPED_FREE, section["Iz"], A=section["area"])
        timoshenko = plane_modes(strip(100, **section, theory="timoshenko", shear_factor=5 / 6), np.arange(6), "xy", 3)
        np.testing.assert_allclose(plane_modes(strip(100, **section), np.arange(6), "xy", 3), exact, rtol=1e-6)
        gaps.append(1 - timoshenko / exact)
    gaps = np.array(gaps)
    assert np.all(gaps > 0) and gaps[0, 0] < 1e-4
    np.testing.assert_allclose(gaps[:-1] / gaps[1:], 4.0, rtol=0.02)


def test_lumped_and_consistent_mass_converge_to_one_another():
    """The clamped–free strip with lumped (singular: rotations massless) and consistent
    mass: their frequencies differ by O(h²), a quarter per halving of the elements, and
    both approach the analytic ones."""
    gaps, exact = [], euler_bernoulli(CLAMPED_FREE, STRIP["Iz"])
    for N in (20, 40, 80):
        lumped = plane_modes(strip(N, mass="lumped"), np.arange(6), "xy", 3)
        consistent = plane_modes(strip(N), np.arange(6), "xy", 3)
        gaps.append(np.abs(lumped / consistent - 1))
    gaps = np.array(gaps)
    np.testing.assert_allclose(gaps[:-1] / gaps[1:], 4.0, rtol=0.02)
    assert gaps[-1].max() < 5e-4
    np.testing.assert_allclose(lumped, exact, rtol=5e-4)


def test_lumped_mass_gives_rotations_none():
    fe = strip(4, mass="lumped")
    diagonal = fe.mass.diagonal().reshape(-1, 6)
    assert np.all(diagonal[:, 3:] == 0) and fe.mass.nnz == 3 * 5
    np.testing.assert_allclose(fe.mass.sum() / 3, STRIP["density"] * STRIP["area"] * LENGTH, rtol=1e-14)


def test_a_slanted_beam_deflects_and_twists_as_the_closed_forms_say():
    """A cantilever along a slanted axis with its section turned (``up``): under a tip force
    along its local y the tip moves PL³/3EI_z + PL/κGA (Timoshenko, exact for end loads);
    a torque about its axis twists it TL/GJ, an axial force stretches it PL/EA."""
    L, A, Iy, Iz, J, E, G, kappa = 1.5, 2e-4, 3e-8, 1e-8, 2e-8, 7e10, 2.6e10, 0.85
    axis = np.array([1.0, 2.0, 2.0]) / 3
    up = np.array([0.0, 0.0, 1.0])
    z = up - (up @ axis) * axis
    z /= np.linalg.norm(z)
    y = np.cross(z, axis)
    fe = beam(L, 7, area=A, Iy=Iy, Iz=Iz, J=J, E=E, G=G, density=2700.0, theory="timoshenko",
              shear_factor=kappa, start=(1.0, -1.0, 0.5), axis=axis, up=up)
    np.testing.assert_allclose(fe.nodes[-1], np.array([1.0, -1.0, 0.5]) + L * axis, rtol=1e-14)
    free = np.arange(6, fe.size)
    K = fe.stiffness[free][:, free].toarray()
    tip = slice(-6, None)
    for load, along, expected in ((np.r_[y, 0, 0, 0], y, L**3 / (3 * E * Iz) + L / (kappa * G * A)),
                                  (np.r_[axis, 0, 0, 0], axis, L / (E * A))):
        f = np.zeros(len(free))
        f[tip] = load
        u = np.linalg.solve(K, f)[tip][:3]
        np.testing.assert_allclose(u, expected * along, rtol=1e-9, atol=1e-9 * expected)  # each component to 1e-9 of the deflection: the solve rounds at κ(K) ε
    f = np.zeros(len(free))
    f[tip] = np.r_[0, 0, 0, axis]
    np.testing.assert_allclose(np.linalg.solve(K, f)[tip][3:], L / (G * J) * axis, rtol=1e-9)


@pytest.mark.parametrize("change, message", [
    (dict(theory="kirchhoff"), "theory must be one of euler_bernoulli, timoshenko"),
    (dict(mass="diagonal"), "mass must be one of consistent, lumped"),
    (dict(theory="timoshenko"), "a Timoshenko beam needs shear_factor"),
    (dict(shear_factor=0.8), "shear_factor is for theory: timoshenko"),
    (dict(G=8e10), "give exactly one of G (shear modulus) and nu"),
    (dict(area=-1.0), "area must be a positive number"),
    (dict(up=(2.0, 0.0, 0.0)), "up must be a 3-vector not parallel to the axis"),
])
def test_bad_beams_are_refused_by_name(change, message):
    with pytest.raises(ModelError, match="^beam: " + re.escape(message)):
        beam(LENGTH, 4, **{**STRIP, **change})


def test_a_slanted_cantilever_buckles_at_eulers_load():
    """K + K_G(−P) turns singular first at P = π²EI/4L² (the weaker plane): with 40
    elements to 1e-6."""
    axis = np.array([2.0, -1.0, 2.0]) / 3
    fe = beam(LENGTH, 40, **STRIP, axis=axis, up=(0.0, 1.0, 0.0))
    free = np.arange(6, fe.size)
    K = fe.stiffness[free][:, free].toarray()
    KG = geometric_stiffness(LENGTH, 40, 1.0, axis=axis)[free][:, free].toarray()
    largest = scipy.linalg.eigh(KG, K, eigvals_only=True, subset_by_index=[len(free) - 1, len(free) - 1])[0]
    np.testing.assert_allclose(1 / largest, np.pi**2 * STRIP["E"] * STRIP["Iz"] / (4 * LENGTH**2), rtol=1e-6)


def test_tension_stiffens_a_simply_supported_beam_as_the_closed_form_says():
    """ω_n² = ((nπ/L)⁴ EI + (nπ/L)² P) / ρA for a simply supported beam under tension P
    (here P doubling the first frequency's square); per-element forces given as an array."""
    E, I, A, rho, N = STRIP["E"], STRIP["Iz"], STRIP["area"], STRIP["density"], 100
    P = (np.pi / LENGTH) ** 2 * E * I
    fe = strip(N)
    K = fe.stiffness + geometric_stiffness(LENGTH, N, np.full(N, P))
    held = np.r_[0, 1, 2, 3, 6 * N + 1, 6 * N + 2]
    keep = np.setdiff1d(np.arange(fe.size), held)
    omega, shapes = normal_modes(fe.mass[keep][:, keep], K[keep][:, keep], count=6)
    k = np.arange(1, 4) * np.pi / LENGTH
    exact = np.sqrt((k**4 * E * I + k**2 * P) / (rho * A))
    full = np.zeros((fe.size, 6))
    full[keep] = shapes
    np.testing.assert_allclose(omega[plane_share(fe.mass, full, "xy") > 0.5][:3], exact, rtol=1e-6)


def test_a_geometric_stiffness_needs_one_force_per_element():
    message = "force must be a finite number or 4 of them (one per element), got shape (3,)"
    with pytest.raises(ModelError, match=re.escape(message)):
        geometric_stiffness(LENGTH, 4, [1.0, 2.0, 3.0])
