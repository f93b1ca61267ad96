"""Event-driven motion with unilateral constraints (model/unilateral.py): joint limits and
contacts that strike, rest and lift off.

``EventIntegration`` is the continuous strategy (continuous.py) with events. After each
accepted step it looks at the gaps g ≥ 0 that are open and at the forces λ ≥ 0 of those
that hold; where one changes sign within the step its time is found by Brent's method on
the step's dense output (no step-size crawl), the step is taken again up to that time, and
the state there is ``settle``d:

1. impacts: the open gaps that touch (g ≤ the run's atol) and close faster than they could
   rest strike. Their velocity jump is the impulse form of the singular-mass equation
   (impulse.py: M Δq̇ = AᵀΛ with the bilateral rows kept, Newton's law on the striking
   rows), Result 3 deciding whether it is unique. Simultaneous impacts are a linear
   complementarity problem 0 ≤ Λ ⊥ ġ⁺ + e ġ⁻ ≥ 0 over the striking rows and the held
   ones (e = 0 there), solved exactly by enumerating its active sets; a row the jump
   leaves closing strikes in the next round at the same instant (sequential impacts:
   Newton's cradle exchanges its velocities so). A rebound whose hop height v²/(2|g̈|) is
   below REST_HOP × atol is not followed: the row takes e = 0 and comes to rest (a bouncing
   ball's accumulation of impacts ends after finitely many; the remaining flights, at most
   2v/(|g̈|(1 − e)), are within the run's accuracy).
2. persistent contact: the touching gaps at rest and the held ones form the acceleration
   complementarity problem 0 ≤ λ ⊥ g̈ ≥ 0, again solved by enumeration; the rows of its
   solution hold (a System with them appended: unilateral.with_active), each newly held
   one brought to rest first (an e = 0 jump); one that sank from rest (its g̈ below the
   tolerance: a box tipping over the diagonal it rests on) is held in every set tried. A
   held row is released where its force falls to zero.

A striking contact with Coulomb friction μ sticks or slips through its impact
(impulse.Rough): Newton's law on its normal, and either its slip rows held at zero
(stick: |Λ_t| ≤ μ Λ_n) or the tangential impulse μ Λ_n along the impulse stick would need
(slip: Brach's algebraic impact law). A held contact with friction sticks or slides
(``_modes``): sticking, its slip rows T q̇ = 0 are held beside its gap's row (bilateral
rows, unilateral.with_active) while |λ_t| ≤ μ λ_n, and where μ λ_n − |λ_t| falls to zero
(an event found on the dense output) it slides from there against λ_t; sliding, C =
−μ λ_n Tᵀû (T its slip rows, û the unit slip; λ_n found exactly, ``_held_motion``), and
where its slip stops (an event) it sticks again, or slides on against λ_t where |λ_t| >
μ λ_n there. Sticking contacts whose forces their rows leave free (a box on four corners)
stick as a group while some split of the forces lies in every cone (cones.py: s* ≤ 0),
break away where s* reaches zero (an event) and slide in the first consistent mode
(``_breakaway``), on the first set of the touching contacts that has one (``_contact_mode``).

Every impact, contact and release is an ``Event`` in the run's trajectory (and its .npz).
A state with no consistent contact mode (Painlevé-type) or a jump that is not unique raises
EventError (a SolveError) naming the time and the gaps: the run stops there.
"""

import itertools
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from . import stepper
from .cones import Cone, Shared, shared_rows
from .continuous import ContinuousIntegration
from .derivative import Crawl
from .impulse import Rough, velocity_jump
from .trajectory import Event
from ..core.errors import EventError, ModelError, SolveError
from ..core.solvers import kkt_acceleration
from ..core.tolerances import (ASSEMBLED_TOL, COMPLEMENTARITY_RTOL, DIVISION_GUARD, EVENT_TIME_RTOL, REST_HOP,
                               SLIP_DIRECTION_TOL,
                               SPEED_ROUNDING)
from ..model.reactions import indeterminate, multipliers
from ..model.unilateral import Gaps, slip_direction, with_active

ROUNDS = 1000  # impacts at one instant: a row that strikes this often at once is chattering (no hang)
IDLE_EVENTS = 100  # events in a row that change nothing: the gaps chatter without an impact
INSTANT_EVENTS = 100  # events in a row at one instant: held contacts switch between stick and slip without end
SLIP_DIRECTION_ROUNDS = 20  # a breakaway's slip directions are followed to their fixed point this often
ENUMERATED = 12  # rows of a complementarity problem solved by enumeration (2^12 active sets at most)
SUNK = 0.5  # a gap at rest this many atol deep (an event puts a gap sinking from rest at 1 atol) is held


class Pending(NamedTuple):
    """The next event: at ``t`` the open gaps ``closing`` touch, the held ``released`` ones
    lose their force, the held contacts with friction ``switching`` stop sliding or reach
    their friction cone's edge (indices into Gaps)."""

    t: float
    closing: frozenset
    released: frozenset
    switching: frozenset = frozenset()


