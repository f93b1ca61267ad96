"""Whole robots as parts: every URDF link a rigid body in its own seven coordinates,
every URDF joint a constraint between frames on two links.

A link's body has its centre of mass as position and the link frame's axes as body
axes; its inertia is turned from the URDF inertial frame into link axes (urdf.py). A
joint becomes a ``Joint`` between a frame on the parent body at (joint origin − parent's
centre of mass) and a frame on the child body at (−child's centre of mass), both with
z along the joint axis: revolute and continuous → revolute, prismatic → prismatic,
fixed → fixed. A fixed base is a fixed joint from the world to the root link; a
floating base is none (the root body is free). A link without mass stays a massless
body: its block of M is zero, and the joints decide whether its motion is determined
(Result 3) — a massless leaf on a revolute joint is not, and ``mbsynth check`` says so.

Every movable joint is driven by a parameter ``tau_<joint>`` (default 0): a torque about
a revolute axis, a force along a prismatic one (joint_forces.actuation).

With ``merge_fixed`` each link on a fixed joint is merged into its nearest ancestor on a
movable joint (urdf.Description.merged, as Pinocchio's parser does) and kept as a frame of
that ancestor's body named after the link: fewer bodies, the same joint motion.

Robots by name are those ``example-robot-data`` ships (``robot_files``); any URDF path
works too.
"""

import glob
import os
import re
import sys
from dataclasses import dataclass, field, replace

import numpy as np
import sympy as sp

from .. import compiled
from ..model.constraints.joints import Joint
from ..core.errors import ModelError
from ..core.joint_kinds import URDF_KINDS
from ..model.joint_forces import actuation, joint_motion
from ..core.kinematics import axis_matrix, matrix_quaternion
from ..model.parts import LINK_FRAME, Frame, RigidBody
from ..model.system import System
from .urdf import read_urdf
from ..core.tolerances import EXACT_ENTRY_TOL

GRAVITY = (0.0, 0.0, -9.81)
# example-robot-data's own short names (those of its Python loaders), by file
ALIASES = {
    "ur3": "ur_description/urdf/ur3_robot.urdf", "ur5": "ur_description/urdf/ur5_robot.urdf",
    "ur10": "ur_description/urdf/ur10_robot.urdf", "ur3_limited": "ur_description/urdf/ur3_joint_limited_robot.urdf",
    "ur5_limited": "ur_description/urdf/ur5_joint_limited_robot.urdf",
    "ur10_limited": "ur_description/urdf/ur10_joint_limited_robot.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf", "talos_box": "talos_data/robots/talos_reduced_box.urdf",
    "talos_full": "talos_data/robots/talos_full_v2.urdf", "talos_full_box": "talos_data/robots/talos_full_v2_box.urdf",
    "talos_arm": "talos_data/robots/talos_left_arm.urdf", "solo8": "solo_description/robots/solo.urdf",
    "anymal": "anymal_b_simple_description/robots/anymal.urdf",
    "anymal_c": "anymal_c_simple_description/urdf/anymal.urdf",
    "anymal_kinova": "anymal_b_simple_description/robots/anymal-kinova.urdf",
    "hyq": "hyq_description/robots/hyq_no_sensors.urdf", "hector": "hector_description/robots/quadrotor_base.urdf",
    "asr_twodof": "asr_twodof_description/urdf/TwoDofs.urdf",
}


def share_dir():
    """The folder holding example-robot-data's package (its ``package://`` root), or None:
    ``cmeel.prefix/share`` beside the installed packages (sys.path), else where the
    distribution's metadata places it (importlib.metadata, imported only then)."""
    for entry in sys.path:
        path = os.path.join(entry or ".", "cmeel.prefix", "share")
        if os.path.isdir(os.path.join(path, "example-robot-data", "robots")):
            return path
    import importlib.metadata

    try:
        distribution = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        return None
    path = str(distribution.locate_file("cmeel.prefix/share"))
    return path if os.path.isdir(os.path.join(path, "example-robot-data", "robots")) else None


