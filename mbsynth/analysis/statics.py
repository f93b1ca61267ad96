"""Static equilibrium: a configuration where the model rests, q̈ = 0 at q̇ = 0 on its constraints.

The rest the model comes to from its start when its motion is damped away: the path of
the overdamped flow u' = a(u) in the independent coordinates u of the constraints'
tangent space (linearization.py), a = ü at rest. At rest A q̈ = b = 0 for scleronomic
rows, so q̈ = N a is a tangent vector (N the tangent basis), and a = M_t⁻¹ F_t (the
tangential force over the tangential mass): the flow is steepest descent of the potential
energy in the metric of the mass, so it ends at a minimum — the stable rest whose basin
holds the start — and never climbs to a maximum or a saddle (a Newton iteration on
a = 0 alone goes to whichever root its steps reach: the upright double pendulum from a
start near hanging).

The flow is followed by pseudo-transient continuation (implicit Euler steps whose size
grows as the acceleration falls, Kelley & Keyes 1998): (I/h − K) Δu = a with
K = ∂a/∂u (the linearization's stiffness block), h from 1/max|K| (at most a step of
STEP_LIMIT) and growing by ‖a_old‖/‖a_new‖ (at most GROWTH times a step), so its last
steps are Newton's (h → ∞), quadratic near the rest. A step moves q by N Δu, puts it back
on φ = 0 (projection.project_positions) and is taken only where the forces at rest do
non-negative work along it, ½ (F(q) + F(q'))·(q' − q) ≥ 0 with F = M q̈ (the trapezoidal
estimate of the potential's fall, exact for linear forces; it also serves forces with no
potential, such as a joint's constant torque); else h is quartered. Massless parts balance
through their rows (a ``closure: auto`` balance is one of them), so their equilibrium comes
with the rest.

Verdicts (``NoEquilibrium``): no rest after ``max_iterations`` steps (a model that keeps
falling), no step that the forces do work along, an equilibrium that is not isolated (a
free direction: rest as well after a move along it). Bad input (NaN, a start the
constraints cannot reach) is a SolveError.
"""

import numpy as np

from ..core.errors import NoEquilibrium, SolveError
from .linearization import finite_state, linearize, prescribed_motion
from .projection import project_positions
from ..core.tolerances import ACCELERATION_TOL, ISOLATED_RTOL

MAX_ITERATIONS = 200
HALVINGS = 30  # a step's h is quartered at most this often before the search gives up
STEP_LIMIT = 0.5  # largest change of a coordinate in one step, relative to max(1, max |q|) at the start
GROWTH = 10.0  # h grows at most this many times from one step to the next
LEAST_GROWTH = 2.0  # and at least this many (a step the work test refuses quarters it)
WORK_RTOL = 1e-12  # work below −WORK_RTOL · (|F·Δq| + |F'·Δq|) counts as negative (not rounding)


def equilibrium(system, q=None, t=0.0, tolerance=ACCELERATION_TOL, max_iterations=MAX_ITERATIONS):
    """The static equilibrium of ``system`` the model comes to from ``q`` (default: the
    initial positions) when its motion is damped away: the stable rest whose basin holds q,
    or q itself where it rests already (module docstring). An array in the model's
    coordinates. Raises NoEquilibrium when no rest is found from q, or when the rest found
    is not isolated (the coordinates along its free directions are named); SolveError for a
    q that is not finite or cannot be put on the constraints."""
    q = system.initial_state()[0] if q is None else np.array(q, dtype=float)
    zero = np.zeros(system.n)
    q, _ = finite_state(system, q, zero)
    limit = STEP_LIMIT * max(1.0, np.abs(q).max())
    moving = prescribed_motion(system, t, q, zero)
    if moving:
        raise NoEquilibrium(f"model '{system.name}': no static equilibrium at t = {t:g}: rows {moving} prescribe a "
                            "motion then (∂φ/∂t ≠ 0)", constraints=moving)
    q = project_positions(system, t, q)
    h, previous = None, None
    for _ in range(max_iterations):
        lin = linearize(system, t, q, zero, inputs=())
        k = lin.k
        if k == 0:
            return q
        a = np.linalg.lstsq(lin.basis, lin.qdd, rcond=None)[0]
        K = lin.A[k:, :k]
        if np.abs(lin.qdd).max() <= tolerance * (1.0 + np.abs(K).max()):
            _check_isolated(system, t, q, lin, K)
            return q
        if h is None:
            h = min(1.0 / max(np.abs(K).max(), np.finfo(float).tiny), limit / np.abs(lin.qdd).max())
        else:
            h *= min(GROWTH, max(LEAST_GROWTH, previous / np.linalg.norm(a)))
        previous = np.linalg.norm(a)
        q, h = _step(system, t, q, lin, a, K, h, limit)
    worst = int(np.argmax(np.abs(lin.qdd)))
    raise NoEquilibrium(f"model '{system.name}': no static equilibrium found from the given configuration: after "
                        f"{max_iterations} steps down the potential it still accelerates (largest q̈ "
                        f"{lin.qdd[worst]:.3g} along {system.coordinates[worst]}; it keeps moving where nothing "
                        "holds it)", coordinates=[system.coordinates[worst]])


