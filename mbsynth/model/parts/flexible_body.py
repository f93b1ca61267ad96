"""A flexible body in the floating frame of reference: coordinates x, y, z (the
frame's origin in the world), the unit quaternion qw, qx, qy, qz of its axes (as a rigid
body, with the same unit-norm row) and the amplitudes eta1 … etar of a reduced FE model
(model/flexible/reduction.py), u = Φ η the nodal DOFs in the frame's axes.

M(q) and Q(q, q̇) are sympy expressions of the part's coordinates written with the reduced
model's invariants as numbers (model/flexible/invariants.py): with ν = (V, ω, η̇) = B q̇,
B = blockdiag(Aᵀ, 2E(u), I), the invariants' M(η) ν̇ = h + F gives

    M_q = Bᵀ M(η) B,   Q_q = Bᵀ (h + F + M(η) (ω × V, 0, 0)),

(Ḃq̇ = (−ω × V, 0, 0) since E(u̇)u̇ = 0), F = gravity (exact: the first moment s(η)),
−K_r η and −D η̇ on η. M_q keeps the rigid body's null direction u (closed by the unit-norm
row). Being ordinary sympy M and Q, the part is evaluated, linearized (complex step) and
compiled as any other part; its size grows as r², so it is meant for few modes (tens).
With ``stiffening`` S (model/flexible/stiffening.py), M(η)'s ω–ω block loses Σ ω_a ω_b ηᵀ
S_ab η: the centrifugal stiffening of a spinning part, as a term of its kinetic energy.

Frames sit at FE nodes: node j at x_j + u_j(η) in the part's axes, turned by the node's
elastic rotation θ_j(η) (its rotation DOFs; none for 3-DOF nodes) through the Cayley map
(1 − |θ|²/4) I + ½θθᵀ + [θ]× over 1 + |θ|²/4 — orthogonal, and the linear theory's
I + [θ]× to first order — so joints and forces attach to them as to a rigid body's frames.
``angular_velocity()`` is the floating frame's; ``frame_angular_velocity(frame)`` adds a node
frame's elastic turn rate (joint rates, actuation and springs along a joint, reaction frames).
"""

import numpy as np
import sympy as sp

from ..constraints.base import Constraint
from ...core.errors import ModelError
from ...core.kinematics import body_rate_matrix, rotation, world_rate_matrix
from ...symbolic.derive import positions
from ..flexible.invariants import invariants
from .base import Frame, Part
from .part_type import EXTRA_NODE, FE_MESH, PartType, QUATERNION, check
from .rigid_body import COORDINATES as FRAME_COORDINATES, _unit_norm_rows
from ...core.tolerances import GRAM_ZERO_RTOL