class Held(NamedTuple):
    """The motion with some gaps held (``EventIntegration._held_motion``): q̈, the held gaps'
    forces λ, every gap's g̈ and the size of its terms, the size of the forces, and per
    sticking contact its tangential force λ_t (on its slip rows); where the rows leave
    forces free (cones.py), the held gaps they reach (``group``), their ``Shared`` forces
    and its margin s* (≤ 0: some distribution sticks), λ and λ_t then the ones chosen."""

    qdd: np.ndarray
    lam: np.ndarray
    gdd: np.ndarray
    scale: np.ndarray
    force: float
    tangential: dict
    group: tuple = ()
    shared: Shared = None
    margin: float = None


class EventIntegration(ContinuousIntegration):
    """The continuous strategy with the events of unilateral constraints (module docstring)."""

    def __init__(self, *args):
        self.active = frozenset()  # the held gaps (indices)
        self.sliding = {}  # the held contacts with friction that slide: {index: the slip's direction at onset}
        self.started = False  # whether the state at the start is settled (``advance``)
        super().__init__(*args)
        self.base = self.data  # the run's Data: the model without held gaps
        system = self.base.system
        self.gaps = Gaps(system, self.base.parameter_values)
        self.phases = {(frozenset(), ()): self.base}  # (active set, sliding) -> its Data
        self.pending = None
        self.events = []  # trajectory.Event (simulate hands the recorder's list)
        self.idle = 0  # events in a row that changed nothing
        self.instant = (None, 0)  # the time of the last event and how many in a row came at it

    # ---- the phases: the System with the held rows appended

    def _phase(self, active, sliding):
        """The Data of the active set (``sliding``: its contacts with friction, which slide),
        at the run's parameter values."""
        sticking = self._sticking(active, sliding)
        key = (active, tuple(sorted((i, tuple(d)) for i, d in sliding.items())), sticking)
        data = self.phases.get(key)
        if data is None:
            names = {self.gaps.names[i] for i in active}
            slid = {self.gaps.names[i]: (self.gaps.friction[i], d, self.atol) for i, d in sliding.items()}
            stuck = {self.gaps.names[i] for i in sticking}
            data = self.phases[key] = with_active(self.base.system, names, slid, stuck).data(self.base.path)
        if not np.array_equal(data.parameter_values, self.base.parameter_values):
            defined = self.base.system.definitions or {}
            data.set_parameters({k: v for k, v in self.base.parameters.items() if k not in defined})
        return data

    def _sticking(self, active, sliding):
        """The held contacts with friction among ``active`` that stick (do not slide)."""
        return tuple(i for i in sorted(active) if self.gaps.friction[i] > 0 and i not in sliding)

    def restart(self):
        if self.active:  # new parameter values at a control sample: the phase's Data follows the run's
            self.data = self.f.data = self._phase(self.active, self.sliding)
        if self.started:  # and the restitutions
            self.gaps = Gaps(self.base.system, self.base.parameter_values)
        super().restart()

    def _switch(self, active, sliding):
        """Integrate with the rows of ``active`` held from here, its contacts ``sliding``
        sliding (the solver's f is given anew by the caller)."""
        if active == self.active and sliding.keys() == self.sliding.keys():
            return
        self.active, self.sliding = active, sliding
        self.data = self.f.data = self._phase(active, sliding)
        engine = self.data.engine
        self.f.use(engine)
        self.projection = None if engine is None else engine.projection()
        self.compiled_energy = self.projection is not None and self.projection.energies and self.potential_free
        self.has_rows = len(self.data.system.constraint_names) > 0
        self.watch = self.crossing = None

    # ---- the run loop's calls

    def advance(self, t_next, q, qd, t_stop):
        if not self.started:
            self._check_start(self.t_now, q, qd)
            self.started = True
            q, qd, _ = self.settle(self.t_now, q, qd)
        q, qd = super().advance(t_next, q, qd, t_stop)
        if self.solver is not None:  # integrated continuously, its events found
            return q, qd
        g = self.gaps.values(t_next, q, qd, self.base.parameter_values)[0]
        passed = [self.gaps.names[i] for i in self._open() if g[i] < -self.atol]
        if passed:  # an interval integrated cut (cut.py, near a singular position) sees no events
            self.f.t_failed = t_next
            raise EventError(f"the run passed through {', '.join(passed)} without its event (an interval "
                             f"integrated cut near a singular position)", constraints=passed)
        return q, qd

    def _reach(self, t_next, q, qd, t_stop):
        """ContinuousIntegration._reach; where its integrator collapses or crawls while held
        contacts with friction stick or slide, an EventError there naming them: no interval
        integrated cut holds their modes (its stages would crawl on through the friction's
        switching instead)."""
        try:
            return super()._reach(t_next, q, qd, t_stop)
        except (Crawl, SolveError) as stop:
            rough = [i for i in sorted(self.active) if self.gaps.friction[i] > 0]
            if isinstance(stop, EventError) or not rough:
                raise
            t = self.t_now if self.solver is None else self.solver.t
            raise self._fail(t, rough, f"the run cannot go on with these contacts held in their friction modes "
                                       f"(no consistent stick or slip: {stop})") from None

    def _check_start(self, t, q, qd):
        """ModelError where the state the run starts from penetrates a gap by more than
        ASSEMBLED_TOL (io/unilateral.py's check of a model file's initial state, for a state
        given otherwise: ``q0``, other parameter values)."""
        g = self.gaps.values(t, q, qd, self.base.parameter_values)[0]
        deep = [(name, -x) for name, x in zip(self.gaps.names, g) if x < -ASSEMBLED_TOL]
        if deep:
            raise ModelError(f"model '{self.base.system.name}': the state at t = {t:g} penetrates "
                             + ", ".join(f"'{name}' by {depth:.6g}" for name, depth in deep) + " (gaps must be ≥ 0)")

    def _step(self, solver, t_next):
        if self.pending is None:
            super()._step(solver, t_next)
            return
        if solver.t < self.pending.t:
            self._take(solver, t_next, stepper.saved(solver), self.pending.t, False)
        if self.pending is not None and solver.t == self.pending.t:
            self._at_event(solver)

    def _at_event(self, solver):
        """Settle the state the step reached at the pending event; go on from the new one."""
        pending, self.pending = self.pending, None
        t = solver.t
        q, qd = self.form.to_state(solver.y)
        q, qd_new, changed = self.settle(t, q, qd, pending.released, pending.switching)
        self.idle = 0 if changed else self.idle + 1
        if self.idle > IDLE_EVENTS:
            self.f.t_failed = t
            names = [self.gaps.names[i] for i in sorted(pending.closing | pending.released | pending.switching)]
            raise EventError(f"the gaps {', '.join(names)} chatter at t = {t:.9g}: {IDLE_EVENTS} events in a row "
                             f"changed nothing", constraints=names)
        self.instant = (t, self.instant[1] + 1 if self.instant[0] == t else 1)
        if self.instant[1] > INSTANT_EVENTS:
            raise self._fail(t, sorted(pending.switching | pending.closing | pending.released),
                             f"{INSTANT_EVENTS} events at this instant: held contacts switch between stick and slip "
                             f"without end (no consistent friction mode: several held contacts share the tangential "
                             f"load, which their rows do not determine)")
        if changed:
            y = self.form.to_integrator(q, qd_new)
            stepper.move(solver, y, self.f(t, y))

    def contact_forces(self, t, q, qd, held):
        """{gap name: (its normal force λ, its friction force, world x, y, z)} at (t, q, q̇)
        with the gaps named in ``held`` held (those of them sliding now slide): a sticking
        contact's friction is its slip rows' forces λ_t along its tangents, a sliding one's
        −μ λ_n û (û the unit slip); zero without friction."""
        rows = sorted(self.gaps.names.index(name) for name in held)
        if not rows:
            return {}
        sliding = {i: d for i, d in self.sliding.items() if i in rows}
        motion = self._held_motion(t, q, qd, rows, sliding)
        p, speed, found = self.base.parameter_values, np.abs(qd).max(initial=0.0), {}
        for i, lam in zip(rows, motion.lam):
            along = motion.tangential.get(i)
            if i in sliding:
                along = -self.gaps.friction[i] * lam * slip_direction(self.gaps.slip_rows(t, q, qd, p, i), qd,
                                                                     sliding[i], speed)
            friction = np.zeros(3) if along is None else self.gaps.tangents[i] @ along
            found[self.gaps.names[i]] = (float(lam), friction)
        return found

    def stats(self):
        counts = super().stats()
        counts["events"] = len(self.events)
        return counts

    # ---- finding events within a step

    def event_in(self, solver, start, target):
        """Whether the step from ``start`` passed an event (an open gap closing, a held one's
        force turning negative): then ``pending`` holds the earliest, found by Brent's
        method on the step's dense output. A step aimed at the pending event ignores its
        rows and gaps that touch (within atol) at its end: ``settle`` takes them there. An
        open gap that is open at both ends but turns from closing to opening within the step
        (ġ < 0 at its start, > 0 at its end: a free flight past a contact in one step) is
        looked at where g is least (Brent's bounded minimization; ġ may have no value where
        two centres pass through each other): it closed within the step where g < 0 there."""
        t0, t1 = start[0], solver.t
        aiming = self.pending is not None and target == self.pending.t
        ignore = (self.pending.closing | self.pending.released | self.pending.switching) if aiming else frozenset()
        q1, qd1 = self.form.to_state(solver.y)
        q0, qd0 = self.form.to_state(start[1])
        p = self.base.parameter_values
        (g0, gd0), (g1, gd1) = self.gaps.values(t0, q0, qd0, p), self.gaps.values(t1, q1, qd1, p)
        limit = -self.atol if aiming else 0.0
        ends = {i: (t1, g1[i]) for i in self._open() if i not in ignore and g1[i] < limit}
        turning = [i for i in self._open() if i not in ignore and i not in ends and g0[i] > self.atol and
                   gd0[i] < 0 < gd1[i]]
        dense = solver.dense_output() if turning else None
        for i in turning:
            lowest = minimize_scalar(lambda t: self._gap_at(dense, i, t), bounds=(t0, t1), method="bounded",
                                     options={"xatol": EVENT_TIME_RTOL * max(abs(t0), abs(t1))})
            if lowest.fun < limit:
                ends[i] = (lowest.x, lowest.fun)
        closing = list(ends)
        held = self.active - ignore
        reference = self._slip_references(t0, q0, qd0)
        watched1 = {k: x for k, x in self._watched(t1, q1, qd1, reference).items() if k[1] in held} if held else {}
        crossing = [k for k, x in watched1.items() if x < 0]
        if not closing and not crossing:
            return False
        dense = solver.dense_output() if dense is None else dense
        floor = self._rounding(t0, q0, qd0)
        roots = {("close", i): self._closing(dense, i, t0, ends[i][0], g0[i], gd0[i], ends[i][1], floor[i])
                 for i in closing}
        roots = {k: t for k, t in roots.items() if t is not None}
        if crossing:
            watched0 = self._watched(t0, q0, qd0, reference)
            roots.update({k: self._crossing(dense, k, reference, t0, t1, watched0[k], watched1[k]) for k in crossing})
        if not roots:
            return False
        t_event = min(roots.values())
        at = [k for k, t in roots.items() if t == t_event]
        before = self.pending if aiming else Pending(t_event, frozenset(), frozenset())
        self.pending = Pending(t_event, frozenset(i for kind, i in at if kind == "close") | (ignore & self._open_set()),
                               frozenset(i for kind, i in at if kind == "release") | before.released |
                               (before.closing & self.active),
                               frozenset(i for kind, i in at if kind == "switch") | before.switching)
        return True

    def _open(self):
        return [i for i in range(len(self.gaps)) if i not in self.active]

    def _open_set(self):
        return frozenset(self._open())

    def _gap_at(self, dense, i, t):
        q, qd = self.form.to_state(dense(t))
        return self.gaps.values(t, q, qd, self.base.parameter_values)[0][i]

    def _rounding(self, t, q, qd):
        """Per gap, the rate within which it is rounding (SPEED_ROUNDING × ‖a‖₁ max |q̇|)."""
        return SPEED_ROUNDING * np.abs(self.gaps.rows(t, q, qd, self.base.parameter_values)[0]).sum(axis=1) * \
            np.abs(qd).max(initial=0.0)

    def _closing(self, dense, i, t0, t1, g0, gd0, g1, floor):
        """When the open gap i, g0 at t0 and g1 < 0 at t1, closes within the step: where g
        falls to zero from above; from a touching start (g0 ≤ atol) moving apart, where g
        returns to g0 ((g − g0)/(t − t0), ġ0 at t0, changes sign); from a touching start at
        rest or closing, where it sinks atol below (there settle finds it). None where
        the gap ends above where it started touching. A touching start counts as moving apart
        where ġ0 would lift it by atol within the step: below that (the rounding of a state
        at rest, ġ0 ~ 1e-24) it is at rest."""
        if g0 > self.atol:
            return _root(lambda t: self._gap_at(dense, i, t), t0, t1, g0, g1)
        if gd0 > max(floor, self.atol / (t1 - t0)):
            if not g1 < min(g0, 0.0):
                return None
            return _root(lambda t: (self._gap_at(dense, i, t) - g0) / (t - t0), t0, t1, gd0, (g1 - g0) / (t1 - t0))
        if not g1 < -self.atol:
            return None
        if g0 <= -self.atol:
            return t0
        return _root(lambda t: self._gap_at(dense, i, t) + self.atol, t0, t1, g0 + self.atol, g1 + self.atol)

    def _crossing(self, dense, key, reference, t0, t1, f0, f1):
        """Where the watched value ``key`` (``_watched``), f0 at t0 and f1 < 0 at t1, falls
        to zero."""
        if f0 <= 0:
            return t0
        return _root(lambda t: self._watched(t, *self.form.to_state(dense(t)), reference)[key], t0, t1, f0, f1)

    # ---- the motion with some gaps held

    def _held_motion(self, t, q, qd, rows, sliding=None, free=()):
        """The ``Held`` motion of (2.14) with the gaps ``rows`` held beside the model's rows
        (its KKT form, solvers.py): of those with friction, the ones ``free`` slip without
        it, the ones in ``sliding`` (default: the run's) slide, C = −μ λ_n Tᵀû (λ_n affine
        in the C assumed: found exactly by one solve more per sliding contact), the others
        stick, their slip rows held. The sizes judge signs: a gap's acceleration is measured
        against its row times the larger of q̈ and the forces over the largest mass (a state
        at rest has q̈ = 0 to rounding), a multiplier against the largest |Q + C| and |λ|."""
        sliding = self.sliding if sliding is None else sliding
        arrays, p = self.base.evaluate(t, q, qd), self.base.parameter_values
        A_gaps, b_gaps = self.gaps.rows(t, q, qd, p)
        rows = list(rows)
        rough = [i for i in rows if self.gaps.friction[i] > 0 and i not in free]
        sticking, slipping = [i for i in rough if i not in sliding], [i for i in rough if i in sliding]
        slips = {i: self.gaps.slip_arrays(t, q, qd, p, i) for i in rough}
        A = np.vstack([arrays.A, A_gaps[rows], *(slips[i][0] for i in sticking)])
        b = np.concatenate([arrays.b, b_gaps[rows], *(slips[i][1] for i in sticking)])
        names = list(self.base.system.constraint_names) + [self.gaps.names[i] for i in rows] + \
            [f"{self.gaps.names[i]}.slip" for i in sticking for _ in slips[i][1]]
        speed = np.abs(qd).max(initial=0.0)
        per_unit = [-self.gaps.friction[i] * slips[i][0].T @ slip_direction(slips[i][0], qd, sliding[i], speed, self.atol)
                    for i in slipping]
        at = [len(arrays.b) + rows.index(i) for i in slipping]

        def solve(x):
            C = arrays.C + sum((xj * d for xj, d in zip(x, per_unit)), np.zeros(len(q)))
            motion = kkt_acceleration(arrays.M, arrays.Q, A, b, C, coordinates=self.base.system.coordinates,
                                      constraints=names)
            return motion, multipliers(A, arrays.M @ motion.qdd - arrays.Q - C)[0], C

        motion, lam, C = solve(np.zeros(len(slipping)))
        if slipping:
            alpha = lam[at]
            B = np.column_stack([solve(unit)[1][at] - alpha for unit in np.eye(len(slipping))])
            try:
                motion, lam, C = solve(np.linalg.solve(np.eye(len(slipping)) - B, alpha))
            except np.linalg.LinAlgError:
                raise self._fail(t, slipping, "no consistent sliding contact (the friction force undoes the normal "
                                              "force: Painlevé-type)") from None
        gdd = A_gaps @ motion.qdd - b_gaps
        force = np.abs(arrays.Q + C).max(initial=0.0)
        acceleration = max(np.abs(motion.qdd).max(initial=0.0), force / (np.abs(arrays.M).max(initial=0.0) +
                                                                           DIVISION_GUARD))
        scale = np.abs(A_gaps).sum(axis=1) * acceleration + np.abs(b_gaps)
        first, start, slip_at = len(arrays.b), len(arrays.b) + len(rows), {}
        for i in sticking:
            slip_at[i], start = tuple(range(start, start + len(slips[i][1]))), start + len(slips[i][1])
        W = indeterminate(A)
        group = tuple(i for i in rows if shared_rows(W, (first + rows.index(i),) + slip_at.get(i, ())))
        shared = margin = None
        if group:
            shared = Shared(lam, W, [Cone(first + rows.index(i), slip_at[i], self.gaps.friction[i])
                                     for i in group if i in slip_at],
                            [first + rows.index(i) for i in group if i not in slip_at], force)
            margin, lam = shared.margin()
        tangential = {i: lam[list(at)] for i, at in slip_at.items()}
        return Held(motion.qdd, lam[first:first + len(rows)], gdd, scale, force + np.abs(lam).max(initial=0.0),
                    tangential, group, shared, margin)

    def _slip_references(self, t, q, qd):
        """{sliding contact: the unit direction its slip's component along is watched}: the
        slip's direction at (t, q, q̇), or its onset's where it has no speed there."""
        speed, found = np.abs(qd).max(initial=0.0), {}
        for i, d in self.sliding.items():
            T = self.gaps.slip_rows(t, q, qd, self.base.parameter_values, i)
            found[i] = T.T @ slip_direction(T, qd, d, speed, self.atol)
        return found

    def _watched(self, t, q, qd, reference):
        """{(kind, held gap): a value whose sign change is an event}: ("release", i) its force
        λ; ("switch", i) of a sliding contact, its slip along its ``reference`` direction
        (T q̇)·û, given on the generalized side as Tᵀû (it stops); of a sticking one, μ λ_n −
        |λ_t| (it reaches its friction cone's edge); of a group whose forces the rows leave
        free (cones.py), −s* for each of its contacts."""
        held = sorted(self.active)
        motion = self._held_motion(t, q, qd, held)
        found = {("release", i): lam for i, lam in zip(held, motion.lam)}
        for i, direction in reference.items():
            found[("switch", i)] = float(direction @ qd)
        for i, lam_t in motion.tangential.items():
            found[("switch", i)] = self.gaps.friction[i] * motion.lam[held.index(i)] - float(np.linalg.norm(lam_t))
        for i in motion.group:  # forces the rows leave free: the group holds while s* ≤ 0
            del found[("release", i)]
            found[("switch" if i in motion.tangential else "release", i)] = -motion.margin
        return found

    # ---- settling the state at an event

    def settle(self, t, q, qd, released=frozenset(), switching=frozenset()):
        """(q, q̇⁺, whether anything changed) at an event at t: the impacts, then the
        persistent contacts (module docstring); ``released``: held gaps whose force fell
        to zero here (they open, as do held ones an impact here left opening);
        ``switching``: sliding contacts whose slip stops here, sticking ones that reach
        their friction cone's edge. Records the events."""
        p, changed = self.base.parameter_values, False
        for _ in range(ROUNDS):
            g, gd = self.gaps.values(t, q, qd, p)
            gdd = self._held_motion(t, q, qd, sorted(self.active)).gdd
            rest = np.sqrt(2 * np.maximum(-gdd, 0.0) * REST_HOP * self.atol)
            floor = self._rounding(t, q, qd)
            striking = [i for i in self._open() if g[i] <= self.atol and gd[i] < -max(rest[i], floor[i])]
            if not striking:
                break
            e = np.where(self.gaps.restitution * -gd > rest, self.gaps.restitution, 0.0)
            qd = self._impact(t, q, qd, striking, e, gd, floor)
            changed = True
        else:
            raise self._fail(t, striking, f"{ROUNDS} impacts at one instant")
        g, gd = self.gaps.values(t, q, qd, p)
        floor = self._rounding(t, q, qd)
        gdd = self._held_motion(t, q, qd, sorted(self.active)).gdd
        rest = np.sqrt(2 * np.maximum(-gdd, 0.0) * REST_HOP * self.atol)
        resting = [i for i in self._open() if g[i] <= self.atol and abs(gd[i]) <= max(rest[i], floor[i])
                   and i not in released]
        leaving = {i for i in self.active if changed and gd[i] > max(rest[i], floor[i])}  # an impact left it opening
        # sunk to where the event of a gap sinking from rest puts it and still sinking: left open it would
        # come back here again and again
        sunk = {i for i in resting if g[i] < -SUNK * self.atol and gd[i] <= 0}
        kept = self.active - released - leaving
        active, qd, sliding = self._contact_mode(t, q, qd, sorted(kept | set(resting)), kept, sunk, switching)
        for i in sorted(self.active - active):
            self.events.append(Event(float(t), self.gaps.names[i], "release", 0.0))
        sticking = self._sticking(active, sliding)
        for i in sorted(set(sliding) - set(self.sliding)):
            self.events.append(Event(float(t), self.gaps.names[i], "slip", 0.0))
        for i in sorted(set(sticking) - set(self._sticking(self.active, self.sliding))):
            self.events.append(Event(float(t), self.gaps.names[i], "stick", 0.0))
        changed |= active != self.active or sliding.keys() != self.sliding.keys()
        self._switch(active, sliding)
        return q, qd, changed

    def _contact_mode(self, t, q, qd, candidates, kept, sunk, switching):
        """(the held gaps, q̇ with the newly held ones at rest, the sliding contacts) from t:
        the first contact set (``_contact_sets``) whose friction modes are consistent
        (``_modes``): a group breaking away may slide only on another set of contacts (a
        box stuck on two diagonal corners tips onto a third as it slides). Records the
        newly held gaps' contact events."""
        first = None  # the first set tried, named where none slides
        for active in self._contact_sets(t, q, qd, candidates, kept, sunk):
            held_qd, contacts = self._come_to_rest(t, q, qd, active) if active - self.active else (qd, [])
            sliding = self._modes(t, q, held_qd, active, switching, [i for i in candidates if i not in active])
            if sliding is not None:
                self.events += contacts
                return active, held_qd, sliding
            first = first or active
        if first is None:
            raise self._fail(t, candidates, "no consistent contact mode (Painlevé-type: no active set of the "
                                            "complementarity problem)")
        raise self._fail(t, sorted(first), "these contacts break away, but no slide of theirs was found on any set of "
                                           "the touching contacts (slip directions that their accelerations follow, "
                                           "with the other contacts in their friction cones and none sinking)")

    def _modes(self, t, q, qd, active, switching, others=()):
        """{held contact that slides from t: its slip's direction} among the held contacts
        with friction ``active``: one sliding goes on sliding unless it is ``switching``
        (its slip stopped) here; a newly held one slides where it moves; a sticking one
        ``switching`` (at its friction cone's edge) slides against λ_t. The others stick
        where |λ_t| ≤ μ λ_n with their slip rows held, and otherwise slide against λ_t; a
        group whose forces the rows leave free breaks away as ``_breakaway`` finds (the
        touching gaps not held, ``others``, kept open), None where it finds no slide."""
        speed, sliding, trial = np.abs(qd).max(initial=0.0), {}, []
        stuck = self._sticking(self.active, self.sliding)
        for i in sorted(i for i in active if self.gaps.friction[i] > 0):
            moving = slip_direction(self.gaps.slip_rows(t, q, qd, self.base.parameter_values, i), qd, None, speed,
                                    self.atol)  # slower than the run resolves: at rest, its rounding no direction
            if i in self.sliding and i not in switching:
                sliding[i] = self.sliding[i] if moving is None else moving
            elif i not in self.active and moving is not None:
                sliding[i] = moving
            else:
                trial.append(i)
        if not trial:
            return sliding
        motion = self._held_motion(t, q, qd, sorted(active), sliding)
        held = sorted(active)
        for i in (i for i in trial if i not in motion.group):
            lam_t, lam_n = motion.tangential[i], motion.lam[held.index(i)]
            size = np.linalg.norm(lam_t)
            breaks = i in switching and i in stuck  # its friction cone's edge reached: it slips from here
            if breaks or size > self.gaps.friction[i] * lam_n * (1 + COMPLEMENTARITY_RTOL):
                sliding[i] = -lam_t / size
        group = [i for i in trial if i in motion.group]
        if group:
            motion = self._held_motion(t, q, qd, held, sliding)
            breaks = bool(set(group) & set(switching) & set(stuck))  # the group's s* reached zero: it breaks
            if breaks or motion.margin > COMPLEMENTARITY_RTOL * motion.force:
                return self._breakaway(t, q, qd, held, sliding, [i for i in group if i in motion.tangential],
                                       motion, others)
        return sliding

    def _breakaway(self, t, q, qd, held, sliding, group, motion, others):
        """``sliding`` with those of the sticking contacts ``group`` (whose forces the rows
        leave free, cones.py) that slide from t, or None: the first subset, largest first (a
        load that breaks the group free moves it as a whole), whose mode is consistent
        (``_consistent``). Each sliding one's slip accelerates along its direction: the
        fixed point of the slip's acceleration, followed from the slip the load would give
        the subset without its friction (a box pushed or on a slope starts to slide as it
        is pushed; a group breaking away at s* = 0 has no acceleration yet, and takes that
        direction), or against its minimum-norm force where that slip is negligible."""
        p = self.base.parameter_values
        slips = {i: self.gaps.slip_arrays(t, q, qd, p, i) for i in group}
        least = {i: motion.shared.lam[list(motion.shared.cones[k].tangential)]  # the minimum-norm λ_t
                 for k, i in enumerate(j for j in motion.group if j in motion.tangential)}

        def accelerations_of(found, chosen):
            return {i: slips[i][0] @ found.qdd - slips[i][1] for i in chosen}

        for chosen in _subsets(group)[:0:-1]:
            pushed = accelerations_of(self._held_motion(t, q, qd, held, sliding, free=chosen), chosen)
            negligible = COMPLEMENTARITY_RTOL * max(np.linalg.norm(a) for a in pushed.values())
            trial = {**sliding, **{i: _unit(pushed[i], negligible, -least[i]) for i in chosen}}
            for _ in range(SLIP_DIRECTION_ROUNDS):
                found = self._held_motion(t, q, qd, held, trial)
                accelerations = accelerations_of(found, chosen)
                turned = {i: a / np.linalg.norm(a) for i, a in accelerations.items() if np.linalg.norm(a) > negligible}
                if all(np.linalg.norm(turned[i] - trial[i]) <= SLIP_DIRECTION_TOL for i in turned):
                    break
                trial.update(turned)
            else:  # no fixed point reached: no slide of this subset is known to be consistent
                continue
            if self._consistent(found, held, accelerations, trial, negligible, others):
                return trial
        return None

    def _consistent(self, motion, held, accelerations, directions, negligible, others):
        """Whether the mode of ``motion`` (contacts newly sliding along ``directions``, their
        slips' ``accelerations``) is consistent: the held gaps' determined forces λ_n ≥ 0, a
        group's margin s* ≤ 0, the other sticking contacts in their cones, each slip that is
        not ``negligible`` accelerating along its direction, and the touching gaps not held
        (``others``) not sinking (g̈ ≥ 0)."""
        tol = COMPLEMENTARITY_RTOL * motion.force
        if (motion.lam < -tol).any() and any(i not in motion.group for i, lam in zip(held, motion.lam) if lam < -tol):
            return False
        if motion.margin is not None and motion.margin > tol:
            return False
        if any(motion.gdd[i] < -COMPLEMENTARITY_RTOL * motion.scale[i] for i in others):
            return False
        for i, lam_t in motion.tangential.items():
            if i not in motion.group and np.linalg.norm(lam_t) > \
                    self.gaps.friction[i] * motion.lam[held.index(i)] * (1 + COMPLEMENTARITY_RTOL):
                return False
        return all(np.linalg.norm(a / np.linalg.norm(a) - directions[i]) <= SLIP_DIRECTION_TOL
                   for i, a in accelerations.items() if np.linalg.norm(a) > negligible)

    def _bilateral(self, t, q, qd):
        """(A, target, names) of the model's velocity-level rows at (t, q, q̇): A q̇ = target
        keeps them holding through a jump (target = A q̇ − ψ; acceleration-level rows,
        which have no velocity form, are left out)."""
        arrays = self.base.constraint_arrays(t, q, qd, sparse=False)
        keep = np.isfinite(arrays.psi)
        A = arrays.A[keep]
        names = [n for n, k in zip(self.base.system.constraint_names, keep) if k]
        return A, A @ qd - arrays.psi[keep], names

    def _impact(self, t, q, qd, striking, e, gd, floor):
        """q̇⁺ of the impact of the ``striking`` gaps (their restitution ``e``, rates ``gd``)
        with the held ones (e = 0): the complementarity problem over them solved by
        enumeration, the first consistent active set in order (smallest first) taken; an
        active set whose jump is not unique (Result 3) is none, and where every one is
        such, the largest one's SolveError is raised."""
        rows = sorted(set(striking) | self.active)
        if len(rows) > ENUMERATED:
            raise self._fail(t, rows, f"{len(rows)} gaps strike at once (at most {ENUMERATED} are solved exactly)")
        A_b, v_b, names_b = self._bilateral(t, q, qd)
        A_gaps = self.gaps.rows(t, q, qd, self.base.parameter_values)[0]
        M = self.base.evaluate(t, q, qd).M
        coordinates = self.base.system.coordinates
        failed = None
        for chosen in _subsets(rows):
            target = np.array([-e[i] * gd[i] if i in striking else 0.0 for i in chosen])
            rough = Rough(self.gaps, t, q, qd, self.base.parameter_values, chosen)
            try:
                qd_after, impulses, modes = rough.jump(M, qd, A_b, v_b, names_b, A_gaps, target, coordinates)
            except SolveError as err:
                failed = err
                continue
            after = A_gaps @ qd_after
            others = [i for i in rows if i not in chosen]
            if (impulses >= -COMPLEMENTARITY_RTOL * np.abs(impulses).max(initial=0.0)).all() and \
                    all(after[i] + e[i] * gd[i] >= -COMPLEMENTARITY_RTOL * abs(gd[i]) - floor[i] for i in others):
                for i, impulse in zip(chosen, impulses):
                    if i in striking:
                        self.events.append(Event(float(t), self.gaps.names[i], "impact", float(impulse)))
                    if i in modes:
                        self.events.append(Event(float(t), self.gaps.names[i], *modes[i]))
                return qd_after
        if failed is not None:
            raise self._fail(t, rows, str(failed), failed.coordinates)
        raise self._fail(t, rows, "no consistent impact (no active set of the complementarity problem)")

    def _contact_sets(self, t, q, qd, candidates, kept=frozenset(), sunk=frozenset()):
        """The sets of gaps among ``candidates`` (touching, at rest or held) that may hold
        from t, in the order tried: active sets, smallest first, with λ ≥ 0 on their rows
        (where the rows leave forces free: for some distribution of them, cones.py) and
        g̈ ≥ 0 on the others with their contacts sticking; those that keep all of ``kept``
        (held, their force not fallen to zero) first: where dependent rows make several sets
        consistent (a box on four corners holds on three, or on two at a diagonal while it
        sticks), a held contact stays held. Those ``sunk`` (sinking from rest into their gap,
        found where it is atol deep: a body tipping over an edge of its supports at a rate
        g̈ below the tolerance) are held in every set tried."""
        if len(candidates) > ENUMERATED:
            raise self._fail(t, candidates, f"{len(candidates)} gaps rest at once (at most {ENUMERATED} are solved "
                                            f"exactly)")
        subsets = [c for c in _subsets(candidates) if sunk <= set(c)]
        for chosen in [c for c in subsets if kept <= set(c)] + [c for c in subsets if not kept <= set(c)]:
            motion = self._held_motion(t, q, qd, chosen)
            others = [i for i in candidates if i not in chosen]
            determined = [lam for i, lam in zip(chosen, motion.lam) if i not in motion.group]
            pushing = motion.shared is None or motion.shared.margin(with_cones=False)[0] <= \
                COMPLEMENTARITY_RTOL * motion.force
            if pushing and (np.array(determined) >= -COMPLEMENTARITY_RTOL * motion.force).all() and \
                    all(motion.gdd[i] >= -COMPLEMENTARITY_RTOL * motion.scale[i] for i in others):
                yield frozenset(chosen)

    def _come_to_rest(self, t, q, qd, active):
        """(q̇⁺ with the newly held gaps of ``active`` brought to rest (an e = 0 jump, every
        held row at zero rate), their contact events)."""
        A_b, v_b, names_b = self._bilateral(t, q, qd)
        A_gaps = self.gaps.rows(t, q, qd, self.base.parameter_values)[0]
        rows = sorted(active)
        jump = self._jump(t, rows, self.base.evaluate(t, q, qd).M, qd, np.vstack([A_b, A_gaps[rows]]),
                          np.concatenate([v_b, np.zeros(len(rows))]), coordinates=self.base.system.coordinates,
                          constraints=names_b + [self.gaps.names[i] for i in rows])
        return jump.qd, [Event(float(t), self.gaps.names[i], "contact", float(impulse))
                         for i, impulse in zip(rows, jump.impulses[len(v_b):]) if i not in self.active]

    def _fail(self, t, rows, why, coordinates=()):
        """The EventError at t of the gaps ``rows``."""
        self.f.t_failed = t
        names = [self.gaps.names[i] for i in rows]
        return EventError(f"at t = {t:.9g}, {', '.join(names)}: {why}", constraints=names, coordinates=coordinates)

    def _jump(self, t, rows, *args, **kwargs):
        """``velocity_jump(*args, **kwargs)`` of the impact of the gaps ``rows`` at t; its
        SolveError (a jump that is not unique, contradictory rows) as an EventError there."""
        try:
            return velocity_jump(*args, **kwargs)
        except SolveError as err:
            raise self._fail(t, rows, str(err), err.coordinates) from None


def _subsets(rows):
    """The subsets of ``rows``, smallest first, each in order: the active sets enumerated (a
    row that needs no force or impulse is not held)."""
    rows = list(rows)
    return [chosen for size in range(len(rows) + 1) for chosen in itertools.combinations(rows, size)]


def _unit(a, negligible, otherwise):
    """a's direction, or ``otherwise``'s where |a| is ``negligible`` (zero where both are)."""
    size = np.linalg.norm(a)
    if size > negligible:
        return a / size
    return otherwise / (np.linalg.norm(otherwise) or 1.0)


def _root(f, t0, t1, f0, f1):
    """The root of f in [t0, t1] (f0 = f(t0) ≥ 0 > f1 = f(t1), given) by Brent's method, to
    rounding."""
    if f0 == 0:
        return t0
    known = {t0: f0, t1: f1}
    return brentq(lambda t: known[t] if t in known else f(t), t0, t1, xtol=DIVISION_GUARD, rtol=EVENT_TIME_RTOL)
