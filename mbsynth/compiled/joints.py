"""The rows of A and b of the holonomic joints (constraints/joints.py) over q̈, differentiated
by hand: used for joints with a particle end and for loop rows (rate_rows.py writes the
rows of joints between rigid bodies directly in the bodies' (r̈, α)).

Every joint row φ is built from a few world vectors of the two frames: the offset
d = p_B − p_A and the frames' axes x_A, y_A, z_A, x_B, y_B, z_B. Each vector v(q) has a
Jacobian J_v over the 14 coordinates of the two parts (7 per end: a rigid body's r, u; a
particle's r) and a velocity-product term, v̈ = J_v q̈ + β_v:

    frame origin  p = r + R(u) s:  J = [I, J_s(u)],  β = 2 R(u̇) s     (bodies.rotation_jacobian)
    frame axis    a = R(u) c:      J = [0, J_c(u)],  β = 2 R(u̇) c
    on a particle p = r, a = c; in the world both constant (J = 0, β = 0).

A row's A and b then follow from φ̈ = a q̈ − b:

    component   φ = d_k            a = J_d[k],              b = −β_d[k]
    dot         φ = v·w            a = wᵀJ_v + vᵀJ_w,       b = −(w·β_v + v·β_w + 2 v̇·ẇ)
    distance    φ = (d·d − L²)/2L  a = dᵀJ_d / L,           b = −(ḋ·ḋ + d·β_d)/L

A joint's program is its kind's rows (core/joint_kinds.py: operation, vector, vector or
component), the rows ``constraints.joints.joint_equations`` reads too; the tests compare the
two for every kind. ``EVALUATED``: the operations ``joint_rows`` has a branch for, all of
core/joint_kinds.OPERATIONS (checked at import).
"""

import numpy as np
from numba import njit

from ..core.joint_kinds import COMPONENT, D, DISTANCE, DOT, XA, XB, ZA, ZB, check_operations
from .bodies import OPTIONS, rotation, rotation_jacobian

EVALUATED = (COMPONENT, DOT, DISTANCE)  # joint_rows' branches, in order
check_operations("compiled/joints.joint_rows", EVALUATED)

WORLD, RIGID, PARTICLE = 0, 1, 2  # what a joint's end sits on; vectors 7, 8: the two origins
VALUE, VELOCITY, BIAS, JAC = 0, 1, 2, 3  # columns of a vector's record: 3 values each, then 14 Jacobian columns


def vector_work():
    """Work space of ``joint_rows``: 9 vectors × 3 components × (value, velocity, bias, 14 Jacobian)."""
    return np.zeros((9, 3, 17)), np.zeros((2, 3, 3)), np.zeros((3, 4))


@njit(**OPTIONS)
def _end(e, kind, o, s, Rf, axes, q, qd, V, R, Jt):
    """The origin (record 7 + e) and, when ``axes``, the three axes (1 + 3e ...) of end e
    into V (only the values, velocities, biases and the end's own 7 Jacobian columns)."""
    c0 = JAC + 7 * e
    count = 4 if axes else 1
    for a in range(count):  # the records: a = 0 the origin, a = 1, 2, 3 the axes
        X = V[7 + e] if a == 0 else V[3 * e + a]
        for i in range(3):
            for col in range(3):
                X[i, col] = 0.0
            for col in range(7):
                X[i, c0 + col] = 0.0
            X[i, VALUE] = s[i] if a == 0 else Rf[i, a - 1]
    P = V[7 + e]
    if kind == WORLD:
        return
    for i in range(3):
        P[i, VALUE] = q[o + i]
        P[i, VELOCITY] = qd[o + i]
        P[i, c0 + i] = 1.0
    if kind == PARTICLE:
        return
    u, ud = q[o + 3:o + 7], qd[o + 3:o + 7]
    rotation(u, R[0])
    rotation(ud, R[1])
    for a in range(count):  # a = 0: the origin's offset s; a = 1, 2, 3: the frame's axes
        X = P if a == 0 else V[3 * e + a]
        c = (s[0], s[1], s[2]) if a == 0 else (Rf[0, a - 1], Rf[1, a - 1], Rf[2, a - 1])
        rotation_jacobian(u, c, Jt)
        for i in range(3):
            X[i, VALUE] = (P[i, VALUE] if a == 0 else 0.0) + R[0, i, 0] * c[0] + R[0, i, 1] * c[1] + R[0, i, 2] * c[2]
            X[i, BIAS] += 2 * (R[1, i, 0] * c[0] + R[1, i, 1] * c[1] + R[1, i, 2] * c[2])
            for k in range(4):
                X[i, VELOCITY] += Jt[i, k] * ud[k]
                X[i, c0 + 3 + k] = Jt[i, k]


@njit(**OPTIONS)
def uses_axes(program, k):
    """Whether the k rows of ``program`` use end A's axes, and end B's (dot rows only)."""
    axes_a = axes_b = False
    for r in range(k):
        if program[r, 0] == DOT:
            for x in (program[r, 1], program[r, 2]):
                axes_a |= XA <= x <= ZA
                axes_b |= XB <= x <= ZB
    return axes_a, axes_b


@njit(**OPTIONS)
def joint_rows(program, k, kinds, starts, s, Rf, length, q, qd, V, R, Jt, A, b):
    """Rows A[:k] (k × 14: end A's 7 coordinates, then end B's) and b[:k] of one joint.

    program: k × 3 (operation, vector, vector or component); kinds, starts: per end, what it
    sits on and its first coordinate; s, Rf: per end, the frame's offset and rotation in
    its part (in the world for a world end); length: a distance joint's L."""
    axes_a, axes_b = uses_axes(program, k)  # the ends as np.int64: _end compiled once, not per literal
    _end(np.int64(0), kinds[0], starts[0], s[0], Rf[0], axes_a, q, qd, V, R, Jt)
    _end(np.int64(1), kinds[1], starts[1], s[1], Rf[1], axes_b, q, qd, V, R, Jt)
    for i in range(3):  # d = p_B − p_A: value, velocity, bias and Jacobian alike
        for col in range(17):
            V[D, i, col] = V[8, i, col] - V[7, i, col]
    for r in range(k):
        op, i1, i2 = program[r, 0], program[r, 1], program[r, 2]
        X, Y = V[i1], V[i2]
        if op == COMPONENT:
            for col in range(14):
                A[r, col] = X[i2, JAC + col]
            b[r] = -X[i2, BIAS]
        elif op == DOT:
            for col in range(14):
                A[r, col] = (Y[0, VALUE] * X[0, JAC + col] + Y[1, VALUE] * X[1, JAC + col] + Y[2, VALUE] * X[2, JAC + col]
                             + X[0, VALUE] * Y[0, JAC + col] + X[1, VALUE] * Y[1, JAC + col]
                             + X[2, VALUE] * Y[2, JAC + col])
            total = 0.0
            for i in range(3):
                total += Y[i, VALUE] * X[i, BIAS] + X[i, VALUE] * Y[i, BIAS] + 2 * X[i, VELOCITY] * Y[i, VELOCITY]
            b[r] = -total
        else:  # DISTANCE
            for col in range(14):
                A[r, col] = (X[0, VALUE] * X[0, JAC + col] + X[1, VALUE] * X[1, JAC + col]
                             + X[2, VALUE] * X[2, JAC + col]) / length
            total = 0.0
            for i in range(3):
                total += X[i, VELOCITY] * X[i, VELOCITY] + X[i, VALUE] * X[i, BIAS]
            b[r] = -total / length
