"""Linear-time block elimination of a tree-structured KKT system (Baraff 1996).

Each node i (a body) owns a block of unknowns: its v_i accelerations (6 for a rigid body
after bodies.py's change of variables, 3 for a particle) followed by the k_i multipliers
of the joint that hangs it from its parent. Only those joint rows touch the parent, so
the KKT matrix is a tree of blocks

    D_i = [[H_i, J_iᵀ], [J_i, 0]]          J_i: the joint's rows on node i (k_i × v_i)
    K_pi = [[0, P_iᵀ], [0, 0]]             P_i: the same rows on the parent (k_i × v_p)

and eliminating from the leaves to the roots causes no fill-in:

    D_p ← D_p − K_pi D_i⁻¹ K_ip,  i.e.  H_p ← H_p − P_iᵀ (D_i⁻¹)_λλ P_i.

A block alone may be singular (a massless body, a rank-3 inertia); with its joint rows and
its children's contributions it is invertible exactly when its subtree is determinate.
``factor`` inverts each eliminated block by Gauss–Jordan with partial pivoting and
reports a pivot below ``PIVOT_RTOL`` of the block's largest entry as singular: the caller
then hands the problem to the exact treatment.
"""

from numba import njit

from .bodies import OPTIONS

PIVOT_RTOL = 1e-9  # a pivot below this fraction of the block's largest entry counts as zero


@njit(**OPTIONS)
def invert(D, d, perm):
    """D[:d, :d] ← its inverse, in place (Gauss–Jordan, row pivoting). False when a pivot is
    below PIVOT_RTOL · max |D|."""
    scale = 0.0
    for i in range(d):
        for j in range(d):
            scale = max(scale, abs(D[i, j]))
    for k in range(d):
        p, best = k, abs(D[k, k])
        for i in range(k + 1, d):
            if abs(D[i, k]) > best:
                p, best = i, abs(D[i, k])
        if not best > PIVOT_RTOL * scale:
            return False
        perm[k] = p
        if p != k:
            for j in range(d):
                D[k, j], D[p, j] = D[p, j], D[k, j]
        pivot = 1.0 / D[k, k]
        D[k, k] = 1.0
        for j in range(d):
            D[k, j] *= pivot
        for i in range(d):
            if i != k:
                f = D[i, k]
                if f != 0.0:
                    D[i, k] = 0.0
                    for j in range(d):
                        D[i, j] -= f * D[k, j]
    for k in range(d - 1, -1, -1):
        p = perm[k]
        if p != k:
            for i in range(d):
                D[i, k], D[i, p] = D[i, p], D[i, k]
    return True


@njit(**OPTIONS)
def factor(topology, H, J, P, Dinv, acc, perm):
    """Eliminate leaves to roots; Dinv (flat) receives each block's inverse at doff[i].

    topology: (order, parent, v, k, doff, yoff, rows) of the nodes (layout.Layout); H:
    (N, 6, 6) node masses; J, P: (rows, 6) each node's joint rows on itself / on its
    parent, node i's starting at rows[i]; acc: (N, 6, 6) work for the children's
    contributions. Returns the first node whose block is singular, or −1."""
    order, parent, v, k, doff, _, rows = topology
    for idx in range(order.shape[0]):
        acc[order[idx]] = 0.0
    for idx in range(order.shape[0] - 1, -1, -1):
        i = order[idx]
        vi, ki = v[i], k[i]
        d = vi + ki
        D = Dinv[doff[i]:doff[i] + d * d].reshape((d, d))
        r0 = rows[i]
        for a in range(vi):
            for c in range(vi):
                D[a, c] = H[i, a, c] + acc[i, a, c]
            for r in range(ki):
                D[a, vi + r] = J[r0 + r, a]
                D[vi + r, a] = J[r0 + r, a]
        for r in range(ki):
            for c in range(ki):
                D[vi + r, vi + c] = 0.0
        if not invert(D, d, perm):
            return i
        p = parent[i]
        if p >= 0:  # acc_p −= Pᵀ (D⁻¹)_λλ P
            vp = v[p]
            for r in range(ki):
                for c in range(vp):
                    t = 0.0
                    for s in range(ki):
                        t += D[vi + r, vi + s] * P[r0 + s, c]
                    for a in range(vp):
                        acc[p, a, c] -= P[r0 + r, a] * t
    return -1


@njit(**OPTIONS)
def solve(topology, P, Dinv, y, x):
    """x = K⁻¹ y for the factored tree (y is overwritten)."""
    order, parent, v, k, doff, yoff, rows = topology
    n = order.shape[0]
    for idx in range(n - 1, -1, -1):  # leaves to roots: x_i = D_i⁻¹ y_i, passed up through P
        i = order[idx]
        vi, ki = v[i], k[i]
        d = vi + ki
        D = Dinv[doff[i]:doff[i] + d * d].reshape((d, d))
        o = yoff[i]
        for a in range(d):
            t = 0.0
            for c in range(d):
                t += D[a, c] * y[o + c]
            x[o + a] = t
        p = parent[i]
        if p >= 0:
            op, r0 = yoff[p], rows[i]
            for r in range(ki):
                lam = x[o + vi + r]
                for c in range(v[p]):
                    y[op + c] -= P[r0 + r, c] * lam
    for idx in range(n):  # roots to leaves: x_i −= D_i⁻¹[:, λ] P x_p
        i = order[idx]
        p = parent[i]
        if p < 0:
            continue
        vi, ki = v[i], k[i]
        d = vi + ki
        D = Dinv[doff[i]:doff[i] + d * d].reshape((d, d))
        o, op, r0 = yoff[i], yoff[p], rows[i]
        for r in range(ki):
            w = 0.0
            for c in range(v[p]):
                w += P[r0 + r, c] * x[op + c]
            if w != 0.0:
                for a in range(d):
                    x[o + a] -= D[a, vi + r] * w
