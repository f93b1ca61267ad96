"""The rows of a joint between rigid bodies (or a body and the world) written directly in
the bodies' unknowns (r̈, α) (assembly.world_rates), without joints.py's 14 columns.

Per body, three matrices serve every frame vector c of the body (nodes in assembly.py):
R = R(u), Ṙ = d/dt R(u) and Rb = 2R(u̇) + (2s/ν) R, so that e = R c has

    ė = Ṙ c,      ë = α × e + Rb c.

A frame origin p = r + R s has p̈ = r̈ + α × ρ + Rb s (ρ = R s). With the rows of
a kind's program (core/joint_kinds.py), each row's coefficients on (r̈_A, α_A, r̈_B, α_B) follow from
(α × x)·w = α·(x × w):

    component k of d    e_k on r̈_B, ρ_B × e_k on α_B; the negatives on end A
    dot x·w             x × w on the α of x's body (w × x on w's), and for x = d:
                        w on r̈_B, ρ_B × w on α_B, the negatives on end A
    distance            as dot d·d, divided by 2L

and b = −(the bias terms + 2 ẋ·ẇ) as in joints.py. A world end has no unknowns: its
coefficients are dropped.

``EVALUATED``: the operations ``_row`` has a branch for, all of core/joint_kinds.OPERATIONS
(checked at import). Each row is computed on its own, its vectors as 3-tuples (``_row``), so that they stay in
registers, not in a table of the joint's vectors filled first.
"""

import math

from numba import njit

from ..core.joint_kinds import COMPONENT, D, DISTANCE, DOT, check_operations
from .bodies import INLINE, cross3, dot3, times3
from .joints import WORLD

ZERO = (0.0, 0.0, 0.0)
EVALUATED = (COMPONENT, DOT, DISTANCE)  # _row's branches: a component; a dot of two axes or of d, and the distance
check_operations("compiled/rate_rows._row", EVALUATED)


@njit(**INLINE)
def _axpy(f, x, y):
    """f x + y."""
    return (f * x[0] + y[0], f * x[1] + y[1], f * x[2] + y[2])


@njit(**INLINE)
def _origin(kind, node, o, s, q, qd, Rs):
    """(ρ = R s, p = r + ρ, ṗ, the bias Rb s of p̈) of a frame origin at s on its end; the
    world's slot of Rs (I, 0, 0) and a factor 0 on its r make the world's (s, s, 0, 0)."""
    c, f = (s[0], s[1], s[2]), 0.0 if kind == WORLD else 1.0
    rho, vel = times3(Rs[node, 0], c), times3(Rs[node, 1], c)
    return (rho, (f * q[o] + rho[0], f * q[o + 1] + rho[1], f * q[o + 2] + rho[2]),
            (f * qd[o] + vel[0], f * qd[o + 1] + vel[1], f * qd[o + 2] + vel[2]), times3(Rs[node, 2], c))


@njit(**INLINE)
def _axis(x, nodes, Rf, Rs):
    """(value, velocity, bias) of axis x = 1 + 3e + col (a world end's: its slot of Rs)."""
    e = 0 if x <= 3 else 1
    col = x - 1 - 3 * e
    c, M = (Rf[e, 0, col], Rf[e, 1, col], Rf[e, 2, col]), Rs[nodes[e]]
    return times3(M[0], c), times3(M[1], c), times3(M[2], c)


