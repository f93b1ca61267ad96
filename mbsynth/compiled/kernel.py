"""The compiled path's whole evaluation, in numba: assemble, factor the tree, close the loops,
recover q̈ and Qc, check.

Extra rows (loop joints, other constraints) and extra coordinates (other parts) join the
tree system K z = r as a bordered system. With G the extra rows on the tree unknowns,

    [[M_x, A_xᵀ], [A_x, −G K⁻¹ Gᵀ]] [q̈_x; λ_x] = [F_x; b_x − G K⁻¹ r],   z = K⁻¹ (r − Gᵀ λ_x):

the tree is factored once and each extra row costs one tree solve. The small symmetric
Schur matrix is solved by its eigendecomposition, dropping eigenvalues below
``SCHUR_ZERO_RTOL`` of the largest, or of 1 (redundant rows, as a planar loop's in 3D; the
masses are divided by the largest and the rows have unit norm, so a row that acts has an
eigenvalue of the order of an inverse mass, ≥ about 1/N, and rows that repeat tree rows
give a Schur matrix of rounding noise). A dropped
direction must leave the right side alone (else the rows contradict: INCONSISTENT) and
must move no acceleration (else the motion is not unique: NOT_UNIQUE).

Where the extra coordinates' mass block is positive definite (planar bodies, energy-defined
parts of positive mass), their accelerations are eliminated first and the Schur matrix is the
rows' alone, A_x M_x⁻¹ A_xᵀ + G K⁻¹ Gᵀ (``_close_reduced``): smaller, and semi-definite.
A flexible part's stiffening term can make its mass indefinite along a direction the rows
hold (the spin-up beam's torsion about its axis): off the manifold, with every row kept,
M_x + A_xᵀA_x (``_augmented``) has the same motion and multipliers and is positive definite.
Otherwise the bordered matrix is solved whole (``_close``).

Off the manifold (an integrator's stage, ``motion``'s ``drift``) the Schur step follows the
drift rule of core/equations.py instead: directions the drift splits off dependent rows are
dropped with their part of the right side (least squares), and a nearly dependent one the
drift does not explain goes to the exact treatment (NEAR_SINGULAR).

Status: OK, or why the caller must hand the problem to the exact treatment — a singular
tree block (SINGULAR), the cases above, a residual above ``KERNEL_RESIDUAL_MAX`` or a
non-finite result. ``residual`` is the relative residual of the equilibrated KKT
equations M q̈ + Aᵀλ = Q + C, A q̈ = b (its numerator bounds that of (2.12), since
P Aᵀ = 0 and ‖P‖ = 1).
"""

import math

import numpy as np
from numba import njit

from . import banded
from .assembly import Work, divide_masses, extra_rows, generated, nodes, transports, tree_rhs, tree_rows
from .bodies import INLINE, OPTIONS, rate_transpose, velocities
from .certify import rows_certified
from .eigen import symmetric_eigen
from .joints import RIGID
from .layout import Layout
from .packing import borrowed, fields, view1, view2, view3, view4
from .tree import cholesky, cholesky_solve, factor, solve
from ..core.tolerances import (DIVISION_GUARD, DRIFT_MASS_SPREAD, DRIFT_RANK, KERNEL_CONSISTENCY_RTOL,
                               KERNEL_NULL_RTOL, KERNEL_RESIDUAL_MAX, NEAR_SINGULAR as NEAR_SINGULAR_RTOL,
                               SCHUR_CONDITION_MAX, SCHUR_DEPENDENT_RTOL, SCHUR_ZERO_RTOL, SPLIT_MOVES)

OK, SINGULAR, INCONSISTENT, NOT_UNIQUE, RESIDUAL, NOT_FINITE, NEAR_SINGULAR = range(7)
CHECKED, UNCHECKED, REUSED = (np.int64(m) for m in range(3))  # modes of ``motion`` (what a call factors and
# checks): numpy integers, which numba types as int64 rather than as a literal per value (one compilation)
RIGID_TREE, GENERAL = None, True  # ``motion``'s ``general``: numba prunes the branches on ``general is None``, so
# a rigid tree's motion compiles without particle joints, extra rows and extra coordinates (Layout.general)
ESTIMATE_MARGIN = 10.0  # banded.inverse_norm1 is a lower bound of ‖S⁻¹‖₁: certified with this much to spare
LAYOUT, WORK = fields(Layout), fields(Work)


@njit(**OPTIONS)
def _copy(a, b):
    """b ← a (a loop: numba's slice assignment compiles slowly)."""
    for i in range(a.shape[0]):
        b[i] = a[i]


@njit(**OPTIONS)
def _scatter(x, weight, segs, seg6, y):
    """y += weight · (extra row x on the tree unknowns). segs: (xseg_ptr, xseg_node, v, yoff)."""
    ptr, node, v, yoff = segs
    for seg in range(ptr[x], ptr[x + 1]):
        i = node[seg]
        for a in range(v[i]):
            y[yoff[i] + a] += weight * seg6[seg, a]


@njit(**OPTIONS)
def _row_dot(x, segs, seg6, z):
    """(extra row x on the tree unknowns) · z."""
    ptr, node, v, yoff = segs
    total = 0.0
    for seg in range(ptr[x], ptr[x + 1]):
        i = node[seg]
        for a in range(v[i]):
            total += seg6[seg, a] * z[yoff[i] + a]
    return total


@njit(**OPTIONS)
def _moves(vec, nx, topology, segs, seg6, factored, y, w):
    """The acceleration a unit Schur direction (u_x, μ) moves: (u_x, −(K⁻¹Gᵀμ) on accelerations)."""
    y[:] = 0.0
    for x in range(vec.shape[0] - nx):
        _scatter(x, -vec[nx + x], segs, seg6, y)
    solve(topology, factored, y, w, False)
    total = 0.0
    for x in range(nx):
        total += vec[x] * vec[x]
    v, yoff = segs[2], segs[3]
    for i in range(v.shape[0]):
        for a in range(v[i]):
            total += w[yoff[i] + a] ** 2
    return math.sqrt(total)


