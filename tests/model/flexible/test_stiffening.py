"""Centrifugal stiffening (model/flexible/stiffening.py): the spin's member forces against the
closed form, energy kept with the stiffening term in T, and the spin-up beam of Kane, Ryan and
Banerjee (1987) against a geometrically exact reference computed here."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mbsynth as mb
from mbsynth.core.errors import ModelError
from mbsynth.model.flexible.beam import beam, geometric_stiffness, stress_stiffness
from mbsynth.model.flexible.reduction import craig_bampton, free_interface
from mbsynth.model.flexible.stiffening import centrifugal_stiffening

SPIN_UP = Path(__file__).parents[3] / "models" / "flexible" / "spin_up_beam.yaml"
# Kane, Ryan & Banerjee's beam: EA = 2.8e7 N, EI = 1.4e4 N m², ρA = 1.2 kg/m, L = 10 m
L, EI, RHO_A, TS, WS = 10.0, 1.4e4, 1.2, 15.0, 6.0
SECTION = dict(area=4e-4, Iy=2e-7, Iz=2e-7, J=4e-7, E=7e10, nu=0.3, density=3000.0)


@pytest.mark.parametrize("hub", [0.0, 2.5])
def test_the_spins_member_forces_are_the_closed_form(hub):
    """A beam along x from x = hub, held at its root: spun about z (or y) at unit rate its axial
    force is N(s) = ρA ∫_s^L (hub + σ) dσ; the FE solve of the load case gives each element the
    mean of N over it exactly (linear axial elements under consistent loads), so S_zz = S_yy =
    Φᵀ K_G(N̄) Φ to rounding. A spin about the beam's own axis (x) and the mixed cases load it
    across only: no axial force, S zero."""
    elements = 10
    fe = beam(L, elements, **SECTION, start=(hub, 0.0, 0.0))
    reduction = craig_bampton(fe, [0], count=4).hold(0)
    S = centrifugal_stiffening(reduction, stress_stiffness(L, elements, **SECTION))
    s = np.linspace(0.0, L, elements + 1)

    def integral(a):  # ∫_a^L N(σ) dσ with N(σ) = ρA((hub + L)² − (hub + σ)²)/2
        return RHO_A / 2 * ((hub + L) ** 2 * (L - a) - ((hub + L) ** 3 - (hub + a) ** 3) / 3)
    mean = (integral(s[:-1]) - integral(s[1:])) / np.diff(s)
    Phi = reduction.basis
    expected = Phi.T @ geometric_stiffness(L, elements, mean) @ Phi
    scale = np.abs(expected).max()
    for a in (1, 2):
        np.testing.assert_allclose(S[a, a], expected, atol=1e-12 * scale)
    for a, b in ((0, 0), (0, 1), (0, 2), (1, 2)):
        assert np.abs(S[a, b]).max() < 1e-12 * scale


def test_stiffening_needs_a_held_node_and_member_forces(tmp_path):
    fe = beam(L, 4, **SECTION)
    with pytest.raises(ModelError, match="needs a reference node held"):
        centrifugal_stiffening(free_interface(fe, count=2, rigid=False), stress_stiffness(L, 4, **SECTION))
    from mbsynth.model.flexible.files import write_fe
    write_fe(fe, tmp_path / "rod.npz")
    (tmp_path / "m.yaml").write_text("""parts:
  rod:
    type: flexible_body
    fe: {bundle: rod.npz}
    reduction: {method: craig_bampton, interface: [0], modes: 2}
    stiffening: true
""")
    with pytest.raises(ModelError, match=r"m\.yaml:6: at parts\.rod\.stiffening: .*beam: parts"):
        mb.load(tmp_path / "m.yaml")


def test_a_spinning_stiffened_body_keeps_its_energy():
    """A soft rod thrown spinning about all three axes, stiffening on, no gravity or damping:
    the stiffening is a term of T, so T + V stays within 1e-9 of T while the modes trade energy
    with the spin (the elastic energy varies by more than 1e-4 of T) and the stiffening's
    share of T is no rounding (its ωᵀ[ηᵀSη]ω is above 1e-6 of T somewhere)."""
    model = mb.loads("""
parts:
  rod:
    type: flexible_body
    beam: {length: 1.0, elements: 10, area: 1e-4, Iy: 2e-9, Iz: 1e-9, J: 2e-9, E: 2e8, nu: 0.3, density: 1000}
    reduction: {method: craig_bampton, interface: [0], modes: 4}
    stiffening: true
    initial: {velocity: [0.1, 0, 0], angular_velocity: [0.5, 2.0, 3.0], amplitudes: [1e-3, -1e-3, 5e-4, 2e-4]}
