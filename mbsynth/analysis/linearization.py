"""The linearization of a model's motion about a state, on its constraint manifold.

The motion q̈ = f(q, q̇, t) of (2.14) lives on the manifold of the position-level rows
φ(q, t) = 0 and their velocity forms ψ = Φ_q q̇ + φ_t = 0. Its linearization is taken in
independent coordinates of that manifold's tangent space, so redundant coordinates (a
rigid body's four quaternion numbers: each body's ``<body>.unit_quaternion`` is a row),
dependent loop coordinates and massless coordinates fixed by a holonomic balance
(``balances: auto``, model/balances.py, or a model's own, as models/paper/example3_m1_zero.yaml's
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

Non-holonomic rows (a rolling disk's slip, a knife edge) restrict velocities only: the
state is then x = [δu; δv], the k independent coordinates and s < k independent speeds v,
s of the q̇ picked by coordinate partitioning of the null space of all velocity rows
W = [Φ_q; A_v] (or named by the caller); δq̇ = S δv + c with S that null space's basis,
the identity on v, and W c = −Ψ_W N δu, c zero on v (the tangent of ψ = 0 for every
velocity row). A = [[rows u of T's velocity part], [v̇'s rows of dq̈ T]].

Steady motions. Linearized about a moving state, A is the variational equation of the
motion through that state; where the state is a steady motion (only cyclic coordinates
move, at constant rates: a bicycle rolling upright, a disk rolling in a circle, each body
turned by angles whose spin is the last, model/parts/euler_body.py), A is the same at every
instant of it and its eigenvalues are the motion's stability exponents. A cyclic coordinate
drives only other cyclic ones and a conserved speed changes at zero rate, so A is block
triangular in them: ``Linearization.eigenvalues`` takes the diagonal blocks of that form
(``blocks``; the zeros exact, named in ``cyclic``) and splits off the null directions
within a block, so an exponent near zero (a bicycle at its capsize speed) keeps its
accuracy next to the zeros.

Massless parts. The independent state is that of the masses: a massless coordinate is
fixed, at every instant, by its balance wᵀ(Q + C) = 0 (model/balances.py). Written as a
holonomic row (``balances: auto`` appends it so when it involves no velocities), the
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
eigenvalues at one instant no measure of stability), non-unique motion,
acceleration-level rows (a balance with velocities: a first-order equation of its own,
outside the state), Coulomb friction (not differentiable), a configuration near a singular
position (Φ_q nearly rank deficient: a loop near a change point) or at one (rows
dependent here whose dependency does not persist along the tangent directions, detected
by the rows' second derivatives).
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse
from ..core.memo import MEMO
import scipy.sparse.csgraph
import sympy as sp

from ..core.errors import SolveError
from ..model.data import shared, workspace
from .projection import relative_drift
from ..symbolic.derive import T_SYMBOL, compile_function, jacobian
from ..core.tolerances import (CHANGE_POINT_RTOL, COMPLEX_STEP, NAME_RTOL, NEAR_SINGULAR, ON_MANIFOLD_RTOL, RANK_RTOL,
                               STRUCTURAL_ZERO_RTOL)

_CACHE_SIZE = 8


@dataclass(frozen=True)
class Linearization:
    """ẋ = A x + B u about (t, q, q̇) in k independent coordinates and s independent
    speeds (s = k without non-holonomic rows; module docstring).

    ``A`` ((k + s) × (k + s)) and ``B`` ((k + s) × len(inputs)) act on the state
    x = [δq_ind; δv]; ``basis`` (n × k) maps δq_ind to the model's δq; ``state_map``
    (2n × (k + s)) maps x to (δq, δq̇); ``state_names`` are the independent coordinates,
    then the coordinates whose rates are the speeds with ``_dot``;
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
        """The eigenvalues of A (1/s), ordered by imaginary part then real part: those of the
        diagonal blocks of A's block-triangular form (``blocks``), so the zeros of cyclic
        coordinates and conserved speeds are exact and leave the others untouched (a
        defective zero block taken whole spreads into ±√ε), and within each block the
        directions A sends to zero (a cyclic direction mixed into the block, as a heading
        with the absolute yaw of a steered part) are split off first
        (``_deflated_eigenvalues``)."""
        A = self._structural
        values = [_deflated(A[np.ix_(b, b)])[0] for b in self.blocks]
        values = np.concatenate(values).astype(complex) if values else np.zeros(0, complex)
        return values[np.lexsort((values.real, values.imag))]

    @property
    def zero_states(self):
        """One name per exact zero of ``eigenvalues``: a cyclic coordinate or conserved speed
        alone in its block (``cyclic``), or a direction split off within a block, named by
        the states it moves, largest 1 (``rear.wheel.angle_z + front.wheel.angle_z``: the
        heading of the whole bicycle, steered part and all)."""
        A, names = self._structural, []
        for b in self.blocks:
            directions = _deflated(A[np.ix_(b, b)])[1]
            names += [_combination([self.state_names[i] for i in b], d) for d in directions.T]
        return tuple(names)

    @property
    def blocks(self):
        """The state indices of the diagonal blocks of A's block-triangular form: the strongly
        connected components of the graph i ← j where |A_ij| > STRUCTURAL_ZERO_RTOL times its
        row's largest entry."""
        links = self._structural != 0
        if not links.size:
            return []
        count, label = scipy.sparse.csgraph.connected_components(scipy.sparse.csr_matrix(links), connection="strong")
        return [np.flatnonzero(label == c) for c in range(count)]

    @property
    def cyclic(self):
        """The states alone in their block with eigenvalue 0: cyclic coordinates (nothing
        depends on them but other such states: the wheel angles, the position and heading on
        the ground) and conserved speeds (their rate is zero: the forward speed)."""
        A = self._structural
        return tuple(self.state_names[b[0]] for b in self.blocks if b.size == 1 and A[b[0], b[0]] == 0)

    @property
    def _structural(self):
        """A with the entries below STRUCTURAL_ZERO_RTOL times their row's largest set to 0."""
        scale = np.abs(self.A).max(axis=1, keepdims=True, initial=0.0)
        return np.where(np.abs(self.A) > STRUCTURAL_ZERO_RTOL * scale, self.A, 0.0)