@njit(**OPTIONS)
def _close(topology, segs, seg6, factored, Mx, Ax, xb, Fx, ry, z0, y, w, z, S, vectors, values, rhs, lam, multipliers,
           drift):
    """Solve the Schur system of the extra rows and coordinates into lam (extra
    accelerations, then extra multipliers), then the tree into z (its multipliers too
    where ``multipliers``: tree.solve). Returns a status. ``drift``: negative on the
    manifold (the rules of the module docstring), else the state's relative drift δ
    (``motion``). The Schur matrix's eigenvectors and eigenvalues stay in ``vectors`` and
    ``values`` (``_close_solve`` solves with them again). Off the manifold with extra
    coordinates whose mass is not positive definite (rows certified by ``motion``: the drift
    rule keeps every row, its answer the plain one), the mass augmented by the rows on no
    tree unknown (``_augmented``) is tried first; where it is not positive definite either,
    the bordered matrix must have a condition of at most SCHUR_CONDITION_MAX, else
    NEAR_SINGULAR (its solve's rounding, ε κ)."""
    mx, nx = Ax.shape[0], Ax.shape[1]
    if nx > 0:
        L, scale, forces = S[mx:mx + nx, :nx], values[:nx], rhs[mx:mx + nx]  # free until _close_reduced uses them
        largest = 0.0
        for x in range(nx):
            largest = max(largest, Mx[x, x])
        scale[:] = largest
        if cholesky(Mx, nx, scale, L):
            _copy(Fx, forces)
            return _close_reduced(topology, segs, seg6, factored, L, Ax, xb, forces, ry, z0, y, w, z, S,
                                  vectors, values, rhs, lam, multipliers, drift)
        if drift >= 0.0:
            _augmented(Mx, Ax, xb, Fx, segs, L, forces)
            scale[:] = largest + 1.0
            if cholesky(L, nx, scale, L):
                return _close_reduced(topology, segs, seg6, factored, L, Ax, xb, forces, ry, z0, y, w, z, S,
                                      vectors, values, rhs, lam, multipliers, drift)
    S[:, :] = 0.0
    for x in range(nx):
        for c in range(nx):
            S[x, c] = Mx[x, c]
    for x in range(mx):
        for c in range(nx):
            S[c, nx + x] = Ax[x, c]
            S[nx + x, c] = Ax[x, c]
    for x in range(mx):
        y[:] = 0.0
        _scatter(x, 1.0, segs, seg6, y)
        solve(topology, factored, y, w, False)
        for r in range(mx):
            S[nx + r, nx + x] = -_row_dot(r, segs, seg6, w)
    symmetric_eigen(S, vectors, values)
    if drift >= 0.0 and nx and not np.abs(values).min() * SCHUR_CONDITION_MAX >= np.abs(values).max():
        return NEAR_SINGULAR  # a mass not definite and a bordered matrix near singular: the exact drift rule's
    return _close_solve(topology, segs, seg6, factored, Fx, xb, ry, z0, y, w, z, vectors, values, rhs, lam, nx, mx,
                        multipliers, drift)


@njit(**OPTIONS)
def _augmented(Mx, Ax, xb, Fx, segs, out, Fa):
    """out ← Mx + Σ A_xᵀA_x over the extra rows on no tree unknown, Fa ← F_x + Σ A_xᵀ b_x over
    them. Where those rows hold (A_x q̈_x = b_x, every row kept: ``_close`` off the manifold,
    rows certified) the added terms cancel, so the motion and the multipliers are Mx's, and a
    mass indefinite only along directions the rows hold (a flexible part's stiffening term
    along its torsion) becomes positive definite (weight 1: the rows have unit norm, the
    masses are over the largest)."""
    nx = Mx.shape[0]
    _copy(Fx, Fa)
    for c in range(nx):
        for d in range(nx):
            out[c, d] = Mx[c, d]
    ptr = segs[0]
    for x in range(Ax.shape[0]):
        if ptr[x + 1] > ptr[x]:
            continue
        for c in range(nx):
            a = Ax[x, c]
            if a == 0.0:
                continue
            Fa[c] += a * xb[x]
            for d in range(nx):
                out[c, d] += a * Ax[x, d]


@njit(**OPTIONS)
def _close_solve(topology, segs, seg6, factored, Fx, xb, ry, z0, y, w, z, vectors, values, rhs, lam, nx, mx,
                 multipliers, drift):
    """``_close``'s solve, from the Schur matrix's eigenvectors and eigenvalues (``vectors``,
    ``values``) and z0 = K⁻¹ ry: the right side, the dropped directions' rules, lam, z."""
    for x in range(nx):
        rhs[x] = Fx[x]
    for x in range(mx):
        rhs[nx + x] = xb[x] - _row_dot(x, segs, seg6, z0)
    top = max(np.abs(values).max(), 1.0) if values.shape[0] else 1.0
    dependent = max(SCHUR_DEPENDENT_RTOL, (DRIFT_RANK * drift) ** 2) * top  # off the manifold: the drift's own
    lam[:] = 0.0
    dropped = size = 0.0
    for e in range(values.shape[0]):  # the right side's scale: before the tree's part cancels
        size += rhs[e] * rhs[e]
    for x in range(mx):
        size += xb[x] * xb[x]
    for e in range(values.shape[0]):
        coef = 0.0
        for c in range(values.shape[0]):
            coef += vectors[c, e] * rhs[c]
        if abs(values[e]) > SCHUR_ZERO_RTOL * top:
            for c in range(values.shape[0]):
                lam[c] += coef / values[e] * vectors[c, e]
            continue
        if drift >= 0.0 and abs(values[e]) > dependent:
            return NEAR_SINGULAR  # not the drift's: for the exact drift rule (equations.py)
        allowed = KERNEL_NULL_RTOL
        if drift >= 0.0:  # rows the drift split move accelerations by about their σ
            allowed = max(KERNEL_NULL_RTOL, SPLIT_MOVES * math.sqrt(abs(values[e]) / top))
        if _moves(vectors[:, e], nx, topology, segs, seg6, factored, y, w) > allowed:
            return NOT_UNIQUE
        dropped += coef * coef
        if drift >= 0.0:  # least squares: the rows' right side less its part along the dropped direction
            for x in range(mx):
                xb[x] -= coef * vectors[nx + x, e]
    if drift < 0.0 and math.sqrt(dropped) > KERNEL_CONSISTENCY_RTOL * (math.sqrt(size) + DIVISION_GUARD):
        return INCONSISTENT
    _tree_solve(topology, segs, seg6, factored, ry, y, z, lam, nx, mx, multipliers)
    return OK


