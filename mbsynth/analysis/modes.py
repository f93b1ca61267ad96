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
from ..model.data import workspace
from .linearization import finite_state, linearize, prescribed_motion
from .projection import project_positions
from .statics import equilibrium as find_equilibrium
from .steady import check_steady
from .trajectory import Trajectory
from ..core.tolerances import (ACCELERATION_TOL, COMPLEX_SHAPE_TOL, DAMPING_ROUNDING, DEGENERATE_RTOL, DIVISION_GUARD,
                               IMAGINARY_SHOWN_RTOL, MODE_SHOWN_RTOL, MODE_ZERO_RTOL, NODE_SHAPE_RTOL,
                               SHAPE_ENTRY_ZERO, STABILITY_RTOL)

SHOWN = 3  # coordinates named per mode in the table


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
    lowest frequency first, and the linearization; ``cyclic``: one name per zero eigenvalue
    that is not a mode (cyclic coordinates, conserved speeds and directions that combine
    them: ``Linearization.zero_states``); ``zeros``: how many (0 at a holonomic rest, whose
    zeros are free modes)."""

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
        """Whether no eigenvalue has a positive real part (beyond STABILITY_RTOL): the
        ``verdict`` is stable or neutral."""
        return self.verdict.kind != "unstable"

    @property
    def verdict(self):
        """The ``Verdict``: decided by the mode whose exponent has the largest real part (the
        zero eigenvalues of ``cyclic`` aside: they move along the family of motions)."""
        scale = np.abs(self.linearization.eigenvalues).max(initial=0.0)
        if not self.modes:
            return Verdict("neutral", None, None, STABILITY_RTOL * scale)
        index = max(range(len(self.modes)), key=lambda i: self.modes[i].eigenvalue.real)
        s = self.modes[index].eigenvalue
        margin = STABILITY_RTOL * scale
        kind = "unstable" if s.real > margin else "stable" if s.real < -margin else "neutral"
        return Verdict(kind, index, s, margin)


@dataclass(frozen=True)
class Verdict:
    """Whether a rest or steady motion keeps itself: ``kind`` "stable" (every mode decays),
    "unstable" (one grows) or "neutral" (the slowest neither grows nor decays, within
    ``margin`` = STABILITY_RTOL times the largest |s|: undamped vibration, a free direction,
    a speed at a boundary of stability); ``mode``: the index in ``Modes.modes`` of the one
    that decides (the largest real part), ``eigenvalue`` its exponent (None without modes)."""

    kind: str
    mode: int
    eigenvalue: complex
    margin: float


def modes(model, q=None, t=0.0, equilibrium=False, tolerance=ACCELERATION_TOL, qd=None, steady=False):
    """The ``Modes`` of ``model`` (a System, at its parameter values, or a Data, at its own)
    at rest at ``q`` (default: the initial positions); with
    ``equilibrium=True`` at the static equilibrium found from there (statics.py); with
    ``steady=True`` about the steady motion (q, q̇) (default: the initial state; a bicycle
    rolling upright, a disk rolling in a circle): its eigenvalues are the motion's stability
    exponents, and its cyclic coordinates and conserved speeds (``Modes.cyclic``) give
    exact zeros that are not listed as modes. Raises NoEquilibrium when the model does not
    rest at q (q̈ ≠ 0 at q̇ = 0), or the motion is not steady, or no equilibrium is found;
    SolveError where the linearization is refused (linearization.py)."""
    data = workspace(model)
    system = data.model
    q0, qd0 = data.initial_state()
    q = q0 if q is None else np.array(q, dtype=float)
    if equilibrium:
        q = find_equilibrium(data, q, t)
    qd = (qd0 if qd is None else np.array(qd, dtype=float)) if steady else np.zeros(system.n)
    q, qd = finite_state(system, q, qd)
    moving = [] if steady else prescribed_motion(data, t, q, qd)
    if moving:
        raise NoEquilibrium(f"model '{system.name}' does not rest at this configuration: rows {moving} prescribe a "
                            f"motion at t = {t:g} (∂φ/∂t ≠ 0); modes are taken at rest", constraints=moving)
    lin = linearize(data, t, q, qd)
    _check_rest_or_steady(system, lin, tolerance, steady)
    k = lin.k
    values = lin.eigenvalues
    scale = np.abs(values).max(initial=0.0)
    rest = _holonomic_rest(lin)
    # zeros: at a holonomic rest in pairs, a free direction and its rate (modes of their own); else the
    # exact zeros of the cyclic directions (Linearization.zero_states), every other exponent a mode
    free = np.abs(values) <= MODE_ZERO_RTOL * scale if rest else values == 0
    found = []
    if rest:
        found = [_mode(data, t, q, lin, 0j, x, scale) for x in _free_directions(lin, (int(free.sum()) + 1) // 2)]
    upper = [s for s in values[~free] if s.imag >= -MODE_ZERO_RTOL * scale]  # one of each conjugate pair
    for group in _degenerate_groups(upper):
        for s, x in zip(group, _eigenspace(lin.A, group, k)):
            found.append(_mode(data, t, q, lin, s, x, scale))
    found.sort(key=lambda m: (m.frequency, m.eigenvalue.real))
    cyclic = () if rest else lin.zero_states
    return Modes(system.name, system.coordinates, float(t), q, tuple(found), lin, qd, cyclic, len(cyclic))


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


def _mode(data, t, q, lin, s, x, scale):
    """The Mode of eigenvalue s with the independent coordinates' motion x."""
    shape = lin.basis @ x
    shape = shape / shape[np.argmax(np.abs(shape))]
    return Mode(complex(s), float(abs(s) / (2 * np.pi)), _damping(s, scale), _kind(s, scale), shape,
                _joint_shape(data, t, q, shape), _node_shapes(data.model, shape))


