"""M and Q (2.1) of a flexible part in the floating frame of reference, from its invariants
as arrays: one compiled function for every flexible part (model/parts/flexible_body.py,
whose module docstring gives the formulas; model/flexible/invariants.py the invariants).

``equations(q, qd, g, axes, W, s0, K, D, S, M, Q, Mnu, nu)``: the part's own coordinates q =
(R, u, η) and velocities q̇ (7 + r each; u a unit quaternion where ``axes`` is empty, else
three angles of the intrinsic sequence ``axes`` (3 axis indices), 6 + r each), the gravity
vector g (world), the Gram matrix W
((6 + 4r) square, entries below GRAM_ZERO_RTOL of the largest zeroed), the undeformed first
moment s0, K_r, D (r × r) and the stiffening S (3 × 3 × r × r) give M_q (square) and
Q_q in M and Q, and M(η) ((6 + r) square) and ν = (V, ω, η̇) in Mnu and nu (the
energies: T = ½ νᵀ M(η) ν). Cost O(r²): W P(η) is formed on the three ω columns only and
∂M/∂η_k = Z_k + Z_kᵀ − ∂Σ(η)/∂η_k needs only the rows X_k of W P(η) (Z_k: those rows put
at the ω rows). q, q̇, g and the outputs may be complex (the complex step of a
linearization: every operation is analytic); the invariants are real.

``fill(q, qd, out, ...)`` writes the M_q and Q_q of one flexible part of a model into the
outputs of its generated function (codegen.py: layout.py leaves their places to it; ``Filled``
calls it after that function), ``fill_rows`` the same per row of a batch, without the GIL.
Compiled ahead with the kernels (ahead.PARTS).
"""

import numpy as np
from numba import njit

from .bodies import OPTIONS


@njit(**OPTIONS)
def _rotation(u, A):
    """A(u) = (w² − vᵀv) I + 2 v vᵀ + 2 w [v]× (core/kinematics.py ``rotation``)."""
    w, x, y, z = u[0], u[1], u[2], u[3]
    d = w * w - (x * x + y * y + z * z)
    v = (x, y, z)
    for i in range(3):
        for j in range(3):
            A[i, j] = 2.0 * v[i] * v[j] + (d if i == j else 0.0)
    A[0, 1] -= 2.0 * w * z
    A[0, 2] += 2.0 * w * y
    A[1, 0] += 2.0 * w * z
    A[1, 2] -= 2.0 * w * x
    A[2, 0] -= 2.0 * w * y
    A[2, 1] += 2.0 * w * x


@njit(**OPTIONS)
def _rate_matrix(u, E):
    """E(u) = [−v, w I − [v]×] (core/kinematics.py ``body_rate_matrix``): ω = 2 E(u) u̇."""
    w, x, y, z = u[0], u[1], u[2], u[3]
    E[0, 0], E[0, 1], E[0, 2], E[0, 3] = -x, w, z, -y
    E[1, 0], E[1, 1], E[1, 2], E[1, 3] = -y, -z, w, x
    E[2, 0], E[2, 1], E[2, 2], E[2, 3] = -z, y, -x, w


@njit(**OPTIONS)
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(**OPTIONS)
def _axis_turn(axis, angle, R):
    """R_axis(angle), the turn about the body axis ``axis`` (0, 1, 2: x, y, z), into R."""
    c, s = np.cos(angle), np.sin(angle)
    j, k = (axis + 1) % 3, (axis + 2) % 3
    for a in range(3):
        for b in range(3):
            R[a, b] = 0.0 * c
    R[axis, axis] = 1.0 + 0.0 * c
    R[j, j], R[k, k], R[j, k], R[k, j] = c, c, -s, s


@njit(**OPTIONS)
def _transposed_times(R, v, out):
    """out = Rᵀ v."""
    for a in range(3):
        out[a] = R[0, a] * v[0] + R[1, a] * v[1] + R[2, a] * v[2]


