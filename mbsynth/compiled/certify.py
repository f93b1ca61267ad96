"""Whether an integrator's stage of a model with extra coordinates may keep the kernel's plain
answer: the rows certainly have no nearly dependent direction by the drift rule of
core/equations.py, judged on the very matrix that rule judges.

Off the constraint manifold the exact treatment replaces the rows by their trusted part
only where the equilibrated A_e (every row of A over q̈, divided by its 2-norm) has a
singular value σ_i below NEAR_SINGULAR σ₁; elsewhere it keeps every row and its answer is
the plain solution of (2.12), which the kernel gives. ``rows_certified`` builds A_e
densely — the tree joints' rows over q (joints.py), the extra rows (their coefficients
on the nodes' coordinates and on the extra coordinates) and each rigid body's unit-norm row
u/|u| — and takes the eigenvalues σ_i² of A_e A_eᵀ, where a Cholesky factor of A_e A_eᵀ
less NEAR_SINGULAR² m (its trace m bounds σ₁²) does not already certify them. This judges
the rows alone, in the coordinates the exact rule uses, so it holds for any mass matrix: a flexible part's
M, whose condition number (10⁶ and more: a strip's torsional inertia beside its bending
inertia) says nothing about its rows, is not in it.
"""

import math

import numpy as np
from numba import njit

from .assembly import _joint
from .bodies import OPTIONS
from .eigen import symmetric_eigen
from .joints import PARTICLE, RIGID, WORLD
from ..core.tolerances import NEAR_SINGULAR

ROWS_MAX = 64  # rows A_e is formed densely for (m² n products, an m × m eigensolve): beyond, the exact path judges


@njit(**OPTIONS)
def _width(kind):
    """A node's coordinates that a row segment covers: 7 for a rigid body (r, u), 3 for a particle."""
    return 7 if kind == RIGID else 3


@njit(**OPTIONS)
def rows_certified(q, qd, kind, start, node_joint, joints, scratch, quat_row, xseg_ptr, xseg_node, seg7, xscale,
                   Ax, x_coord):
    """σ_min(A_e) ≥ NEAR_SINGULAR σ₁(A_e) for the rows of one state (module docstring);
    False also where there are more than ROWS_MAX rows. ``joints``, ``scratch``: as
    assembly.tree_rows reads them; seg7, xscale, Ax: assembly.extra_rows' outputs."""
    count_joint = joints[1]
    kinds, starts = joints[2], joints[3]
    m = 0
    for i in range(kind.shape[0]):
        if node_joint[i] >= 0:
            m += count_joint[node_joint[i]]
        if kind[i] == RIGID and quat_row[i] >= 0:
            m += 1
    m += xscale.shape[0]
    if m == 0:
        return True
    if m > ROWS_MAX:
        return False
    A = np.zeros((m, q.shape[0]))
    row = 0
    for i in range(kind.shape[0]):
        j = node_joint[i]
        if j >= 0:
            k = _joint(j, q, qd, joints, scratch)
            rows = scratch[3]
            for r in range(k):
                for e in range(2):
                    if kinds[j, e] == WORLD:
                        continue
                    for a in range(3 if kinds[j, e] == PARTICLE else 7):
                        A[row, starts[j, e] + a] += rows[r, 7 * e + a]
                row += 1
        if kind[i] == RIGID and quat_row[i] >= 0:
            for a in range(4):
                A[row, start[i] + 3 + a] = q[start[i] + 3 + a]
            row += 1
    for x in range(xscale.shape[0]):
        for seg in range(xseg_ptr[x], xseg_ptr[x + 1]):
            i = xseg_node[seg]
            for a in range(_width(kind[i])):
                A[row, start[i] + a] += xscale[x] * seg7[seg, a]
        for c in range(x_coord.shape[0]):
            A[row, x_coord[c]] += Ax[x, c]
        row += 1
    for r in range(m):
        total = 0.0
        for c in range(A.shape[1]):
            total += A[r, c] * A[r, c]
        if not total > 0.0:
            return False  # a zero row: the exact rule's rank cut decides
        scale = 1.0 / math.sqrt(total)
        for c in range(A.shape[1]):
            A[r, c] *= scale
    T = np.zeros((m, m))
    for r in range(m):
        for s in range(r + 1):
            total = 0.0
            for c in range(A.shape[1]):
                total += A[r, c] * A[s, c]
            T[r, s] = total
            T[s, r] = total
    if _above(T, NEAR_SINGULAR ** 2 * m):
        return True  # λ_min ≥ NEAR_SINGULAR² m ≥ NEAR_SINGULAR² λ_max: the rows have unit norms, trace(T) = m
    V, values = np.zeros((m, m)), np.zeros(m)
    symmetric_eigen(T, V, values)
    least, top = np.inf, 0.0
    for e in range(m):
        least, top = min(least, values[e]), max(top, values[e])
    return top > 0.0 and least >= NEAR_SINGULAR ** 2 * top


@njit(**OPTIONS)
def _above(T, floor):
    """Whether T − floor·I is positive definite (its Cholesky factor found, T left as it
    was): λ_min(T) > floor, decided by a Cholesky rather than an eigensolve."""
    m = T.shape[0]
    L = np.zeros((m, m))
    for r in range(m):
        for c in range(r + 1):
            total = T[r, c] - (floor if r == c else 0.0)
            for k in range(c):
                total -= L[r, k] * L[c, k]
            if r == c:
                if not total > 0.0:
                    return False
                L[r, r] = math.sqrt(total)
            else:
                L[r, c] = total / L[c, c]
    return True
