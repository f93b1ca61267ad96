"""Linear-time elimination of a tree-structured KKT system (Baraff 1996), in articulated
form (Featherstone's ABA, here over maximal coordinates and any joint rows).

Each node i (a body) owns a block of unknowns: its v_i accelerations y_i (6 for a rigid
body after bodies.py's change of variables, 3 for a particle) followed by the k_i
multipliers λ_i of the joint that hangs it from its parent. Only those joint rows touch
the parent:

    H_i y_i + J_iᵀ λ_i + Σ_children P_cᵀ λ_c = f_i,      J_i y_i + P_i y_p = g_i.

``factor`` finds, per joint, a basis S_i of J_i's null space and a right inverse Jr_i
(J_i Jr_i = I) — in closed form for joints whose rows are components of d and dots of
axes, else by Gauss–Jordan with full pivoting — and X_i with J_i X_i = −P_i: for a rigid
body on a rigid parent the rigid transport X = [[I, [ζ]×], [0, I]] (assembly.transports),
exact for the rows of rate_rows.py, else X_i = −Jr_i P_i. The rows then say y_i = X_i y_p + Jr_i g_i + S_i x_i (x_i: the joint's
free accelerations), and eliminating from the leaves to the roots causes no fill-in:

    H^A_i = H_i + Σ_children X_cᵀ I^a_c X_c,     N_i = (S_iᵀ H^A_i S_i)⁻¹,
    I^a_i = H^A_i − U_i N_i U_iᵀ,  U_i = H^A_i S_i       (the articulated mass).

A block alone may be singular (a massless body, a rank-3 inertia); S_iᵀ H^A_i S_i is
positive definite exactly when the subtree is determinate. A pivot of its Cholesky
factor below ``PIVOT_RTOL`` of max(‖H^A_i‖, 1) ‖s‖² — H is divided by the model's largest
mass (kernel.py), so 1 is the whole model's scale, as in the rank rule of (2.14) — or
joint rows that are dependent to that tolerance, make ``factor`` report the node: the
caller then hands the problem to the exact treatment, whose rank rule decides a block
that is small against the model (a nearly massless link) as it decides any other.
``solve`` returns the λ_i too (λ_i = Jr_iᵀ (f^A_i − H^A_i y_i)).

The per-node steps are inlined helpers called with constant sizes for a rigid body on a
revolute (v = 6, k = 5) or a fixed joint (6, 6) and with the node's sizes otherwise: numba
unrolls the constant loops (about a third off the elimination and the solve). What they
call (null spaces, inverses) takes the sizes as np.int64, which numba types as int64 rather
than as literals, so it is compiled once rather than once per constant.
"""

import math

import numpy as np
from numba import njit

from .bodies import INLINE, OPTIONS, cross3, dot3
from ..core.tolerances import PIVOT_RTOL

GENERAL, RIGID_INVARIANT, RIGID_COMPONENTS = 0, 1, 2  # a node's transport X (layout.node_transport)


@njit(**OPTIONS)
def _null_space(J, r0, k, v, S, Jr, G, pivot):
    """S[:v, :v − k] a basis of the null space and Jr[:v, :k] a right inverse of the node's
    rows J[r0:r0 + k, :v] (Gauss–Jordan with full pivoting on G = [J | I]). False when
    the rows are dependent."""
    scale = 0.0
    for r in range(k):
        for c in range(v):
            G[r, c] = J[r0 + r, c]
            scale = max(scale, abs(G[r, c]))
        for c in range(k):
            G[r, v + c] = 1.0 if r == c else 0.0
    for c in range(v):
        pivot[6 + c] = 0  # column c taken
    for step in range(k):
        best, pr, pc = 0.0, step, 0
        for r in range(step, k):
            for c in range(v):
                if pivot[6 + c] == 0 and abs(G[r, c]) > best:
                    best, pr, pc = abs(G[r, c]), r, c
        if not best > PIVOT_RTOL * scale:
            return False
        if pr != step:
            for c in range(v + k):
                G[step, c], G[pr, c] = G[pr, c], G[step, c]
        inv = 1.0 / G[step, pc]
        for c in range(v + k):
            G[step, c] *= inv
        for r in range(k):
            f = G[r, pc]
            if r != step and f != 0.0:
                for c in range(v + k):
                    G[r, c] -= f * G[step, c]
        pivot[step], pivot[6 + pc] = pc, 1
    m = 0
    for c in range(v):
        for a in range(v):
            S[a, c] = 0.0
        for r in range(k):
            Jr[c, r] = 0.0
    for c in range(v):
        if pivot[6 + c] == 0:
            S[c, m] = 1.0
            for step in range(k):
                S[pivot[step], m] = -G[step, c]
            m += 1
    for step in range(k):
        for r in range(k):
            Jr[pivot[step], r] = G[step, v + r]
    return True