def _damping(s, scale):
    """−Re s/|s|; NaN for a free mode, 0 where Re s is rounding (below ε times the largest |s|)."""
    if abs(s) <= MODE_ZERO_RTOL * scale:
        return float("nan")
    return 0.0 if abs(s.real) <= DAMPING_ROUNDING * scale else float(-s.real / abs(s))


def _kind(s, scale):
    if abs(s) <= MODE_ZERO_RTOL * scale:
        return "free"
    if abs(s.imag) > MODE_ZERO_RTOL * scale:
        return "vibration" if s.real <= MODE_ZERO_RTOL * scale else "unstable"
    return "overdamped" if s.real < 0 else "unstable"


def _joint_shape(data, t, q, shape):
    """{joint: complex array}: the change of each joint's positions along ``shape``."""
    real = data.joint_values(t, q, shape.real)
    imag = data.joint_values(t, q, shape.imag)
    return {name: real[name].rate + 1j * imag[name].rate for name in real}


def _node_shapes(system, shape):
    """{flexible body: NodeShape} of the flexible bodies whose elastic coordinates ``shape``
    moves (by more than NODE_SHAPE_RTOL of its largest component)."""
    found, start = {}, 0
    for part in system.parts:
        n = len(part.coordinates)
        if part.part_type.elastic:
            reduction = part.reduction
            eta = shape[start:start + n][part.elastic]
            if np.abs(eta).max(initial=0.0) > NODE_SHAPE_RTOL * np.abs(shape).max():
                u = (reduction.basis @ eta).reshape(len(reduction.fe.nodes), -1)
                found[part.name] = NodeShape(u[:, :3], u[:, 3:6] if u.shape[1] == 6 else None)
        start += n
    return found


