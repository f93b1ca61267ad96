"""The well-posedness report behind ``mbsynth check``: Result 3 at a state.

Counts coordinates and constraints, the ranks of M, A and M̂ = [M; A], whether the
motion is unique, each indeterminate direction, and for each the balance
wᵀ(Q + C) = 0 that would close the model (see model/balances.py), or, where a part's angles
are at their singular position, that part (model/angle_singularity.py). How firm the verdict is:
the condition number of the equilibrated M̂, the rank tolerance, the verdict margin
(equations.py) and a warning when that margin is below ``VERDICT_MARGIN``. For a model made
of model files, each one's coordinates, rows and degrees of freedom (substructure_counts.py).
"""

from dataclasses import asdict, dataclass, field

import numpy as np

from ..model.angle_singularity import AngleParts
from ..model.balances import balances
from ..model.data import workspace
from ..model.parts.part_type import PLANE, POINT, QUATERNION
from ..core.equations import rank_report
from ..core.errors import SolveError
from ..core.kinematics import body_rate_matrix, quaternion_matrix, rotation_z
from ..core.tolerances import AXIS_TOL, BALANCE_ZERO_RTOL, COMPONENT_TOL, VERDICT_MARGIN
from .substructure_counts import substructure_counts



@dataclass(frozen=True)
class Diagnosis:
    model: str
    n: int
    m: int
    rank_M: int
    rank_A: int
    rank_Mhat: int
    unique: bool
    indeterminate: list
    suggested_constraints: list
    balances: list
    state_dependent: bool
    appended_balances: list
    constraint_residuals: dict
    qdd: dict = field(default_factory=dict)
    error: str = None
    condition: float = None  # σ₁/σ_n of the equilibrated [M; A]; None when infinite
    rank_tolerance: float = None  # singular values below rank_tolerance · σ₁ count as zero
    verdict_margin: float = None  # see RankReport.verdict_margin; None when infinite
    warnings: list = field(default_factory=list)
    joints: dict = field(default_factory=dict)  # joint -> {coordinates, position, rate, acceleration, ...}
    free_joints: list = field(default_factory=list)  # per indeterminate direction: {joint: rate per unit}
    # the parts whose angles are at their singular position (AngleSingularity.to_dict): indeterminate directions
    # of the coordinates, left out of ``balances``
    angle_singularities: list = field(default_factory=list)
    # the model files it includes, as a tree: coordinates, rows and degrees of freedom of each (substructure_counts)
    substructures: list = field(default_factory=list)
    # the limits and contacts (model/unilateral.py): name -> {kind, gap, rate, restitution} at the state
    gaps: dict = field(default_factory=dict)

    @property
    def consistent(self):
        return self.error is None

    def to_dict(self):
        return dict(asdict(self), consistent=self.consistent)


def diagnose(data, t=0.0, q=None, qd=None):
    """Result 3 and the balances of the model of ``data`` (a Data, or a model: its
    default-path Data) at (t, q, q̇), by default its initial state."""
    data = workspace(data)
    system = data.model
    q0, qd0 = data.initial_state()
    q = q0 if q is None else np.asarray(q, dtype=float)
    qd = qd0 if qd is None else np.asarray(qd, dtype=float)
    arrays = data.evaluate(t, q, qd)
    report = rank_report(arrays.M, arrays.A)
    found = balances(data, t, q, qd)
    phi, phidot = data.constraint_residuals(t, q, qd)
    residuals = {name: {"phi": _number(a), "phi_dot": _number(b)}
                 for name, a, b in zip(system.constraint_names, phi, phidot)}
    try:
        motion = data.motion(t, q, qd, method="reference")
        qdd, error = dict(zip(system.coordinates, map(float, motion.qdd))), None
    except SolveError as err:
        motion, qdd, error = None, {}, str(err)
    return Diagnosis(
        model=system.name, n=report.n, m=report.m, rank_M=report.rank_M, rank_A=report.rank_A,
        rank_Mhat=report.rank_Mhat, unique=report.unique,
        indeterminate=[_components(w, system.coordinates) for w in report.nullspace.T],
        suggested_constraints=[b.equation for b in found if not b.free],
        balances=[_balance(system, b, arrays.Q + arrays.C, q) for b in found],
        state_dependent=any(b.state_dependent for b in found),
        appended_balances=[{"constraint": c.constraint, "equation": c.equation, "direction": c.direction,
                   "state_dependent": c.state_dependent} for c in system.appended_balances],
        constraint_residuals=residuals, qdd=qdd, error=error, condition=_finite(report.condition),
        rank_tolerance=report.rtol, verdict_margin=_finite(report.verdict_margin), warnings=_warnings(report),
        joints=_joints(data, t, q, qd, motion), free_joints=_moved_joints(data, t, q, report.nullspace),
        angle_singularities=[a.to_dict() for a in AngleParts(system).set_aside(q, report.nullspace)[0]],
        substructures=substructure_counts(system, arrays.M, arrays.A), gaps=_gaps(data, t, q, qd))


