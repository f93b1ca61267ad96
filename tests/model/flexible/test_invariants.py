"""The FFRF invariants against the unreduced model: the kinetic energy of every nodal DOF
written out from the frame's pose (world positions of the deformed nodes, differentiated
by complex step) and the full FE mass matrix. Its Lagrange equations (by central
differences) match the invariants' M(η)ν̇ − h at random states, its gravity potential their
gravity force; the rigid block is the rod's closed form, and a point-mass cloud's inertia
tensor; a free flexible body conserves energy, linear and angular momentum."""

import numpy as np
import pytest
import scipy.integrate

from tests.helpers.flexible_beams import LENGTH, STRIP, strip, truss
from mbsynth.model.flexible.invariants import invariants
from mbsynth.model.flexible.reduction import craig_bampton, free_interface


def euler_rotation(angles):
    """A = Rz(a) Ry(b) Rx(c), complex-safe."""
    a, b, c = angles
    Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    Ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    Rx = np.array([[1, 0, 0], [0, np.cos(c), -np.sin(c)], [0, np.sin(c), np.cos(c)]])
    return Rz @ Ry @ Rx


class Unreduced:
    """A reduced beam in q = (R, Euler angles, η), its kinetic energy written out over all
    nodal DOFs: translations' velocities Aᵀ d/dt (R + A(x_j + u_j)) and sections' angular
    velocities ω + θ̇_j, weighed by the full FE mass matrix."""

    def __init__(self, reduction):
        self.fe, self.Phi = reduction.fe, reduction.basis
        self.r = self.Phi.shape[1]
        self.x0 = np.zeros(self.fe.size)
        self.x0[np.arange(self.fe.size) % 6 < 3] = self.fe.nodes.ravel()
        self.translation = np.arange(self.fe.size) % 6 < 3

    def world_places(self, q):
        """R + A(x_j + u_j) for every node, (N, 3); analytic in q."""
        A = euler_rotation(q[3:6])
        local = (self.x0 + self.Phi @ q[6:])[self.translation].reshape(-1, 3)
        return q[:3] + local @ A.T

    def nu(self, q, qd):
        """(V, ω, η̇) in the frame's components, by complex step (exact to rounding)."""
        A = euler_rotation(q[3:6])
        A_dot = euler_rotation(q[3:6] + 1e-30j * qd[3:6]).imag / 1e-30
        W = A.T @ A_dot
        return np.concatenate([A.T @ qd[:3], [W[2, 1], W[0, 2], W[1, 0]], qd[6:]])

    def w(self, q, qd):
        """Every nodal DOF's velocity in the frame's components."""
        A = euler_rotation(q[3:6])
        places = self.world_places(q + 1e-30j * qd).imag / 1e-30  # d/dt of the world places
        w = self.Phi @ qd[6:]
        w[self.translation] = (places @ A).ravel()
        w[~self.translation] += np.tile(self.nu(q, qd)[3:6], len(self.fe.nodes))
        return w

    def T(self, q, qd):
        w = self.w(q, qd)
        return 0.5 * w @ (self.fe.mass @ w)

    def gravity_potential(self, q, g):
        """−(Γ_t g)ᵀ M_w X: X the world DOFs (places R + A(x_j + u_j), rotations A θ_j), M_w
        the FE mass matrix turned to world axes (a consistent M loads rotations too)."""
        A = euler_rotation(q[3:6])
        turn = np.kron(np.eye(2 * len(self.fe.nodes)), A)
        X = turn @ (self.Phi @ q[6:])
        X[self.translation] = self.world_places(q).ravel()
        G = np.zeros(self.fe.size)
        G[self.translation] = np.tile(g, len(self.fe.nodes))
        return -G @ (turn @ (self.fe.mass @ (turn.T @ X)))


def derivative(f, x, i, step):
    e = np.zeros_like(x)
    e[i] = step
    return (f(x + e) - f(x - e)) / (2 * step)


@pytest.fixture(scope="module")
def model():
    fe = strip(8, Iz=2e-9)  # no two equal bending planes
    reduction = craig_bampton(fe, [0, 8], count=3)  # r = 15: constraint modes hold rigid motion too
    return Unreduced(reduction), invariants(reduction)


def random_euler_state(r, rng):
    """(q, q̇, q̈) of the unreduced model: a position, Euler angles in (−1, 1), small η (r modes)."""
    q = np.concatenate([rng.normal(size=3), rng.uniform(-1, 1, 3), 1e-2 * rng.normal(size=r)])
    return q, rng.normal(size=6 + r), rng.normal(size=6 + r)


