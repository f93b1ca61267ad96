"""Reduction of an FE model (matrices.py) to few coordinates η, u = T η (u: the n nodal
DOFs), with reduced matrices Tᵀ M T and Tᵀ K T.

- ``craig_bampton(fe, interface, ...)``: η = (u_b, p): u_b the DOFs of the interface
  nodes, in the order the nodes are given, 6 (or 3) each, *equal to* those nodes'
  displacements and rotations; p the amplitudes of the fixed-interface normal modes
  (u_b = 0). T = [Ψ Φ]: the constraint modes Ψ (u_b = I, the rest at static equilibrium,
  −K_ii⁻¹ K_ib) and the modes Φ (M-orthonormal, K_ii Φ = M_ii Φ Ω²). A static load at
  the interface is reproduced exactly, whatever the number of modes. ``hold(node)`` removes
  an interface node's columns: that node then moves with a floating frame.
- ``free_interface(fe, interface, ...)``: η = amplitudes of the lowest normal modes of the
  whole unconstrained model (rigid-body modes kept unless ``rigid=False``); the interface
  nodes' DOFs are rows of T.

Modes are chosen by ``count`` or ``max_frequency`` (Hz, every mode up to it). ``normal_modes``
solves K φ = ω² M φ in shift-invert form about a negative shift (so rigid-body modes, K
singular, are found too), by scipy's ``eigsh`` from a fixed start or, for small models, a
dense solver; M may be singular (lumped: rotations without mass), its infinite eigenvalues
are never returned. The Ritz vectors are refined by the projected problem: the modes are
M-orthonormal to rounding.

Repeated frequencies (a round section's two bending planes, a symmetric model's): modes
whose ω² agree to FE_CLUSTER_RTOL span one eigenspace, whose basis a solver leaves to rounding.
Each such cluster gets a fixed basis (``_fixed_basis``: the shape of largest component at the
first DOF that has it, then the same in what is left), so every process gives the same modes.
A count that would split a cluster is refused (a part's coordinates would depend on which of
equal modes came first); ``max_frequency`` takes a cluster whole or leaves it out.

Scale: ω² of the modes a double-precision K resolves lie above FE_ZERO_RTOL · tr K / tr M (rigid-body
modes come out at rounding, a few ε of the largest ω²); the shift sits just above that level,
below every such mode whatever the model's size, so the modes sought are the operator's best
separated ones. A Craig–Bampton interface that leaves a motion free (a rigid-body one, from the
nodes' geometry; a mechanism, or a model too fine to resolve, from its lowest mode) is refused.
"""

from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from ...core.errors import ModelError
from .invariants import rigid_body_modes
from .matrices import FEModel
from ...core.tolerances import (FE_CLUSTER_RTOL, FE_DENSE_SHIFT_RTOL, FE_FINITE_RTOL, FE_RIGID_RANK_RTOL,
                                FE_SHIFT_RTOL, FE_TIE_RTOL, FE_ZERO_RTOL)

RIGID_MODES_MAX = 6  # a free body has at most six rigid-body modes; more zero modes: a mechanism
FIRST_BATCH = 12  # modes asked for first when they are chosen by frequency (doubled until past it)
LOOK_PAST = 4  # modes asked for beyond a count, to see whether the last one's frequency repeats
DENSE_MODES_MAX = 120  # up to this many DOFs the modes come from a dense solver, every finite one at once
EIGSH_RESTARTS = 300  # eigsh's restarts at most (tens suffice about this shift): a spectrum lost in rounding ends
START_SEED = 0  # eigsh's start vector (and any restart it draws) from this seed: the same modes in every process


