"""The kinds of joint between two frames: one record per kind, the one list every floor reads.

A joint holds frame B (on the child) to frame A (on the parent, or the world). Its rows
φ = 0 (holonomic constraints, differentiated twice to the rows of A q̈ = b, (2.4)) are
written as data, each an operation on the world vectors of the two frames, d = p_B − p_A
(``D``) and the axes x_A, y_A, z_A, x_B, y_B, z_B (``XA`` … ``ZB``). The operations are
specified once, in ``OPERATIONS``: each one's φ and φ̇ on the values and velocities of its
two vectors (x, w), the statement every interpreter of a row program computes:

    component (D, k)   φ = d_k                    φ̇ = ḋ_k
    dot (v, w)         φ = v·w                    φ̇ = v̇·w + v·ẇ
    distance (D, D)    φ = (d·d − L²) / 2L        φ̇ = d·ḋ / L         (L the joint's length)

The interpreters: the sympy rows (model/constraints/joints.py: ``joint_equations``, which
evaluates ``OPERATIONS`` itself), the compiled rows over q̈ (compiled/joints.py), the compiled
φ, φ̇ (compiled/rows.py) and the rows in the bodies' rates (compiled/rate_rows.py). Each
names the operations it covers and is refused at import unless that is all of them
(``check_operations``); tests/core/test_joint_kinds.py compares each with ``OPERATIONS`` at
seeded states for every kind.

Beside its rows a kind names its joint values (model/joint_values.py: positions, rates,
accelerations, which positions are angles), whether it turns about z_A and slides along it
(its free motions, which actuation, springs and friction act along: ``EFFORTS``), the rate
friction opposes and the rows that carry the joint's load (model/friction.py), whether the
compiled path takes it (``compiled``, stated for every kind), the URDF joint types read as it
(robots/build.py) and its Pinocchio counterparts (robots/twin.py). ``free`` is no constraint:
the joint values of a floating robot's root (no rows; model files cannot name it).

A consumer that keeps something per kind (the formulas of the joint values, say) keeps it in
a table keyed by kind and calls ``check_table`` at import: a kind it lacks is refused there,
not met silently at use. ``check_kinds`` holds the records against themselves at this
module's import (tests/core/test_joint_kinds.py).
"""

from typing import Callable, NamedTuple


class KindTableError(Exception):
    """A table of joint kinds or row operations that lacks an entry or contradicts itself
    (raised at the import of the module that holds it)."""


def _dot(x, w):
    return sum(a * b for a, b in zip(x, w))  # sympy vectors and numpy arrays alike


class Operation(NamedTuple):
    """One row operation: its ``name``, what its second argument is (``"component"``: an
    index 0-2 of the first vector; ``"vector"``), and ``phi`` (x, w, L) and ``rate``
    (x, ẋ, w, ẇ, L): φ and φ̇ from the two arguments' values and velocities and the joint's
    length (module docstring)."""

    name: str
    second: str
    phi: Callable
    rate: Callable


OPERATIONS = (  # indexed by the codes below
    Operation("component", "component", lambda x, k, L: x[k], lambda x, xd, k, kd, L: xd[k]),
    Operation("dot", "vector", lambda x, w, L: _dot(x, w), lambda x, xd, w, wd, L: _dot(xd, w) + _dot(x, wd)),
    Operation("distance", "vector", lambda x, w, L: (_dot(x, x) - L**2) / (2 * L),
              lambda x, xd, w, wd, L: _dot(x, xd) / L),
)
# a row's operation: its index in OPERATIONS
COMPONENT, DOT, DISTANCE = ([op.name for op in OPERATIONS].index(name) for name in ("component", "dot", "distance"))
D, XA, YA, ZA, XB, YB, ZB = range(7)  # the vectors a row reads (compiled/joints.py adds 7, 8: the origins)


def check_operations(interpreter, covered, operations=OPERATIONS):
    """Refuse (``KindTableError``) an interpreter of row programs that does not cover every
    operation: ``covered`` the codes it evaluates, ``interpreter`` its name for the message."""
    missing = sorted(set(range(len(operations))) - set(covered))
    if missing:
        raise KindTableError(f"{interpreter} does not evaluate the row operation(s) "
                             f"{', '.join(operations[op].name for op in missing)} (core/joint_kinds.OPERATIONS)")
    unknown = sorted(set(covered) - set(range(len(operations))))
    if unknown:
        raise KindTableError(f"{interpreter} names row operation code(s) {unknown}, which OPERATIONS lacks")


class Row(NamedTuple):
    """One row φ = 0 of a joint: its ``label`` (the row's name is ``<joint>[<label>]``) and
    its program (``operation``, ``first`` vector, ``second`` vector or component)."""

    label: str
    operation: int
    first: int
    second: int