def mode_motion(model, result, index, amplitude=0.05, periods=2, frames=60):
    """A Trajectory that shows mode ``index`` of ``result`` (the ``Modes`` of ``model``, a
    System or a Data; for the viewer: one per mode):
    q(t) = q₀ + amplitude · Re(shape · e^{iωt}) over ``periods`` periods (1 s each for a
    mode of frequency 0), put back on the constraints at each frame (a finite amplitude
    leaves the tangent plane). ``amplitude`` is the largest coordinate's excursion, in its
    units. Energies and residuals are not computed (NaN)."""
    data = workspace(model)
    mode = result.modes[index]
    omega = 2 * np.pi * (mode.frequency or 1.0)
    t = np.linspace(0.0, periods * 2 * np.pi / omega, frames)
    q = np.array([project_positions(data, result.t, result.q + amplitude * (mode.shape * np.exp(1j * omega * x)).real)
                  for x in t])
    nan = np.full(frames, np.nan)
    return Trajectory(result.coordinates, t, q, np.gradient(q, t, axis=0), nan, nan, nan, nan)


def format_modes(result, digits=6):
    """The modes as a text table under a header that says about what state they are taken
    and in which coordinates: one row per mode, the joints (or, in a model without joint
    values, the coordinates) that move most, relative to the largest; then the zero
    eigenvalues that are no modes and the verdict (``Modes.verdict``)."""
    lin = result.linearization
    steady = bool(np.any(lin.qd))
    speeds = lin.A.shape[0] - lin.k
    lines = [f"modes of {result.system_name} {'about its steady motion' if steady else 'at rest'} at t = {result.t:g}",
             f"  {_count(lin.k, 'degree')} of freedom, independent coordinates: "
             f"{', '.join(lin.state_names[:lin.k]) or 'none'}"]
    if speeds != lin.k or steady:
        lines.append(f"  {_count(speeds, 'independent speed')} (the non-holonomic rows give the other rates): "
                     f"{', '.join(lin.state_names[lin.k:]) or 'none'}")
    if steady:
        lines.append("  each eigenvalue s is a stability exponent: a small disturbance grows or decays as e^(s t)")
    lines.append(f"{'#':>3}  {'frequency [Hz]':>15}  {'damping ratio':>13}  {'kind':<10}  {'eigenvalue [rad/s]':<26}"
                 "  largest motion")
    for i, mode in enumerate(result.modes, 1):
        s = mode.eigenvalue
        lines.append(f"{i:>3}  {mode.frequency:>15.{digits}g}  {mode.damping_ratio:>13.4g}  {mode.kind:<10}  "
                     f"{f'{s.real:.{digits}g}{s.imag:+.{digits}g}j':<26}  {_largest(result, mode)}")
        lines += [f"{'':>5}{_nodes(name, nodes)}" for name, nodes in (mode.node_shape or {}).items()]
    if result.zeros:
        lines.append(f"zero eigenvalues: {result.zeros}, no modes: directions along the family of "
                     f"{'steady motions' if steady else 'rests'} (cyclic coordinates, conserved speeds): "
                     f"{', '.join(result.cyclic)}")
    lines.append(_verdict_line(result, steady))
    return "\n".join(lines)


def _count(number, noun):
    return f"{number} {noun}{'' if number == 1 else 's'}"


def _verdict_line(result, steady):
    """The verdict in words: stable, unstable or neutral, and the exponent that decides."""
    verdict = result.verdict
    what = "the steady motion" if steady else "the rest"
    if verdict.mode is None:
        return f"verdict: neutral ({what} has no mode beyond the zero eigenvalues)"
    s = verdict.eigenvalue
    exponent = f"mode {verdict.mode + 1}, s = {s.real:.6g}{s.imag:+.6g}j"
    if verdict.kind == "stable":
        return f"verdict: stable: every mode decays; the slowest, {exponent}, decides"
    if verdict.kind == "unstable":
        return f"verdict: unstable: {exponent} grows (Re s > 0): {what} is not one the model keeps"
    why = {"vibration": "undamped: it neither grows nor decays", "free": "a free direction, which nothing restores"}
    return (f"verdict: neutral: the largest real part, of {exponent}, is zero within {STABILITY_RTOL:g} of the "
            f"largest |s| ({why.get(result.modes[verdict.mode].kind, 'at a boundary of stability')}): the "
            "linearization does not decide")


