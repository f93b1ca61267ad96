"""FE models from files, and back.

Two layouts:

- one ``.npz`` bundle (``read_fe(path)``, ``write_fe(fe, path)``): arrays ``nodes`` (N × 3),
  and for ``mass`` and ``stiffness`` either a dense array under that name or COO triplets
  ``<name>_rows``, ``<name>_cols``, ``<name>_values`` (0-based, repeated entries summed as
  an FE assembly does); optional ``dofs_per_node``;
- one file per array (``read_fe(mass=..., stiffness=..., nodes=...)``): Matrix Market
  ``.mtx`` (``scipy.io.mmread``: coordinate or array, general or symmetric) or ``.npz``
  (``scipy.sparse.save_npz``, or ``numpy.savez`` holding one array); nodes also as
  ``.csv``/``.txt`` (three columns, ``#`` comments). ``write_fe(fe, folder)`` writes
  ``mass.mtx``, ``stiffness.mtx`` and ``nodes.mtx`` there.

DOFs run node by node (matrices.py). Every error names the file and what is wrong.
"""

import zipfile
import zlib
from pathlib import Path

import numpy as np
import scipy.sparse

from ...core.errors import ModelError
from .matrices import DOFS_PER_NODE, check_dofs_per_node, fe_model, real_array

ARRAYS = ("mass", "stiffness", "nodes")
# what numpy raises for a file that is not a whole .npz: empty or truncated, not a zip, a damaged member
NPZ_ERRORS = (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error)
# what scipy.sparse.load_npz raises for arrays that do not make its sparse format
SPARSE_NPZ_ERRORS = (ValueError, TypeError, IndexError, KeyError)
# what scipy.io.mmread raises for a file that is not Matrix Market (its reader's header and body checks)
MTX_ERRORS = (ValueError, OSError, IndexError, OverflowError, RuntimeError, TypeError)


def read_fe(path=None, *, mass=None, stiffness=None, nodes=None, dofs_per_node=None):
    """An FEModel (matrices.py) from one ``.npz`` bundle ``path``, or from the three files
    ``mass``, ``stiffness``, ``nodes``."""
    if path is not None:
        if mass is not None or stiffness is not None or nodes is not None:
            raise ModelError(f"{path}: give either one .npz bundle or mass=, stiffness=, nodes= files, not both")
        return _read_bundle(Path(path), dofs_per_node)
    given = {"mass": mass, "stiffness": stiffness, "nodes": nodes}
    missing = [k for k, v in given.items() if v is None]
    if missing:
        raise ModelError(f"read_fe: no file given for {', '.join(missing)}")
    arrays = {k: _read_one(Path(v), k) for k, v in given.items()}
    return fe_model(arrays["mass"], arrays["stiffness"], _nodes(arrays["nodes"], given["nodes"]),
                    dofs_per_node=dofs_per_node, where={k: str(v) for k, v in given.items()})


def write_fe(fe, path):
    """Write ``fe``: to an ``.npz`` bundle (COO triplets), or to ``mass.mtx``,
    ``stiffness.mtx``, ``nodes.mtx`` in the folder ``path`` (made if absent)."""
    path = Path(path)
    if path.suffix == ".npz":
        arrays = {"nodes": fe.nodes, "dofs_per_node": np.int64(fe.dofs_per_node)}
        for name in ("mass", "stiffness"):
            coo = getattr(fe, name).tocoo()
            arrays |= {f"{name}_rows": coo.row, f"{name}_cols": coo.col, f"{name}_values": coo.data}
        np.savez(path, **arrays)
        return path
    from scipy.io import mmwrite  # Matrix Market only: a model of beam elements or .npz files never loads it
    path.mkdir(parents=True, exist_ok=True)
    for name in ("mass", "stiffness"):
        mmwrite(path / f"{name}.mtx", scipy.sparse.coo_matrix(getattr(fe, name)), precision=17, symmetry="symmetric")
    mmwrite(path / "nodes.mtx", fe.nodes, precision=17)
    return path


def _read_bundle(path, dofs_per_node):
    if path.suffix != ".npz":
        raise ModelError(f"{path}: a bundle is one .npz file (mass, stiffness, nodes); for .mtx give mass=, stiffness=, nodes=")
    arrays = _load_npz(path)
    if "nodes" not in arrays:
        raise ModelError(f"{path}: no array 'nodes' (N × 3 node coordinates); it holds {sorted(arrays)}")
    nodes = _nodes(arrays["nodes"], path)
    if dofs_per_node is None and "dofs_per_node" in arrays:
        dofs_per_node = check_dofs_per_node(arrays["dofs_per_node"], path)
    sizes = [len(nodes) * d for d in ((dofs_per_node,) if dofs_per_node is not None else DOFS_PER_NODE)]
    matrices = {name: _bundle_matrix(arrays, name, path, sizes) for name in ("mass", "stiffness")}
    where = {name: f"{path} [{name}]" for name in ARRAYS}
    return fe_model(matrices["mass"], matrices["stiffness"], nodes, dofs_per_node=dofs_per_node, where=where)