@njit(**OPTIONS)
def _tree_solve(topology, segs, seg6, factored, ry, y, z, lam, nx, mx, multipliers):
    """z ← the tree's solution (its multipliers too where ``multipliers``) with the extra
    rows' multipliers lam[nx:] acting on it."""
    _copy(ry, y)
    for x in range(mx):
        _scatter(x, -lam[nx + x], segs, seg6, y)
    solve(topology, factored, y, z, multipliers)


@njit(**OPTIONS)
def _close_reduced(topology, segs, seg6, factored, L, Ax, xb, forces, ry, z0, y, w, z, S, vectors, values, rhs,
                   lam, multipliers, drift):
    """``_close`` where the extra coordinates' mass Mx is positive definite (``L``: its Cholesky
    factor, Mx = L Lᵀ, tree.cholesky; ``forces``: F_x, rhs[m_x:] itself): their accelerations
    q̈_x = Mx⁻¹ (F_x − A_xᵀ λ) are eliminated, leaving the rows' Schur matrix
    A_x Mx⁻¹ A_xᵀ + G K⁻¹ Gᵀ = WᵀW + G K⁻¹ Gᵀ with W = L⁻¹ A_xᵀ (positive semi-definite,
    m_x × m_x) for λ. The motion is unique (the masses are), so dropped directions are
    dependent rows, judged for consistency. Off the manifold (``drift`` ≥ 0) ``motion`` comes
    here only with rows certified (certify.py): the drift rule keeps every direction and its
    answer is this plain one, which this solve gives to about ε κ of the Schur matrix; a
    stage whose κ exceeds SCHUR_CONDITION_MAX (a singular position near: κ grows as σ_min⁻²),
    or with a direction dropped here, is left to the exact treatment (NEAR_SINGULAR). Where a
    Cholesky factor of the Schur matrix shows that none of this can happen (``_plain_schur``)
    λ comes from that factor, with no eigendecomposition. Work: W in vectors[m_x:, :m_x],
    L⁻¹ F_x over ``forces``, the Schur eigenvalues in values[:m_x] (or the Schur factor in
    vectors[:m_x, :m_x])."""
    mx, nx = Ax.shape[0], Ax.shape[1]
    Sc, Vc, W = S[:mx, :mx], vectors[:mx, :mx], vectors[mx:mx + nx, :mx]
    for c in range(nx):  # forces ← L⁻¹ F_x, W ← L⁻¹ A_xᵀ (forward substitution)
        inv = 1.0 / L[c, c]
        total = forces[c]
        for d in range(c):
            total -= L[c, d] * forces[d]
        forces[c] = total * inv
        for x in range(mx):
            total = Ax[x, c]
            for d in range(c):
                total -= L[c, d] * W[d, x]
            W[c, x] = total * inv
    for x in range(mx):
        y[:] = 0.0
        _scatter(x, 1.0, segs, seg6, y)
        solve(topology, factored, y, w, False)
        for r in range(mx):
            total = _row_dot(r, segs, seg6, w)
            for c in range(nx):
                total += W[c, r] * W[c, x]
            Sc[r, x] = total
        total = -xb[x] + _row_dot(x, segs, seg6, z0)
        for c in range(nx):
            total += W[c, x] * forces[c]
        rhs[x] = total
    values = values[:mx]
    if _plain_schur(Sc, Vc, values, drift):  # every direction kept: λ by the Cholesky factor in Vc
        cholesky_solve(Vc, rhs, lam[nx:nx + mx])
        _reduced_accelerations(L, W, forces, lam, nx, mx)
        _tree_solve(topology, segs, seg6, factored, ry, y, z, lam, nx, mx, multipliers)
        return OK
    symmetric_eigen(Sc, Vc, values)
    if drift >= 0.0 and mx and not values.min() * SCHUR_CONDITION_MAX >= values.max():
        return NEAR_SINGULAR  # its solve's rounding, ε κ, is the exact rule's to avoid
    top = max(np.abs(values).max(), 1.0) if mx else 1.0
    lam[:] = 0.0
    dropped = size = 0.0
    for x in range(mx):
        size += rhs[x] * rhs[x] + xb[x] * xb[x]
    for e in range(mx):
        coef = 0.0
        for c in range(mx):
            coef += Vc[c, e] * rhs[c]
        if abs(values[e]) > SCHUR_ZERO_RTOL * top:
            for c in range(mx):
                lam[nx + c] += coef / values[e] * Vc[c, e]
        elif drift >= 0.0:
            return NEAR_SINGULAR
        else:
            dropped += coef * coef
    if math.sqrt(dropped) > KERNEL_CONSISTENCY_RTOL * (math.sqrt(size) + DIVISION_GUARD):
        return INCONSISTENT
    _reduced_accelerations(L, W, forces, lam, nx, mx)
    _tree_solve(topology, segs, seg6, factored, ry, y, z, lam, nx, mx, multipliers)
    return OK


@njit(**OPTIONS)
def _reduced_accelerations(L, W, forces, lam, nx, mx):
    """lam[:nx] ← q̈_x = L⁻ᵀ (L⁻¹ F_x − W λ) (back substitution; ``_close_reduced``'s L, W,
    forces = L⁻¹ F_x and λ in lam[nx:])."""
    for c in range(nx):
        total = forces[c]
        for x in range(mx):
            total -= W[c, x] * lam[nx + x]
        lam[c] = total
    for c in range(nx - 1, -1, -1):
        total = lam[c]
        for d in range(c + 1, nx):
            total -= L[d, c] * lam[d]
        lam[c] = total / L[c, c]


