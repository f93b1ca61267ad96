"""eigen.symmetric_eigen (cyclic Jacobi) against numpy's eigvalsh: eigenvalues to rounding, V
orthonormal, V diag Vᵀ = S; and its sweeps stop once the off-diagonal is at rounding, also
where eigenvalues repeat, there the rotations cannot push it lower (such matrices ran all
SWEEPS under a bound below rounding: the Bennett linkage's Schur matrix, 60 sweeps at every
evaluation)."""

import numpy as np
import pytest

from mbsynth.compiled.eigen import SWEEPS, symmetric_eigen

EPS = np.finfo(float).eps
# spectra with repeated (and zero) eigenvalues, as dependent rows give a Schur matrix
REPEATED = ([0.0, 0.0, 0.0, 1.0, 2.0], [0.0, 1.0, 1.0, 2.0, 2.0], [1.0, 1.0, 1.0, 2.0, 3.0], [0.0, 0.0, 1.0, 1.0, 2.0])
SWEEPS_NEEDED = 10  # Jacobi converges quadratically: a 5 × 5 matrix takes about six sweeps


def _matrix(spectrum, seed):
    turn = np.linalg.qr(np.random.default_rng(seed).standard_normal((len(spectrum),) * 2))[0]
    return turn @ np.diag(spectrum) @ turn.T


@pytest.mark.parametrize("spectrum", REPEATED)
@pytest.mark.parametrize("seed", range(12))
def test_eigenvalues_to_rounding_in_a_few_sweeps(spectrum, seed):
    S = _matrix(spectrum, seed)
    work, V, values = S.copy(), np.empty(S.shape), np.empty(len(spectrum))
    sweeps = symmetric_eigen(work, V, values)
    scale = np.linalg.norm(S)
    np.testing.assert_allclose(np.sort(values), np.linalg.eigvalsh(S), rtol=0, atol=8 * EPS * scale)
    np.testing.assert_allclose(V.T @ V, np.eye(len(spectrum)), rtol=0, atol=8 * EPS)
    np.testing.assert_allclose(V @ np.diag(values) @ V.T, S, rtol=0, atol=8 * EPS * scale)
    assert sweeps <= SWEEPS_NEEDED < SWEEPS


def test_the_matrices_include_ones_whose_off_diagonal_stalls_at_rounding():
    """Some of the matrices above end with an off-diagonal above 1e-18 of the matrix (the
    former bound, below rounding, which they could not meet: they ran all SWEEPS): the test
    above holds cases that a bound below rounding fails."""
    stalled = 0
    for spectrum in REPEATED:
        for seed in range(12):
            S = _matrix(spectrum, seed)
            scale = np.linalg.norm(S)
            symmetric_eigen(S, np.empty(S.shape), np.empty(len(spectrum)))  # S left diagonal to rounding
            stalled += np.linalg.norm(np.triu(S, 1)) > 1e-18 * scale
    assert stalled > 0