""")
    part = model.parts[0]
    run = mb.simulate(model, 0.2)
    energies = np.array([model.energy(t, q, qd) for t, q, qd in zip(run.t, run.q, run.qd)])
    kinetic, elastic = energies[:, 0], energies[:, 1]
    assert np.ptp(elastic) > 1e-4 * kinetic.max()
    assert run.energy_drift < 1e-9
    share = []
    for q, qd in zip(run.q, run.qd):
        u, u_dot, eta = q[3:7], qd[3:7], q[7:]
        w, x, y, z = u
        E = np.array([[-x, w, z, -y], [-y, -z, w, x], [-z, y, -x, w]])
        omega = 2 * E @ u_dot  # the body-axes angular velocity
        share.append(omega @ np.einsum("abkl,k,l->ab", part.stiffening, eta, eta) @ omega / 2)
    assert max(share) > 1e-6 * kinetic.max()


def chain_tip(links, times):
    """The geometrically exact reference: the beam as ``links`` rigid links with point masses
    ρAℓ at their ends (ρAℓ/2 at the tip) and rotational springs EI/ℓ between them (2EI/ℓ at the
    clamp: a bar chain, second order in ℓ), on the hub turned by θ(t); absolute link angles ψ,
    Lagrange's equations M(ψ)ψ̈ + ℓ² μ sin(ψ_j − ψ_k) ψ̇_k² = −∂V/∂ψ. Returns the tip's deflection
    across the hub's radial line at ``times``."""
    ell = L / links
    m = np.full(links, RHO_A * ell)
    m[-1] /= 2
    mu = np.cumsum(m[::-1])[::-1][np.maximum.outer(np.arange(links), np.arange(links))]
    k = np.full(links, EI / ell)
    k[0] *= 2

    def rhs(t, y):
        psi, rate = y[:links], y[links:]
        d = np.subtract.outer(psi, psi)
        force = k * np.diff(np.concatenate([[hub_angle(t)], psi]))
        dV = force - np.append(force[1:], 0.0)
        return np.concatenate([rate, np.linalg.solve(ell**2 * mu * np.cos(d),
                                                     -ell**2 * (mu * np.sin(d)) @ rate**2 - dV)])
    run = solve_ivp(rhs, (0.0, times[-1]), np.zeros(2 * links), method="LSODA", rtol=1e-9, atol=1e-11,
                    t_eval=times)
    psi, theta = run.y[:links], hub_angle(run.t)
    x, y = ell * np.cos(psi).sum(0), ell * np.sin(psi).sum(0)
    return -x * np.sin(theta) + y * np.cos(theta)


def hub_angle(t):
    """θ(t) of the spin-up, 0 ≤ t ≤ Ts."""
    return WS / TS * (t**2 / 2 + (TS / (2 * np.pi)) ** 2 * (np.cos(2 * np.pi * t / TS) - 1))


@pytest.mark.slow  # 10 s of the spin-up beam, with and without stiffening, and the bar chains
def test_the_spin_up_beam_with_stiffening_follows_the_exact_beam_and_without_it_diverges():
    """models/flexible/spin_up_beam.yaml (10 elements, 6 Craig–Bampton modes, stiffening on)
    against the bar chain of 10 and 20 links, extrapolated to zero link length (Richardson,
    the chain's error ∝ ℓ²): the tip's deflection over the spin-up (its trough −0.574 m at
    t = 6.75 s) within 1e-3 m of it at every quarter second (actual 4.5e-4). The same beam without stiffening
    passes its first bending frequency (3.8 rad/s, at t ≈ 9.5 s) and diverges: by t = 10 s its
    tip is further than the beam's length off the radial line."""
    times = np.arange(0.0, TS + 1e-9, 0.25)
    coarse, fine = chain_tip(10, times), chain_tip(20, times)
    exact = fine + (fine - coarse) / 3
    text = SPIN_UP.read_text()
    run = mb.simulate(mb.load(SPIN_UP), TS, dt=0.25, rtol=1e-8, atol=1e-8)
    theta = run.column("hub")
    tip = -run.column("tip[x]") * np.sin(theta) + run.column("tip[y]") * np.cos(theta)
    np.testing.assert_allclose(run.t, times, atol=1e-9)
    assert np.abs(tip - exact).max() < 1e-3
    assert exact.min() < -0.5  # the reference's trough: the test compares a real transient
    soft = mb.loads(text.replace("stiffening: true", "stiffening: false"))
    run = mb.simulate(soft, 10.0, dt=0.25, rtol=1e-8, atol=1e-8)
    theta = run.column("hub")
    assert np.abs(-run.column("tip[x]") * np.sin(theta) + run.column("tip[y]") * np.cos(theta)).max() > L
