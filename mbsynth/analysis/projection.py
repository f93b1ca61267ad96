"""Putting a state back on the constraint manifold.

(2.14) enforces the constraints only at the acceleration level (2.4): an integrated
state drifts off φ(q, t) = 0 and φ̇ = 0. These functions move it back with the least
change (each coordinate weighed by how strongly it moves the constraints, ``_least_change``):
positions by Gauss–Newton on the position-level rows, q ← q − Φ_q⁺ φ
(Φ_q = the rows of A of the holonomic constraints), then velocities on every
velocity-level row (holonomic and non-holonomic, both linear in q̇),
q̇ ← q̇ − A_v⁺ ψ. Coordinates marked fixed are not changed. Unit quaternions are
holonomic rows of their bodies, so they are restored like any other constraint.

Tolerances are relative, so a mechanism projects alike in millimetres or kilometres: a
row's residual is judged against the size of its terms, estimated from the row of A
(``equations.term_scales``: Σ_j |A_ij q_j| for φ_i, Σ_j |A_ij q̇_j| for ψ_i), times
``PROJECTION_RTOL``.
"""

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

from ..core.equations import term_scales
from ..model.data import workspace
from ..model.evaluation import DENSE_ENTRIES
from ..core.errors import SolveError
from ..core.tolerances import (COLUMN_FLOOR, CURVATURE_STEP, DIVISION_GUARD, DRIFT_FLOOR, DRIFT_TARGET, NEAR_SINGULAR,
                               PROJECTION_DIVERGED, PROJECTION_RCOND, PROJECTION_RTOL, SPARSE_ACCEPT, VELOCITY_ACCEPT)
from ..core.memo import MEMO

MAX_ITERATIONS = 50


def _free_columns(n, fixed):
    free = np.ones(n, dtype=bool)
    if fixed is not None:
        free[np.asarray(fixed, dtype=int)] = False
    return free




def _least_change(J, r, groups, floor=0.0):
    """The smallest Δ with J Δ = r in the metric that weighs each coordinate by how strongly
    it moves the constraints, ‖diag(c) Δ‖ with c_j = ‖J_:j‖ (column equilibration): a
    quaternion's unit then costs as much as the lever arms it turns, so a body 1 km long is
    moved, not turned, as one 1 m long is. Coordinates that move together (``groups``, one
    label per column: System.coordinate_groups) share one scale, the root mean square of
    their columns' norms: a single component's column vanishes where that component passes
    through zero (∂(|u|² − 1)/∂u_z = 2u_z; a particle's x on a rod), and a scale of its own
    would let the step move it by r/c_j. With G = J D (D = diag(1/c)) and independent
    rows, Δ = D Gᵀ (G Gᵀ)⁻¹ r, G Gᵀ factored sparse (a tree of joints gives a
    tree-structured G Gᵀ: linear time), or dense when J is small (DENSE_ENTRIES). Rows that are dependent, or dependent to within
    ``PROJECTION_RCOND`` (a loop whose dependency moves with the configuration, off its
    manifold: the step along the near-dependent direction would be r's drift over σ), go to
    dense least squares that drops those directions; so does a sparse step that does not
    meet J Δ = r to SPARSE_ACCEPT."""
    if J.shape[0] == 0 or J.shape[1] == 0:  # no rows, or every coordinate fixed
        return np.zeros(J.shape[1])
    if not scipy.sparse.issparse(J):
        return _dense_least_change(J, r, groups, floor)
    if J.shape[0] * J.shape[1] <= DENSE_ENTRIES:
        return _dense_least_change(J.toarray(), r, groups, floor)
    columns = _grouped(np.asarray(J.multiply(J).sum(axis=0)).ravel(), groups)
    magnitude = abs(J).tocsr()
    widest = np.asarray(magnitude.max(axis=1).todense()).ravel()  # each row's largest entry
    touched = magnitude.copy()
    touched.data = np.repeat(widest, np.diff(touched.indptr))
    columns = _floored(columns, floor * np.asarray(touched.max(axis=0).todense()).ravel())
    D = scipy.sparse.diags(1.0 / columns)
    G = (J @ D).tocsr()
    size = np.linalg.norm(r) + DIVISION_GUARD
    try:
        with np.errstate(all="ignore"):
            z = G.T @ scipy.sparse.linalg.splu((G @ G.T).tocsc()).solve(r)
        if _accepted(z, G, scipy.sparse.linalg.norm(G), r, size):
            return D @ z
    except RuntimeError:  # splu: the matrix is exactly singular
        pass
    return D @ np.linalg.lstsq(G.toarray(), r, rcond=PROJECTION_RCOND)[0]


