"""A flexible body in the floating frame of reference: coordinates x, y, z (the
frame's origin in the world), the unit quaternion qw, qx, qy, qz of its axes (as a rigid
body, with the same unit-norm row) and the amplitudes eta1 … etar of a reduced FE model
(model/flexible/reduction.py), u = Φ η the nodal DOFs in the frame's axes.

M(q) and Q(q, q̇) follow from the reduced model's invariants (model/flexible/invariants.py):
with ν = (V, ω, η̇) = B q̇, B = blockdiag(Aᵀ, 2E(u), I), the invariants' M(η) ν̇ = h + F gives

    M_q = Bᵀ M(η) B,   Q_q = Bᵀ (h + F + M(η) (ω × V, 0, 0)),

(Ḃq̇ = (−ω × V, 0, 0) since E(u̇)u̇ = 0), F = gravity (exact: the first moment s(η)),
−K_r η and −D η̇ on η. M_q keeps the rigid body's null direction u (closed by the unit-norm
row). With ``stiffening`` S (model/flexible/stiffening.py), M(η)'s ω–ω block loses Σ ω_a ω_b
ηᵀ S_ab η: the centrifugal stiffening of a spinning part, as a term of its kinetic energy.
One compiled kernel evaluates them for every flexible part from its invariants as arrays
(compiled/flexible.py, O(r²)): on both paths (``evaluate``; the compiled path's generated
outputs, compiled/layout.py) and, through complex numbers, the exact Jacobians of a
linearization (``derivatives``); nothing is derived or generated per model. The same
formulas in sympy (``reference``, ``symbolic()``) are the kernel's test reference.

Frames sit at FE nodes: node j at x_j + u_j(η) in the part's axes, turned by the node's
elastic rotation θ_j(η) (its rotation DOFs; none for 3-DOF nodes) through the Cayley map
(1 − |θ|²/4) I + ½θθᵀ + [θ]× over 1 + |θ|²/4 — orthogonal, and the linear theory's
I + [θ]× to first order — so joints and forces attach to them as to a rigid body's frames.
``angular_velocity()`` is the floating frame's; ``frame_angular_velocity(frame)`` adds a node
frame's elastic turn rate (joint rates, actuation and springs along a joint, reaction frames).
"""

import functools
from typing import NamedTuple

import numpy as np
import sympy as sp

from ..constraints.base import Constraint
from ...core.errors import ModelError
from ...core.values import freeze
from ...core.kinematics import body_rate_matrix, rotation, world_rate_matrix
from ...symbolic.derive import PARAMETERS, T_SYMBOL, compile_function, positions
from ..flexible.invariants import invariants
from .base import Part
from .part_type import EXTRA_NODE, FE_MESH, PartType, QUATERNION, check
from .rigid_body import COORDINATES as FRAME_COORDINATES, _unit_norm_rows
from ...core.tolerances import COMPLEX_STEP, GRAM_ZERO_RTOL