@njit(**OPTIONS)
def _null_space_components(J, r0, k, S, Jr, G):
    """_null_space for rows of a rigid transport with components (layout): three rows
    d_a r̈_a + C_a·α (a component of d) and k − 3 rows N_b·α (dots of axes). The null
    space is α = T x with T a basis of N's null space, r̈ = −D⁻¹C α; a right inverse
    takes α = Nᵀ(NNᵀ)⁻¹ g_N and r̈ = D⁻¹(g_D − C α). G: work. False when rows are dependent."""
    n = k - 3
    top = 0.0
    for a in range(3):
        top = max(top, abs(J[r0 + a, a]))
    for a in range(3):
        if not abs(J[r0 + a, a]) > PIVOT_RTOL * top:
            return False
    for b in range(n):  # G[8] ← ‖N_b‖², G[0:3, 0:3] ← N Nᵀ
        for c in range(n):
            t = 0.0
            for e in range(3):
                t += J[r0 + 3 + b, 3 + e] * J[r0 + 3 + c, 3 + e]
            G[b, c] = t
        G[8, b] = G[b, b]
    if not spd_inverse(G, n, G[8], G[3:6]):
        return False
    for e in range(3):  # T into S[3:6, :6 − k]
        for x in range(3):
            S[3 + e, x] = 1.0 if (n == 0 and e == x) else 0.0
    if n == 1:
        e = 0  # the axis least along N_0, then t1 = N_0 × axis, t2 = N_0 × t1
        for x in range(3):
            if abs(J[r0 + 3, 3 + x]) < abs(J[r0 + 3, 3 + e]):
                e = x
        n0, n1, n2 = J[r0 + 3, 3], J[r0 + 3, 4], J[r0 + 3, 5]
        u0, u1, u2 = (0.0, n2, -n1) if e == 0 else ((-n2, 0.0, n0) if e == 1 else (n1, -n0, 0.0))
        S[3, 0], S[4, 0], S[5, 0] = u0, u1, u2
        S[3, 1], S[4, 1], S[5, 1] = n1 * u2 - n2 * u1, n2 * u0 - n0 * u2, n0 * u1 - n1 * u0
    elif n == 2:
        a0, a1, a2 = J[r0 + 3, 3], J[r0 + 3, 4], J[r0 + 3, 5]
        b0, b1, b2 = J[r0 + 4, 3], J[r0 + 4, 4], J[r0 + 4, 5]
        S[3, 0], S[4, 0], S[5, 0] = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    for a in range(3):  # r̈ part of S: −D⁻¹ C T
        inv = 1.0 / J[r0 + a, a]
        for x in range(3 - n):
            t = 0.0
            for e in range(3):
                t += J[r0 + a, 3 + e] * S[3 + e, x]
            S[a, x] = -inv * t
    for e in range(3):  # Jr: the N columns α = Nᵀ (NNᵀ)⁻¹, the D columns 0
        for c in range(3):
            Jr[3 + e, c] = 0.0
        for c in range(n):
            t = 0.0
            for b in range(n):
                t += J[r0 + 3 + b, 3 + e] * G[b, c]
            Jr[3 + e, 3 + c] = t
    for a in range(3):  # r̈ = D⁻¹ (g_D − C α)
        inv = 1.0 / J[r0 + a, a]
        for c in range(k):
            t = 1.0 if c == a else 0.0
            for e in range(3):
                t -= J[r0 + a, 3 + e] * Jr[3 + e, c]
            Jr[a, c] = inv * t
    return True


@njit(**INLINE)
def _row3(J, r, o):
    """J[r, o:o + 3] as a 3-tuple."""
    return (J[r, o], J[r, o + 1], J[r, o + 2])