def _dense_least_change(J, r, groups, floor=0.0):
    """``_least_change`` of a small or dense J, with numpy's dense solve of G Gᵀ (no sparse overhead)."""
    columns = _grouped(np.einsum("ij,ij->j", J, J), groups)
    least = 0.0
    if floor:
        magnitude = np.abs(J)
        touched = np.where(magnitude > 0, magnitude.max(axis=1, keepdims=True, initial=0.0), 0.0)
        least = floor * touched.max(axis=0, initial=0.0)
    d = 1.0 / _floored(columns, least)
    G = J * d
    size = np.linalg.norm(r) + DIVISION_GUARD
    try:
        with np.errstate(all="ignore"):
            z = G.T @ np.linalg.solve(G @ G.T, r)
        if _accepted(z, G, np.linalg.norm(G), r, size):
            return d * z
    except np.linalg.LinAlgError:  # exactly singular
        pass
    return d * np.linalg.lstsq(G, r, rcond=PROJECTION_RCOND)[0]


def _grouped(squares, groups):
    """Column scales from the squared column norms: per group, the root mean square."""
    labels, inverse, counts = _labelled(np.asarray(groups).tobytes(), np.asarray(groups).dtype.str)
    return np.sqrt(np.bincount(inverse, weights=squares, minlength=labels)[inverse] / counts[inverse])


@MEMO.function(64)
def _labelled(groups, dtype):
    """(number of groups, each column's group index, each group's size) of the group labels
    (as bytes: a System's labels are the same at every projection of a run)."""
    labels, inverse, counts = np.unique(np.frombuffer(groups, dtype=dtype), return_inverse=True,
                                        return_counts=True)
    return labels.size, inverse, counts


def _floored(columns, least):
    """Column scales c_j, at least ``least`` (1 for a column that is zero)."""
    floored = np.maximum(columns, least)
    return np.where(floored > 0, floored, 1.0)


def _accepted(z, G, norm_G, r, size):
    """The step z from the normal equations: finite, not amplified beyond PROJECTION_RCOND
    (nearly dependent rows), and meeting G z = r to SPARSE_ACCEPT."""
    well_posed = np.linalg.norm(z) * PROJECTION_RCOND * norm_G <= size
    return bool(np.all(np.isfinite(z)) and well_posed and np.linalg.norm(G @ z - r) <= SPARSE_ACCEPT * size)


def project_positions(data, t, q, fixed=None, tolerance=PROJECTION_RTOL, arrays=None):
    """q on φ(q, t) = 0, changing only the coordinates not in ``fixed`` (indices);
    ``arrays``: the ConstraintArrays at q (any q̇), if at hand.

    Gauss–Newton in the equilibrated metric of ``_least_change``; where its residual grows,
    again from q with every column scale at least COLUMN_FLOOR × the largest entry of the
    rows it meets. A column nearly zero only at this point (a quaternion component near 0:
    ∂(|u|² − 1)/∂u_z = 2u_z) counts in that metric as nearly free to move: the step moves
    it by about r/c_j, whose second-order effect (r/c_j)² exceeds r, and Newton diverges
    even from a state on the manifold to rounding."""
    data = workspace(data)
    start = np.array(q, dtype=float)
    free = _free_columns(start.size, fixed)
    q = _newton(data, t, start, free, tolerance, floor=0.0, arrays=arrays)
    return q if q is not None else _newton(data, t, start, free, tolerance, floor=COLUMN_FLOOR, last=True,
                                           arrays=arrays)


def _newton(data, t, q, free, tolerance, floor, last=False, arrays=None):
    """Gauss–Newton steps from q (a copy is changed) until every position row is met; None
    when the residual grows (unless ``last``: then a SolveError names the rows unmet,
    ``_unmet_positions``). ``arrays``: the ConstraintArrays at q, if at hand (φ and A do
    not depend on q̇)."""
    start, q, qd = q, q.copy(), np.zeros_like(q)
    previous, best = np.inf, (np.inf, q.copy())
    for _ in range(MAX_ITERATIONS):
        if arrays is None:
            arrays = data.constraint_arrays(t, q, qd, sparse=None)
        phi = arrays.phi
        rows = np.isfinite(phi)
        unmet = np.abs(phi[rows]) > tolerance * term_scales(arrays.A, q)[rows]
        if not unmet.any():
            return q
        size = np.abs(phi[rows]).max()
        if not last and size > 2 * previous:
            return None
        if size < best[0]:
            best = (size, q.copy())
        elif size > PROJECTION_DIVERGED * best[0]:  # the last pass gives up once it runs away from its best
            break
        previous = size
        q[free] -= _least_change(arrays.A[rows][:, free], phi[rows], data.model.coordinate_groups[free], floor)
        arrays = None
        if not np.all(np.isfinite(q)):
            break
    if not last:
        return None
    raise _unmet_positions(data, t, start, best[1], free, tolerance)


