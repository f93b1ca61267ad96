"""φ, φ̇ of the kernel's rows and the energies of its nodes, compiled (for ``simulate``'s
rows and corrections: fast/correction.py).

The rows are those of kernel.py: each rigid body's unit-norm row φ = (uᵀu − 1)/2,
φ̇ = uᵀu̇, and each kernel joint's rows from the vectors of joints.py (value and velocity):
component φ = d_k, φ̇ = ḋ_k; dot φ = v·w, φ̇ = v̇·w + v·ẇ; distance φ = (d·d − L²)/2L,
φ̇ = d·ḋ/L. Energies: T = ½ m ṙᵀṙ + 2 u̇ᵀEᵀJEu̇, V = −m gᵀr (rigid_body.py).
"""

import numpy as np
from numba import njit

from .bodies import OPTIONS
from .joints import COMPONENT, D, DOT, VALUE, VELOCITY, _end, uses_axes, vector_work


@njit(**OPTIONS)
def residuals_energy(q, qd, node_kind, node_q, node_mass, node_mg, node_J, quat_row, joint_kinds, joint_start,
                     joint_s, joint_R, joint_length, joint_program, joint_k, joint_row, phi, psi, V, R, Jt):
    """φ, φ̇ into phi, psi (rows of the kernel; others untouched); returns (T, V)."""
    kinetic = potential = 0.0
    for i in range(node_kind.shape[0]):
        o = node_q[i]
        m = node_mass[i]
        kinetic += 0.5 * m * (qd[o] * qd[o] + qd[o + 1] * qd[o + 1] + qd[o + 2] * qd[o + 2])
        potential -= node_mg[i, 0] * q[o] + node_mg[i, 1] * q[o + 1] + node_mg[i, 2] * q[o + 2]
        r = quat_row[i]
        if r < 0:
            continue
        w, x, y, z = q[o + 3], q[o + 4], q[o + 5], q[o + 6]
        wd, xd, yd, zd = qd[o + 3], qd[o + 4], qd[o + 5], qd[o + 6]
        phi[r] = 0.5 * (w * w + x * x + y * y + z * z - 1.0)
        psi[r] = w * wd + x * xd + y * yd + z * zd
        # ω_body = 2 E(u) u̇, E = [−v, w I − [v]×]
        o0 = 2 * (-x * wd + w * xd + z * yd - y * zd)
        o1 = 2 * (-y * wd - z * xd + w * yd + x * zd)
        o2 = 2 * (-z * wd + y * xd - x * yd + w * zd)
        J = node_J[i]
        kinetic += 0.5 * (o0 * (J[0, 0] * o0 + J[0, 1] * o1 + J[0, 2] * o2)
                          + o1 * (J[1, 0] * o0 + J[1, 1] * o1 + J[1, 2] * o2)
                          + o2 * (J[2, 0] * o0 + J[2, 1] * o1 + J[2, 2] * o2))
    for k in range(joint_k.shape[0]):
        program, count, row = joint_program[k], joint_k[k], joint_row[k]
        axes_a, axes_b = uses_axes(program, count)
        _end(0, joint_kinds[k, 0], joint_start[k, 0], joint_s[k, 0], joint_R[k, 0], axes_a, q, qd, V, R, Jt)
        _end(1, joint_kinds[k, 1], joint_start[k, 1], joint_s[k, 1], joint_R[k, 1], axes_b, q, qd, V, R, Jt)
        for i in range(3):
            V[D, i, VALUE] = V[8, i, VALUE] - V[7, i, VALUE]
            V[D, i, VELOCITY] = V[8, i, VELOCITY] - V[7, i, VELOCITY]
        for r in range(count):
            op, i1, i2 = program[r, 0], program[r, 1], program[r, 2]
            X, Y = V[i1], V[i2]
            if op == COMPONENT:
                phi[row + r] = X[i2, VALUE]
                psi[row + r] = X[i2, VELOCITY]
            elif op == DOT:
                value = rate = 0.0
                for i in range(3):
                    value += X[i, VALUE] * Y[i, VALUE]
                    rate += X[i, VELOCITY] * Y[i, VALUE] + X[i, VALUE] * Y[i, VELOCITY]
                phi[row + r] = value
                psi[row + r] = rate
            else:
                L = joint_length[k]
                value = rate = 0.0
                for i in range(3):
                    value += X[i, VALUE] * X[i, VALUE]
                    rate += X[i, VALUE] * X[i, VELOCITY]
                phi[row + r] = (value - L * L) / (2 * L)
                psi[row + r] = rate / L
    return kinetic, potential


class Rows:
    """The compiled φ, φ̇ and energies on an Engine's Layout ``L`` of a System with ``m`` rows.
    ``covers``: whether the kernel's rows are all of the System's rows and its nodes all of
    its coordinates (no extra rows or coordinates), so that these are the System's φ, φ̇
    and its parts' energies."""

    def __init__(self, L, m):
        self.args = (L.node_kind, L.node_q, L.node_mass, L.node_mg, L.node_J, L.quat_row, L.joint_kinds,
                     L.joint_start, L.joint_s, L.joint_R, L.joint_length, L.joint_program, L.joint_k, L.joint_row)
        covered = np.zeros(m, dtype=bool)
        covered[L.quat_row[L.quat_row >= 0]] = True
        for row, count in zip(L.joint_row, L.joint_k):
            covered[row:row + count] = True
        self.covers = bool(covered.all()) and L.x_coord.size == 0
        self.work = vector_work()
        self.phi, self.psi = np.zeros(m), np.zeros(m)

    def __call__(self, q, qd):
        """(φ, φ̇, T, V) at (q, q̇): the arrays are this object's, overwritten by the next call."""
        T, V = residuals_energy(q, qd, *self.args, self.phi, self.psi, *self.work)
        return self.phi, self.psi, T, V
