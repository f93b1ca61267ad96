"""What every part shares: its unconstrained M q̈ = Q (2.1) as sympy expressions of its
own coordinates, compiled once; its energies; its named frames."""

import functools
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from ...core.values import Keyed
from ...symbolic.derive import PARAMETERS, T_SYMBOL, compile_function, placed_values

LINK_FRAME = "link"  # the frame a robot link's body carries at the URDF link frame (robots/build.py)

@dataclass(frozen=True)
class Frame:
    """A named frame on a part: ``position`` (sympy 3-vector) and ``rotation`` (3 × 3,
    frame → part axes) relative to the part's own reference, and drawing ``geometry``."""

    part: str
    name: str
    position: sp.Matrix
    rotation: sp.Matrix
    geometry: tuple = field(default=(), compare=False)

    @property
    def label(self):
        return f"{self.part}.{self.name}"

    @functools.cached_property
    def constant_rotation(self):
        """``rotation`` as floats where it is made of real numbers alone (a robot's frames),
        else None (it holds parameters or coordinates): read by every run's branch check."""
        rotation = sp.Matrix(self.rotation)
        try:
            return None if rotation.free_symbols else np.array(rotation, dtype=float)
        except TypeError:  # no real number
            return None


class Part(Keyed):
    """A part given by sympy M, Q, T, V in its own coordinate symbols ``q``, ``qd``
    and the model's parameter symbols ``params``.

    Subclasses describe a type of part: each declares its type's record ``part_type``
    (part_type.py: what code outside the class asks of its type) and provides ``pose(frame)``
    (world position and rotation of a frame), ``angular_velocity()`` (world) and may add
    constraints of its own (``own_constraints``) and initial values (``initial``).
    """

    defaults = {}  # initial coordinate values that are not zero unless the model says otherwise
    # coordinates that move together (a point's x, y, z; a quaternion's four numbers): one
    # scale for all of them in the projection's metric (projection.py); others stand alone
    groups = ()
    # q̇ᵀ Q_nc in the part's symbols: the power of its forces that derive from neither T nor V
    # (dampers, generalized forces); a subclass with such forces sets it before Part.__init__
    power_expression = sp.S.Zero
    # attributes beyond the base's that define a part of a subclass (``content``)
    content_fields = ()
    # the arrays from which one compiled kernel evaluates the part's (2.1) (compiled/flexible.py's
    # PartArrays), or None: its M and Q are sympy expressions compiled per part
    kernel_arrays = None

    def __init__(self, name, coordinates, q, qd, M, Q, T, V, params, frames=(), geometry=(), initial=None,
                 shared=None):
        """``shared``: (q slots, q̇ slots, constants) when M, Q, T, V are a template's,
        written in those slots and in placeholders with the values ``constants`` ((symbol,
        value) pairs): compiled once for all parts alike, put in only when asked. M None: a
        part that evaluates (2.1) and its energies itself (``evaluate``, ``energy``,
        ``power``, ``reads``, ``derivatives``), its sympy M, Q, T, V made by ``reference``
        when first asked."""
        self.name = name
        self.coordinates = tuple(coordinates)
        self.q, self.qd = list(q), list(qd)
        self.frames = {f.name: f for f in frames}
        self.geometry = tuple(geometry)
        self.initial = dict(initial or {})
        if M is None:
            self._symbolic = self._shared = self._evaluate = self._energy = None
            self._defined_by = ()
            return
        template = (_matrix(M), _matrix(Q), sp.sympify(T), sp.sympify(V))
        q_slots, qd_slots, constants = shared or (self.q, self.qd, ())
        self._symbolic = None if shared else template
        self._shared = shared and (template, (q_slots, qd_slots), constants)
        self._defined_by = (template, (q_slots, qd_slots), constants)
        args = (T_SYMBOL, list(q_slots), list(qd_slots), list(params))
        self._evaluate = compile_function(args, template[:2], constants, picked=PARAMETERS)
        self._energy = compile_function(args, template[2:], constants, picked=PARAMETERS)
        self._power, self._power_args = None, (args, constants)  # compiled when first asked (``power``)
        self._reads = None  # the symbols M and Q are written in (``reads``), once asked

    def content(self):
        """What defines the part (its equality, ``core.values``): its names, symbols, frames,
        the expressions of (2.1) it was given and the subclass's ``content_fields``."""
        base = (self.name, self.coordinates, self.q, self.qd, self.frames, self.geometry, self.initial,
                self.groups, self.power_expression, self._defined_by)
        return base + tuple(getattr(self, name) for name in self.content_fields)

    def _materialized(self):
        if self._symbolic is None and not self._shared:
            self._symbolic = tuple(self.reference())
        elif self._symbolic is None:
            template, slots, constants = self._shared
            put = placed_values(slots, range(len(self.q)), constants, self.q, self.qd)
            self._symbolic = tuple(x.xreplace(put) for x in template)
        return self._symbolic

    M = property(lambda self: self._materialized()[0], doc="mass matrix (2.1), sympy")
    Q = property(lambda self: self._materialized()[1], doc="force vector (2.1), sympy")
    T = property(lambda self: self._materialized()[2], doc="kinetic energy, sympy")
    V = property(lambda self: self._materialized()[3], doc="potential energy, sympy")

    @property
    def type_name(self):
        """The name of the part's type (its ``part_type``'s: the ``type:`` a model file gives)."""
        return self.part_type.name

    def reads(self, symbols):
        """Whether M or Q (2.1) is written in any of ``symbols`` (parameter symbols: whether
        new values of them can change this part; ``System.with_parameters``)."""
        if self._reads is None:
            if self._symbolic is None:
                template, _, constants = self._shared
                values = [sp.sympify(value) for _, value in constants]
            else:
                template, values = self._symbolic, []
            self._reads = frozenset().union(*(x.free_symbols for x in (*template[:2], *values)))
        return not self._reads.isdisjoint(symbols)

    def evaluate(self, t, q, qd, p):
        """(M, Q) of this part at its own coordinates q, velocities qd (2.1)."""
        M, Q = self._evaluate(t, q, qd, p)
        return M, Q.ravel()

    def energy(self, t, q, qd, p):
        """(kinetic, potential) energy of this part."""
        T, V = self._energy(t, q, qd, p)
        return float(T), float(V)

    @property
    def working(self):
        """Whether the part's forces beyond T and V can do work (``power`` not identically 0)."""
        return self.power_expression != 0

    def power(self, t, q, qd, p):
        """The power q̇ᵀ Q_nc of the part's forces beyond T and V (``power_expression``) at
        its own coordinates q, velocities qd: what they add to d(T + V)/dt."""
        return float(self.power_function()(t, q, qd, p)[0])

    def power_function(self):
        """The compiled ``power_expression`` of (t, q, q̇, p) at the part's own coordinates,
        made at the first call."""
        if self._power is None:
            args, constants = self._power_args
            expression = self.power_expression
            if self._shared:  # in the template's coordinate slots
                q_slots, qd_slots = self._shared[1]
                expression = sp.sympify(expression).xreplace({**dict(zip(self.q, q_slots)), **dict(zip(self.qd, qd_slots))})
            self._power = compile_function(args, [expression], constants, picked=PARAMETERS)
        return self._power

    def symbolic(self):
        """(M, Q) as sympy matrices of the model's symbols."""
        return self.M, self.Q

    def reference(self):
        """(M, Q, T, V) in sympy of a part that evaluates them itself (``__init__``'s M None)."""
        raise NotImplementedError(f"a {self.kind} part has no sympy form")

    def derivatives(self):
        """The exact Jacobians of M q̈ − Q of a part that evaluates (2.1) itself, as an object
        with analysis/linearization.py's ``BlockFunction.jacobians``; None: derived from its
        sympy M and Q."""
        return None

    def own_constraints(self, q, qd, params):
        """Constraints the part's coordinates always obey (a quaternion's unit norm)."""
        return []

    def pose(self, frame):
        """(position, rotation) of ``frame`` in the world, as sympy expressions."""
        raise NotImplementedError(f"a {self.type_name} part has no frames")

    def frame_position(self, frame):
        """The world position of ``frame`` (``pose``'s first half), as sympy expressions."""
        return self.pose(frame)[0]

    def angular_velocity(self):
        """The part's angular velocity in world axes (zero for point-like parts)."""
        return sp.zeros(3, 1)

    def frame_angular_velocity(self, frame):
        """The world angular velocity of ``frame``: the part's own, for frames fixed on it
        (a flexible body's frames turn with their nodes)."""
        return self.angular_velocity()

    def idle_directions(self, q):
        """Orthonormal columns (over the part's coordinates, at its coordinates ``q``) of
        the directions that move nothing: none for most parts."""
        return np.zeros((len(self.coordinates), 0))


def _matrix(x):
    """``x`` as a sympy matrix; one already (a template shared by all parts alike) as it is."""
    return x if isinstance(x, sp.MatrixBase) else sp.Matrix(x)


def frame_velocity(position, q, qd):
    """d/dt of a world position that depends on q only."""
    return sp.Matrix(position).jacobian(sp.Matrix(q)) * sp.Matrix(qd)

