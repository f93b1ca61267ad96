"""The record of a type of part: what every floor asks of a part's type, in one place.

Each part class (model/parts/<type>.py) declares its ``PartType`` beside it as the class
attribute ``part_type``; ``Part.type_name`` is the record's ``name``, and ``PART_TYPES``
(model/parts/__init__.py) gathers them. Code outside a part's class asks its type questions
by reading ``part.part_type``, never by comparing ``part.type_name`` with a name or testing its
class. Every field is required (no defaults): a record that leaves a question open fails at
import. The class itself answers what needs its symbols: ``pose(frame)`` (a frame's world
pose from the coordinates), ``angular_velocity``, ``own_constraints``, M and Q (2.1).

Floors: compiled/ sits below model/ and reads ``part.part_type.node`` as an attribute (it
imports nothing of model/); io/ and view/ sit above and read the records. How a model file
names and reads a part (its ``type:`` value, its reader, its schema section) is io/'s: one
``FileType`` record per model-file type in io/part_types.py, naming the part types it builds
(``rigid_body`` builds a RigidBody, or an EulerBody with ``rotation:``; ``robot`` one rigid
body per link; ``solid`` a RigidBody whose mass and inertia come from its shape). A new kind
of dynamics is a part module here and its line in PART_TYPES; a new way to write a part in
a model file is a module in io/ and its line in io/part_types.py FILE_TYPES.
"""

from typing import NamedTuple

from ...compiled.nodes import EXTRA_NODE, PARTICLE_NODE, RIGID_NODE

# how a part's coordinates turn it (``orientation``)
QUATERNION = "quaternion"  # a unit quaternion among its coordinates (``quaternion``)
ANGLES = "angles"          # three angles of an intrinsic sequence (singular somewhere: angle_singularity.py)
PLANE = "plane"            # an angle about the world's z axis (a body in the xy plane)
POINT = "point"            # none: its frames are points (a particle, a spring's ends)
OWN = "own"                # coordinates of its own meaning (a part given by its energies): no pose to move

# how the viewer draws a part without geometry of its own (view/scene.py)
BODY = "body"      # a sphere at its centre of mass, rods to its frames
SPHERE = "sphere"  # a sphere sized by its mass
FRAMES = "frames"  # a small sphere at each of its frames
LINE = "line"      # the line between its frames ``end1`` and ``end2``
FE_MESH = "mesh"   # its deformed finite-element mesh, node to node

NODES = (RIGID_NODE, PARTICLE_NODE, EXTRA_NODE)
ORIENTATIONS = (QUATERNION, ANGLES, PLANE, POINT, OWN)
DRAWINGS = (BODY, SPHERE, FRAMES, LINE, FE_MESH)


class PartType(NamedTuple):
    """One type of part (module docstring).

    ``node``: what the compiled path makes of it (compiled/layout.py): a rigid-body node
    (``mass``, ``inertia`` about the centre of mass, ``gravity``, coordinates x, y, z and a
    unit quaternion), a particle node (M = m I₃), or extra coordinates of the kernel's Schur
    system. ``orientation``: how its coordinates turn it (the constants above).
    ``quaternion``: the slice of its coordinates that is its unit quaternion, or None.
    ``points``: the triples of its coordinates that are world points (moved by a placement).
    ``elastic``: it has elastic coordinates, the slice ``part.elastic`` (held by statics, drawn
    scaled, shown as node shapes by modes). ``body_rates``: the integrator carries its body
    angular velocity instead of its quaternion rates (analysis/velocity_form.py).
    ``origin``: a frame reference may name the part alone (its own origin and axes).
    ``shared_pose``: its frames' poses depend on its coordinates alone, so joints on it share
    derivations (model/joint_templates.py). ``drawing``: how it is drawn without geometry."""

    name: str
    node: str
    orientation: str
    quaternion: slice | None
    points: tuple
    elastic: bool
    body_rates: bool
    origin: bool
    shared_pose: bool
    drawing: str

    @property
    def rigid(self):
        """Whether it turns as one rigid piece (an orientation and no elastic coordinates)."""
        return self.orientation in (QUATERNION, ANGLES, PLANE) and not self.elastic


def check(part_type):
    """``part_type``, its fields checked against the values above (ValueError otherwise)."""
    for field, allowed in (("node", NODES), ("orientation", ORIENTATIONS), ("drawing", DRAWINGS)):
        if getattr(part_type, field) not in allowed:
            raise ValueError(f"part type {part_type.name!r}: {field} {getattr(part_type, field)!r} is not one of "
                             f"{', '.join(allowed)}")
    if (part_type.quaternion is not None) != (part_type.orientation == QUATERNION):
        raise ValueError(f"part type {part_type.name!r}: a quaternion slice goes with orientation {QUATERNION!r}")
    return part_type
