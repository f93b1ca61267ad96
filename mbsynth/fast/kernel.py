"""The fast path's whole evaluation, in numba: assemble, factor the tree, close the loops,
recover q̈ and Qc, check.

Extra rows (loop joints, other constraints) and extra coordinates (other parts) join the
tree system K z = r as a bordered system. With G the extra rows on the tree unknowns,

    [[M_x, A_xᵀ], [A_x, −G K⁻¹ Gᵀ]] [q̈_x; λ_x] = [F_x; b_x − G K⁻¹ r],   z = K⁻¹ (r − Gᵀ λ_x):

the tree is factored once and each extra row costs one tree solve. The small symmetric
Schur matrix is solved by its eigendecomposition, dropping eigenvalues below
``EIG_RTOL`` of the largest (redundant rows, as a planar loop's in 3D). A dropped
direction must leave the right side alone (else the rows contradict: INCONSISTENT) and
must move no acceleration (else the motion is not unique: NOT_UNIQUE).

Status: OK, or why the caller must hand the problem to the exact treatment — a singular
tree block (SINGULAR), the two cases above, a residual above ``RESIDUAL_MAX`` or a
non-finite result. ``residual`` is the relative residual of the equilibrated KKT
equations M q̈ + Aᵀλ = Q + C, A q̈ = b (it bounds that of (2.12): P Aᵀ = 0, ‖P‖ = 1).
"""

import math

import numpy as np
from numba import njit, prange

from .assembly import assemble, make_work
from .bodies import OPTIONS, rate_transpose
from .joints import RIGID
from .tree import factor, solve

OK, SINGULAR, INCONSISTENT, NOT_UNIQUE, RESIDUAL, NOT_FINITE = range(6)
REASONS = ("ok", "a singular tree block", "contradictory extra rows", "a free direction",
           "a large residual", "a value that is not finite")
EIG_RTOL = 1e-10  # Schur eigenvalues below this fraction of the largest count as zero
CONSISTENCY_RTOL = 1e-10  # largest part of the right side along dropped directions
NULL_RTOL = 1e-8  # largest acceleration a dropped (unit) direction may move
RESIDUAL_MAX = 1e-9


@njit(**OPTIONS)
def _tree_solve(L, W, y, x):
    solve(L.order, L.node_parent, L.node_v, L.node_k, L.node_doff, L.node_yoff, L.node_rows, W.P, W.Dinv, y, x)


@njit(**OPTIONS)
def _scatter(x, weight, L, W, y):
    """y += weight · (extra row x on the tree unknowns)."""
    for seg in range(L.xseg_ptr[x], L.xseg_ptr[x + 1]):
        i = L.xseg_node[seg]
        for a in range(L.node_v[i]):
            y[L.node_yoff[i] + a] += weight * W.seg6[seg, a]


@njit(**OPTIONS)
def _row_dot(x, L, W, z):
    """(extra row x on the tree unknowns) · z."""
    total = 0.0
    for seg in range(L.xseg_ptr[x], L.xseg_ptr[x + 1]):
        i = L.xseg_node[seg]
        for a in range(L.node_v[i]):
            total += W.seg6[seg, a] * z[L.node_yoff[i] + a]
    return total


@njit(**OPTIONS)
def _moves(vec, nx, mx, L, W):
    """The acceleration a unit Schur direction (u_x, μ) moves: (u_x, −(K⁻¹Gᵀμ) on accelerations)."""
    W.y[:] = 0.0
    for x in range(mx):
        _scatter(x, -vec[nx + x], L, W, W.y)
    _tree_solve(L, W, W.y, W.w)
    total = 0.0
    for x in range(nx):
        total += vec[x] * vec[x]
    for i in range(L.node_kind.shape[0]):
        for a in range(L.node_v[i]):
            total += W.w[L.node_yoff[i] + a] ** 2
    return math.sqrt(total)


