"""mb.equilibrium of a mechanism with a flexible body (statics.py): the flexible slider-crank
(models/flexible/slider_crank.yaml) comes to rest with its crank hanging, its forces balanced
by the constraints' (Q + Aᵀλ = 0), and its rod sagging under its weight as the closed-form
simply supported beam."""

from pathlib import Path

import numpy as np

import mbsynth as mb
from mbsynth.core.kinematics import quaternion_matrix

MODEL = Path(__file__).resolve().parents[2] / "models" / "flexible" / "slider_crank.yaml"
E, DENSITY = 2e9, 7500.0  # the model file's rod


def test_the_flexible_slider_crank_rests_with_its_rod_sagging_as_a_beam():
    """From the model's start (crank up, rod straight: not at rest) the search comes down to
    the crank hanging straight down (its quaternion a half turn about x; the slider at
    √(l2² − ya² − (za − l1)²)), where the constraints hold (1e-10) and the applied forces
    are the constraint forces' (‖Q + Aᵀλ‖ ≤ 1e-6 ‖Q‖, λ by least squares: the search stops at
    |q̈| ≤ 1e-10 (1 + max |K|), and the rod's stiffest modes put ω² ≈ 1e7 in K; actual 1.1e-7).
    The rod, pinned at
    B (ball) and C (the cross turns its spin, which nothing else holds), sags at its middle
    node by the simply supported beam's 5 w L⁴/(384 EI) under w = ρA g sin(angle of BC to the
    vertical), to 1 % (the reduction's two fixed-interface modes: actual +0.18 %)."""
    system = mb.load(MODEL)
    q = mb.equilibrium(system)
    names, p = system.coordinates, system.parameters
    at = {name: q[names.index(name)] for name in names}
    np.testing.assert_allclose(abs(at["crank.qx"]), 1.0, atol=1e-9)
    slider = np.sqrt(p["l2"] ** 2 - p["ya"] ** 2 - (p["za"] - p["l1"]) ** 2)
    np.testing.assert_allclose(at["slider.x"], slider, rtol=1e-3)  # the rod's sag shortens BC a little

    zero = np.zeros(system.n)
    phi, _ = system.constraint_residuals(0.0, q, zero)
    assert np.abs(phi).max() < 1e-10
    arrays = system.evaluate(0.0, q, zero)
    A = arrays.A.toarray() if hasattr(arrays.A, "toarray") else np.asarray(arrays.A)
    Q = np.asarray(arrays.Q, dtype=float)
    lam = np.linalg.lstsq(A.T, -Q, rcond=None)[0]
    assert np.linalg.norm(Q + A.T @ lam) <= 1e-6 * np.linalg.norm(Q)

    rod = next(part for part in system.parts if part.name == "rod")
    start = names.index("rod.x")
    own = q[start:start + len(rod.coordinates)]
    basis, nodes = rod.reduction.basis, rod.reduction.fe.nodes
    B, middle, C = (own[:3] + quaternion_matrix(own[3:7]) @ (nodes[j] + basis[rod.reduction.node_rows(j)[:3]] @ own[7:])
                    for j in (0, 4, 8))
    chord = (C - B) / np.linalg.norm(C - B)
    sag = np.linalg.norm(np.cross(middle - B, chord))
    w = DENSITY * np.pi * p["d"] ** 2 / 4 * p["g"] * np.linalg.norm(np.cross([0.0, 0.0, 1.0], chord))
    beam = 5 * w * p["l2"] ** 4 / (384 * E * np.pi * p["d"] ** 4 / 64)
    np.testing.assert_allclose(sag, beam, rtol=1e-2)