class PartArrays(NamedTuple):
    """What compiled/flexible.py's kernel reads of a flexible part (``kernel_arrays``)."""

    axes: np.ndarray     # the frame's turns: empty for a quaternion, the 3 axis indices of an angle sequence
    W: np.ndarray        # the Gram matrix, (6 + 4r) square, rounding-level entries zeroed (``_gram``)
    s0: np.ndarray       # the undeformed first moment (3,)
    K: np.ndarray        # K_r (r × r)
    D: np.ndarray        # the damping (r × r)
    S: np.ndarray        # the stiffening (3 × 3 × r × r)
    gravity: sp.Matrix   # the gravity vector, in the model's parameter symbols


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
    axes = np.zeros(0, np.int64)  # the kernel's sign of a quaternion (PartArrays.axes)

    def __init__(self, name, q, qd, reduction, gravity, params, frames=None, damping=None, geometry=(),
                 initial=None, stiffening=None):
        r = reduction.size
        if r == 0:
            raise ModelError(f"flexible body '{name}': its reduction has no elastic coordinate: a part without one "
                             "is a rigid_body")
        names = self.coordinate_names(r)
        if len(q) != len(names):
            raise ModelError(f"flexible body '{name}': {len(q)} coordinate symbols, its reduction needs {len(names)}")
        self.reduction, self.gravity = reduction, sp.Matrix(gravity)
        self.elastic = slice(len(names) - r, len(names))
        self.invariants = invariants(reduction)
        self.damping = np.zeros((r, r)) if damping is None else np.asarray(damping, float)
        if self.damping.shape != (r, r):
            raise ModelError(f"flexible body '{name}': damping is {self.damping.shape}, the reduction has {r} coordinates")
        self.stiffening = np.zeros((3, 3, r, r)) if stiffening is None else np.asarray(stiffening, float)
        if self.stiffening.shape != (3, 3, r, r):
            raise ModelError(f"flexible body '{name}': stiffening is {self.stiffening.shape}, expected {(3, 3, r, r)}")
        named = {f"node_{j}": j for j in reduction.interface}
        named.update(frames or {})
        self.frame_nodes = {label: spec[0] if isinstance(spec, tuple) else spec for label, spec in named.items()}
        made = [NodeFrame(name, label, spec, reduction, q[self.elastic], qd[self.elastic])
                for label, spec in named.items()]
        self.kernel_arrays = PartArrays(self.axes, _gram(self.invariants), np.array(self.invariants.first_moment, float),
                                        np.ascontiguousarray(reduction.stiffness, float),
                                        np.ascontiguousarray(self.damping), np.ascontiguousarray(self.stiffening),
                                        self.gravity)
        self._params = list(params)
        self._gravity = compile_function((T_SYMBOL, list(q), list(qd), self._params), [self.gravity],
                                         picked=PARAMETERS)
        self._gravity_last = None  # (p, the gravity vector at p), ``gravity_at``
        super().__init__(name, names, q, qd, None, None, None, None, params, made, geometry, initial)

    @staticmethod
    def coordinate_names(modes):
        """The part's coordinate names with ``modes`` reduced coordinates."""
        return coordinates(modes)

    def turning(self):
        """(A, B, c) in sympy: the frame's axes A (world), ω = B u̇ in them over the orientation's
        coordinates u, and c = Ḃ u̇ (zero for a quaternion: 2E(u̇)u̇ = 0)."""
        return self.frame_axes(), 2 * body_rate_matrix(self.q[3:7]), sp.zeros(3, 1)

    def frame_axes(self):
        """The frame's axes A (world) in sympy."""
        return rotation(self.q[3:7])

    def reference(self):
        """(M, Q, T, V) in sympy (the module's formulas): the kernel's test reference."""
        return _equations(self.invariants, self.reduction.stiffness, self.damping, self.stiffening, self.q,
                          self.qd, self.gravity, self.turning())

    def gravity_at(self, t, p):
        """The gravity vector (world) at parameter values p (the last one kept while t does not enter)."""
        last = self._gravity_last
        if last is not None and np.array_equal(last[0], p):
            return last[1]
        rest = np.zeros(len(self.q))
        g = np.ascontiguousarray(self._gravity(t, rest, rest, p)[0], float).ravel()
        if T_SYMBOL not in self.gravity.free_symbols:
            self._gravity_last = (np.array(p, float), g)
        return g

    def evaluate(self, t, q, qd, p):
        """(M, Q) at the part's coordinates (2.1), by the compiled kernel."""
        return equations(np.asarray(q, float), np.asarray(qd, float), self.gravity_at(t, p), self.kernel_arrays)[:2]

    def energy(self, t, q, qd, p):
        """(T, V): ½ νᵀ M(η) ν and ½ ηᵀ K_r η − gᵀ(m R + A s(η))."""
        q, qd = np.asarray(q, float), np.asarray(qd, float)
        g = self.gravity_at(t, p)
        _, _, Mnu, nu = equations(q, qd, g, self.kernel_arrays)
        W, s0, K = self.kernel_arrays[1:4]
        eta = q[self.elastic]
        first = s0 + W[:3, 6 + 3 * len(eta):] @ eta
        return float(nu @ Mnu @ nu) / 2, float(eta @ K @ eta / 2 - g @ (W[0, 0] * q[:3] + self.axes_of(q) @ first))

    def axes_of(self, q):
        """The frame's axes A (numeric) at the part's coordinates q."""
        return _rotation(q[3:7])

    @property
    def working(self):
        return bool(self.damping.any())

    def power(self, t, q, qd, p):
        """The damping's power −η̇ᵀ D η̇."""
        eta_dot = np.asarray(qd, float)[self.elastic]
        return float(-eta_dot @ self.damping @ eta_dot)

    def reads(self, symbols):
        return not self.gravity.free_symbols.isdisjoint(symbols)

    def derivatives(self):
        return _Derivatives(self)

    def own_constraints(self, q, qd, params):
        """The frame's quaternion has unit norm (the rigid body's row, rigid_body.py)."""
        where = positions(q, qd)
        rows, slots = _unit_norm_rows()
        return [Constraint.placed(f"{self.name}.unit_quaternion", "holonomic", rows, slots,
                                 [where[s] for s in self.q[3:7]], q, qd, params)]

    def pose(self, frame):
        return self.frame_position(frame), _product(self._axes, frame.rotation)

    def frame_position(self, frame):
        return sp.Matrix(self.q[:3]) + _product(self._axes, frame.position)

    @functools.cached_property
    def _axes(self):
        """``frame_axes()``, built once: every frame's pose reads it."""
        return self.frame_axes()

    def angular_velocity(self):
        return 2 * world_rate_matrix(self.q[3:7]) * sp.Matrix(self.qd[3:7])

    def frame_angular_velocity(self, frame):
        """The floating frame's angular velocity plus, for a frame at a node with rotation DOFs,
        the node's elastic turn's (turned to world axes)."""
        rate = frame.turn_rate if frame.part == self.name and isinstance(frame, NodeFrame) else None
        own = self.angular_velocity()
        return own if rate is None else own + self._axes * rate

    def idle_directions(self, q):
        """The quaternion's own direction: scaling u turns nothing."""
        direction = np.zeros((len(self.coordinates), 1))
        direction[3:7, 0] = q[3:7] / np.linalg.norm(q[3:7])
        return direction


