"""The flexible part (model/parts/flexible_body.py) against the unreduced FE model written
here in the part's own coordinates (R, unit quaternion, η): every node's world place from
the frame's pose, velocities by complex step, the full FE mass and stiffness matrices, and
Lagrange's equations by central differences; its node frames against the deformed nodes."""

import numpy as np
import pytest
import sympy as sp

import mbsynth as mb
from tests.helpers.flexible_beams import strip
from mbsynth.model.flexible.reduction import craig_bampton
from mbsynth.model.parts.flexible_body import FlexibleBody, coordinates, modal_damping, rayleigh_damping

GRAVITY = np.array([0.3, -9.81, 1.2])
STEP = 1e-4  # central differences of Lagrange's equations


def unit_rotation(u):
    """The rotation of the quaternion u / |u| (complex-safe): scaling u turns nothing."""
    u = u / np.sqrt(u @ u)
    w, v = u[0], u[1:]
    skew = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return (w * w - v @ v) * np.eye(3) + 2 * np.outer(v, v) + 2 * w * skew


class Unreduced:
    """T = ½ wᵀ M w over every nodal DOF (translations: the frame components of the world
    velocities of R + A(x_j + u_j); rotations: ω + θ̇_j), V = ½ uᵀ K u − gᵀ(world first
    moment weighed by M turned to world axes), and Rayleigh damping of the full model."""

    def __init__(self, reduction, alpha=0.0, beta=0.0):
        self.fe, self.Phi = reduction.fe, reduction.basis
        n = self.fe.size
        self.translation = np.arange(n) % 6 < 3
        self.x0 = np.zeros(n)
        self.x0[self.translation] = self.fe.nodes.ravel()
        self.alpha, self.beta = alpha, beta

    def places(self, q):
        local = (self.x0 + self.Phi @ q[7:])[self.translation].reshape(-1, 3)
        return q[:3] + local @ unit_rotation(q[3:7]).T

    def w(self, q, qd):
        A = unit_rotation(q[3:7])
        A_dot = unit_rotation(q[3:7] + 1e-30j * qd[3:7]).imag / 1e-30
        S = A.T @ A_dot
        w = self.Phi @ qd[7:] + 0j
        w[self.translation] = ((self.places(q + 1e-30j * qd).imag / 1e-30) @ A).ravel()
        w[~self.translation] += np.tile([S[2, 1], S[0, 2], S[1, 0]], len(self.fe.nodes))
        return w

    def T(self, q, qd):
        w = self.w(q, qd)
        return 0.5 * w @ (self.fe.mass @ w)

    def V(self, q):
        A = unit_rotation(q[3:7])
        turn = np.kron(np.eye(2 * len(self.fe.nodes)), A)
        X = turn @ (self.Phi @ q[7:])
        X[self.translation] = self.places(q).ravel()
        G = np.zeros(self.fe.size)
        G[self.translation] = np.tile(GRAVITY, len(self.fe.nodes))
        u = self.Phi @ q[7:]
        return 0.5 * u @ (self.fe.stiffness @ u) - G @ (turn @ (self.fe.mass @ (turn.T @ X)))

    def residual(self, q, qd, qdd):
        """d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q + the damping force, along q + q̇t + ½q̈t²."""
        n = len(q)
        path = lambda t: (q + qd * t + qdd * t * t / 2, qd + qdd * t)  # noqa: E731
        momentum = lambda t: np.array([derivative(lambda v: self.T(path(t)[0], v), path(t)[1], i, 1.0)  # noqa: E731
                                       for i in range(n)])
        out = (momentum(STEP) - momentum(-STEP)) / (2 * STEP)
        out -= np.array([derivative(lambda x: self.T(x, qd), q, i, STEP) for i in range(n)])
        out += np.array([derivative(self.V, q, i, STEP) for i in range(n)])
        u_dot = self.Phi @ qd[7:]
        out[7:] += self.Phi.T @ (self.alpha * (self.fe.mass @ u_dot) + self.beta * (self.fe.stiffness @ u_dot))
        return out


def derivative(f, x, i, step):
    e = np.zeros_like(x)
    e[i] = step
    return (f(x + e) - f(x - e)) / (2 * step)


def flexible_body(reduction, name="beam", **kwargs):
    names = coordinates(reduction.size)
    q = [sp.Symbol(f"{name}.{c}") for c in names]
    qd = [sp.Symbol(f"{name}.{c}_dot") for c in names]
    return FlexibleBody(name, q, qd, reduction, sp.Matrix(GRAVITY), [], **kwargs)


def random_body_state(r, rng):
    """A unit quaternion with a tangent rate (uᵀu̇ = 0), small η."""
    u = rng.normal(size=4)
    u /= np.linalg.norm(u)
    u_dot = rng.normal(size=4)
    u_dot -= u * (u @ u_dot)
    q = np.concatenate([rng.normal(size=3), u, 1e-2 * rng.normal(size=r)])
    qd = np.concatenate([rng.normal(size=3), u_dot, rng.normal(size=r)])
    return q, qd, rng.normal(size=7 + r)


def radial_removed(q, x):
    """x without its component along the quaternion u in the quaternion rows (the unit-norm
    row's multiplier takes that part, whatever it is)."""
    x = x.copy()
    u = q[3:7]
    x[3:7] -= u * (u @ x[3:7])
    return x


@pytest.fixture(scope="module")
def beam():
    reduction = craig_bampton(strip(8, Iz=2e-9), [0, 8], count=3).hold(0)  # r = 9
    alpha, beta = 0.3, 2e-4
    return (reduction, flexible_body(reduction, damping=rayleigh_damping(reduction, alpha, beta)),
            Unreduced(reduction, alpha, beta))