def project_velocities(data, t, q, qd, fixed=None, tolerance=PROJECTION_RTOL, arrays=None):
    """q̇ on the velocity-level rows (φ̇ = 0, ψ = 0), changing only free velocities;
    ``arrays``: the ConstraintArrays at (q, q̇), if at hand."""
    data = workspace(data)
    qd = np.array(qd, dtype=float)
    free = _free_columns(qd.size, fixed)
    if arrays is None:
        arrays = data.constraint_arrays(t, q, qd, sparse=None)
    psi = arrays.psi
    rows = np.isfinite(psi)
    if not (np.abs(psi[rows]) > tolerance * term_scales(arrays.A, qd)[rows]).any():
        return qd
    A = arrays.A[rows]
    before, largest = np.abs(qd), np.abs(psi[rows]).max()
    qd[free] -= _least_change(A[:, free], psi[rows], data.model.coordinate_groups[free])  # ψ is affine in q̇, slope A
    _, psi = data.constraint_residuals(t, q, qd)
    # the step's rounding is that of the rates it subtracted from, not of what is left (at rest: rounding alone),
    # and, in a row whose own terms are smaller, that of the other rows' corrections: the least-squares step over
    # dependent rows (a box's corners) leaves each row about ε κ of the largest ψ it removed
    unmet = np.abs(psi[rows]) > VELOCITY_ACCEPT * np.maximum(term_scales(A, np.maximum(before, np.abs(qd))), largest)
    if unmet.any():
        raise SolveError(_unmet(data, psi, "velocities", free),
                         constraints=[n for n, u in zip(np.array(data.model.constraint_names)[rows], unmet) if u])
    return qd




def relative_drift(data, t, q, qd, arrays=None, span=None):
    """The largest residual of φ or ψ relative to its row's terms (module docstring), at
    least DRIFT_FLOOR of the row's norm times the largest coordinate (or rate): how far
    the state lies off the manifold, alike at every scale. ``span``: the length of the
    span integrated to (q, q̇); a drift above DRIFT_TARGET is then judged again with each
    row's terms at least its norm times how far the span's motion moves a coordinate and
    a rate (``_span_motion``): a span's drift is the rounding of the motion it integrated,
    and a state at rest on its rows (a contact that sticks: q̇ = 0 to rounding) is
    otherwise judged against its own rounding and reads as drifted however small it is.
    ``arrays``: the ConstraintArrays at (q, q̇), if at hand."""
    data = workspace(data)
    if arrays is None:
        arrays = data.constraint_arrays(t, q, qd, sparse=None)
    drift = _relative_drift(arrays, q, qd, (0.0, 0.0))
    if span is None or drift <= DRIFT_TARGET:
        return drift
    return _relative_drift(arrays, q, qd, _span_motion(data, t, q, qd, span))


def _relative_drift(arrays, q, qd, moved):
    """``relative_drift`` with each row's terms at least its norm times ``moved``'s
    (position, rate)."""
    worst = 0.0
    norms = np.asarray(abs(arrays.A).sum(axis=1)).ravel()
    for residual, x, floor in ((arrays.phi, q, moved[0]), (arrays.psi, qd, moved[1])):
        rows = np.isfinite(residual)
        scale = np.maximum(term_scales(arrays.A, x, floor=DRIFT_FLOOR), floor * norms)[rows]
        relative = np.abs(residual[rows]) / np.maximum(scale, np.finfo(float).tiny)
        worst = max(worst, float(relative.max(initial=0.0)))
    return worst


def _span_motion(data, t, q, qd, span):
    """(position, rate): how far a span of length h ending at (t, q, q̇) moves a
    coordinate and a rate under the applied forces, from their acceleration a = max |Q| /
    max |M|: (|q̇|∞ h + a h², a h)."""
    arrays = data.evaluate(t, q, qd)
    a = np.abs(arrays.Q).max(initial=0.0) / max(np.abs(arrays.M).max(initial=0.0), np.finfo(float).tiny)
    return np.abs(qd).max(initial=0.0) * span + a * span**2, a * span


