"""The linearization of a model's motion about a state, on its constraint manifold.

The motion q̈ = f(q, q̇, t) of (2.14) lives on the manifold of the position-level rows
φ(q, t) = 0 and their velocity forms ψ = Φ_q q̇ + φ_t = 0. Its linearization is taken in
independent coordinates of that manifold's tangent space, so redundant coordinates (a
rigid body's four quaternion numbers: each body's ``<body>.unit_quaternion`` is a row),
dependent loop coordinates and massless coordinates fixed by a holonomic balance
(``closure: auto``, model/balances.py, or a model's own, as models/paper/example3_m1_zero.yaml's
``node_balance``) all drop out by themselves:

- positions: the k independent coordinates u are k of the model's coordinates, picked by
  coordinate partitioning (Wehage & Haug: QR with column pivoting of a basis of
  null(Φ_q)ᵀ); the others follow from φ(q, t) = 0, so δq = N δu with N (n × k,
  ``Linearization.basis``) the basis of null(Φ_q) that is the identity on u;
- velocities: δq̇ = N δu̇ + c, c zero on u and Φ_q c = −Ψ_q N δu (the tangent of
  ψ(q, q̇) = 0; Ψ_q = ∂ψ/∂q, zero at rest for scleronomic rows);
- the state x = [δu; δu̇] (2k) gives the model's state change T x (``state_map``,
  2n × 2k), and ü = f(q, q̇)[u], so ẋ = A x + B δp with
  A = [[0, I], [(∂f/∂q, ∂f/∂q̇) T restricted to the rows u]] — exact at any state on the
  manifold, at rest or moving.

Massless parts. The independent state is that of the masses: a massless coordinate is
fixed, at every instant, by its balance wᵀ(Q + C) = 0 (model/balances.py). Written as a
holonomic row (``closure: auto`` appends it so when it involves no velocities), the
balance is one of the rows of Φ_q and removes the massless coordinate from the tangent
space: in example 3 with m1 = 0 the node x1 follows from (5.40) and (5.32), and the state
is (q2, q̇2), one mode. A balance with velocities (a damper at a massless node) is a
first-order equation of its own and is refused with the non-holonomic rows.

Derivatives: exact, not finite differences: the complex step (Im f(x + ih)/h, h = 1e-30,
exact to rounding) on each block's compiled M, Q, a, b, C, ψ (``BlockFunction``; compiled
sympy Jacobians for a block with a non-analytic function such as Abs). Where Result 3
holds, q̈ of (2.14) is the unique q̈ of (2.5)–(2.6) with ideal forces Aᵀλ:
M q̈ − Q − C − Aᵀλ = 0, A q̈ − b = 0 (λ: the multipliers, reactions.py). Differentiating
these (the implicit function theorem on the KKT form of (2.14)):

    [M  −Aᵀ] [dq̈]      [∂(Mq̈ − Q − C − Aᵀλ)/∂(q, q̇)]
    [A   0 ] [dλ ] = − [∂(Aq̈ − b)/∂(q, q̇)          ] [dq; dq̇]

with q̈, λ held at their values in the derivatives on the right. The matrix has the null
space {0} × null(Aᵀ) when [M; A] has full column rank (Result 3), so dq̈ is unique even
with redundant rows or singular M; least squares picks one dλ. Rows that are redundant
all along the manifold change the right side only by terms in range(Aᵀ) along tangent
directions, so the choice of λ does not matter there.

Refused, with a SolveError naming the rows or coordinates: NaN or infinite input, states
off the manifold, rows that depend on time (a servo's prescribed motion) at a state that
moves (q̇ ≠ 0, or ∂φ/∂t ≠ 0: the motion about it is a time-varying system, its
eigenvalues at one instant no measure of stability), non-unique motion, non-holonomic
and acceleration-level rows (they restrict velocities or accelerations only, not the
state's manifold), Coulomb friction (not differentiable), a configuration near a singular
position (Φ_q nearly rank deficient: a loop near a change point) or at one (rows
dependent here whose dependency does not persist along the tangent directions, detected
by the rows' second derivatives).
"""

import functools
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import sympy as sp