class FlexibleBody(Part):
    """A reduced FE model ``reduction`` (a Reduction whose basis carries no rigid-body
    motion: Craig–Bampton with one interface node held, ``Reduction.hold``, or free-interface
    modes without rigid ones) on a floating frame. ``frames``: {name: node} or {name: (node,
    rotation 3 × 3[, drawing geometry])}; every interface node also gets a frame ``node_<j>``. ``damping``: an
    r × r matrix D (``rayleigh_damping``, ``modal_damping``), default none. ``gravity``:
    sympy 3-vector of parameters. ``stiffening``: the 3 × 3 × r × r S of
    ``centrifugal_stiffening``, default none. ``frame_nodes``: {frame name: FE node};
    ``elastic``: the slice of the part's coordinates that are η."""

    content_fields = ("reduction", "gravity", "damping", "stiffening", "frame_nodes")

    part_type = check(PartType("flexible_body", node=EXTRA_NODE, orientation=QUATERNION, quaternion=slice(3, 7),
                               points=(("x", "y", "z"),), elastic=True, body_rates=False, origin=True,
                               shared_pose=False, drawing=FE_MESH))
    groups = (("x", "y", "z"), ("qw", "qx", "qy", "qz"))
    defaults = {"qw": 1.0}

    def __init__(self, name, q, qd, reduction, gravity, params, frames=None, damping=None, geometry=(),
                 initial=None, stiffening=None):
        r = reduction.size
        if r == 0:
            raise ModelError(f"flexible body '{name}': its reduction has no elastic coordinate: a part without one "
                             "is a rigid_body")
        if len(q) != 7 + r:
            raise ModelError(f"flexible body '{name}': {len(q)} coordinate symbols, its reduction needs {7 + r}")
        self.reduction, self.gravity = reduction, sp.Matrix(gravity)
        self.elastic = slice(len(FRAME_COORDINATES), len(FRAME_COORDINATES) + r)
        self.invariants = invariants(reduction)
        self.damping = np.zeros((r, r)) if damping is None else np.asarray(damping, float)
        if self.damping.shape != (r, r):
            raise ModelError(f"flexible body '{name}': damping is {self.damping.shape}, the reduction has {r} coordinates")
        eta_dot = sp.Matrix(qd[7:])
        if self.damping.any():
            self.power_expression = -(eta_dot.T * _numbers(self.damping) * eta_dot)[0]  # the damping's: −η̇ᵀDη̇
        self.stiffening = np.zeros((3, 3, r, r)) if stiffening is None else np.asarray(stiffening, float)
        if self.stiffening.shape != (3, 3, r, r):
            raise ModelError(f"flexible body '{name}': stiffening is {self.stiffening.shape}, expected {(3, 3, r, r)}")
        named = {f"node_{j}": j for j in reduction.interface}
        named.update(frames or {})
        self.frame_nodes = {label: spec[0] if isinstance(spec, tuple) else spec for label, spec in named.items()}
        self._turn_rates = {}  # frame name -> its elastic turn's angular velocity in the part's axes
        made = [self._node_frame(name, label, spec, q[self.elastic], qd[self.elastic]) for label, spec in named.items()]
        M, Q, T, V = _equations(self.invariants, reduction.stiffness, self.damping, self.stiffening, q, qd,
                                self.gravity)
        super().__init__(name, coordinates(r), q, qd, M, Q, T, V, params, made, geometry, initial)

    def _node_frame(self, part, label, spec, eta, eta_dot):
        node, turn, geometry = (*spec, ())[:3] if isinstance(spec, tuple) else (spec, np.eye(3), ())
        rows = self.reduction.node_rows(node)  # raises for a node the FE model lacks
        Phi = _numbers(self.reduction.basis[rows])
        position = sp.Matrix(self.reduction.fe.nodes[node]) + Phi[:3, :] * sp.Matrix(eta)
        if len(rows) == 6:
            half, half_rate = Phi[3:, :] * sp.Matrix(eta) / 2, Phi[3:, :] * sp.Matrix(eta_dot) / 2
            elastic = rotation([1, *half]) / (1 + (half.T * half)[0])
            # the Cayley map's angular velocity (Rodrigues parameters g = θ/2): 2(ġ + g × ġ)/(1 + gᵀg)
            self._turn_rates[label] = 2 * (half_rate + half.cross(half_rate)) / (1 + (half.T * half)[0])
        else:
            elastic = sp.eye(3)
        return Frame(part, label, position, elastic * sp.Matrix(turn), tuple(geometry))

    def own_constraints(self, q, qd, params):
        """The frame's quaternion has unit norm (the rigid body's row, rigid_body.py)."""
        where = positions(q, qd)
        rows, slots = _unit_norm_rows()
        return [Constraint.placed(f"{self.name}.unit_quaternion", "holonomic", rows, slots,
                                 [where[s] for s in self.q[3:7]], q, qd, params)]

    def pose(self, frame):
        A = rotation(self.q[3:7])
        return sp.Matrix(self.q[:3]) + A * frame.position, A * frame.rotation

    def angular_velocity(self):
        return 2 * world_rate_matrix(self.q[3:7]) * sp.Matrix(self.qd[3:7])

    def frame_angular_velocity(self, frame):
        """The floating frame's angular velocity plus, for a frame at a node with rotation DOFs,
        the node's elastic turn's (turned to world axes)."""
        rate = self._turn_rates.get(frame.name) if frame.part == self.name else None
        own = self.angular_velocity()
        return own if rate is None else own + rotation(self.q[3:7]) * rate

    def idle_directions(self, q):
        """The quaternion's own direction: scaling u turns nothing."""
        direction = np.zeros((len(self.coordinates), 1))
        direction[3:7, 0] = q[3:7] / np.linalg.norm(q[3:7])
        return direction


def coordinates(modes):
    """The coordinate names of a flexible body with ``modes`` reduced coordinates."""
    return (*FRAME_COORDINATES, *(f"eta{k + 1}" for k in range(modes)))


def rayleigh_damping(reduction, alpha, beta):
    """D = α M_r + β K_r on the reduced coordinates."""
    return alpha * reduction.mass + beta * reduction.stiffness


def modal_damping(reduction, ratio):
    """D = M_r Ψ diag(2ζω) Ψᵀ M_r: each normal mode of the reduced model with the frame
    held (K_r ψ = ω² M_r ψ, ψ M_r-orthonormal) damped at the ratio ζ = ``ratio``."""
    L = np.linalg.cholesky(reduction.mass)
    Linv = np.linalg.inv(L)
    lam, Y = np.linalg.eigh(Linv @ reduction.stiffness @ Linv.T)
    Psi = Linv.T @ Y
    omega = np.sqrt(np.clip(lam, 0.0, None))
    D = reduction.mass @ Psi @ np.diag(2 * ratio * omega) @ Psi.T @ reduction.mass
    return (D + D.T) / 2