@dataclass(frozen=True, eq=False)
class Reduction:
    """A reduced FE model: u = ``basis`` @ η (n × r), ``mass`` and ``stiffness`` (r × r);
    ``interface`` (FE node indices), ``modes`` (the columns of η that are modal
    amplitudes, a slice), ``frequencies`` (their normal modes' ω, rad/s: fixed-interface for
    Craig–Bampton, free for free-interface), ``method``, the ``fe`` model it reduces and the
    interface nodes ``held`` at zero (``hold``)."""

    fe: FEModel
    method: str
    interface: tuple
    basis: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    modes: slice
    frequencies: np.ndarray
    held: tuple = ()

    @property
    def size(self):
        return self.basis.shape[1]

    def node_rows(self, node):
        """Rows of ``basis`` giving ``node``'s DOFs: its displacement is basis[rows] @ η."""
        return self.fe.node_dofs(node)

    def interface_columns(self, node):
        """Craig–Bampton: the columns of η that are ``node``'s DOFs themselves."""
        if self.method != "craig_bampton" or node not in self.interface or node in self.held:
            why = "is held (it moves with the frame)" if node in self.held else "has no coordinates of its own"
            raise ModelError(f"{self.fe.source}: node {node} {why} in this {self.method} reduction "
                             f"(interface nodes: {list(self.interface)}, held: {list(self.held)})")
        d = self.fe.dofs_per_node
        k = [j for j in self.interface if j not in self.held].index(node)
        return np.arange(k * d, (k + 1) * d)

    def hold(self, node):
        """This Craig–Bampton reduction with the interface ``node``'s DOFs held at zero (their
        columns removed): the node moves with a floating frame, the reference condition that
        leaves the frame the only rigid-body motion (invariants.py)."""
        columns = self.interface_columns(node)
        keep = np.setdiff1d(np.arange(self.size), columns)
        shift = len(columns)
        return replace(self, basis=self.basis[:, keep], mass=self.mass[np.ix_(keep, keep)],
                       stiffness=self.stiffness[np.ix_(keep, keep)], held=self.held + (node,),
                       modes=slice(self.modes.start - shift, self.modes.stop - shift))


def craig_bampton(fe, interface, *, count=None, max_frequency=None, shift=None):
    """The Craig–Bampton reduction of ``fe`` at the nodes ``interface`` (indices into
    fe.nodes), with the fixed-interface modes chosen by ``count`` or ``max_frequency``
    (count=0: constraint modes only, Guyan's reduction)."""
    nodes = _interface(fe, interface)
    b = np.concatenate([fe.node_dofs(j) for j in nodes]) if nodes else np.zeros(0, int)
    i = np.setdiff1d(np.arange(fe.size), b)
    K, M = fe.stiffness.tocsc(), fe.mass.tocsc()
    Kii, Mii = K[i][:, i], M[i][:, i]
    T = np.zeros((fe.size, len(b)))
    T[b, np.arange(len(b))] = 1.0
    singular = f"{fe.source}: with the interface nodes {list(nodes)} held, the stiffness is singular: "
    if len(b):
        _stops_rigid_motion(fe, b, singular)
        try:
            interior = scipy.sparse.linalg.splu(Kii, **_SYMMETRIC)
        except RuntimeError as err:
            raise ModelError(singular + "a motion of the other nodes has no stiffness (a mechanism, or a piece "
                             "the interface does not reach)") from err
        T[i, :] = -interior.solve(K[i][:, b].toarray())
        if len(i):
            _resolved(Mii, Kii, _rayleigh_bound(fe, i, Mii, interior), singular)
    omega, shapes = normal_modes(Mii, Kii, count=count, max_frequency=max_frequency, shift=shift, source=fe.source)
    if len(b) and len(i):
        _resolved(Mii, Kii, omega[0] ** 2 if len(omega) else _lowest(Mii, Kii, shift, fe.source), singular)
    Phi = np.zeros((fe.size, len(omega)))
    Phi[i] = shapes
    return _reduction(fe, "craig_bampton", nodes, np.hstack([T, Phi]), slice(len(b), len(b) + len(omega)), omega)


def free_interface(fe, interface=(), *, count=None, max_frequency=None, rigid=True, shift=None):
    """The lowest normal modes of the unconstrained ``fe`` as the basis (``rigid=False``: the
    rigid-body modes, at most six, left out, and ``count`` counts the others); ``interface``
    only names the nodes a part attaches to."""
    nodes = _interface(fe, interface)
    omega, shapes = normal_modes(fe.mass, fe.stiffness, count=count, max_frequency=max_frequency, shift=shift,
                                 rigid=rigid, source=fe.source)
    return _reduction(fe, "free_interface", nodes, shapes, slice(0, len(omega)), omega)


