"""Putting a state back on the constraints with the kernel itself, in the mass metric.

At q̇ = 0, with no gravity and no generated forces, the kernel's Q and b vanish (every
b term of a kernel row is quadratic in q̇), so its q̈ for a right side shifted by −r is
the least-M-norm Δ with A Δ = −r ((2.14) with Q = 0). One such call is a Gauss–Newton
step of the projection in the mass metric: positions with r = φ(q) (repeated while φ is
above MASS_PROJECTION_RTOL of the coordinates' size, at most MAX_STEPS times), then velocities
with r = φ̇(q, q̇) = A q̇, a linear problem one step solves. From an integrator's drift of
5e-9 one step leaves rounding (2e-15 on a UR5). After a single position step of at most
MASS_PROJECTION_REUSE of the coordinates' size, with φ̇ at most MASS_PROJECTION_REUSE of the
rates, the velocity step reuses that step's factorization: A at the unprojected q leaves φ̇ off by about
|Δq| |Δq̇|, REUSE² relative; each body's quaternion rate first loses its part along u
(``_unit_rates``), so that the reusing call solves for the joint rows' right sides alone
(kernel.motion's REUSED at rest). The kernel's own residual check is skipped
(kernel.UNCHECKED):
the rows after each step check it, and a velocity step that does not cut φ̇ sends the
state to analysis/projection.py. A projection here costs a kernel call with its factorization,
one that reuses it and three passes of the rows, far less than analysis/projection.py's sparse
factorization (benchmarks/end_to_end_results.md).
``project`` does it in one compiled call for each state of a block; ``Projection.block``
splits a block among the cores (``simulate``: the output times a step passed, with its
end), each thread with its own Work.

Only for Systems all of whose rows and coordinates the kernel covers (rows.py's ``covers``:
the rows of its tree and loop joints, no extra coordinates); elsewhere, and at any state the
kernel declines, the caller projects with analysis/projection.py. With loops, each step's Schur step
follows the drift rule (kernel.motion's ``drift``: the state's relative drift).
"""

import threading
from typing import NamedTuple

import numpy as np
from numba import njit

from .bodies import OPTIONS
from . import row_fit, threads
from .joints import RIGID
from .kernel import LAYOUT, OK, REUSED, UNCHECKED, WORK, motion
from .packing import view1
from .rows import Rows, largest, residuals_energy
from ..core.tolerances import MASS_PROJECTION_RATE_RTOL, MASS_PROJECTION_REUSE, MASS_PROJECTION_RTOL, MASS_PROJECTION_SHRINK

MAX_STEPS = 3  # position steps before the state goes to analysis/projection.py
TINY = np.finfo(float).tiny  # the largest rate's floor
# a thread of ``Projection.block`` takes states of this many coordinates in all at least: handing
# work to a thread costs about what projecting states of several hundred coordinates costs
PER_THREAD = 1500
KINETIC, POTENTIAL, PHI_MAX, PSI_MAX, DONE = range(5)  # the columns of ``project``'s ``found``


class Projected(NamedTuple):
    """A projected state and, there (rows.py), the kinetic and potential energy and the
    largest |φ| and |φ̇|."""

    q: np.ndarray
    qd: np.ndarray
    kinetic: float
    potential: float
    phi_max: float
    psi_max: float


class ProjectedRows(NamedTuple):
    """States projected in one block: q, q̇ (a row each) and ``found`` (a row each:
    KINETIC, POTENTIAL, PHI_MAX, PSI_MAX, DONE = 1 where the row was projected, else 0 and
    the row's state is not on the constraints)."""

    q: np.ndarray
    qd: np.ndarray
    found: np.ndarray

    @property
    def done(self):
        """Whether each row was projected."""
        return self.found[:, DONE] == 1.0

    def part(self, a, b):
        """Rows a to b (views)."""
        return ProjectedRows(self.q[a:b], self.qd[a:b], self.found[a:b])

    def row(self, i):
        """Row i as Projected, or None where it was not projected."""
        info = self.found[i]
        return Projected(self.q[i], self.qd[i], *info[:DONE]) if info[DONE] else None