def _numbers(array):
    """A numpy array as a sympy matrix of floats."""
    return sp.Matrix(np.atleast_2d(array).tolist())


def _polynomial(constant, linear, quadratic, eta):
    """The sympy matrix constant + Σ_k η_k linear[k] + Σ_kl η_k η_l quadratic[k, l], its
    entries sums of float multiples of monomials (zeros left out)."""
    monomials = [(linear[k], x) for k, x in enumerate(eta)]
    monomials += [(quadratic[k, l] + quadratic[l, k] if k < l else quadratic[k, k], eta[k] * eta[l])
                  for k in range(len(eta)) for l in range(k, len(eta))]
    rows, cols = constant.shape
    return sp.Matrix(rows, cols, lambda i, j: sp.Add(sp.Float(constant[i, j]), *(
        sp.Float(c[i, j]) * m for c, m in monomials if c[i, j] != 0)))


def _product(*factors):
    """The matrix product of sympy matrices, each entry one sum of the nonzero products
    (sympy's own product goes through its domain machinery: slow on these)."""
    out = factors[0]
    for right in factors[1:]:
        out = sp.Matrix(out.rows, right.cols, lambda i, j: sp.Add(*(
            out[i, k] * right[k, j] for k in range(out.cols) if out[i, k] != 0 and right[k, j] != 0)))
    return out


def _equations(inv, K, D, S, q, qd, gravity):
    """(M, Q, T, V) of the part in its coordinates q = (R, u, η): the module's formulas."""
    r = inv.modes
    u, eta = sp.Matrix(q[3:7]), sp.Matrix(q[7:])
    R_dot, u_dot, eta_dot = sp.Matrix(qd[:3]), sp.Matrix(qd[3:7]), sp.Matrix(qd[7:])
    A, E = rotation(u), body_rate_matrix(u)
    W = np.where(np.abs(inv.gram) > GRAM_ZERO_RTOL * np.abs(inv.gram).max(), inv.gram, 0.0)
    # M(η) = Pᵀ W P with P = P0 + Σ η_k P_k (invariants.py): P_k puts I₃ at rows 6 + 3k, columns 3:6
    P0 = np.zeros((6 + 4 * r, 6 + r))
    P0[:6, :6], P0[6 + 3 * r:, 6:] = np.eye(6), np.eye(r)
    P = np.zeros((r, 6 + 4 * r, 6 + r))
    for k in range(r):
        P[k, 6 + 3 * k:9 + 3 * k, 3:6] = np.eye(3)
    linear = np.einsum("kai,ab,bj->kij", P, W, P0)
    linear += linear.transpose(0, 2, 1)
    quadratic = np.einsum("kai,ab,lbj->klij", P, W, P)
    quadratic[:, :, 3:6, 3:6] -= S.transpose(2, 3, 0, 1)  # centrifugal stiffening: T₂ = −½ ωᵀ [ηᵀ S_ab η] ω
    M_nu = _polynomial(P0.T @ W @ P0, linear, quadratic, eta)  # M(η), ν = (V, ω, η̇)
    slopes = [_polynomial(linear[k], quadratic[k] + quadratic[:, k], np.zeros((r, r) + linear.shape[1:]), eta)
              for k in range(r)]  # ∂M/∂η_k
    V, omega = _product(A.T, R_dot), _product(2 * E, u_dot)
    nu = sp.Matrix.vstack(V, omega, eta_dot)
    p = _product(M_nu, nu)
    h = -_product(sp.Matrix.hstack(*(_product(S, nu) for S in slopes)), eta_dot)  # −Ṁν
    h[:3, 0] -= omega.cross(p[:3, 0])
    h[3:6, 0] -= omega.cross(p[3:6, 0]) + V.cross(p[:3, 0])
    for k, S in enumerate(slopes):
        h[6 + k] += _product(nu.T, S, nu)[0] / 2
    mass = float(W[0, 0])
    a = _product(A.T, gravity)
    first = _numbers(inv.first_moment).T + _product(_numbers(W[:3, 6 + 3 * r:]), eta)  # s(η)
    F = sp.Matrix.vstack(mass * a, first.cross(a), _product(_numbers(W[6 + 3 * r:, :3]), a)
                         - _product(_numbers(K), eta) - _product(_numbers(D), eta_dot))
    f = h + F + _product(M_nu[:, :3], omega.cross(V))
    B = sp.diag(A.T, 2 * E, sp.eye(r))
    M = _product(B.T, M_nu, B)
    M[:3, :3] = mass * sp.eye(3)  # A m Aᵀ for a unit quaternion
    Q = _product(B.T, f)
    T = _product(nu.T, M_nu, nu)[0] / 2
    potential = (_product(eta.T, _numbers(K), eta)[0] / 2
                 - _product(gravity.T, mass * sp.Matrix(q[:3]) + _product(A, first))[0])
    return M, Q, T, potential
