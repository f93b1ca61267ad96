"""Steady motions: states along which only cyclic coordinates move, at constant rates (a
bicycle rolling upright, a disk rolling in a circle, a top spinning about the vertical),
and the check that a state is one (linearization.py: about a steady motion the
linearization's eigenvalues are the motion's stability exponents).

A coordinate is cyclic when the dynamics depends on it only through other cyclic ones
(``Linearization.cyclic``: a wheel's spin angle of a body turned by angles whose spin is the
last, model/parts/euler_body.py; the position on the ground). A state (q, q̇) is steady
when the independent speeds do not change (q̈ = 0 along them) and no independent
coordinate but the cyclic ones moves.
"""

import numpy as np
import scipy.linalg
import scipy.optimize

from ..core.errors import NoEquilibrium, SolveError
from ..model.data import model_of, workspace
from ..core.tolerances import ACCELERATION_TOL, ON_MANIFOLD_RTOL, RANK_RTOL, STEADY_FIT_TOL
from .linearization import finite_state, linearize
from .projection import project_positions

QUATERNION = ("qw", "qx", "qy", "qz")  # the coordinates of a part turned by a unit quaternion (Part.groups)


def steady_motion(model, rates, q=None, t=0.0, solve=(), tolerance=ACCELERATION_TOL):
    """(q, q̇) of a steady motion of ``model`` (a System, at its parameter values, or a Data,
    at its own): ``q`` (default its initial positions) put on
    its position rows, q̇ with the given ``rates`` ({coordinate: rate}, e.g. a wheel's
    spin rate v/R for a forward speed v), every velocity row met, and the rest of q̇ the
    one of least kinetic energy (no lean or steer rate where nothing asks for one).
    ``solve``: names of coordinates or of ``<coordinate>_dot`` rates (one of ``rates``)
    adjusted so that the motion is steady (a disk's spin rate for its lean and turning
    rate). Raises NoEquilibrium when the state found is not steady (``check_steady``)."""
    data = workspace(model)
    system = data.model
    q0, _ = data.initial_state()
    q = project_positions(data, t, q0 if q is None else np.array(q, dtype=float))
    index = {c: i for i, c in enumerate(system.coordinates)}
    unknown = [c for c in list(rates) + [s.removesuffix("_dot") for s in solve] if c not in index]
    if unknown:
        raise SolveError(f"model '{system.name}': unknown coordinate(s) {unknown}", coordinates=unknown)
    given = {index[c]: float(x) for c, x in rates.items()}
    if solve:
        q, given = _solved(data, t, q, given, solve, index)
    qd = _least_energy_velocities(data, t, q, given)
    check_steady(system, linearize(data, t, q, qd), tolerance)
    return finite_state(system, q, qd)


def _least_energy_velocities(data, t, q, given):
    """q̇ at q with q̇[j] = given[j], every velocity row met (A q̇ + ψ(q, 0) = 0 over the rows
    with a velocity form), and the least ½ q̇ᵀ M q̇ over the freedom left."""
    n = data.model.n
    arrays = data.constraint_arrays(t, q, np.zeros(n), sparse=False)
    rows = np.isfinite(arrays.psi)
    fix = np.zeros((len(given), n))
    fix[np.arange(len(given)), list(given)] = 1.0
    W = np.vstack([arrays.A[rows], fix])
    right = np.concatenate([-arrays.psi[rows], list(given.values())])
    particular = np.linalg.lstsq(W, right, rcond=None)[0]
    _check_rates(data.model, arrays, rows, given, W, right, particular)
    _, s, Vt = np.linalg.svd(W)
    free = Vt[int(np.sum(s > RANK_RTOL * s[0])):].T if s.size else np.eye(n)
    M = data.evaluate(t, q, particular).M
    y = np.linalg.lstsq(free.T @ M @ free, -free.T @ M @ particular, rcond=None)[0] if free.size else []
    return particular + free @ y if free.size else particular


