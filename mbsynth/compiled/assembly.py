"""One state's blocks for the tree solver, in numba: bodies (bodies.py), joint rows
(joints.py) and the generated function's outputs (codegen.py), laid out by layout.py.

In the order kernel.motion calls them, the functions below fill a Work with: the
generated Q, C and extra M (``generated``); each node's mass H and force F in its reduced
unknowns (``nodes``, bodies.py); the masses and forces divided by μ, the largest mass
entry (``divide_masses``); each node's parent-joint rows on itself (J) and on its parent
(P) with their right sides (``tree_rows``); the extra rows as segments of 6 reduced
coefficients per node plus their entries on the extra coordinates, Ax (``extra_rows``);
the tree's right side (``tree_rhs``). Every row of A and b is divided by the 2-norm of
its row of A — with μ, the equilibration of equations.py, so that pivots and tolerances
compare like with like.
"""

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from .bodies import INLINE, OPTIONS, body_force, rate, reduce_row, rotation, rotation_rate
from ..core.joint_kinds import MAX_ROWS
from .joints import PARTICLE, RIGID, joint_rows, vector_work
from .rate_rows import equilibrated_rows
from .tree import GENERAL, RIGID_INVARIANT


class Work(NamedTuple):
    """Buffers of one evaluation (sizes from a Layout; see ``make_work``)."""

    Qf: np.ndarray     # (n,) Q: bodies' own and the generated additions
    Cf: np.ndarray     # (n,) C
    H: np.ndarray      # (N, 6, 6) node masses / μ
    F: np.ndarray      # (N, 6) node forces / μ
    s: np.ndarray      # (N,) quaternion norm accelerations (bodies.py)
    Rs: np.ndarray     # (N + 1, 4, 3, 3) per body R(u), d/dt R(u), Rb and B (nodes; rate_rows.py), then the world's (I, 0, 0, 0)
    zeta: np.ndarray   # (N, 3) each node's rigid transport (transports)
    nu: np.ndarray     # (N,) quaternion lengths
    HA: np.ndarray     # (N, 6, 6) articulated masses (tree.factor)
    Sn: np.ndarray     # (N, 6, 6) null-space bases of the parent-joint rows
    Jr: np.ndarray     # (N, 6, 6) right inverses of those rows
    X: np.ndarray      # (N, 6, 6) X = −Jr P
    U: np.ndarray      # (N, 6, 6) H^A S
    Ninv: np.ndarray   # (N, 6, 6) (Sᵀ H^A S)⁻¹
    c: np.ndarray      # (N, 12) tree.solve work
    x0: np.ndarray     # (N, 6) tree.solve work
    G: np.ndarray      # (12, 12) tree.factor work
    pivot: np.ndarray  # (12,) tree.factor's pivots
    J: np.ndarray      # (tree rows, 6) parent-joint rows on the node
    P: np.ndarray      # (tree rows, 6) the same rows on the parent
    rb: np.ndarray     # (tree rows,) their right sides
    rscale: np.ndarray  # (tree rows,) the factors that equilibrated them (1 / the row's 2-norm)
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
    xscale: np.ndarray  # (m_x,) the factors that equilibrated them (1 / the row's 2-norm)
    Ax: np.ndarray     # (m_x, n_x) extra rows on extra coordinates
    Mx: np.ndarray     # (n_x, n_x) extra coordinates' M / μ
    Fx: np.ndarray     # (n_x,) their F / μ
    S: np.ndarray      # (n_x + m_x,)² Schur complement (kernel.py)
    rhs: np.ndarray    # (n_x + m_x,)
    lam: np.ndarray    # (n_x + m_x,) extra accelerations, then extra multipliers
    vectors: np.ndarray  # (n_x + m_x,)² eigenvectors of S
    values: np.ndarray  # (n_x + m_x,) its eigenvalues
    band: np.ndarray   # (2, m_x, w + 1) the banded Schur matrix and A_x A_xᵀ, then their Cholesky factors (banded.py); empty: dense S
    bandv: np.ndarray  # (2, m_x) work of banded.py
    dyn: np.ndarray    # (N, 6) residual work
    qdd: np.ndarray    # (n,) result: q̈
    Qc: np.ndarray     # (n,) result: M q̈ − Q (2.5)


