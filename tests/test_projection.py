"""projection._correction: the least-norm step of a sparse J, checked against dense least
squares (numpy's SVD-based lstsq, an independent computation)."""

import numpy as np
import scipy.sparse

from mbsynth.projection import _correction

RNG = np.random.default_rng(3)


def tree_rows(count, width=5):
    """Rows like a chain's joints: each block of ``width`` rows touches two neighbouring bodies."""
    J = scipy.sparse.lil_matrix((width * count, 7 * count))
    for i in range(count):
        J[width * i:width * (i + 1), 7 * i:7 * (i + 1)] = RNG.normal(size=(width, 7))
        if i:
            J[width * i:width * (i + 1), 7 * (i - 1):7 * i] = RNG.normal(size=(width, 7))
    return J.tocsr()


def test_independent_rows_give_the_least_norm_step():
    J = tree_rows(40)
    r = RNG.normal(size=J.shape[0])
    step = _correction(J, r)
    expected = np.linalg.lstsq(J.toarray(), r, rcond=None)[0]
    assert np.linalg.norm(step - expected) < 1e-10 * np.linalg.norm(expected)


def test_dependent_rows_still_give_the_least_norm_step():
    J = tree_rows(10)
    J = scipy.sparse.vstack([J, J[3] + 2 * J[17]]).tocsr()  # a redundant row, as a planar loop in 3D has
    r = J @ RNG.normal(size=J.shape[1])  # consistent right side
    step = _correction(J, r)
    expected = np.linalg.lstsq(J.toarray(), r, rcond=1e-12)[0]
    assert np.linalg.norm(step - expected) < 1e-9 * np.linalg.norm(expected)
    assert np.linalg.norm(J @ step - r) < 1e-9 * np.linalg.norm(r)