def test_the_mass_matrix_is_the_unreduced_kinetic_energys(model):
    """T = ½ νᵀ M(η) ν for every ν: M(η) against the unreduced T's Hessian in ν, read off
    by polarization (T(ν_i + ν_j) − T(ν_i) − T(ν_j))."""
    full, inv = model
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, qd, _ = random_euler_state(inv.modes, rng)
        nu = full.nu(q, qd)
        np.testing.assert_allclose(inv.kinetic_energy(q[6:], nu), full.T(q, qd), rtol=1e-12)
        B = np.column_stack([full.nu(q, e) for e in np.eye(len(q))])  # ν = B q̇
        Mq = np.array([[full.T(q, a + b) - full.T(q, a) - full.T(q, b) for b in np.eye(len(q))] for a in np.eye(len(q))])
        np.testing.assert_allclose(B.T @ inv.mass(q[6:]) @ B, Mq, rtol=1e-10, atol=1e-10 * np.abs(Mq).max())


def test_the_rigid_block_is_the_rods(model):
    """η = 0: mass ρAL, first moment about the frame's origin (the root) ρAL²/2 along x,
    inertia ρAL³/3 about y and z (Euler–Bernoulli: no rotary inertia of sections) and ρ(Iy +
    Iz)L about the axis: the consistent mass holds a rigid motion exactly."""
    _, inv = model
    rho, A = STRIP["density"], STRIP["area"]
    m, L = rho * A * LENGTH, LENGTH
    expected = np.zeros((6, 6))
    expected[:3, :3] = m * np.eye(3)
    first = np.array([m * L / 2, 0, 0])
    skew = np.array([[0, -first[2], first[1]], [first[2], 0, -first[0]], [-first[1], first[0], 0]])
    expected[:3, 3:], expected[3:, :3] = -skew, skew
    expected[3:, 3:] = np.diag([rho * (STRIP["Iy"] + 2e-9) * L, m * L**2 / 3, m * L**2 / 3])
    np.testing.assert_allclose(inv.mass(np.zeros(inv.modes))[:6, :6], expected, rtol=1e-12, atol=1e-12 * m * L**2)


def test_the_motion_is_lagranges_of_the_unreduced_model(model):
    """Along q(t) = q + q̇t + ½q̈t² (central differences, step 1e-4): d/dt ∂T/∂q̇ − ∂T/∂q of
    the unreduced T equals Bᵀ(M(η)ν̇ − h(η, ν)), ν = Bq̇ (virtual power), and −∂V/∂q of
    the unreduced gravity potential equals Bᵀ gravity(η, Aᵀg)."""
    full, inv = model
    rng = np.random.default_rng(5)
    g = np.array([0.3, -9.81, 1.2])
    step = 1e-4
    for _ in range(3):
        q, qd, qdd = random_euler_state(inv.modes, rng)
        path = lambda t: (q + qd * t + qdd * t * t / 2, qd + qdd * t)  # noqa: E731
        n = len(q)
        momentum = lambda t: np.array([derivative(lambda v: full.T(path(t)[0], v), path(t)[1], i, 1.0)  # noqa: E731
                                       for i in range(n)])
        lagrange = (momentum(step) - momentum(-step)) / (2 * step)
        lagrange -= np.array([derivative(lambda x: full.T(x, qd), q, i, step) for i in range(n)])
        nu_dot = (full.nu(*path(step)) - full.nu(*path(-step))) / (2 * step)
        B = np.column_stack([full.nu(q, e) for e in np.eye(n)])
        ours = B.T @ (inv.mass(q[6:]) @ nu_dot - inv.quadratic_velocity(q[6:], full.nu(q, qd)))
        np.testing.assert_allclose(ours, lagrange, rtol=1e-6, atol=1e-6 * np.abs(lagrange).max())
        weight = -np.array([derivative(lambda x: full.gravity_potential(x, g), q, i, step) for i in range(n)])
        A = euler_rotation(q[3:6])
        np.testing.assert_allclose(B.T @ inv.gravity(q[6:], A.T @ g), weight, rtol=1e-7, atol=1e-7 * np.abs(weight).max())