@njit(**OPTIONS)
def _components_closed(J, r0, k, S, Jr):
    """_null_space_components in closed form for a revolute (k = 5: two dot rows N_0, N_1,
    T = N_0 × N_1) or a fixed joint (k = 6: N invertible, Nᵀ(NNᵀ)⁻¹ = N⁻¹ by cross
    products); the same pivot tests as the Cholesky factor of NNᵀ."""
    D = (J[r0, 0], J[r0 + 1, 1], J[r0 + 2, 2])
    top = max(abs(D[0]), max(abs(D[1]), abs(D[2])))
    for a in range(3):
        if not abs(D[a]) > PIVOT_RTOL * top:
            return False
    N0, N1 = _row3(J, r0 + 3, 3), _row3(J, r0 + 4, 3)
    g00, g11, T = dot3(N0, N0), dot3(N1, N1), cross3(N0, N1)
    t2 = dot3(T, T)  # |N_0 × N_1|², the determinant of N Nᵀ (k = 5)
    if not (g00 > PIVOT_RTOL * g00 and t2 > PIVOT_RTOL * g11 * g00):
        return False
    if k == 5:
        g01, r2 = dot3(N0, N1), 1.0 / t2
        j0 = ((g11 * N0[0] - g01 * N1[0]) * r2, (g11 * N0[1] - g01 * N1[1]) * r2, (g11 * N0[2] - g01 * N1[2]) * r2)
        j1 = ((g00 * N1[0] - g01 * N0[0]) * r2, (g00 * N1[1] - g01 * N0[1]) * r2, (g00 * N1[2] - g01 * N0[2]) * r2)
        for e in range(3):
            S[3 + e, 0] = T[e]
            Jr[3 + e, 0] = Jr[3 + e, 1] = Jr[3 + e, 2] = 0.0
            Jr[3 + e, 3], Jr[3 + e, 4] = j0[e], j1[e]
        for a in range(3):
            C = _row3(J, r0 + a, 3)
            inv = 1.0 / D[a]
            S[a, 0] = -inv * dot3(C, T)
            for c in range(3):
                Jr[a, c] = inv if c == a else 0.0
            Jr[a, 3], Jr[a, 4] = -inv * dot3(C, j0), -inv * dot3(C, j1)
        return True
    N2 = _row3(J, r0 + 5, 3)
    det = dot3(N2, T)
    if not det * det > PIVOT_RTOL * dot3(N2, N2) * t2:
        return False
    r = 1.0 / det  # N⁻¹'s columns: (N1×N2, N2×N0, N0×N1)/det
    c0, c1, c2 = _scaled3(r, cross3(N1, N2)), _scaled3(r, cross3(N2, N0)), _scaled3(r, T)
    for e in range(3):
        Jr[3 + e, 0] = Jr[3 + e, 1] = Jr[3 + e, 2] = 0.0
        Jr[3 + e, 3], Jr[3 + e, 4], Jr[3 + e, 5] = c0[e], c1[e], c2[e]
    for a in range(3):
        C = _row3(J, r0 + a, 3)
        inv = 1.0 / D[a]
        for c in range(3):
            Jr[a, c] = inv if c == a else 0.0
        Jr[a, 3], Jr[a, 4], Jr[a, 5] = -inv * dot3(C, c0), -inv * dot3(C, c1), -inv * dot3(C, c2)
    return True


@njit(**INLINE)
def _scaled3(f, x):
    """f x for a 3-tuple x."""
    return (f * x[0], f * x[1], f * x[2])


@njit(**INLINE)
def cholesky(A, m, scale, L):
    """L[:m, :m]'s lower triangle ← the Cholesky factor of A[:m, :m] (from its lower
    triangle; L may be A itself). False when a pivot is not above PIVOT_RTOL · scale[j]
    (scale: per column)."""
    for j in range(m):
        d = A[j, j]
        for c in range(j):
            d -= L[j, c] * L[j, c]
        if not d > PIVOT_RTOL * scale[j]:
            return False
        L[j, j] = math.sqrt(d)
        for r in range(j + 1, m):
            t = A[r, j]
            for c in range(j):
                t -= L[r, c] * L[j, c]
            L[r, j] = t / L[j, j]
    return True


@njit(**OPTIONS)
def cholesky_solve(L, rhs, out):
    """out ← (L Lᵀ)⁻¹ rhs for ``cholesky``'s factor L (m × m, m = out's size; rhs[:m])."""
    m = out.shape[0]
    for r in range(m):
        t = rhs[r]
        for c in range(r):
            t -= L[r, c] * out[c]
        out[r] = t / L[r, r]
    for r in range(m - 1, -1, -1):
        t = out[r]
        for c in range(r + 1, m):
            t -= L[c, r] * out[c]
        out[r] = t / L[r, r]


