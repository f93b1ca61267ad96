"""φ, φ̇ of the kernel's rows and the energies of its nodes, compiled (for ``simulate``'s
rows and projections: compiled/projection.py).

The rows are those of kernel.py: each rigid body's unit-norm row φ = (uᵀu − 1)/2,
φ̇ = uᵀu̇, and each kernel joint's rows from the vectors of joints.py (value and velocity):
component φ = d_k, φ̇ = ḋ_k; dot φ = v·w, φ̇ = v̇·w + v·ẇ; distance φ = (d·d − L²)/2L,
φ̇ = d·ḋ/L. Energies: T = ½ m ṙᵀṙ + 2 u̇ᵀEᵀJEu̇, V = −m gᵀr (rigid_body.py). Only values
and velocities: R(u) and Ṙ(u, u̇) once per body, then a frame's vector R c moves at Ṙ c
(no Jacobians, unlike joints.py), each row's vectors 3-tuples (as in rate_rows.py). These
are the φ and φ̇ of core/joint_kinds.OPERATIONS; ``EVALUATED``: the operations the row loop
has a branch for, all of them (checked at import).
"""

import numpy as np
from numba import njit

from ..core.joint_kinds import COMPONENT, D, DISTANCE, DOT, check_operations
from .bodies import OPTIONS, INLINE, dot3, rotation, rotation_rate, times3
from .layout import Layout
from .packing import borrowed, fields, view1, view2, view3, view4
from .joints import PARTICLE, RIGID, WORLD

LAYOUT = fields(Layout)
EVALUATED = (COMPONENT, DOT, DISTANCE)  # residuals_energy's row branches, in order
check_operations("compiled/rows.residuals_energy", EVALUATED)