def _deflated(A):
    """(the eigenvalues of the square A, its zero directions): zero for each direction of
    its null space (singular values below STRUCTURAL_ZERO_RTOL times the largest), split off
    by the orthogonal change of basis [Z W] (A Z = 0 makes it block-triangular), and again
    on WᵀAW until none is left; then those of what remains. Exact zeros stay zero and a
    small eigenvalue near them (a mode at its stability boundary) keeps its accuracy. The
    directions: A's columns (one per zero), Z and the later ones turned back by the Ws."""
    found, basis = [], np.eye(A.shape[0])
    while A.size:
        _, sv, Vt = np.linalg.svd(A)
        null = sv <= STRUCTURAL_ZERO_RTOL * sv[0] if sv[0] > 0 else np.ones(sv.size, bool)
        if not null.any():
            break
        found.append(basis @ Vt[null].T)
        W = Vt[~null].T
        A, basis = W.T @ A @ W, basis @ W
    rest = np.linalg.eigvals(A) if A.size else np.zeros(0)
    directions = np.hstack(found) if found else np.zeros((basis.shape[0], 0))
    return np.concatenate([rest.astype(complex), np.zeros(directions.shape[1], complex)]), directions


def _combination(names, direction):
    """The direction as a sum of the ``names`` it moves (components above NAME_RTOL of
    the largest), largest 1: ``x``, ``x + y``, ``x − 0.5 y``."""
    direction = direction / direction[np.argmax(np.abs(direction))]
    terms = [(x, name) for x, name in zip(direction, names) if abs(x) > NAME_RTOL]
    text = ""
    for x, name in terms:
        size = "" if abs(abs(x) - 1) <= NAME_RTOL else f"{abs(x):.3g} "
        text += (f"{'−' if x < 0 else ''}" if not text else f" {'−' if x < 0 else '+'} ") + size + name
    return text