@njit(**OPTIONS)
def _plain_schur(Sc, Lc, column, drift):
    """Whether the rows' Schur matrix Sc (symmetric positive semi-definite, m × m) certainly
    keeps every eigen-direction under ``_close_reduced``'s rules, so that its solve is the
    plain one: Lc's lower triangle ← the Cholesky factor of Sc (Sc untouched; ``column``: m
    of work). Its eigenvalues lie in [1/‖L⁻¹‖_F², trace Sc] (‖Sc⁻¹‖₂ = ‖L⁻¹‖₂² ≤ ‖L⁻¹‖_F²),
    so where 1/‖L⁻¹‖_F² is above SCHUR_ZERO_RTOL · max(trace, 1) no direction is dropped,
    and off the manifold (drift ≥ 0) where trace · ‖L⁻¹‖_F² ≤ SCHUR_CONDITION_MAX the
    condition is within bounds. False where either bound fails or a pivot is not positive:
    the eigendecomposition judges then."""
    m = Sc.shape[0]
    column[:] = 0.0  # the pivots' floor (tree.cholesky): positive
    if not cholesky(Sc, m, column, Lc):
        return False
    trace = 0.0
    for j in range(m):
        trace += Sc[j, j]
    inverse = 0.0  # ‖L⁻¹‖_F², a column of L⁻¹ at a time (forward substitution of e_j)
    for j in range(m):
        for r in range(j, m):
            t = 1.0 if r == j else 0.0
            for c in range(j, r):
                t -= Lc[r, c] * column[c]
            column[r] = t / Lc[r, r]
            inverse += column[r] * column[r]
    if not inverse * SCHUR_ZERO_RTOL * max(trace, 1.0) < 1.0:
        return False
    return drift < 0.0 or trace * inverse <= SCHUR_CONDITION_MAX


@njit(**OPTIONS)
def _close_banded(Mx, Ax, xb, Fx, lam, patterns, position, width, bands, work, rhs):
    """``_close_reduced`` for a model of extra coordinates alone whose mass Mx is diagonal and
    whose rows' Schur matrix S = A_x Mx⁻¹ A_xᵀ is banded in the order ``position`` (layout.py,
    banded.py): S assembled coordinate by coordinate from the entries of A_x, factored by
    Cholesky, λ = S⁻¹ (A_x Mx⁻¹ F_x − b_x), q̈_x = Mx⁻¹ (F_x − A_xᵀ λ). On the manifold and
    off it alike the answer is kept only where the equilibrated rows are certainly
    independent, σ_min ≥ NEAR_SINGULAR σ₁, so that the drift rule of core/equations.py keeps
    every direction and its answer is this plain one: with T = A_x A_xᵀ (banded alike),
    σ_min² = λ_min(T) ≥ 1 / ‖T⁻¹‖₁ and σ₁² = λ_max(T) ≤ ‖T‖₁, ‖T⁻¹‖₁ taken as
    ESTIMATE_MARGIN times its estimate (banded.inverse_norm1, a lower bound) where that
    certifies, else computed (banded.inverse_norm1_exact: near a singular position only).
    Else (dependent or nearly dependent rows, a singular position near, a mass not positive)
    NEAR_SINGULAR: the exact treatment's. ``bands``: (S, T)."""
    xa_ptr, xa_col, xc_ptr, xc_row = patterns[0], patterns[1], patterns[2], patterns[3]
    mx, nx = Ax.shape[0], Ax.shape[1]
    S, T = bands[0], bands[1]
    for c in range(nx):
        if not Mx[c, c] > 0.0:
            return NEAR_SINGULAR
    S[:, :] = 0.0
    T[:, :] = 0.0
    for c in range(nx):
        inverse = 1.0 / Mx[c, c]
        for e in range(xc_ptr[c], xc_ptr[c + 1]):
            r = xc_row[e]
            for f in range(xc_ptr[c], xc_ptr[c + 1]):
                d = position[r] - position[xc_row[f]]
                if d >= 0:
                    product = Ax[r, c] * Ax[xc_row[f], c]
                    S[position[r], d] += product * inverse
                    T[position[r], d] += product
    size = banded.norm1(T, width, work[0])
    if not (banded.cholesky(T, width) and banded.cholesky(S, width)):
        return NEAR_SINGULAR
    needed = NEAR_SINGULAR_RTOL ** 2 * size  # 1 / ‖T⁻¹‖₁ must reach this
    estimate = banded.inverse_norm1(T, width, work[0], work[1])  # ≤ ‖T⁻¹‖₁
    if not 1.0 >= estimate * needed:
        return NEAR_SINGULAR  # ‖T⁻¹‖₁ is larger still
    if not 1.0 >= ESTIMATE_MARGIN * estimate * needed and \
            not 1.0 >= banded.inverse_norm1_exact(T, width, work[0]) * needed:
        return NEAR_SINGULAR
    for x in range(mx):
        total = -xb[x]
        for e in range(xa_ptr[x], xa_ptr[x + 1]):
            total += Ax[x, xa_col[e]] * Fx[xa_col[e]] / Mx[xa_col[e], xa_col[e]]
        rhs[position[x]] = total
    banded.solve(S, width, rhs)
    for x in range(mx):
        lam[nx + x] = rhs[position[x]]
    for c in range(nx):
        total = Fx[c]
        for e in range(xc_ptr[c], xc_ptr[c + 1]):
            total -= Ax[xc_row[e], c] * lam[nx + xc_row[e]]
        lam[c] = total / Mx[c, c]
    return OK