def _gaps(data, t, q, qd):
    """{limit or contact: {kind, gap g, rate ġ, restitution}} at (t, q, q̇)."""
    system = data.model
    found = {}
    for u in system.unilaterals:
        (g,), (rate,) = u.row.residuals(t, q, qd, data.parameter_values)
        found[u.name] = {"kind": u.kind, "gap": float(g), "rate": float(rate),
                         "restitution": u.restitution_at(system, data.parameter_values)}
    return found


def _joints(data, t, q, qd, motion):
    """{joint: {coordinates, position, rate, acceleration names and values}} at the state
    (accelerations None without a motion): Data.joint_values."""
    kinematics = data.model.joint_kinematics()
    values = data.joint_values(t, q, qd, None if motion is None else motion.qdd)
    return {name: {"coordinates": list(kinematics[name].position_names),
                   "accelerations": list(kinematics[name].acceleration_names),
                   "position": v.position.tolist(), "rate": v.rate.tolist(),
                   "acceleration": None if v.acceleration is None else v.acceleration.tolist()}
            for name, v in values.items()}


def _moved_joints(data, t, q, nullspace):
    """Per indeterminate direction w (scaled as in ``indeterminate``), {joint: its rates
    when the state moves along w}: the joints the free direction turns or slides."""
    if not nullspace.shape[1] or not data.model.joint_kinematics():
        return [{} for _ in nullspace.T]
    rest = data.joint_values(t, q, np.zeros(data.model.n))
    found = []
    for w in nullspace.T:
        moving = data.joint_values(t, q, w / w[np.argmax(np.abs(w))])
        rates = {name: (v.rate - rest[name].rate) for name, v in moving.items()}
        scale = max((np.abs(r).max(initial=0.0) for r in rates.values()), default=0.0)
        found.append({name: r.tolist() for name, r in rates.items() if np.abs(r).max(initial=0.0) > COMPONENT_TOL
                      * max(scale, 1.0)})
    return found


def _balance(system, balance, force, q):
    """The report of one balance: its direction, whether it is free, its equation (exact,
    and ``readable``), and what it is physically (``effort``, at the state q)."""
    if balance.free:
        return {"direction": balance.direction, "free": True, "equation": None}
    return {"direction": balance.direction, "free": False, "equation": balance.equation,
            "readable": balance.readable_equation, "effort": effort(system, balance.direction, force, q)}


