"""Cross-checks against Pinocchio: mbsynth's joint accelerations against ``pinocchio.aba``
(``constraintDynamics`` where loops are closed) at random states and torques.

A sample is drawn in Pinocchio's coordinates: q within the joint limits (revolute joints
without limits in [−π, π], prismatic ones in [−0.5, 0.5] m, a free-flyer's position in
[−1, 1]³ with a uniformly random orientation), v ~ N(0, 1), every robot joint torque
uniform within its URDF effort limit (N(0, 1) where it has none). The state is carried
into mbsynth's coordinates by forward kinematics (twin.py); with loops it is first put
on the constraint manifold (projection.py) and read back. mbsynth's q̈ (2.14) becomes v̇
(twin.py) and is compared with Pinocchio's: absolute error ‖Δv̇‖∞, relative error
‖Δv̇‖∞ / ‖v̇‖∞, the largest over the samples. Force elements other than the joint
torques (springs, applied forces) enter Pinocchio as τ = Sᵀ Q_e, S = ∂q̇/∂v (virtual power).

Joint space, at the same samples: ``System.joint_values`` against Pinocchio's (q, v, v̇)
joint by joint (angles modulo 2π, a free-flyer's quaternion up to sign; relative to
1 + the largest |v|, |v̇|), and, on a tree without other force elements, each joint's
``System.reactions`` wrench against ``data.f`` of ``rnea(q, v, v̇)`` (relative to the
largest entry of data.f).

Loop-closing joints, at the same samples, against ``data.lambda_c`` of
``constraintDynamics`` (each loop's wrench at its child frame: ``Twin.loop_wrench_maps``).
Where a loop is over-constrained (a planar four-bar in space) the wrenches its joints
carry are not unique: any self-stress — λ with Jᵀλ = 0, J Pinocchio's constraint Jacobian
— may be added, and mbsynth (the least-norm λ in its rows) and Pinocchio (the proximal
solution in its contact forces) legitimately choose differently. Only what is determined
is compared: each joint's wrench projected onto the orthogonal complement of the wrenches
the self-stresses give it (``determined_projector``), relative to the largest projected
entry of Pinocchio's wrenches. ``loop_free`` counts the undetermined components (0: the
whole wrench is compared).
"""

import contextlib
import os
import sys
import time
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass

import numpy as np
import pinocchio as pin

from ..core.errors import ModelError, SolveError
from ..analysis.projection import project
from .build import describe, fix_base, from_robot, robot_files
from .twin import Twin
from ..core.tolerances import NULLSPACE_SHOWN_TOL, SAME_STATE_TOL, SELF_STRESS_RTOL, VALIDATION_RTOL

MAX_TRIES = 20  # samples drawn to find one a loop can close at


@dataclass(frozen=True)
class Validation:
    """The outcome of one comparison: ``robot`` (or model) with a ``base`` (fixed,
    floating, or "model" for a model file), its ``links`` (bodies) and ``nv`` (Pinocchio's
    velocity count, before loops close); the largest errors over ``samples`` states; ``passed`` (below ``tolerance``);
    ``build_s`` (seconds to build the System), ``motion_ms`` (mean mbsynth evaluation);
    ``note`` says why a comparison was impossible (no unique motion, NaN from Pinocchio);
    ``joint_error``, ``reaction_error``, ``loop_reaction_error`` (with ``loop_free``): the
    joint-space comparisons (module docstring)."""

    robot: str
    base: str
    links: int
    nv: int
    samples: int
    max_abs_error: float
    max_rel_error: float
    passed: bool
    tolerance: float
    build_s: float
    motion_ms: float
    note: str = ""
    joint_error: float = float("nan")  # joint_values against Pinocchio's (q, v, v̇), relative
    reaction_error: float = float("nan")  # reactions against rnea's data.f, relative (NaN: not compared)
    loop_reaction_error: float = float("nan")  # loop joints against lambda_c, relative (NaN: no loops)
    loop_free: int = 0  # the most undetermined wrench components of a loop joint (module docstring)

    def to_dict(self):
        return asdict(self)


def validate_robot(name_or_urdf, samples=20, seed=0, bases=("fixed", "floating"), tolerance=VALIDATION_RTOL,
                   merge_fixed=False):
    """[Validation] of a robot for each base: built once floating (``merge_fixed``: its
    welded links merged, from_robot), then welded for fixed."""
    started = time.perf_counter()
    floating = from_robot(name_or_urdf, floating=True, merge_fixed=merge_fixed)
    build_s = time.perf_counter() - started
    results = []
    for base in bases:
        system = floating if base == "floating" else fix_base(floating)
        results.append(validate_system(system, samples, seed, tolerance, base=base, build_s=build_s,
                                       label=str(name_or_urdf)))
    return results