def linearize(model, t, q, qd, inputs=None, speeds=None):
    """The ``Linearization`` of the motion of ``model`` (a System, at its parameter values,
    or a Data, at its own) about (t, q, q̇) (module docstring).

    ``inputs``: parameter names B is taken for (they must enter only the forces Q + C);
    by default the robots' joint torques ``tau_*`` and the parameters named ``tau_*`` or
    ``u_*``. ``speeds``: with non-holonomic rows, the coordinates whose rates are the
    independent speeds, or those rates' names as ``state_names`` and ``mbsynth modes`` give
    them (``<coordinate>_dot``); by default picked by coordinate partitioning. Both are lists
    of names (TypeError for one string). Raises SolveError where no linearization on the
    manifold exists."""
    data = workspace(model)
    system = data.model
    q, qd = finite_state(system, q, qd)
    inputs = default_inputs(system) if inputs is None else names_of(inputs, "inputs")
    speeds = None if speeds is None else names_of(speeds, "speeds")
    _refuse_unsupported(data, t, q, qd)
    motion = data.motion(t, q, qd)
    if not motion.unique:
        moving = _named(system.coordinates, np.abs(motion.nullspace).max(axis=1))
        raise SolveError(f"model '{system.name}': the motion is not unique at this state "
                         f"({motion.nullspace.shape[1]} indeterminate direction(s) in {moving}): "
                         "no linearization (add the massless parts' force balances with balances: auto)",
                         coordinates=moving)
    derivatives = derivatives_of(system)
    arrays = data.evaluate(t, q, qd)
    held = derivatives.rows(data, t, q, qd)
    N, pivots = tangent_basis(system, held.Phi_q, held.position_rows)
    _check_change_point(data, derivatives, t, q, qd, held, N)
    n, k = system.n, N.shape[1]
    S, speeds = _speeds(system, held, N, pivots, speeds)
    s = S.shape[1]
    T = np.zeros((2 * n, k + s))
    T[:n, :k] = N
    T[n:, k:] = S
    W, Psi_q = held.velocity_matrices
    dependent = np.setdiff1d(np.arange(n), speeds)
    if W.size and dependent.size:
        T[n + dependent, :k] = -np.linalg.lstsq(W[:, dependent], Psi_q @ N, rcond=None)[0]
    R_q, R_qd, S_q, S_qd, F_p = derivatives.motion(data, t, q, qd, motion.qdd, motion.lam, inputs)
    m = arrays.A.shape[0]
    kkt = np.block([[arrays.M, -arrays.A.T], [arrays.A, np.zeros((m, m))]])
    right = np.hstack([-np.vstack([np.hstack([R_q, R_qd]), np.hstack([S_q, S_qd])]) @ T,
                       np.vstack([F_p, np.zeros((m, len(inputs)))])])
    scale = np.abs(kkt).max(axis=1, keepdims=True)
    scale[scale == 0] = 1.0
    dqdd = np.linalg.lstsq(kkt / scale, right / scale, rcond=None)[0][:n, :][speeds]
    A = np.vstack([T[n:][pivots], dqdd[:, :k + s]])
    B = np.vstack([np.zeros((k, len(inputs))), dqdd[:, k + s:]])
    names = tuple(system.coordinates[i] for i in pivots) + tuple(f"{system.coordinates[i]}_dot" for i in speeds)
    return Linearization(A, B, N, T, names, inputs, system.coordinates, float(t), q, qd, motion.qdd)


def names_of(value, what):
    """``value``, a collection of names, as a tuple; TypeError for one string (it would be
    read letter by letter)."""
    if isinstance(value, str):
        raise TypeError(f"{what}: a list of names, got the string {value!r} (write [{value!r}])")
    return tuple(value)


