"""Static equilibrium: a configuration where the model rests, q̈ = 0 at q̇ = 0 on its constraints.

Found in the tangent space of the constraint manifold φ(q) = 0: at q the linearization
(linearization.py) gives the tangent basis N (n × k, independent coordinates u), the
tangential acceleration a (q̈ = N a: at rest A q̈ = b = 0 for scleronomic rows) and
K = ∂a/∂u. With the tangential mass M_t = Nᵀ M N the tangential force is F_t = M_t a,
and each step solves a trust-region problem in the norm of the mass, ‖p‖²_M = pᵀ M_t p ≤ Δ²,
moves q by N p (shortened to STEP_LIMIT in a coordinate) and puts it back on φ = 0
(projection.project_positions, the retraction; it holds the flexible bodies' elastic
coordinates where the others can close the constraints: its correction, O(|p|²), would
otherwise land partly on them, and at their stiffness its strain energy, which the
quadratic model does not see, outweighs the step's whole fall). A step is taken where its
actual decrease of the merit Ψ is at least ETA of the decrease the quadratic model
predicts; Δ shrinks by SHRINK after a refused step and grows by EXPAND after a good one
that reached it, so near the answer the steps are Newton's (quadratic).

Two contracts:

- ``nearest=False`` (default): a stable rest, a minimum of the potential Ψ on the manifold
  that steps down from q reach. Ψ is the potential of the forces at rest: the model's V
  (System.energy) where every force derives from it (``System.working_forces`` empty), else the work
  −½ (F(q) + F(q'))·(q' − q) of F = M q̈ (trapezoidal, exact for linear forces; it serves a
  joint's torque or a PD law, which V does not hold), and the same trapezoid where V's change
  is below its rounding (V_ROUNDING). The model of Ψ is −F_tᵀ p + ½ pᵀ H p with H the
  symmetric part of −M_t K, its curvatures taken by magnitude (``_Model``). Minimizing Ψ on
  the manifold ends at a minimum: where the steps come to a rest at which H has a negative
  curvature (a maximum or saddle), a step along that curvature goes on down; so the rest
  found from anywhere, near the upright double pendulum too, is a stable one; a start that
  rests at a maximum or saddle (the upright pendulum exactly) is left the same way, along
  its most negative curvature (the eigenvector's sign as LAPACK gives it: the same in every
  run).
- ``nearest=True``: the equilibrium, stable or not, a Newton iteration on the force balance
  a(u) = 0 reaches from q: Ψ = ½ q̈ᵀ M q̈ (= ½ aᵀ M_t a), modelled as ½ ‖a + K p‖²_M
  (Levenberg–Marquardt). From a start near an equilibrium, that one (the inverted pendulum
  near the top); from far away, whichever equilibrium the iteration reaches, or a verdict.

Massless parts balance through their rows (a ``balances: auto`` balance is one of them), so
their equilibrium comes with the rest.

Verdicts (``NoEquilibrium``): no rest after ``max_iterations`` steps (a model that keeps
falling), no step left that lowers Ψ, an equilibrium that is not isolated (a free
direction: rest as well after a move along it). Bad input (NaN, a start the constraints
cannot reach) and non-holonomic rows are a SolveError.
"""

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from ..core.errors import NoEquilibrium, SolveError
from ..model.data import workspace
from .linearization import finite_state, linearize, prescribed_motion
from .projection import project_positions
from ..core.tolerances import ACCELERATION_TOL, FREE_SHOWN_RTOL, ISOLATED_RTOL, TRUST_CURVATURE_RTOL, V_ROUNDING

MAX_ITERATIONS = 200
HALVINGS = 30  # refused steps in a row (each shrinks Δ) before the search gives up
STEP_LIMIT = 0.5  # largest change of a coordinate in one step, relative to max(1, max |q|) at the start
ETA = 0.01  # a step is taken where Ψ falls by at least this share of the model's prediction
SHRINK = 0.25  # Δ after a refused step or a poor one (actual < GOOD × predicted), times the step's length
EXPAND = 3.0  # Δ after a good step that reached the boundary, times Δ
GOOD = 0.75


