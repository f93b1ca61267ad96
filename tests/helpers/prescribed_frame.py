"""The unreduced FE model of a beam clamped to a frame whose rotation is prescribed, written
directly from Lagrange's equations (no reduction, no inertia invariants): an independent
reference for the floating-frame quadratic-velocity terms.

Every nodal DOF's velocity in the frame's axes is w = c(t) + S(t) u + u̇, with c the rigid
velocity of the undeformed DOFs (ω × x_j on node j's translations, ω on its rotations), S the
block diagonal of [ω]× on the translations (zero on the rotations: a section turns at
ω + θ̇_j), the frame's origin fixed. With T = ½ wᵀ M w and V = ½ uᵀ K u, Lagrange's equations
on the free DOFs (node 0 clamped) are

    M (ü + ċ + Ṡ u + S u̇) − Sᵀ M (c + S u + u̇) + K u = 0,

linear in u with coefficients that follow the prescribed ω(t), ω̇(t) (the same kinetic
energy as tests/model/flexible/test_invariants.py's unreduced model)."""

import numpy as np
import scipy.integrate


def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def ramp(t, tau):
    """s(t) = t − τ tanh(t/τ), ṡ = tanh²(t/τ), s̈: the angles' time law (rest at t = 0)."""
    th = np.tanh(t / tau)
    return t - tau * th, th ** 2, 2 * th * (1 - th ** 2) / tau


def tumbling_rotation(spin, precession, tau):
    """A(t) = R_x(φ) R_z(ψ), φ = precession·s(t), ψ = spin·s(t)."""

    def rotation(t):
        phi, psi = precession * ramp(t, tau)[0], spin * ramp(t, tau)[0]
        Rx = np.array([[1, 0, 0], [0, np.cos(phi), -np.sin(phi)], [0, np.sin(phi), np.cos(phi)]])
        Rz = np.array([[np.cos(psi), -np.sin(psi), 0], [np.sin(psi), np.cos(psi), 0], [0, 0, 1]])
        return Rx @ Rz

    return rotation


def tumbling_rates(spin, precession, tau):
    """t → (ω, ω̇) in the frame's axes of ``tumbling_rotation`` (the intrinsic xyz angles with
    the middle one 0): ω = (φ̇ cos ψ, −φ̇ sin ψ, ψ̇)."""

    def omega(t):
        s, sd, sdd = ramp(t, tau)
        psi, psi_d, psi_dd = spin * s, spin * sd, spin * sdd
        phi_d, phi_dd = precession * sd, precession * sdd
        c, n = np.cos(psi), np.sin(psi)
        w = np.array([phi_d * c, -phi_d * n, psi_d])
        w_dot = np.array([phi_dd * c - phi_d * n * psi_d, -phi_dd * n - phi_d * c * psi_d, psi_dd])
        return w, w_dot

    return omega


def tip_history(fe, omega, times, rtol=1e-10, atol=1e-13):
    """The last node's translations u (frame axes) at ``times`` of the FE model ``fe`` (6 DOFs
    per node, node 0 clamped at the frame's origin) whose frame turns at ``omega(t)`` →
    (ω, ω̇) from rest; (len(times), 3). S and c are linear in ω (S = Σ ω_a S_a, c = Σ ω_a c_a),
    so the equation's matrices are sums of constant ones weighed by ω_a, ω̇_a and ω_a ω_b;
    DOP853 (the axial modes near 2e4 rad/s bound its step, not its accuracy)."""
    M, K = fe.mass.toarray(), fe.stiffness.toarray()
    n = M.shape[0]
    translation = np.arange(n) % 6 < 3
    x = np.zeros(n)
    x[translation] = fe.nodes.ravel()
    free = np.arange(6, n)
    solve = np.linalg.inv(M[np.ix_(free, free)])
    S, c = [], []
    for axis in np.eye(3):
        S_a = np.zeros((n, n))
        for j in range(len(fe.nodes)):
            S_a[6 * j:6 * j + 3, 6 * j:6 * j + 3] = skew(axis)
        c_a = S_a @ x
        c_a[~translation] = np.tile(axis, len(fe.nodes))
        S.append(S_a)
        c.append(c_a)

    def reduce(matrix):
        return solve @ matrix[np.ix_(free, free)] if matrix.ndim == 2 else solve @ matrix[free]

    stiffness = reduce(-K)
    rate = np.array([reduce(-(M @ S_a - S_a.T @ M)) for S_a in S])            # u̇: Σ ω_a rate_a
    spin_up = np.array([reduce(-M @ S_a) for S_a in S])                        # u: Σ ω̇_a spin_up_a
    centrifugal = np.array([[reduce(S_a.T @ M @ S_b) for S_b in S] for S_a in S])  # u: Σ ω_a ω_b …
    loads = (np.array([reduce(-M @ c_a) for c_a in c]),                     # Σ ω̇_a loads_a
             np.array([[reduce(S_a.T @ M @ c_b) for c_b in c] for S_a in S]))  # Σ ω_a ω_b loads_ab
    m = len(free)

    def rates(t, y):
        w, w_dot = omega(t)
        ww = np.outer(w, w)
        on_u = stiffness + np.tensordot(w_dot, spin_up, 1) + np.tensordot(ww, centrifugal, 2)
        load = w_dot @ loads[0] + np.tensordot(ww, loads[1], 2)
        return np.concatenate([y[m:], on_u @ y[:m] + np.tensordot(w, rate, 1) @ y[m:] + load])

    run = scipy.integrate.solve_ivp(rates, (0.0, times[-1]), np.zeros(2 * m), method="DOP853", t_eval=times,
                                    rtol=rtol, atol=atol)
    assert run.success, run.message
    return run.y[m - 6:m - 3].T