def validate_system(system, samples=20, seed=0, tolerance=VALIDATION_RTOL, base="model", build_s=0.0, label=None):
    """The Validation of ``system`` (named ``label``, by default its own name) against its
    Pinocchio twin (ModelError when it has none)."""
    twin = Twin(system)
    rng = np.random.default_rng(seed)
    efforts = {robot.torques[j.name]: j.effort for robot in system.robots for j in robot.description.joints
               if j.name in robot.torques}
    others = [e for e in system.forces if e.name not in twin.torque_elements]
    worst_abs = worst_rel = worst_joint = 0.0
    worst_reaction = 0.0 if not (others or twin.constraints) else float("nan")
    worst_loop, loop_free = float("nan"), 0
    notes, seconds = [], []
    for _ in range(samples):
        q, v, qm, qdm = _consistent_sample(system, twin, rng)
        torques = {c.torque: _torque(rng, efforts.get(c.torque)) for c in twin.coordinates if c.torque}
        tau = np.zeros(twin.model.nv)
        for c in twin.coordinates:
            if c.torque:
                tau[c.idx_v] = torques[c.torque]
        if others:
            Q = np.zeros(system.n)
            for element in others:
                Q[element.indices] += element.evaluate(0.0, qm, qdm, system.parameter_values)
            tau += twin.velocity_map(q).T @ Q
        driven = system.with_parameters(**torques) if torques else system
        started = time.perf_counter()
        try:
            motion = driven.motion(0.0, qm, qdm)
        except SolveError as err:  # a force on a direction no mass resists: no motion at all
            motion = err
        seconds.append(time.perf_counter() - started)
        with np.errstate(all="ignore"):
            reference = twin.accelerations(q, v, tau)
        if isinstance(motion, SolveError) or not motion.unique or not np.all(np.isfinite(reference)):
            notes.append(_why(motion, reference, system))
            continue
        if twin.loops:  # first: the twin's data still holds this sample's lambda_c
            error, free = loop_reaction_error(driven, twin, (qm, qdm), motion)
            worst_loop, loop_free = float(np.fmax(worst_loop, error)), max(loop_free, free)
        error = np.abs(twin.to_pinocchio(qm, qdm, motion.qdd)[2] - reference).max() if reference.size else 0.0
        scale = np.abs(reference).max() if reference.size else 0.0
        worst_abs = max(worst_abs, error)
        worst_rel = max(worst_rel, error / scale if scale > 0 else error)
        worst_joint = max(worst_joint, joint_space_error(driven, twin, (q, v, reference), (qm, qdm), motion))
        if not np.isnan(worst_reaction):
            worst_reaction = max(worst_reaction, reaction_error(driven, twin, (q, v, reference), (qm, qdm), motion))
    links = len(system.parts)
    note = notes[0] if notes else ""
    joint_ok = worst_joint <= tolerance and not worst_reaction > tolerance and not worst_loop > tolerance
    return Validation(label or system.name, base, links, twin.model.nv, samples, float(worst_abs), float(worst_rel),
                      bool(not notes and worst_rel <= tolerance and joint_ok), tolerance, round(build_s, 3),
                      round(1e3 * float(np.mean(seconds)), 3) if seconds else 0.0, note, float(worst_joint),
                      float(worst_reaction), float(worst_loop), int(loop_free))


def joint_space_error(system, twin, pinocchio_state, state, motion):
    """The largest error of ``system.joint_values`` against Pinocchio's (q, v, v̇) of
    the twin's joints (module docstring)."""
    q, v, a = pinocchio_state
    values = system.joint_values(0.0, *state, motion.qdd)
    scale = 1 + max(np.abs(v).max(initial=0), np.abs(a).max(initial=0))
    worst = 0.0
    for c in twin.coordinates:
        if c.name not in values:  # a body no joint reaches: Pinocchio's free-flyer only
            continue
        ours, window = values[c.name], slice(c.idx_v, c.idx_v + c.nv)
        worst = max(worst, _position_error(c, c.sign * ours.position, q[c.idx_q:c.idx_q + c.nq]),
                    np.abs(c.sign * ours.rate - v[window]).max() / scale,
                    np.abs(c.sign * ours.acceleration - a[window]).max() / scale)
    return worst


