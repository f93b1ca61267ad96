"""kernel._augmented: a mass indefinite only along directions its rows hold (a flexible part's
stiffening term along its torsion) made positive definite by M + AᵀA over the rows on no tree
unknown, with the right side F + Aᵀb: the constrained motion and the multipliers are the
plain KKT solution's of (M, F), to rounding."""

import numpy as np

from mbsynth.compiled.kernel import _augmented

ROWS, COORDINATES = 3, 7


def _kkt(M, A, F, b):
    """(q̈, λ) of M q̈ + Aᵀλ = F, A q̈ = b by a dense solve."""
    m, n = A.shape
    x = np.linalg.solve(np.block([[M, A.T], [A, np.zeros((m, m))]]), np.concatenate([F, b]))
    return x[:n], x[n:]


def test_a_mass_indefinite_along_held_rows_keeps_its_motion_and_multipliers():
    rng = np.random.default_rng(5)
    A = rng.standard_normal((ROWS, COORDINATES))
    A /= np.linalg.norm(A, axis=1)[:, None]  # the kernel's rows are equilibrated to unit norm
    held = A[0] / np.linalg.norm(A[0])
    turn = np.linalg.qr(rng.standard_normal((COORDINATES, COORDINATES)))[0]
    # eigenvalues 0.2–0.4 less 0.8 along the held row: negative there, positive definite once it is added back
    M = turn @ np.diag(rng.uniform(0.2, 0.4, COORDINATES)) @ turn.T - 0.8 * np.outer(held, held)
    F, b = rng.standard_normal(COORDINATES), rng.standard_normal(ROWS)
    assert held @ M @ held < 0.0
    empty = np.zeros(0, dtype=np.int64)
    segments = (np.array([0, 0, 0, 1], dtype=np.int64), empty, empty, empty)  # the last row also acts on a tree node
    out, Fa = np.zeros((COORDINATES, COORDINATES)), np.zeros(COORDINATES)
    _augmented(M, A, b, F, segments, out, Fa)
    np.testing.assert_allclose(out, M + A[:2].T @ A[:2], atol=1e-15)  # the tree's row is left out
    assert np.linalg.eigvalsh(out).min() > 0.0
    qdd, lam = _kkt(M, A, F, b)
    qdd_a, lam_a = _kkt(out, A, Fa, b)
    np.testing.assert_allclose(qdd_a, qdd, atol=1e-12 * np.abs(qdd).max())
    np.testing.assert_allclose(lam_a, lam, atol=1e-12 * np.abs(lam).max())