@njit(**OPTIONS)
def _uneven_masses(v, H, Mx):
    """Whether the diagonal of the masses (divided by the largest: H per node, Mx) spans more
    than DRIFT_MASS_SPREAD (or has a zero): off the manifold the Schur eigenvalues, in the
    mass metric, then do not stand for the rows' singular values that the drift rule
    judges (``motion``'s ``drift``)."""
    least = 1.0
    for i in range(v.shape[0]):
        for a in range(v[i]):
            least = min(least, H[i, a, a])
    for x in range(Mx.shape[0]):
        least = min(least, Mx[x, x])
    return not least >= DRIFT_MASS_SPREAD


@njit(**OPTIONS)
def _recover(q, kind, start, mass, inertia, yoff, x_coord, nu, s, Rs, z, Qf, Mx, gen_mi, gen_mj, lam, mu, qdd, Qc):
    """q̈ (bodies.py: ü = (u s + Eᵀa)/ν, a = Bᵀα) and Qc = M q̈ − Q from the solution."""
    for i in range(kind.shape[0]):
        c, o, m = start[i], yoff[i], mass[i]
        for a in range(3):
            qdd[c + a] = z[o + a]
            Qc[c + a] = m * z[o + a] - Qf[c + a]
        if kind[i] != RIGID:
            continue
        u, J, Bi = q[c + 3:c + 7], inertia[i], Rs[i, 3]
        a_rates = (Bi[0, 0] * z[o + 3] + Bi[1, 0] * z[o + 4] + Bi[2, 0] * z[o + 5],
                   Bi[0, 1] * z[o + 3] + Bi[1, 1] * z[o + 4] + Bi[2, 1] * z[o + 5],
                   Bi[0, 2] * z[o + 3] + Bi[1, 2] * z[o + 4] + Bi[2, 2] * z[o + 5])
        et = rate_transpose(u, a_rates)
        f = rate_transpose(u, (J[0, 0] * a_rates[0] + J[0, 1] * a_rates[1] + J[0, 2] * a_rates[2],
                               J[1, 0] * a_rates[0] + J[1, 1] * a_rates[1] + J[1, 2] * a_rates[2],
                               J[2, 0] * a_rates[0] + J[2, 1] * a_rates[1] + J[2, 2] * a_rates[2]))
        for a in range(4):
            qdd[c + 3 + a] = (u[a] * s[i] + et[a]) / nu[i]
            Qc[c + 3 + a] = 4 * nu[i] * f[a] - Qf[c + 3 + a]
    for x in range(x_coord.shape[0]):
        qdd[x_coord[x]] = lam[x]
        Qc[x_coord[x]] = -Qf[x_coord[x]]
    for e in range(gen_mi.shape[0]):  # the entries of Mx (assembly.generated)
        Qc[x_coord[gen_mi[e]]] += mu * Mx[gen_mi[e], gen_mj[e]] * lam[gen_mj[e]]


@njit(**OPTIONS)
def _shifts_only(qd, bshift, kind, quat_row):
    """Whether a state is at rest (q̇ = 0) and its shifts leave the unit-norm rows alone: then
    every b term of the rows vanishes (each is quadratic in q̇, or a unit-norm row's
    acceleration s, zero), and their right sides are the shifts alone."""
    if bshift.shape[0] == 0:
        return False
    for c in range(qd.shape[0]):
        if qd[c] != 0.0:
            return False
    for i in range(kind.shape[0]):
        if kind[i] == RIGID and bshift[quat_row[i]] != 0.0:
            return False
    return True


@njit(**OPTIONS)
def _shifted_rows(kind, node_joint, k, rows, joint_row, bshift, rscale, rb, s):
    """The tree rows' right sides of a state ``_shifts_only`` accepts: the shifts, equilibrated
    as the rows were (rscale); the unit-norm rows' s zero."""
    for i in range(kind.shape[0]):
        if kind[i] == RIGID:
            s[i] = 0.0
        j = node_joint[i]
        if j >= 0:
            for r in range(k[i]):
                rb[rows[i] + r] = rscale[rows[i] + r] * bshift[joint_row[j] + r]


@njit(**OPTIONS)
def _finite(qdd, Qc):
    """Whether every entry of q̈ and Qc is finite."""
    for c in range(qdd.shape[0]):
        if not (math.isfinite(qdd[c]) and math.isfinite(Qc[c])):
            return False
    return True


@njit(**INLINE)
def _node_dynamics(i, vi, ki, yoff, rows, H, F, J, z, dyn):
    """dyn_i ← H_i y_i + J_iᵀ λ_i − F_i (the children's rows are added later); returns its
    contributions to (‖M‖², ‖x‖², ‖r‖²)."""
    o, r0 = yoff[i], rows[i]
    norm_M = norm_x = norm_r = 0.0
    for a in range(vi):
        t = -F[i, a]
        for c in range(vi):
            t += H[i, a, c] * z[o + c]
            norm_M += H[i, a, c] ** 2
        for r in range(ki):
            t += J[r0 + r, a] * z[o + vi + r]
        dyn[i, a] = t
        norm_x += z[o + a] ** 2
        norm_r += F[i, a] ** 2
    return norm_M, norm_x, norm_r


@njit(**INLINE)
def _node_rows(i, vi, ki, vp, p, yoff, rows, J, P, rb, z, dyn):
    """The residual of node i's parent-joint rows, their multipliers added to the parent's
    dyn; returns (Σ residual², ‖A‖², ‖b‖²) of those rows."""
    o, r0 = yoff[i], rows[i]
    res = norm_A = norm_r = 0.0
    for r in range(ki):
        lam_r, t = z[o + vi + r], -rb[r0 + r]
        for a in range(vi):
            t += J[r0 + r, a] * z[o + a]
            norm_A += J[r0 + r, a] ** 2
        if p >= 0:
            for a in range(vp):
                dyn[p, a] += P[r0 + r, a] * lam_r
                t += P[r0 + r, a] * z[yoff[p] + a]
                norm_A += P[r0 + r, a] ** 2
        res += t * t
        norm_r += rb[r0 + r] ** 2
    return res, norm_A, norm_r


