"""One state's blocks for the tree solver, in numba: bodies (bodies.py), joint rows
(joints.py) and the generated function's outputs (codegen.py), laid out by layout.py.

``assemble`` fills a Work: each node's mass H and force F in its reduced unknowns
(bodies.py), its parent joint's rows on itself (J) and on its parent (P) with their right
sides, the extra rows as segments of 6 reduced coefficients per node plus their entries on
the extra coordinates (Ax), and the extra coordinates' M and F. Every row of A and b is
divided by the 2-norm of its row of A and M, Q, C by μ, the largest mass entry — the
equilibration of equations.py, so that pivots and tolerances compare like with like.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .bodies import OPTIONS, body_force, rate, reduce_row
from .joints import MAX_ROWS, RIGID, joint_rows

MAX_BLOCK = 6 + MAX_ROWS


class Work(NamedTuple):
    """Buffers of one evaluation (sizes from a Layout; see ``make_work``)."""

    Qf: np.ndarray     # (n,) Q: bodies' own and the generated additions
    Cf: np.ndarray     # (n,) C
    H: np.ndarray      # (N, 6, 6) node masses / μ
    F: np.ndarray      # (N, 6) node forces / μ
    s: np.ndarray      # (N,) quaternion norm accelerations (bodies.py)
    nu: np.ndarray     # (N,) quaternion lengths
    acc: np.ndarray    # (N, 6, 6) children's contributions (tree.factor)
    perm: np.ndarray   # (MAX_BLOCK,) pivot rows
    J: np.ndarray      # (tree rows, 6) parent-joint rows on the node
    P: np.ndarray      # (tree rows, 6) the same rows on the parent
    rb: np.ndarray     # (tree rows,) their right sides
    Dinv: np.ndarray   # flat inverse blocks
    ry: np.ndarray     # (tree unknowns,) right side of the tree system
    y: np.ndarray      # (tree unknowns,) work
    z: np.ndarray      # (tree unknowns,) solution
    z0: np.ndarray     # (tree unknowns,) K⁻¹ ry before the extra rows act
    w: np.ndarray      # (tree unknowns,) work
    V: np.ndarray      # joint vectors (joints.vector_work)
    R: np.ndarray
    Jt: np.ndarray
    A: np.ndarray      # (MAX_ROWS, 14) one joint's rows
    b: np.ndarray      # (MAX_ROWS,)
    q7: np.ndarray     # (7,) one body's Q
    seg7: np.ndarray   # (S, 7) extra rows' coefficients per node
    seg6: np.ndarray   # (S, 6) the same in reduced unknowns, equilibrated
    xb: np.ndarray     # (m_x,) extra rows' right sides
    Ax: np.ndarray     # (m_x, n_x) extra rows on extra coordinates
    Mx: np.ndarray     # (n_x, n_x) extra coordinates' M / μ
    Fx: np.ndarray     # (n_x,) their F / μ
    S: np.ndarray      # (n_x + m_x,)² Schur complement (kernel.py)
    rhs: np.ndarray    # (n_x + m_x,)
    lam: np.ndarray    # (n_x + m_x,) extra accelerations, then extra multipliers
    dyn: np.ndarray    # (N, 6) residual work
    qdd: np.ndarray    # (n,) result: q̈
    Qc: np.ndarray     # (n,) result: M q̈ − Q (2.5)


@njit(**OPTIONS)
def make_work(L):
    n, nz, dsize, rows = L.sizes[0], L.sizes[2], L.sizes[3], L.sizes[4]
    N, S = L.node_kind.shape[0], L.xseg_node.shape[0]
    mx, nx = L.xrow_row.shape[0], L.x_coord.shape[0]
    p = nx + mx
    return Work(np.zeros(n), np.zeros(n), np.zeros((N, 6, 6)), np.zeros((N, 6)), np.zeros(N), np.ones(N),
                np.zeros((N, 6, 6)), np.zeros(MAX_BLOCK, np.int64), np.zeros((rows, 6)), np.zeros((rows, 6)),
                np.zeros(rows), np.zeros(dsize), np.zeros(nz), np.zeros(nz), np.zeros(nz), np.zeros(nz), np.zeros(nz),
                np.zeros((9, 3, 17)), np.zeros((2, 3, 3)), np.zeros((3, 4)), np.zeros((MAX_ROWS, 14)),
                np.zeros(MAX_ROWS), np.zeros(7), np.zeros((S, 7)), np.zeros((S, 6)), np.zeros(mx), np.zeros((mx, nx)),
                np.zeros((nx, nx)), np.zeros(nx), np.zeros((p, p)), np.zeros(p), np.zeros(p), np.zeros((N, 6)),
                np.zeros(n), np.zeros(n))


@njit(**OPTIONS)
def _rows_of(j, q, qd, L, W):
    k = L.joint_k[j]
    joint_rows(L.joint_program[j], k, L.joint_kinds[j], L.joint_start[j], L.joint_s[j], L.joint_R[j],
               L.joint_length[j], q, qd, W.V, W.R, W.Jt, W.A, W.b)
    return k


@njit(**OPTIONS)
def _reduce(c7, i, q, L, W, out):
    """A row segment on node i in its reduced unknowns; returns the right-side shift."""
    if L.node_kind[i] == RIGID:
        o = L.node_q[i]
        return reduce_row(c7, q[o + 3:o + 7], W.nu[i], W.s[i], out)
    for a in range(3):
        out[a] = c7[a]
        out[3 + a] = 0.0
    return 0.0


@njit(**OPTIONS)
def _nodes(q, qd, bshift, L, W):
    """Masses, forces and quaternion norm accelerations of the nodes; returns μ."""
    mu = 0.0
    for i in range(L.node_kind.shape[0]):
        c, m = L.node_q[i], L.node_mass[i]
        H = W.H[i]
        H[:, :] = 0.0
        for a in range(3):
            H[a, a] = m
        mu = max(mu, abs(m))
        if L.node_kind[i] != RIGID:
            for a in range(3):
                W.Qf[c + a] += L.node_mg[i, a]
                W.F[i, a] = W.Qf[c + a] + W.Cf[c + a]
            continue
        u, ud = q[c + 3:c + 7], qd[c + 3:c + 7]
        nu = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + u[3] * u[3])
        W.nu[i] = nu
        shift = bshift[L.quat_row[i]] if bshift.shape[0] else 0.0
        W.s[i] = (shift - (ud[0] * ud[0] + ud[1] * ud[1] + ud[2] * ud[2] + ud[3] * ud[3])) / nu
        body_force(L.node_mg[i], L.node_J[i], u, ud, W.q7)
        for a in range(7):
            W.Qf[c + a] += W.q7[a]
        f = (W.Qf[c + 3] + W.Cf[c + 3], W.Qf[c + 4] + W.Cf[c + 4], W.Qf[c + 5] + W.Cf[c + 5],
             W.Qf[c + 6] + W.Cf[c + 6])
        e = rate(u, f)
        for a in range(3):
            W.F[i, a] = W.Qf[c + a] + W.Cf[c + a]
            W.F[i, 3 + a] = e[a] / nu
            for b in range(3):
                H[3 + a, 3 + b] = 4 * nu * nu * L.node_J[i, a, b]
                mu = max(mu, abs(H[3 + a, 3 + b]))
    return mu


@njit(**OPTIONS)
def _tree_rows(q, qd, bshift, L, W):
    """Each node's parent-joint rows: J (on the node), P (on the parent), rb; equilibrated."""
    for i in range(L.node_kind.shape[0]):
        j = L.node_joint[i]
        if j < 0:
            continue
        k = _rows_of(j, q, qd, L, W)
        me, p, r0 = L.node_end[i], L.node_parent[i], L.node_rows[i]
        for r in range(k):
            norm = 0.0
            for col in range(14):
                norm += W.A[r, col] * W.A[r, col]
            norm = math.sqrt(norm) if norm > 0 else 1.0
            rhs = W.b[r] + (bshift[L.joint_row[j] + r] if bshift.shape[0] else 0.0)
            rhs += _reduce(W.A[r, 7 * me:7 * me + 7], i, q, L, W, W.J[r0 + r])
            if p >= 0:
                rhs += _reduce(W.A[r, 7 - 7 * me:14 - 7 * me], p, q, L, W, W.P[r0 + r])
            else:
                W.P[r0 + r, :] = 0.0
            for a in range(6):
                W.J[r0 + r, a] /= norm
                W.P[r0 + r, a] /= norm
            W.rb[r0 + r] = rhs / norm