@njit(nogil=True, **OPTIONS)
def project(Q, QD, Q_on, QD_on, found, LI, LF, LX, LF_rest, WI, WF, WX, gen, general, work):
    """Each state (row of Q, Q̇) projected into Q_on, Q̇_on (module docstring), found's row
    (KINETIC, POTENTIAL, PHI_MAX, PSI_MAX there, DONE = 1), or DONE = 0 where the kernel
    declines it or the rows' checks fail. LI, LF, LX: the Layout packed; LF_rest: its
    floats with no gravity (Engine.at_rest); WI, WF, WX: a Work packed; gen: zeros for
    the generated function's outputs; general: kernel.motion's (Template.general); work:
    a thread's arrays (``Projection._arguments``: rows.py's φ, φ̇, Rs; the right side; the
    factored q; q̇ = 0)."""
    phi, psi, Rs, shift, factored, rest = work
    qdd = view1(WF, WX, WORK.qdd)
    kind, start = view1(LI, LX, LAYOUT.node_kind), view1(LI, LX, LAYOUT.node_q)
    quat_row = view1(LI, LX, LAYOUT.quat_row)
    for b in range(Q.shape[0]):
        found[b, DONE] = 0.0
        q, qd = Q_on[b], QD_on[b]
        for c in range(q.shape[0]):
            q[c], qd[c] = Q[b, c], QD[b, c]
        _, _, phi_max, _, q_max, qd_max = residuals_energy(q, qd, LI, LF, LX, phi, psi, Rs, False)
        size, reuse, declined = max(q_max, 1.0), False, False
        for step in range(MAX_STEPS + 1):
            if phi_max <= MASS_PROJECTION_RTOL * size:
                break
            _negated(phi, shift)
            if step == MAX_STEPS or \
                    motion(q, rest, gen, shift, LI, LF_rest, LX, WI, WF, WX, UNCHECKED, phi_max / size,
                           general)[0] != OK:
                declined = True
                break
            reuse = step == 0 and largest(qdd) <= MASS_PROJECTION_REUSE * size  # the Work keeps q's factorization
            for c in range(q.shape[0]):
                factored[c] = q[c] if reuse else factored[c]
                q[c] += qdd[c]
            _unit_rates(q, qd, kind, start)
            _, _, phi_max, psi_max, _, _ = residuals_energy(q, qd, LI, LF, LX, phi, psi, Rs)
        if declined:
            continue
        if step == 0:  # on the constraints as it came: its φ̇ not read yet
            _, _, _, psi_max, _, _ = residuals_energy(q, qd, LI, LF, LX, phi, psi, Rs)
        rates = max(qd_max, TINY)
        _negated(psi, shift)
        if reuse and psi_max <= MASS_PROJECTION_REUSE * rates:
            for i in range(kind.shape[0]):
                if kind[i] == RIGID:
                    shift[quat_row[i]] = 0.0  # met by _unit_rates, to rounding: the kernel redoes only the solve
            status = motion(factored, rest, gen, shift, LI, LF_rest, LX, WI, WF, WX, REUSED, phi_max / size, general)[0]
        else:
            status = motion(q, rest, gen, shift, LI, LF_rest, LX, WI, WF, WX, UNCHECKED, phi_max / size, general)[0]
        if status != OK:
            continue
        before = psi_max
        for c in range(qd.shape[0]):
            qd[c] += qdd[c]
        kinetic, potential, phi_max, psi_max, _, _ = residuals_energy(q, qd, LI, LF, LX, phi, psi, Rs)
        if psi_max <= max(MASS_PROJECTION_SHRINK * before, MASS_PROJECTION_RATE_RTOL * size * rates):
            found[b, KINETIC], found[b, POTENTIAL], found[b, PHI_MAX], found[b, PSI_MAX] = \
                kinetic, potential, phi_max, psi_max
            found[b, DONE] = 1.0


@njit(**OPTIONS)
def judge(Q, QD, found, skip, LI, LF, LX, phi, psi, Rs):
    """found's row for each state (row of Q, Q̇) but those at ``skip`` (increasing indices),
    as ``project`` leaves it, without moving the state: DONE = 1 where |φ| is within
    MASS_PROJECTION_RTOL of the coordinates' size and |φ̇| within MASS_PROJECTION_RATE_RTOL of that
    times the largest rate (row_fit.py's rows)."""
    skipped = 0
    for b in range(Q.shape[0]):
        if skipped < skip.shape[0] and skip[skipped] == b:
            skipped += 1
            continue
        kinetic, potential, phi_max, psi_max, q_max, qd_max = residuals_energy(Q[b], QD[b], LI, LF, LX, phi, psi, Rs)
        size = max(q_max, 1.0)
        found[b, KINETIC], found[b, POTENTIAL], found[b, PHI_MAX], found[b, PSI_MAX] = \
            kinetic, potential, phi_max, psi_max
        found[b, DONE] = 1.0 if phi_max <= MASS_PROJECTION_RTOL * size and \
            psi_max <= MASS_PROJECTION_RATE_RTOL * size * max(qd_max, TINY) else 0.0