def project(data, t, q, qd, fixed_q=None, fixed_qd=None, arrays=None):
    """(q, q̇) on the constraint manifold: positions first, then velocities. ``arrays``:
    the ConstraintArrays at (q, q̇), if at hand (used while q is unchanged)."""
    data = workspace(data)
    moved = project_positions(data, t, q, fixed_q, arrays=arrays)
    same = arrays is not None and np.array_equal(moved, q)
    return moved, project_velocities(data, t, moved, qd, fixed_qd, arrays=arrays if same else None)


def consistent_initial_state(data, t=0.0):
    """The model's initial state made consistent with the constraints.

    First every value the model sets is kept and only the others are completed (a
    partial state). If that is impossible (a state slightly off), only the values
    listed in ``initial_fixed`` are kept and the rest change as little as possible.
    Returns (q, q̇, changes) with changes = {name: (given, new)} for the values that
    moved. Raises SolveError when no consistent state keeps the fixed values."""
    data = workspace(data)
    q0, qd0 = data.initial_state()
    try:
        q, qd = _project_keeping(data, t, q0, qd0, data.model.initial_given)
    except SolveError:
        try:
            q, qd = _project_keeping(data, t, q0, qd0, data.model.initial_fixed)
        except SolveError as err:
            kept = ", ".join(sorted(data.model.initial_fixed)) or "nothing"
            raise SolveError(f"no consistent initial state exists (keeping {kept}): {err}",
                             constraints=err.constraints) from None
    data.check_branches(q, t)  # a joint's rows met on a branch it does not mean: a fixed joint flipped
    names = list(data.model.coordinates)
    changes = {}
    q_size, qd_size = np.abs(q).max(initial=0.0), np.abs(qd).max(initial=0.0)
    for i, c in enumerate(names):
        if abs(q[i] - q0[i]) > PROJECTION_RTOL * q_size:
            changes[c] = (float(q0[i]), float(q[i]))
        if abs(qd[i] - qd0[i]) > PROJECTION_RTOL * qd_size:
            changes[c + "_dot"] = (float(qd0[i]), float(qd[i]))
    return q, qd, changes


def _project_keeping(data, t, q, qd, keep):
    names = list(data.model.coordinates)
    return project(data, t, q, qd, [i for i, c in enumerate(names) if c in keep],
                   [i for i, c in enumerate(names) if c + "_dot" in keep])


def _unmet(data, residual, level, free):
    worst = np.nanargmax(np.abs(residual))
    return (f"the constraints cannot be met by adjusting the {level} of {_listed(data, free)}; "
            f"largest residual {abs(residual[worst]):.3g} in {data.model.constraint_names[worst]}")


LISTED = 8  # coordinates named in an error before "… (n in all)"


def _listed(data, free):
    """The free coordinates, the first LISTED of them named."""
    names = [c for c, f in zip(data.model.coordinates, free) if f]
    if not names:
        return "no coordinate (all are fixed)"
    return ", ".join(names) if len(names) <= LISTED else f"{', '.join(names[:LISTED])}, … ({len(names)} in all)"


def _unmet_positions(data, t, start, best, free, tolerance):
    """The SolveError of a projection that could not meet the position rows: the rows
    unmet at ``start``, largest residual relative to its row's terms first (a row no
    configuration meets, such as a servo beyond a joint's range, is one of them; the rows
    Newton's steps break on their way are not), and the largest residual at ``best``,
    the iterate that came closest. Where the residual at ``best`` lies along a dependency
    of the rows (dependent at this configuration only: a singular position, where no
    first-order change moves it), that dependency's rows are named instead."""
    unmet = _unmet_rows(data, t, start, tolerance)
    arrays = data.constraint_arrays(t, best, np.zeros_like(best), sparse=None)
    phi = np.where(np.isfinite(arrays.phi), arrays.phi, 0.0)
    worst = int(np.argmax(np.abs(phi)))
    closest = f"{abs(phi[worst]):.3g} in {data.model.constraint_names[worst]}"
    listed = ", ".join(f"{name} ({residual:.3g})" for name, residual in unmet[:LISTED])
    if len(unmet) > LISTED:
        listed += f", … ({len(unmet)} rows in all)"
    dependency = _dependency(data, t, best, arrays.A, phi, free)
    if dependency is None:
        return SolveError(f"the constraints cannot be met by adjusting the positions of {_listed(data, free)}: "
                          f"unmet {listed}; Newton's steps left at best a residual of {closest}",
                          constraints=[name for name, _ in unmet])
    rows, distance = dependency
    if distance is None:
        return SolveError(f"the constraints cannot be met by adjusting the positions of {_listed(data, free)}: "
                          f"unmet {listed}; the residual left ({closest}) is the least the rows {_names(rows)} "
                          "reach near here (no change of the positions lowers it, to first or second order)",
                          constraints=rows)
    return SolveError(f"the constraints cannot be met near this configuration: rows {_names(rows)} are dependent "
                      "here (a singular position: a loop stretched straight, or joint axes in line) and the "
                      f"residual ({closest}) lies along their dependency; a consistent configuration lies about "
                      f"{distance:.2g} away, which no first-order step reaches: start the model away from the "
                      "singular position", constraints=rows)


