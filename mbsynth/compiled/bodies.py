"""Rigid bodies in numba: rotations, the blocks of (2.1), and the change of variables that
takes a quaternion's norm direction out of the body's block.

A rigid body (rigid_body.py) has M = blockdiag(m I₃, 4 EᵀJE), Q = [m g; −8 E(u̇)ᵀ J E(u) u̇]
with the homogeneous forms of kinematics.py (exact for any u, unit or not):

    R(u) = (w² − vᵀv) I + 2 v vᵀ + 2 w [v]×,      E(u) = [−v, w I − [v]×].

With ν = |u|, U = [uᵀ; E(u)]/ν is orthogonal (E u = 0, E Eᵀ = ν² I), so

    ü = Uᵀ [s; a] = (u s + Eᵀ a)/ν,     U (4 EᵀJE) Uᵀ = blockdiag(0, 4 ν² J),

and the unit-norm row uᵀü = −u̇ᵀu̇ fixes s = −u̇ᵀu̇/ν before any solve. The norm row's
multiplier only balances the s component, which no other unknown sees, so the row and its
multiplier leave the system exactly (an orthogonal change of variables). A second change,
a = Bᵀα with B = R(u)/(2ν), makes the body's unknowns y = (r̈, α) — for a unit quaternion α
is the world angular acceleration — with mass H = blockdiag(m I₃, R J Rᵀ) and force
(Q_r, B E Q_u/ν); a row c = (c_r, c_u) of A becomes (c_r, B E c_u/ν), with (c_u·u) s/ν moved
to its right side. In these unknowns a vector e = R(u)c fixed in the body has, for any u,

    ë = α × e + (2s/ν) e + 2R(u̇)c,

so the rows of a joint between two bodies take the same form on both (rate_rows.py), and a
rigid transport carries one body's unknowns to the other's (tree.py).
"""

from . import cache

cache.configure()  # every kernel module imports this one before it compiles: numba must see the cache first

from numba import njit  # noqa: E402

OPTIONS = dict(cache=True, error_model="numpy")  # no fastmath: contract and reassoc do not pay here
# numba inlines INLINE functions into each caller (their IR retyped at every call site, which
# costs compile time): for the node steps, whose constant sizes must meet the caller's, and the
# 3-tuple helpers (cross3, dot3, times3: left to LLVM they slow the kernel). The rest
# (the packed views, the closed-form null space, the SPD inverse, the rigid transport) stays
# OPTIONS: LLVM inlines what pays (benchmarks/fast_ab.py).
INLINE = dict(OPTIONS, inline="always")


@njit(**INLINE)
def cross3(x, w):
    """x × w of two 3-tuples (or arrays), as a 3-tuple."""
    return (x[1] * w[2] - x[2] * w[1], x[2] * w[0] - x[0] * w[2], x[0] * w[1] - x[1] * w[0])


@njit(**INLINE)
def dot3(x, w):
    return x[0] * w[0] + x[1] * w[1] + x[2] * w[2]


@njit(**INLINE)
def times3(M, c):
    """M c for a 3 × 3 M and a 3-tuple c."""
    return (M[0, 0] * c[0] + M[0, 1] * c[1] + M[0, 2] * c[2], M[1, 0] * c[0] + M[1, 1] * c[1] + M[1, 2] * c[2],
            M[2, 0] * c[0] + M[2, 1] * c[1] + M[2, 2] * c[2])


@njit(**INLINE)
def rotation(u, R):
    """R(u) into R (3 × 3)."""
    w, x, y, z = u[0], u[1], u[2], u[3]
    d = w * w - x * x - y * y - z * z
    R[0, 0] = d + 2 * x * x
    R[1, 1] = d + 2 * y * y
    R[2, 2] = d + 2 * z * z
    R[0, 1] = 2 * (x * y - w * z)
    R[1, 0] = 2 * (x * y + w * z)
    R[0, 2] = 2 * (x * z + w * y)
    R[2, 0] = 2 * (x * z - w * y)
    R[1, 2] = 2 * (y * z - w * x)
    R[2, 1] = 2 * (y * z + w * x)


@njit(**INLINE)
def rotation_rate(u, ud, Rd):
    """d/dt R(u) into Rd: 2(wẇ − v·v̇) I + 2(v̇vᵀ + v v̇ᵀ) + 2ẇ[v]× + 2w[v̇]×."""
    w, x, y, z = u[0], u[1], u[2], u[3]
    wd, xd, yd, zd = ud[0], ud[1], ud[2], ud[3]
    d = 2 * (w * wd - x * xd - y * yd - z * zd)
    Rd[0, 0] = d + 4 * x * xd
    Rd[1, 1] = d + 4 * y * yd
    Rd[2, 2] = d + 4 * z * zd
    Rd[0, 1] = 2 * (xd * y + x * yd - wd * z - w * zd)
    Rd[1, 0] = 2 * (xd * y + x * yd + wd * z + w * zd)
    Rd[0, 2] = 2 * (xd * z + x * zd + wd * y + w * yd)
    Rd[2, 0] = 2 * (xd * z + x * zd - wd * y - w * yd)
    Rd[1, 2] = 2 * (yd * z + y * zd - wd * x - w * xd)
    Rd[2, 1] = 2 * (yd * z + y * zd + wd * x + w * xd)


