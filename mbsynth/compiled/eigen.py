"""Eigendecomposition of a small symmetric matrix by cyclic Jacobi rotations, in numba.

Used for the Schur system of the extra rows (kernel.py), which may be singular: Jacobi
is accurate for small and zero eigenvalues alike, and compiles in a fraction of the time
LAPACK's bindings take in numba.
"""

import math

from numba import njit

from .bodies import OPTIONS
from ..core.tolerances import JACOBI_OFF_RTOL

SWEEPS = 60


@njit(**OPTIONS)
def symmetric_eigen(S, V, values):
    """S = V diag(values) Vᵀ for a symmetric S (overwritten; p × p). Returns the sweeps
    of rotations taken: they stop once the off-diagonal is at rounding (JACOBI_OFF_RTOL), at
    most SWEEPS."""
    p = S.shape[0]
    for i in range(p):
        for j in range(p):
            V[i, j] = 1.0 if i == j else 0.0
    sweeps = 0
    for _ in range(SWEEPS):
        off = total = 0.0
        for i in range(p):
            total += S[i, i] ** 2
            for j in range(i + 1, p):
                off += S[i, j] ** 2
        if off <= JACOBI_OFF_RTOL * (total + 2 * off) or off == 0.0:
            break
        sweeps += 1
        for i in range(p - 1):
            for j in range(i + 1, p):
                if S[i, j] == 0.0:
                    continue
                theta = (S[j, j] - S[i, i]) / (2 * S[i, j])
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                t = -t if theta < 0 else t
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(p):
                    a, b = S[k, i], S[k, j]
                    S[k, i], S[k, j] = c * a - s * b, s * a + c * b
                for k in range(p):
                    a, b = S[i, k], S[j, k]
                    S[i, k], S[j, k] = c * a - s * b, s * a + c * b
                for k in range(p):
                    a, b = V[k, i], V[k, j]
                    V[k, i], V[k, j] = c * a - s * b, s * a + c * b
    for i in range(p):
        values[i] = S[i, i]
    return sweeps