from ..core.errors import SolveError
from .projection import relative_drift
from ..symbolic.derive import T_SYMBOL, compile_function, jacobian
from ..core.tolerances import CHANGE_POINT_RTOL, NAME_RTOL, NEAR_SINGULAR, ON_MANIFOLD_RTOL, RANK_RTOL

_CACHE_SIZE = 8
_cache = OrderedDict()  # (ids of the parts, rows and forces) -> (those tuples, Derivatives)


@dataclass(frozen=True)
class Linearization:
    """ẋ = A x + B u about (t, q, q̇) in k independent coordinates (module docstring).

    ``A`` (2k × 2k) and ``B`` (2k × len(inputs)) act on the state x = [δq_ind; δq̇_ind];
    ``basis`` (n × k) maps δq_ind to the model's δq; ``state_map`` (2n × 2k) maps x to
    (δq, δq̇); ``state_names`` are the independent coordinates and their ``_dot``;
    ``input_names`` are the parameters B is taken for; ``qdd`` is q̈ at the state.
    """

    A: np.ndarray
    B: np.ndarray
    basis: np.ndarray
    state_map: np.ndarray
    state_names: tuple
    input_names: tuple
    coordinates: tuple
    t: float
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray

    @property
    def k(self):
        """The number of degrees of freedom (independent coordinates)."""
        return self.basis.shape[1]

    @property
    def eigenvalues(self):
        """The eigenvalues of A (rad/s), ordered by imaginary part then real part."""
        values = np.linalg.eigvals(self.A) if self.A.size else np.zeros(0, complex)
        return values[np.lexsort((values.real, values.imag))]


def linearize(system, t, q, qd, inputs=None):
    """The ``Linearization`` of ``system``'s motion about (t, q, q̇) (module docstring).

    ``inputs``: parameter names B is taken for (they must enter only the forces Q + C);
    by default the robots' joint torques ``tau_*`` and the parameters named ``tau_*`` or
    ``u_*``. Raises SolveError where no linearization on the manifold exists."""
    q, qd = finite_state(system, q, qd)
    inputs = default_inputs(system) if inputs is None else tuple(inputs)
    _refuse_unsupported(system, t, q, qd)
    motion = system.motion(t, q, qd)
    if not motion.unique:
        moving = _named(system.coordinates, np.abs(motion.nullspace).max(axis=1))
        raise SolveError(f"model '{system.name}': the motion is not unique at this state "
                         f"({motion.nullspace.shape[1]} indeterminate direction(s) in {moving}): "
                         "no linearization (add the massless parts' balances: closure: auto)",
                         coordinates=moving)
    derivatives = derivatives_of(system)
    arrays = system.evaluate(t, q, qd)
    held = derivatives.rows(system, t, q, qd)
    N, pivots = tangent_basis(system, held.Phi_q, held.position_rows)
    _check_change_point(system, derivatives, t, q, qd, held, N)
    n, k = system.n, N.shape[1]
    T = np.zeros((2 * n, 2 * k))
    T[:n, :k] = N
    T[n:, k:] = N
    dependent = np.setdiff1d(np.arange(n), pivots)
    if held.Phi_q.size and dependent.size:
        T[n + dependent, :k] = -np.linalg.lstsq(held.Phi_q[:, dependent], held.Psi_q @ N, rcond=None)[0]
    R_q, R_qd, S_q, S_qd, F_p = derivatives.motion(system, t, q, qd, motion.qdd, motion.lam, inputs)
    m = arrays.A.shape[0]
    kkt = np.block([[arrays.M, -arrays.A.T], [arrays.A, np.zeros((m, m))]])
    right = np.hstack([-np.vstack([np.hstack([R_q, R_qd]), np.hstack([S_q, S_qd])]) @ T,
                       np.vstack([F_p, np.zeros((m, len(inputs)))])])
    scale = np.abs(kkt).max(axis=1, keepdims=True)
    scale[scale == 0] = 1.0
    dqdd = np.linalg.lstsq(kkt / scale, right / scale, rcond=None)[0][:n, :][pivots]
    A = np.vstack([T[n:][pivots], dqdd[:, :2 * k]])
    B = np.vstack([np.zeros((k, len(inputs))), dqdd[:, 2 * k:]])
    names = [system.coordinates[i] for i in pivots]
    return Linearization(A, B, N, T, tuple(names) + tuple(f"{c}_dot" for c in names), inputs, system.coordinates,
                         float(t), q, qd, motion.qdd)