def _bundle_matrix(arrays, name, path, sizes):
    """A bundle's dense ``name`` or its COO triplets, n the first of ``sizes`` (the DOFs the
    nodes may have) that holds every index."""
    if name in arrays:
        return arrays[name]
    keys = [f"{name}_{k}" for k in ("rows", "cols", "values")]
    if not all(k in arrays for k in keys):
        raise ModelError(f"{path}: no '{name}' array and no COO triplets {', '.join(keys)}; it holds {sorted(arrays)}")
    rows, cols, values = (np.asarray(arrays[k]).ravel() for k in keys)
    if not len(rows) == len(cols) == len(values):
        raise ModelError(f"{path}: {name}_rows, {name}_cols, {name}_values have lengths "
                         f"{len(rows)}, {len(cols)}, {len(values)}: they must be equal")
    if rows.dtype.kind not in "iu" or cols.dtype.kind not in "iu" or len(rows) and min(rows.min(), cols.min()) < 0:
        raise ModelError(f"{path}: {name}_rows and {name}_cols must be non-negative integers (0-based)")
    values = real_array(values, f"{path} [{name}_values]", name)
    largest = int(max(rows.max(initial=-1), cols.max(initial=-1)))
    n = next((size for size in sizes if largest < size), sizes[-1])
    if largest >= n:
        raise ModelError(f"{path}: {name} has an entry at index {largest} but the nodes give "
                         f"{'at most ' if len(sizes) > 1 else ''}{n} DOFs "
                         f"(0..{n - 1})")
    return scipy.sparse.coo_array((values, (rows, cols)), shape=(n, n)).tocsr()


def _read_one(path, what):
    _check_file(path, f"the {what}")
    suffix = path.suffix.lower()
    if suffix == ".mtx":
        from scipy.io import mmread  # as in ``write_fe``
        try:
            return mmread(path)
        except MTX_ERRORS as err:
            raise ModelError(f"{path}: not a readable Matrix Market file ({type(err).__name__}: {err})") from err
    if suffix == ".npz":
        arrays = _load_npz(path)
        if {"data", "indices", "indptr", "format", "shape"} <= set(arrays) or {"row", "col", "data", "format", "shape"} <= set(arrays):
            try:
                return scipy.sparse.load_npz(path)
            except SPARSE_NPZ_ERRORS as err:
                raise ModelError(f"{path}: not a readable scipy.sparse .npz file ({type(err).__name__}: {err})") from err
        if len(arrays) != 1:
            raise ModelError(f"{path}: a {what} .npz must hold one array (or be scipy.sparse.save_npz's); "
                             f"it holds {sorted(arrays)}")
        return next(iter(arrays.values()))
    if suffix in (".csv", ".txt") and what == "nodes":
        try:
            return np.loadtxt(path, delimiter="," if suffix == ".csv" else None, ndmin=2)
        except ValueError as err:
            raise ModelError(f"{path}: not a table of numbers ({err})") from err
    kinds = ".mtx, .npz" + (", .csv, .txt" if what == "nodes" else "")
    raise ModelError(f"{path}: the {what} must be a {kinds} file")


def _check_file(path, what):
    if not path.is_file():
        raise ModelError(f"{path}: " + ("is a folder" if path.is_dir() else "no such file") + f" ({what})")


def _load_npz(path):
    _check_file(path, "an .npz file")
    try:
        data = np.load(path, allow_pickle=False)
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ModelError(f"{path}: one array (numpy.save's .npy), not an .npz archive (numpy.savez's)")
        with data:
            return {k: data[k] for k in data.files}
    except NPZ_ERRORS as err:
        raise ModelError(f"{path}: not a readable .npz file ({type(err).__name__}: {err})") from err


def _nodes(X, path):
    X = real_array(X.toarray() if scipy.sparse.issparse(X) else X, path, "node coordinates")
    if X.ndim != 2 or X.shape[1] != 3:
        raise ModelError(f"{path}: node coordinates must be N × 3 (x y z per node), got shape {X.shape}")
    return X