def _step(system, t, q, lin, a, K, h, limit):
    """(q moved by the implicit Euler step (I/h − K) Δu = a of the largest h, from ``h``
    down by quarters, whose move is at most ``limit``, can be put back on the constraints
    and along which the forces at rest do non-negative work; that h)."""
    zero = np.zeros(system.n)
    force = _force(system, t, q, lin.qdd)
    for _ in range(HALVINGS):
        step = lin.basis @ np.linalg.lstsq(np.eye(lin.k) / h - K, a, rcond=None)[0]
        if np.abs(step).max() <= limit:
            try:
                moved = project_positions(system, t, q + step)
                qdd = system.motion(t, moved, zero).qdd
            except SolveError:
                moved = None
            if moved is not None and np.all(np.isfinite(qdd)):
                change = moved - q
                ends = (force @ change, _force(system, t, moved, qdd) @ change)
                if sum(ends) / 2 >= -WORK_RTOL * (abs(ends[0]) + abs(ends[1])):
                    return moved, h
        h /= 4
    worst = int(np.argmax(np.abs(lin.qdd)))
    raise NoEquilibrium(f"model '{system.name}': no static equilibrium found from the given configuration: no "
                        f"step down the potential is left (largest q̈ {lin.qdd[worst]:.3g} along "
                        f"{system.coordinates[worst]})", coordinates=[system.coordinates[worst]])


def _force(system, t, q, qdd):
    """F = M q̈ at rest: the generalized force whose tangential part moves the model (the
    constraints' forces do no work along the tangent space)."""
    return system.evaluate(t, q, np.zeros(system.n)).M @ qdd


def _check_isolated(system, t, q, lin, K):
    """NoEquilibrium when K is singular at the equilibrium: rest is possible along a direction."""
    _, s, Vt = np.linalg.svd(K)
    free = Vt[s <= ISOLATED_RTOL * max(s[0], np.finfo(float).tiny)] if s.size else Vt[:0]
    if len(free):
        moves = [lin.basis @ v for v in free]
        directions = [_described(system, t, q, dq) for dq in moves]
        coordinates = sorted({system.coordinates[i] for dq in moves
                              for i in np.flatnonzero(np.abs(dq) > SHOWN_RTOL * np.abs(dq).max())})
        raise NoEquilibrium(f"model '{system.name}': the equilibrium is not isolated: it rests as well after a move "
                            f"along {len(free)} free direction(s) {directions}", coordinates=coordinates)


SHOWN_RTOL = 1e-6  # a direction's component below this share of its largest is not shown


def _described(system, t, q, dq):
    """{name: component} of the direction dq, largest 1: the rates of the joints that have
    values (System.joint_values) and the coordinates of the parts no such joint holds."""
    entries = {}
    held = set()
    for name, joint in system.joint_kinematics().items():
        held.update(int(i) for i in joint.indices)
    for name, value in system.joint_values(t, q, dq).items():
        rates = np.atleast_1d(value.rate)
        entries.update({name if len(rates) == 1 else f"{name}[{i}]": x for i, x in enumerate(rates)})
    entries.update({c: x for i, (c, x) in enumerate(zip(system.coordinates, dq)) if i not in held})
    top = max(entries.values(), key=abs)
    return {c: round(float(x / top), 6) for c, x in entries.items() if abs(x) > SHOWN_RTOL * abs(top)}
