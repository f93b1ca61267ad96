"""The keys of a model file: one source of truth for the loader and the reference.

Each ``Section`` is one kind of mapping a model file holds (the top level, a part of a
given ``type``, a joint, a force element, ...) and lists every key it takes with its
type, default, meaning and an example. The loader checks a mapping against its section
(``_Builder.section``: unknown keys and missing required keys, with the file and line);
the documentation's model-file reference is generated from ``SECTIONS``. Mappings whose
keys are the model's own names (parameters, coordinates, frames, outputs) are described in
their section's text and checked by the loader against those names.
"""

from dataclasses import dataclass

from ..core.joint_kinds import JOINT_KINDS


@dataclass(frozen=True)
class Key:
    """One key of a section: ``type`` and ``meaning`` in words, ``example`` in YAML,
    ``default`` (None when the key is required or has no default)."""

    name: str
    type: str
    meaning: str
    example: str
    default: str | None = None
    required: bool = False


@dataclass(frozen=True)
class Section:
    """A kind of mapping: ``name`` (its id), ``where`` it sits in a file, its ``keys``."""

    name: str
    where: str
    text: str
    keys: tuple

    @property
    def allowed(self):
        """The names of every key the section takes."""
        return {key.name for key in self.keys}

    @property
    def required(self):
        """The names of the keys that must be given, in the order they are checked."""
        return tuple(key.name for key in self.keys if key.required)


def _required(name, type_, meaning, example):
    return Key(name, type_, meaning, example, required=True)


_EXPR = "expression of parameters"
_EXPRS = "expressions of parameters"
_TYPE = {  # the ``type`` key of a part; its value selects the section
    "lagrangian": "part given by its kinetic and potential energies",
    "rigid_body": "rigid body in space (position and unit quaternion)",
    "particle": "point mass in space",
    "planar_body": "rigid body in the xy plane",
    "spring": "spring (with optional mass) between two free ends",
    "robot": "a whole robot from a URDF, one rigid body per link",
    "flexible_body": "a reduced finite-element body on a floating frame (docs/flexible.md)",
    "model": "another model file as a substructure, its names prefixed by the entry's (docs/substructures.md)",
}
_DESCRIPTION = Key("description", "string", "free text, ignored by the loader", "'the left wheel'")
_NAME = Key("name", "plain name", "the element's name in reports", "spring_1", default="<type>_<index>")
_FRAMES = Key("frames", "mapping name → frame", "named frames on the part (section *frame*)",
              "{tip: {position: [0, 0, -L]}}")
_GEOMETRY = Key("geometry", "shape or list of shapes", "what the viewer draws (section *geometry*)",
                "{box: [0.2, 0.1, 0.1], color: blue}")
_POSITION = Key("position", "list of 3 expressions of parameters", "origin of the frame in the part's "
                "axes", "[0, 0, -L]", default="[0, 0, 0]")
_ORIENTATION = (
    Key("rpy", "list of 3 expressions of parameters", "orientation as roll, pitch, yaw (URDF: "
        "Rz(yaw) Ry(pitch) Rx(roll)); at most one of rpy, axis, quaternion", "[0, 0, pi/2]",
        default="identity"),
    Key("axis", "list of 3 expressions of parameters", "orientation with z along this vector", "[1, 0, 0]",
        default="identity"),
    Key("quaternion", "list of 4 expressions of parameters", "orientation as a unit quaternion (w, x, y, z)",
        "[1, 0, 0, 0]", default="identity"),
)
_TYPE_KEY = {kind: _required("type", "string", f"``{kind}``: {meaning}", kind) for kind, meaning in _TYPE.items()}
_MASS = _required("mass", _EXPR + ", ≥ 0", "mass [kg]; zero is allowed (a massless part)", "m")
_BETWEEN = _required("between", "list of 2 frames", "the two frames joined (at most one on the world)",
                     "[body.tip, world.anchor]")
_ROTATION = Key("rotation", "string", "``quaternion``, or an intrinsic angle sequence: three different "
               "axes (xyz, xzy, yxz, yzx, zxy, zyx) or proper Euler (xyx, xzx, yxy, yzy, zxz, zyz)", "zxy",
               default="quaternion")
_FORCE_KEYS = (_NAME, Key("type", "string", "the kind of force element", "spring", required=True), _DESCRIPTION)
# the keys a part type's section written in the type's own module (io/solid.py) shares with those here
SHARED_KEYS = {key.name: key for key in (_DESCRIPTION, _FRAMES, _GEOMETRY)}