def make_work(L):
    """A Work for the Layout L (numpy; one per thread)."""
    n, nz, rows = (int(x) for x in L.sizes[[0, 2, 3]])
    N, S = L.node_kind.shape[0], L.xseg_node.shape[0]
    mx, nx = L.xrow_row.shape[0], L.x_coord.shape[0]
    p = nx + mx
    width = int(L.band_width[0]) if L.band_width.size else -1
    dense, banded = (0 if width >= 0 else p), (mx if width >= 0 else 0)  # S is dense or banded
    shapes = dict(Qf=n, Cf=n, H=(N, 6, 6), F=(N, 6), s=N, nu=N, Rs=(N + 1, 4, 3, 3), zeta=(N, 3), HA=(N, 6, 6), Sn=(N, 6, 6), Jr=(N, 6, 6), X=(N, 6, 6), U=(N, 6, 6),
                  Ninv=(N, 6, 6), c=(N, 12), x0=(N, 6), G=(12, 12), J=(rows, 6), P=(rows, 6), rb=rows, rscale=rows, ry=nz, y=nz, z=nz, z0=nz, w=nz, A=(MAX_ROWS, 14), b=MAX_ROWS, q7=7, seg7=(S, 7), seg6=(S, 6), xb=mx, xscale=mx, Ax=(mx, nx), Mx=(nx, nx), Fx=nx, S=(dense, dense),
                  rhs=p, lam=p, vectors=(dense, dense), values=dense, band=(2, banded, width + 1), bandv=(2, banded), dyn=(N, 6), qdd=n, Qc=n)
    arrays = {name: np.zeros(shape) for name, shape in shapes.items()}
    arrays["Rs"][N, 0] = np.eye(3)  # the world, as a body at rest in its own frame (rate_rows.py)
    V, R, Jt = vector_work()
    return Work(pivot=np.zeros(12, np.int64), V=V, R=R, Jt=Jt, **arrays)


@njit(**OPTIONS)
def _joint(j, q, qd, joints, scratch):
    """Rows of kernel joint j into scratch's A, b; returns their number."""
    program, k, kinds, start, offset, rotation, length, _ = joints
    V, R, Jt, A, b = scratch
    joint_rows(program[j], k[j], kinds[j], start[j], offset[j], rotation[j], length[j], q, qd, V, R, Jt, A, b)
    return k[j]


@njit(**INLINE)
def _turn(B, x, o):
    """x[o:o + 3] ← B x[o:o + 3]: a row's coefficients on a from those on α (a = Bᵀα)."""
    a, b, c = x[o], x[o + 1], x[o + 2]
    for r in range(3):
        x[o + r] = B[r, 0] * a + B[r, 1] * b + B[r, 2] * c


@njit(**OPTIONS)
def _reduce(c7, rigid, q, o, nu, s, B, out):
    """A row segment on a node in its reduced unknowns (r̈, α); returns the right-side shift."""
    if rigid:
        shift = reduce_row(c7, q[o + 3:o + 7], nu, s, out)
        _turn(B, out, 3)
        return shift
    for a in range(3):
        out[a] = c7[a]
        out[3 + a] = 0.0
    return 0.0


@njit(**OPTIONS)
def nodes(q, qd, bshift, kind, start, mass, mg, inertia, quat_row, Qf, Cf, H, F, s, nu, q7, Rs):
    """Masses, forces and quaternion norm accelerations of the nodes, a rigid body's in
    (r̈, α) (module docstring of bodies.py): H_αα = R J Rᵀ, F_α = B F_a with B = R/(2ν);
    and per body Rs = (R(u), d/dt R(u), Rb = 2R(u̇) + (2s/ν) R, B). Returns μ."""
    mu = 0.0
    for i in range(kind.shape[0]):
        c, m = start[i], mass[i]
        H[i, :, :] = 0.0
        for a in range(3):
            H[i, a, a] = m
        mu = max(mu, abs(m))
        if kind[i] != RIGID:
            for a in range(3):
                Qf[c + a] += mg[i, a]
                F[i, a] = Qf[c + a] + Cf[c + a]
            continue
        u, ud = q[c + 3:c + 7], qd[c + 3:c + 7]
        length = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + u[3] * u[3])
        nu[i] = length
        shift = bshift[quat_row[i]] if bshift.shape[0] else 0.0
        s[i] = (shift - (ud[0] * ud[0] + ud[1] * ud[1] + ud[2] * ud[2] + ud[3] * ud[3])) / length
        body_force(mg[i], inertia[i], u, ud, q7)
        for a in range(7):
            Qf[c + a] += q7[a]
        e = rate(u, (Qf[c + 3] + Cf[c + 3], Qf[c + 4] + Cf[c + 4], Qf[c + 5] + Cf[c + 5], Qf[c + 6] + Cf[c + 6]))
        R, Rb, B = Rs[i, 0], Rs[i, 2], Rs[i, 3]
        rotation(u, R)
        rotation_rate(u, ud, Rs[i, 1])
        rotation(ud, Rb)
        for a in range(3):
            for b in range(3):
                Rb[a, b] = 2 * Rb[a, b] + 2 * s[i] / length * R[a, b]
                B[a, b] = R[a, b] / (2 * length)
        Ji, RJ = inertia[i], H[i, 0:3, 3:6]  # R J into H's upper right block (work, zeroed after)
        for a in range(3):
            F[i, a] = Qf[c + a] + Cf[c + a]
            F[i, 3 + a] = (B[a, 0] * e[0] + B[a, 1] * e[1] + B[a, 2] * e[2]) / length
            for b in range(3):
                RJ[a, b] = R[a, 0] * Ji[0, b] + R[a, 1] * Ji[1, b] + R[a, 2] * Ji[2, b]
        for a in range(3):  # (R J Rᵀ)[a, b], symmetric
            for b in range(a + 1):
                t = RJ[a, 0] * R[b, 0] + RJ[a, 1] * R[b, 1] + RJ[a, 2] * R[b, 2]
                H[i, 3 + a, 3 + b] = H[i, 3 + b, 3 + a] = t
                mu = max(mu, abs(t))
        for a in range(3):
            for b in range(3):
                RJ[a, b] = 0.0
    return mu


