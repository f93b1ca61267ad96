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
"""

import contextlib
import os
import sys
import time
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass

import numpy as np
import pinocchio as pin

from .errors import ModelError, SolveError
from .projection import project
from .robots import describe, fix_base, from_robot, robot_files
from .twin import Twin

TOLERANCE = 1e-9  # largest relative error that passes
MAX_TRIES = 20  # samples drawn to find one a loop can close at


@dataclass(frozen=True)
class Validation:
    """The outcome of one comparison: ``robot`` (or model) with a ``base`` (fixed,
    floating, or "model" for a model file), its ``links`` (bodies) and ``nv`` (Pinocchio's
    velocity count, before loops close); the largest errors over ``samples`` states; ``passed`` (below ``tolerance``);
    ``build_s`` (seconds to build the System), ``motion_ms`` (mean mbsynth evaluation);
    ``note`` says why a comparison was impossible (no unique motion, NaN from Pinocchio)."""

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

    def to_dict(self):
        return asdict(self)


def validate_robot(name_or_urdf, samples=20, seed=0, bases=("fixed", "floating"), tolerance=TOLERANCE):
    """[Validation] of a robot for each base: built once floating, then welded for fixed."""
    started = time.perf_counter()
    floating = from_robot(name_or_urdf, floating=True)
    build_s = time.perf_counter() - started
    results = []
    for base in bases:
        system = floating if base == "floating" else fix_base(floating)
        results.append(validate_system(system, samples, seed, tolerance, base=base, build_s=build_s,
                                       label=str(name_or_urdf)))
    return results


def validate_system(system, samples=20, seed=0, tolerance=TOLERANCE, base="model", build_s=0.0, label=None):
    """The Validation of ``system`` (named ``label``, by default its own name) against its
    Pinocchio twin (ModelError when it has none)."""
    twin = Twin(system)
    rng = np.random.default_rng(seed)
    efforts = {robot.torques[j.name]: j.effort for robot in system.robots for j in robot.description.joints
               if j.name in robot.torques}
    others = [e for e in system.forces if e.name not in twin.torque_elements]
    worst_abs = worst_rel = 0.0
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
        error = np.abs(twin.to_pinocchio(qm, qdm, motion.qdd)[2] - reference).max() if reference.size else 0.0
        scale = np.abs(reference).max() if reference.size else 0.0
        worst_abs = max(worst_abs, error)
        worst_rel = max(worst_rel, error / scale if scale > 0 else error)
    links = len(system.subsystems)
    note = notes[0] if notes else ""
    return Validation(label or system.name, base, links, twin.model.nv, samples, float(worst_abs), float(worst_rel),
                      bool(not notes and worst_rel <= tolerance), tolerance, round(build_s, 3),
                      round(1e3 * float(np.mean(seconds)), 3) if seconds else 0.0, note)


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


def _same_state(a, b, tol=1e-8):
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
        moving = [c for c, x in zip(system.coordinates, worst) if x > 1e-6]
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
