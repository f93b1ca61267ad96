"""A banded symmetric positive definite system, in numba: the Schur matrix of a large model
of extra coordinates (kernel.py's ``_close_banded``).

Rows of A couple in S = A_x M_x⁻¹ A_xᵀ only through a coordinate they share (M_x diagonal),
so a chain of loops (the N-four-bar) gives a sparse S. Ordered once per structure by reverse
Cuthill–McKee (``band_order``, at layout time), S is banded, width w, and its Cholesky factor
keeps the band: O(m w²) to factor and O(m w) per solve, where the dense Schur step costs
O(m³). Storage: ``band[i, d]`` = S[i, i − d] (d = 0 … w), the lower band by rows, factored in
place into L (S = L Lᵀ).

``inverse_norm1`` estimates ‖S⁻¹‖₁ by Hager's method with Higham's extra vector (LAPACK's
lacon): a lower bound, exact in most cases and within a small factor in the rest, from a few
solves; ``inverse_norm1_exact`` computes it column by column (m solves), for the cases the
estimate leaves open.
"""

import math

import numpy as np
from numba import njit

from .bodies import OPTIONS

ESTIMATE_STEPS = 5  # Hager's iterations at most


def band_order(row_ptr, row_col, count):
    """(position of each of ``count`` rows in the banded order, the band's width w) for the
    rows' pattern (CSR: row r touches the columns row_col[row_ptr[r]:row_ptr[r + 1]]): two
    rows are coupled where they share a column; reverse Cuthill–McKee on that graph."""
    import scipy.sparse
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    columns = int(row_col.max()) + 1 if row_col.size else 0
    pattern = scipy.sparse.csr_matrix((np.ones(row_col.size), row_col, row_ptr), shape=(count, max(columns, 1)))
    coupled = (pattern @ pattern.T).tocsr()
    order = reverse_cuthill_mckee(coupled, symmetric_mode=True)
    position = np.empty(count, dtype=np.int64)
    position[order] = np.arange(count)
    rows, cols = coupled.nonzero()
    width = int(np.abs(position[rows] - position[cols]).max(initial=0))
    return position, width


@njit(**OPTIONS)
def cholesky(band, width):
    """L of S = L Lᵀ in place (``band``: S's lower band, module docstring). False where a
    pivot is not positive: S is not positive definite to working precision."""
    m = band.shape[0]
    for j in range(m):
        total = band[j, 0]
        for k in range(max(0, j - width), j):
            total -= band[j, j - k] ** 2
        if not total > 0.0:
            return False
        pivot = math.sqrt(total)
        band[j, 0] = pivot
        for i in range(j + 1, min(m, j + width + 1)):
            total = band[i, i - j]
            for k in range(max(0, i - width), j):
                total -= band[i, i - k] * band[j, j - k]
            band[i, i - j] = total / pivot
    return True


@njit(**OPTIONS)
def solve(band, width, x):
    """x ← S⁻¹ x with S = L Lᵀ factored by ``cholesky``."""
    m = band.shape[0]
    for i in range(m):
        total = x[i]
        for k in range(max(0, i - width), i):
            total -= band[i, i - k] * x[k]
        x[i] = total / band[i, 0]
    for i in range(m - 1, -1, -1):
        total = x[i]
        for k in range(i + 1, min(m, i + width + 1)):
            total -= band[k, k - i] * x[k]
        x[i] = total / band[i, 0]


@njit(**OPTIONS)
def norm1(band, width, sums):
    """‖S‖₁ of the symmetric S whose lower band is ``band`` (before it is factored); sums: work (m)."""
    m = band.shape[0]
    sums[:] = 0.0
    for i in range(m):
        for d in range(min(i, width) + 1):
            a = abs(band[i, d])
            sums[i] += a
            if d > 0:
                sums[i - d] += a
    return sums.max() if m else 0.0


@njit(**OPTIONS)
def inverse_norm1(band, width, y, z):
    """An estimate of ‖S⁻¹‖₁ (S factored by ``cholesky``; S⁻¹ symmetric), from below: Hager's
    iteration (x the uniform vector, then e_j), then Higham's alternating vector. y, z: work (m)."""
    m = band.shape[0]
    if m == 0:
        return 0.0
    estimate, j = 0.0, -1  # x = e_j, or uniform where j < 0
    for _ in range(ESTIMATE_STEPS):
        y[:] = 0.0
        if j < 0:
            y[:] = 1.0 / m
        else:
            y[j] = 1.0
        solve(band, width, y)  # y = S⁻¹ x
        size = 0.0
        for i in range(m):
            size += abs(y[i])
            z[i] = 1.0 if y[i] >= 0.0 else -1.0
        estimate = max(estimate, size)
        solve(band, width, z)  # z = S⁻ᵀ sign(y)
        best, inner = 0, 0.0
        for i in range(m):
            if abs(z[i]) > abs(z[best]):
                best = i
            inner += z[i] / m
        if abs(z[best]) <= (inner if j < 0 else z[j]) or best == j:
            break
        j = best
    for i in range(m):
        y[i] = (-1.0) ** i * (1.0 + i / max(m - 1, 1))
    solve(band, width, y)
    size = 0.0
    for i in range(m):
        size += abs(y[i])
    return max(estimate, 2.0 * size / (3.0 * m))


@njit(**OPTIONS)
def inverse_norm1_exact(band, width, y):
    """‖S⁻¹‖₁ (S factored by ``cholesky``), column by column: m solves, O(m² w). y: work (m)."""
    m = band.shape[0]
    largest = 0.0
    for j in range(m):
        y[:] = 0.0
        y[j] = 1.0
        solve(band, width, y)
        total = 0.0
        for i in range(m):
            total += abs(y[i])
        largest = max(largest, total)
    return largest