def equilibrium(model, q=None, t=0.0, tolerance=ACCELERATION_TOL, max_iterations=MAX_ITERATIONS, nearest=False):
    """The static equilibrium of ``model`` (a System, at its parameter values, or a Data, at
    its own) found from ``q`` (default: the initial positions),
    an array in the model's coordinates: by default a stable rest, a minimum of the potential
    on the constraints that steps down from q reach (in a model with one, the rest; with
    several, mostly the one the damped motion from q comes to, not always), or q itself
    where it rests stably already; with ``nearest=True`` the equilibrium, stable or not, that
    Newton's iteration on the force balance reaches from q (the one near q where q starts
    near one: an inverted pendulum near the top). Module docstring. Raises NoEquilibrium
    when no rest is found from q, or when the rest found is not isolated (the coordinates
    along its free directions are named); SolveError for a q that is not finite or cannot
    be put on the constraints."""
    data = workspace(model)
    system = data.model
    q = data.initial_state()[0] if q is None else np.array(q, dtype=float)
    zero = np.zeros(system.n)
    q, _ = finite_state(system, q, zero)
    limit = STEP_LIMIT * max(1.0, np.abs(q).max())
    moving = prescribed_motion(data, t, q, zero)
    if moving:
        raise NoEquilibrium(f"model '{system.name}': no static equilibrium at t = {t:g}: rows {moving} prescribe a "
                            "motion then (∂φ/∂t ≠ 0)", constraints=moving)
    merit = _Merit(data, t, nearest)
    elastic = _elastic_coordinates(system)
    q = project_positions(data, t, q)
    radius = None
    for iteration in range(max_iterations):
        lin = linearize(data, t, q, zero, inputs=())
        k = lin.k
        if k == 0:
            return q
        if lin.A.shape[0] != 2 * k:
            raise SolveError(f"model '{system.name}': its non-holonomic rows leave {lin.A.shape[0] - k} of {k} "
                             "speeds free: mb.equilibrium does not search models with rows that restrict "
                             "velocities only (its steps move along every direction the holonomic rows allow)")
        K = lin.A[k:, :k]
        resolution = tolerance * (1.0 + np.abs(K).max())
        quadratic = None
        if np.abs(lin.qdd).max() <= resolution:
            quadratic = None if nearest else _Model(data, t, q, lin, K, nearest, resolution)
            if quadratic is None or not quadratic.unstable:
                _check_isolated(data, t, q, lin, K)
                return q
            quadratic.downhill()  # a maximum or saddle (the start, or where the steps came to): on down from it
        quadratic = quadratic or _Model(data, t, q, lin, K, nearest, resolution)
        if radius is None:
            radius = quadratic.first_radius(lin.basis, limit)
        q, radius = _step(data, t, q, lin, quadratic, merit, radius, limit, elastic)
    worst = int(np.argmax(np.abs(lin.qdd)))
    raise NoEquilibrium(f"model '{system.name}': no static equilibrium found from the given configuration: after "
                        f"{max_iterations} steps down the potential it still accelerates (largest q̈ "
                        f"{lin.qdd[worst]:.3g} along {system.coordinates[worst]}; it keeps moving where nothing "
                        "holds it)", coordinates=[system.coordinates[worst]])