def normal_modes(M, K, *, count=None, max_frequency=None, shift=None, rigid=True, source="FE model"):
    """(ω in rad/s ascending, shapes n × k M-orthonormal) of K φ = ω² M φ: the ``count``
    lowest, or every one with ω ≤ 2π ``max_frequency``; ``rigid=False``: the zero modes
    (ω² at the rounding level, at most RIGID_MODES_MAX) left out, ``count`` counting the
    others. Equal frequencies come with a fixed basis; a count that splits them is refused
    (the module's docstring). ``shift`` (ω², > 0): the shift-invert point is −shift (default
    FE_SHIFT_RTOL · tr K / tr M). Up to DENSE_MODES_MAX DOFs a dense solver, above it eigsh."""
    if (count is None) == (max_frequency is None):
        raise ModelError(f"{source}: choose the modes by count or by max_frequency (one of them)")
    M, K = scipy.sparse.csc_array(M), scipy.sparse.csc_array(K)
    n = M.shape[0]
    most = n if n <= DENSE_MODES_MAX else n - 2
    if count is not None and not (isinstance(count, (int, np.integer)) and not isinstance(count, bool)
                                  and 0 <= count <= most):
        raise ModelError(f"{source}: the mode count must be an integer from 0 to {most}, not {count!r}")
    if max_frequency is not None and not max_frequency >= 0:
        raise ModelError(f"{source}: max_frequency must be ≥ 0 Hz, not {max_frequency!r}")
    if count == 0 or n == 0:
        return np.zeros(0), np.zeros((n, 0))
    zero = FE_ZERO_RTOL * _scale(M, K)
    limit = None if max_frequency is None else (2 * np.pi * max_frequency) ** 2

    def first_kept(lam):
        return 0 if rigid else int(np.sum(lam <= zero))

    def stop_at(lam, clusters):
        """Where the modes kept end (an index into lam), or None if lam does not reach past it."""
        first = first_kept(lam)
        if count is not None:
            return first + count if first + count <= len(lam) else None
        return next((start for start, end in clusters if start >= first and np.mean(lam[start:end]) > limit), None)

    def enough(lam, clusters):
        stop = stop_at(lam, clusters)
        return np.sum(lam <= zero) > RIGID_MODES_MAX or (stop is not None and stop <= clusters[-1][0])

    batch = FIRST_BATCH if count is None else count + (0 if rigid else RIGID_MODES_MAX) + LOOK_PAST
    lam, vectors = _solve(M, K, shift, batch, enough, zero, source)
    if np.sum(lam <= zero) > RIGID_MODES_MAX:
        raise ModelError(f"{source}: {np.sum(lam <= zero)} modes or more at zero frequency (ω² ≤ {zero:.3g}, the "
                         f"rounding level of K), more than a body's {RIGID_MODES_MAX} rigid-body motions: a mechanism, "
                         f"unconnected pieces, or {_TOO_FINE}")
    first, clusters = first_kept(lam), _clusters(lam, zero)
    stop = stop_at(lam, clusters)
    if stop is None and count is not None:
        found = (f"eigsh finds only {len(lam) - first}" if n > DENSE_MODES_MAX else
                 f"the mass matrix gives only {len(lam) - first} finite ones")
        why = f"at most n − 2 = {n - 2} modes" if n > DENSE_MODES_MAX else "a lumped mass gives rotations none"
        raise ModelError(f"{source}: {count} modes asked for, but {found}"
                         + (" besides the rigid-body ones" if first else "") + f" ({why})")
    if stop is None:
        if n <= DENSE_MODES_MAX:
            stop = len(lam)  # every finite mode lies below max_frequency
        else:
            raise ModelError(f"{source}: more than {len(lam)} modes lie below {max_frequency} Hz (eigsh takes at most "
                             "n − 2): choose them by count, or a lower max_frequency")
    if stop < len(lam) and not any(start == stop for start, _ in clusters):
        start, end = next((start, end) for start, end in clusters if start < stop < end)
        hz = np.sqrt(max(np.mean(lam[start:end]), 0.0)) / (2 * np.pi)
        raise ModelError(f"{source}: {stop - first} modes would split modes {start + 1 - first} to {end - first}, "
                         f"which share the frequency {hz:.6g} Hz (a repeated mode, as a round section's two bending "
                         f"planes): ask for {start - first} or {end - first} modes, or choose them by max_frequency")
    lam, vectors = _fixed_basis(M, K, lam[:stop], vectors[:, :stop], [c for c in clusters if c[1] <= stop])
    return np.sqrt(np.clip(lam[first:], 0.0, None)), vectors[:, first:]


