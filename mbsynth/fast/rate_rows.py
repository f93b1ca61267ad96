"""The rows of a joint between rigid bodies (or a body and the world) written directly in
the bodies' unknowns (r̈, α) (assembly.world_rates), without joints.py's 14 columns.

Per body, three matrices serve every frame vector c of the body (nodes in assembly.py):
R = R(u), Ṙ = d/dt R(u) and Rb = 2R(u̇) + (2s/ν) R, so that e = R c has

    ė = Ṙ c,      ë = α × e + Rb c.

A frame origin p = r + R s has p̈ = r̈ + α × ρ + Rb s (ρ = R s). With the rows of
joints.PROGRAMS, each row's coefficients on (r̈_A, α_A, r̈_B, α_B) follow from
(α × x)·w = α·(x × w):

    component k of d    e_k on r̈_B, ρ_B × e_k on α_B; the negatives on end A
    dot x·w             x × w on the α of x's body (w × x on w's), and for x = d:
                        w on r̈_B, ρ_B × w on α_B, the negatives on end A
    distance            as dot d·d, divided by 2L

and b = −(the bias terms + 2 ẋ·ẇ) as in joints.py.
"""

from numba import njit

from .bodies import INLINE
from .joints import COMPONENT, DOT, WORLD

D, ORIGIN_A, ORIGIN_B = 0, 7, 8  # records of ``vectors``: d, the axes (1 + 3e + a), the origins
VALUE, VELOCITY, BIAS = 0, 1, 2


@njit(**INLINE)
def _vector(Rs, node, s, Rf, e, col, V, rec):
    """V[rec] ← (value, velocity, bias) of c = s[e] (col < 0) or Rf[e, :, col] on the body."""
    if col < 0:
        c0, c1, c2 = s[e, 0], s[e, 1], s[e, 2]
    else:
        c0, c1, c2 = Rf[e, 0, col], Rf[e, 1, col], Rf[e, 2, col]
    for m in range(3):
        M = Rs[node, m]
        for a in range(3):
            V[rec, a, m] = M[a, 0] * c0 + M[a, 1] * c1 + M[a, 2] * c2


@njit(**INLINE)
def _end(e, kind, node, s, Rf, q, qd, start, Rs, V, rho, used):
    """The origin and the axes of end e that the rows use (bit 1 + 3e + x of ``used``) into
    V (value, velocity, bias), and its offset ρ."""
    origin = ORIGIN_A + e
    if kind == WORLD:
        for a in range(3):
            V[origin, a, VALUE] = s[e, a]
            V[origin, a, VELOCITY] = V[origin, a, BIAS] = rho[e, a] = 0.0
            for x in range(3):
                V[1 + 3 * e + x, a, VALUE] = Rf[e, a, x]
                V[1 + 3 * e + x, a, VELOCITY] = V[1 + 3 * e + x, a, BIAS] = 0.0
        return
    _vector(Rs, node, s, Rf, e, -1, V, origin)
    for a in range(3):
        rho[e, a] = V[origin, a, VALUE]
        V[origin, a, VALUE] += q[start + a]
        V[origin, a, VELOCITY] += qd[start + a]
    for x in range(3):
        if used >> (1 + 3 * e + x) & 1:
            _vector(Rs, node, s, Rf, e, x, V, 1 + 3 * e + x)


@njit(**INLINE)
def _cross_add(V, x, w0, w1, w2, sign, A, r, o):
    """A[r, o:o + 3] += sign · (value of record x) × w."""
    x0, x1, x2 = V[x, 0, VALUE], V[x, 1, VALUE], V[x, 2, VALUE]
    A[r, o] += sign * (x1 * w2 - x2 * w1)
    A[r, o + 1] += sign * (x2 * w0 - x0 * w2)
    A[r, o + 2] += sign * (x0 * w1 - x1 * w0)


@njit(**INLINE)
def _along(x, w, kinds, V, rho, A, r):
    """A[r] += the coefficients of ẍ·w (x, w: records of V)."""
    w0, w1, w2 = V[w, 0, VALUE], V[w, 1, VALUE], V[w, 2, VALUE]
    if x == D:
        for e in range(2):
            if kinds[e] != WORLD:
                sign = 1.0 if e == 1 else -1.0
                A[r, 6 * e] += sign * w0
                A[r, 6 * e + 1] += sign * w1
                A[r, 6 * e + 2] += sign * w2
                r0, r1, r2 = rho[e, 0], rho[e, 1], rho[e, 2]
                A[r, 6 * e + 3] += sign * (r1 * w2 - r2 * w1)
                A[r, 6 * e + 4] += sign * (r2 * w0 - r0 * w2)
                A[r, 6 * e + 5] += sign * (r0 * w1 - r1 * w0)
    else:
        e = 0 if x <= 3 else 1  # records 1–3: end A's axes, 4–6: end B's
        if kinds[e] != WORLD:
            _cross_add(V, x, w0, w1, w2, 1.0, A, r, 6 * e + 3)


@njit(**INLINE)
def rate_rows(program, k, kinds, nodes, starts, s, Rf, length, q, qd, Rs, V, rho, A, b):
    """Rows A[:k, :12] on (r̈_A, α_A, r̈_B, α_B) and b[:k] of one joint whose ends are rigid
    bodies (nodes) or the world. s, Rf, length: as joints.joint_rows; Rs: the bodies'
    matrices (module docstring); V, rho: work."""
    used = 0
    for r in range(k):
        if program[r, 0] == DOT:
            used |= (1 << program[r, 1]) | (1 << program[r, 2])
    for e in range(2):
        _end(e, kinds[e], nodes[e], s, Rf, q, qd, starts[e], Rs, V, rho, used)
    for a in range(3):
        for col in range(3):
            V[D, a, col] = V[ORIGIN_B, a, col] - V[ORIGIN_A, a, col]
    for r in range(k):
        op, x, w = program[r, 0], program[r, 1], program[r, 2]
        for col in range(12):
            A[r, col] = 0.0
        if op == COMPONENT:  # d_w: e_w on r̈_B, ρ_B × e_w on α_B, the negatives on A
            w1, w2 = (w + 1 if w < 2 else 0), (w + 2 if w < 1 else w - 1)  # (w + 1, w + 2) mod 3
            for e in range(2):
                if kinds[e] != WORLD:
                    sign = 1.0 if e == 1 else -1.0
                    A[r, 6 * e + w] = sign
                    A[r, 6 * e + 3 + w1] = sign * rho[e, w2]
                    A[r, 6 * e + 3 + w2] = -sign * rho[e, w1]
            b[r] = -V[D, w, BIAS]
            continue
        if op == DOT:
            _along(x, w, kinds, V, rho, A, r)
            _along(w, x, kinds, V, rho, A, r)
            scale = 1.0
        else:  # distance: (d·d − L²)/2L
            _along(D, D, kinds, V, rho, A, r)
            scale = 1.0 / length
            w = x
        total = 0.0
        for a in range(3):
            total += (V[x, a, BIAS] * V[w, a, VALUE] + V[x, a, VALUE] * V[w, a, BIAS]
                      + 2 * V[x, a, VELOCITY] * V[w, a, VELOCITY])
        b[r] = -total * scale * (0.5 if op != DOT else 1.0)
        if op != DOT:
            for col in range(12):
                A[r, col] *= scale