COINCIDENT = (Row("x", COMPONENT, D, 0), Row("y", COMPONENT, D, 1), Row("z", COMPONENT, D, 2))  # p_B = p_A
ALIGNED_AXIS = (Row("axis_x", DOT, ZB, XA), Row("axis_y", DOT, ZB, YA))  # z_B ⟂ x_A, y_A
ON_AXIS = (Row("slide_x", DOT, D, XA), Row("slide_y", DOT, D, YA))  # d ⟂ x_A, y_A
# x_A·y_B = y_A·z_B = z_A·x_B = 0: independent near aligned frames (Joint.wrong_branch)
ORIENTATION_LOCK = (Row("rx", DOT, XA, YB), Row("ry", DOT, YA, ZB), Row("rz", DOT, ZA, XB))
CROSS = (Row("cross", DOT, ZA, ZB),)  # z_A ⟂ z_B
LENGTH = (Row("length", DISTANCE, D, D),)  # |d| = L

# what acts along each free motion (model/joint_forces.py)
EFFORTS = {"angle": "torque", "displacement": "force"}


class Pinocchio(NamedTuple):
    """A kind's counterparts in Pinocchio (robots/twin.py): ``tree``, the joint model that
    hangs a body by it (``WELD``: the body joins its parent's joint), and ``loop``, the
    rigid constraint that closes a loop by it (contact type, point offsets along z)."""

    tree: str = None
    loop: tuple = None


WELD = "weld"  # Pinocchio.tree of a fixed joint

class FrictionRate(NamedTuple):
    """Where a kind takes joint friction: the ``rate`` it opposes (a Joint attribute) and the
    labels of the rows whose multipliers are the joint's load (model/friction.py)."""

    rate: str
    load_rows: tuple


class JointKind(NamedTuple):
    """One kind of joint (module docstring)."""

    name: str
    rows: tuple = ()            # Row, in order
    positions: tuple = ()       # joint-value names (model/joint_values.py) ...
    rates: tuple = ()
    accelerations: tuple = ()
    angles: tuple = ()          # per position: an angle (unwrapped along a trajectory)
    matrix_positions: bool = False  # positions from the frames' rotations (not compiled scalars)
    turns: bool = False         # its free motions: ``angle`` about z_A, with ``angle_rate`` ...
    slides: bool = False        # ... ``displacement`` along z_A, with ``displacement_rate``
    friction: FrictionRate = None  # None: takes no friction
    urdf: tuple = ()            # URDF joint types read as this kind
    compiled: bool = None       # whether the compiled path takes it: stated for every kind (``check_kinds``)
    pinocchio: Pinocchio = Pinocchio()  # its Pinocchio counterparts (none: no Pinocchio twin)

    @property
    def program(self):
        """The rows as (operation, first, second), what the compiled kernels read."""
        return tuple(row[1:] for row in self.rows)

    @property
    def labels(self):
        return tuple(row.label for row in self.rows)

    def holds(self, group):
        """Whether the kind has the rows ``group`` (e.g. ORIENTATION_LOCK)."""
        return set(group) <= set(self.rows)

    @property
    def motions(self):
        """The Joint attributes of its free motions: ("angle", "displacement") or part of it."""
        return ("angle",) * self.turns + ("displacement",) * self.slides

    @property
    def limited(self):
        """The joint value a ``limits: [lo, hi]`` bounds (model/unilateral.py): its one free
        motion ("angle" or "displacement"), or None where it has none or two."""
        return self.motions[0] if len(self.motions) == 1 else None

    @property
    def effort(self):
        """What acts along its one free motion (``EFFORTS``: "torque" when it turns, "force"
        when it slides), else None (none, or two: a cylindrical joint's actuation names both)."""
        return EFFORTS[self.motions[0]] if len(self.motions) == 1 else None

    @property
    def has_length(self):
        """Whether its rows read the joint's length L (a distance row)."""
        return any(row.operation == DISTANCE for row in self.rows)


_TURN = dict(positions=("angle",), rates=("rate",), accelerations=("acceleration",), angles=(True,))
_SLIDE = dict(positions=("displacement",), rates=("rate",), accelerations=("acceleration",), angles=(False,))
_SPIN = dict(rates=("wx", "wy", "wz"), accelerations=("wx_dot", "wy_dot", "wz_dot"))

