"""Shared by the flexible-body tests: a steel strip, the analytic
Euler–Bernoulli frequencies, the FE modes of one bending plane, and a point-mass truss
(3 DOFs per node)."""

import numpy as np

from mbsynth.model.flexible.beam import beam
from mbsynth.model.flexible.matrices import fe_model
from mbsynth.model.flexible.reduction import normal_modes

# a steel strip, 2 m long, its stiffer bending plane 2× higher in frequency (Iy = 4 Iz)
STRIP = dict(area=1e-4, Iy=4e-9, Iz=1e-9, J=5e-9, E=2.1e11, nu=0.3, density=7850.0)
LENGTH = 2.0
FREE_FREE = (4.7300407, 7.8532046, 10.9956078)  # βL, cosh βL cos βL = 1
CLAMPED_FREE = (1.8751041, 4.6940911, 7.8547574)  # cosh βL cos βL = −1
PLANES = {"xy": (1, 5), "xz": (2, 4)}  # a plane's DOFs of a beam along x: (uy, θz), (uz, θy)


def strip(elements, **changes):
    """The strip of STRIP along x with ``elements`` elements (``changes`` to beam's arguments)."""
    return beam(LENGTH, elements, **{**STRIP, **changes})


def euler_bernoulli(beta_L, I, E=STRIP["E"], rho=STRIP["density"], A=STRIP["area"], L=LENGTH):
    """ω = (βL)² √(EI / (ρ A L⁴)) (rad/s)."""
    return np.asarray(beta_L) ** 2 * np.sqrt(E * I / (rho * A * L**4))


def plane_share(M, shapes, plane):
    """The part of each column's φᵀMφ in ``plane``'s DOFs (shapes n × k, full DOFs)."""
    n = shapes.shape[0]
    mine = np.concatenate([np.arange(c, n, 6) for c in PLANES[plane]])
    return np.einsum("ik,ik->k", shapes[mine], (M @ shapes)[mine]) / np.einsum("ik,ik->k", shapes, M @ shapes)


def plane_modes(fe, held, plane, count):
    """The ω of the modes of ``fe`` with the DOFs ``held`` fixed whose kinetic energy lies
    mostly (> ½) in ``plane``'s DOFs, lowest first, rigid-body modes (ω below 1e-4 of the
    highest found) left out."""
    keep = np.setdiff1d(np.arange(fe.size), held)
    omega, shapes = normal_modes(fe.mass[keep][:, keep], fe.stiffness[keep][:, keep], count=4 * count + 6)
    full = np.zeros((fe.size, shapes.shape[1]))
    full[keep] = shapes
    return omega[(plane_share(fe.mass, full, plane) > 0.5) & (omega > 1e-4 * omega.max())][:count]


def truss(seed=11):
    """Ten point masses at random places, every pair joined by an axial spring of 1e3 N/m: a
    rigid truss (six rigid-body modes only), its M diagonal."""
    rng = np.random.default_rng(seed)
    x, m = rng.normal(size=(10, 3)), rng.uniform(0.5, 2.0, 10)
    K = np.zeros((30, 30))
    for i, j in zip(*np.triu_indices(10, 1)):
        e = (x[j] - x[i]) / np.linalg.norm(x[j] - x[i])
        for a, b, sign in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
            K[3 * a:3 * a + 3, 3 * b:3 * b + 3] += sign * 1e3 * np.outer(e, e)
    return fe_model(np.diag(np.repeat(m, 3)), K, x)
