"""kernel._plain_schur and tree.cholesky_solve: the rows' Schur matrix solved by its Cholesky
factor only where the factor proves that the eigendecomposition would keep every direction.
Checked against numpy's eigenvalues and solve: the bound 1/‖L⁻¹‖_F² ≤ λ_min, the solution,
and a refusal wherever an eigenvalue lies below SCHUR_ZERO_RTOL · max(λ_max, 1), or off the
manifold the condition exceeds SCHUR_CONDITION_MAX."""

import numpy as np
import pytest

from mbsynth.compiled.kernel import _plain_schur
from mbsynth.compiled.tree import cholesky_solve
from mbsynth.core.tolerances import SCHUR_CONDITION_MAX, SCHUR_ZERO_RTOL

ROWS = 6
ON_MANIFOLD, OFF_MANIFOLD = -1.0, 1e-9  # ``drift`` as kernel.motion passes it


def _schur(eigenvalues, seed):
    """A symmetric matrix with these eigenvalues in a random orthonormal basis."""
    turn = np.linalg.qr(np.random.default_rng(seed).standard_normal((len(eigenvalues),) * 2))[0]
    return turn @ np.diag(eigenvalues) @ turn.T


def _plain(S, drift):
    """(_plain_schur's answer, its factor)."""
    factor, column = np.zeros_like(S), np.zeros(S.shape[0])
    return _plain_schur(S, factor, column, drift), factor


@pytest.mark.parametrize("seed", range(5))
def test_a_well_conditioned_schur_matrix_is_solved_by_its_factor(seed):
    S = _schur(np.geomspace(1e-3, 10.0, ROWS), seed)
    kept = S.copy()
    plain, factor = _plain(S, OFF_MANIFOLD)
    assert plain
    np.testing.assert_array_equal(S, kept)  # the matrix is left for the eigendecomposition
    L = np.tril(factor)
    np.testing.assert_allclose(L @ L.T, S, atol=1e-14 * np.abs(S).max())
    assert 1.0 / np.sum(np.linalg.inv(L) ** 2) <= np.linalg.eigvalsh(S).min() * (1 + 1e-12)
    rhs = np.random.default_rng(seed).standard_normal(ROWS)
    out = np.zeros(ROWS)
    cholesky_solve(factor, rhs, out)
    np.testing.assert_allclose(out, np.linalg.solve(S, rhs), rtol=1e-12)


def test_an_eigenvalue_the_kernel_would_drop_is_left_to_the_eigendecomposition():
    dropped = 0.5 * SCHUR_ZERO_RTOL  # below SCHUR_ZERO_RTOL × max(λ_max, 1) = SCHUR_ZERO_RTOL
    S = _schur([dropped, 0.1, 0.2, 0.3, 0.5, 0.9], 1)
    assert not _plain(S, ON_MANIFOLD)[0]
    assert not _plain(_schur([0.0, 0.1, 0.2, 0.3, 0.5, 0.9], 2), ON_MANIFOLD)[0]  # singular: no factor
    assert not _plain(_schur([-1e-3, 0.1, 0.2, 0.3, 0.5, 0.9], 3), ON_MANIFOLD)[0]  # not semi-definite


def test_off_the_manifold_a_condition_above_the_limit_is_left_to_the_eigendecomposition():
    """κ = 1e9: above SCHUR_CONDITION_MAX, yet no eigenvalue is near zero (λ_min = 1e-3): kept
    on the manifold, refused off it; κ = 1e6 is kept off it as well."""
    ill = _schur([1e-3, 1.0, 2.0, 3.0, 5.0, 1e6], 4)
    assert np.linalg.cond(ill) > SCHUR_CONDITION_MAX
    assert _plain(ill, ON_MANIFOLD)[0]
    assert not _plain(ill, OFF_MANIFOLD)[0]
    assert _plain(_schur([1.0, 2.0, 3.0, 5.0, 10.0, 1e6], 5), OFF_MANIFOLD)[0]