def _largest(result, mode):
    """The SHOWN joint values (where the model has joints with values and the mode moves them:
    beyond MODE_SHOWN_RTOL of the shape's largest coordinate, 1) or coordinates that move most
    in ``mode``, relative to the largest (a blade bending on its driven hub moves no joint)."""
    names, values = list(result.coordinates), mode.shape
    joints = np.concatenate(list(mode.joint_shape.values())) if mode.joint_shape else np.zeros(0)
    if np.abs(joints).max(initial=0.0) > MODE_SHOWN_RTOL:
        names = [f"{j}[{c}]" if len(v) > 1 else j for j, v in mode.joint_shape.items() for c in range(len(v))]
        values = joints
    top = np.abs(values).max(initial=0.0)
    if top == 0:
        return ""
    values = values / values[np.argmax(np.abs(values))]
    order = np.argsort(-np.abs(values))[:SHOWN]
    return ", ".join(f"{names[j]} {_short(values[j])}" for j in order if abs(values[j]) > MODE_SHOWN_RTOL)


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
    """(x, y, z) short, real and imaginary parts below MODE_SHOWN_RTOL of the vector's size shown as 0."""
    small = MODE_SHOWN_RTOL * np.linalg.norm(v)
    v = np.where(np.abs(v.real) > small, v.real, 0.0) + 1j * np.where(np.abs(v.imag) > small, v.imag, 0.0)
    return f"({', '.join(_short(x) for x in v)})"


def _short(z):
    real = abs(z.imag) <= IMAGINARY_SHOWN_RTOL * max(abs(z), DIVISION_GUARD)
    return f"{z.real:.3g}" if real else f"{z.real:.3g}{z.imag:+.3g}j"


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
           "stable": result.stable, "verdict": _verdict_entry(result.verdict), "modes": []}
    for mode in result.modes:
        entry = {"eigenvalue": [mode.eigenvalue.real, mode.eigenvalue.imag], "frequency_hz": mode.frequency,
                 "damping_ratio": None if np.isnan(mode.damping_ratio) else mode.damping_ratio, "kind": mode.kind,
                 "shape": {c: float(x.real) for c, x in zip(result.coordinates, mode.shape)
                           if abs(x) > SHAPE_ENTRY_ZERO},
                 "joint_shape": {j: [float(x) for x in v.real] for j, v in mode.joint_shape.items()}}
        if mode.node_shape:
            entry["node_shape"] = {name: _node_entry(nodes, np.real) for name, nodes in mode.node_shape.items()}
        if np.abs(mode.shape.imag).max(initial=0.0) > COMPLEX_SHAPE_TOL:
            entry["shape_imag"] = {c: float(x.imag) for c, x in zip(result.coordinates, mode.shape)
                                   if abs(x) > SHAPE_ENTRY_ZERO}
            entry["joint_shape_imag"] = {j: [float(x) for x in v.imag] for j, v in mode.joint_shape.items()}
            if mode.node_shape:
                entry["node_shape_imag"] = {name: _node_entry(nodes, np.imag) for name, nodes in mode.node_shape.items()}
        out["modes"].append(entry)
    return out


def _verdict_entry(verdict):
    """A Verdict as JSON-ready data: its kind, the deciding mode (1-based, as in the table)
    and exponent, and the margin that separates stable, neutral and unstable."""
    s = verdict.eigenvalue
    return {"kind": verdict.kind, "mode": None if verdict.mode is None else verdict.mode + 1,
            "eigenvalue": None if s is None else [s.real, s.imag], "margin": verdict.margin,
            "stability_rtol": STABILITY_RTOL}


def _node_entry(nodes, part):
    """A NodeShape as JSON-ready data: the ``part`` (np.real or np.imag) of each node's
    translation (and rotation), the largest translation's node and size."""
    node, t = nodes.largest()
    entry = {"translations": part(nodes.translations).tolist(), "largest_translation_node": node,
             "largest_translation": float(np.linalg.norm(t))}
    if nodes.rotations is not None:
        entry["rotations"] = part(nodes.rotations).tolist()
    return entry
