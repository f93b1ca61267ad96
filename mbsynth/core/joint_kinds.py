"""The kinds of joint between two frames: one record per kind, the one list every floor reads.

A joint holds frame B (on the child) to frame A (on the parent, or the world). Its rows
φ = 0 (holonomic constraints, differentiated twice to the rows of A q̈ = b, (2.4)) are
written as data, each an operation on the world vectors of the two frames, d = p_B − p_A
(``D``) and the axes x_A, y_A, z_A, x_B, y_B, z_B (``XA`` … ``ZB``):

    (COMPONENT, D, k)   φ = d_k
    (DOT, v, w)         φ = v·w
    (DISTANCE, D, D)    φ = (d·d − L²) / 2L          (L the joint's length)

The sympy rows (model/connectors/joints.py: ``joint_equations``) and the compiled rows
(compiled/joints.py: ``joint_rows``; compiled/rate_rows.py) are both read from a kind's
``rows``, in the same order and with the same labels. Beside its rows a kind names its joint
values (model/joint_values.py: positions, rates, accelerations, which positions are angles),
whether it turns about z_A and slides along it (its free motions, which actuation, springs
and friction act along), the rate friction opposes and the rows that carry the joint's load
(model/friction.py), and the URDF joint types read as it (robots/build.py). ``free`` is no
constraint: the joint values of a floating robot's root (no rows; model files cannot name it).

Invariants (tests/core/test_joint_kinds.py): every row reads valid vectors; a kind with values
has one rate and one acceleration name per rate coordinate; friction's rate is one of the
kind's free motions' rates and its load rows are rows of the kind.
"""

from typing import NamedTuple

COMPONENT, DOT, DISTANCE = 0, 1, 2  # a row's operation
D, XA, YA, ZA, XB, YB, ZB = range(7)  # the vectors a row reads (compiled/joints.py adds 7, 8: the origins)


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
    def effort(self):
        """What acts along its one free motion: "torque" (turns), "force" (slides), else None
        (none, or two: a cylindrical joint's actuation names both)."""
        return {("angle",): "torque", ("displacement",): "force"}.get(self.motions)


_TURN = dict(positions=("angle",), rates=("rate",), accelerations=("acceleration",), angles=(True,))
_SLIDE = dict(positions=("displacement",), rates=("rate",), accelerations=("acceleration",), angles=(False,))
_SPIN = dict(rates=("wx", "wy", "wz"), accelerations=("wx_dot", "wy_dot", "wz_dot"))

# in the order model files and messages list them; free last
KINDS = {kind.name: kind for kind in (
    JointKind("fixed", COINCIDENT + ORIENTATION_LOCK, urdf=("fixed",)),
    JointKind("revolute", COINCIDENT + ALIGNED_AXIS, **_TURN, turns=True,
              friction=FrictionRate("angle_rate", ("x", "y", "z")), urdf=("revolute", "continuous")),
    JointKind("prismatic", ORIENTATION_LOCK + ON_AXIS, **_SLIDE, slides=True,
              friction=FrictionRate("displacement_rate", ("slide_x", "slide_y")), urdf=("prismatic",)),
    JointKind("cylindrical", ALIGNED_AXIS + ON_AXIS, positions=("angle", "displacement"),
              rates=("angle_rate", "displacement_rate"),
              accelerations=("angle_acceleration", "displacement_acceleration"), angles=(True, False), turns=True,
              slides=True),
    JointKind("spherical", COINCIDENT, positions=("rx", "ry", "rz"), **_SPIN, angles=(False,) * 3,
              matrix_positions=True),
    JointKind("universal", COINCIDENT + CROSS, positions=("angle1", "angle2"), rates=("rate1", "rate2"),
              accelerations=("acceleration1", "acceleration2"), angles=(True, True)),
    JointKind("distance", LENGTH),
    JointKind("free", (), positions=("x", "y", "z", "qw", "qx", "qy", "qz"),
              rates=("vx", "vy", "vz", *_SPIN["rates"]),
              accelerations=("vx_dot", "vy_dot", "vz_dot", *_SPIN["accelerations"]), angles=(False,) * 7,
              matrix_positions=True),
)}
JOINT_KINDS = tuple(name for name, kind in KINDS.items() if kind.rows)  # what a Joint (and a model file) may be
FRICTION_KINDS = tuple(name for name, kind in KINDS.items() if kind.friction)
MAX_ROWS = max(len(kind.rows) for kind in KINDS.values())
URDF_KINDS = {urdf: kind.name for kind in KINDS.values() for urdf in kind.urdf}  # URDF joint type -> kind