def robot_files():
    """{name: URDF path} of every robot example-robot-data ships: its short names
    (``ur5``, ``talos``, ``anymal``, …) and every other file by its stem."""
    share = share_dir()
    if share is None:
        return {}
    robots = os.path.join(share, "example-robot-data", "robots")
    files = {os.path.relpath(f, robots): f for f in sorted(glob.glob(os.path.join(robots, "*", "*", "*.urdf")))}
    names = {name: files[rel] for name, rel in ALIASES.items() if rel in files}
    aliased = set(names.values())
    for rel, path in files.items():
        stem = identifier(os.path.splitext(os.path.basename(rel))[0].lower())
        if path not in aliased:
            names[stem if stem not in names else identifier(f"{rel.split('/')[0]}_{stem}")] = path
    return dict(sorted(names.items()))


def describe(name_or_urdf, package_dirs=()):
    """The urdf.Description of a robot named by example-robot-data, or of a URDF file."""
    share = share_dir()
    path = _alias_file(share, name_or_urdf)
    if path is None:
        files = robot_files()
        if name_or_urdf in files:
            path = files[name_or_urdf]
        elif os.path.isfile(str(name_or_urdf)):
            path = str(name_or_urdf)
        else:
            known = ", ".join(files) or "none (example-robot-data is not installed)"
            raise ModelError(f"no robot or URDF file {name_or_urdf!r}; robots: {known}")
    return read_urdf(path, tuple(package_dirs) + ((share,) if share else ()))


def _alias_file(share, name):
    """The URDF of a short name (ALIASES) where it is installed, found without listing
    every robot (robot_files); else None."""
    relative = ALIASES.get(name) if share and isinstance(name, str) else None
    path = relative and os.path.join(share, "example-robot-data", "robots", relative)
    return path if path and os.path.isfile(path) else None


def identifier(text):
    """``text`` made a plain name (letters, digits, _), as part, frame and parameter names must be."""
    name = re.sub(r"\W", "_", text)
    return name if name and not name[0].isdigit() else f"_{name}"