@njit(**OPTIONS)
def fitted(fractions, a, at, Q, QD, Q_at, QD_at, found_at, Q_on, QD_on, found, LI, LF, LX, phi, psi, Rs):
    """The states Q, Q̇ at ``fractions`` of a step, a span of it from θ = a, moved into
    Q_on, Q̇_on by the projections interpolated (row_fit.interpolate) through those of the
    rows ``at`` (Q_at, Q̇_at, found_at: ``project``'s), each then judged into ``found``
    (``judge``; the rows ``at`` get found_at). Returns how many rows fail the judgement,
    or −1 where a row ``at`` was not projected (nothing written then)."""
    for i in range(at.shape[0]):
        if found_at[i, DONE] == 0.0:
            return -1
    row_fit.interpolate(fractions, a, at, Q, QD, Q_at, QD_at, Q_on, QD_on)
    for i in range(at.shape[0]):
        found[at[i]] = found_at[i]
    judge(Q_on, QD_on, found, at, LI, LF, LX, phi, psi, Rs)
    failed = 0
    for r in range(found.shape[0]):
        failed += found[r, DONE] == 0.0
    return failed


@njit(**OPTIONS)
def _unit_rates(q, qd, kind, start):
    """Each body's quaternion rate u̇ less its part along u, (u·u̇/uᵀu) u: the velocity step's
    own change along u (its unit-norm row uᵀΔu̇ = −uᵀu̇ moves u̇ only there, a direction
    of no mass), made before it, so that the step's right side is the joint rows' alone
    (kernel.motion's REUSED then redoes only the solve)."""
    for i in range(kind.shape[0]):
        if kind[i] == RIGID:
            o = start[i] + 3
            uu = q[o] * q[o] + q[o + 1] * q[o + 1] + q[o + 2] * q[o + 2] + q[o + 3] * q[o + 3]
            f = (q[o] * qd[o] + q[o + 1] * qd[o + 1] + q[o + 2] * qd[o + 2] + q[o + 3] * qd[o + 3]) / uu
            for a in range(4):
                qd[o + a] -= f * q[o + a]


@njit(**OPTIONS)
def _negated(x, out):
    for i in range(x.shape[0]):
        out[i] = -x[i]