@njit(**OPTIONS)
def _angles_frame(alpha, rates, axes, A, B, c):
    """The frame turned by the intrinsic sequence ``axes`` (core/kinematics.py
    ``euler_rotation``): A = R₁(α₁) R₂(α₂) R₃(α₃); B = H(α) (``euler_rate_matrix``: ω = H α̇
    in the body's axes, columns h₁ = R₃ᵀR₂ᵀe₁, h₂ = R₃ᵀe₂, h₃ = e₃); c = Ḣ α̇ = α̇₁ ḣ₁ + α̇₂ ḣ₂
    with ḣ₁ = −α̇₃ e₃ × h₁ − α̇₂ R₃ᵀ(e₂ × R₂ᵀe₁), ḣ₂ = −α̇₃ e₃ × h₂ (d(Rᵢᵀ)/dt = −α̇ᵢ[eᵢ]× Rᵢᵀ)."""
    dt = A.dtype
    R1, R2, R3 = np.zeros((3, 3), dt), np.zeros((3, 3), dt), np.zeros((3, 3), dt)
    _axis_turn(axes[0], alpha[0], R1)
    _axis_turn(axes[1], alpha[1], R2)
    _axis_turn(axes[2], alpha[2], R3)
    for a in range(3):
        for b in range(3):
            A[a, b] = 0.0 * alpha[0]
            for m in range(3):
                for l in range(3):
                    A[a, b] += R1[a, m] * R2[m, l] * R3[l, b]
    e1, e2, e3 = np.zeros(3, dt), np.zeros(3, dt), np.zeros(3, dt)
    e1[axes[0]], e2[axes[1]], e3[axes[2]] = 1.0, 1.0, 1.0
    vectors = np.zeros((7, 3), dt)
    t, h1, h2, w, dh1, dh2, x = vectors[0], vectors[1], vectors[2], vectors[3], vectors[4], vectors[5], vectors[6]
    _transposed_times(R2, e1, t)
    _transposed_times(R3, t, h1)
    _transposed_times(R3, e2, h2)
    for a in range(3):
        B[a, 0], B[a, 1], B[a, 2] = h1[a], h2[a], e3[a]
    _cross(e2, t, w)
    _transposed_times(R3, w, x)
    _cross(e3, h1, dh1)
    _cross(e3, h2, dh2)
    for a in range(3):
        c[a] = rates[0] * (-rates[2] * dh1[a] - rates[1] * x[a]) - rates[1] * rates[2] * dh2[a]