def test_the_parts_M_and_Q_are_lagranges_of_the_unreduced_model(beam):
    """At random states: M_q = ∂²T/∂q̇² of the unreduced T (1e-10), and M_q q̈ − Q_q equals the
    unreduced Lagrange equations (with gravity, elastic and Rayleigh damping forces) to the
    central differences' 1e-6, but for the part along u that the unit-norm row takes."""
    reduction, part, full = beam
    rng = np.random.default_rng(46)
    n = 7 + reduction.size
    for _ in range(3):
        q, qd, qdd = random_body_state(reduction.size, rng)
        M, Q = part.evaluate(0.0, q, qd, np.zeros(0))
        expected = np.array([[full.T(q, a + b) - full.T(q, a) - full.T(q, b) for b in np.eye(n)] for a in np.eye(n)]).real
        np.testing.assert_allclose(M, expected, rtol=1e-10, atol=1e-10 * np.abs(expected).max())
        lagrange = radial_removed(q, full.residual(q, qd, qdd).real)
        ours = radial_removed(q, M @ qdd - Q)
        np.testing.assert_allclose(ours, lagrange, rtol=1e-6, atol=1e-6 * np.abs(lagrange).max())
        assert part.energy(0.0, q, qd, np.zeros(0))[0] == pytest.approx(full.T(q, qd).real, rel=1e-12)


def test_the_potential_is_the_unreduced_models(beam):
    """V(q) − V_unreduced(q) is one constant over random states (both measure gravity from
    the world origin): their difference at three states agrees to 1e-9 of V."""
    reduction, part, full = beam
    rng = np.random.default_rng(3)
    gaps = []
    for _ in range(3):
        q, qd, _ = random_body_state(reduction.size, rng)
        V = part.energy(0.0, q, qd, np.zeros(0))[1]
        gaps.append(V - full.V(q).real)
    np.testing.assert_allclose(gaps, gaps[0], atol=1e-9 * abs(V))


def test_node_frames_follow_the_deformed_nodes(beam):
    """Node 8's frame (the free interface node): at the deformed node's world place, its
    rotation orthogonal and A(I + [θ]×) to first order in θ (θ the node's rotation DOFs)."""
    reduction, part, full = beam
    rng = np.random.default_rng(8)
    q, _, _ = random_body_state(reduction.size, rng)
    position, rotation = part.pose(part.frames["node_8"])
    values = dict(zip(part.q, q))
    p = np.array(position.xreplace(values), dtype=float).ravel()
    R = np.array(rotation.xreplace(values), dtype=float)
    np.testing.assert_allclose(p, full.places(q)[8], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-14)
    theta = reduction.basis[reduction.node_rows(8)[3:]] @ q[7:]
    skew = np.array([[0, -theta[2], theta[1]], [theta[2], 0, -theta[0]], [-theta[1], theta[0], 0]])
    A = unit_rotation(q[3:7])
    assert np.abs(A.T @ R - np.eye(3) - skew).max() < np.linalg.norm(theta) ** 2
    assert np.linalg.norm(theta) > 1e-3  # the node did turn
    assert sorted(part.frames) == ["node_0", "node_8"]


def test_a_node_frames_angular_velocity_is_its_rotations_rate(beam):
    """frame_angular_velocity(node_8) = vee(Ṙ Rᵀ) of the frame's world rotation R(q(t)) along
    q + q̇t (central differences, 1e-8), and differs from the floating frame's own by the node's
    elastic turn rate."""
    reduction, part, _ = beam
    rng = np.random.default_rng(12)
    q, qd, _ = random_body_state(reduction.size, rng)
    frame = part.frames["node_8"]
    R = sp.lambdify([part.q], part.pose(frame)[1])
    values = {**dict(zip(part.q, q)), **dict(zip(part.qd, qd))}
    omega = np.array(part.frame_angular_velocity(frame).xreplace(values), dtype=float).ravel()
    step = 1e-6
    W = (np.array(R(q + step * qd)) - np.array(R(q - step * qd))) / (2 * step) @ np.array(R(q)).T
    np.testing.assert_allclose(omega, [W[2, 1], W[0, 2], W[1, 0]], rtol=1e-8, atol=1e-8 * np.abs(omega).max())
    own = np.array(part.angular_velocity().xreplace(values), dtype=float).ravel()
    assert np.linalg.norm(omega - own) > 1e-2 * np.linalg.norm(omega)


def test_modal_damping_damps_each_reduced_mode_at_its_ratio():
    """D = modal_damping(r, ζ) with M_r, K_r: the reduced model's eigenvalues are
    −ζω ± iω√(1 − ζ²) of its undamped ω."""
    reduction = craig_bampton(strip(6), [0, 6], count=2).hold(0)
    M, K = reduction.mass, reduction.stiffness
    D = modal_damping(reduction, 0.05)
    n = len(M)
    state = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, D)]])
    s = np.linalg.eigvals(state)
    s = s[s.imag > 0]
    ratio = -s.real / np.abs(s)
    np.testing.assert_allclose(ratio, 0.05, rtol=1e-9)


def test_a_reduction_without_elastic_coordinates_is_refused():
    """Guyan's reduction held at its only interface node leaves no η: a ModelError naming the
    part (the loader names the key and why first), not a sympy shape error."""
    with pytest.raises(mb.ModelError, match="flexible body 'beam': its reduction has no elastic coordinate"):
        flexible_body(craig_bampton(strip(4), [0], count=0).hold(0))