def _check_rates(system, arrays, rows, given, W, right, x):
    """SolveError where the ``given`` rates contradict the velocity rows (W x = right has no
    solution: x, its least-squares one, misses a row by more than ON_MANIFOLD_RTOL of the
    row's norm times |x|), naming those rows and, as the model has them, what the rates may
    be: those of independent coordinates (position rows alone) or of independent speeds
    (with non-holonomic rows, such as rolling without slipping), examples picked by
    coordinate partitioning."""
    scale = np.linalg.norm(W, axis=1) * np.linalg.norm(x) + np.abs(right)  # a row's size at x, rounding's scale
    missed = np.abs(W @ x - right) > ON_MANIFOLD_RTOL * scale
    names = [name for name, row in zip([c for c, kept in zip(system.constraint_names, rows) if kept], missed) if row]
    if not names:
        return
    A = W[:len(W) - len(given)]
    _, s, Vt = np.linalg.svd(A)
    free = Vt[int(np.sum(s > RANK_RTOL * s[0])):] if s.size else np.eye(system.n)
    independent = [system.coordinates[i] for i in sorted(scipy.linalg.qr(free, pivoting=True)[2][:len(free)])]
    rates = {system.coordinates[i]: v for i, v in given.items()}
    nonholonomic = [name for name, phi, psi in zip(system.constraint_names, arrays.phi, arrays.psi)
                    if np.isnan(phi) and np.isfinite(psi)]
    if nonholonomic:
        ties = (f"the position rows and the velocity rows {nonholonomic} (rolling without slipping, a knife edge) "
                f"leave {len(independent)} independent speed(s), e.g. the rates of {independent}")
    else:
        ties = (f"the position rows fix every rate from {len(independent)} independent coordinate(s), e.g. "
                f"{independent}")
    raise SolveError(f"model '{system.name}': the rates {rates} contradict the rows {names}: {ties}; give rates "
                     "the rows allow (those of independent ones; the others follow)", constraints=names)


def _solved(data, t, q, given, solve, index):
    """(q, given) with the ``solve`` entries adjusted (least squares) so that q̈ = 0 along the
    speeds of the linearization at the first guess."""
    start = linearize(data, t, q, _least_energy_velocities(data, t, q, given))
    speeds = [index[c.removesuffix("_dot")] for c in start.state_names[start.k:]]

    def state(x):
        moved_q, moved = q.copy(), dict(given)
        for name, value in zip(solve, x):
            if name.endswith("_dot"):
                moved[index[name.removesuffix("_dot")]] = value
            else:
                moved_q[index[name]] = value
        moved_q = project_positions(data, t, moved_q)
        return moved_q, moved

    def residual(x):
        moved_q, moved = state(x)
        return data.motion(t, moved_q, _least_energy_velocities(data, t, moved_q, moved)).qdd[speeds]

    guess = [given[index[c.removesuffix("_dot")]] if c.endswith("_dot") else q[index[c]] for c in solve]
    fit = scipy.optimize.least_squares(residual, guess, xtol=STEADY_FIT_TOL, ftol=STEADY_FIT_TOL,
                                      gtol=STEADY_FIT_TOL)
    return state(fit.x)


def check_steady(model, lin, tolerance=ACCELERATION_TOL):
    """NoEquilibrium unless the state of ``lin`` (a linearization of ``model``, a System or
    a Data) is a steady motion: the speeds do not change (q̈ along them within ``tolerance``
    of the stiffness scale) and no independent coordinate moves but the cyclic ones."""
    system = model_of(model)
    k = lin.k
    size = 1 + np.abs(lin.A[k:, :k]).max(initial=0.0)
    index = {c: i for i, c in enumerate(system.coordinates)}
    speeds = [name.removesuffix("_dot") for name in lin.state_names[k:]]
    moving = [c for c in lin.state_names[:k] if c not in lin.cyclic
              and abs(lin.qd[index[c]]) > tolerance * (1 + np.abs(lin.qd).max())]
    changing = [c for c in speeds if abs(lin.qdd[index[c]]) > tolerance * size]
    if moving or changing:
        raise NoEquilibrium(f"model '{system.name}' does not move steadily here: "
                            + "; ".join(([f"{moving} move but the dynamics depends on them"] if moving else [])
                                        + ([f"the rates of {changing} change"] if changing else []))
                            + " (a steady motion moves only cyclic coordinates, at constant speeds"
                            + _quaternion_hint(system) + ")", coordinates=moving + changing)


def _quaternion_hint(system):
    """For a model with parts turned by a quaternion, whose spin is no coordinate of its
    own: the advice to turn them by angles, the spin last."""
    turned = [part.name for part in system.parts if QUATERNION in part.groups]
    if not turned:
        return ""
    one = len(turned) == 1
    return (f"; {', '.join(turned[:4])}{', ...' if len(turned) > 4 else ''} {'is' if one else 'are'} turned by a "
            f"quaternion, whose spin is no cyclic coordinate: give {'it' if one else 'them'} rotation: zxy, the "
            "spin angle last")
