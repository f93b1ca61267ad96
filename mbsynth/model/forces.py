"""Force elements: forces on the model's coordinates that no single part owns.

Every element is written as a potential V(q, t) and a list of (effort, rate) pairs,
where a rate is linear in the velocities (a joint rate, a spring's lengthening rate, a
point's velocity component) and the effort acts along it. By virtual power its
generalized force is

    Q_e = −∂V/∂q + Σ effort_k ∂rate_k/∂q̇,

added to the parts' Q of (2.1). Dampers use effort = −c·rate; actuators an effort of t.
Gravity is part of each massive part's own Q.

Builders: ``point_spring`` (a linear spring and damper between two points),
``applied_force`` (a force at a point), ``applied_torque`` (a torque on a body).
"""

import numpy as np
import sympy as sp

from .parts.base import Frame, frame_velocity
from .parts.spring import quiet_at_zero_length, spring_damper
from ..core.values import Keyed, freeze
from ..symbolic.cache import placeholder
from ..symbolic.derive import T_SYMBOL, compile_function, generalized_force, placed_values
from ..core.memo import MEMO

AXES = ("world", "body")


class ForceElement(Keyed):
    """A named force element: ``Q`` (sympy, over all the model's coordinates) and its
    potential energy ``V`` (0 for non-conservative elements). ``joint``: the name of the
    joint it acts across (joint_forces.py), whose reaction includes it; None otherwise."""

    def __init__(self, name, V, efforts, q, qd, params, joint=None):
        self.name, self.joint = name, joint
        self._defined_by = (sp.sympify(V), freeze(efforts), tuple(q), tuple(qd))
        self.conservative = all(sp.sympify(effort) == 0 for effort, _ in efforts)  # all of Q from V
        self.efforts = tuple(sp.sympify(effort) for effort, _ in efforts)
        self.V = sp.sympify(V)
        self._Q = Q = generalized_force(self.V, efforts, q, qd)
        used = Q.free_symbols | self.V.free_symbols
        self.indices = np.array([i for i in range(len(q)) if q[i] in used or qd[i] in used or Q[i] != 0], dtype=int)
        local = [int(i) for i in self.indices]
        self._evaluate = compile_function(
            (T_SYMBOL, [q[i] for i in local], [qd[i] for i in local], list(params)),
            [Q.extract(local, [0]), self.V])
        self._power = None  # compiled when first asked (``power``), from:
        self._power_terms = None if self.conservative or self.V == 0 else (
            Q.extract(local, [0]), self.V, [q[i] for i in local], [qd[i] for i in local], list(params))

    @classmethod
    def along_rates(cls, name, efforts, gradients, placed, params, joint=None):
        """Efforts along rates whose ∂/∂q̇ are known in a template's velocity slots (a
        joint's free motions: constraints.joints): ``efforts`` are expressions of t and the
        parameters, ``placed`` = (slots, coordinates, constants, q, q̇) as the joint keeps
        it. Compiled once for every element of the template; Q over the model's symbols is
        built only when asked."""
        slots, coordinates, constants, q, qd = placed
        marks = tuple(placeholder(f"effort{k}") for k in range(len(efforts)))
        column, local = _column(tuple(gradients), marks, slots)
        local = sorted(local, key=coordinates.__getitem__)
        element = cls.__new__(cls)
        element.name, element.joint, element.conservative, element.V = name, joint, False, sp.S.Zero
        element.efforts = tuple(sp.sympify(effort) for effort in efforts)
        element._power = element._power_terms = None
        constants = {**constants, **dict(zip(marks, efforts))}
        element._Q, element._placed = None, (column, slots, coordinates, constants, q, qd)
        element._defined_by = element._placed
        element.indices = np.array([coordinates[j] for j in local], dtype=int)
        element._evaluate = compile_function(
            (T_SYMBOL, [slots[0][j] for j in local], [slots[1][j] for j in local], list(params)),
            [sp.Matrix([column[j] for j in local]), sp.S.Zero], constants=list(constants.items()))
        return element

    def content(self):
        """What defines the element (its equality, ``core.values``): its name, joint and the
        potential and efforts (or the template and values) it was given."""
        return self.name, self.joint, self._defined_by

    @property
    def Q(self):
        """The generalized force over all the model's coordinates (sparse sympy column)."""
        if self._Q is None:
            column, slots, coordinates, constants, q, qd = self._placed
            put = placed_values(slots, coordinates, constants, q, qd)
            self._Q = sp.SparseMatrix(len(q), 1, {(coordinates[j], 0): x.xreplace(put)
                                                   for j, x in enumerate(column) if x != 0})
        return self._Q

    def evaluate(self, t, q, qd, p):
        """Q_e on ``indices`` at the full state (q, qd)."""
        with quiet_at_zero_length():
            return self._evaluate(t, q[self.indices], qd[self.indices], p)[0].ravel()

    @property
    def efforts_only(self):
        """Whether all of Q_e is the efforts' (no potential, not conservative): its power is
        q̇ᵀQ_e, from the values ``evaluate`` gives (evaluation.py sums it over all elements)."""
        return not self.conservative and self._power_terms is None

    def idle_at(self, values):
        """Whether the element's efforts are all identically zero with the parameters at
        ``values`` ({symbol: number}): then it does no work (its power is 0 at every state)
        and is conservative there."""
        return all(effort.xreplace(values).is_zero for effort in self.efforts)

    def power(self, t, q, qd, p):
        """The power q̇ᵀ(Q_e + ∂V/∂q) = Σ effort·rate of the element's efforts at the full
        state: what they add to d(T + V)/dt (0 for a conservative element)."""
        if self.conservative:
            return 0.0
        if self._power_terms is None:  # no potential: all of Q_e is the efforts'
            return float(qd[self.indices] @ self.evaluate(t, q, qd, p))
        if self._power is None:
            self._power = _power_function(*self._power_terms)
        with quiet_at_zero_length():
            return float(self._power(t, q[self.indices], qd[self.indices], p)[0])

    def potential(self, t, q, qd, p):
        return float(self._evaluate(t, q[self.indices], qd[self.indices], p)[1])

    def symbolic(self):
        return self.Q