@njit(**OPTIONS)
def spd_inverse(A, m, scale, L):
    """A[:m, :m] ← its inverse by Cholesky (L: work). False when a pivot is not above
    PIVOT_RTOL · scale[j] (scale: per column)."""
    if m == 1:  # one free unknown (a revolute, a slider): the pivot's reciprocal
        if not A[0, 0] > PIVOT_RTOL * scale[0]:
            return False
        A[0, 0] = 1.0 / A[0, 0]
        return True
    if not cholesky(A, m, scale, L):
        return False
    for j in range(m):  # L ← L⁻¹ (lower triangular)
        L[j, j] = 1.0 / L[j, j]
        for r in range(j + 1, m):
            t = 0.0
            for c in range(j, r):
                t -= L[r, c] * L[c, j]
            L[r, j] = t / L[r, r]
    for r in range(m):  # A⁻¹ = L⁻ᵀ L⁻¹
        for c in range(r + 1):
            t = 0.0
            for e in range(r, m):
                t += L[e, r] * L[e, c]
            A[r, c] = t
            A[c, r] = t
    return True


@njit(**INLINE)
def _cross_into(x, z, out, o):
    """out[o:o + 3] += x × z."""
    out[o] += x[1] * z[2] - x[2] * z[1]
    out[o + 1] += x[2] * z[0] - x[0] * z[2]
    out[o + 2] += x[0] * z[1] - x[1] * z[0]


@njit(**OPTIONS)
def _add_rigid_transport(Ia, z, Hp, W):
    """Hp += Xᵀ Ia X for X = [[I, [ζ]×], [0, I]]: with Ia = [[A, B], [Bᵀ, D]] and
    M = A [ζ]× + B, Xᵀ Ia X = [[A, M], [Mᵀ, [ζ]×ᵀ M + Bᵀ [ζ]× + D]] (rows of A [ζ]× and
    Bᵀ[ζ]×: a row × ζ; columns of [ζ]×ᵀ M: a column × ζ). W: work, its rows 6 to 9 (Ia may
    be W's first six)."""
    M = W[6:9, 0:3]
    for a in range(3):
        for c in range(3):
            M[a, c] = Ia[a, 3 + c]
        _cross_into(Ia[a, 0:3], z, M[a], 0)
    for a in range(3):
        for c in range(3):
            Hp[a, c] += Ia[a, c]
            Hp[a, 3 + c] += M[a, c]
            Hp[3 + c, a] += M[a, c]
            Hp[3 + a, 3 + c] += Ia[3 + a, 3 + c]
        _cross_into(Ia[0:3, 3 + a], z, Hp[3 + a], 3)  # row a of Bᵀ[ζ]×
    col = W[9, 0:3]
    for c in range(3):  # column c of [ζ]×ᵀ M
        col[0], col[1], col[2] = M[1, c] * z[2] - M[2, c] * z[1], M[2, c] * z[0] - M[0, c] * z[2], \
            M[0, c] * z[1] - M[1, c] * z[0]
        for a in range(3):
            Hp[3 + a, 3 + c] += col[a]


