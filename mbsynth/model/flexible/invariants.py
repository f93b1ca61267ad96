"""The inertia invariants of a reduced FE model in the floating frame of reference (FFRF):
constant matrices computed once, from which a flexible part's mass matrix, quadratic
velocity forces and gravity follow at any state in O(r²) work, r modes (Shabana,
*Dynamics of Multibody Systems*, ch. 5, for FE models given by their mass matrix).

Kinematics. A floating frame at R (world) turned by A (body → world), with V = AᵀṘ and ω
(body components) its velocities, carries the nodal DOFs u = Φη (``basis`` Φ, n × r, of a
reduction) measured from the nodes' places x (translations at x_j, rotations at 0). In
the frame's components the DOFs move with

    w = Γ(η) (V, ω) + Φ η̇,   Γ(η): node j's translation rows [I, −[x_j + u_j]×], rotation rows [0, I],

and T = ½ wᵀ M w with the FE mass matrix M (the linear theory's rotations: a section turns
with ω + θ̇_j). In the quasi-velocities ν = (V, ω, η̇), T = ½ νᵀ M(η) ν with

    M(η) = G(η)ᵀ M G(η),  G(η) = [Γ(η), Φ] = S P(η),

S = [Γ_t, Γ_r(0), Ξ_1 … Ξ_r, Φ] (Ξ_k: −[φ_k at node j]× in the translation rows) and
P(η) the (6 + 4r) × (6 + r) matrix that sums Γ_r(0) + Σ η_k Ξ_k: the invariants are the
one Gram matrix W = Sᵀ M S, M(η) = P(η)ᵀ W P(η) exactly (no lumping of M).

Motion (Kirchhoff's equations for the frame, Lagrange's for η), with p = M(η) ν:

    M(η) ν̇ = h(η, ν) + F,   h = −Ṁ ν − (ω × p_V,  ω × p_ω + V × p_V,  −∂T/∂η),

F the generalized forces in the same velocities: gravity (``gravity``), elastic −K_r η on
η (K_r the reduction's stiffness), joint and applied loads by virtual power. νᵀh = −½νᵀṀν,
so T + ½ηᵀK_rη is conserved when F is elastic only; so are A p_V and R × A p_V + A p_ω.
Gravity is the exact force of the potential −gᵀ(m R + A s(η)), s(η) = Γ_tᵀ M (x + Φη) the
first moment of mass about the frame's origin (Γ_t: unit translations of every node).
Mapping ν to a part's coordinates (a quaternion's rates, ω = 2E(u)u̇) is the part's.

With Craig–Bampton's constraint modes, Φ holds the rigid-body motion too: a part pins
the frame to it (reference conditions: ``Reduction.hold(node)``, an interface node held at
the frame), or takes free-interface modes without rigid-body ones.
"""

from dataclasses import dataclass

import numpy as np

from ...core.errors import ModelError