def _speeds(system, held, N, pivots, names):
    """(S, speeds): the basis S (n × s) of the velocities every row allows at the state
    (null of Φ_q and of the non-holonomic rows' A), the identity on the s independent
    speeds at indices ``speeds``: the coordinates ``names`` (or their rates, ``_dot``) when
    given, else those picked by coordinate partitioning (``tangent_basis``). Without
    non-holonomic rows, (N, pivots)."""
    W, _ = held.velocity_matrices
    if names is None:
        if not held.velocity_rows.any():
            return N, pivots
        return tangent_basis(system, W, held.position_rows | held.velocity_rows)
    given = list(names)
    names = [c if c in system.coordinates else c.removesuffix("_dot") for c in given]  # a speed's rate name
    unknown = [g for g, c in zip(given, names) if c not in system.coordinates]
    if unknown:
        raise SolveError(f"model '{system.name}': unknown speed(s) {unknown}: name coordinates or their rates "
                         "(<coordinate>_dot, as mbsynth modes lists the independent speeds)", coordinates=unknown)
    S, _ = tangent_basis(system, W, held.position_rows | held.velocity_rows)
    speeds = np.array(sorted(system.coordinates.index(c) for c in names), dtype=int)
    if speeds.size != S.shape[1] or np.linalg.matrix_rank(S[speeds]) < S.shape[1]:
        raise SolveError(f"model '{system.name}': speeds {given} do not fix the velocities the rows allow "
                         f"({S.shape[1]} independent speed(s) here, e.g. "
                         f"{[system.coordinates[i] for i in tangent_basis(system, W)[1]]})",
                         coordinates=names)
    return S @ np.linalg.inv(S[speeds]), speeds


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
    return _time_rows(system.constraints)


@MEMO.function(_CACHE_SIZE)
def _time_rows(constraints):
    found = []
    for con in constraints:
        own = con.phi if con.phi is not None else con.psi if con.psi is not None else con.b
        found += [name for name, x in zip(con.row_names, own) if x.has(T_SYMBOL)]
    return tuple(found)


def prescribed_motion(model, t, q, qd):
    """The rows that depend on time (``time_rows``) where the state (t, q, q̇) moves: all of
    them where q̇ ≠ 0, else those whose ∂φ/∂t (their ψ at q̇ = 0, at the parameter values of
    ``model``, a System or a Data) is not zero; [] elsewhere."""
    data = workspace(model)
    system = data.model
    rows = time_rows(system)
    if not rows or np.any(qd):
        return list(rows)
    _, rate = data.constraint_residuals(t, q, np.zeros_like(q))
    return [name for name, x in zip(system.constraint_names, rate) if name in rows and abs(x) > ON_MANIFOLD_RTOL]


def _refuse_unsupported(data, t, q, qd):
    """SolveError for what the linearization does not cover (module docstring)."""
    system = data.model
    friction = [c.name for c in system.constraints if getattr(c, "coulomb", None)]
    if friction:
        raise SolveError(f"model '{system.name}': Coulomb friction at {friction} is not differentiable; "
                         "no linearization", constraints=friction)
    phi, psi = data.constraint_residuals(t, q, qd)
    acceleration_only = [name for name, x, y in zip(system.constraint_names, phi, psi) if np.isnan(x) and np.isnan(y)]
    if acceleration_only:
        raise SolveError(f"model '{system.name}': rows {acceleration_only} restrict accelerations only (a balance "
                         "with velocities, a servo's acceleration row): they are first-order equations of their own, "
                         "outside the state (q, speeds) the linearization takes (write a massless part's balance as "
                         "a holonomic row, or use balances: auto)", constraints=acceleration_only)
    moving = prescribed_motion(data, t, q, qd)
    if moving:
        why = "q̇ ≠ 0" if np.any(qd) else f"∂φ/∂t ≠ 0 at t = {t:g}"
        raise SolveError(f"model '{system.name}': rows {moving} depend on time (a prescribed "
                         f"motion) and the state moves ({why}): the motion about it is a time-varying system, "
                         "whose eigenvalues at one instant say nothing of its stability; linearize where the rows "
                         "hold still (q̇ = 0 and ∂φ/∂t = 0), or with the prescribed motion held at a constant",
                         constraints=moving)
    drift = relative_drift(data, t, q, qd)
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


def _check_change_point(data, derivatives, t, q, qd, held, N):
    """SolveError at a singular position: a dependency wᵀΦ_q = 0 of the position rows whose
    second derivative wᵀφ_qq is not zero on the tangent space (a dependency that holds all
    along the manifold, such as a spatial loop's redundant rows, has it zero)."""
    system = data.model
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
    reference = np.abs(derivatives.hessian(data, t, q, qd, generic, held.position_rows)).max()
    for w in U[:, rank:].T:
        curvature = Nn.T @ derivatives.hessian(data, t, q, qd, w / norms, held.position_rows) @ Nn
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
    """The rows at a state: the position-level rows (mask), their Φ_q and Ψ_q = ∂ψ/∂q; the
    velocity-level (non-holonomic) rows (mask), their A_v and their ∂ψ/∂q, Ψv_q."""

    position_rows: np.ndarray
    Phi_q: np.ndarray
    Psi_q: np.ndarray
    velocity_rows: np.ndarray
    A_v: np.ndarray
    Psi_v_q: np.ndarray

    @property
    def velocity_matrices(self):
        """(W, Ψ_W): every row that restricts velocities, [Φ_q; A_v], and its ∂ψ/∂q."""
        return np.vstack([self.Phi_q, self.A_v]), np.vstack([self.Psi_q, self.Psi_v_q])