@njit(**OPTIONS)
def equations(q, qd, g, axes, W, s0, K, D, S, M, Q, Mnu, nu):
    """M_q, Q_q into M, Q; M(η), ν into Mnu, nu (module docstring)."""
    r = K.shape[0]
    n, X, Eo = 6 + r, 6, 6 + 3 * r  # ν's size; W's first row of Ξ_1 and of Φ
    dt = q.dtype
    turns = 4 if axes.shape[0] == 0 else 3  # the orientation's coordinates: a quaternion, or three angles
    o = 3 + turns  # the first η
    eta, eta_dot = q[o:], qd[o:]
    A, B, turn = np.zeros((3, 3), dt), np.zeros((3, turns), dt), np.zeros(3, dt)  # turn: Ḃq̇'s ω part
    if turns == 4:  # ω = 2E(u) u̇, and Ḃ q̇ = 2E(u̇) u̇ = 0
        _rotation(q[3:7], A)
        _rate_matrix(q[3:7], B)
        for a in range(3):
            for b in range(4):
                B[a, b] *= 2.0
    else:
        _angles_frame(q[3:6], qd[3:6], axes, A, B, turn)
    for a in range(3):  # ν = (AᵀṘ, B u̇, η̇)
        nu[a] = A[0, a] * qd[0] + A[1, a] * qd[1] + A[2, a] * qd[2]
        s = 0.0 * qd[0]
        for b in range(turns):
            s += B[a, b] * qd[3 + b]
        nu[3 + a] = s
    for k in range(r):
        nu[6 + k] = eta_dot[k]
    # Y = W P(η) on the ω columns: W[:, 3 + a] + Σ_k η_k W[:, X_k + a], every row of W
    rows = 6 + 4 * r
    Y = np.zeros((rows, 3), dt)
    for i in range(rows):
        for a in range(3):
            Y[i, a] = W[i, 3 + a]
        for k in range(r):
            e = eta[k]
            for a in range(3):
                Y[i, a] += e * W[i, X + 3 * k + a]
    # M(η) = P(η)ᵀ W P(η): its V and η̇ rows and columns are W's; the ω column is Y's rows
    # 0:3 and Φ, the ω–ω block Pᵀ Y less the stiffening Σ(η)_ab = ηᵀ S_ab η
    for i in range(3):
        for j in range(3):
            Mnu[i, j] = W[i, j]
        for k in range(r):
            Mnu[i, 6 + k] = W[i, Eo + k]
            Mnu[6 + k, i] = W[Eo + k, i]
    for k in range(r):
        for l in range(r):
            Mnu[6 + k, 6 + l] = W[Eo + k, Eo + l]
    for a in range(3):
        for i in range(3):
            Mnu[i, 3 + a] = Y[i, a]
            Mnu[3 + a, i] = Y[i, a]
        for k in range(r):
            Mnu[6 + k, 3 + a] = Y[Eo + k, a]
            Mnu[3 + a, 6 + k] = Y[Eo + k, a]
    sigma = np.zeros((3, 3, r), dt)  # ∂Σ_ab/∂η_k = Σ_l (S_ab[k, l] + S_ab[l, k]) η_l
    for a in range(3):
        for b in range(3):
            ww = Y[3 + a, b]
            for k in range(r):
                ww += eta[k] * Y[X + 3 * k + a, b]
                s = 0.0 * eta[k]
                for l in range(r):
                    s += (S[a, b, k, l] + S[a, b, l, k]) * eta[l]
                sigma[a, b, k] = s
            stiff = 0.0 * ww
            for k in range(r):
                stiff += 0.5 * sigma[a, b, k] * eta[k]
            Mnu[3 + a, 3 + b] = ww - stiff
    p = np.zeros(n, dt)
    for i in range(n):
        s = 0.0 * nu[0]
        for j in range(n):
            s += Mnu[i, j] * nu[j]
        p[i] = s
    # Y_k = rows X_k of W P(η): columns V and η̇ from W, ω from Y; ykn = Y_k ν
    V, omega = nu[0:3], nu[3:6]
    f = np.zeros(n, dt)  # h, then f = h + F + M(η)[:, V] (ω × V)
    ykn = np.zeros(3, dt)
    for k in range(r):
        c = X + 3 * k
        ed = eta_dot[k]
        for a in range(3):
            s = Y[c + a, 0] * omega[0] + Y[c + a, 1] * omega[1] + Y[c + a, 2] * omega[2]
            for j in range(3):
                s += W[c + a, j] * V[j]
            for m in range(r):
                s += W[c + a, Eo + m] * eta_dot[m]
            ykn[a] = s
        # −Ṁν's Z_k ν and Z_kᵀ ν terms; ∂T/∂η_k = ωᵀ Y_k ν − ½ ωᵀ (∂Σ/∂η_k) ω
        for a in range(3):
            f[3 + a] -= ed * ykn[a]
            wa = omega[a]
            for j in range(3):
                f[j] -= ed * wa * W[c + a, j]
                f[3 + j] -= ed * wa * Y[c + a, j]
            for m in range(r):
                f[6 + m] -= ed * wa * W[c + a, Eo + m]
        dT = omega[0] * ykn[0] + omega[1] * ykn[1] + omega[2] * ykn[2]
        for a in range(3):
            for b in range(3):
                f[3 + a] += ed * sigma[a, b, k] * omega[b]
                dT -= 0.5 * omega[a] * omega[b] * sigma[a, b, k]
        f[6 + k] += dT
    c1, c2 = np.zeros(3, dt), np.zeros(3, dt)
    _cross(omega, p[0:3], c1)
    _cross(omega, p[3:6], c2)
    for a in range(3):
        f[a] -= c1[a]
        f[3 + a] -= c2[a]
    _cross(V, p[0:3], c1)
    for a in range(3):
        f[3 + a] -= c1[a]
    # forces: gravity (a = Aᵀg; the first moment s(η) = s0 + W[V, Φ] η), −K_r η − D η̇
    mass = W[0, 0]
    ga, first = np.zeros(3, dt), np.zeros(3, dt)
    for a in range(3):
        ga[a] = A[0, a] * g[0] + A[1, a] * g[1] + A[2, a] * g[2]
        s = s0[a] + 0.0 * eta[0]
        for k in range(r):
            s += W[a, Eo + k] * eta[k]
        first[a] = s
    _cross(first, ga, c1)
    for a in range(3):
        f[a] += mass * ga[a]
        f[3 + a] += c1[a]
    for k in range(r):
        s = W[Eo + k, 0] * ga[0] + W[Eo + k, 1] * ga[1] + W[Eo + k, 2] * ga[2]
        for l in range(r):
            s -= K[k, l] * eta[l] + D[k, l] * eta_dot[l]
        f[6 + k] += s
    _cross(omega, V, c1)
    for i in range(n):  # Ḃq̇ = (−ω × V, turn, 0) moved to the right
        f[i] += Mnu[i, 0] * c1[0] + Mnu[i, 1] * c1[1] + Mnu[i, 2] * c1[2]
        f[i] -= Mnu[i, 3] * turn[0] + Mnu[i, 4] * turn[1] + Mnu[i, 5] * turn[2]
    _mapped(A, B, Mnu, f, mass, M, Q)