class NodeFrame:
    """A frame at FE node ``spec`` (a node, or (node, rotation 3 × 3[, drawing geometry])) of
    part ``part`` with reduction ``reduction``: Frame's fields (base.py), its ``position``
    x_j + Φ_j η, ``rotation`` (the Cayley map of the module docstring, then the given turn)
    and ``turn_rate`` (the Cayley map's angular velocity in the part's axes, None for a node
    without rotation DOFs) sympy expressions in the amplitudes ``eta`` built when first read:
    the sums over r modes cost seconds of sympy at r = 20, and a model reads few of them
    (joints, outputs and drawings at a node). Equal when what its expressions are made of is
    (part, name, node, turn, the node's place and rows of Φ, the symbols; the drawing
    ``geometry`` is not compared, as Frame's)."""

    def __init__(self, part, name, spec, reduction, eta, eta_dot):
        node, turn, geometry = (*spec, ())[:3] if isinstance(spec, tuple) else (spec, np.eye(3), ())
        self.rows = reduction.node_rows(node)  # raises for a node the FE model lacks
        self.part, self.name, self.node, self.geometry = part, name, node, tuple(geometry)
        self.turn = np.array(turn, float)
        self._basis = np.asarray(reduction.basis[self.rows], float)
        self._place = np.asarray(reduction.fe.nodes[node], float)
        self._eta, self._eta_dot = list(eta), list(eta_dot)

    def content(self):
        return (self.part, self.name, self.node, freeze(self.turn), freeze(self._place), freeze(self._basis),
                tuple(self._eta), tuple(self._eta_dot))

    def __eq__(self, other):
        return type(other) is NodeFrame and self.content() == other.content()

    def __hash__(self):
        return hash(self.content())

    @property
    def label(self):
        return f"{self.part}.{self.name}"

    @functools.cached_property
    def position(self):
        return sp.Matrix(self._place.tolist()) + _combination(self._basis[:3], self._eta)

    @functools.cached_property
    def _cayley(self):
        """(the elastic rotation, its angular velocity in the part's axes or None)."""
        if len(self.rows) != 6:
            return sp.eye(3), None
        # Rodrigues parameters g = θ/2; the angular velocity 2(ġ + g × ġ)/(1 + gᵀg)
        half, half_rate = _combination(self._basis[3:] / 2, self._eta), _combination(self._basis[3:] / 2, self._eta_dot)
        scale = 1 + sp.Add(*(x * x for x in half))
        return _cayley(half, scale), 2 * (half_rate + half.cross(half_rate)) / scale

    @functools.cached_property
    def rotation(self):
        elastic = self._cayley[0]
        return elastic if np.array_equal(self.turn, np.eye(3)) else _product(elastic, _numbers(self.turn))

    @property
    def turn_rate(self):
        return self._cayley[1]

    @functools.cached_property
    def constant_rotation(self):
        """``rotation`` as floats where it holds no amplitude (a node without rotation DOFs,
        or one the reduction holds: all its rows of Φ zero), else None (Frame's)."""
        if len(self.rows) == 6 and self._basis[3:].any():
            return None
        return np.array(self.turn)


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


def _gram(inv):
    """The invariants' Gram matrix W with the entries below GRAM_ZERO_RTOL of the largest zeroed."""
    return np.ascontiguousarray(np.where(np.abs(inv.gram) > GRAM_ZERO_RTOL * np.abs(inv.gram).max(), inv.gram, 0.0))


def _cayley(g, scale):
    """((1 − gᵀg) I + 2 g gᵀ + 2 [g]×) / ``scale`` (= 1 + gᵀg) in sympy, entry by entry:
    core/kinematics.py's ``rotation`` of (1, g) over its norm, without sympy's matrix
    products (slow on sums of many terms)."""
    g = list(g)
    diagonal = 2 - scale  # 1 − gᵀg

    def entry(i, j):
        k = 3 - i - j  # the third axis, for i ≠ j
        turn = 0 if i == j else sp.Mul(2 if (j - i) % 3 == 1 else -2, g[k])  # 2[g]×: (0, 1) holds −2 g_z
        return sp.Add(diagonal if i == j else 0, sp.Mul(2, g[i], g[j]), -turn) / scale
    return sp.Matrix(3, 3, entry)


