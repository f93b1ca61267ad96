"""The banded symmetric positive definite solver of the large Schur step (banded.py), against
numpy's dense linear algebra on random banded matrices, and the band order against the
bandwidth its pattern implies."""

import numpy as np
import pytest

from mbsynth.compiled import banded


def banded_spd(m, half, rng, shift):
    """A random symmetric positive definite matrix of half-bandwidth 2·half (B Bᵀ + shift I,
    B lower triangular of bandwidth half), and its lower band in banded.py's storage."""
    B = np.zeros((m, m))
    for i in range(m):
        for j in range(max(0, i - half), i + 1):
            B[i, j] = rng.normal()
    S = B @ B.T + shift * np.eye(m)
    width = 2 * half
    band = np.zeros((m, width + 1))
    for i in range(m):
        for d in range(min(i, width) + 1):
            band[i, d] = S[i, i - d]
    return S, band, width


@pytest.mark.parametrize("m, half, shift", [(1, 0, 1.0), (40, 2, 1e-3), (120, 5, 1e-6)])
def test_the_band_solver_gives_numpys_answers(m, half, shift):
    rng = np.random.default_rng(m)
    S, band, width = banded_spd(m, half, rng, shift)
    work = np.zeros(m)
    assert banded.norm1(band, width, work) == pytest.approx(np.abs(S).sum(axis=0).max(), rel=1e-14)
    assert banded.cholesky(band, width)
    x = rng.normal(size=m)
    y = x.copy()
    banded.solve(band, width, y)
    assert np.abs(y - np.linalg.solve(S, x)).max() <= 1e-9 * np.abs(y).max()
    exact = np.abs(np.linalg.inv(S)).sum(axis=0).max()
    estimate = banded.inverse_norm1(band, width, np.zeros(m), np.zeros(m))
    assert exact / 3 <= estimate <= exact * (1 + 1e-9)  # a lower bound, within Hager's usual factor
    assert banded.inverse_norm1_exact(band, width, np.zeros(m)) == pytest.approx(exact, rel=1e-8)


def test_an_indefinite_matrix_is_refused():
    """A symmetric matrix with a negative eigenvalue: ``cholesky`` reports it (the kernel then
    leaves the state to the exact treatment)."""
    S = np.array([[1.0, 2.0], [2.0, 1.0]])
    band = np.array([[S[0, 0], 0.0], [S[1, 1], S[1, 0]]])
    assert not banded.cholesky(band, 1)


def test_the_band_order_keeps_coupled_rows_within_its_width():
    """Rows of a chain (row r touches columns r and r + 1) given in a scrambled order: reverse
    Cuthill–McKee finds a width of 1, and every pair of rows that share a column lies within it."""
    rng = np.random.default_rng(2)
    count = 30
    label = rng.permutation(count)  # row label[r] is the chain's r-th
    columns = {label[r]: [r, r + 1] for r in range(count)}
    ptr = np.cumsum([0] + [len(columns[r]) for r in range(count)])
    col = np.array([c for r in range(count) for c in columns[r]])
    position, width = banded.band_order(ptr, col, count)
    assert width == 1
    assert sorted(position.tolist()) == list(range(count))
    for r in range(count - 1):
        assert abs(position[label[r]] - position[label[r + 1]]) <= width