class _Model:
    """The quadratic model of Ψ at q in the coordinates y of the trust-region problem:
    predicted change cᵀy + ½ Σ d_i y_i², ‖y‖ = ‖p‖_M, p = P y (module docstring). With
    M_t = L Lᵀ and z = Lᵀ p: the potential's model has gradient −Lᵀ a and Hessian the
    symmetric part of −Lᵀ K L⁻ᵀ (its eigenvectors are P's columns, before L⁻ᵀ); the
    residual's is ½ ‖Lᵀ a + J z‖² with J = Lᵀ K L⁻ᵀ (its right singular vectors). The
    potential's curvatures enter as their magnitudes |d| (Dauphin et al. 2014: away from rest
    −M_t K is not Ψ's Hessian, which has the further term (∂M_t/∂u) a, and a negative value
    from it sends the whole step along a light coordinate, a body's spin); ``downhill`` keeps
    their signs where that term vanishes, at a rest. Components of c whose share of q̈ is
    below the stopping rule's ``resolution`` (a tenth of it, all together) are rounding, and
    zero: along a free direction (zero curvature) they would take the whole trust region."""

    def __init__(self, data, t, q, lin, K, nearest, resolution):
        N = lin.basis
        a = np.linalg.lstsq(N, lin.qdd, rcond=None)[0]
        M = data.evaluate(t, q, np.zeros(data.model.n)).M
        mass = N.T @ (M @ N)
        L = np.linalg.cholesky((mass + mass.T) / 2)
        J = L.T @ np.linalg.solve(L, K.T).T  # Lᵀ K L⁻ᵀ
        if nearest:
            U, s, Wt = np.linalg.svd(J)
            parts, V, W = U.T @ (L.T @ a), U, Wt.T  # a = L⁻ᵀ V parts
            self.c, self.d = s * parts, s ** 2
        else:
            self.curvature, W = np.linalg.eigh(-(J + J.T) / 2)
            parts, V = W.T @ (-(L.T @ a)), -W  # a = L⁻ᵀ V parts
            self.c, self.d = parts, np.abs(self.curvature)
        shares = np.abs(parts) * np.abs(N @ np.linalg.solve(L.T, V)).max(axis=0)  # of q̈ = N a
        self.c = np.where(shares * len(shares) <= resolution / 10, 0.0, self.c)  # together ≤ resolution/10
        self.P = np.linalg.solve(L.T, W)
        self.mass = mass
        self.along_force = a  # the direction of the damped motion (steepest descent of Ψ in the mass's metric)

    @property
    def unstable(self):
        """Whether the potential's curvature is negative along a direction (beyond ISOLATED_RTOL
        of the largest): at a rest, a maximum or saddle."""
        return self.curvature.min() < -ISOLATED_RTOL * np.abs(self.curvature).max()

    def downhill(self):
        """The model of a rest's neighbourhood with its negative curvature kept: its steps go
        down along it (the trust region's hard case)."""
        self.c, self.d = np.zeros_like(self.c), self.curvature

    def first_radius(self, basis, limit):
        """The first step's Δ: that of a move by ``limit`` in the largest coordinate along the
        force or, at a rest (a maximum or saddle), along the most negative curvature."""
        p = self.along_force if np.any(self.along_force) else self.P[:, np.argmin(self.d)]
        return self.size(p) * limit / np.abs(basis @ p).max()

    def size(self, p):
        """‖p‖_M."""
        return float(np.sqrt(p @ self.mass @ p))


def _trust_region(c, d, radius):
    """y minimizing cᵀy + ½ Σ d_i y_i² with ‖y‖ ≤ Δ (Moré & Sorensen 1983, in the model's
    eigenbasis): y = −c/(d + λ) with λ ≥ max(0, −min d), λ = 0 where that step lies inside
    (Newton's, least-norm along the curvatures that are zero), else ‖y‖ = Δ; in the hard
    case (negative curvature that c has no share along, as at a maximum) y fills up to Δ
    along it. Curvatures below TRUST_CURVATURE_RTOL of the largest are zero."""
    d = np.where(np.abs(d) <= TRUST_CURVATURE_RTOL * max(np.abs(d).max(), np.finfo(float).tiny), 0.0, d)
    low = max(0.0, -d.min())
    lowest = d + low == 0

    def y(shift):  # −c/(d + λ); along the lowest curvature at λ = −min d: 0 where c has no share, else ∞
        at_low = lowest & (shift <= low)
        return np.where(at_low, np.where(c != 0, np.inf, 0.0), -c / np.where(at_low, 1.0, d + shift))

    inner = y(low)
    if np.linalg.norm(inner) <= radius:
        if low > 0:  # the hard case
            inner[np.flatnonzero(lowest)[0]] = np.sqrt(radius ** 2 - inner @ inner)
        return inner
    high = low + 2 * np.linalg.norm(c) / radius  # there ‖y‖ ≤ Δ/2
    secular = lambda shift: 1 / np.linalg.norm(y(shift)) - 1 / radius  # from −1/Δ (or less) at low up to ≥ 0
    shift = scipy.optimize.brentq(secular, low, high, xtol=np.finfo(float).tiny, maxiter=500)
    return y(max(shift, np.nextafter(low, np.inf)))


def _step(data, t, q, lin, model, merit, radius, limit, elastic):
    """(q moved by the trust-region step p of the largest radius, from ``radius`` down
    (shortened where its move N p exceeds ``limit`` in a coordinate), that can be put back on
    the constraints (``_retract``, holding ``elastic``) and along which Ψ falls by at least ETA
    of the predicted fall; the radius for the next step)."""
    system = data.model
    here = merit.at(q, lin.qdd)
    for _ in range(HALVINGS):
        y = _trust_region(model.c, model.d, radius)
        move = lin.basis @ (model.P @ y)
        if np.abs(move).max() > limit:  # shortened to the limit: still down the model, if less far
            shorter = limit / np.abs(move).max()
            y, move = y * shorter, move * shorter
        predicted = -(model.c @ y + 0.5 * model.d @ y ** 2)
        length = np.linalg.norm(y)
        if not predicted > 0:
            break
        try:
            moved = _retract(data, t, q + move, elastic)
            there = merit.at(moved, data.motion(t, moved, np.zeros(system.n)).qdd)
        except SolveError:
            there = None
        if there is not None and np.all(np.isfinite(there.qdd)):
            ratio = merit.fall(here, there) / predicted
            if ratio >= ETA:
                if ratio < GOOD:
                    radius = SHRINK * length
                elif length >= 0.99 * radius:
                    radius *= EXPAND
                return moved, radius
        radius = SHRINK * length
    worst = int(np.argmax(np.abs(lin.qdd)))
    raise NoEquilibrium(f"model '{system.name}': no static equilibrium found from the given configuration: no "
                        f"step down the {merit.name} is left (largest q̈ {lin.qdd[worst]:.3g} along "
                        f"{system.coordinates[worst]})", coordinates=[system.coordinates[worst]])


