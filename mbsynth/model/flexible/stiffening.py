"""Centrifugal stiffening of a reduced FE model on a spinning floating frame.

The linear displacement field u = Φη misses the second-order shortening u₂(η) of a bent
member (a beam's ends draw together by ½∫w'²). Where the part spins, the centrifugal
forces f(ω) = −M (ω × (ω × x)) work through it: the kinetic energy gains

    T₂ = ∫ f(ω)·u₂ = −½ ηᵀ Φᵀ K_G(N(ω)) Φ η,

N(ω) the member forces of the static state under f(ω) with the reference node held (the
quasi-static stress of the spin), K_G the FE geometric stiffness of those forces. f is
quadratic in ω: ω × (ω × x) = Σ_ab ω_a ω_b (E_ab − δ_ab I) x, six load cases (aa and
a < b), so

    T₂ = −½ Σ_ab ω_a ω_b ηᵀ S_ab η,   S_aa = Φᵀ K_G(aa) Φ,  S_ab = S_ba = ½ Φᵀ K_G(ab) Φ,

an ω–ω entry of the part's quasi-velocity mass matrix M(η) quadratic in η
(invariants.py). Being part of T, it keeps energy and momenta conserved and gives the
stiffening −∂T₂/∂η = +K_G η that a beam spun past its first bending frequency needs: without
it the linear theory's centrifugal softening makes such a beam diverge (Kane, Ryan and
Banerjee 1987).
"""

import numpy as np
import scipy.sparse.linalg

from ...core.errors import ModelError

LOAD_CASES = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))  # the pairs ab of ω_a ω_b


def centrifugal_stiffening(reduction, stress_stiffness):
    """S (3 × 3 × r × r) of the module's T₂ for a Reduction with a held reference node
    (Craig–Bampton, ``Reduction.hold``); ``stress_stiffness(u)``: the FE model's geometric
    stiffness at the member forces of nodal displacements u (beam.stress_stiffness)."""
    fe = reduction.fe
    if not reduction.held:
        raise ModelError(f"{fe.source}: centrifugal stiffening needs a reference node held at the part's frame "
                         f"(a Craig–Bampton reduction); this {reduction.method} reduction holds none")
    held = np.concatenate([fe.node_dofs(j) for j in reduction.held])
    free = np.setdiff1d(np.arange(fe.size), held)
    K = fe.stiffness.tocsc()
    static = scipy.sparse.linalg.splu(K[free][:, free].tocsc())
    Phi = np.asarray(reduction.basis, float)
    translation = fe.node_dofs(0)[:3][None, :] + fe.dofs_per_node * np.arange(len(fe.nodes))[:, None]
    S = np.zeros((3, 3, reduction.size, reduction.size))
    for a, b in LOAD_CASES:
        C = -np.eye(3) * (a == b)
        C[a, b] += 1.0
        C[b, a] += a != b
        field = np.zeros(fe.size)
        field[translation] = fe.nodes @ C.T  # node j's acceleration per ω_a ω_b: C x_j
        u = np.zeros(fe.size)
        u[free] = static.solve(-(fe.mass @ field)[free])
        projected = Phi.T @ (stress_stiffness(u) @ Phi)
        S[a, b] = S[b, a] = (projected + projected.T) / (2 if a == b else 4)
    return S