class Projection:
    """The kernel's projection: ``rows`` (rows.py) on an Engine's Layout, and ``at_rest``,
    that Engine with no gravity (Engine.at_rest)."""

    energies = True  # Projected holds the kinetic and potential energy of the projected state
    watched = False  # the run's singular watch (analysis/singular_watch.py) does not look at its states
    measure = None  # no measure of how near its rows are to losing rank (extra_projection.py's ``measure``)

    def __init__(self, rows, at_rest):
        self.rows, self.at_rest = rows, at_rest
        self.gen = np.zeros(at_rest.outputs)
        self.arguments = [self._arguments(at_rest.work, (rows.phi, rows.psi, *rows.work))]  # one per thread
        self.lock = threading.Lock()  # Systems that differ in parameters only share it (Engine.at)

    def _arguments(self, packed_work, rows_work):
        """``project``'s arguments after ``found``, for one thread: its Work (packed) and the
        rows' work arrays (φ, φ̇, Rs) its own."""
        n = self.at_rest.n
        work = (*rows_work, np.zeros(rows_work[0].shape), np.zeros(n), np.zeros(n))
        return (*self.rows.packed, self.at_rest.packed[1], *packed_work, self.gen, self.at_rest.general, work)

    def at(self, engine):
        """This projection for ``engine``, a copy of its Engine at other parameter values
        (``Engine.at``): itself, its numbers being the Layout's, which the copy shares."""
        return self

    def rows_at(self, t, q, qd):
        """None: the run's singular watch does not look at its states (``watched``), and reads
        no rows from it (extra_projection.py's ``rows_at``)."""
        return None

    @classmethod
    def build(cls, engine):
        """The Projection on ``engine``'s Layout, or None where its kernel does not cover the System."""
        rows = Rows(engine.L, engine.packed, int(engine.L.sizes[1]))
        return cls(rows, engine.at_rest()) if rows.covers else None

    def __call__(self, t, q, qd):
        """``Projected`` (q, q̇) on the constraints (new arrays) with their rows, or None where
        the kernel declines the state, MAX_STEPS position steps leave φ above MASS_PROJECTION_RTOL, or
        the velocity step leaves φ̇ above MASS_PROJECTION_SHRINK of what it was (and above rounding).
        The kernel's rows do not read the time t (nor ``times`` below: the API of extra_projection.py)."""
        return self.block([t], q[None, :], qd[None, :]).row(0)

    def block(self, times, Q, QD, fractions=None):
        """``__call__`` of each state (row of Q, Q̇), as ProjectedRows. ``fractions``: where
        the states are the rows a step passed, each one's fraction θ of the step (the last
        1, its end): where they are at least row_fit.MIN_ROWS, a few of them are projected
        and the others get the projections interpolated through those (row_fit.py), each
        then judged (``judge``) and projected on its own where it fails."""
        Q, QD = np.ascontiguousarray(Q, dtype=float), np.ascontiguousarray(QD, dtype=float)
        if fractions is None:
            return self._exact(Q, QD)
        rows = ProjectedRows(np.empty(Q.shape), np.empty(QD.shape), np.empty((Q.shape[0], DONE + 1)))
        self._fitted(Q, QD, np.asarray(fractions, dtype=float), 0.0, rows)
        return rows

    def _fitted(self, Q, QD, fractions, a, rows):
        """The states Q, Q̇ at ``fractions``, a span of a step from θ = a (below the first
        fraction: the step's start, on the constraints), projected into ``rows`` by
        row_fit.py (``fitted``): each exactly where they are fewer than row_fit.MIN_ROWS or
        the kernel declines a node; halved where more than row_fit.NODES fail the fit."""
        if Q.shape[0] < row_fit.MIN_ROWS:
            rows.q[:], rows.qd[:], rows.found[:] = self._exact(Q, QD)
            return
        at = row_fit.nodes(fractions, a)
        exact = self._exact(Q[at], QD[at])
        with self.lock:
            failed = fitted(fractions, a, at, Q, QD, *exact, *rows, *self.rows.packed, self.rows.phi, self.rows.psi,
                            self.rows.work[0])
        if failed < 0:  # a node the kernel declined: no interpolant through it
            rows.q[:], rows.qd[:], rows.found[:] = self._exact(Q, QD)
        elif failed > row_fit.NODES:
            half = Q.shape[0] // 2
            self._fitted(Q[:half], QD[:half], fractions[:half], a, rows.part(0, half))
            self._fitted(Q[half:], QD[half:], fractions[half:], fractions[half], rows.part(half, Q.shape[0]))
        elif failed:
            again = np.flatnonzero(rows.found[:, DONE] == 0.0)
            rows.q[again], rows.qd[again], rows.found[again] = self._exact(Q[again], QD[again])

    def _exact(self, Q, QD):
        """Each state (row of Q, Q̇) projected by ``project``, in compiled calls on up to
        threads.THREADS threads (states of PER_THREAD coordinates in all at least each)."""
        count = Q.shape[0]
        Q_on, QD_on, found = np.empty(Q.shape), np.empty(QD.shape), np.empty((count, DONE + 1))
        parts = max(1, min(threads.THREADS, count * Q.shape[1] // PER_THREAD))  # read here: a benchmark may lower it
        if parts == 1:
            with self.lock:
                project(Q, QD, Q_on, QD_on, found, *self.arguments[0])
            return ProjectedRows(Q_on, QD_on, found)
        bounds = [count * k // parts for k in range(parts + 1)]

        def part(k):
            a, b = bounds[k], bounds[k + 1]
            project(Q[a:b], QD[a:b], Q_on[a:b], QD_on[a:b], found[a:b], *self.arguments[k])

        with self.lock:
            while len(self.arguments) < parts:
                self.arguments.append(self._arguments(self.at_rest.new_work()[0], self.rows.new_work(*self.rows.sizes)))
            others = [threads.pool().submit(part, k) for k in range(1, parts)]
            part(0)  # on this thread meanwhile
            for other in others:
                other.result()
        return ProjectedRows(Q_on, QD_on, found)

    def residuals_energy(self, t, q, qd):
        """(φ, φ̇, T, V) at (q, q̇): the System's residuals and its parts' energies."""
        with self.lock:
            phi, psi, kinetic, potential = self.rows(q, qd)[:4]
            return phi.copy(), psi.copy(), kinetic, potential

    def drift(self, t, q, qd):
        """The largest |φ| relative to the largest coordinate (at least 1: a quaternion's
        unit), or |φ̇| relative to the largest rate."""
        with self.lock:
            phi_max, psi_max, q_max, qd_max = self.rows(q, qd)[4:]
        return max(phi_max / max(q_max, 1.0), psi_max / max(qd_max, TINY))