@njit(**OPTIONS)
def _residual(topology, kind, segs, seg6, H, F, J, P, rb, s, z, lam, xb, Ax, Mx, Fx, patterns, dyn, t_x):
    """Relative residual of the equilibrated KKT equations at the solution (module docstring).
    Rigid nodes on revolute or fixed joints run with constant sizes (numba unrolls them).
    patterns: (xa_ptr, xa_col, xc_ptr, xc_row, gen_mi, gen_mj), the entries of Ax and Mx
    (layout.py); t_x: work (n_x)."""
    xa_ptr, xa_col, xc_ptr, xc_row, mi, mj = patterns
    _, parent, v, k, yoff, rows, _ = topology
    ptr, node = segs[0], segs[1]
    mx, nx = Ax.shape[0], Ax.shape[1]
    res = norm_M = norm_A = norm_x = norm_r = 0.0
    for i in range(kind.shape[0]):
        if v[i] == 6 and k[i] == 5:
            m2, x2, r2 = _node_dynamics(i, 6, 5, yoff, rows, H, F, J, z, dyn)
        elif v[i] == 6 and k[i] == 6:
            m2, x2, r2 = _node_dynamics(i, 6, 6, yoff, rows, H, F, J, z, dyn)
        else:
            m2, x2, r2 = _node_dynamics(i, v[i], k[i], yoff, rows, H, F, J, z, dyn)
        norm_M += m2
        norm_x += x2
        norm_r += r2
        if kind[i] == RIGID:  # the unit-norm row, exact by construction
            norm_x += s[i] ** 2
            norm_r += s[i] ** 2
            norm_A += 1.0
    for i in range(kind.shape[0]):
        p = parent[i]
        vp = v[p] if p >= 0 else 0
        if v[i] == 6 and vp == 6 and k[i] == 5:
            t2, a2, r2 = _node_rows(i, 6, 5, 6, p, yoff, rows, J, P, rb, z, dyn)
        elif v[i] == 6 and vp == 6 and k[i] == 6:
            t2, a2, r2 = _node_rows(i, 6, 6, 6, p, yoff, rows, J, P, rb, z, dyn)
        else:
            t2, a2, r2 = _node_rows(i, v[i], k[i], vp, p, yoff, rows, J, P, rb, z, dyn)
        res += t2
        norm_A += a2
        norm_r += r2
    for x in range(mx):
        t = _row_dot(x, segs, seg6, z) - xb[x]
        for seg in range(ptr[x], ptr[x + 1]):
            for a in range(6):
                dyn[node[seg], a] += seg6[seg, a] * lam[nx + x]
                norm_A += seg6[seg, a] ** 2
        for e in range(xa_ptr[x], xa_ptr[x + 1]):
            t += Ax[x, xa_col[e]] * lam[xa_col[e]]
            norm_A += Ax[x, xa_col[e]] ** 2
        res += t * t
        norm_r += xb[x] ** 2
    for i in range(kind.shape[0]):
        for a in range(v[i]):
            res += dyn[i, a] ** 2
    for c in range(nx):
        t_x[c] = -Fx[c]
    for e in range(mi.shape[0]):
        t_x[mi[e]] += Mx[mi[e], mj[e]] * lam[mj[e]]
        norm_M += Mx[mi[e], mj[e]] ** 2
    for c in range(nx):
        t = t_x[c]
        for e in range(xc_ptr[c], xc_ptr[c + 1]):
            t += Ax[xc_row[e], c] * lam[nx + xc_row[e]]
        res += t * t
        norm_x += lam[c] ** 2
        norm_r += Fx[c] ** 2
    scale = (math.sqrt(norm_M) + math.sqrt(norm_A)) * math.sqrt(norm_x) + math.sqrt(norm_r) + DIVISION_GUARD
    return math.sqrt(res) / scale