SECTIONS = {section.name: section for section in (
    Section("model", "the top level of a model file",
            "A model file is one mapping. Only ``parts`` is required. A key under its old name is read "
            "as the key: ``subsystems`` (old name of ``parts``), ``closure`` (old name of ``balances``).",
            (Key("name", "string", "the model's name", "example1_wheel", default="the file name"),
             _DESCRIPTION,
             Key("parameters", "mapping name → expression", "named constants; each may use those before it",
                 "{m: 2.0, R: 0.3, I: 0.5*m*R**2}", default="{}"),
             Key("gravity", "list of 3 " + _EXPRS, "gravitational acceleration acting on rigid bodies, "
                 "particles, planar bodies, spring masses and flexible bodies [m/s²]", "[0, 0, -g]", default="[0, 0, 0]"),
             Key("world", "mapping (section *world*)", "frames fixed in the world", "{frames: {pin: {}}}"),
             _required("parts", "mapping name → part", "the parts, each with a ``type`` whose section "
                       "below lists its keys (e.g. *rigid_body*; *model_part* for another model file)",
                       "{wheel: {type: particle, mass: m}}"),
             Key("constraints", "list of constraints (section *constraint*)",
                 "constraints written as equations in the parts' coordinates", "[{holonomic: a.x - b.x}]",
                 default="[]"),
             Key("joints", "list of joints (sections *joint*, *rolling_disk*, *knife_edge*)",
                 "joints between named frames and ground contacts", "[{name: pin, type: revolute, parent: world, child: link.top}]",
                 default="[]"),
             Key("contacts", "list of contacts (sections *contact_plane*, *contact_spheres*)",
                 "unilateral contacts that strike, rest and lift off (docs/guide.md, impacts)",
                 "[{name: floor, type: plane, child: ball, radius: r, restitution: 0.8}]", default="[]"),
             Key("balances", "``auto`` or ``none``", "``auto`` appends the force balance of each massless "
                 "part whose motion the model leaves open (model/balances.py)", "auto", default="none"),
             Key("initial", "mapping coordinate → " + _EXPR, "initial values by coordinate name "
                 "(``part.c``, velocities ``part.c_dot``)", "{wheel.theta: 0.0, wheel.theta_dot: 1.0}",
                 default="0 (orientations: identity)"),
             Key("initial_fixed", "list of names from ``initial``", "initial values kept exactly when the "
                 "state is made consistent with the constraints", "[wheel.theta]", default="[]"),
             Key("forces", "list of force elements (sections *force_spring*, *force_damper*, *force_force*, *force_torque*)", "springs, dampers, forces and "
                 "torques between frames", "[{type: spring, between: [a.tip, world], stiffness: k, rest_length: 0.3}]", default="[]"),
             Key("outputs", "mapping name → expression or output (section *output*)",
                 "quantities recorded along a run", "{height: body.z, pin_force: {reaction: pin.force}}",
                 default="{}"),
             Key("ports", "mapping name → frame", "frames a file that includes this one joins to as "
                 "``<entry>.<port>`` (docs/substructures.md)", "{hip: pelvis.hip}", default="{}"))),
    Section("model_part", "``parts: {NAME: {type: model, ...}}``",
            "Another model file as a substructure: its parts, joints, constraints, forces, outputs, "
            "initial values and parameters join the model, every name prefixed by the entry's "
            "(``NAME.thigh``, ``NAME.thigh.x``, ``NAME.L``; copies ``NAME[0]`` …). Its ``gravity`` "
            "and ``name`` are the including model's.",
            (_TYPE_KEY["model"],
             _required("file", "file name", "the model file, relative to this one", "leg.yaml"),
             Key("parameters", "mapping name → " + _EXPR, "values of the file's parameters, as expressions "
                 "of this file's (and ``index``)", "{L: 0.4, m: m_leg}", default="the file's own"),
             Key("placement", "mapping (section *placement*)", "a rigid transform of the whole file: its "
                 "world frames and its parts' initial poses and velocities", "{position: [0, 0.2, 0]}",
                 default="identity"),
             Key("count", "expression of parameters, a whole number ≥ 1", "copies ``NAME[0]`` … "
                 "``NAME[count-1]``; ``index`` is each copy's number in ``parameters`` and ``placement`` (so "
                 "this file may have no parameter named ``index``)",
                 "N", default="one copy, named NAME"),
             _DESCRIPTION)),
    Section("placement", "``placement:`` of a ``type: model`` entry",
            "Where the included file's axes sit in this file's: a position and at most one "
            "orientation key (expressions may use ``index``). Placements compose through nesting; a placed "
            "body's quaternion keeps qw ≥ 0, as an orientation a file gives does.",
            (Key("position", "list of 3 " + _EXPRS, "the origin of the file's axes", "[index*L, 0, 0]",
                 default="[0, 0, 0]"),
             *_ORIENTATION)),
    Section("world", "``world:``", "The world's own frames (joints and springs may attach to them).",
            (Key("frames", "mapping name → frame", "named frames fixed in the world (section *frame*)",
                 "{anchor: {position: [0, 0, 1]}}", default="{}"),)),
    Section("frame", "each entry of a ``frames:`` mapping (parts and world)",
            "A frame fixed on a part, at ``position`` in the part's axes, turned by at most one "
            "orientation key. On a lagrangian part the position may use its coordinates.",
            (_POSITION, Key("geometry", "shape or list of shapes", "what the viewer draws at the frame",
                            "{sphere: 0.05}"), *_ORIENTATION)),
    Section("lagrangian", "``parts: {NAME: {type: lagrangian, ...}}``",
            "A part in its own coordinates, with M and Q derived from Lagrange's equations. Expressions "
            "use the parameters, ``t``, the coordinates and their velocities (``c_dot``).",
            (_TYPE_KEY["lagrangian"],
             _required("coordinates", "list of names", "the part's coordinates (not ending in ``_dot``)",
                       "[theta, y]"),
             _required("T", "expression", "kinetic energy", "0.5*m*(R*theta_dot)**2"),
             Key("V", "expression of coordinates (no velocities)", "potential energy", "-m*g*y", default="0"),
             Key("forces", "mapping coordinate → expression", "generalized forces not derived from V",
                 "{theta: -c*theta_dot}", default="{}"),
             _FRAMES, _GEOMETRY, _DESCRIPTION)),
    Section("rigid_body", "``parts: {NAME: {type: rigid_body, ...}}``",
            "A rigid body in space: coordinates x, y, z and the unit quaternion qw, qx, qy, qz; with "
            "``rotation: zxy`` (or another intrinsic sequence) three angles instead, ``angle_z``, "
            "``angle_x``, ``angle_y``, of turns about the body's axes in that order (``angle_z2`` for a "
            "second turn about z, as in zxz); a wheel's spin axis last makes its spin angle cyclic, for "
            "steady motions.",
            (_TYPE_KEY["rigid_body"], _MASS,
             _required("inertia", "list of 3, or 3 × 3 list, of " + _EXPRS,
                       "principal moments [Ixx, Iyy, Izz] or the inertia matrix about the centre of mass",
                       "[0.1, 0.1, 0.2]"),
             _ROTATION, _FRAMES, _GEOMETRY,
             Key("initial", "mapping (section *initial_rigid_body*)", "initial pose and velocities",
                 "{position: [0, 0, 1]}", default="at rest at the origin"), _DESCRIPTION)),
    Section("particle", "``parts: {NAME: {type: particle, ...}}``",
            "A point mass in space: coordinates x, y, z. Its frames cannot be offset.",
            (_TYPE_KEY["particle"], _MASS, _FRAMES, _GEOMETRY,
             Key("initial", "mapping (section *initial_particle*)", "initial position and velocity",
                 "{position: [1, 0, 0]}", default="at rest at the origin"), _DESCRIPTION)),
    Section("planar_body", "``parts: {NAME: {type: planar_body, ...}}``",
            "A rigid body moving in the xy plane: coordinates x, y, theta.",
            (_TYPE_KEY["planar_body"], _MASS,
             _required("inertia", _EXPR + ", ≥ 0", "moment of inertia I_zz about the centre of mass", "0.02"),
             _FRAMES, _GEOMETRY,
             Key("initial", "mapping (section *initial_planar_body*)", "initial pose and velocities",
                 "{position: [0, 1], theta: 0.3}", default="at rest at the origin"), _DESCRIPTION)),
    Section("spring", "``parts: {NAME: {type: spring, ...}}``",
            "A spring part with two free ends, frames ``end1`` and ``end2`` (coordinates x1, y1, z1, x2, y2, z2); "
            "with mass, the uniform bar's consistent mass matrix and half its weight on each end.",
            (_TYPE_KEY["spring"],
             _required("stiffness", _EXPR + ", ≥ 0", "stiffness [N/m]", "k"),
             _required("rest_length", _EXPR + ", ≥ 0", "unstretched length [m]", "0.5"),
             Key("damping", _EXPR + ", ≥ 0", "damping [N s/m]", "0.1", default="0"),
             Key("mass", _EXPR + ", ≥ 0", "mass [kg]", "0.2", default="0"),
             Key("initial", "mapping (section *initial_spring*)", "initial positions and velocities of the ends",
                 "{end1: [0, 0, 0], end2: [0.5, 0, 0]}", default="at rest at the origin"), _DESCRIPTION)),
    Section("robot", "``parts: {NAME: {type: robot, ...}}``",
            "A whole robot: one rigid body per link (``NAME_<link>``), one joint per URDF joint "
            "(``NAME_<joint>``) and a torque parameter ``tau_NAME_<joint>`` per movable joint.",
            (_TYPE_KEY["robot"],
             _required("robot", "string", "an example-robot-data name (``mbsynth robots``) or a URDF file "
                       "relative to the model file", "ur5"),
             Key("floating", "boolean", "a free-floating base instead of one welded to the world", "true",
                 default="false"),
             Key("base", "mapping (section *pose*)", "pose of the root link (the initial pose when floating)",
                 "{position: [0, 0, 0.5]}", default="the world's origin"),
             Key("initial", "mapping URDF joint name → " + _EXPR, "initial position of each movable joint "
                 "[rad or m]: the links start where the URDF's kinematics puts them", "{elbow_joint: 0.5}",
                 default="0 for every joint"),
             Key("merge_fixed", "boolean", "merge each link on a fixed joint into its nearest ancestor on a "
                 "movable joint (fewer bodies, the same joint motion); ``NAME_<link>`` then names a frame of "
                 "that ancestor's body", "true", default="false"), _DESCRIPTION)),
    Section("flexible_body", "``parts: {NAME: {type: flexible_body, ...}}``",
            "A flexible body: a finite-element model (``beam`` or ``fe``, exactly one) reduced to a few "
            "coordinates, on a floating frame. Coordinates x, y, z (the frame's origin, which is the FE "
            "model's origin), the unit quaternion qw, qx, qy, qz of its axes (with ``rotation: zxy`` or "
            "another intrinsic sequence three angles instead, as a rigid body's: the spin axis last makes a "
            "spinning part's spin angle cyclic, for ``modes --steady`` and Campbell diagrams) and the reduced "
            "coordinates eta1, eta2, …; every interface node is a frame ``node_<index>``, whose pose follows "
            "the node's elastic displacement and rotation.",
            (_TYPE_KEY["flexible_body"],
             Key("beam", "mapping (section *flexible_beam*)", "a straight beam from the built-in generator",
                 "{length: 1.0, elements: 20, area: 1e-4, Iy: 1e-9, Iz: 1e-9, J: 2e-9, E: 2.1e11, nu: 0.3, "
                 "density: 7850}"),
             Key("fe", "mapping (section *flexible_fe*)", "an FE model's mass and stiffness matrices and nodes "
                 "from files", "{bundle: rod.npz}"),
             _required("reduction", "mapping (section *flexible_reduction*)", "how the FE model is reduced",
                       "{method: craig_bampton, interface: [0, 20], modes: 4}"),
             Key("damping", "mapping (section *flexible_damping*)", "structural damping of the reduced "
                 "coordinates", "{modal: 0.02}", default="none"),
             Key("stiffening", "true or false", "centrifugal stiffening of a spinning part: the geometric "
                 "stiffness of the spin's member forces (beam parts; docs/flexible.md)", "true", default="false"),
             _ROTATION,
             Key("frames", "mapping name → node frame (section *flexible_frame*)", "named frames at FE nodes, "
                 "besides the interface nodes' ``node_<index>``", "{tip: {node: 20}}", default="{}"),
             _GEOMETRY,
             Key("initial", "mapping (section *initial_flexible_body*)", "initial pose, velocities and "
                 "amplitudes", "{position: [0, 0, 1]}", default="at rest at the origin, undeformed"),
             _DESCRIPTION)),
    Section("flexible_beam", "``beam:`` of a flexible_body",
            "A uniform straight beam of two-node elements (6 DOFs per node) from the origin along ``axis``: "
            "node 0 at the origin, node ``elements`` at the far end. Give exactly one of G and nu.",
            (_required("length", _EXPR + ", > 0", "length [m]", "1.0"),
             _required("elements", "integer ≥ 1", "number of elements", "20"),
             _required("area", _EXPR + ", > 0", "cross-section area [m²]", "1e-4"),
             _required("Iy", _EXPR + ", > 0", "second moment about the section's y axis [m⁴] (bending in "
                       "the x–z plane)", "1e-9"),
             _required("Iz", _EXPR + ", > 0", "second moment about the section's z axis [m⁴] (bending in "
                       "the x–y plane)", "1e-9"),
             _required("J", _EXPR + ", > 0", "torsion constant [m⁴]", "2e-9"),
             _required("E", _EXPR + ", > 0", "Young's modulus [Pa]", "2.1e11"),
             _required("density", _EXPR + ", > 0", "density [kg/m³]", "7850"),
             Key("G", _EXPR + ", > 0", "shear modulus [Pa]", "8.1e10"),
             Key("nu", _EXPR, "Poisson's ratio (G = E / 2(1 + ν))", "0.3"),
             Key("shear_factor", _EXPR + ", > 0", "Timoshenko's shear factor κ (timoshenko only)", "0.8333"),
             Key("theory", "string", "``euler_bernoulli`` or ``timoshenko``", "timoshenko",
                 default="euler_bernoulli"),
             Key("mass", "string", "``consistent`` or ``lumped`` (nothing on rotations: M singular)", "lumped",
                 default="consistent"),
             Key("axis", "list of 3 " + _EXPRS, "the beam's direction (the section's x axis)", "[1, 0, 0]",
                 default="[1, 0, 0]"),
             Key("up", "list of 3 " + _EXPRS, "the section's z axis (made normal to axis)", "[0, 0, 1]",
                 default="[0, 0, 1]"))),
    Section("flexible_fe", "``fe:`` of a flexible_body",
            "FE matrices from files relative to the model file: one ``bundle`` (.npz with nodes, mass, "
            "stiffness) or all three of mass, stiffness, nodes (Matrix Market .mtx or .npz; nodes also "
            ".csv or .txt). DOFs node by node, 6 (ux uy uz θx θy θz) or 3 per node.",
            (Key("bundle", "file name", "an .npz holding nodes, mass and stiffness", "rod.npz"),
             Key("mass", "file name", "the mass matrix", "rod_M.mtx"),
             Key("stiffness", "file name", "the stiffness matrix", "rod_K.mtx"),
             Key("nodes", "file name", "the node coordinates (N × 3)", "rod_nodes.csv"),
             Key("dofs_per_node", "3 or 6", "DOFs per node", "6", default="n / N"))),
    Section("flexible_reduction", "``reduction:`` of a flexible_body",
            "Exactly one of modes and max_frequency. Craig–Bampton's coordinates are the interface nodes' "
            "DOFs (6 each, but the reference node's, held at the part's frame) and the fixed-interface modes; "
            "free-interface modes are those of the free model, without its rigid-body modes.",
            (_required("method", "string", "``craig_bampton`` or ``free_interface``", "craig_bampton"),
             Key("interface", "list of node indices", "the nodes joints attach to (each a frame "
                 "``node_<index>``)", "[0, 20]", default="[]"),
             Key("modes", "integer ≥ 0", "number of (fixed-interface or free) normal modes", "4"),
             Key("max_frequency", _EXPR + ", ≥ 0", "every normal mode up to this frequency [Hz]", "500"),
             Key("reference", "node index", "Craig–Bampton: the interface node that moves with the part's frame",
                 "0", default="the first interface node"))),
    Section("flexible_damping", "``damping:`` of a flexible_body", "Exactly one key.",
            (Key("rayleigh", "list of 2 " + _EXPRS + ", ≥ 0", "[α, β]: D = α M_r + β K_r", "[0.0, 1e-4]"),
             Key("modal", _EXPR + ", ≥ 0", "one damping ratio ζ for every mode of the reduced model with its "
                 "frame held", "0.02"))),
    Section("flexible_frame", "each entry of ``frames:`` of a flexible_body",
            "A frame at an FE node, turned by at most one orientation key; it moves with the node. A "
            "``line`` in its geometry may run to another frame of the part: lines between frames along "
            "the body draw it deformed.",
            (_required("node", "node index", "the FE node", "20"),
             Key("geometry", "shape or list of shapes", "what the viewer draws at the frame", "{sphere: 0.01}"),
             *_ORIENTATION)),
    Section("initial_flexible_body", "``initial:`` of a flexible_body",
            "The frame's origin and axes as a rigid body's (velocities in world axes), and the reduced "
            "coordinates.",
            (Key("position", "list of 3 " + _EXPRS, "position of the frame's origin", "[0, 0, 1]",
                 default="[0, 0, 0]"),
             Key("velocity", "list of 3 " + _EXPRS, "velocity of the frame's origin", "[1, 0, 0]",
                 default="[0, 0, 0]"),
             Key("angular_velocity", "list of 3 " + _EXPRS, "angular velocity (world axes)", "[0, 0, 2]",
                 default="[0, 0, 0]"), *_ORIENTATION,
             Key("amplitudes", "list of " + _EXPRS, "eta1, eta2, … (one per reduced coordinate)", "[0.001]",
                 default="zeros"),
             Key("amplitude_rates", "list of " + _EXPRS, "their rates", "[0.0]", default="zeros"))),
    Section("initial_rigid_body", "``initial:`` of a rigid_body",
            "Velocities are in world axes.",
            (Key("position", "list of 3 " + _EXPRS, "position of the centre of mass", "[0, 0, 1]",
                 default="[0, 0, 0]"),
             Key("velocity", "list of 3 " + _EXPRS, "velocity of the centre of mass", "[1, 0, 0]",
                 default="[0, 0, 0]"),
             Key("angular_velocity", "list of 3 " + _EXPRS, "angular velocity (world axes)", "[0, 0, 2]",
                 default="[0, 0, 0]"), *_ORIENTATION)),
    Section("initial_particle", "``initial:`` of a particle", "",
            (Key("position", "list of 3 " + _EXPRS, "position", "[1, 0, 0]", default="[0, 0, 0]"),
             Key("velocity", "list of 3 " + _EXPRS, "velocity", "[0, 1, 0]", default="[0, 0, 0]"))),
    Section("initial_planar_body", "``initial:`` of a planar_body", "",
            (Key("position", "list of 2 " + _EXPRS, "position of the centre of mass", "[0, 1]", default="[0, 0]"),
             Key("theta", _EXPR, "angle [rad]", "0.3", default="0"),
             Key("velocity", "list of 2 " + _EXPRS, "velocity of the centre of mass", "[1, 0]", default="[0, 0]"),
             Key("angular_velocity", _EXPR, "angular velocity [rad/s]", "2.0", default="0"))),
    Section("initial_spring", "``initial:`` of a spring part", "",
            tuple(Key(key, "list of 3 " + _EXPRS, f"{key.replace('_', ' ')} of the end", example,
                      default="[0, 0, 0]")
                  for key, example in (("end1", "[0, 0, 0]"), ("end2", "[0.5, 0, 0]"),
                                       ("end1_velocity", "[0, 0, 0]"), ("end2_velocity", "[0, 1, 0]")))),
    Section("pose", "``base:`` of a robot and ``origin:`` of a shape",
            "A position and at most one orientation key.",
            (Key("position", "list of 3 " + _EXPRS, "position", "[0, 0, 0.5]", default="[0, 0, 0]"),
             *_ORIENTATION)),
    Section("geometry", "``geometry:`` of a part or frame (one shape or a list)",
            "Exactly one of box, sphere, cylinder, capsule, mesh, line per shape. A ``line`` "
            "(on a frame) runs to another frame of the same part and takes only ``color``.",
            (Key("box", "list of 3 " + _EXPRS, "box sizes along x, y, z", "[0.2, 0.1, 0.1]"),
             Key("sphere", _EXPR, "sphere radius", "0.05"),
             Key("cylinder", "list of 2 " + _EXPRS, "[radius, length] along z", "[0.02, 0.5]"),
             Key("capsule", "list of 2 " + _EXPRS, "[radius, length] along z", "[0.02, 0.5]"),
             Key("mesh", "file name", "an .stl, .obj or .dae file, relative to the model file", "meshes/arm.stl"),
             Key("line", "frame name", "another frame of the same part: a line drawn between the two", "tip"),
             Key("color", "colour name or [r, g, b(, a)] in 0..1", "the shape's colour "
                 "(red, green, blue, grey, black, white, orange, yellow, purple)", "blue", default="grey"),
             Key("origin", "mapping (section *pose*)", "the shape's pose in the frame", "{position: [0, 0, 0.1]}",
                 default="the frame's origin"),
             Key("scale", "list of 3 " + _EXPRS, "scale of a mesh", "[0.001, 0.001, 0.001]", default="[1, 1, 1]"))),
    Section("constraint", "each entry of ``constraints:``",
            "Exactly one of holonomic, nonholonomic, acceleration. Expressions use the parameters, "
            "``t``, the coordinates ``part.c``, velocities ``part.c_dot`` and joint values "
            "(``joint.angle``, ...). ``C`` maps coordinates to the constraint's non-ideal force (2.13).",
            (Key("name", "string", "the constraint's name", "rolling", default="constraint_<index>"),
             _DESCRIPTION,
             Key("C", "mapping coordinate → expression", "non-ideal generalized force C of (2.13)",
                 "{wheel.y: -c*wheel.y_dot}", default="ideal (C = 0)"),
             Key("holonomic", "expression of coordinates", "φ(q, t) = 0", "wheel.y - R*wheel.theta*sin(alpha)"),
             Key("nonholonomic", "expression linear in velocities", "ψ(q, q̇, t) = 0",
                 "cart.x_dot - R*cart.theta_dot"),
             Key("acceleration", "mapping (section *acceleration_row*)", "a row A q̈ = b given directly",
                 "{A: {a.x: 1, b.x: -1}, b: 0}"))),
    Section("acceleration_row", "``acceleration:`` of a constraint",
            "``A`` is a list with one entry per coordinate, or a mapping coordinate → entry "
            "(absent entries are zero).",
            (_required("A", "list or mapping of expressions", "the row of A", "{a.x: 1, b.x: -1}"),
             Key("b", "expression", "the right-hand side", "0", default="0"))),
    Section("joint", "each entry of ``joints:`` (other than a ground contact)",
            f"``type`` is one of {', '.join(JOINT_KINDS)}. Frames are written ``part.frame``, ``part`` "
            "(its own origin and axes), ``world`` or ``world.frame``.",
            (_required("name", "plain name", "the joint's name (also the prefix of its values, "
                       "``pin.angle``)", "pin"),
             _required("type", "string", f"one of {', '.join(JOINT_KINDS)}", "revolute"),
             _required("parent", "frame", "frame A, on the parent part or the world", "world.pin"),
             _required("child", "frame", "frame B, on the child part", "link.top"),
             Key("length", _EXPR + ", > 0", "the distance kept by a ``distance`` joint (required there)", "0.5"),
             Key("for", "mapping name → [first, last]", "one joint per whole number from first to last (both "
                 "included; none for [k, k - 1], the range of one copy; a range running further back is "
                 "refused), named ``name[i]``; ``[expression]`` in its frames is replaced by its value",
                 "{i: [0, N - 2]}"),
             _DESCRIPTION,
             Key("actuation", "expression, or mapping (section *joint_actuation*)", "torque (revolute) or "
                 "force (prismatic) along the joint's axis", "tau*sin(t)"),
             Key("spring", "mapping (section *joint_spring*)", "torsional or linear spring and damper "
                 "at a revolute or prismatic joint", "{stiffness: k, rest: 0.1}"),
             Key("friction", "mapping (section *joint_friction*)", "viscous and Coulomb friction at a "
                 "revolute or prismatic joint (non-ideal C)", "{viscous: 0.05}"),
             Key("limits", "list of 2 " + _EXPRS + ", lo ≤ hi; universal: 2 such lists; spherical: mapping "
                 "(section *cone_limit*)", "stops on the angle (revolute) or displacement (prismatic): unilateral "
                 "rows ``<joint>.lower``, ``<joint>.upper``; on a universal joint's angle1 and angle2: "
                 "``.lower1``, ``.upper1``, ``.lower2``, ``.upper2``; on a spherical joint's swing: ``.cone``",
                 "[-0.5, 0.5]"),
             Key("restitution", _EXPR + ", 0 ≤ e ≤ 1", "Newton's coefficient of restitution at the limits",
                 "0.5", default="0"))),
    Section("cone_limit", "``limits:`` of a spherical joint",
            "The swing, the angle between the frames' z axes (z_A on the parent, z_B on the child), stays at "
            "most the cone's half-angle: the gap z_A·z_B − cos(cone) ≥ 0, row ``<joint>.cone``.",
            (_required("cone", _EXPR + ", in (0, π]", "the cone's half-angle [rad]", "0.5"),)),
    Section("contact_plane", "an entry of ``contacts:`` with ``type: plane``",
            "A point (radius 0) or sphere on a part's frame against the plane n·x = ground (n the unit "
            "normal): the gap n·p − ground − radius stays ≥ 0. A ``capsule`` is its two end spheres "
            "(contacts ``NAME[0]``, ``NAME[1]``), a ``box`` its eight corners (``NAME[0]`` … ``NAME[7]``), "
            "each a contact of its own.",
            (_required("name", "plain name", "the contact's name", "floor"),
             _required("type", "string", "``plane``", "plane"),
             _required("child", "frame", "the sphere's centre: a frame on a part", "ball"),
             Key("radius", _EXPR + ", ≥ 0", "the sphere's radius (0: a point)", "r", default="0"),
             Key("capsule", "list of 2 " + _EXPRS + ", > 0", "instead of a sphere, a capsule [radius, length] "
                 "along the frame's z, centred on it: ``NAME[0]`` its end sphere at −length/2, ``NAME[1]`` at "
                 "+length/2", "[0.02, 0.5]"),
             Key("box", "list of 3 " + _EXPRS + ", > 0", "instead of a sphere, a box of these sizes along the "
                 "frame's x, y, z, centred on it: ``NAME[k]`` its corner (±x/2, ±y/2, ±z/2), bit j of k the sign "
                 "of axis j (0: −)", "[0.4, 0.2, 0.1]"),
             Key("ground", _EXPR, "the plane's offset along its normal", "0", default="0"),
             Key("normal", "list of 3 " + _EXPRS, "the plane's normal, pointing out of the ground", "[0, 0, 1]",
                 default="[0, 0, 1]"),
             Key("restitution", _EXPR + ", 0 ≤ e ≤ 1", "Newton's coefficient of restitution", "0.8", default="0"),
             Key("friction", _EXPR + ", ≥ 0", "Coulomb's coefficient μ at the contact point (a sphere's "
                 "moves with its spin): tangential impulses at impacts, stick or slip; sliding", "0.5", default="0"),
             _DESCRIPTION)),
    Section("contact_spheres", "an entry of ``contacts:`` with ``type: spheres``",
            "Two spheres on two parts: the gap |p_B − p_A| − r_A − r_B stays ≥ 0. With a ``length``, one or "
            "both of them is a capsule (its segment along its frame's z, centred on it): the gap is the "
            "distance from the sphere's centre to the segment, or between the two segments, less both radii "
            "(parallel capsules overlapping along their length: one row, at the first's point nearest the "
            "second's centre).",
            (_required("name", "plain name", "the contact's name", "c12"),
             _required("type", "string", "``spheres``", "spheres"),
             _required("between", "list of 2 frames", "the spheres' centres, on two parts", "[ball1, ball2]"),
             _required("radius", "list of 2 " + _EXPRS + ", ≥ 0", "their radii", "[r, r]"),
             Key("length", "list of 2 " + _EXPRS + ", ≥ 0", "their segments' lengths (0: a sphere; > 0: a "
                 "capsule along its frame's z)", "[0, 0.5]", default="[0, 0]"),
             Key("restitution", _EXPR + ", 0 ≤ e ≤ 1", "Newton's coefficient of restitution", "1", default="0"),
             _DESCRIPTION)),
    Section("rolling_disk", "an entry of ``joints:`` with ``type: rolling_disk``",
            "A disk rolling without slipping on the plane z = ground.",
            (_required("name", "plain name", "the contact's name", "roll"),
             _required("type", "string", "``rolling_disk``", "rolling_disk"),
             _required("child", "frame", "the disk's centre frame on a rigid body, z along its axis", "disk"),
             _required("radius", _EXPR + ", > 0", "the disk's radius", "R"),
             Key("ground", _EXPR, "height of the plane (in an included file, raised by its placement, "
                 "which may not tilt it)", "0", default="0"), _DESCRIPTION)),
    Section("knife_edge", "an entry of ``joints:`` with ``type: knife_edge``",
            "A blade that slides along itself but not across (a nonholonomic constraint).",
            (_required("name", "plain name", "the contact's name", "blade"),
             _required("type", "string", "``knife_edge``", "knife_edge"),
             _required("child", "frame", "a frame on a rigid or planar body whose x axis is the blade", "sled"),
             _DESCRIPTION)),
    Section("joint_actuation", "``actuation:`` of a joint, written as a mapping",
            "A single expression drives the joint's one motion; a cylindrical joint takes both keys.",
            (Key("torque", "expression", "torque about the joint's z axis (revolute, cylindrical)", "tau"),
             Key("force", "expression", "force along the joint's z axis (prismatic, cylindrical)", "f"))),
    Section("joint_spring", "``spring:`` of a joint", "",
            (_required("stiffness", _EXPR + ", ≥ 0", "stiffness [N m/rad or N/m]", "k"),
             Key("damping", _EXPR + ", ≥ 0", "damping", "0.1", default="0"),
             Key("rest", _EXPR, "rest angle (in [−π, π]) or displacement", "0.2", default="0"))),
    Section("joint_friction", "``friction:`` of a revolute or prismatic joint",
            "Give viscous and/or coulomb; Coulomb friction at a revolute joint needs the pin radius.",
            (Key("viscous", _EXPR + ", ≥ 0", "viscous coefficient", "0.05", default="0"),
             Key("coulomb", _EXPR + ", ≥ 0", "Coulomb coefficient μ", "0.3", default="0"),
             Key("radius", _EXPR + ", > 0", "pin radius r of a revolute joint, required there with ``coulomb`` (friction torque μ r N)", "0.01"))),
    Section("force_spring", "an entry of ``forces:`` with ``type: spring``",
            "A linear spring (and damper) between two frames.",
            (_BETWEEN, _required("stiffness", _EXPR + ", ≥ 0", "stiffness [N/m]", "k"),
             _required("rest_length", _EXPR + ", ≥ 0", "unstretched length [m]", "0.3"),
             Key("damping", _EXPR + ", ≥ 0", "damping [N s/m]", "0.1", default="0"), *_FORCE_KEYS)),
    Section("force_damper", "an entry of ``forces:`` with ``type: damper``",
            "A linear damper between two frames.",
            (_BETWEEN, _required("damping", _EXPR + ", ≥ 0", "damping [N s/m]", "0.1"), *_FORCE_KEYS)),
    Section("force_force", "an entry of ``forces:`` with ``type: force``",
            "A force at a frame of a part, in world axes.",
            (_required("at", "frame", "where the force acts (on a part)", "body.tip"),
             _required("value", "list of 3 expressions", "the force (world axes); may use t, coordinates, "
                       "velocities", "[0, 0, -F*sin(t)]"), *_FORCE_KEYS)),
    Section("force_torque", "an entry of ``forces:`` with ``type: torque``",
            "A torque on a rigid or planar body.",
            (_required("part", "part name", "the body the torque acts on", "body"),
             _required("value", "list of 3 expressions", "the torque", "[0, 0, tau]"),
             Key("axes", "``world`` or ``body``", "the axes the value is given in", "body", default="world"),
             *_FORCE_KEYS)),
    Section("output", "each entry of ``outputs:`` written as a mapping",
            "An output is an expression (of parameters, t, coordinates, joint values) or a mapping "
            "with exactly one of these keys.",
            (Key("reaction", "string", "``<joint>.force``, ``.torque`` or ``.multipliers``", "pin.force"),
             Key("position", "frame", "world position of a frame", "link.tip"),
             Key("velocity", "frame", "world velocity of a frame", "link.tip"),
             Key("energy", "string", "``kinetic``, ``potential`` or ``total``", "total"),
             Key("contact", "string", "``<contact>.force`` (its normal force, 0 while open) or ``.impulse`` (its "
                 "normal impulses since the previous row); a joint limit as ``<joint>.upper.force``",
                 "floor.force"))),
)}

PART_SECTIONS = tuple(_TYPE)  # the part sections, by the value of their ``type`` key
FORCE_SECTIONS = {"spring": "force_spring", "damper": "force_damper", "force": "force_force",
                  "torque": "force_torque"}
