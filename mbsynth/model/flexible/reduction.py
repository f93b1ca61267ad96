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
singular, are found too), by scipy's ``eigsh`` or, for small models, a dense solver; M may
be singular (lumped: rotations without mass), its infinite eigenvalues are never returned.
The Ritz vectors are refined by the projected problem: the modes are M-orthonormal to
rounding.
"""

from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from ...core.errors import ModelError
from .matrices import FEModel

SHIFT_RTOL = 1e-8  # the default shift: −SHIFT_RTOL · tr K / tr M (below every mode; rigid ones factor)
RIGID_RTOL = 1e-9  # a mode with ω² below RIGID_RTOL · tr K / tr M is a rigid-body mode
FIRST_BATCH = 12  # modes asked for first when they are chosen by frequency (doubled until past it)
DENSE_MODES_MAX = 120  # up to this many DOFs the modes come from a dense solver, every finite one at once
INTERIOR_PIVOT_RTOL = 1e-14  # a pivot of K_ii below this fraction of the largest: the interface leaves K_ii singular
FINITE_RTOL = 1e-12  # a dense mode with 1/(λ + shift) below FINITE_RTOL / shift is an infinite one (M φ = 0)


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
    Kii, Kib = K[i][:, i], K[i][:, b]
    T = np.zeros((fe.size, len(b)))
    T[b, np.arange(len(b))] = 1.0
    if len(b):
        singular = (f"{fe.source}: with the interface nodes {list(nodes)} held, the stiffness is singular: the "
                    "interface does not stop every rigid-body motion (add interface nodes)")
        try:
            interior = scipy.sparse.linalg.splu(Kii.tocsc())
        except RuntimeError as err:
            raise ModelError(singular) from err
        pivots = np.abs(interior.U.diagonal())
        if pivots.min() <= INTERIOR_PIVOT_RTOL * pivots.max():
            raise ModelError(singular)
        T[i, :] = -interior.solve(Kib.toarray())
    omega, shapes = normal_modes(M[i][:, i], Kii, count=count, max_frequency=max_frequency, shift=shift,
                                 source=fe.source)
    Phi = np.zeros((fe.size, len(omega)))
    Phi[i] = shapes
    return _reduction(fe, "craig_bampton", nodes, np.hstack([T, Phi]), slice(len(b), len(b) + len(omega)), omega)


def free_interface(fe, interface=(), *, count=None, max_frequency=None, rigid=True, shift=None):
    """The lowest normal modes of the unconstrained ``fe`` as the basis (``rigid=False``: the
    rigid-body modes, at most six, left out, and ``count`` counts the others); ``interface``
    only names the nodes a part attaches to."""
    nodes = _interface(fe, interface)
    K, M = fe.stiffness.tocsc(), fe.mass.tocsc()
    more = count if rigid or count is None else min(count + 6, fe.size - 2)  # a free body has 6 rigid-body modes
    omega, shapes = normal_modes(M, K, count=more, max_frequency=max_frequency, shift=shift, source=fe.source)
    if not rigid:
        flexible = omega**2 >= RIGID_RTOL * _scale(M, K)
        omega, shapes = omega[flexible][:count], shapes[:, flexible][:, :count]
    return _reduction(fe, "free_interface", nodes, shapes, slice(0, len(omega)), omega)


def normal_modes(M, K, *, count=None, max_frequency=None, shift=None, source="FE model"):
    """(ω in rad/s ascending, shapes n × k M-orthonormal) of K φ = ω² M φ: the ``count``
    lowest, or every one with ω ≤ 2π ``max_frequency``. ``shift`` (ω², > 0): the
    shift-invert point is −shift (default SHIFT_RTOL · tr K / tr M). Up to DENSE_MODES_MAX
    DOFs a dense solver, above it eigsh."""
    if (count is None) == (max_frequency is None):
        raise ModelError(f"{source}: choose the modes by count or by max_frequency (one of them)")
    M, K = scipy.sparse.csc_array(M), scipy.sparse.csc_array(K)
    n = M.shape[0]
    most = n if n <= DENSE_MODES_MAX else n - 2
    if count is not None and not (isinstance(count, (int, np.integer)) and 0 <= count <= most):
        raise ModelError(f"{source}: the mode count must be an integer from 0 to {most}, not {count!r}")
    if max_frequency is not None and not max_frequency >= 0:
        raise ModelError(f"{source}: max_frequency must be ≥ 0 Hz, not {max_frequency!r}")
    if count == 0 or n == 0:
        return np.zeros(0), np.zeros((n, 0))
    sigma = -(shift if shift is not None else SHIFT_RTOL * _scale(M, K))
    limit = None if max_frequency is None else (2 * np.pi * max_frequency) ** 2
    if n <= DENSE_MODES_MAX:
        lam, vectors = _dense_modes(M, K, sigma, source)
        if count is not None and count > len(lam):
            raise ModelError(f"{source}: {count} modes asked for, but the mass matrix gives only {len(lam)} "
                             "finite ones (a lumped mass gives rotations none)")
    else:
        lam, vectors = _sparse_modes(M, K, sigma, count, limit, max_frequency, source)
    keep = slice(count) if limit is None else lam <= limit
    return np.sqrt(np.clip(lam[keep], 0.0, None)), vectors[:, keep]


def _dense_modes(M, K, sigma, source):
    """Every finite mode, by the symmetric form of shift-invert: with K − σM = LLᵀ, the
    eigenvalues μ = 1/(λ − σ) of L⁻¹ M L⁻ᵀ (μ = 0: an infinite mode of a singular M)."""
    try:
        L = np.linalg.cholesky((K - sigma * M).toarray())
    except np.linalg.LinAlgError as err:
        raise ModelError(_NEITHER.format(source)) from err
    half = scipy.linalg.solve_triangular(L, M.toarray(), lower=True)
    mu, Y = scipy.linalg.eigh(scipy.linalg.solve_triangular(L, half.T, lower=True))
    finite = mu * -sigma > FINITE_RTOL
    vectors = scipy.linalg.solve_triangular(L.T, Y[:, finite][:, ::-1], lower=False)
    return _ritz(M, K, vectors, source)


def _sparse_modes(M, K, sigma, count, limit, max_frequency, source):
    """The ``count`` lowest modes, or enough to pass ``limit`` (ω²), by eigsh."""
    n = M.shape[0]
    try:
        inverse = scipy.sparse.linalg.splu(K - sigma * M)
    except RuntimeError as err:
        raise ModelError(_NEITHER.format(source)) from err
    operator = scipy.sparse.linalg.LinearOperator((n, n), matvec=inverse.solve, dtype=float)
    k = count if count is not None else min(FIRST_BATCH, n - 2)
    while True:
        try:
            lam, vectors = scipy.sparse.linalg.eigsh(K, k=k, M=M, sigma=sigma, OPinv=operator, which="LM")
        except scipy.sparse.linalg.ArpackError as err:
            raise ModelError(f"{source}: eigsh found no {k} modes ({err}); fewer modes, or more than the mass "
                             "matrix has finite ones?") from err
        lam, vectors = _ritz(M, K, vectors, source)
        if limit is None or lam[-1] > limit or k == n - 2:
            break
        k = min(2 * k, n - 2)
    if limit is not None and lam[-1] <= limit:
        raise ModelError(f"{source}: more than {k} modes lie below {max_frequency} Hz (eigsh takes at most n − 2): "
                         "choose them by count, or a lower max_frequency")
    return lam, vectors


_NEITHER = ("{}: K + s M is singular for every s: some motion has neither mass nor stiffness "
            "(with a lumped mass, a free beam's twist about its own axis)")


def _ritz(M, K, vectors, source):
    """The Rayleigh–Ritz refinement on span(vectors): eigenvalues ascending, M-orthonormal."""
    Mr = vectors.T @ (M @ vectors)
    Kr = vectors.T @ (K @ vectors)
    try:
        lam, V = scipy.linalg.eigh((Kr + Kr.T) / 2, (Mr + Mr.T) / 2)
    except np.linalg.LinAlgError as err:
        raise ModelError(f"{source}: more modes asked for than the mass matrix has finite ones "
                         "(a lumped mass gives rotations none)") from err
    return lam, vectors @ V


def _scale(M, K):
    """tr K / tr M: an ω² of the model's scale, for the shift and the rigid-body threshold."""
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