@njit(**OPTIONS)
def _close(L, W):
    """Solve the Schur system of the extra rows and coordinates into W.lam, then the tree
    into W.z. Returns a status."""
    nx, mx = L.x_coord.shape[0], L.xrow_row.shape[0]
    S, rhs = W.S, W.rhs
    S[:, :] = 0.0
    S[:nx, :nx] = W.Mx
    for x in range(mx):
        for c in range(nx):
            S[c, nx + x] = W.Ax[x, c]
            S[nx + x, c] = W.Ax[x, c]
        rhs[nx + x] = W.xb[x] - _row_dot(x, L, W, W.z0)
    rhs[:nx] = W.Fx
    for x in range(mx):
        W.y[:] = 0.0
        _scatter(x, 1.0, L, W, W.y)
        _tree_solve(L, W, W.y, W.w)
        for r in range(mx):
            S[nx + r, nx + x] = -_row_dot(r, L, W, W.w)
    values, vectors = np.linalg.eigh(S)
    top = np.abs(values).max() if values.shape[0] else 0.0
    W.lam[:] = 0.0
    dropped = 0.0
    for e in range(values.shape[0]):
        coef = vectors[:, e] @ rhs
        if abs(values[e]) > EIG_RTOL * top:
            for c in range(values.shape[0]):
                W.lam[c] += coef / values[e] * vectors[c, e]
        else:
            dropped += coef * coef
            if _moves(vectors[:, e], nx, mx, L, W) > NULL_RTOL:
                return NOT_UNIQUE
    if math.sqrt(dropped) > CONSISTENCY_RTOL * (math.sqrt(rhs @ rhs) + 1e-300):
        return INCONSISTENT
    W.y[:] = W.ry
    for x in range(mx):
        _scatter(x, -W.lam[nx + x], L, W, W.y)
    _tree_solve(L, W, W.y, W.z)
    return OK


@njit(**OPTIONS)
def _recover(q, L, W, mu):
    """q̈ (bodies.py: ü = (u s + Eᵀa)/ν) and Qc = M q̈ − Q from the solution."""
    for i in range(L.node_kind.shape[0]):
        c, o, m = L.node_q[i], L.node_yoff[i], L.node_mass[i]
        for a in range(3):
            W.qdd[c + a] = W.z[o + a]
            W.Qc[c + a] = m * W.z[o + a] - W.Qf[c + a]
        if L.node_kind[i] != RIGID:
            continue
        u, nu, s, J = q[c + 3:c + 7], W.nu[i], W.s[i], L.node_J[i]
        alpha = (W.z[o + 3], W.z[o + 4], W.z[o + 5])
        et = rate_transpose(u, alpha)
        Ja = (J[0, 0] * alpha[0] + J[0, 1] * alpha[1] + J[0, 2] * alpha[2],
              J[1, 0] * alpha[0] + J[1, 1] * alpha[1] + J[1, 2] * alpha[2],
              J[2, 0] * alpha[0] + J[2, 1] * alpha[1] + J[2, 2] * alpha[2])
        f = rate_transpose(u, Ja)
        for a in range(4):
            W.qdd[c + 3 + a] = (u[a] * s + et[a]) / nu
            W.Qc[c + 3 + a] = 4 * nu * f[a] - W.Qf[c + 3 + a]
    nx = L.x_coord.shape[0]
    for x in range(nx):
        total = 0.0
        for c in range(nx):
            total += W.Mx[x, c] * W.lam[c]
        W.qdd[L.x_coord[x]] = W.lam[x]
        W.Qc[L.x_coord[x]] = mu * total - W.Qf[L.x_coord[x]]