@dataclass(frozen=True, eq=False)
class Invariants:
    """``gram`` W = Sᵀ M S ((6 + 4r) square) of a reduced model with r modes and its
    undeformed ``first_moment`` Γ_tᵀ M x; ``mass``, ``quadratic_velocity``, ``gravity`` and
    ``kinetic_energy`` at a state (η, ν)."""

    gram: np.ndarray
    first_moment: np.ndarray
    modes: int

    def _P(self, eta):
        r = self.modes
        P = np.zeros((6 + 4 * r, 6 + r))
        P[:6, :6] = np.eye(6)
        P[6:6 + 3 * r, 3:6] = np.kron(eta[:, None], np.eye(3))
        P[6 + 3 * r:, 6:] = np.eye(r)
        return P

    def _check(self, eta, nu=None):
        eta = np.asarray(eta, dtype=float)
        if eta.shape != (self.modes,):
            raise ModelError(f"FFRF invariants: η has shape {eta.shape}, the reduction has {self.modes} coordinates")
        if nu is not None and np.shape(nu) != (6 + self.modes,):
            raise ModelError(f"FFRF invariants: ν has shape {np.shape(nu)}, expected ({6 + self.modes},): V, ω, η̇")
        return eta

    def mass(self, eta):
        """M(η), (6 + r) square, for ν = (V, ω, η̇)."""
        P = self._P(self._check(eta))
        return P.T @ self.gram @ P

    def kinetic_energy(self, eta, nu):
        nu = np.asarray(nu, float)
        return 0.5 * nu @ self.mass(eta) @ nu

    def quadratic_velocity(self, eta, nu):
        """h(η, ν) = −Ṁν − (ω × p_V, ω × p_ω + V × p_V, −∂T/∂η): M(η) ν̇ = h + F."""
        eta = self._check(eta, nu)
        nu = np.asarray(nu, float)
        r = self.modes
        P = self._P(eta)
        p = P.T @ self.gram @ (P @ nu)
        V, omega, eta_dot = nu[:3], nu[3:6], nu[6:]
        Y = (self.gram[6:6 + 3 * r] @ P).reshape(r, 3, 6 + r)  # ∂M/∂η_k = Z_k + Z_kᵀ, Z_k's rows 3:6 = Y_k
        Y_nu = Y @ nu  # r × 3
        M_dot_nu = np.einsum("k,kij,i->j", eta_dot, Y, omega)
        M_dot_nu[3:6] += eta_dot @ Y_nu
        h = -M_dot_nu
        h[:3] -= np.cross(omega, p[:3])
        h[3:6] -= np.cross(omega, p[3:6]) + np.cross(V, p[:3])
        h[6:] += Y_nu @ omega  # ∂T/∂η_k = ωᵀ Y_k ν
        return h

    def first_moment_at(self, eta):
        """s(η) = Γ_tᵀ M (x + Φη): mass times the centre of mass, from the frame's origin."""
        eta = self._check(eta)
        return self.first_moment + self.gram[:3, 6 + 3 * self.modes:] @ eta

    def gravity(self, eta, g_body):
        """The generalized force of a uniform field g (its frame components Aᵀg = a), for ν:
        (m a, s(η) × a, Φᵀ M Γ_t a)."""
        a = np.asarray(g_body, float)
        r = self.modes
        return np.concatenate([self.gram[0, 0] * a, np.cross(self.first_moment_at(eta), a),
                               self.gram[6 + 3 * r:, :3] @ a])


def invariants(reduction):
    """The Invariants of a Reduction (reduction.py): its FE model's mass matrix and nodes,
    and its basis (r = the reduction's size). Nodes of 3 DOFs (solids) have no rotation rows."""
    fe, Phi = reduction.fe, np.asarray(reduction.basis, float)
    n, r, d = fe.size, Phi.shape[1], fe.dofs_per_node
    translation = (np.arange(n) % d) < 3
    S = np.zeros((n, 6 + 4 * r))
    S[:, :6] = rigid_body_modes(fe)
    for k in range(r):
        # Ξ_k: the translation rows of node j hold −[φ_k,j]×, that is ω ↦ ω × φ_k,j
        S[translation, 6 + 3 * k:9 + 3 * k] = _cross_rows(Phi[translation, k].reshape(-1, 3))
    S[:, 6 + 3 * r:] = Phi
    W = S.T @ (fe.mass @ S)
    places = np.zeros(n)
    places[translation] = fe.nodes.ravel()
    return Invariants((W + W.T) / 2, S[:, :3].T @ (fe.mass @ places), r)


def rigid_body_modes(fe):
    """Γ(0), n × 6: the nodal DOFs of a unit translation and rotation about the origin of
    the nodes' frame (translation rows [I, −[x_j]×], rotation rows [0, I])."""
    n, d = fe.size, fe.dofs_per_node
    G = np.zeros((n, 6))
    rows = np.arange(len(fe.nodes)) * d
    for c in range(3):
        G[rows + c, c] = 1.0
        if d == 6:
            G[rows + 3 + c, 3 + c] = 1.0
    G[np.add.outer(rows, np.arange(3)).ravel(), 3:] = _cross_rows(fe.nodes)
    return G


def _cross_rows(points):
    """The stacked −[x_j]× (3 rows per point): ω ↦ ω × x_j."""
    x, y, z = points.T
    zero = np.zeros_like(x)
    blocks = np.stack([np.stack([zero, z, -y], -1), np.stack([-z, zero, x], -1), np.stack([y, -x, zero], -1)], 1)
    return blocks.reshape(-1, 3)
