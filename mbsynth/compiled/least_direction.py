"""How near a model's rows are to losing rank: σ_min/σ₁ of A, from its entries, in a band.

With each row of A scaled to unit norm, T = A Aᵀ has a unit diagonal and eigenvalues σ_i²;
σ_min² = λ_min(T) is found by inverse iteration (near a singular position λ_min ≪ λ₂, so a
few steps settle it) and λ_max is bounded by T's largest row sum (Gershgorin). Rows couple
in T only through a coordinate they share, so a chain of loops gives a sparse T; ordered by
reverse Cuthill–McKee once (banded.band_order) it is banded, factored by LAPACK's band
Cholesky (pbtrf) and solved in O(m w) per step. The pairs of entries that make each band
entry are found once per structure (``LeastDirection``), so a measure costs a bincount, a
band factorization and STEPS band solves.
"""

import numpy as np
from scipy.linalg import lapack

from .banded import band_order

STEPS = 6  # steps of inverse iteration


class LeastDirection:
    """σ_min/σ₁ of the ``count`` rows of A whose entries lie at (``rows``, ``columns``)
    (an entry may repeat: its values add up)."""

    def __init__(self, rows, columns, count):
        by_row = np.argsort(rows, kind="stable")
        row_ptr = np.searchsorted(rows[by_row], np.arange(count + 1))
        self.position, self.width = band_order(row_ptr, columns[by_row].astype(np.int64), count)
        self.count = count
        # every pair of entries sharing a column: their product adds to T at their rows
        by_column = np.argsort(columns, kind="stable")
        bounds = np.flatnonzero(np.r_[True, np.diff(columns[by_column]) != 0, True])
        first = np.concatenate([np.repeat(by_column[a:b], b - a) for a, b in zip(bounds[:-1], bounds[1:])])
        second = np.concatenate([np.tile(by_column[a:b], b - a) for a, b in zip(bounds[:-1], bounds[1:])])
        i, j = self.position[rows[first]], self.position[rows[second]]
        lower = i >= j  # the lower band in LAPACK's storage: ab[i − j, j] = T[i, j]
        self.first, self.second, self.i, self.j = first[lower], second[lower], i[lower], j[lower]
        self.band_index = (self.i - self.j) * count + self.j
        self.off = self.i != self.j

    def __call__(self, values):
        """(m, weights): m = σ_min/σ₁ of A with its entries ``values``, each row scaled to
        unit norm, and each row's weight |x_r| in its least direction x (unit norm); m = 0
        where T is singular to working precision."""
        count, width, i, j = self.count, self.width, self.i, self.j
        products = values[self.first] * values[self.second]
        diagonal = np.bincount(i[~self.off], weights=products[~self.off], minlength=count)
        scale = 1.0 / np.sqrt(np.maximum(diagonal, np.finfo(float).tiny))
        products *= scale[i] * scale[j]  # T of the rows at unit norm: a unit diagonal
        band = np.bincount(self.band_index, weights=products, minlength=(width + 1) * count).reshape(width + 1, count)
        magnitudes = np.abs(band)  # |T[j + d, j]| at [d, j]: in row j (by symmetry) and in row j + d
        row_sums = magnitudes.sum(axis=0)
        for d in range(1, width + 1):
            row_sums[d:] += magnitudes[d, :count - d]
        factor, info = lapack.dpbtrf(band, lower=1)
        if info != 0:  # not positive definite to working precision
            return 0.0, np.zeros(count)
        x = np.full(count, 1.0 / np.sqrt(count))
        for _ in range(STEPS):
            x = lapack.dpbtrs(factor, x, lower=1)[0]
            x /= np.linalg.norm(x)
        least = 1.0 / float(x @ lapack.dpbtrs(factor, x, lower=1)[0])  # 1/λ_min once x has settled
        return float(np.sqrt(least / row_sums.max())), np.abs(x)[self.position]