def _solve(M, K, shift, batch, enough, zero, source):
    """(λ ascending, M-orthonormal vectors) of the lowest modes: every finite one (dense), or
    eigsh's, ``batch`` of them doubled until ``enough(λ, clusters)`` or n − 2 of them."""
    n = M.shape[0]
    if n <= DENSE_MODES_MAX:
        return _dense_modes(M, K, -(shift if shift is not None else FE_DENSE_SHIFT_RTOL * _scale(M, K)), source)
    sigma = -(shift if shift is not None else FE_SHIFT_RTOL * _scale(M, K))
    try:
        inverse = scipy.sparse.linalg.splu(K - sigma * M, **_SYMMETRIC)
    except RuntimeError as err:
        raise ModelError(_NEITHER.format(source)) from err
    operator = scipy.sparse.linalg.LinearOperator((n, n), matvec=inverse.solve, dtype=float)
    k = min(batch, n - 2)
    while True:
        lam, vectors = _sparse_modes(M, K, sigma, operator, k, source)
        if k == n - 2 or enough(lam, _clusters(lam, zero)):
            return lam, vectors
        k = min(2 * k, n - 2)


def _lowest(M, K, shift, source):
    """The lowest ω² of K φ = ω² M φ."""
    return _solve(M, K, shift, 1, lambda lam, clusters: True, 0.0, source)[0][0]


def _dense_modes(M, K, sigma, source):
    """Every finite mode, by the symmetric form of shift-invert: with K − σM = LLᵀ, the
    eigenvalues μ = 1/(λ − σ) of L⁻¹ M L⁻ᵀ (μ = 0: an infinite mode of a singular M)."""
    try:
        L = np.linalg.cholesky((K - sigma * M).toarray())
    except np.linalg.LinAlgError as err:
        raise ModelError(_NEITHER.format(source)) from err
    half = scipy.linalg.solve_triangular(L, M.toarray(), lower=True)
    mu, Y = scipy.linalg.eigh(scipy.linalg.solve_triangular(L, half.T, lower=True))
    finite = mu * -sigma > FE_FINITE_RTOL
    vectors = scipy.linalg.solve_triangular(L.T, Y[:, finite][:, ::-1], lower=False)
    return _ritz(M, K, vectors, source)


def _sparse_modes(M, K, sigma, operator, k, source):
    """The ``k`` lowest modes by eigsh about σ, from a fixed start vector, then one step of
    inverse iteration (``operator``: (K − σM)⁻¹) and the Ritz refinement: a shift far below
    the modes amplifies the rigid-body ones by λ/|σ|, whose traces in the others this removes."""
    rng = np.random.default_rng(START_SEED)
    try:
        lam, vectors = scipy.sparse.linalg.eigsh(K, k=k, M=M, sigma=sigma, OPinv=operator, which="LM",
                                                 v0=rng.uniform(-1.0, 1.0, M.shape[0]), rng=rng,
                                                 maxiter=EIGSH_RESTARTS)
    except scipy.sparse.linalg.ArpackError as err:
        raise ModelError(f"{source}: eigsh found no {k} modes ({err}); fewer modes, more than the mass matrix has "
                         f"finite ones, or {_TOO_FINE}?") from err
    return _ritz(M, K, operator.matmat(M @ vectors), source)


_NEITHER = ("{}: K + s M is singular for every s: some motion has neither mass nor stiffness "
            "(with a lumped mass, a free beam's twist about its own axis)")
_TOO_FINE = ("a model whose stiffness spans more scales than double precision resolves (an Euler–Bernoulli "
             "beam's ω² spread grows as elements⁴: fewer elements, or theory: timoshenko)")
_SYMMETRIC = dict(permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})  # Cholesky's


def _ritz(M, K, vectors, source):
    """The Rayleigh–Ritz refinement on span(vectors): M-orthonormal modes, ascending, and
    their Rayleigh quotients (accurate to the rounding of K φ, where the projected problem's
    eigenvalues carry an error of ε times the largest)."""
    Mr = vectors.T @ (M @ vectors)
    Kr = vectors.T @ (K @ vectors)
    try:
        _, V = scipy.linalg.eigh((Kr + Kr.T) / 2, (Mr + Mr.T) / 2)
    except np.linalg.LinAlgError as err:
        raise ModelError(f"{source}: more modes asked for than the mass matrix has finite ones "
                         "(a lumped mass gives rotations none)") from err
    vectors = vectors @ V
    return np.einsum("ik,ik->k", vectors, K @ vectors), vectors


