"""(2.14) written out in numpy, for tests that need an answer independent of equations.py.

Pseudo-inverses drop singular values below RCOND of the largest: above rounding (a matrix of
rank r < n computed in floats keeps n − r singular values of about n ε of the largest, which
numpy's default cut of 1e-15 may keep, and whose inverses would swamp the answer) and far
below the ratios a model may legitimately have (masses 1e-9 of each other)."""

import numpy as np

RCOND = 1e-12


def augmented(M, A):
    """(M̄, P) of (2.13): M̄ = [P M; A] with P = I − A⁺A."""
    P = np.eye(M.shape[0]) - np.linalg.pinv(A, rcond=RCOND) @ A
    return np.vstack([P @ M, A]), P


def literal_2_14(M, Q, A, b, C):
    """q̈ of (2.14) with η = 0, unscaled: M̄⁺ [Q + C; b] (M̄ of (2.13), ``augmented``)."""
    Mbar, _ = augmented(M, A)
    return np.linalg.pinv(Mbar, rcond=RCOND) @ np.concatenate([Q + C, b])