def test_a_free_flexible_body_conserves_energy_and_momentum():
    """The strip with its four lowest free-interface flexible modes, thrown spinning: under
    its elastic forces alone T + ½ηᵀK_rη, A p_V and R × A p_V + A p_ω stay constant."""
    fe = strip(10, Iz=2e-9)
    reduction = free_interface(fe, count=4, rigid=False)
    inv, K = invariants(reduction), reduction.stiffness

    def rates(t, y):
        A, eta, nu = y[3:12].reshape(3, 3), y[12:16], y[16:]
        V, omega = nu[:3], nu[3:6]
        force = inv.quadratic_velocity(eta, nu)
        force[6:] -= K @ eta
        skew = np.array([[0, -omega[2], omega[1]], [omega[2], 0, -omega[0]], [-omega[1], omega[0], 0]])
        return np.concatenate([A @ V, (A @ skew).ravel(), nu[6:], np.linalg.solve(inv.mass(eta), force)])

    def invariants_of(y):
        R, A, eta, nu = y[:3], y[3:12].reshape(3, 3), y[12:16], y[16:]
        p = inv.mass(eta) @ nu
        return np.concatenate([[inv.kinetic_energy(eta, nu) + 0.5 * eta @ K @ eta], A @ p[:3],
                               np.cross(R, A @ p[:3]) + A @ p[3:6]])

    omega0 = np.array([0.5, 2.0, 3.0])
    y0 = np.concatenate([[0.1, 0.2, 0.3], np.eye(3).ravel(), 1e-3 * np.array([1.0, -1.0, 0.5, 0.2]),
                         [0.4, -0.2, 0.1], omega0, [0.3, -0.1, 0.2, 0.05]])
    run = scipy.integrate.solve_ivp(rates, (0, 0.5), y0, method="DOP853", rtol=1e-11, atol=1e-13)
    assert run.success
    start, end = invariants_of(y0), invariants_of(run.y[:, -1])
    assert abs(np.abs(run.y[12:16, -1]).max()) > 1e-4  # it did vibrate
    np.testing.assert_allclose(end[0], start[0], rtol=1e-8)
    np.testing.assert_allclose(end[1:], start[1:], rtol=1e-8, atol=1e-8 * np.abs(start[1:]).max())


def test_holding_an_interface_node_leaves_the_frame_the_only_rigid_motion(model):
    """Craig–Bampton's constraint modes can move the beam rigidly, as the frame does: M(0)
    has six null directions (rounding: 1e-12 of its largest eigenvalue); with the root held
    at the frame (``hold``) M(η) is positive definite."""
    _, loose = model
    reduction = craig_bampton(strip(8, Iz=2e-9), [0, 8], count=3).hold(0)
    held = invariants(reduction)
    assert held.modes == loose.modes - 6 == reduction.size
    eta = 1e-2 * np.random.default_rng(7).normal(size=loose.modes)
    spectrum = np.linalg.eigvalsh(loose.mass(0 * eta))
    assert np.all(np.abs(spectrum[:6]) < 1e-12 * spectrum[-1]) and spectrum[6] > 1e-9 * spectrum[-1]
    spectrum = np.linalg.eigvalsh(held.mass(eta[6:]))
    assert spectrum[0] > 1e-9 * spectrum[-1]


def test_point_masses_on_springs_have_the_rigid_inertia_of_their_cloud():
    """A solid-like model (3 DOFs per node), the point-mass truss: M(0)'s rigid block is m,
    the first moment Σ mᵢxᵢ and the inertia tensor Σ mᵢ(|xᵢ|²I − xᵢxᵢᵀ) about the frame's
    origin; gravity's torque is Σ xᵢ × mᵢa."""
    fe = truss()
    x, m = fe.nodes, fe.mass.diagonal()[::3]
    reduction = free_interface(fe, count=4, rigid=False)
    assert reduction.frequencies[0] > 1e-3 * reduction.frequencies[-1]  # no mechanism left
    inv = invariants(reduction)
    first = m @ x
    inertia = sum(mi * (xi @ xi * np.eye(3) - np.outer(xi, xi)) for mi, xi in zip(m, x))
    skew = np.array([[0, -first[2], first[1]], [first[2], 0, -first[0]], [-first[1], first[0], 0]])
    expected = np.block([[m.sum() * np.eye(3), -skew], [skew, inertia]])
    np.testing.assert_allclose(inv.mass(np.zeros(4))[:6, :6], expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    a = np.array([0.0, -9.81, 0.0])
    np.testing.assert_allclose(inv.gravity(np.zeros(4), a)[3:6], np.cross(m[:, None] * x, a).sum(0), rtol=1e-12)