@njit(**INLINE)
def _factor_node(i, vi, ki, topology, H, J, P, factored, G, pivot):
    """Node i (vi unknowns, ki rows) of ``factor``: its S, Jr, N and U, and its articulated
    mass carried into its parent's H^A. False when its block is singular."""
    parent, v, rows, transport = topology[1], topology[2], topology[5], topology[6]
    HA, S, Jr, X, U, N, zeta = factored[0], factored[1], factored[2], factored[3], factored[4], factored[5], factored[8]
    m = vi - ki
    if transport[i] == RIGID_COMPONENTS:
        if ki == 5 or ki == 6:
            if not _components_closed(J, rows[i], np.int64(ki), S[i], Jr[i]):
                return False
        elif not _null_space_components(J, rows[i], np.int64(ki), S[i], Jr[i], G):
            return False
    elif not _null_space(J, rows[i], np.int64(ki), np.int64(vi), S[i], Jr[i], G, pivot):
        return False
    Ha, Si, Ui, Ni = HA[i], S[i], U[i], N[i]
    if vi == 6:  # a rigid body's H is blockdiag(m I₃, R J Rᵀ) (assembly.nodes): its nonzero entries alone
        for a in range(3):
            Ha[a, a] += H[i, a, a]
            for c in range(3):
                Ha[3 + a, 3 + c] += H[i, 3 + a, 3 + c]
    else:
        for a in range(vi):
            for c in range(vi):
                Ha[a, c] += H[i, a, c]
    top = 0.0  # max |H^A| (H^A is positive semidefinite: its largest entry is on the diagonal)
    for a in range(vi):
        top = max(top, Ha[a, a])
    for a in range(vi):
        for e in range(m):
            t = 0.0
            for c in range(vi):
                t += Ha[a, c] * Si[c, e]
            Ui[a, e] = t
    top = max(top, 1.0)  # H is divided by the model's largest mass: a pivot is judged against the model too
    for e in range(m):
        norm = 0.0
        for a in range(vi):
            norm += Si[a, e] * Si[a, e]
        G[0, e] = top * norm
        for f in range(e + 1):
            t = 0.0
            for a in range(vi):
                t += Si[a, e] * Ui[a, f]
            Ni[e, f] = t
            Ni[f, e] = t
    if not spd_inverse(Ni, m, G[0], G[1:7]):
        return False
    p = parent[i]
    if p < 0:  # a root passes nothing on
        return True
    if m == 0 and transport[i] != GENERAL:  # held by its rows alone (welded): I^a = H^A
        _add_rigid_transport(Ha, zeta[i], HA[p], G)
        return True
    for a in range(vi):  # G ← I^a = H^A − U N Uᵀ
        for c in range(a + 1):
            t = Ha[a, c]
            for e in range(m):
                w = 0.0
                for f in range(m):
                    w += Ni[e, f] * Ui[c, f]
                t -= Ui[a, e] * w
            G[a, c] = t
            G[c, a] = t
    if transport[i] != GENERAL:
        _add_rigid_transport(G, zeta[i], HA[p], G)
        return True
    vp, r0, Xi = v[p], rows[i], X[i]
    for a in range(vi):
        for c in range(vp):
            t = 0.0
            for r in range(ki):
                t -= Jr[i, a, r] * P[r0 + r, c]
            Xi[a, c] = t
    for a in range(vi):  # G[6:] ← I^a X
        for c in range(vp):
            t = 0.0
            for e in range(vi):
                t += G[a, e] * Xi[e, c]
            G[6 + a, c] = t
    Hp = HA[p]
    for a in range(vp):  # H^A_p += Xᵀ I^a X
        for c in range(vp):
            t = 0.0
            for e in range(vi):
                t += Xi[e, a] * G[6 + e, c]
            Hp[a, c] += t
    return True


@njit(**OPTIONS)
def factor(topology, H, J, P, factored, G, pivot):
    """Eliminate leaves to roots into ``factored`` = (H^A, S, Jr, X, U, N, c, x0, ζ): per
    node 6 × 6 matrices, then solve's work and the rigid transports (assembly.transports).
    topology: (order, parent, v, k, yoff, rows, transport) of the nodes (layout.Layout); H: (N, 6, 6) node masses; J, P: (rows, 6) each node's joint rows on
    itself / on its parent, node i's starting at rows[i]. Returns the first node whose
    block is singular, or −1. The common sizes (a rigid body on a revolute or a fixed
    joint) are compiled with constant sizes, which numba unrolls."""
    order, v, k = topology[0], topology[2], topology[3]
    HA = factored[0]
    for idx in range(order.shape[0]):
        HA[order[idx]] = 0.0
    for idx in range(order.shape[0] - 1, -1, -1):
        i = order[idx]
        if v[i] == 6 and k[i] == 5:
            done = _factor_node(i, 6, 5, topology, H, J, P, factored, G, pivot)
        elif v[i] == 6 and k[i] == 6:
            done = _factor_node(i, 6, 6, topology, H, J, P, factored, G, pivot)
        else:
            done = _factor_node(i, v[i], k[i], topology, H, J, P, factored, G, pivot)
        if not done:
            return i
    return -1