def default_inputs(system):
    """The parameters that act as inputs: the robots' joint torques and those named tau_* or u_*."""
    torques = {name for robot in system.robots for name in robot.torques.values()}
    return tuple(p for p in system.parameters if p in torques or p.startswith(("tau_", "u_")))


def finite_state(system, q, qd):
    """(q, q̇) as flat arrays of the model's size; SolveError naming the coordinates where
    either is NaN or infinite."""
    q, qd = system._state(q, qd)
    bad = [f"{label} contains {kind} at {', '.join(system.coordinates[i] for i in np.flatnonzero(test(x)))}"
           for label, x in (("q", q), ("qd", qd)) for kind, test in (("NaN", np.isnan), ("inf", np.isinf))
           if test(x).any()]
    if bad:
        raise SolveError(f"model '{system.name}': {'; '.join(bad)}",
                         coordinates=[c for c, x, y in zip(system.coordinates, q, qd) if not np.isfinite(x + y)])
    return q, qd


def time_rows(system):
    """The names of the rows whose constraint holds t explicitly (a servo's θ(t)): their
    manifold moves with time."""
    return _time_rows(system.connectors)


@functools.lru_cache(maxsize=_CACHE_SIZE)
def _time_rows(connectors):
    found = []
    for con in connectors:
        own = con.phi if con.phi is not None else con.psi if con.psi is not None else con.b
        found += [name for name, x in zip(con.row_names, own) if x.has(T_SYMBOL)]
    return tuple(found)


def prescribed_motion(system, t, q, qd):
    """The rows that depend on time (``time_rows``) where the state (t, q, q̇) moves: all of
    them where q̇ ≠ 0, else those whose ∂φ/∂t (their ψ at q̇ = 0) is not zero; [] elsewhere."""
    rows = time_rows(system)
    if not rows or np.any(qd):
        return list(rows)
    _, rate = system.constraint_residuals(t, q, np.zeros_like(q))
    return [name for name, x in zip(system.constraint_names, rate) if name in rows and abs(x) > ON_MANIFOLD_RTOL]


def _refuse_unsupported(system, t, q, qd):
    """SolveError for what the linearization does not cover (module docstring)."""
    friction = [c.name for c in system.connectors if getattr(c, "coulomb", None)]
    if friction:
        raise SolveError(f"model '{system.name}': Coulomb friction at {friction} is not differentiable; "
                         "no linearization", constraints=friction)
    phi, psi = system.constraint_residuals(t, q, qd)
    velocity_only = [name for name, x in zip(system.constraint_names, phi) if np.isnan(x)]
    if velocity_only:
        raise SolveError(f"model '{system.name}': rows {velocity_only} restrict velocities or accelerations only "
                         "(non-holonomic or acceleration-level): the linearization covers holonomic rows "
                         "(write a massless part's balance as a holonomic row, or use closure: auto)",
                         constraints=velocity_only)
    moving = prescribed_motion(system, t, q, qd)
    if moving:
        why = "q̇ ≠ 0" if np.any(qd) else f"∂φ/∂t ≠ 0 at t = {t:g}"
        raise SolveError(f"model '{system.name}': rows {moving} depend on time (a prescribed "
                         f"motion) and the state moves ({why}): the motion about it is a time-varying system, "
                         "whose eigenvalues at one instant say nothing of its stability; linearize where the rows "
                         "hold still (q̇ = 0 and ∂φ/∂t = 0), or with the prescribed motion held at a constant",
                         constraints=moving)
    drift = relative_drift(system, t, q, qd)
    if drift > ON_MANIFOLD_RTOL:
        worst = system.constraint_names[int(np.nanargmax(np.abs(np.concatenate([phi, psi]))) % len(phi))]
        raise SolveError(f"model '{system.name}': the state is off the constraints (relative residual {drift:.2g}, "
                         f"largest in {worst}): put it on them first (mbsynth.equilibrium, or projection.project)",
                         constraints=[worst])