@njit(**OPTIONS)
def motion(q, qd, gen, bshift, LI, LF, LX, WI, WF, WX, mode, drift, general):
    """(status, residual) at one state; on OK, the Work's qdd holds q̈ and its Qc M q̈ − Q.
    gen: the generated function's outputs at (t, q, q̇) — time enters only there; bshift:
    added to b per row of the System (empty for none); LI, LF, LX and WI, WF, WX: the
    Layout and the Work packed (packing.py). ``mode``: CHECKED factors the tree and checks
    the residual; UNCHECKED skips the check (residual 0: a caller that checks the result
    itself, compiled/projection.py); REUSED also keeps the factorization the last call on this Work
    left, for a call with the same M and A (the same q) and another right side; when that
    call was at the same state, at rest (q̇ = 0) with the same forces, and this one's shifts
    leave the unit-norm rows alone (``_shifts_only``: a projection's velocity step), only
    the right side is rebuilt and solved, not the masses and rows (nor, with loop rows, their
    Schur matrix: ``_close_solve`` with the last call's eigenvectors; not for a model with
    extra coordinates or generated right sides). ``drift``: negative for
    a state on the constraint manifold, else its relative drift δ (Engine.relative_drift),
    by which the Schur step of the extra rows follows the drift rule of core/equations.py:
    a direction whose eigenvalue is below (DRIFT_RANK δ)² (or SCHUR_DEPENDENT_RTOL) of the
    largest is rows dependent on the manifold that the drift split, dropped with its part
    of the right side (least squares: no INCONSISTENT); one between that and
    SCHUR_ZERO_RTOL (a singular position near) is the exact rule's to judge
    (NEAR_SINGULAR), as is every stage of a model with kernel nodes, extra rows and no extra
    coordinates whose masses are uneven (``_uneven_masses``: a millimetre four-bar's bar
    inertias): there the Schur eigenvalues, in the mass metric, do not stand for the rows'
    singular values that the drift rule judges. A model with extra coordinates (flexible parts,
    planar bodies, energy-defined parts; rigid bodies beside them or not) keeps a stage only
    where its equilibrated rows certainly have no nearly dependent direction (certify.py,
    judged on the rows alone, whatever the masses), so that the drift rule keeps every one
    and its answer is the plain one. ``general``: RIGID_TREE for
    a Layout of rigid bodies on tree joints only (compiled without the rest), else GENERAL."""
    q, qd, gen = borrowed(q), borrowed(qd), borrowed(gen)  # sliced below; the views carry no count already
    kind, start = view1(LI, LX, LAYOUT.node_kind), view1(LI, LX, LAYOUT.node_q)
    mass, mg, inertia = view1(LF, LX, LAYOUT.node_mass), view2(LF, LX, LAYOUT.node_mg), view3(LF, LX, LAYOUT.node_J)
    v, k, yoff, rows = (view1(LI, LX, LAYOUT.node_v), view1(LI, LX, LAYOUT.node_k), view1(LI, LX, LAYOUT.node_yoff),
                        view1(LI, LX, LAYOUT.node_rows))
    parent, x_coord = view1(LI, LX, LAYOUT.node_parent), view1(LI, LX, LAYOUT.x_coord)
    transport = view1(LI, LX, LAYOUT.node_transport)
    topology = (view1(LI, LX, LAYOUT.order), parent, v, k, yoff, rows, transport)
    joints = (view3(LI, LX, LAYOUT.joint_program), view1(LI, LX, LAYOUT.joint_k), view2(LI, LX, LAYOUT.joint_kinds),
              view2(LI, LX, LAYOUT.joint_start), view3(LF, LX, LAYOUT.joint_s), view4(LF, LX, LAYOUT.joint_R),
              view1(LF, LX, LAYOUT.joint_length), view2(LI, LX, LAYOUT.joint_node))
    xseg_ptr, xseg_node = view1(LI, LX, LAYOUT.xseg_ptr), view1(LI, LX, LAYOUT.xseg_node)
    segs = (xseg_ptr, xseg_node, v, yoff)
    gen_rows = (view1(LI, LX, LAYOUT.gen_arow), view1(LI, LX, LAYOUT.gen_aseg), view1(LI, LX, LAYOUT.gen_acol),
                view1(LI, LX, LAYOUT.gen_brow))
    Qf, Cf, qdd, Qc = view1(WF, WX, WORK.Qf), view1(WF, WX, WORK.Cf), view1(WF, WX, WORK.qdd), view1(WF, WX, WORK.Qc)
    H, F, dyn = view3(WF, WX, WORK.H), view2(WF, WX, WORK.F), view2(WF, WX, WORK.dyn)
    factored = (view3(WF, WX, WORK.HA), view3(WF, WX, WORK.Sn), view3(WF, WX, WORK.Jr), view3(WF, WX, WORK.X),
                view3(WF, WX, WORK.U), view3(WF, WX, WORK.Ninv), view2(WF, WX, WORK.c), view2(WF, WX, WORK.x0),
                view2(WF, WX, WORK.zeta))
    s, nu, Rs = view1(WF, WX, WORK.s), view1(WF, WX, WORK.nu), view4(WF, WX, WORK.Rs)
    J, P, rb, rscale = view2(WF, WX, WORK.J), view2(WF, WX, WORK.P), view1(WF, WX, WORK.rb), view1(WF, WX, WORK.rscale)
    ry, y, z, z0, w = (view1(WF, WX, WORK.ry), view1(WF, WX, WORK.y), view1(WF, WX, WORK.z), view1(WF, WX, WORK.z0),
                       view1(WF, WX, WORK.w))
    scratch = (view3(WF, WX, WORK.V), view3(WF, WX, WORK.R), view2(WF, WX, WORK.Jt), view2(WF, WX, WORK.A),
               view1(WF, WX, WORK.b))
    seg7, seg6, xb, Ax = view2(WF, WX, WORK.seg7), view2(WF, WX, WORK.seg6), view1(WF, WX, WORK.xb), view2(WF, WX, WORK.Ax)
    Mx, Fx, lam = view2(WF, WX, WORK.Mx), view1(WF, WX, WORK.Fx), view1(WF, WX, WORK.lam)
    node_joint, joint_row, quat_row = (view1(LI, LX, LAYOUT.node_joint), view1(LI, LX, LAYOUT.joint_row),
                                       view1(LI, LX, LAYOUT.quat_row))
    patterns = (view1(LI, LX, LAYOUT.xa_ptr), view1(LI, LX, LAYOUT.xa_col), view1(LI, LX, LAYOUT.xc_ptr),
                view1(LI, LX, LAYOUT.xc_row), view1(LI, LX, LAYOUT.gen_mi), view1(LI, LX, LAYOUT.gen_mj))
    band_width = view1(LI, LX, LAYOUT.band_width)

    xscale, xrow_row = view1(WF, WX, WORK.xscale), view1(LI, LX, LAYOUT.xrow_row)
    if mode == REUSED and x_coord.shape[0] + view1(LI, LX, LAYOUT.gen_brow).shape[0] == 0 and \
            _shifts_only(qd, bshift, kind, quat_row):
        _shifted_rows(kind, node_joint, k, rows, joint_row, bshift, rscale, rb, s)
        tree_rhs(v, k, yoff, rows, F, rb, ry)
        _copy(ry, y)
        if general is not None and xb.shape[0]:
            for x in range(xb.shape[0]):  # the loop rows' right sides: their shifts alone, equilibrated
                xb[x] = xscale[x] * bshift[xrow_row[x]]
            solve(topology, factored, y, z0, False)
            status = _close_solve(topology, segs, seg6, factored, Fx, xb, ry, z0, y, w, z, view2(WF, WX, WORK.vectors),
                                  view1(WF, WX, WORK.values), view1(WF, WX, WORK.rhs), lam, 0, xb.shape[0], False,
                                  drift)
            if status != OK:
                return status, 0.0
        else:
            solve(topology, factored, y, z, False)
        _recover(q, kind, start, mass, inertia, yoff, x_coord, nu, s, Rs, z, Qf, Mx, patterns[4], patterns[5], lam, 1.0,
                 qdd, Qc)
        return (OK if _finite(qdd, Qc) else NOT_FINITE), 0.0
    o = generated(gen, view1(LI, LX, LAYOUT.gen_q), view1(LI, LX, LAYOUT.gen_c), view1(LI, LX, LAYOUT.gen_mi),
                  view1(LI, LX, LAYOUT.gen_mj), Qf, Cf, Mx)
    mu = nodes(q, qd, bshift, kind, start, mass, mg, inertia, quat_row, Qf, Cf, H, F, s, nu,
               view1(WF, WX, WORK.q7), Rs)
    gen_mi, gen_mj = view1(LI, LX, LAYOUT.gen_mi), view1(LI, LX, LAYOUT.gen_mj)
    for x in range(x_coord.shape[0]):
        Fx[x] = Qf[x_coord[x]] + Cf[x_coord[x]]
    for e in range(gen_mi.shape[0]):
        mu = max(mu, abs(Mx[gen_mi[e], gen_mj[e]]))
    mu = mu if mu > 0 else 1.0
    divide_masses(mu, H, F, Mx, Fx, gen_mi, gen_mj)
    if drift >= 0.0 and xb.shape[0] and v.shape[0] and not x_coord.shape[0] and _uneven_masses(v, H, Mx):
        return NEAR_SINGULAR, 0.0  # the drift rule's to judge (``drift``)
    tree_rows(q, qd, bshift, kind, start, node_joint, view1(LI, LX, LAYOUT.node_end), parent,
              rows, nu, s, Rs, joints, joint_row, scratch, J, P, rb, rscale, general)
    if general is not None and xb.shape[0]:
        extra_rows(q, qd, gen[o:], bshift, kind, start, nu, s, Rs, joints, view1(LI, LX, LAYOUT.joint_xrow),
                   view2(LI, LX, LAYOUT.joint_xseg), xrow_row, xseg_ptr, xseg_node, gen_rows,
                   patterns[0], patterns[1], scratch, seg7, seg6, xb, xscale, Ax)
        if drift >= 0.0 and x_coord.shape[0] and not band_width.shape[0] and \
                not rows_certified(q, qd, kind, start, node_joint, joints, scratch, quat_row, xseg_ptr, xseg_node, seg7,
                                   xscale, Ax, x_coord):
            return NEAR_SINGULAR, 0.0  # the drift rule's to judge (certify.py)
    transports(q, start, parent, node_joint, view1(LI, LX, LAYOUT.node_end), transport,
               joints[4], Rs, factored[8])
    tree_rhs(v, k, yoff, rows, F, rb, ry)

    if mode != REUSED and factor(topology, H, J, P, factored, view2(WF, WX, WORK.G), view1(WI, WX, WORK.pivot)) >= 0:
        return SINGULAR, 0.0
    _copy(ry, y)
    if general is not None and x_coord.shape[0] + xb.shape[0] > 0:
        solve(topology, factored, y, z0, False)  # _close solves again into z
        if band_width.shape[0]:
            status = _close_banded(Mx, Ax, xb, Fx, lam, patterns, view1(LI, LX, LAYOUT.band_pos), band_width[0],
                                   view3(WF, WX, WORK.band), view2(WF, WX, WORK.bandv), view1(WF, WX, WORK.rhs))
        else:
            status = _close(topology, segs, seg6, factored, Mx, Ax, xb, Fx, ry, z0, y, w, z, view2(WF, WX, WORK.S),
                            view2(WF, WX, WORK.vectors), view1(WF, WX, WORK.values), view1(WF, WX, WORK.rhs), lam,
                            mode == CHECKED, drift)
        if status != OK:
            return status, 0.0
    else:
        solve(topology, factored, y, z, mode == CHECKED)
    _recover(q, kind, start, mass, inertia, yoff, x_coord, nu, s, Rs, z, Qf, Mx, gen_mi, gen_mj, lam, mu, qdd, Qc)
    residual = 0.0
    if mode == CHECKED:
        residual = _residual(topology, kind, segs, seg6, H, F, J, P, rb, s, z, lam, xb, Ax, Mx, Fx, patterns, dyn,
                             view1(WF, WX, WORK.rhs))
    if not _finite(qdd, Qc):
        return NOT_FINITE, residual
    if not residual <= KERNEL_RESIDUAL_MAX:
        return RESIDUAL, residual
    return OK, residual