# in the order model files and messages list them; free last
KINDS = {kind.name: kind for kind in (
    JointKind("fixed", COINCIDENT + ORIENTATION_LOCK, urdf=("fixed",), compiled=True,
              pinocchio=Pinocchio(WELD, ("CONTACT_6D", (0.0,)))),
    JointKind("revolute", COINCIDENT + ALIGNED_AXIS, **_TURN, turns=True,
              friction=FrictionRate("angle_rate", ("x", "y", "z")), urdf=("revolute", "continuous"), compiled=True,
              pinocchio=Pinocchio("JointModelRZ", ("CONTACT_3D", (0.0, 1.0)))),
    JointKind("prismatic", ORIENTATION_LOCK + ON_AXIS, **_SLIDE, slides=True,
              friction=FrictionRate("displacement_rate", ("slide_x", "slide_y")), urdf=("prismatic",), compiled=True,
              pinocchio=Pinocchio("JointModelPZ")),
    JointKind("cylindrical", ALIGNED_AXIS + ON_AXIS, positions=("angle", "displacement"),
              rates=("angle_rate", "displacement_rate"),
              accelerations=("angle_acceleration", "displacement_acceleration"), angles=(True, False), turns=True,
              slides=True, compiled=True),
    JointKind("spherical", COINCIDENT, positions=("rx", "ry", "rz"), **_SPIN, angles=(False,) * 3,
              matrix_positions=True, compiled=True, pinocchio=Pinocchio(loop=("CONTACT_3D", (0.0,)))),
    JointKind("universal", COINCIDENT + CROSS, positions=("angle1", "angle2"), rates=("rate1", "rate2"),
              accelerations=("acceleration1", "acceleration2"), angles=(True, True), compiled=True),
    JointKind("distance", LENGTH, compiled=True),
    JointKind("free", (), positions=("x", "y", "z", "qw", "qx", "qy", "qz"),
              rates=("vx", "vy", "vz", *_SPIN["rates"]),
              accelerations=("vx_dot", "vy_dot", "vz_dot", *_SPIN["accelerations"]), angles=(False,) * 7,
              matrix_positions=True, compiled=False),
)}
JOINT_KINDS = tuple(name for name, kind in KINDS.items() if kind.rows)  # what a Joint (and a model file) may be
FRICTION_KINDS = tuple(name for name, kind in KINDS.items() if kind.friction)
MAX_ROWS = max(len(kind.rows) for kind in KINDS.values())
URDF_KINDS = {urdf: kind.name for kind in KINDS.values() for urdf in kind.urdf}  # URDF joint type -> kind


def _row_faults(kind):
    """What is wrong with ``kind``'s rows (an operation or vector out of range), as messages."""
    faults = []
    for row in kind.rows:
        if not 0 <= row.operation < len(OPERATIONS):
            faults.append(f"row {row.label!r} has no operation {row.operation} (OPERATIONS)")
        elif OPERATIONS[row.operation].second == "component" and not (row.first == D and 0 <= row.second < 3):
            faults.append(f"row {row.label!r} takes a component 0-2 of d")
        elif not all(D <= x <= ZB for x in row[2:]):
            faults.append(f"row {row.label!r} reads a vector outside D … ZB")
    return faults


def _kind_faults(name, kind):
    """What ``kind`` (keyed ``name``) lacks or contradicts, as messages (``check_kinds``)."""
    faults = [] if kind.name == name else [f"is named {kind.name!r}"]
    faults += _row_faults(kind)
    if kind.compiled not in (True, False):
        faults.append("does not state whether the compiled path takes it (compiled=True or False)")
    elif kind.compiled and not kind.rows:
        faults.append("is compiled but has no rows")
    if len(set(kind.labels)) != len(kind.rows):
        faults.append("repeats a row label")
    if not len(kind.positions) == len(kind.angles) or not len(kind.rates) == len(kind.accelerations):
        faults.append("needs one angle flag per position and one acceleration per rate")
    if bool(kind.positions) != bool(kind.rates):
        faults.append("has positions without rates, or rates without positions")
    if kind.motions and not kind.rates:
        faults.append("has free motions but no joint values")
    faults += [f"has no effort along its motion {m!r} (EFFORTS)" for m in kind.motions if m not in EFFORTS]
    if kind.friction and (kind.friction.rate not in [f"{m}_rate" for m in kind.motions]
                          or not set(kind.friction.load_rows) <= set(kind.labels)):
        faults.append("takes friction along a rate that is not its free motion's, or on rows it lacks")
    if kind.urdf and len(kind.motions) > 1:
        faults.append("is read from URDF but has more than one free motion")
    if kind.pinocchio.tree is not None and (kind.pinocchio.tree == WELD) != (not kind.motions):
        faults.append("hangs a Pinocchio body by a joint model that does not match its free motions")
    return faults


def check_kinds(kinds):
    """Refuse (``KindTableError``) a table of kinds {name: JointKind} in which a kind lacks
    something every consumer needs or contradicts itself."""
    faults = [f"joint kind {name!r} {fault}" for name, kind in kinds.items() for fault in _kind_faults(name, kind)]
    if faults:
        raise KindTableError("; ".join(faults))


def check_table(consumer, table, kinds=None, agrees=None):
    """Refuse (``KindTableError``) a ``consumer``'s per-kind ``table`` {kind name: entry} that
    lacks a kind of ``kinds`` (by default ``KINDS``) or has a name that is none; ``agrees``
    (record, entry) -> a message or None holds each entry against its kind's record."""
    kinds = KINDS if kinds is None else kinds
    faults = [f"has no entry for the joint kind {name!r}" for name in kinds if name not in table]
    faults += [f"has an entry for {name!r}, which is no joint kind" for name in table if name not in kinds]
    if agrees is not None:
        faults += [f"{name!r}: {message}" for name in kinds if name in table
                   for message in [agrees(kinds[name], table[name])] if message]
    if faults:
        raise KindTableError(f"{consumer}: {'; '.join(faults)} (core/joint_kinds.KINDS)")


check_kinds(KINDS)