@njit(**INLINE)
def _normalize(row, count):
    """1 / the 2-norm of row[:count] (1 for a zero row)."""
    total = 0.0
    for a in range(count):
        total += row[a] * row[a]
    return 1.0 / math.sqrt(total) if total > 0 else 1.0


@njit(**OPTIONS)
def tree_rows(q, qd, bshift, kind, start, node_joint, node_end, parent, rows, nu, s, Rs, joints, joint_row, scratch,
              J, P, rb, rscale, general):
    """Each node's parent-joint rows: J (on the node), P (on the parent), rb; equilibrated
    (the factors in rscale).
    Joints between rigid bodies or the world: rate_rows.py; others: joints.py, reduced
    (``general`` None: there are none, and numba compiles without them)."""
    program, count, kinds, starts, offset, frame, length, ends = joints
    A, b = scratch[3], scratch[4]
    for i in range(kind.shape[0]):
        j = node_joint[i]
        if j < 0:
            continue
        me, p, r0 = node_end[i], parent[i], rows[i]
        if general is None or (kinds[j, 0] != PARTICLE and kinds[j, 1] != PARTICLE):
            equilibrated_rows(program[j], count[j], kinds[j], ends[j], starts[j], offset[j], frame[j], length[j], q,
                              qd, Rs, me, bshift, joint_row[j], J, P, rb, rscale, r0)
            continue
        k = _joint(j, q, qd, joints, scratch)
        for r in range(k):
            scale = _normalize(A[r], 14)
            rhs = b[r] + (bshift[joint_row[j] + r] if bshift.shape[0] else 0.0)
            rhs += _reduce(A[r, 7 * me:7 * me + 7], kind[i] == RIGID, q, start[i], nu[i], s[i], Rs[i, 3], J[r0 + r])
            if p >= 0:
                rhs += _reduce(A[r, 7 - 7 * me:14 - 7 * me], kind[p] == RIGID, q, start[p], nu[p], s[p], Rs[p, 3],
                               P[r0 + r])
            else:
                P[r0 + r, :] = 0.0
            for a in range(6):
                J[r0 + r, a] *= scale
                P[r0 + r, a] *= scale
            rb[r0 + r], rscale[r0 + r] = rhs * scale, scale