@njit(**INLINE)
def _row(op, x, w, kinds, nodes, Rf, length, Rs, A, B):
    """One row: (coefficients on r̈_A, α_A, r̈_B, α_B; b), a world end's zero. A, B: the
    ends' origins. Each kind of row returns on its own and no branch picks tuples per
    end: numba then keeps the tuples in registers (with the kinds' tuples merged after
    the branches, or a branch on the world end, the rows took twice as long)."""
    fA, fB = 0.0 if kinds[0] == WORLD else 1.0, 0.0 if kinds[1] == WORLD else 1.0
    if op == COMPONENT:  # e_w on r̈_B, ρ_B × e_w on α_B, the negatives on A
        rhoA, rhoB = A[0], B[0]
        if w == 0:
            e, cA, cB, b = (1.0, 0.0, 0.0), (0.0, rhoA[2], -rhoA[1]), (0.0, rhoB[2], -rhoB[1]), A[3][0] - B[3][0]
        elif w == 1:
            e, cA, cB, b = (0.0, 1.0, 0.0), (-rhoA[2], 0.0, rhoA[0]), (-rhoB[2], 0.0, rhoB[0]), A[3][1] - B[3][1]
        else:
            e, cA, cB, b = (0.0, 0.0, 1.0), (rhoA[1], -rhoA[0], 0.0), (rhoB[1], -rhoB[0], 0.0), A[3][2] - B[3][2]
        return _axpy(-fA, e, ZERO), _axpy(-fA, cA, ZERO), _axpy(fB, e, ZERO), _axpy(fB, cB, ZERO), b
    if x != D:  # a dot of two axes: x × w on x's α, w × x on w's
        xv, xd, xb = _axis(x, nodes, Rf, Rs)
        wv, wd, wb = _axis(w, nodes, Rf, Rs)
        f = (1.0 if x <= 3 else 0.0) - (1.0 if w <= 3 else 0.0)  # on α_A; −f on α_B
        c = cross3(xv, wv)
        return ZERO, _axpy(fA * f, c, ZERO), ZERO, _axpy(-fB * f, c, ZERO), \
            -(dot3(xb, wv) + dot3(xv, wb) + 2 * dot3(xd, wd))
    # d·w for an axis w, or the distance: d·d scaled by 1/2L
    xv, xd, xb = _axpy(-1.0, A[1], B[1]), _axpy(-1.0, A[2], B[2]), _axpy(-1.0, A[3], B[3])
    distance = op != DOT
    wv, wd, wb = (xv, xd, xb) if distance else _axis(w, nodes, Rf, Rs)
    scale = 0.5 / length if distance else 1.0
    fd = 1.0 if distance else 0.0
    fa = 0.0 if distance or w > 3 else 1.0
    t = _axpy(fd, xv, wv)  # the coefficients of d̈·w and, for the distance, of ẅ·d = d̈·d
    c = cross3(wv, xv)
    aA = _axpy(fa * scale, c, _axpy(-scale, cross3(A[0], t), ZERO))
    aB = _axpy((1.0 - fd - fa) * scale, c, _axpy(scale, cross3(B[0], t), ZERO))
    return (_axpy(-fA * scale, t, ZERO), _axpy(fA, aA, ZERO), _axpy(fB * scale, t, ZERO), _axpy(fB, aB, ZERO),
            -scale * (dot3(xb, wv) + dot3(xv, wb) + 2 * dot3(xd, wd)))


@njit(**INLINE)
def rate_rows(program, k, kinds, nodes, starts, s, Rf, length, q, qd, Rs, A, b):
    """Rows A[:k, :12] on (r̈_A, α_A, r̈_B, α_B) and b[:k] of one joint whose ends are rigid
    bodies (nodes) or the world. s, Rf, length: as joints.joint_rows; Rs: the bodies'
    matrices (module docstring)."""
    A0 = _origin(kinds[0], nodes[0], starts[0], s[0], q, qd, Rs)
    B0 = _origin(kinds[1], nodes[1], starts[1], s[1], q, qd, Rs)
    for r in range(k):
        rA, aA, rB, aB, b[r] = _row(program[r, 0], program[r, 1], program[r, 2], kinds, nodes, Rf, length, Rs, A0, B0)
        for a in range(3):
            A[r, a], A[r, 3 + a], A[r, 6 + a], A[r, 9 + a] = rA[a], aA[a], rB[a], aB[a]


@njit(**INLINE)
def equilibrated_rows(program, k, kinds, nodes, starts, s, Rf, length, q, qd, Rs, me, bshift, brow, J, P, rb, rscale,
                      r0):
    """The rows of rate_rows divided by their 2-norms into J (on end ``me``) and P (on the
    other end) from row r0, their b + bshift[brow:] into rb (bshift empty: none), the
    factors into rscale."""
    A0 = _origin(kinds[0], nodes[0], starts[0], s[0], q, qd, Rs)
    B0 = _origin(kinds[1], nodes[1], starts[1], s[1], q, qd, Rs)
    for r in range(k):
        rA, aA, rB, aB, beta = _row(program[r, 0], program[r, 1], program[r, 2], kinds, nodes, Rf, length, Rs, A0, B0)
        total = dot3(rA, rA) + dot3(aA, aA) + dot3(rB, rB) + dot3(aB, aB)
        scale = 1.0 / math.sqrt(total) if total > 0 else 1.0
        mr, ma, orr, oa = (rA, aA, rB, aB) if me == 0 else (rB, aB, rA, aA)
        for a in range(3):
            J[r0 + r, a], J[r0 + r, 3 + a] = mr[a] * scale, ma[a] * scale
            P[r0 + r, a], P[r0 + r, 3 + a] = orr[a] * scale, oa[a] * scale
        rb[r0 + r], rscale[r0 + r] = (beta + (bshift[brow + r] if bshift.shape[0] else 0.0)) * scale, scale
