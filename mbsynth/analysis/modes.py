"""Modes of a model at rest: natural frequencies, damping ratios and mode shapes.

The eigenvalues s of the linearization's A (linearization.py) at an equilibrium (q̇ = 0,
q̈ = 0) give the modes: a complex pair s = −ζω ± iω√(1 − ζ²) is one vibration mode of
natural frequency ω/2π (Hz) and damping ratio ζ = −Re s/|s|; a real s is an overdamped
(s < 0) or unstable (s > 0) motion, s = 0 a free (rigid-body) one. A mode's shape is its
eigenvector's position part mapped to the model's coordinates, δq = N x, scaled so that
its largest component is 1, and in joint values: a joint's position changes at the rate
its ``rate`` gives for q̇ = δq (System.joint_values; exact, the rates being linear in q̇).
A flexible body's share of a shape is also given in FE terms: its elastic coordinates' part
δη gives the nodal displacements Φ δη in the part's axes (each node's translation and, for
6-DOF nodes, rotation), so a mode reads as bending, stretching or twisting of the mesh.
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..core.errors import NoEquilibrium
from .linearization import finite_state, linearize, prescribed_motion
from .projection import project_positions
from .statics import equilibrium as find_equilibrium
from .steady import check_steady
from .trajectory import Trajectory
from ..core.tolerances import ACCELERATION_TOL, MODE_ZERO_RTOL

SHOWN = 3  # coordinates named per mode in the table
DEGENERATE_RTOL = 1e-6  # eigenvalues this close (relative) are one repeated mode, split by rounding
NODE_SHAPE_RTOL = 1e-9  # a flexible body's elastic coordinates below this share of a shape's largest: it does not bend


@dataclass(frozen=True)
class Mode:
    """One mode: ``eigenvalue`` s (rad/s), ``frequency`` |s|/2π (Hz), ``damping_ratio``
    −Re s/|s| (NaN for a free mode), ``kind`` ("vibration", "overdamped", "unstable" or
    "free"), ``shape`` (n complex, largest component 1), ``joint_shape``
    ({joint: complex array of its positions' changes}) and ``node_shape`` ({flexible body
    whose elastic coordinates the shape moves: NodeShape})."""

    eigenvalue: complex
    frequency: float
    damping_ratio: float
    kind: str
    shape: np.ndarray
    joint_shape: dict
    node_shape: dict = None


@dataclass(frozen=True)
class NodeShape:
    """A flexible body's nodal displacements Φ δη in a mode (its axes, the mode's scale):
    ``translations`` (nodes × 3 complex), ``rotations`` (nodes × 3 complex; None for 3-DOF
    nodes)."""

    translations: np.ndarray
    rotations: np.ndarray = None

    def largest(self, which="translations"):
        """(node, its displacement vector) of the largest translation (or rotation) by magnitude."""
        values = getattr(self, which)
        node = int(np.argmax(np.linalg.norm(values, axis=1)))
        return node, values[node]


@dataclass(frozen=True)
class Modes:
    """The modes of ``system_name`` at (t, q) (moving at ``qd`` about a steady motion),
    lowest frequency first, and the linearization; ``cyclic``: the states whose zero
    eigenvalues are not modes (cyclic coordinates, conserved speeds); ``zeros``: how many
    zero eigenvalues those and any others make (0 at a holonomic rest, whose zeros are
    free modes)."""

    system_name: str
    coordinates: tuple
    t: float
    q: np.ndarray
    modes: tuple
    linearization: object
    qd: np.ndarray = None
    cyclic: tuple = ()
    zeros: int = 0

    @property
    def frequencies(self):
        """The natural frequencies (Hz) of the modes, in order."""
        return np.array([m.frequency for m in self.modes])

    @property
    def damping_ratios(self):
        return np.array([m.damping_ratio for m in self.modes])

    @property
    def stable(self):
        """Whether no eigenvalue has a positive real part (beyond rounding)."""
        values = self.linearization.eigenvalues
        scale = np.abs(values).max(initial=0.0)
        return bool(np.all(values.real <= MODE_ZERO_RTOL * scale))


def modes(system, q=None, t=0.0, equilibrium=False, tolerance=ACCELERATION_TOL, qd=None, steady=False):
    """The ``Modes`` of ``system`` at rest at ``q`` (default: the initial positions); with
    ``equilibrium=True`` at the static equilibrium found from there (statics.py); with
    ``steady=True`` about the steady motion (q, q̇) (default: the initial state; a bicycle
    rolling upright, a disk rolling in a circle): its eigenvalues are the motion's stability
    exponents, and its cyclic coordinates and conserved speeds (``Modes.cyclic``) give
    exact zeros that are not listed as modes. Raises NoEquilibrium when the model does not
    rest at q (q̈ ≠ 0 at q̇ = 0), or the motion is not steady, or no equilibrium is found;
    SolveError where the linearization is refused (linearization.py)."""
    q0, qd0 = system.initial_state()
    q = q0 if q is None else np.array(q, dtype=float)
    if equilibrium:
        q = find_equilibrium(system, q, t)
    qd = (qd0 if qd is None else np.array(qd, dtype=float)) if steady else np.zeros(system.n)
    q, qd = finite_state(system, q, qd)
    moving = [] if steady else prescribed_motion(system, t, q, qd)
    if moving:
        raise NoEquilibrium(f"model '{system.name}' does not rest at this configuration: rows {moving} prescribe a "
                            f"motion at t = {t:g} (∂φ/∂t ≠ 0); modes are taken at rest", constraints=moving)
    lin = linearize(system, t, q, qd)
    _check_rest_or_steady(system, lin, tolerance, steady)
    k = lin.k
    values = lin.eigenvalues
    scale = np.abs(values).max(initial=0.0)
    free = np.abs(values) <= MODE_ZERO_RTOL * scale
    found = []
    if _holonomic_rest(lin):  # zeros in pairs: a free direction and its rate
        found = [_mode(system, t, q, lin, 0j, x, scale) for x in _free_directions(lin, (int(free.sum()) + 1) // 2)]
    upper = [s for s in values[~free] if s.imag >= -MODE_ZERO_RTOL * scale]  # one of each conjugate pair
    for group in _degenerate_groups(upper):
        for s, x in zip(group, _eigenspace(lin.A, group, k)):
            found.append(_mode(system, t, q, lin, s, x, scale))
    found.sort(key=lambda m: (m.frequency, m.eigenvalue.real))
    cyclic = () if _holonomic_rest(lin) else lin.cyclic
    return Modes(system.name, system.coordinates, float(t), q, tuple(found), lin, qd, cyclic,
                 0 if _holonomic_rest(lin) else int(free.sum()))


def _holonomic_rest(lin):
    """Whether ``lin`` is about a rest with as many speeds as coordinates (no
    non-holonomic rows): its free directions are double zeros, one mode each."""
    return lin.A.shape[0] == 2 * lin.k and not np.any(lin.qd)


def _check_rest_or_steady(system, lin, tolerance, steady):
    """NoEquilibrium unless the state is a rest (q̈ = 0) or, ``steady``, a steady motion
    (steady.check_steady)."""
    if steady:
        check_steady(system, lin, tolerance)
        return
    worst = int(np.argmax(np.abs(lin.qdd))) if lin.qdd.size else 0
    if lin.qdd.size and abs(lin.qdd[worst]) > tolerance * (1 + np.abs(lin.A[lin.k:, :lin.k]).max(initial=0.0)):
        raise NoEquilibrium(f"model '{system.name}' does not rest at this configuration (q̈ = {lin.qdd[worst]:.3g} "
                            f"along {system.coordinates[worst]}): modes are taken at an equilibrium "
                            "(mbsynth.equilibrium, or equilibrium=True)", coordinates=[system.coordinates[worst]])


def _degenerate_groups(values):
    """The eigenvalues grouped where they repeat (within DEGENERATE_RTOL of their size: a
    round beam's two bending planes, split by rounding only)."""
    groups = []
    for s in sorted(values, key=lambda z: (z.imag, z.real)):
        if groups and abs(s - groups[-1][0]) <= DEGENERATE_RTOL * max(abs(s), abs(groups[-1][0])):
            groups[-1].append(s)
        else:
            groups.append([s])
    return groups


def _eigenspace(A, group, k):
    """One position part (the first k components) of an eigenvector of A per eigenvalue of
    ``group`` (equal but for rounding), spanning their eigenspace: the right singular
    vectors of A − s̄I of the smallest singular values. Where those positions span a real
    space (an undamped or proportionally damped repeated mode), a real orthonormal basis of
    it, so that each shape is one real motion rather than a complex mixture of the others,
    each moving one of the basis's pivot coordinates (QR with column pivoting) and not the
    others' (a beam's bending in each of its axes' planes, where its coordinates are those)."""
    mean = np.mean(group)
    vectors = np.linalg.svd(A - mean * np.eye(A.shape[0]))[2][-len(group):].conj()[:, :k]
    if len(group) == 1:
        return list(vectors)
    parts = np.vstack([vectors.real, vectors.imag])
    _, sigma, Vt = np.linalg.svd(parts)
    if sigma.size > len(group) and sigma[len(group)] > DEGENERATE_RTOL * sigma[0]:
        return list(vectors)  # a complex eigenspace (gyroscopic, non-proportional damping)
    basis = Vt[:len(group)]
    pivots = scipy.linalg.qr(basis, pivoting=True)[2][:len(group)]
    return list(np.linalg.solve(basis[:, pivots], basis).astype(complex))


def _free_directions(lin, count):
    """``count`` directions x of the independent coordinates along which nothing resists:
    the right singular vectors of the stiffness block K = ∂ü/∂u of A with the smallest
    singular values (a free direction is a double zero eigenvalue of A, one mode)."""
    k = lin.k
    return np.linalg.svd(lin.A[k:, :k])[2][k - count:] if count else []


def _mode(system, t, q, lin, s, x, scale):
    """The Mode of eigenvalue s with the independent coordinates' motion x."""
    shape = lin.basis @ x
    shape = shape / shape[np.argmax(np.abs(shape))]
    return Mode(complex(s), float(abs(s) / (2 * np.pi)), _damping(s, scale), _kind(s, scale), shape,
                _joint_shape(system, t, q, shape), _node_shapes(system, shape))


def _damping(s, scale):
    """−Re s/|s|; NaN for a free mode, 0 where Re s is rounding (below ε times the largest |s|)."""
    if abs(s) <= MODE_ZERO_RTOL * scale:
        return float("nan")
    return 0.0 if abs(s.real) <= 8 * np.finfo(float).eps * scale else float(-s.real / abs(s))


def _kind(s, scale):
    if abs(s) <= MODE_ZERO_RTOL * scale:
        return "free"
    if abs(s.imag) > MODE_ZERO_RTOL * scale:
        return "vibration" if s.real <= MODE_ZERO_RTOL * scale else "unstable"
    return "overdamped" if s.real < 0 else "unstable"


def _joint_shape(system, t, q, shape):
    """{joint: complex array}: the change of each joint's positions along ``shape``."""
    real = system.joint_values(t, q, shape.real)
    imag = system.joint_values(t, q, shape.imag)
    return {name: real[name].rate + 1j * imag[name].rate for name in real}


def _node_shapes(system, shape):
    """{flexible body: NodeShape} of the flexible bodies whose elastic coordinates ``shape``
    moves (by more than NODE_SHAPE_RTOL of its largest component)."""
    found, start = {}, 0
    for part in system.parts:
        n = len(part.coordinates)
        if part.kind == "flexible_body":
            reduction = part.reduction
            eta = shape[start:start + n][part.elastic]
            if np.abs(eta).max(initial=0.0) > NODE_SHAPE_RTOL * np.abs(shape).max():
                u = (reduction.basis @ eta).reshape(len(reduction.fe.nodes), -1)
                found[part.name] = NodeShape(u[:, :3], u[:, 3:6] if u.shape[1] == 6 else None)
        start += n
    return found


def mode_motion(system, result, index, amplitude=0.05, periods=2, frames=60):
    """A Trajectory that shows mode ``index`` of ``result`` (for the viewer: one per mode):
    q(t) = q₀ + amplitude · Re(shape · e^{iωt}) over ``periods`` periods (1 s each for a
    mode of frequency 0), put back on the constraints at each frame (a finite amplitude
    leaves the tangent plane). ``amplitude`` is the largest coordinate's excursion, in its
    units. Energies and residuals are not computed (NaN)."""
    mode = result.modes[index]
    omega = 2 * np.pi * (mode.frequency or 1.0)
    t = np.linspace(0.0, periods * 2 * np.pi / omega, frames)
    q = np.array([project_positions(system, result.t, result.q + amplitude * (mode.shape * np.exp(1j * omega * x)).real)
                  for x in t])
    nan = np.full(frames, np.nan)
    return Trajectory(result.coordinates, t, q, np.gradient(q, t, axis=0), nan, nan, nan, nan)


def format_modes(result, digits=6):
    """The modes as a text table: one row per mode, the joints (or, in a model without
    joint values, the coordinates) that move most, relative to the largest."""
    lin = result.linearization
    independent = ", ".join(lin.state_names[:lin.k]) or "none"
    about = "about its steady motion" if np.any(lin.qd) else "at rest"
    speeds = (f", {lin.A.shape[0] - lin.k} independent speed(s): {', '.join(lin.state_names[lin.k:])}"
              if lin.A.shape[0] != 2 * lin.k or np.any(lin.qd) else "")
    lines = [f"modes of {result.system_name} {about} at t = {result.t:g}: {lin.k} degree(s) of freedom "
             f"(independent coordinates: {independent}{speeds})",
             f"{'#':>3}  {'frequency [Hz]':>15}  {'damping ratio':>13}  {'kind':<10}  {'eigenvalue [rad/s]':<26}"
             "  largest motion"]
    for i, mode in enumerate(result.modes, 1):
        s = mode.eigenvalue
        lines.append(f"{i:>3}  {mode.frequency:>15.{digits}g}  {mode.damping_ratio:>13.4g}  {mode.kind:<10}  "
                     f"{f'{s.real:.{digits}g}{s.imag:+.{digits}g}j':<26}  {_largest(result, mode)}")
        lines += [f"{'':>5}{_nodes(name, nodes)}" for name, nodes in (mode.node_shape or {}).items()]
    if result.zeros:
        named = f" (cyclic coordinates and conserved speeds: {', '.join(result.cyclic)})" if result.cyclic else ""
        lines.append(f"zero eigenvalues: {result.zeros}{named}")
    if not result.stable:
        lines.append("unstable: an eigenvalue has a positive real part (the equilibrium is not a rest one keeps)"
                     if not np.any(lin.qd) else "unstable: an eigenvalue has a positive real part")
    return "\n".join(lines)


def _largest(result, mode):
    """The SHOWN joint values (where the model has joints with values) or coordinates that
    move most in ``mode``, relative to the largest."""
    names, values = list(result.coordinates), mode.shape
    if mode.joint_shape:
        names = [f"{j}[{c}]" if len(v) > 1 else j for j, v in mode.joint_shape.items() for c in range(len(v))]
        values = np.concatenate(list(mode.joint_shape.values()))
    top = np.abs(values).max(initial=0.0)
    if top == 0:
        return ""
    values = values / values[np.argmax(np.abs(values))]
    order = np.argsort(-np.abs(values))[:SHOWN]
    return ", ".join(f"{names[j]} {_short(values[j])}" for j in order if abs(values[j]) > 1e-6)


def _nodes(name, nodes):
    """A flexible body's line under its mode: the node that moves most and its translation
    (real parts, the part's axes), and the node that turns most."""
    node, t = nodes.largest()
    text = f"{name}: node {node} moves most, {_vector(t)} in its axes"
    if nodes.rotations is not None:
        node, r = nodes.largest("rotations")
        text += f"; node {node} turns most, {_vector(r)} rad"
    return text


def _vector(v):
    """(x, y, z) short, real and imaginary parts below 1e-6 of the vector's size shown as 0."""
    small = 1e-6 * np.linalg.norm(v)
    v = np.where(np.abs(v.real) > small, v.real, 0.0) + 1j * np.where(np.abs(v.imag) > small, v.imag, 0.0)
    return f"({', '.join(_short(x) for x in v)})"


def _short(z):
    return f"{z.real:.3g}" if abs(z.imag) <= 1e-9 * max(abs(z), 1e-300) else f"{z.real:.3g}{z.imag:+.3g}j"


def to_dict(result):
    """The modes as JSON-ready data: per mode its eigenvalue, frequency, damping ratio,
    kind and shapes (real parts; ``*_imag`` where a shape is complex)."""
    lin = result.linearization
    out = {"model": result.system_name, "t": result.t, "q": dict(zip(result.coordinates, map(float, result.q))),
           "degrees_of_freedom": lin.k, "independent_coordinates": list(lin.state_names[:lin.k]),
           "independent_speeds": list(lin.state_names[lin.k:]), "steady_motion": bool(np.any(lin.qd)),
           "qd": dict(zip(result.coordinates, map(float, lin.qd))),
           "eigenvalues": [[float(x.real), float(x.imag)] for x in lin.eigenvalues],
           "zero_eigenvalues": result.zeros, "cyclic": list(result.cyclic),
           "stable": result.stable, "modes": []}
    for mode in result.modes:
        entry = {"eigenvalue": [mode.eigenvalue.real, mode.eigenvalue.imag], "frequency_hz": mode.frequency,
                 "damping_ratio": None if np.isnan(mode.damping_ratio) else mode.damping_ratio, "kind": mode.kind,
                 "shape": {c: float(x.real) for c, x in zip(result.coordinates, mode.shape) if abs(x) > 1e-12},
                 "joint_shape": {j: [float(x) for x in v.real] for j, v in mode.joint_shape.items()}}
        if mode.node_shape:
            entry["node_shape"] = {name: _node_entry(nodes, np.real) for name, nodes in mode.node_shape.items()}
        if np.abs(mode.shape.imag).max(initial=0.0) > 1e-9:
            entry["shape_imag"] = {c: float(x.imag) for c, x in zip(result.coordinates, mode.shape) if abs(x) > 1e-12}
            entry["joint_shape_imag"] = {j: [float(x) for x in v.imag] for j, v in mode.joint_shape.items()}
            if mode.node_shape:
                entry["node_shape_imag"] = {name: _node_entry(nodes, np.imag) for name, nodes in mode.node_shape.items()}
        out["modes"].append(entry)
    return out


def _node_entry(nodes, part):
    """A NodeShape as JSON-ready data: the ``part`` (np.real or np.imag) of each node's
    translation (and rotation), the largest translation's node and size."""
    node, t = nodes.largest()
    entry = {"translations": part(nodes.translations).tolist(), "largest_translation_node": node,
             "largest_translation": float(np.linalg.norm(t))}
    if nodes.rotations is not None:
        entry["rotations"] = part(nodes.rotations).tolist()
    return entry
