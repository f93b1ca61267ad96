"""Closed loops and massless links against independent references: a four-bar linkage
(planar bodies, and rigid bodies whose loop has redundant rows) and a slider-crank against
their single-degree-of-freedom equation M(θ) θ̈ + ½ M'(θ) θ̇² + V'(θ) = 0 derived here from
the loop geometry; a massless rod against a distance joint and the rod's closed form; the
free spin of a massless link as the one indeterminate direction."""

import functools
import json
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.analysis.diagnose import diagnose
from mbsynth.core.equations import rank_report, term_scales
from tests.helpers.rotations import G, R, body_coordinates

MECHANISMS = Path(__file__).resolve().parents[2] / "models" / "mechanisms"
THETA = sp.Symbol("theta")
load = functools.cache(lambda name: mb.load(MECHANISMS / name))  # each model compiled once


class OneDof:
    """A one-degree-of-freedom planar mechanism in its input angle θ, from each body's pose
    (x, y, φ)(θ), mass and moment of inertia (sympy, closed form):
    T = ½ M(θ) θ̇², M = Σ m (x'² + y'²) + I φ'², V = g Σ m y, and Lagrange's equation
    θ̈ = −(½ M' θ̇² + V') / M. The poses' second time derivative is q' θ̈ + q'' θ̇²."""

    def __init__(self, bodies, g):
        pose = sp.Matrix([e for x, y, phi, _, _ in bodies for e in (x, y, phi)])
        d1 = pose.diff(THETA)
        M = sum(m * (d1[3 * i] ** 2 + d1[3 * i + 1] ** 2) + inertia * d1[3 * i + 2] ** 2
                for i, (_, _, _, m, inertia) in enumerate(bodies))
        V = g * sum(m * y for _, y, _, m, _ in bodies)
        self._pose = sp.lambdify(THETA, [pose, d1, d1.diff(THETA)], modules="numpy", cse=True)
        self._mass = sp.lambdify(THETA, [M, M.diff(THETA), V.diff(THETA)], modules="numpy", cse=True)

    def acceleration(self, theta, theta_dot):
        M, dM, dV = self._mass(theta)
        return -(dM * theta_dot**2 / 2 + dV) / M

    def state(self, theta, theta_dot):
        """(q, q̇, q̈) of the bodies' planar coordinates (x, y, φ per body)."""
        q, d1, d2 = (np.asarray(x, dtype=float).ravel() for x in self._pose(theta))
        return q, d1 * theta_dot, d1 * self.acceleration(theta, theta_dot) + d2 * theta_dot**2


def four_bar(p):
    """Crank OB = a at angle θ, coupler BC = b at β (centre of mass h off BC), rocker DC = c
    at γ, O = (0, 0), D = (d, 0): C is where the circles about B (radius b) and D (radius c)
    meet, on the side the model is assembled (β = ∠(D − B) + arccos((b² + ℓ² − c²)/(2bℓ)))."""
    a, b, c, d, h = (p[k] for k in "abcdh")
    B = sp.Matrix([a * sp.cos(THETA), a * sp.sin(THETA)])
    e = sp.Matrix([d, 0]) - B
    ell = sp.sqrt(e.dot(e))
    beta = sp.atan2(e[1], e[0]) + sp.acos((b**2 + ell**2 - c**2) / (2 * b * ell))
    along, normal = sp.Matrix([sp.cos(beta), sp.sin(beta)]), sp.Matrix([-sp.sin(beta), sp.cos(beta)])
    C = B + b * along
    coupler = B + b / 2 * along + h * normal
    return OneDof([(B[0] / 2, B[1] / 2, THETA, p["m1"], p["m1"] * a**2 / 12),
                   (coupler[0], coupler[1], beta, p["m2"], p["I2"]),
                   ((d + C[0]) / 2, C[1] / 2, sp.atan2(C[1], C[0] - d), p["m3"], p["m3"] * c**2 / 12)], p["g"])


def slider_crank(p):
    """Crank OB = a at θ, rod BC = b, slider C on the line y = e:
    x_C = a cos θ + √(b² − (e − a sin θ)²), rod angle atan2(e − a sin θ, x_C − a cos θ)."""
    a, b, e = p["a"], p["b"], p["e"]
    B = sp.Matrix([a * sp.cos(THETA), a * sp.sin(THETA)])
    rise = e - B[1]
    run = sp.sqrt(b**2 - rise**2)
    beta = sp.atan2(rise, run)
    return OneDof([(B[0] / 2, B[1] / 2, THETA, p["m1"], p["m1"] * a**2 / 12),
                   (B[0] + run / 2, (B[1] + e) / 2, beta, p["m2"], p["m2"] * b**2 / 12),
                   (B[0] + run, e, 0, p["m3"], p["I3"])], p["g"])