@dataclass(frozen=True)
class Robot:
    """A robot decomposed into parts: ``parts`` maps each URDF link to its part's name,
    ``joints`` each URDF joint to its constraint's name, ``torques`` each movable joint to
    its torque parameter; with the welded links merged (``Description.merged``), ``welded``
    maps each merged link to the name its part would have and ``welded_joints`` each merged
    fixed joint's would-be constraint name to its link. ``base`` is the root link's world
    (position, rotation) when fixed, its initial pose when ``floating``; ``positions`` the
    initial joint positions ({URDF joint name: value}, 0 where not given)."""

    description: object
    prefix: str
    floating: bool
    base: tuple
    parts: dict
    joints: dict
    torques: dict
    base_joint: str
    positions: dict = field(default_factory=dict)
    welded: dict = field(default_factory=dict)  # merged link → the name of the part it would be
    welded_joints: dict = field(default_factory=dict)  # merged fixed joint's constraint name → its link

    @classmethod
    def plan(cls, description, prefix="", floating=False, base=None, scope=""):
        """Names for the parts, constraints and torque parameters of ``description``, each
        after ``scope`` (a substructure's ``left_leg.``); a merged link (``welded``) keeps
        the part name it would have, the name that finds its frame on its host."""
        base = (np.zeros(3), np.eye(3)) if base is None else tuple(np.asarray(x, dtype=float) for x in base)
        links = (*description.links, *description.welded)
        parts = _unique({link: scope + prefix + identifier(link) for link in links})
        welded = {link: parts.pop(link) for link in description.welded}
        joints = _unique({j: prefix + identifier(j) for j in (*(j.name for j in description.joints),
                                                               *(w.joint for w in description.welded.values()))}
                         | {None: prefix + "fixed_base"})
        base_joint = scope + joints.pop(None)
        torques = {j.name: f"{scope}tau_{joints[j.name]}" for j in description.joints if j.kind != "fixed"}
        joints = {key: scope + name for key, name in joints.items()}
        welded_joints = {joints.pop(w.joint): link for link, w in description.welded.items()}
        return cls(description, prefix, floating, base, parts, joints, torques, base_joint, welded=welded,
                   welded_joints=welded_joints)

    @property
    def parameters(self):
        """The torque parameters and their default, 0."""
        return {name: 0.0 for name in self.torques.values()}

    def bodies(self, gravity, params):
        """One RigidBody per link, at the pose of the robot with its joints at ``positions``."""
        frames = {link: [Frame(self.parts[link], LINK_FRAME, exact(-lk.com), sp.eye(3))]
                  for link, lk in self.description.links.items()}
        for joint in self.description.joints:
            on_parent, on_child = self.joint_frames(joint)
            frames[joint.parent].append(on_parent)
            frames[joint.child].append(on_child)
        for link, weld in self.description.welded.items():
            frame = self.welded_frame(link)
            if any(f.name == frame.name for f in frames[weld.host]):
                raise ModelError(f"{self.description.path}: merged link '{link}' would be frame '{frame.name}' of "
                                 f"'{frame.part}', which has a frame of that name (a joint's): build without "
                                 "merge_fixed")
            frames[weld.host].append(frame)
        poses = self.description.poses(self.base, self.positions)
        bodies = []
        for link, lk in self.description.links.items():
            name = self.parts[link]
            q = [sp.Symbol(f"{name}.{c}") for c in RigidBody.COORDINATES]
            qd = [sp.Symbol(f"{name}.{c}_dot") for c in RigidBody.COORDINATES]
            p, R = poses[link]
            initial = dict(zip(RigidBody.COORDINATES, [*(p + R @ lk.com), *matrix_quaternion(R)]))
            geometry = tuple(dict(v, position=(np.asarray(v["position"]) - lk.com).tolist())
                             for v in lk.visuals)
            bodies.append(RigidBody(name, q, qd, exact(lk.mass)[0], exact(lk.inertia), gravity, params,
                                    frames[link], geometry, initial))
        return bodies

    def joint_frames(self, joint):
        """(frame on the parent body, frame on the child body) of a URDF joint: at the
        joint origin and the child link's origin, z along the axis (identity axes for fixed)."""
        A = np.eye(3) if joint.kind == "fixed" else axis_matrix(joint.axis)
        parent, child = self.description.links[joint.parent], self.description.links[joint.child]
        name = identifier(joint.name)
        return (Frame(self.parts[joint.parent], name, exact(joint.position - parent.com), exact(joint.rotation @ A)),
                Frame(self.parts[joint.child], name, exact(-child.com), exact(A)))

    def welded_frame(self, link, origin=False):
        """The frame on its host's body of a merged link: its link frame, named after the
        link (``origin``: at its own centre of mass, the origin its part would have)."""
        weld = self.description.welded[link]
        host = self.description.links[weld.host]
        position = weld.position + (weld.rotation @ weld.com if origin else 0.0) - host.com
        return Frame(self.parts[weld.host], identifier(link) + ("_com" if origin else ""), exact(position),
                     exact(weld.rotation))

    def welded_reference(self, part, frame, parts):
        """(host part, Frame) for frame ``frame`` ('' its origin) of ``part``, the part a
        merged link would be: its link frame (``link``, or the frame of the fixed joint that
        hung it), the frame of a joint that hung from it, or its origin (its centre of mass,
        link axes). None when ``part`` is no merged link's; a ModelError for another frame.
        ``parts``: the parts by name."""
        link = next((link for link, name in self.welded.items() if name == part), None)
        if link is None:
            return None
        weld = self.description.welded[link]
        host = parts[self.parts[weld.host]]
        below = {identifier(j): j for j in weld.children}
        if frame in ("", LINK_FRAME, identifier(weld.joint)):
            merged = self.welded_frame(link, origin=not frame and bool(np.any(weld.com)))
            return host, host.frames.get(merged.name, merged)
        if frame in below:
            child = next((c for c, w in self.description.welded.items() if w.joint == below[frame]), None)
            return host, host.frames[identifier(child) if child else frame]
        known = ", ".join([LINK_FRAME, identifier(weld.joint), *below])
        raise ModelError(f"'{part}' (link '{link}', merged into '{host.name}' by merge_fixed) has no frame "
                         f"'{frame}'; it has: {known}")

    def connect(self, parts, q, qd, params):
        """(joints, torque force elements) between the bodies ``parts`` (name → part)."""
        joints = [] if self.floating else [self.weld(parts, q, qd, params)]
        elements = []
        for joint in self.description.joints:
            on_parent, on_child = self.joint_frames(joint)
            child = parts[on_child.part]
            constraint = Joint(self.joints[joint.name], URDF_KINDS[joint.kind], parts[on_parent.part], on_parent,
                              child, on_child, q, qd, params, report_frame=child.frames[LINK_FRAME])
            joints.append(constraint)
            if joint.name in self.torques:
                elements.append(actuation(f"{constraint.name}.actuation", constraint,
                                          {joint_motion(constraint): sp.Symbol(self.torques[joint.name])}, q, qd, params))
        return joints, elements

    def weld(self, parts, q, qd, params):
        """The fixed joint that holds the root link's frame at ``base`` in the world."""
        root = parts[self.parts[self.description.root]]
        world = Frame("world", self.base_joint, exact(self.base[0]), exact(self.base[1]))
        return Joint(self.base_joint, "fixed", None, world, root, root.frames[LINK_FRAME], q, qd, params)