NON_ANALYTIC = (sp.Abs, sp.sign, sp.atan2, sp.Piecewise, sp.Min, sp.Max, sp.floor, sp.ceiling, sp.Heaviside,
                sp.re, sp.im)  # functions a complex step cannot differentiate through


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
    constraint's −C, Aᵀλ, A q̈ − b and ψ, over its own coordinates (``BlockFunction``).
    Compiled once per model structure; the parameter values are arguments (a Data's
    ``parameter_values`` at each call), so the models and Data of one structure share them."""

    def __init__(self, system):
        p = list(system.parameter_symbols)
        self._forces = []  # (indices, BlockFunction of G = M q̈ − Q − C)
        self._rows = []  # (indices, rows, BlockFunction of [Aᵀλ; A q̈ − b; ψ])
        where = {s: i for i, s in enumerate(system.q_symbols)}
        for part in system.parts:
            own = part.derivatives()  # a part that evaluates (2.1) itself gives its own exact Jacobians
            if own is not None:
                self._forces.append((np.array([where[s] for s in part.q], dtype=int), own))
                continue
            M, Q = part.symbolic()
            self._add_force([where[s] for s in part.q], M, -Q, system, p)
        for element in system.forces:
            indices = [int(i) for i in element.indices]
            self._add_force(indices, None, -element.symbolic().extract(indices, [0]), system, p)
        row = 0
        for con in system.constraints:
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

    def rows(self, data, t, q, qd):
        """``HeldRows`` at (t, q, q̇) and the parameter values of ``data``."""
        phi, psi = data.constraint_residuals(t, q, qd)
        position, velocity = ~np.isnan(phi), np.isnan(phi) & ~np.isnan(psi)
        A = data.evaluate(t, q, qd).A
        Psi_q = np.zeros((len(phi), data.model.n))
        p = data.parameter_values
        for i, rows, f in self._rows:
            k = rows.stop - rows.start
            Psi_q[rows, i] = f.jacobians(t, q[i], qd[i], np.zeros(len(i)), np.zeros(k), p)[0][len(i) + k:]
        return HeldRows(position, A[position], Psi_q[position], velocity, A[velocity], Psi_q[velocity])

    def motion(self, data, t, q, qd, qdd, lam, inputs):
        """(R_q, R_q̇, S_q, S_q̇, F_u): the derivatives of R = Mq̈ − Q − C − Aᵀλ and S = Aq̈ − b
        by q and q̇, and of Q + C by the ``inputs`` (which must not enter A or b), at the
        parameter values of ``data``."""
        system = data.model
        n, m, p = system.n, len(system.constraint_names), data.parameter_values
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

    def hessian(self, data, t, q, qd, w, position_rows):
        """∂(Φ_qᵀ w)/∂q: the second derivative of the combination wᵀφ of the position rows,
        at the parameter values of ``data``."""
        lam = np.zeros(len(position_rows))
        lam[position_rows] = w
        n = data.model.n
        H, p = np.zeros((n, n)), data.parameter_values
        for i, rows, f in self._rows:
            if np.any(lam[rows]):
                H[np.ix_(i, i)] += f.jacobians(t, q[i], qd[i], np.zeros(len(i)), lam[rows], p)[0][:len(i)]
        return H


def _dummies(prefix, count):
    return sp.Matrix([sp.Dummy(f"{prefix}{i}") for i in range(count)]) if count else sp.zeros(0, 1)


def derivatives_of(system):
    """The ``Derivatives`` of ``system``, shared by the models of one structure (they
    differ only in parameter values: data.Shared, in the one cache)."""
    held = shared(system)
    if held.derivatives is None:
        held.derivatives = Derivatives(system)
    return held.derivatives