@njit(cache=True, error_model="numpy", nogil=True)
def motion_rows(q, qd, gen, LI, LF, LX, WI, WF, WX, general, mode, qdd, status):
    """q̈ of each state (row of q, q̇, gen) into qdd and its status into status, ``motion``
    in ``mode`` (CHECKED or UNCHECKED). Releases the GIL: engine.py runs blocks of rows in
    threads, each with its own Work."""
    empty = np.zeros(0)
    qdd_view = view1(WF, WX, WORK.qdd)
    for row in range(q.shape[0]):
        status[row] = motion(q[row], qd[row], gen[row], empty, LI, LF, LX, WI, WF, WX, mode, -1.0, general)[0]
        _copy(qdd_view, qdd[row])


@njit(**OPTIONS)
def motion_rates(q, qd, gen, bshift, LI, LF, LX, WI, WF, WX, mode, drift, general, starts, out):
    """``motion``'s (status, residual), and on OK with ``out`` not empty an integrator's rates:
    out (2n less one entry per entry of ``starts``) ← (q̇, v̇), v̇ being q̈ with the four
    quaternion accelerations of each rigid body whose quaternion starts at an entry of
    ``starts`` replaced by the integrator's three (bodies.velocities; none: v̇ = q̈); else out
    is left as it was. The kernel's one entry from outside compiled code (Engine.motion from
    Python; an integrator's stage and the extra projection through function pointers): each
    entry's cached library holds the whole kernel, and a process loads it once."""
    status, residual = motion(q, qd, gen, bshift, LI, LF, LX, WI, WF, WX, mode, drift, general)
    if status == OK and out.shape[0]:
        n = q.shape[0]
        for c in range(n):
            out[c] = qd[c]
        velocities(q, view1(WF, WX, WORK.qdd), starts, out[n:])
    return status, residual