def effort(system, direction, force, q):
    """wᵀ(Q + C) along ``direction`` (a Balance's) read physically, when w moves one part
    alone: {"name": "torque about rod's z axis", "value": 0.3} when it turns a rigid body
    (body rate 2 E(u) w, kinematics.py) or a planar body, {"name": "force on p1 along the
    world's x axis", ...} when it moves a body or particle without turning; else None.
    ``force`` is Q + C at the state q, numbers over all coordinates; a value below BALANCE_ZERO_RTOL
    times its largest entry is 0."""
    owners = {name.split(".")[0] for name in direction}
    part = next((p for p in system.parts if {p.name} == owners), None)
    if part is None or not _one_piece(part.part_type):
        return None
    index = [system.coordinates.index(f"{part.name}.{c}") for c in part.coordinates]
    w = np.array([direction.get(f"{part.name}.{c}", 0.0) for c in part.coordinates])
    shift, turn, rotation = _motion_of(part.part_type, w, q[index])
    if np.any(shift) == np.any(turn):  # both (turning about another point) or neither
        return None
    moving = np.any(shift)
    own, words, length = _axis(shift if moving else turn, part.name, rotation)
    name = f"{'force' if moving else 'torque'}{'' if own else ' on ' + part.name} {'along' if moving else 'about'}"
    value = float(w @ force[index]) / length
    return {"name": f"{name} {words}", "value": 0.0 if abs(value) <= BALANCE_ZERO_RTOL * np.abs(force).max() else value}


def _one_piece(part_type):
    """Whether a step of a part's coordinates reads as one shift and one turn (``_motion_of``):
    a point, or a rigid body turned by a quaternion or in the plane."""
    if part_type.orientation == POINT:
        return len(part_type.points) == 1
    return part_type.rigid and part_type.orientation in (QUATERNION, PLANE)


def _motion_of(part_type, w, x):
    """(displacement, turn, both in world axes, and the part's rotation or None) of the
    step w of the coordinates x of a part of type ``part_type`` (``_one_piece``)."""
    if part_type.orientation == POINT:
        return w[:3], np.zeros(3), None
    if part_type.orientation == PLANE:
        return np.array([w[0], w[1], 0.0]), np.array([0.0, 0.0, w[2]]), np.array(rotation_z(x[2]), dtype=float)
    u = x[part_type.quaternion]
    R = quaternion_matrix(u)
    E = np.array(body_rate_matrix(u / np.linalg.norm(u)), dtype=float)
    return w[:3], R @ (2 * E @ w[part_type.quaternion]), R


def _axis(vector, name, rotation):
    """(whether it is the part's own axis, words for the axis along ``vector``, the signed
    length of ``vector`` along it): the part's own x, y or z axis (``rotation``: its axes in
    the world; None for a particle), else the world's, else the unit vector in world axes."""
    length = np.linalg.norm(vector)
    unit = vector / length
    for axes, owner in ((rotation, f"{name}'s"), (np.eye(3), "the world's")):
        if axes is None:
            continue
        local = axes.T @ unit
        i = int(np.argmax(np.abs(local)))
        if abs(local[i]) > 1 - AXIS_TOL:
            return axes is rotation, f"{owner} {'xyz'[i]} axis", length * np.sign(local[i])
    return False, "(" + ", ".join(f"{x:.3g}" for x in unit + 0.0) + ") in world axes", length


def _warnings(report):
    """A warning for each side of the rank cut-off that a singular value comes close to."""
    kept, dropped = report.margins
    found = []
    if kept < VERDICT_MARGIN:
        found.append(f"uncertain verdict: the smallest singular value kept in rank [M; A] = {report.rank_Mhat} "
                     f"is only {kept:.3g} times the cut-off ({report.rtol:g} of the largest, equilibrated); "
                     "a nearly singular mass or nearly dependent constraints: the motion may in fact not "
                     "be unique")
    if dropped < VERDICT_MARGIN:
        found.append(f"uncertain verdict: the largest singular value of [M; A] counted as zero is only "
                     f"{dropped:.3g} times below the cut-off ({report.rtol:g} of the largest, equilibrated); "
                     "the motion may in fact be unique")
    return found


def _finite(x):
    return float(x) if np.isfinite(x) else None


def _components(w, coordinates):
    """{coordinate: component} of a direction scaled so its largest component is +1."""
    w = w / w[np.argmax(np.abs(w))]
    return {c: float(x) for c, x in zip(coordinates, w) if abs(x) > COMPONENT_TOL}


def _number(x):
    return None if np.isnan(x) else float(x)