def _unmet_rows(data, t, q, tolerance):
    """[(row name, |φ|)] of the position rows unmet at q, largest relative residual first."""
    arrays = data.constraint_arrays(t, q, np.zeros_like(q), sparse=None)
    phi = np.where(np.isfinite(arrays.phi), arrays.phi, 0.0)
    scales = term_scales(arrays.A, q)
    order = np.argsort(-np.abs(phi) / np.maximum(scales, np.finfo(float).tiny))
    return [(data.model.constraint_names[i], float(abs(phi[i]))) for i in order if abs(phi[i]) > tolerance * scales[i]]


def _names(rows):
    """Row names, the first LISTED of them."""
    return ", ".join(rows) if len(rows) <= LISTED else f"{', '.join(rows[:LISTED])}, … ({len(rows)} in all)"


DIAGNOSED_ENTRIES = 4_000_000  # a dense SVD of the rows is taken for a diagnosis up to this size


def _dependency(data, t, q, A, phi, free):
    """None where φ lies mostly in the range of A's free columns (rows scaled to unit norm);
    else (the rows of the dependency wᵀA = 0 along which it lies — singular values below
    NEAR_SINGULAR of the largest —, the distance to a configuration that meets it or None).
    wᵀφ(q + δ) = wᵀφ + ½ δᵀ C δ for δ in null(A) (C: the second derivative of wᵀφ there,
    central differences of A): met at |δ| = √(2|wᵀφ|/|λ|) along an eigenvector of C whose
    eigenvalue λ has the sign opposite to wᵀφ, and nowhere near q if none has."""
    J = A.toarray() if scipy.sparse.issparse(A) else np.asarray(A)
    J = J[:, free]
    if J.size > DIAGNOSED_ENTRIES:
        return None
    norms = np.linalg.norm(J, axis=1)
    norms[norms == 0] = 1.0
    U, s, Vt = np.linalg.svd(J / norms[:, None])
    rank = int(np.sum(s > NEAR_SINGULAR * s[0])) if s.size else 0
    r = phi / norms
    along = U[:, rank:].T @ r
    if not along.size or np.linalg.norm(along) < 0.5 * np.linalg.norm(r):
        return None
    w = U[:, rank:] @ along / np.linalg.norm(along)  # the dependency that carries φ
    weights = np.abs(w)
    rows = [n for n, x in zip(data.model.constraint_names, weights) if x > DEPENDENCY_SHARE * weights.max()]
    N = Vt[rank:].T  # the free coordinates' directions the rows do not move (to first order)
    if not N.shape[1] or N.shape[1] > DIAGNOSED_DIRECTIONS:
        return rows, None
    h = CURVATURE_STEP * max(np.abs(q).max(), 1.0)
    slopes = []
    for n in N.T:
        step = np.zeros_like(q)
        step[free] = h * n
        ends = [data.constraint_arrays(t, q + sign * step, np.zeros_like(q), sparse=False).A[:, free]
                for sign in (1, -1)]
        slopes.append(((w / norms) @ (ends[0] - ends[1])) / (2 * h))
    C = np.array(slopes) @ N
    values = np.linalg.eigvalsh((C + C.T) / 2)
    residual = w @ r
    opposite = values[values * residual < 0]
    if not opposite.size:
        return rows, None
    return rows, float(np.sqrt(2 * abs(residual) / np.abs(opposite).max()))


DIAGNOSED_DIRECTIONS = 60  # the curvature is taken along at most this many free directions
DEPENDENCY_SHARE = 0.1  # a row is named in a dependency where its weight exceeds this share of the largest