@njit(**OPTIONS)
def extra_rows(q, qd, gen, bshift, kind, start, nu, s, Rs, joints, joint_xrow, joint_xseg, xrow_row, xseg_ptr,
                xseg_node, gen_rows, xa_ptr, xa_col, scratch, seg7, seg6, xb, xscale, Ax):
    """Loop-joint rows and the generated rows (gen: their entries, then their b), as
    segments and Ax entries; equilibrated (each row's factor into xscale). Only the entries of Ax's pattern (xa_ptr,
    xa_col: layout.py) are written; the others stay zero."""
    arow, aseg, acol, brow = gen_rows
    A, b = scratch[3], scratch[4]
    seg7[:, :] = 0.0
    for e in range(arow.shape[0]):
        if aseg[e] < 0:
            Ax[arow[e], acol[e]] = 0.0
    xb[:] = 0.0
    for j in range(joint_xrow.shape[0]):
        x0 = joint_xrow[j]
        if x0 < 0:
            continue
        k = _joint(j, q, qd, joints, scratch)
        for r in range(k):
            for e in range(2):
                if joint_xseg[j, e] >= 0:
                    seg = xseg_ptr[x0 + r] + joint_xseg[j, e]
                    for a in range(7):
                        seg7[seg, a] = A[r, 7 * e + a]
            xb[x0 + r] = b[r]
    for e in range(arow.shape[0]):
        if aseg[e] >= 0:
            seg7[aseg[e] // 7, aseg[e] % 7] += gen[e]
        else:
            Ax[arow[e], acol[e]] += gen[e]
    for e in range(brow.shape[0]):
        xb[brow[e]] += gen[arow.shape[0] + e]
    for x in range(xrow_row.shape[0]):
        total = 0.0
        for seg in range(xseg_ptr[x], xseg_ptr[x + 1]):
            for a in range(7):
                total += seg7[seg, a] * seg7[seg, a]
        for e in range(xa_ptr[x], xa_ptr[x + 1]):
            total += Ax[x, xa_col[e]] ** 2
        scale = 1.0 / math.sqrt(total) if total > 0 else 1.0
        xscale[x] = scale
        rhs = xb[x] + (bshift[xrow_row[x]] if bshift.shape[0] else 0.0)
        for seg in range(xseg_ptr[x], xseg_ptr[x + 1]):
            i = xseg_node[seg]
            rhs += _reduce(seg7[seg], kind[i] == RIGID, q, start[i], nu[i], s[i], Rs[i, 3], seg6[seg])
            for a in range(6):
                seg6[seg, a] *= scale
        for e in range(xa_ptr[x], xa_ptr[x + 1]):
            Ax[x, xa_col[e]] *= scale
        xb[x] = rhs * scale


@njit(**OPTIONS)
def generated(gen, gen_q, gen_c, gen_mi, gen_mj, Qf, Cf, Mx):
    """Q additions, C and the extra coordinates' M from the generated outputs; returns
    the offset of the row entries that follow. Only the entries of Mx's pattern (gen_mi,
    gen_mj: each pair once) are written; the others stay zero."""
    Qf[:] = 0.0
    Cf[:] = 0.0
    for e in range(gen_mi.shape[0]):
        Mx[gen_mi[e], gen_mj[e]] = 0.0
    o = 0
    for e in range(gen_q.shape[0]):
        Qf[gen_q[e]] += gen[o + e]
    o += gen_q.shape[0]
    for e in range(gen_c.shape[0]):
        Cf[gen_c[e]] += gen[o + e]
    o += gen_c.shape[0]
    for e in range(gen_mi.shape[0]):
        Mx[gen_mi[e], gen_mj[e]] += gen[o + e]
    return o + gen_mi.shape[0]


@njit(**OPTIONS)
def divide_masses(mu, H, F, Mx, Fx, gen_mi, gen_mj):
    """Divide the masses and forces by μ (of Mx, the entries of its pattern: ``generated``)."""
    inv = 1.0 / mu
    for i in range(H.shape[0]):
        for a in range(6):
            F[i, a] *= inv
            for b in range(6):
                H[i, a, b] *= inv
    for x in range(Fx.shape[0]):
        Fx[x] *= inv
    for e in range(gen_mi.shape[0]):
        Mx[gen_mi[e], gen_mj[e]] *= inv


@njit(**OPTIONS)
def transports(q, start, parent, node_joint, node_end, transport, joint_s, Rs, zeta):
    """ζ of each rigid node on a rigid parent: X = [[I, [ζ]×], [0, I]] maps the parent's
    (r̈, α) to the node's when the joint is locked, and J X = −P holds exactly for its rows
    (tree.py): ζ = r_p − r_i for rows invariant under rotation, ζ = R_i s_i − R_p s_p
    (the two frames' offsets) for rows that are world components of d."""
    for i in range(transport.shape[0]):
        p, j, e = parent[i], node_joint[i], node_end[i]
        if transport[i] == GENERAL or p < 0:
            continue
        if transport[i] == RIGID_INVARIANT:
            for a in range(3):
                zeta[i, a] = q[start[p] + a] - q[start[i] + a]
            continue
        si, sp, Ri, Rp = joint_s[j, e], joint_s[j, 1 - e], Rs[i, 0], Rs[p, 0]
        for a in range(3):
            zeta[i, a] = (Ri[a, 0] * si[0] + Ri[a, 1] * si[1] + Ri[a, 2] * si[2]
                          - Rp[a, 0] * sp[0] - Rp[a, 1] * sp[1] - Rp[a, 2] * sp[2])


@njit(**OPTIONS)
def tree_rhs(v, k, yoff, rows, F, rb, ry):
    for i in range(v.shape[0]):
        for a in range(v[i]):
            ry[yoff[i] + a] = F[i, a]
        for r in range(k[i]):
            ry[yoff[i] + v[i] + r] = rb[rows[i] + r]