def _elastic_coordinates(system):
    """Indices of the flexible bodies' elastic coordinates (``FlexibleBody.elastic``)."""
    found, start = [], 0
    for part in system.parts:
        if part.part_type.elastic:
            found += range(start + part.elastic.start, start + part.elastic.stop)
        start += len(part.coordinates)
    return found


def _retract(data, t, q, elastic):
    """q put back on the constraints, the coordinates ``elastic`` held where the others can
    close them (else all move)."""
    if elastic:
        try:
            return project_positions(data, t, q, fixed=elastic)
        except SolveError:
            pass
    return project_positions(data, t, q)


class _Merit:
    """Ψ of the module docstring at a configuration on the constraints, and its fall along a
    step: V, the forces' work or ½ q̈ᵀ M q̈."""

    def __init__(self, data, t, nearest):
        self.data, self.t, self.nearest = data, t, nearest
        self.potential = not nearest and not data.model.working_forces(data.parameter_values)
        self.name = "force balance's residual" if nearest else "potential"

    def at(self, q, qdd):
        """A _Point: q, q̈, F = M q̈ and V (where V is Ψ) there."""
        zero = np.zeros(self.data.model.n)
        force = self.data.evaluate(self.t, q, zero).M @ qdd
        V = self.data.energy(self.t, q, zero)[1] if self.potential else None
        return _Point(q, qdd, force, V)

    def fall(self, here, there):
        """Ψ(here) − Ψ(there)."""
        if self.nearest:
            return (here.force @ here.qdd - there.force @ there.qdd) / 2
        if self.potential and abs(here.V - there.V) > V_ROUNDING * max(abs(here.V), abs(there.V)):
            return here.V - there.V
        return (here.force + there.force) @ (there.q - here.q) / 2


@dataclass(frozen=True)
class _Point:
    """A configuration on the constraints with its q̈, F = M q̈ at rest and V (None where V is not Ψ)."""

    q: np.ndarray
    qdd: np.ndarray
    force: np.ndarray
    V: float


def _check_isolated(data, t, q, lin, K):
    """NoEquilibrium when K is singular at the equilibrium: rest is possible along a direction."""
    system = data.model
    _, s, Vt = np.linalg.svd(K)
    free = Vt[s <= ISOLATED_RTOL * max(s[0], np.finfo(float).tiny)] if s.size else Vt[:0]
    if len(free):
        moves = [lin.basis @ v for v in free]
        directions = [_described(data, t, q, dq) for dq in moves]
        coordinates = sorted({system.coordinates[i] for dq in moves
                              for i in np.flatnonzero(np.abs(dq) > FREE_SHOWN_RTOL * np.abs(dq).max())})
        raise NoEquilibrium(f"model '{system.name}': the equilibrium is not isolated: it rests as well after a move "
                            f"along {len(free)} free direction(s) {directions}", coordinates=coordinates)




def _described(data, t, q, dq):
    """{name: component} of the direction dq, largest 1: the rates of the joints that have
    values (Data.joint_values) and the coordinates of the parts no such joint holds."""
    system = data.model
    entries = {}
    held = set()
    for name, joint in system.joint_kinematics().items():
        held.update(int(i) for i in joint.indices)
    for name, value in data.joint_values(t, q, dq).items():
        rates = np.atleast_1d(value.rate)
        entries.update({name if len(rates) == 1 else f"{name}[{i}]": x for i, x in enumerate(rates)})
    entries.update({c: x for i, (c, x) in enumerate(zip(system.coordinates, dq)) if i not in held})
    top = max(entries.values(), key=abs)
    return {c: round(float(x / top), 6) for c, x in entries.items() if abs(x) > FREE_SHOWN_RTOL * abs(top)}
