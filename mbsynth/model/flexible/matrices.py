"""An FE model as mbsynth takes it: a symmetric positive-semidefinite mass matrix M and
stiffness matrix K (n × n, sparse) and the node coordinates (N × 3), with n = N · d
degrees of freedom, d = 6 (beams, shells: ux uy uz θx θy θz per node) or 3 (solids: ux
uy uz), ordered node by node in the nodes' order, in the nodes' coordinate frame.

``fe_model`` checks every one of these and raises ``ModelError`` naming where each array
came from (a file, or "argument") and what is wrong: shape, values that are not real
numbers (complex ones are refused, never cast), NaN/inf, asymmetry, an eigenvalue below
zero. M may be singular (a lumped mass gives rotations none); the motion
equation (2.14) takes a singular M as it is.
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from ...core.errors import ModelError
from ...core.tolerances import FE_SEMIDEFINITE_RTOL, FE_SYMMETRY_RTOL, FE_TRANSLATION_MASS_RTOL

DOFS_PER_NODE = (3, 6)  # ux uy uz (solids), and θx θy θz (beams, shells)
DENSE_CHECK_MAX = 3000  # up to this many DOFs the lowest eigenvalue an error reports is found by a dense solver


@dataclass(frozen=True, eq=False)
class FEModel:
    """M (``mass``) and K (``stiffness``) as CSR matrices, ``nodes`` (N × 3), ``dofs_per_node``
    (3 or 6) and ``source`` (where it came from, for messages). Build it with ``fe_model``."""

    mass: scipy.sparse.csr_array
    stiffness: scipy.sparse.csr_array
    nodes: np.ndarray
    dofs_per_node: int
    source: str

    @property
    def size(self):
        return self.mass.shape[0]

    def node_dofs(self, node):
        """The DOF indices of ``node`` (an index into ``nodes``)."""
        if not 0 <= node < len(self.nodes):
            raise ModelError(f"{self.source}: node {node} is not one of its {len(self.nodes)} nodes (0..{len(self.nodes) - 1})")
        return np.arange(node * self.dofs_per_node, (node + 1) * self.dofs_per_node)


def fe_model(mass, stiffness, nodes, *, dofs_per_node=None, where=None):
    """A checked FEModel. ``mass``, ``stiffness``: square real arrays or scipy sparse
    matrices; ``nodes``: N × 3; ``dofs_per_node``: 3 or 6 (default: n / N, which must be one
    of them); ``where``: {"mass", "stiffness", "nodes": the name each array came from, e.g. a
    file}."""
    where = {"mass": "argument mass", "stiffness": "argument stiffness", "nodes": "argument nodes", **(where or {})}
    M = _matrix(mass, where["mass"], "mass matrix")
    K = _matrix(stiffness, where["stiffness"], "stiffness matrix")
    if M.shape != K.shape:
        raise ModelError(f"{where['mass']}: the mass matrix is {M.shape[0]} × {M.shape[1]} but the stiffness "
                         f"matrix ({where['stiffness']}) is {K.shape[0]} × {K.shape[1]}")
    X = real_array(nodes, where["nodes"], "node coordinates")
    if X.ndim != 2 or X.shape[1] != 3 or len(X) == 0:
        raise ModelError(f"{where['nodes']}: node coordinates must be N × 3 (x y z per node), got shape {X.shape}")
    _finite(X, where["nodes"], "node coordinates")
    n = M.shape[0]
    d = check_dofs_per_node(dofs_per_node, where["nodes"]) if dofs_per_node is not None else n // len(X)
    if n != d * len(X) or d not in DOFS_PER_NODE:
        raise ModelError(f"{where['nodes']}: {len(X)} nodes do not fit {n} DOFs of the matrices "
                         f"({where['mass']}): n must be 3 or 6 per node (ux uy uz [θx θy θz]), node by node"
                         + (f"; dofs_per_node = {dofs_per_node}" if dofs_per_node is not None else ""))
    for A, what, name in ((M, "mass matrix", where["mass"]), (K, "stiffness matrix", where["stiffness"])):
        _symmetric_semidefinite(A, name, what)
    _isotropic_translation(M, d, where["mass"])
    source = where["mass"] if where["mass"] == where["stiffness"] else f"{where['mass']}, {where['stiffness']}"
    return FEModel(M, K, X, d, source)


def check_dofs_per_node(value, where=None):
    """``value`` as the int 3 or 6, or a ModelError (naming ``where`` if given): a bool, a
    list, a word, 4 are refused."""
    number = value.item() if isinstance(value, np.ndarray) and value.shape == () else value
    if isinstance(number, (bool, np.bool_)) or not isinstance(number, (int, np.integer)) or number not in DOFS_PER_NODE:
        raise ModelError((f"{where}: " if where else "") + "dofs_per_node must be 3 or 6 (ux uy uz [θx θy θz]), "
                         f"got {value!r}")
    return int(number)


def real_array(values, name, what):
    """``values`` (an array or scipy sparse matrix) as floats, or a ModelError naming ``name``
    when it holds anything but real numbers (text, booleans, complex numbers: never cast)."""
    dtype = values.dtype if scipy.sparse.issparse(values) else np.asarray(values).dtype
    if dtype.kind not in "iuf":
        kind = {"c": "complex numbers", "b": "booleans", "U": "text", "S": "text"}.get(dtype.kind, "other values")
        raise ModelError(f"{name}: the {what} must hold real numbers, not {kind} (dtype {dtype})")
    return values.astype(float) if scipy.sparse.issparse(values) else np.asarray(values, dtype=float)


def _matrix(A, name, what):
    """A as a CSR matrix of floats, square and finite."""
    A = real_array(A, name, what)
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
        raise ModelError(f"{name}: the {what} must be square, got shape {A.shape}")
    A = scipy.sparse.csr_array(A)
    _finite(A.data, name, what)
    A.sum_duplicates()
    return A


def _finite(values, name, what):
    bad = ~np.isfinite(values)
    if bad.any():
        raise ModelError(f"{name}: the {what} has {int(bad.sum())} NaN or infinite entries")


def _symmetric_semidefinite(A, name, what):
    scale = abs(A).max() if A.nnz else 0.0
    if scale == 0.0:
        if what == "mass matrix":
            raise ModelError(f"{name}: the mass matrix is zero")
        return
    asym = abs(A - A.T).max() if A.nnz else 0.0
    if asym > FE_SYMMETRY_RTOL * scale:
        i, j = _largest(abs(A - A.T))
        raise ModelError(f"{name}: the {what} is not symmetric: entry ({i}, {j}) = {A[i, j]:.8g} but ({j}, {i}) = "
                         f"{A[j, i]:.8g} (|A − Aᵀ| up to {asym / scale:.2g} of max |A|)")
    shifted = (A + A.T) / 2 + FE_SEMIDEFINITE_RTOL * scale * scipy.sparse.eye_array(A.shape[0], format="csr")
    if not _positive_definite(shifted):
        lowest = _lowest_eigenvalue((A + A.T) / 2)
        raise ModelError(f"{name}: the {what} is not positive semidefinite: an eigenvalue {lowest:.6g} "
                         f"({lowest / scale:.2g} of max |A|; DOFs number from 0, node by node)")


def _isotropic_translation(M, d, name):
    """A body's rigid translations all carry its mass m: Sᵀ M S = m I, S (n × 3) moving every
    node by a unit x, y or z (the floating frame's equations, invariants.py, rest on it)."""
    n = M.shape[0]
    S = scipy.sparse.csr_array((np.ones(n // d * 3), (np.arange(n).reshape(-1, d)[:, :3].ravel(),
                                                      np.tile(np.arange(3), n // d))), shape=(n, 3))
    Mt = (S.T @ (M @ S)).toarray()
    m = np.trace(Mt) / 3
    if not np.abs(Mt - m * np.eye(3)).max() <= FE_TRANSLATION_MASS_RTOL * abs(m):
        masses = ", ".join(f"{x:.6g}" for x in np.diag(Mt))
        raise ModelError(f"{name}: the mass matrix gives the body's rigid translations along x, y, z the masses "
                         f"{masses} and the couplings {Mt[0, 1]:.6g}, {Mt[0, 2]:.6g}, {Mt[1, 2]:.6g}; a body has one "
                         "mass m in every direction (the sum of its translation blocks m·I; DOFs node by node)")


def _largest(A):
    coo = A.tocoo()
    k = int(np.argmax(coo.data))
    return int(coo.row[k]), int(coo.col[k])


def _positive_definite(A):
    """Whether the symmetric A is positive definite: the pivots of a sparse LDLᵀ (SuperLU
    with diagonal pivots, whose signs are A's inertia by Sylvester's law)."""
    try:
        lu = scipy.sparse.linalg.splu(A.tocsc(), diag_pivot_thresh=0.0, permc_spec="MMD_AT_PLUS_A",
                                      options={"SymmetricMode": True})
    except RuntimeError:  # exactly singular
        return False
    if not np.array_equal(lu.perm_r, lu.perm_c):  # not a symmetric pivoting: no inertia to read
        return _lowest_eigenvalue(A) > 0
    return bool(np.all(lu.U.diagonal() > 0))


def _lowest_eigenvalue(A):
    if A.shape[0] <= DENSE_CHECK_MAX:
        return float(scipy.linalg.eigvalsh(A.toarray(), subset_by_index=[0, 0])[0])
    return float(scipy.sparse.linalg.eigsh(A.tocsc(), k=1, which="SA", return_eigenvectors=False)[0])