def _clusters(lam, zero):
    """[(start, end)] of the runs of ascending λ that are one eigenspace: neighbours within
    FE_CLUSTER_RTOL of the larger, or both at the zero level."""
    bounds = [0]
    for j in range(1, len(lam)):
        if lam[j] - lam[j - 1] > FE_CLUSTER_RTOL * abs(lam[j]) and lam[j] > zero:
            bounds.append(j)
    return list(zip(bounds, bounds[1:] + [len(lam)]))


def _fixed_basis(M, K, lam, vectors, clusters):
    """Each cluster's M-orthonormal basis made independent of the one the solver gave: its
    first vector is the cluster's shape of largest component at the DOF of most kinetic
    energy (√M_jj |φ_j| largest; the first DOF within FE_TIE_RTOL of it), that component
    positive, then the same in the part of the cluster M-orthogonal to it, and so on: a
    round beam's pair bends in the section's y, then z plane. λ: the vectors' Rayleigh
    quotients."""
    vectors, lam = vectors.copy(), lam.copy()
    weight = np.sqrt(np.clip(M.diagonal(), 0.0, None))
    for start, end in clusters:
        W = vectors[:, start:end]
        fixed = []
        while W.shape[1]:
            reach = weight * np.linalg.norm(W, axis=1)  # the largest weighted component a unit shape of span(W) has
            dof = int(np.argmax(reach >= (1 - FE_TIE_RTOL) * reach.max()))
            a = W[dof] / np.linalg.norm(W[dof])
            fixed.append(W @ a)
            W = W @ scipy.linalg.null_space(a[None, :])
        block = np.column_stack(fixed)
        vectors[:, start:end] = block
        lam[start:end] = np.einsum("ik,ik->k", block, K @ block)
    return lam, vectors


def _stops_rigid_motion(fe, b, singular):
    """Refuse an interface (DOFs ``b``) that leaves the FE model a rigid-body motion its K
    does not resist: a combination of the rigid-body modes (the nodes' geometry) zero at
    every interface DOF, with ω² at the rounding level."""
    G = rigid_body_modes(fe)
    free = scipy.linalg.null_space(G[b], rcond=FE_RIGID_RANK_RTOL)
    for a in free.T:
        u = G @ a
        if u @ (fe.stiffness @ u) <= FE_ZERO_RTOL * _scale(fe.mass, fe.stiffness) * (u @ (fe.mass @ u)):
            raise ModelError(singular + "the interface does not stop every rigid-body motion (add interface nodes: "
                             "three not on one line for nodes without rotations)")


def _rayleigh_bound(fe, i, Mii, interior):
    """Rayleigh's estimate of the lowest ω² with the interface held, from the static deflections
    u = K_ii⁻¹ M_ii g under the model's own weight along each axis: min (gᵀM_ii u)/(uᵀM_ii u),
    at least the lowest ω² (three solves with the factor at hand)."""
    g = (np.arange(fe.size)[i] % fe.dofs_per_node)[:, None] == np.arange(3)
    load = Mii @ g.astype(float)
    u = interior.solve(load)
    return float(np.min(np.einsum("ik,ik->k", u, load) / np.einsum("ik,ik->k", u, Mii @ u)))


def _resolved(Mii, Kii, lowest, singular):
    """Refuse a Craig–Bampton interior whose lowest ω² (or an upper bound of it) is at the rounding level."""
    if lowest <= FE_ZERO_RTOL * _scale(Mii, Kii):
        raise ModelError(singular + f"its lowest mode, ω² ≤ {lowest:.3g} (rad/s)², is at the rounding level of K "
                         f"({FE_ZERO_RTOL:g} · tr K / tr M = {FE_ZERO_RTOL * _scale(Mii, Kii):.3g}): a motion the "
                         f"interface does not stop (a mechanism, a piece it does not reach), or {_TOO_FINE}")


def _scale(M, K):
    """tr K / tr M: an ω² of the model's scale, for the shift and the zero level."""
    return float(K.diagonal().sum() / M.diagonal().sum())


def _interface(fe, interface):
    nodes = [int(j) for j in interface]
    for j in nodes:
        fe.node_dofs(j)  # raises for a node out of range
    if len(set(nodes)) != len(nodes):
        raise ModelError(f"{fe.source}: interface nodes {nodes} repeat a node")
    return tuple(nodes)


def _reduction(fe, method, nodes, T, modes, omega):
    M, K = fe.mass @ T, fe.stiffness @ T
    Mr, Kr = T.T @ M, T.T @ K
    return Reduction(fe, method, nodes, T, (Mr + Mr.T) / 2, (Kr + Kr.T) / 2, modes, omega)