def tangent_basis(system, Phi_q, position_rows=None):
    """(N, pivots): a basis N (n × k) of null(Φ_q) that is the identity on the k independent
    coordinates at the indices ``pivots`` (coordinate partitioning, QR with column pivoting).
    Raises SolveError near a singular position: a singular value of the row-equilibrated Φ_q
    between RANK_RTOL and NEAR_SINGULAR times the largest (equations.py's rank rule)."""
    n = system.n
    if Phi_q.shape[0] == 0:
        return np.eye(n), np.arange(n)
    norms = np.linalg.norm(Phi_q, axis=1)
    rows = norms > 0
    if not rows.any():
        return np.eye(n), np.arange(n)
    _, s, Vt = np.linalg.svd(Phi_q[rows] / norms[rows, None])
    rank = int(np.sum(s > RANK_RTOL * s[0])) if s.size else 0
    near = [x for x in s[:rank] if x < NEAR_SINGULAR * s[0]]
    if near:
        names = [] if position_rows is None else list(np.array(system.constraint_names)[position_rows])
        raise SolveError(f"model '{system.name}': the constraints are near a singular position here (a singular "
                         f"value {min(near) / s[0]:.2g} of their Jacobian, relative): the tangent space, and so "
                         "the linearization, changes over a tiny distance; no reliable spectrum",
                         constraints=names)
    null = Vt[rank:].T
    k = null.shape[1]
    if k == 0:
        return np.zeros((n, 0)), np.zeros(0, dtype=int)
    pivots = np.sort(scipy.linalg.qr(null.T, pivoting=True)[2][:k])
    N = null @ np.linalg.inv(null[pivots])
    N[pivots] = np.eye(k)
    return N, pivots


def _check_change_point(system, derivatives, t, q, qd, held, N):
    """SolveError at a singular position: a dependency wᵀΦ_q = 0 of the position rows whose
    second derivative wᵀφ_qq is not zero on the tangent space (a dependency that holds all
    along the manifold, such as a spatial loop's redundant rows, has it zero)."""
    Phi_q = held.Phi_q
    if Phi_q.shape[0] == 0 or N.shape[1] == 0:
        return
    norms = np.linalg.norm(Phi_q, axis=1)
    norms[norms == 0] = 1.0
    U, s, _ = np.linalg.svd(Phi_q / norms[:, None])
    rank = int(np.sum(s > RANK_RTOL * s[0])) if s.size else 0
    if rank == Phi_q.shape[0]:
        return
    Nn = N / np.linalg.norm(N, axis=0)
    generic = np.ones(Phi_q.shape[0]) / norms / np.sqrt(Phi_q.shape[0])
    reference = np.abs(derivatives.hessian(system, t, q, qd, generic, held.position_rows)).max()
    for w in U[:, rank:].T:
        curvature = Nn.T @ derivatives.hessian(system, t, q, qd, w / norms, held.position_rows) @ Nn
        if np.abs(curvature).max() > CHANGE_POINT_RTOL * max(reference, np.finfo(float).tiny):
            rows = _named(np.array(system.constraint_names)[held.position_rows], np.abs(w))
            raise SolveError(f"model '{system.name}': the constraints are at a singular position here (rows {rows} "
                             "are dependent at this configuration only: a change point of a loop); the tangent "
                             "space is no linear space here, so no linearization", constraints=rows)


def _named(names, weights):
    """The names whose weight is above NAME_RTOL times the largest."""
    weights = np.asarray(weights, dtype=float)
    top = weights.max(initial=0.0)
    return [str(c) for c, x in zip(names, weights) if top > 0 and x > NAME_RTOL * top]


@dataclass(frozen=True)
class HeldRows:
    """The position-level rows at a state: which rows (mask), Φ_q and Ψ_q = ∂ψ/∂q."""

    position_rows: np.ndarray
    Phi_q: np.ndarray
    Psi_q: np.ndarray


NON_ANALYTIC = (sp.Abs, sp.sign, sp.atan2, sp.Piecewise, sp.Min, sp.Max, sp.floor, sp.ceiling, sp.Heaviside,
                sp.re, sp.im)  # functions a complex step cannot differentiate through