@njit(**OPTIONS)
def _mapped(A, B, Mnu, f, mass, M, Q):
    """M_q = B̄ᵀ M(η) B̄, Q_q = B̄ᵀ f with B̄ = blockdiag(Aᵀ, B, I) (B: 2E(u) of a quaternion,
    H(α) of angles); the R–R block m I (A m Aᵀ: A is orthogonal, a quaternion's kept so by
    its unit-norm row)."""
    n = f.shape[0]
    r = n - 6
    turns = B.shape[1]
    o = 3 + turns  # the first η among the part's coordinates
    dt = f.dtype
    AM = np.zeros((3, n), dt)  # A M(η)[V, :]
    BM = np.zeros((turns, n), dt)  # Bᵀ M(η)[ω, :]
    for i in range(3):
        for j in range(n):
            AM[i, j] = A[i, 0] * Mnu[0, j] + A[i, 1] * Mnu[1, j] + A[i, 2] * Mnu[2, j]
    for i in range(turns):
        for j in range(n):
            BM[i, j] = B[0, i] * Mnu[3, j] + B[1, i] * Mnu[4, j] + B[2, i] * Mnu[5, j]
    for i in range(3):
        for j in range(3):
            M[i, j] = mass if i == j else 0.0
        for j in range(turns):
            s = AM[i, 3] * B[0, j] + AM[i, 4] * B[1, j] + AM[i, 5] * B[2, j]
            M[i, 3 + j] = s
            M[3 + j, i] = s
        for k in range(r):
            M[i, o + k] = AM[i, 6 + k]
            M[o + k, i] = AM[i, 6 + k]
        Q[i] = A[i, 0] * f[0] + A[i, 1] * f[1] + A[i, 2] * f[2]
    for i in range(turns):
        for j in range(turns):
            M[3 + i, 3 + j] = BM[i, 3] * B[0, j] + BM[i, 4] * B[1, j] + BM[i, 5] * B[2, j]
        for k in range(r):
            M[3 + i, o + k] = BM[i, 6 + k]
            M[o + k, 3 + i] = BM[i, 6 + k]
        Q[3 + i] = B[0, i] * f[3] + B[1, i] * f[4] + B[2, i] * f[5]
    for k in range(r):
        for l in range(r):
            M[o + k, o + l] = Mnu[6 + k, 6 + l]
        Q[o + k] = f[6 + k]


@njit(**OPTIONS)
def fill(q, qd, out, start, m0, q0, g0, axes, W, s0, K, D, S):
    """One flexible part's M_q (row by row from out[m0]) and Q_q (from out[q0]) at its
    coordinates from ``start``, its gravity read from out[g0:g0 + 3] (the generated
    function's inputs). A part turned by a quaternion (``axes`` empty) has M_q made positive
    definite: its unit-norm row holds uᵀq̈ = −u̇ᵀu̇, so c u uᵀ q̈ = −c (u̇ᵀu̇) u added to both
    sides (c: M_q's quaternion block's trace over uᵀu) changes no motion, only that row's
    multiplier off the manifold, and the kernel then solves the extra coordinates through
    their mass (kernel._close_reduced); one turned by angles has a regular M_q already (away
    from the angles' singular position)."""
    n = (7 if axes.shape[0] == 0 else 6) + K.shape[0]
    M, Q, Mnu, nu = np.zeros((n, n)), np.zeros(n), np.zeros((K.shape[0] + 6, K.shape[0] + 6)), np.zeros(K.shape[0] + 6)
    equations(q[start:start + n], qd[start:start + n], out[g0:g0 + 3], axes, W, s0, K, D, S, M, Q, Mnu, nu)
    if axes.shape[0] == 0:
        u, u_dot = q[start + 3:start + 7], qd[start + 3:start + 7]
        norm = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + u[3] * u[3]
        c = (M[3, 3] + M[4, 4] + M[5, 5] + M[6, 6]) / norm
        rate = u_dot[0] * u_dot[0] + u_dot[1] * u_dot[1] + u_dot[2] * u_dot[2] + u_dot[3] * u_dot[3]
        for a in range(4):
            Q[3 + a] -= c * rate * u[a]
            for b in range(4):
                M[3 + a, 3 + b] += c * u[a] * u[b]
    for i in range(n):
        out[q0 + i] = Q[i]
        for j in range(n):
            out[m0 + i * n + j] = M[i, j]


@njit(cache=True, error_model="numpy", nogil=True)
def fill_rows(q, qd, out, start, m0, q0, g0, axes, W, s0, K, D, S):
    """``fill`` per row of q, q̇ and out."""
    for row in range(q.shape[0]):
        fill(q[row], qd[row], out[row], start, m0, q0, g0, axes, W, s0, K, D, S)


class Filled:
    """A generated module (codegen.py, or None: no generated output) whose ``evaluate`` and
    ``evaluate_rows`` also write the M and Q of the flexible parts ``own`` (layout.Own)."""

    def __init__(self, generated, own):
        self.generated, self.own = generated, own

    def evaluate(self, t, q, qd, p, out):
        if self.generated is not None:
            self.generated.evaluate(t, q, qd, p, out)
        for part in self.own:
            fill(q, qd, out, part.start, part.m0, part.q0, part.g0, *part.arrays)

    def evaluate_rows(self, t, q, qd, p, out):
        if self.generated is not None:
            self.generated.evaluate_rows(t, q, qd, p, out)
        for part in self.own:
            fill_rows(q, qd, out, part.start, part.m0, part.q0, part.g0, *part.arrays)
