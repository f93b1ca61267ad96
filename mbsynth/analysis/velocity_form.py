"""The integrator's form of a run's state: y = (q, v), v being q̇ with each rigid body's four
quaternion rates u̇ replaced by three numbers, half its body angular velocity:
h = ω/2 = E(u) u̇ / |u|².

An integrator's local error estimate then weighs the body's angular velocity, the physical
rate, directly, not the four u̇ whose second derivative ü carries the unit-norm row's
−|u̇|² u (in that second-order form a spinning body's ω strays past the tolerance: the
tennis-racket flip). h is ω scaled to the size of u̇ (|u̇| = |ω|/2 for a unit u), so the
tolerances weigh a body's rates as they weighed u̇, and an integrator takes about as many
steps. Everything outside the integrator — the
projection onto the constraints, the recorded rows, the drift checks,
Baumgarte, control — keeps (q, q̇); the stages convert here:

- ``to_state`` (y → (q, q̇)): u̇ = E(u)ᵀ h (= ½ u ⊗ (0, ω)), which keeps uᵀu̇ = 0 exactly,
  so the integrated |u| stays constant up to the integration error (the projection or
  projection restores |u| = 1);
- ``to_integrator`` ((q, q̇) → y): h = E(u) u̇ / |u|², half the body angular velocity of the
  unit quaternion u/|u| (ω = 2 E(u) u̇ for a unit u); E(u) E(u)ᵀ = |u|² I makes the round
  trip y → (q, q̇) → y exact in exact arithmetic for any u ≠ 0, and u̇'s component along u,
  which turns nothing, is dropped;
- ``rates`` (ẏ from the motion's q̈): q̇ as above and ḣ = E(u) ü / |u|² (the derivative of
  E(u) u̇ / |u|², as E(u̇) u̇ = 0 and uᵀu̇ = 0).

E(u) = [−u_v, u_w I − [u_v]ₓ] for u = (u_w, u_v) scalar-first, as mbsynth.core.kinematics'
body_rate_matrix. Models without rigid bodies integrate (q, q̇) itself: the conversions are
then views and copies, no per-body work.
"""

import numpy as np
from numba import njit

from ..compiled.bodies import state_of as _state_of, velocities as _velocities


class VelocityForm:
    """The conversions between a run's state (q, q̇) and the integrator's y = (q, v) of
    ``model``: ``size`` entries, 2n less one per rigid body."""

    def __init__(self, model):
        starts, start = [], 0
        for part in model.parts:
            if part.part_type.body_rates:
                starts.append(start + part.part_type.quaternion.start)  # its quaternion (qw, qx, qy, qz)
            start += len(part.coordinates)
        self.n = start
        self.starts = np.array(starts, dtype=np.int64)
        self.size = 2 * self.n - len(starts)
        self.stage = np.empty(2 * self.n)  # ``stage_state``'s array

    def to_integrator(self, q, qd):
        """y = (q, v) of the state (q, q̇)."""
        if not self.starts.size:
            return np.concatenate([q, qd])
        y = np.empty(self.size)
        _integrator_into(np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float), self.starts, y)
        return y

    def state(self, y):
        """(q, q̇) of y stacked in one array of 2n entries (y itself without rigid bodies)."""
        if not self.starts.size:
            return y
        state = np.empty(2 * self.n)  # made here: cheaper than an array a numba function returns
        _state_into(y, self.starts, state)
        return state

    def stage_state(self, y):
        """``state(y)`` in an array of this form's, written over by the next call: for a
        stage's motion, which keeps nothing of it."""
        if not self.starts.size:
            return y
        _state_into(y, self.starts, self.stage)
        return self.stage

    def to_state(self, y):
        """(q, q̇) of y."""
        state = self.state(y)
        return state[:self.n], state[self.n:]

    def states(self, rows):
        """(q, q̇) of y per row of ``rows`` (states stacked, B × size): two B × n arrays,
        C-contiguous."""
        q, qd = np.empty((rows.shape[0], self.n)), np.empty((rows.shape[0], self.n))
        _states_into(rows, self.starts, q, qd)
        return q, qd

    def names(self, coordinates):
        """The names of y's entries, from the model's ``coordinates``: those, then their rates
        (``<coordinate>_dot``), each rigid body's as its angular velocity (``<part>.omega[x]``...)."""
        rates, j = [], 0
        for s in self.starts:
            rates += [f"{c}_dot" for c in coordinates[j:s]]
            part = coordinates[s].rsplit(".", 1)[0]
            rates += [f"{part}.omega[{axis}]" for axis in "xyz"]
            j = s + 4
        return [*coordinates, *rates, *(f"{c}_dot" for c in coordinates[j:])]

    def represents(self, y, q, qd):
        """Whether y converts to exactly (q, q̇)."""
        state = self.state(y)
        return np.array_equal(state[:self.n], q) and np.array_equal(state[self.n:], qd)

    def rates(self, y, state_rates):
        """ẏ at y from ``state_rates`` = (q̇, q̈) stacked, the motion at ``to_state(y)``: a
        view of ``state_rates`` (an array of the caller's, as an integrator's f is), written
        over."""
        if not self.starts.size:
            return state_rates
        _rates_into(y, state_rates, self.starts)
        return state_rates[:self.size]


@njit(cache=True)
def _integrator_into(q, qd, starts, y):
    y[:q.size] = q
    _velocities(q, qd, starts, y[q.size:])


@njit(cache=True)
def _rates_into(y, state_rates, starts):
    """ẏ into the first entries of ``state_rates``: q̇ stays, v̇ is written over q̈."""
    n = state_rates.size // 2
    _velocities(y[:n], state_rates[n:], starts, state_rates[n:])


@njit(cache=True)
def _state_into(y, starts, out):
    """(q, q̇) of y into ``out`` (2n)."""
    n = out.size // 2
    _state_of(y, starts, out[:n], out[n:])


@njit(cache=True)
def _states_into(rows, starts, q, qd):
    for r in range(rows.shape[0]):
        _state_of(rows[r], starts, q[r], qd[r])