COMPLEX_STEP = 1e-30  # Im f(x + i h)/h = f'(x) + O(h²): no cancellation, so h can be tiny


class BlockFunction:
    """Values of sympy expressions of (t, q, q̇, q̈, λ, p) and their exact Jacobians by q,
    q̇ and some parameters: by the complex step, Im f(x + ih e_j)/h, where the expressions
    are analytic (polynomials, sin, cos, sqrt …: all of a rigid body's and a joint's), else
    by compiled sympy Jacobians."""

    def __init__(self, q, qd, qdd, lam, p, exprs):
        exprs = sp.Matrix(exprs)
        args = (T_SYMBOL, list(q), list(qd), list(qdd), list(lam), list(p))
        self.analytic = not any(x.has(*NON_ANALYTIC) for x in exprs)
        if self.analytic:
            self._f = compile_function(args, [exprs], dtype=complex)
        else:
            self._f = compile_function(args, [exprs, jacobian(exprs, q), jacobian(exprs, qd), jacobian(exprs, p)])

    def jacobians(self, t, q, qd, qdd, lam, p, parameters=()):
        """(∂f/∂q, ∂f/∂q̇, ∂f/∂p[:, parameters]) at the given arguments."""
        if not self.analytic:
            _, f_q, f_qd, f_p = self._f(t, q, qd, qdd, lam, p)
            return f_q, f_qd, f_p[:, list(parameters)]
        state = [np.asarray(x, dtype=complex) for x in (q, qd, qdd, lam, p)]
        out = []
        for which, columns in ((0, range(len(q))), (1, range(len(qd))), (4, parameters)):
            cols = []
            for j in columns:
                moved = list(state)
                moved[which] = moved[which].copy()
                moved[which][j] += 1j * COMPLEX_STEP
                cols.append(self._f(t, *moved)[0].ravel().imag / COMPLEX_STEP)
            size = self._f(t, *state)[0].size if not cols else len(cols[0])
            out.append(np.column_stack(cols) if cols else np.zeros((size, 0)))
        return tuple(out)