@njit(**OPTIONS)
def residuals_energy(q, qd, LI, LF, LX, phi, psi, Rs, rates=True):
    """φ, φ̇ into phi, psi (rows of the kernel; others untouched); returns (T, V, max|φ|,
    max|φ̇|, max|q|, max|q̇|), the maxima over the whole arrays. LI, LF, LX: the Layout
    packed (packing.py); Rs: (N + 1, 2, 3, 3) work, R and Ṙ per node, a particle's and
    the world's slot (N) (I, 0) (``Rows.new_work``). ``rates`` False: φ alone (psi
    untouched, T and max|φ̇| 0), less work."""
    q, qd, phi, psi, Rs = borrowed(q), borrowed(qd), borrowed(phi), borrowed(psi), borrowed(Rs)
    node_kind, node_q, quat_row = view1(LI, LX, LAYOUT.node_kind), view1(LI, LX, LAYOUT.node_q), \
        view1(LI, LX, LAYOUT.quat_row)
    node_mass, node_mg, node_J = view1(LF, LX, LAYOUT.node_mass), view2(LF, LX, LAYOUT.node_mg), \
        view3(LF, LX, LAYOUT.node_J)
    joint_kinds, joint_start, joint_program = view2(LI, LX, LAYOUT.joint_kinds), view2(LI, LX, LAYOUT.joint_start), \
        view3(LI, LX, LAYOUT.joint_program)
    joint_k, joint_row, joint_node = view1(LI, LX, LAYOUT.joint_k), view1(LI, LX, LAYOUT.joint_row), \
        view2(LI, LX, LAYOUT.joint_node)
    joint_s, joint_R, joint_length = view3(LF, LX, LAYOUT.joint_s), view4(LF, LX, LAYOUT.joint_R), \
        view1(LF, LX, LAYOUT.joint_length)
    kinetic = potential = 0.0
    for i in range(node_kind.shape[0]):
        o = node_q[i]
        m = node_mass[i]
        potential -= node_mg[i, 0] * q[o] + node_mg[i, 1] * q[o + 1] + node_mg[i, 2] * q[o + 2]
        if node_kind[i] == RIGID:
            rotation(q[o + 3:o + 7], Rs[i, 0])
            w, x, y, z = q[o + 3], q[o + 4], q[o + 5], q[o + 6]
            phi[quat_row[i]] = 0.5 * (w * w + x * x + y * y + z * z - 1.0)
        if not rates:
            continue
        kinetic += 0.5 * m * (qd[o] * qd[o] + qd[o + 1] * qd[o + 1] + qd[o + 2] * qd[o + 2])
        if node_kind[i] != RIGID:
            continue
        rotation_rate(q[o + 3:o + 7], qd[o + 3:o + 7], Rs[i, 1])
        w, x, y, z = q[o + 3], q[o + 4], q[o + 5], q[o + 6]
        wd, xd, yd, zd = qd[o + 3], qd[o + 4], qd[o + 5], qd[o + 6]
        psi[quat_row[i]] = w * wd + x * xd + y * yd + z * zd
        # ω_body = 2 E(u) u̇, E = [−v, w I − [v]×]
        o0 = 2 * (-x * wd + w * xd + z * yd - y * zd)
        o1 = 2 * (-y * wd - z * xd + w * yd + x * zd)
        o2 = 2 * (-z * wd + y * xd - x * yd + w * zd)
        J = node_J[i]
        kinetic += 0.5 * (o0 * (J[0, 0] * o0 + J[0, 1] * o1 + J[0, 2] * o2)
                          + o1 * (J[1, 0] * o0 + J[1, 1] * o1 + J[1, 2] * o2)
                          + o2 * (J[2, 0] * o0 + J[2, 1] * o1 + J[2, 2] * o2))
    for k in range(joint_k.shape[0]):  # without rates, Ṙ is stale and φ̇ left alone
        kinds, nodes, starts, s, Rf = joint_kinds[k], joint_node[k], joint_start[k], joint_s[k], joint_R[k]
        pA, vA = _origin(kinds[0], nodes[0], starts[0], s[0], q, qd, Rs)
        pB, vB = _origin(kinds[1], nodes[1], starts[1], s[1], q, qd, Rs)
        d = (pB[0] - pA[0], pB[1] - pA[1], pB[2] - pA[2])
        dd = (vB[0] - vA[0], vB[1] - vA[1], vB[2] - vA[2])
        program, row = joint_program[k], joint_row[k]
        for r in range(joint_k[k]):
            op, x, w = program[r, 0], program[r, 1], program[r, 2]
            if op == COMPONENT:
                value, rate = (d[0], dd[0]) if w == 0 else (d[1], dd[1]) if w == 1 else (d[2], dd[2])
            elif op == DOT:
                wv, wd = _axis(w, nodes, Rf, Rs)
                if x == D:
                    value, rate = dot3(d, wv), dot3(dd, wv) + dot3(d, wd)
                else:
                    xv, xd = _axis(x, nodes, Rf, Rs)
                    value, rate = dot3(xv, wv), dot3(xd, wv) + dot3(xv, wd)
            else:  # DISTANCE
                L = joint_length[k]
                value, rate = (dot3(d, d) - L * L) / (2 * L), dot3(d, dd) / L
            phi[row + r] = value
            if rates:
                psi[row + r] = rate
    return kinetic, potential, largest(phi), largest(psi) if rates else 0.0, largest(q), largest(qd)


@njit(**OPTIONS)
def largest(x):
    """max |x| (0 for none; nan if any is). Four running maxima over interleaved entries:
    one is bound by its comparison's latency, four run at once (5 times faster on a robot's
    q); a NaN shows in the entries' sum."""
    t0 = t1 = t2 = t3 = total = 0.0
    n = x.shape[0]
    m = n - n % 4
    for i in range(0, m, 4):
        a0, a1, a2, a3 = abs(x[i]), abs(x[i + 1]), abs(x[i + 2]), abs(x[i + 3])
        total += (a0 + a1) + (a2 + a3)
        t0 = a0 if a0 > t0 else t0
        t1 = a1 if a1 > t1 else t1
        t2 = a2 if a2 > t2 else t2
        t3 = a3 if a3 > t3 else t3
    for i in range(m, n):
        a = abs(x[i])
        total += a
        t0 = a if a > t0 else t0
    top = max(max(t0, t1), max(t2, t3))
    return top if total == total else np.nan