def _position_error(coordinate, ours, theirs):
    """|Δ position|: angles modulo 2π (a continuous joint's q is (cos, sin)), a free-flyer's
    quaternion (Pinocchio's x, y, z, w) up to its sign."""
    if coordinate.kind == "continuous":
        theirs = np.array([np.arctan2(theirs[1], theirs[0])])
    if coordinate.kind == "free":
        theirs = np.r_[theirs[:3], theirs[6], theirs[3:6]]
        ours = np.r_[ours[:3], np.sign(ours[3:] @ theirs[3:]) * ours[3:]]
        return np.abs(ours - theirs).max()
    return np.abs((ours - theirs + np.pi) % (2 * np.pi) - np.pi).max()


def reaction_error(system, twin, pinocchio_state, state, motion):
    """The largest error of the joints' ``system.reactions`` against ``data.f`` of
    Pinocchio's ``rnea`` at the same (q, v, v̇), relative to its largest entry."""
    q, v, a = pinocchio_state
    pin.rnea(twin.model, twin.data, q, v, a)
    reactions = system.reactions(0.0, *state, motion)
    joints = [c for c in twin.coordinates if c.kind != "free" and c.sign == 1 and c.name in reactions]
    if not joints:
        return 0.0
    scale = max(np.abs(twin.data.f[c.joint_id].vector).max() for c in joints) or 1.0
    return max(max(np.abs(reactions[c.name].force - twin.data.f[c.joint_id].linear).max(),
                   np.abs(reactions[c.name].torque - twin.data.f[c.joint_id].angular).max()) for c in joints) / scale


def loop_reaction_error(system, twin, state, motion):
    """(error, free) of the loop joints' ``system.reactions`` against the wrenches of
    Pinocchio's ``data.lambda_c`` from the twin's last ``constraintDynamics``, on their
    determined components (module docstring): the largest error relative to the largest
    determined entry of Pinocchio's wrenches, and the most undetermined components of
    one joint. Left out: a loop whose child is the world, and one that carries its own
    actuation or spring (mbsynth's reaction includes them, lambda_c does not); NaN when
    no loop is left."""
    maps = twin.loop_wrench_maps()
    jacobian = pin.getConstraintsJacobian(twin.model, twin.data, twin.constraints, twin.constraint_data)
    stresses = self_stresses(jacobian)
    reactions = system.reactions(0.0, *state, motion)
    errors, scale, free = [], 0.0, 0
    own = {e.joint for e in system.forces}
    for loop in twin.loops:
        if loop.name not in maps or loop.name in own:
            continue
        W = maps[loop.name]
        P = determined_projector(W, stresses[loop.rows])
        ours = np.r_[reactions[loop.name].force, reactions[loop.name].torque]
        theirs = W @ twin.data.lambda_c[loop.rows]
        errors.append(np.abs(P @ (ours - theirs)).max())
        scale = max(scale, np.abs(P @ theirs).max())
        free = max(free, 6 - int(round(np.trace(P))))
    return (max(errors) / (scale or 1.0) if errors else float("nan")), free


def self_stresses(jacobian):
    """Orthonormal columns spanning the λ with Jᵀλ = 0: the constraint forces that balance
    among themselves (the left null space of Pinocchio's constraint Jacobian J)."""
    U, s, _ = np.linalg.svd(jacobian, full_matrices=True)
    rank = int(np.sum(s > SELF_STRESS_RTOL * s[0])) if s.size and s[0] > 0 else 0
    return U[:, rank:]


def determined_projector(W, stresses):
    """The orthogonal projector onto the wrench components that no self-stress changes:
    I − B Bᵀ, B an orthonormal basis of the wrenches W N (N: ``stresses`` restricted to
    the loop's rows), directions below SELF_STRESS_RTOL · ‖W‖ dropped (a revolute loop's two
    points trading force along its axis change no wrench)."""
    U, s, _ = np.linalg.svd(W @ stresses, full_matrices=True)
    basis = U[:, :int(np.sum(s > SELF_STRESS_RTOL * np.linalg.norm(W, 2)))]
    return np.eye(6) - basis @ basis.T