class Derivatives:
    """The exact Jacobians the linearization needs, block by block as ``System.evaluate``
    assembles M, Q, A, b, C: each part's M q̈ − Q, each force element's −Q, each
    connector's −C, Aᵀλ, A q̈ − b and ψ, over its own coordinates (``BlockFunction``).
    Compiled once per model structure; parameters stay arguments, so ``with_parameters``
    reuses them."""

    def __init__(self, system):
        p = list(system.parameter_symbols)
        self._forces = []  # (indices, BlockFunction of G = M q̈ − Q − C)
        self._rows = []  # (indices, rows, BlockFunction of [Aᵀλ; A q̈ − b; ψ])
        where = {s: i for i, s in enumerate(system.q_symbols)}
        for part in system.parts:
            M, Q = part.symbolic()
            self._add_force([where[s] for s in part.q], M, -Q, system, p)
        for element in system.forces:
            indices = [int(i) for i in element.indices]
            self._add_force(indices, None, -element.symbolic().extract(indices, [0]), system, p)
        row = 0
        for con in system.connectors:
            indices, k = [int(i) for i in con.indices], con.size
            q, qd = [system.q_symbols[i] for i in indices], [system.qd_symbols[i] for i in indices]
            qdd, lam = _dummies("qdd", len(indices)), _dummies("lam", k)
            a = sp.Matrix(con.a.extract(list(range(k)), indices))
            C = sp.Matrix(con.C.extract(indices, [0]))
            if any(x != 0 for x in C):
                self._add_force(indices, None, -C, system, p)
            psi = con.psi if con.psi is not None else sp.zeros(k, 1)
            exprs = sp.Matrix.vstack(a.T * lam, a * qdd - con.b, psi)
            self._rows.append((np.array(indices, dtype=int), slice(row, row + k),
                               BlockFunction(q, qd, qdd, lam, p, exprs)))
            row += k
        self.parameters = tuple(system.parameters)

    def _add_force(self, indices, M, G, system, p):
        q, qd = [system.q_symbols[i] for i in indices], [system.qd_symbols[i] for i in indices]
        qdd = _dummies("qdd", len(indices))
        G = G if M is None else M * qdd + G
        self._forces.append((np.array(indices, dtype=int), BlockFunction(q, qd, qdd, [], p, G)))

    def rows(self, system, t, q, qd):
        """``HeldRows`` at (t, q, q̇)."""
        phi, _ = system.constraint_residuals(t, q, qd)
        position = ~np.isnan(phi)
        A = system.evaluate(t, q, qd).A
        Psi_q = np.zeros((len(phi), system.n))
        p = system.parameter_values
        for i, rows, f in self._rows:
            k = rows.stop - rows.start
            Psi_q[rows, i] = f.jacobians(t, q[i], qd[i], np.zeros(len(i)), np.zeros(k), p)[0][len(i) + k:]
        return HeldRows(position, A[position], Psi_q[position])

    def motion(self, system, t, q, qd, qdd, lam, inputs):
        """(R_q, R_q̇, S_q, S_q̇, F_u): the derivatives of R = Mq̈ − Q − C − Aᵀλ and S = Aq̈ − b
        by q and q̇, and of Q + C by the ``inputs`` (which must not enter A or b)."""
        n, m, p = system.n, len(system.constraint_names), system.parameter_values
        lam = np.zeros(m) if lam is None else np.asarray(lam, dtype=float)
        columns = [self.parameters.index(u) for u in inputs]
        R_q, R_qd, F_u = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, len(columns)))
        S_q, S_qd, S_u = np.zeros((m, n)), np.zeros((m, n)), np.zeros((m, len(columns)))
        for i, f in self._forces:
            G_q, G_qd, G_u = f.jacobians(t, q[i], qd[i], qdd[i], np.zeros(0), p, columns)
            R_q[np.ix_(i, i)] += G_q
            R_qd[np.ix_(i, i)] += G_qd
            F_u[i] -= G_u
        for i, rows, f in self._rows:
            d_q, d_qd, d_u = f.jacobians(t, q[i], qd[i], qdd[i], lam[rows], p, columns)
            own, k = len(i), rows.stop - rows.start
            R_q[np.ix_(i, i)] -= d_q[:own]
            R_qd[np.ix_(i, i)] -= d_qd[:own]
            S_q[rows, i], S_qd[rows, i], S_u[rows] = d_q[own:own + k], d_qd[own:own + k], d_u[own:own + k]
        entering = [u for u, j in zip(inputs, range(len(columns))) if np.abs(S_u[:, j]).max(initial=0.0) > 0]
        if entering:
            raise SolveError(f"model '{system.name}': input parameter(s) {entering} enter the constraints, "
                             "not only the forces; they cannot be inputs of B")
        return R_q, R_qd, S_q, S_qd, F_u

    def hessian(self, system, t, q, qd, w, position_rows):
        """∂(Φ_qᵀ w)/∂q: the second derivative of the combination wᵀφ of the position rows."""
        lam = np.zeros(len(position_rows))
        lam[position_rows] = w
        H, p = np.zeros((system.n, system.n)), system.parameter_values
        for i, rows, f in self._rows:
            if np.any(lam[rows]):
                H[np.ix_(i, i)] += f.jacobians(t, q[i], qd[i], np.zeros(len(i)), lam[rows], p)[0][:len(i)]
        return H


def _dummies(prefix, count):
    return sp.Matrix([sp.Dummy(f"{prefix}{i}") for i in range(count)]) if count else sp.zeros(0, 1)


def derivatives_of(system):
    """The ``Derivatives`` of ``system``, shared by the Systems that differ only in their
    parameter values (they share their parts, rows and forces)."""
    held = (system.parts, system.connectors, system.forces, tuple(system.parameters))
    key = tuple(id(x) for x in held[:3]) + held[3:]
    found = _cache.get(key)
    if found is None or any(a is not b for a, b in zip(found[0][:3], held[:3])):
        found = (held, Derivatives(system))
        _cache[key] = found
        while len(_cache) > _CACHE_SIZE:
            _cache.popitem(last=False)
    _cache.move_to_end(key)
    return found[1]