@njit(**INLINE)
def _origin(kind, node, o, s, q, qd, Rs):
    """(value, velocity) of a frame origin at s on its end: r + R s on a rigid body, r on a
    particle, s in the world (joints.py), from the end's slot of Rs (the world's: (I, 0))."""
    f, g = 0.0 if kind == WORLD else 1.0, 0.0 if kind == PARTICLE else 1.0
    c = (g * s[0], g * s[1], g * s[2])
    rho, vel = times3(Rs[node, 0], c), times3(Rs[node, 1], c)
    return (f * q[o] + rho[0], f * q[o + 1] + rho[1], f * q[o + 2] + rho[2]), \
        (f * qd[o] + vel[0], f * qd[o + 1] + vel[1], f * qd[o + 2] + vel[2])


@njit(**INLINE)
def _axis(x, nodes, Rf, Rs):
    """(value, velocity) of axis x = 1 + 3e + col: R c of end e's column c of Rf, from
    its slot of Rs (a particle's and the world's: (I, 0))."""
    e = 0 if x <= 3 else 1
    col = x - 1 - 3 * e
    c, M = (Rf[e, 0, col], Rf[e, 1, col], Rf[e, 2, col]), Rs[nodes[e]]
    return times3(M[0], c), times3(M[1], c)


class Rows:
    """The compiled φ, φ̇ and energies on an Engine's Layout ``L`` (``packed``: packing.pack(L))
    of a System with ``m`` rows.
    ``covers``: whether the kernel's rows are all of the System's rows and its nodes all of
    its coordinates (no extra rows or coordinates), so that these are the System's φ, φ̇
    and its parts' energies."""

    def __init__(self, L, packed, m):
        self.packed = packed
        covered = np.zeros(m, dtype=bool)
        covered[L.quat_row[L.quat_row >= 0]] = True
        for row, count in zip(L.joint_row, L.joint_k):
            covered[row:row + count] = True
        self.covers = bool(covered.all()) and L.x_coord.size == 0
        self.sizes = m, L.node_kind.shape[0]
        self.phi, self.psi, *self.work = self.new_work(*self.sizes)

    @staticmethod
    def new_work(m, N):
        """φ, φ̇ (m) and the work space: R, Ṙ per node and the world's (I, 0) (N + 1)."""
        Rs = np.zeros((N + 1, 2, 3, 3))
        Rs[:, 0] = np.eye(3)  # a rigid body's overwritten at each call
        return np.zeros(m), np.zeros(m), Rs

    def __call__(self, q, qd):
        """(φ, φ̇, T, V, max|φ|, max|φ̇|, max|q|, max|q̇|) at (q, q̇): the arrays are this
        object's, overwritten by the next call."""
        return (self.phi, self.psi, *residuals_energy(q, qd, *self.packed, self.phi, self.psi, *self.work))

    def largest_phi(self, q, qd):
        """The largest |φ| of the kernel's rows at q (φ alone: ``relative_drift``'s phi_max)."""
        return residuals_energy(q, qd, *self.packed, self.phi, self.psi, *self.work, False)[2]


@njit(**OPTIONS)
def relative_drift(phi_max, gen, phi_from, phi_to, q):
    """A state's relative drift, kernel.motion's ``drift``: its largest |φ| — phi_max of the
    kernel's rows (``Rows.largest_phi``), gen[phi_from:phi_to] of the extra rows (the generated
    function's outputs there) — over its largest coordinate, at least 1 (a quaternion's unit)."""
    largest = phi_max
    for k in range(phi_from, phi_to):
        largest = max(largest, abs(gen[k]))
    return largest / max(np.abs(q).max(), 1.0)