def _combination(matrix, symbols):
    """The sympy column Σ_k matrix[:, k] symbols[k] (float coefficients, zeros left out)."""
    return sp.Matrix([sp.Add(*(sp.Mul(sp.Float(c), x) for c, x in zip(row, symbols) if c != 0)) for row in matrix])


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


def _equations(inv, K, D, S, q, qd, gravity, turning):
    """(M, Q, T, V) of the part in its coordinates q = (R, u, η): the module's formulas, the
    frame turned by ``turning`` = (A, B, c) (``FlexibleBody.turning``)."""
    r = inv.modes
    A, B_omega, c = turning
    o = 3 + B_omega.cols  # the first η
    eta = sp.Matrix(q[o:])
    R_dot, u_dot, eta_dot = sp.Matrix(qd[:3]), sp.Matrix(qd[3:o]), sp.Matrix(qd[o:])
    W = _gram(inv)
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
    V, omega = _product(A.T, R_dot), _product(B_omega, u_dot)
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
    f = h + F + _product(M_nu[:, :3], omega.cross(V)) - _product(M_nu[:, 3:6], c)  # Ḃq̇ = (−ω × V, c, 0)
    B = sp.diag(A.T, B_omega, sp.eye(r))
    M = _product(B.T, M_nu, B)
    M[:3, :3] = mass * sp.eye(3)  # A m Aᵀ: A orthogonal
    Q = _product(B.T, f)
    T = _product(nu.T, M_nu, nu)[0] / 2
    potential = (_product(eta.T, _numbers(K), eta)[0] / 2
                 - _product(gravity.T, mass * sp.Matrix(q[:3]) + _product(A, first))[0])
    return M, Q, T, potential


def equations(q, qd, g, arrays):
    """(M_q, Q_q, M(η), ν) of a part with ``arrays`` (PartArrays) at its coordinates q, q̇ and
    gravity g: compiled/flexible.py's kernel, complex where q, q̇ or g is."""
    from ...compiled import flexible  # numba: loaded with the first flexible part evaluated

    dtype = np.result_type(q, qd, g, float)
    n = len(q)
    M, Q = np.zeros((n, n), dtype), np.zeros(n, dtype)
    size = 6 + arrays.K.shape[0]  # ν = (V, ω, η̇)
    Mnu, nu = np.zeros((size, size), dtype), np.zeros(size, dtype)
    flexible.equations(*(np.ascontiguousarray(x, dtype) for x in (q, qd, g)), *arrays[:6], M, Q, Mnu, nu)
    return M, Q, Mnu, nu


def _rotation(u):
    """A(u) of a scalar-first quaternion, numpy (core/kinematics.py ``rotation``)."""
    w, v = u[0], np.asarray(u[1:])
    skew = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return (w * w - v @ v) * np.eye(3) + 2 * np.outer(v, v) + 2 * w * skew


class _Derivatives:
    """The exact Jacobians of G = M q̈ − Q of a flexible part by q, q̇ and parameters, for
    analysis/linearization.py (its ``BlockFunction.jacobians``): the complex step (Im G(x + ih
    e_j)/h, exact to rounding) through the kernel; Q is linear in the gravity vector g, so
    ∂G/∂p = −(∂Q/∂g)(∂g/∂p), ∂g/∂p from the gravity's sympy expressions."""

    def __init__(self, part):
        self.part = part

    def jacobians(self, t, q, qd, qdd, lam, p, parameters=()):
        part, h = self.part, COMPLEX_STEP
        q, qd, qdd = (np.asarray(x, float) for x in (q, qd, qdd))
        g = part.gravity_at(t, p)
        n = len(q)

        def moved(which, j):
            x = [q.astype(complex), qd.astype(complex), g.astype(complex)]
            x[which][j] += 1j * h
            M, Q = equations(*x, part.kernel_arrays)[:2]
            return (M @ qdd - Q).imag / h

        G_q = np.column_stack([moved(0, j) for j in range(n)])
        G_qd = np.column_stack([moved(1, j) for j in range(n)])
        G_g = np.column_stack([moved(2, j) for j in range(3)])
        G_p = np.zeros((n, len(parameters)))
        values = dict(zip(part._params, p))
        for c, j in enumerate(parameters):
            symbol = part._params[j]
            if symbol in part.gravity.free_symbols:
                G_p[:, c] = G_g @ np.array(part.gravity.diff(symbol).subs(values), dtype=float).ravel()
        return G_q, G_qd, G_p