def sample_pinocchio_state(twin, rng):
    """A random Pinocchio (q, v) within the joint limits (module docstring)."""
    q = np.zeros(twin.model.nq)
    for c in twin.coordinates:
        lower, upper = c.limits if c.limits is not None else (None, None)
        if c.kind == "free":
            x, y, z, w = _unit(rng.normal(size=4))
            q[c.idx_q:c.idx_q + 7] = [*rng.uniform(-1, 1, 3), x, y, z, w]
        elif c.kind == "continuous":
            angle = rng.uniform(-np.pi, np.pi)
            q[c.idx_q:c.idx_q + 2] = np.cos(angle), np.sin(angle)
        else:
            default = np.pi if c.kind == "revolute" else 0.5
            finite = lower is not None and np.all(np.abs([lower, upper]) < 1e10)
            q[c.idx_q] = rng.uniform(*(lower[0], upper[0]) if finite else (-default, default))
    return q, rng.normal(size=twin.model.nv)


def _consistent_sample(system, twin, rng):
    """(q, v) for Pinocchio and the same state (q, q̇) for mbsynth; with loops, the drawn
    state projected onto the constraints. A draw is replaced when the loops cannot close
    from it, or when the projection (in maximal coordinates) lands on the spurious branch
    of a revolute joint's equations (z_B = −z_A), which no joint angle reaches."""
    for _ in range(MAX_TRIES):
        q, v = sample_pinocchio_state(twin, rng)
        qm, qdm = twin.to_maximal(q, v)
        if not twin.constraints:
            return q, v, qm, qdm
        try:
            qm, qdm = project(system, 0.0, qm, qdm)
        except SolveError:
            continue
        q, v, _ = twin.to_pinocchio(qm, qdm)
        if _same_state(twin.to_maximal(q, v), (qm, qdm)):
            return q, v, qm, qdm
    raise SolveError(f"model '{system.name}': no random state of {MAX_TRIES} could be put on its constraints")


def _same_state(a, b, tol=SAME_STATE_TOL):
    """Whether two maximal states (q, q̇) of rigid bodies agree, a quaternion's sign aside."""
    (qa, qda), (qb, qdb) = (np.reshape(x, (-1, 7)) for x in a), (np.reshape(x, (-1, 7)) for x in b)
    sign = np.sign(np.sum(qa[:, 3:] * qb[:, 3:], axis=1))[:, None]
    flip = np.hstack([np.ones((len(qa), 3)), np.repeat(sign, 4, axis=1)])
    return np.abs(qa - flip * qb).max() < tol and np.abs(qda - flip * qdb).max() < tol * (1 + np.abs(qdb).max())


def _torque(rng, effort):
    return rng.uniform(-effort, effort) if effort is not None and np.isfinite(effort) and effort > 0 else rng.normal()


def _unit(x):
    return x / np.linalg.norm(x)


def _why(motion, reference, system):
    """Why a sample could not be compared: which side has no (unique) answer."""
    parts = []
    if not np.all(np.isfinite(reference)):
        parts.append("Pinocchio returns NaN or inf")
    if isinstance(motion, SolveError):
        parts.append(f"mbsynth: no motion exists ({motion})")
    elif not motion.unique:
        worst = np.abs(motion.nullspace).max(axis=1)
        moving = [c for c, x in zip(system.coordinates, worst) if x > NULLSPACE_SHOWN_TOL]
        parts.append(f"mbsynth: the motion is not unique ({motion.nullspace.shape[1]} indeterminate "
                     f"direction(s) in {', '.join(moving[:6])}{' ...' if len(moving) > 6 else ''})")
    return "; ".join(parts)


def robot_table():
    """[(name, URDF path, links, movable joints, whether Pinocchio loads it)] of the robots
    example-robot-data ships (robots.robot_files)."""
    rows = []
    for name, path in robot_files().items():
        with _native_stderr_silenced():  # urdfdom prints its own complaint before Pinocchio raises
            try:
                pin.buildModelFromUrdf(path)
                loads = True
            except ValueError:
                loads = False
        try:
            d = describe(path)
            rows.append((name, path, len(d.links), sum(j.kind != "fixed" for j in d.joints), loads))
        except ModelError:  # mbsynth refuses the file (validate_robot says why); Pinocchio may not
            root = ET.parse(path).getroot()
            movable = sum(j.get("type") not in ("fixed", None) for j in root.findall("joint"))
            rows.append((name, path, len(root.findall("link")), movable, loads))
    return rows


@contextlib.contextmanager
def _native_stderr_silenced():
    """File descriptor 2 sent to /dev/null for the duration (C++ libraries write there directly)."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