@njit(**INLINE)
def _backward(i, vi, ki, topology, factored, y, x):
    """Node i (vi unknowns, ki rows) of the leaves-to-roots pass of ``solve``: c = Jr g,
    x0 = N Sᵀ t with t = f − H^A c, and f^A_p += Xᵀ (t − U x0)."""
    parent, v, yoff, transport = topology[1], topology[2], topology[4], topology[6]
    HA, S, Jr, X, U, N, c, x0, zeta = factored
    m, o = vi - ki, yoff[i]
    for a in range(vi):
        t = 0.0
        for r in range(ki):
            t += Jr[i, a, r] * y[o + vi + r]
        c[i, a] = t
    for a in range(vi):  # x[o:o+v] ← t (work)
        t = y[o + a]
        for e in range(vi):
            t -= HA[i, a, e] * c[i, e]
        x[o + a] = t
    for f in range(m):  # c[i, v:] ← Sᵀ t (the spare part of c), then x0 ← N Sᵀ t
        t = 0.0
        for a in range(vi):
            t += S[i, a, f] * x[o + a]
        c[i, vi + f] = t
    for e in range(m):
        t = 0.0
        for f in range(m):
            t += N[i, e, f] * c[i, vi + f]
        x0[i, e] = t
    p = parent[i]
    if p < 0:
        return
    op = yoff[p]
    for a in range(vi):
        t = x[o + a]
        for e in range(m):
            t -= U[i, a, e] * x0[i, e]
        x[o + a] = t
    if transport[i] != GENERAL:  # Xᵀβ = (β_r, β_α + β_r × ζ)
        for a in range(6):
            y[op + a] += x[o + a]
        _cross_into(x[o:o + 3], zeta[i], y, op + 3)
        return
    for c2 in range(v[p]):
        t = 0.0
        for a in range(vi):
            t += X[i, a, c2] * x[o + a]
        y[op + c2] += t


@njit(**INLINE)
def _forward(i, vi, ki, topology, factored, y, x, multipliers):
    """Node i of the roots-to-leaves pass of ``solve``: y_i = c + X y_p + S (x0 − N Uᵀ X y_p),
    then (``multipliers``) λ_i = Jrᵀ (f^A − H^A y_i)."""
    parent, v, yoff, transport = topology[1], topology[2], topology[4], topology[6]
    HA, S, Jr, X, U, N, c, x0, zeta = factored
    m, o, p = vi - ki, yoff[i], parent[i]
    for a in range(vi):
        x[o + a] = c[i, a]
    if p >= 0:
        op = yoff[p]
        if transport[i] != GENERAL:  # X y_p = (r̈_p + ζ × α_p, α_p)
            for a in range(6):
                x[o + a] += x[op + a]
            _cross_into(zeta[i], x[op + 3:op + 6], x, o)
        else:
            for a in range(vi):
                t = 0.0
                for c2 in range(v[p]):
                    t += X[i, a, c2] * x[op + c2]
                x[o + a] += t
        for f in range(m):  # c[i, 6 + f] ← (Uᵀ X y_p)_f
            t = 0.0
            for a in range(vi):
                t += U[i, a, f] * (x[o + a] - c[i, a])
            c[i, vi + f] = t
        for e in range(m):
            t = 0.0
            for f in range(m):
                t += N[i, e, f] * c[i, vi + f]
            x0[i, e] -= t
    for a in range(vi):
        t = 0.0
        for e in range(m):
            t += S[i, a, e] * x0[i, e]
        x[o + a] += t
    if not multipliers:
        return
    for a in range(vi):  # c ← f^A − H^A y, then λ = Jrᵀ c
        t = y[o + a]
        for e in range(vi):
            t -= HA[i, a, e] * x[o + e]
        c[i, a] = t
    for r in range(ki):
        t = 0.0
        for a in range(vi):
            t += Jr[i, a, r] * c[i, a]
        x[o + vi + r] = t


@njit(**OPTIONS)
def solve(topology, factored, y, x, multipliers):
    """x = K⁻¹ y for the factored tree (y is overwritten): per node, the accelerations,
    then (``multipliers``; else they are left as they were) the multipliers of its parent
    joint — only the residual check reads them."""
    order, v, k = topology[0], topology[2], topology[3]
    n = order.shape[0]
    for idx in range(n - 1, -1, -1):
        i = order[idx]
        if v[i] == 6 and k[i] == 6:
            _backward(i, 6, 6, topology, factored, y, x)
        elif v[i] == 6 and k[i] == 5:
            _backward(i, 6, 5, topology, factored, y, x)
        else:
            _backward(i, v[i], k[i], topology, factored, y, x)
    for idx in range(n):
        i = order[idx]
        if v[i] == 6 and k[i] == 6:
            _forward(i, 6, 6, topology, factored, y, x, multipliers)
        elif v[i] == 6 and k[i] == 5:
            _forward(i, 6, 5, topology, factored, y, x, multipliers)
        else:
            _forward(i, v[i], k[i], topology, factored, y, x, multipliers)