def _power_function(Q, V, q, qd, params):
    """The compiled Σ q̇_i (Q_i + ∂V/∂q_i) over the element's coordinates ``q``: its
    efforts' power (Q = −∂V/∂q + Σ effort ∂rate/∂q̇, each rate linear in q̇)."""
    power = sum((v * (f + sp.diff(V, x)) for x, v, f in zip(q, qd, Q)), sp.S.Zero)
    return compile_function((T_SYMBOL, q, qd, params), [power])


@MEMO.function(256)
def _column(gradients, marks, slots):
    """(Σ_k mark_k ∂rate_k/∂q̇ per velocity slot, the slots whose coordinate or velocity it
    involves): once per template."""
    column = tuple(sum((m * g[j] for m, g in zip(marks, gradients)), sp.S.Zero) for j in range(len(slots[1])))
    free = set().union(*(x.free_symbols for x in column))
    return column, [j for j in range(len(slots[0])) if column[j] != 0 or slots[0][j] in free or slots[1][j] in free]


def point_spring(name, pA, pB, stiffness, rest_length, damping, q, qd, params):
    """A spring (k, ℓ0) and damper (c) between two world points (sympy 3-vectors of q);
    ``points`` keeps the two ends (the viewer draws the spring between them)."""
    V, efforts = spring_damper(pA, pB, stiffness, rest_length, damping, q, qd)
    element = ForceElement(name, V, efforts, q, qd, params)
    element.points = (pA, pB)  # its ends, for drawing
    return element


def applied_force(name, point, force_world, q, qd, params):
    """A force (world axes; expressions of q, q̇, t) at a world point: Q = (∂v/∂q̇)ᵀ F
    with v = (∂p/∂q) q̇ the point's velocity."""
    velocity = frame_velocity(point, q, qd)
    return ForceElement(name, 0, list(zip(sp.Matrix(force_world), velocity)), q, qd, params)


def applied_torque(name, part, torque, axes, q, qd, params):
    """A torque on ``part`` (a body with a rotation and ``angular_velocity``), in world
    axes or in the part's own axes (then turned to the world by its rotation R):
    Q = (∂ω/∂q̇)ᵀ Γ_world with ω the part's angular velocity in the world."""
    if axes not in AXES:
        raise ValueError(f"axes must be one of {AXES}, got {axes!r}")
    torque = sp.Matrix(torque)
    if axes == "body":
        torque = part.pose(Frame(part.name, "origin", sp.zeros(3, 1), sp.eye(3)))[1] * torque
    return ForceElement(name, 0, list(zip(torque, part.angular_velocity())), q, qd, params)
