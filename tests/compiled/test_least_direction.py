"""The least singular direction of a model's rows from their entries (least_direction.py),
against numpy's SVD of the same rows, each scaled to unit norm."""

import numpy as np
import pytest

from mbsynth.compiled.least_direction import LeastDirection


def chain_rows(count, rng, near=0.0):
    """The entries (rows, columns, values) of a chain of rows, each touching three
    neighbouring columns of count + 1, and the last row moved to within ``near`` of the
    span of the others (0: independent as drawn)."""
    columns = count + 1
    A = np.zeros((count, columns))
    for r in range(count):
        A[r, r:r + 3 if r + 3 <= columns else columns] = rng.uniform(0.5, 2.0, min(3, columns - r))
    if near:
        A[-1] = A[:-1].T @ rng.uniform(-1, 1, count - 1)
        A[-1, -1] += near  # within about ``near`` of dependent: the chain's last column is its own
    rows, cols = np.nonzero(A)
    return rows, cols, A[rows, cols], A


@pytest.mark.parametrize("near", [0.0, 1e-3, 1e-5])
def test_the_measure_and_direction_match_the_svd(near):
    """Near dependence (the iteration settled: λ_min ≪ λ₂), σ_min of the rows at unit norm
    (m times the Gershgorin bound on σ₁ it uses) and the direction's weights as |u_min| of
    the SVD; far from it an upper bound within 1e-3; m at most σ_min/σ₁ there too. An entry
    given as two parts counts as their sum."""
    rng = np.random.default_rng(3)
    rows, cols, values, A = chain_rows(30, rng, near)
    unit = A / np.linalg.norm(A, axis=1)[:, None]
    U, s, _ = np.linalg.svd(unit)
    least = LeastDirection(rows, cols, A.shape[0])
    m, weights = least(values)
    bound = np.abs(unit @ unit.T).sum(axis=1).max()  # Gershgorin: λ_max ≤ the largest row sum
    settled = max(1e-6, 10 * np.finfo(float).eps / s[-1] ** 2)  # T's rounding, relative to λ_min
    assert m * np.sqrt(bound) == pytest.approx(s[-1], rel=settled if near else 1e-3)
    assert m * np.sqrt(bound) >= s[-1] * (1 - settled)
    assert m <= s[-1] / s[0] * (1 + 1e-3)
    if near:
        np.testing.assert_allclose(weights, np.abs(U[:, -1]), atol=1e-6)
    split = LeastDirection(np.r_[rows, rows[:1]], np.r_[cols, cols[:1]], A.shape[0])
    halves = np.r_[values, values[:1] / 2]
    halves[0] /= 2
    assert split(halves)[0] == pytest.approx(m, rel=1e-12)


def test_dependent_rows_measure_zero():
    """Rows dependent to working precision: m at rounding's level (T = A Aᵀ squares the
    condition: σ_min is resolved down to about √ε σ₁)."""
    rng = np.random.default_rng(5)
    rows, cols, values, A = chain_rows(12, rng, near=0.0)
    A[-1] = A[:-1].T @ rng.uniform(-1, 1, 11)
    rows, cols = np.nonzero(A)
    m, weights = LeastDirection(rows, cols, A.shape[0])(A[rows, cols])
    assert m < 1e-7