@njit(**OPTIONS)
def _extra_rows(q, qd, gen, o, bshift, L, W):
    """Loop-joint rows and the generated rows, as segments and Ax entries; equilibrated."""
    W.seg7[:, :] = 0.0
    W.Ax[:, :] = 0.0
    W.xb[:] = 0.0
    for j in range(L.joint_k.shape[0]):
        x0 = L.joint_xrow[j]
        if x0 < 0:
            continue
        k = _rows_of(j, q, qd, L, W)
        for r in range(k):
            for e in range(2):
                place = L.joint_xseg[j, e]
                if place >= 0:
                    seg = L.xseg_ptr[x0 + r] + place
                    for a in range(7):
                        W.seg7[seg, a] = W.A[r, 7 * e + a]
            W.xb[x0 + r] = W.b[r]
    for e in range(L.gen_arow.shape[0]):
        if L.gen_aseg[e] >= 0:
            W.seg7[L.gen_aseg[e] // 7, L.gen_aseg[e] % 7] += gen[o + e]
        else:
            W.Ax[L.gen_arow[e], L.gen_acol[e]] += gen[o + e]
    o += L.gen_arow.shape[0]
    for e in range(L.gen_brow.shape[0]):
        W.xb[L.gen_brow[e]] += gen[o + e]
    for x in range(L.xrow_row.shape[0]):
        norm = 0.0
        for seg in range(L.xseg_ptr[x], L.xseg_ptr[x + 1]):
            for a in range(7):
                norm += W.seg7[seg, a] * W.seg7[seg, a]
        for c in range(W.Ax.shape[1]):
            norm += W.Ax[x, c] * W.Ax[x, c]
        norm = math.sqrt(norm) if norm > 0 else 1.0
        rhs = W.xb[x] + (bshift[L.xrow_row[x]] if bshift.shape[0] else 0.0)
        for seg in range(L.xseg_ptr[x], L.xseg_ptr[x + 1]):
            rhs += _reduce(W.seg7[seg], L.xseg_node[seg], q, L, W, W.seg6[seg])
            for a in range(6):
                W.seg6[seg, a] /= norm
        for c in range(W.Ax.shape[1]):
            W.Ax[x, c] /= norm
        W.xb[x] = rhs / norm


@njit(**OPTIONS)
def assemble(t, q, qd, gen, bshift, L, W):
    """Fill W at the state (t, q, q̇); gen: the generated function's outputs; bshift: added
    to b per row of the System (empty for none). Returns μ."""
    W.Qf[:] = 0.0
    W.Cf[:] = 0.0
    o = 0
    for e in range(L.gen_q.shape[0]):
        W.Qf[L.gen_q[e]] += gen[o + e]
    o += L.gen_q.shape[0]
    for e in range(L.gen_c.shape[0]):
        W.Cf[L.gen_c[e]] += gen[o + e]
    o += L.gen_c.shape[0]
    W.Mx[:, :] = 0.0
    for e in range(L.gen_mi.shape[0]):
        W.Mx[L.gen_mi[e], L.gen_mj[e]] += gen[o + e]
    o += L.gen_mi.shape[0]
    mu = _nodes(q, qd, bshift, L, W)
    for x in range(L.x_coord.shape[0]):
        W.Fx[x] = W.Qf[L.x_coord[x]] + W.Cf[L.x_coord[x]]
        for c in range(L.x_coord.shape[0]):
            mu = max(mu, abs(W.Mx[x, c]))
    mu = mu if mu > 0 else 1.0
    W.H[:, :, :] /= mu
    W.F[:, :] /= mu
    W.Mx[:, :] /= mu
    W.Fx[:] /= mu
    _tree_rows(q, qd, bshift, L, W)
    _extra_rows(q, qd, gen, o, bshift, L, W)
    for i in range(L.node_kind.shape[0]):
        y0, v = L.node_yoff[i], L.node_v[i]
        for a in range(v):
            W.ry[y0 + a] = W.F[i, a]
        for r in range(L.node_k[i]):
            W.ry[y0 + v + r] = W.rb[L.node_rows[i] + r]
    return mu