@njit(**OPTIONS)
def rotation_jacobian(u, c, J):
    """J = ∂(R(u) c)/∂u (3 × 4) for a constant c. R(u)c is quadratic in u, so
    d²/dt² R(u)c = J ü + 2 R(u̇) c."""
    w, vx, vy, vz = u[0], u[1], u[2], u[3]
    cx, cy, cz = c[0], c[1], c[2]
    vc = vx * cx + vy * cy + vz * cz
    # ∂/∂w = 2 (w c + v × c)
    J[0, 0] = 2 * (w * cx + vy * cz - vz * cy)
    J[1, 0] = 2 * (w * cy + vz * cx - vx * cz)
    J[2, 0] = 2 * (w * cz + vx * cy - vy * cx)
    # ∂/∂v = 2 ((vᵀc) I + v cᵀ − c vᵀ − w [c]×)
    v = (vx, vy, vz)
    for i in range(3):
        for j in range(3):
            J[i, 1 + j] = 2 * (v[i] * c[j] - c[i] * v[j])
        J[i, 1 + i] += 2 * vc
    J[0, 2] += 2 * w * cz
    J[0, 3] -= 2 * w * cy
    J[1, 1] -= 2 * w * cz
    J[1, 3] += 2 * w * cx
    J[2, 1] += 2 * w * cy
    J[2, 2] -= 2 * w * cx


@njit(**INLINE)
def rate(u, x):
    """E(u) x for a 4-vector x: −x_w v + w x_v − v × x_v (a 3-tuple)."""
    w, a, b, c = u[0], u[1], u[2], u[3]
    return (-x[0] * a + w * x[1] - (b * x[3] - c * x[2]),
            -x[0] * b + w * x[2] - (c * x[1] - a * x[3]),
            -x[0] * c + w * x[3] - (a * x[2] - b * x[1]))


@njit(**INLINE)
def rate_transpose(u, g):
    """E(u)ᵀ g for a 3-vector g: (−v·g, w g + v × g) (a 4-tuple)."""
    w, a, b, c = u[0], u[1], u[2], u[3]
    return (-(a * g[0] + b * g[1] + c * g[2]),
            w * g[0] + b * g[2] - c * g[1],
            w * g[1] + c * g[0] - a * g[2],
            w * g[2] + a * g[1] - b * g[0])


@njit(**INLINE)
def body_force(mg, J, u, ud, Q):
    """Q of a rigid body into Q (7): [m g; −8 E(u̇)ᵀ J E(u) u̇]."""
    o = rate(u, ud)
    g = (J[0, 0] * o[0] + J[0, 1] * o[1] + J[0, 2] * o[2],
         J[1, 0] * o[0] + J[1, 1] * o[1] + J[1, 2] * o[2],
         J[2, 0] * o[0] + J[2, 1] * o[1] + J[2, 2] * o[2])
    f = rate_transpose(ud, g)
    for i in range(3):
        Q[i] = mg[i]
    for k in range(4):
        Q[3 + k] = -8 * f[k]


@njit(**OPTIONS)
def reduce_row(c, u, nu, s, out):
    """(c_r, E c_u/ν) of a 7-coefficient row segment c into out (6); returns the right-side
    shift −(c_u·u) s/ν (module docstring)."""
    e = rate(u, c[3:])
    for i in range(3):
        out[i] = c[i]
        out[3 + i] = e[i] / nu
    return -(c[3] * u[0] + c[4] * u[1] + c[5] * u[2] + c[6] * u[3]) * s / nu


@njit(**OPTIONS)
def velocities(q, rates, starts, v):
    """v from a state's q and its rates (q̇ or q̈), the integrator's form (analysis/velocity_form.py):
    each rigid body's four quaternion rates r (its quaternion at q[s:s + 4], s in ``starts``)
    replaced by E(u) r / |u|², the other entries copied. v may be ``rates`` itself, written
    over: each entry is written at or before the one read, a body's four read first."""
    i, j = 0, 0  # where v and rates are read from
    for s in starts:
        while j < s:
            v[i] = rates[j]
            i, j = i + 1, j + 1
        w, x, y, z = q[s], q[s + 1], q[s + 2], q[s + 3]
        a, b, c, d = rates[s], rates[s + 1], rates[s + 2], rates[s + 3]
        scale = 1.0 / (w * w + x * x + y * y + z * z)
        v[i] = scale * (-x * a + w * b + z * c - y * d)
        v[i + 1] = scale * (-y * a - z * b + w * c + x * d)
        v[i + 2] = scale * (-z * a + y * b - x * c + w * d)
        i, j = i + 3, s + 4
    while j < rates.size:
        v[i] = rates[j]
        i, j = i + 1, j + 1


@njit(**OPTIONS)
def state_of(y, starts, q, qd):
    """q and q̇ of y, a state in the integrator's form (``velocities``), into ``q``, ``qd``:
    u̇ = E(u)ᵀ h per body (its h = ω/2 read at its quaternion's place in v), the other entries copied."""
    n = q.size
    q[:] = y[:n]
    i, j = n, 0  # where y's v is read and q̇ written
    for s in starts:
        while j < s:
            qd[j] = y[i]
            i, j = i + 1, j + 1
        w, x, yy, z = y[s], y[s + 1], y[s + 2], y[s + 3]
        a, b, c = y[i], y[i + 1], y[i + 2]
        qd[s] = -x * a - yy * b - z * c
        qd[s + 1] = w * a - z * b + yy * c
        qd[s + 2] = z * a + w * b - x * c
        qd[s + 3] = -yy * a + x * b + w * c
        i, j = i + 3, s + 4
    while j < n:
        qd[j] = y[i]
        i, j = i + 1, j + 1