def from_robot(name_or_urdf, floating=False, *, base=None, gravity=GRAVITY, prefix="", package_dirs=(),
               merge_fixed=False):
    """A System of the robot ``name_or_urdf`` (an example-robot-data name or a URDF file):
    one rigid body per link, one joint per URDF joint, one torque parameter per movable
    joint (``tau_<joint>``, set with ``System.with_parameters``). ``floating``: a free
    root link instead of a fixed base; ``base``: the root link's (position, rotation).
    ``merge_fixed``: each link hung by a fixed joint merged into its nearest ancestor on a
    movable joint (``urdf.Description.merged``), kept as a frame of that ancestor's body
    named after the link (``Robot.welded_frame``): fewer bodies, the same joint motion."""
    compiled.compile_ahead("rigid_tree")  # a robot is a rigid tree: a cold compile starts beside the derivation
    description = describe(name_or_urdf, package_dirs)
    description = description.merged() if merge_fixed else description
    robot = Robot.plan(description, prefix, floating, base)
    params = [sp.Symbol(p) for p in robot.parameters]
    bodies = robot.bodies(sp.Matrix(gravity), params)
    q = [s for body in bodies for s in body.q]
    qd = [s for body in bodies for s in body.qd]
    joints, elements = robot.connect({b.name: b for b in bodies}, q, qd, params)
    constraints = [c for b in bodies for c in b.own_constraints(q, qd, params)] + joints
    initial = {f"{b.name}.{c}": v for b in bodies for c, v in b.initial.items()}
    system = System.build(identifier(description.name), bodies, constraints, q, qd, robot.parameters, initial,
                          forces=elements)
    return replace(system, robots=(robot,))


def fix_base(system):
    """The System of one floating robot with its root link welded to the world at its
    base: the fixed-base robot without building its parts again."""
    (robot,) = system.robots
    fixed = replace(robot, floating=False)
    weld = fixed.weld({p.name: p for p in system.parts}, system.q_symbols, system.qd_symbols,
                      system.parameter_symbols)
    return replace(system.with_constraints([weld]), robots=(fixed,))


def exact(values):
    """A sympy matrix of ``values`` with entries within EXACT_ENTRY_TOL of −1, 0 or 1 made exact
    integers: ``1.0*x`` and ``0.0*x`` terms would otherwise fill every derivative."""
    values = np.atleast_1d(np.asarray(values, dtype=float))
    near = np.round(values)
    exact_entries = (np.abs(values - near) < EXACT_ENTRY_TOL) & (np.abs(near) <= 1)
    return sp.Matrix(values.shape[0], values.shape[1] if values.ndim > 1 else 1,
                     [sp.Integer(int(n)) if e else sp.Float(v) for v, n, e in
                      zip(values.ravel(), near.ravel(), exact_entries.ravel())])


def _unique(names):
    """The same mapping with repeated values made distinct (a suffix _2, _3, …)."""
    seen, out = set(), {}
    for key, name in names.items():
        candidate, k = name, 2
        while candidate in seen:
            candidate, k = f"{name}_{k}", k + 1
        seen.add(candidate)
        out[key] = candidate
    return out
