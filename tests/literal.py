"""(2.14) written out in numpy, for tests that need an answer independent of equations.py."""

import numpy as np


def literal_2_14(M, Q, A, b, C):
    """q̈ of (2.14) with η = 0, unscaled: M̄⁺ [Q + C; b] with M̄ = [(I − A⁺A) M; A] (2.13),
    numpy's pseudo-inverses (singular values below 1e-12 of the largest dropped)."""
    P = np.eye(len(Q)) - np.linalg.pinv(A, rcond=1e-12) @ A
    return np.linalg.pinv(np.vstack([P @ M, A]), rcond=1e-12) @ np.concatenate([Q + C, b])