@njit(**OPTIONS)
def _residual(L, W):
    """Relative residual of the equilibrated KKT equations at the solution (module docstring)."""
    N, nx, mx = L.node_kind.shape[0], L.x_coord.shape[0], L.xrow_row.shape[0]
    z, dyn = W.z, W.dyn
    res = norm_M = norm_A = norm_x = norm_r = 0.0
    for i in range(N):
        o, v, k, r0 = L.node_yoff[i], L.node_v[i], L.node_k[i], L.node_rows[i]
        for a in range(v):
            t = -W.F[i, a]
            for c in range(v):
                t += W.H[i, a, c] * z[o + c]
                norm_M += W.H[i, a, c] ** 2
            for r in range(k):
                t += W.J[r0 + r, a] * z[o + v + r]
            dyn[i, a] = t
            norm_x += z[o + a] ** 2
            norm_r += W.F[i, a] ** 2
        if L.node_kind[i] == RIGID:
            norm_x += W.s[i] ** 2
            norm_r += W.s[i] ** 2
            norm_A += 1.0
    for i in range(N):
        p, o, v, k, r0 = L.node_parent[i], L.node_yoff[i], L.node_v[i], L.node_k[i], L.node_rows[i]
        for r in range(k):
            lam, t = z[o + v + r], -W.rb[r0 + r]
            for a in range(v):
                t += W.J[r0 + r, a] * z[o + a]
                norm_A += W.J[r0 + r, a] ** 2
            if p >= 0:
                op = L.node_yoff[p]
                for a in range(L.node_v[p]):
                    dyn[p, a] += W.P[r0 + r, a] * lam
                    t += W.P[r0 + r, a] * z[op + a]
                    norm_A += W.P[r0 + r, a] ** 2
            res += t * t
            norm_r += W.rb[r0 + r] ** 2
    for x in range(mx):
        lam = W.lam[nx + x]
        t = _row_dot(x, L, W, z) - W.xb[x]
        for seg in range(L.xseg_ptr[x], L.xseg_ptr[x + 1]):
            for a in range(6):
                dyn[L.xseg_node[seg], a] += W.seg6[seg, a] * lam
                norm_A += W.seg6[seg, a] ** 2
        for c in range(nx):
            t += W.Ax[x, c] * W.lam[c]
            norm_A += W.Ax[x, c] ** 2
        res += t * t
        norm_r += W.xb[x] ** 2
    for i in range(N):
        for a in range(L.node_v[i]):
            res += dyn[i, a] ** 2
    for c in range(nx):
        t = -W.Fx[c]
        for e in range(nx):
            t += W.Mx[c, e] * W.lam[e]
            norm_M += W.Mx[c, e] ** 2
        for x in range(mx):
            t += W.Ax[x, c] * W.lam[nx + x]
        res += t * t
        norm_x += W.lam[c] ** 2
        norm_r += W.Fx[c] ** 2
    scale = (math.sqrt(norm_M) + math.sqrt(norm_A)) * math.sqrt(norm_x) + math.sqrt(norm_r) + 1e-300
    return math.sqrt(res) / scale


@njit(**OPTIONS)
def motion(t, q, qd, gen, bshift, L, W):
    """(status, residual) at one state; on OK, W.qdd holds q̈ and W.Qc holds M q̈ − Q."""
    mu = assemble(t, q, qd, gen, bshift, L, W)
    if factor(L.order, L.node_parent, L.node_v, L.node_k, L.node_doff, L.node_rows, W.H, W.J, W.P, W.Dinv,
              W.acc, W.perm) >= 0:
        return SINGULAR, 0.0
    W.y[:] = W.ry
    _tree_solve(L, W, W.y, W.z0)
    W.z[:] = W.z0
    if L.x_coord.shape[0] + L.xrow_row.shape[0] > 0:
        status = _close(L, W)
        if status != OK:
            return status, 0.0
    _recover(q, L, W, mu)
    residual = _residual(L, W)
    for c in range(W.qdd.shape[0]):
        if not (math.isfinite(W.qdd[c]) and math.isfinite(W.Qc[c])):
            return NOT_FINITE, residual
    if not residual <= RESIDUAL_MAX:
        return RESIDUAL, residual
    return OK, residual


@njit(cache=True, error_model="numpy", parallel=True)
def motion_batch(t, q, qd, gen, L, qdd, status, chunks):
    """q̈ of each state (row) into qdd and its status into status, ``chunks`` blocks of
    states in parallel (each with its own Work)."""
    count = q.shape[0]
    size = (count + chunks - 1) // chunks
    empty = np.zeros(0)
    for chunk in prange(chunks):
        W = make_work(L)
        for row in range(chunk * size, min(count, (chunk + 1) * size)):
            status[row] = motion(t[row], q[row], qd[row], gen[row], empty, L, W)[0]
            qdd[row, :] = W.qdd
