"""The rotating uniform Euler–Bernoulli cantilever with zero hub radius, by Rayleigh–Ritz:
the reference of models/flexible/rotating_blade.yaml's frequencies (its beam's numbers).

The transverse deflection w(ξ), ξ = x/L, in the power basis ξ², …, ξ^(TERMS+1), with
T = ½ ∫ ẇ² (ρA L) and U = ½ ∫ w''² (EI/L³) + ½ ∫ N w'² (1/L), N = ½ ρAΩ²L²(1 − ξ²) the
centrifugal tension; in the rotation plane (lead-lag) the centrifugal force's component
along w adds −½ ρAΩ² ∫ w². In λ = Ω/√(EI/ρAL⁴) the lowest frequency converges to 1e-11
in the basis size."""

import numpy as np
import scipy.linalg

LENGTH, LINE_MASS = 10.0, 3000 * 4e-4           # the model file's beam
EI = {"flap": 7e10 * 2e-7, "lag": 7e10 * 8e-7}  # about the section's y axis (out of plane), z (in plane)
TERMS = 10  # the basis size


def reference(omega, plane):
    """The lowest frequency (rad/s) of the rotating cantilever at the spin rate ``omega``, in
    ``plane`` "flap" or "lag" (module docstring)."""
    scale = np.sqrt(EI[plane] / (LINE_MASS * LENGTH ** 4))
    lam = omega / scale
    p = np.arange(2, TERMS + 2, dtype=float)
    P, Q = np.meshgrid(p, p, indexing="ij")
    bending = P * Q * (P - 1) * (Q - 1) / (P + Q - 3)
    tension = P * Q * (1 / (P + Q - 1) - 1 / (P + Q + 1)) / 2
    mass = 1 / (P + Q + 1)
    K = bending + lam ** 2 * (tension - (mass if plane == "lag" else 0))
    return scale * np.sqrt(scipy.linalg.eigh(K, mass, eigvals_only=True)[0])