def rigid_from_planar(q, qd):
    """Rigid-body coordinates (x, y, 0, cos φ/2, 0, 0, sin φ/2) of planar poses (x, y, φ)."""
    rows = [body_coordinates([x, y, 0.0], Rz(phi), [xd, yd, 0.0], [0.0, 0.0, phid])
            for (x, y, phi), (xd, yd, phid) in zip(q.reshape(-1, 3), qd.reshape(-1, 3))]
    return np.concatenate([r[0] for r in rows]), np.concatenate([r[1] for r in rows])


def planar_from_rigid(q, qdd):
    """(ẍ, ÿ, φ̈) per body from rigid-body accelerations, and the out-of-plane ones (z̈, ω̇x, ω̇y)."""
    planar, spatial = [], []
    for body, acc in zip(q.reshape(-1, 7), qdd.reshape(-1, 7)):
        omega_dot = 2 * G(body[3:]) @ acc[3:]  # G(u̇) u̇ = 0
        planar += [acc[0], acc[1], omega_dot[2]]
        spatial += [acc[2], omega_dot[0], omega_dot[1]]
    return np.array(planar), np.array(spatial)


def Rz(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


# model, reference, rigid bodies?, (m, rank A): n − rank A = 1 degree of freedom
LOOPS = [("four_bar.yaml", four_bar, False, (8, 8)),
         ("four_bar_3d.yaml", four_bar, True, (23, 20)),
         ("slider_crank.yaml", slider_crank, False, (8, 8))]


@pytest.mark.parametrize("name, geometry, rigid, rows", LOOPS)
def test_closed_loop_matches_its_one_degree_of_freedom_equation(name, geometry, rigid, rows):
    """At random crank angles and rates every body's acceleration equals the one of the
    hand-derived θ̈; the dependent rows are accepted (both solution paths), rank [M; A] = n.
    Planar bodies: the rows that vanish identically (a revolute's z and axis rows) are
    left out, so A has full row rank and the KKT path applies. Rigid
    bodies: three rows of the spatial loop are redundant, and the out-of-plane
    accelerations are zero."""
    system = load(name)
    reference = geometry(system.parameters)
    rng = np.random.default_rng(21)
    for _ in range(4):
        theta, theta_dot = rng.uniform(0, 2 * np.pi), 3 * rng.normal()
        q, qd, expected = reference.state(theta, theta_dot)
        if rigid:
            q, qd = rigid_from_planar(q, qd)
        phi, phi_dot = system.constraint_residuals(0.0, q, qd)
        assert np.abs(phi).max() < 1e-12 and np.abs(phi_dot).max() < 1e-12
        arrays = system.evaluate(0.0, q, qd)
        report = rank_report(arrays.M, arrays.A)
        assert (report.m, report.rank_A, report.rank_Mhat) == (*rows, system.n)
        scale = np.abs(expected).max()
        for method in ("kkt", "reference"):
            qdd = system.motion(0.0, q, qd, method=method).qdd
            if rigid:
                qdd, out_of_plane = planar_from_rigid(q, qdd)
                assert np.abs(out_of_plane).max() < 1e-9 * scale
            np.testing.assert_allclose(qdd, expected, rtol=1e-9, atol=1e-9 * scale)


def unit(v):
    return v / np.linalg.norm(v)


def test_massless_rod_between_particles_is_a_distance_constraint():
    """Particles joined by a massless rigid rod (spherical joints at its ends) move as the
    twin pair joined by a distance joint, and as the closed form of a rigid dumbbell:
    d = p1 − p2 obeys d̈ = −|ḋ|²/L² d (ḋ ⟂ d), and m1 p̈1 + m2 p̈2 = (m1 + m2) g."""
    system = load("massless_rod.yaml")
    m1, m2, L, g = (system.parameters[k] for k in ("m1", "m2", "L", "g"))
    rng = np.random.default_rng(22)
    for _ in range(4):
        p1, d = rng.normal(size=3), L * unit(rng.normal(size=3))
        v1, d_dot = rng.normal(size=3), np.cross(rng.normal(size=3), d)
        z = d / L
        x = unit(np.cross(z, rng.normal(size=3)))  # a random spin of the rod about its axis
        omega = np.cross(d, d_dot) / L**2 + rng.normal() * z
        rod_q, rod_qd = body_coordinates(p1 - d / 2, np.column_stack([x, np.cross(z, x), z]), v1 - d_dot / 2, omega)
        pair_q, pair_qd = np.concatenate([p1, p1 - d]), np.concatenate([v1, v1 - d_dot])
        q = np.concatenate([pair_q, rod_q, pair_q + 1.0])
        qd = np.concatenate([pair_qd, rod_qd, pair_qd])
        phi, phi_dot = system.constraint_residuals(0.0, q, qd)
        assert np.abs(phi).max() < 1e-12 and np.abs(phi_dot).max() < 1e-12
        qdd = system.motion(0.0, q, qd).qdd
        a1, a2, twin = qdd[:3], qdd[3:6], qdd[13:]
        np.testing.assert_allclose(np.concatenate([a1, a2]), twin, rtol=1e-10, atol=1e-10 * g)
        np.testing.assert_allclose(a1 - a2, -(d_dot @ d_dot) / L**2 * d, rtol=1e-10, atol=1e-10 * g)
        np.testing.assert_allclose(m1 * a1 + m2 * a2, [0, 0, -(m1 + m2) * g], rtol=1e-10, atol=1e-10 * g)


def spin_direction(system, body, q, direction):
    """Check ``direction`` ({coordinate: component}) lies on the body's quaternion only and
    is the quaternion rate of a spin about the body's z axis a: ∝ G(u)ᵀ a (ω = 2 G u̇)."""
    names = [f"{body}.q{c}" for c in "wxyz"]
    assert set(direction) <= set(names)
    start = system.coordinates.index(names[0])
    u = q[start:start + 4]
    w = np.array([direction.get(c, 0.0) for c in names])
    spin = G(u).T @ R(u)[:, 2]
    np.testing.assert_allclose(unit(w) * np.sign(w @ spin), unit(spin), atol=1e-9)


def test_massless_link_spin_is_the_one_free_indeterminate_direction(capsys):
    """A massless link hanging from a spherical joint, a particle on its lower end:
    `mbsynth check --json` exits 0 and reports rank [M; A] = n − 1, one indeterminate
    direction — the link's spin about its axis — and it is free (no balance needed)."""
    code = main(["check", str(MECHANISMS / "massless_link.yaml"), "--json"])
    report = json.loads(capsys.readouterr().out)
    assert code == 0 and report["consistent"]
    assert not report["unique"] and report["rank_Mhat"] == report["n"] - 1 == 9
    (direction,) = report["indeterminate"]
    assert report["balances"] == [{"direction": report["balances"][0]["direction"], "free": True, "equation": None}]
    assert report["suggested_constraints"] == []
    system = load("massless_link.yaml")
    q0, _ = system.initial_state()
    spin_direction(system, "link", q0, direction)
    spin_direction(system, "link", q0, report["balances"][0]["direction"])


def test_massless_rod_spin_is_free_at_a_moving_state():
    """diagnose at a moving state of massless_rod.yaml: one free direction, the rod's spin."""
    system = load("massless_rod.yaml")
    q, qd = system.initial_state()
    report = diagnose(system, q=q, qd=qd)
    assert report.consistent and not report.unique and report.rank_Mhat == system.n - 1
    (direction,) = report.indeterminate
    assert [b["free"] for b in report.balances] == [True] and report.suggested_constraints == []
    spin_direction(system, "rod", q, direction)


@pytest.mark.parametrize("name", sorted(p.name for p in MECHANISMS.glob("*.yaml")))
def test_every_mechanism_checks_clean_at_its_consistent_initial_state(name):
    """`mbsynth check` would exit 0: consistent, no balance missing; the initial state
    satisfies every joint."""
    system = load(name)
    report = diagnose(system)
    assert report.consistent and report.suggested_constraints == []
    q, qd = system.initial_state()
    phi, phi_dot = system.constraint_residuals(0.0, q, qd)
    A = system.evaluate(0.0, q, qd).A  # residuals relative to their rows' terms (a 1 km pendulum's are ~1e6)
    assert np.all(np.abs(phi) < 1e-12 * term_scales(A, q)) and np.all(np.abs(phi_dot) <= 1e-12 * term_scales(A, qd))
