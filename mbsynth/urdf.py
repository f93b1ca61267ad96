"""Reading a URDF file into plain numbers: links (mass, centre of mass, inertia,
visuals) and joints (kind, parent, child, origin, axis, limits).

Only what the dynamics and the viewer need is read. Conventions are URDF's: an origin
is (xyz, rpy) with R = Rz(yaw) Ry(pitch) Rx(roll); a joint's child link frame is the
joint frame, moved by the joint about / along ``axis`` (in that frame, default x).
``<mimic>`` is ignored (every joint moves on its own, as Pinocchio's parser does by
default); ``<dynamics>`` (damping, friction) is ignored.
"""

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np

from .errors import ModelError
from .kinematics import rpy_matrix

KINDS = ("revolute", "continuous", "prismatic", "fixed")


@dataclass(frozen=True)
class Link:
    """A link: ``mass``, ``com`` (centre of mass in link axes), ``inertia`` (3 × 3 about
    the centre of mass, in link axes) and ``visuals`` (geometry dicts, link frame)."""

    name: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    visuals: tuple = ()


@dataclass(frozen=True)
class UrdfJoint:
    """A joint: ``origin`` (position, rotation) of its frame in the parent link's frame,
    ``axis`` (unit, joint frame) and position ``limits`` (lower, upper) or None."""

    name: str
    kind: str
    parent: str
    child: str
    position: np.ndarray
    rotation: np.ndarray
    axis: np.ndarray
    limits: tuple = None
    effort: float = None


@dataclass(frozen=True)
class Description:
    """A robot: links by name, joints in file order, and its root link."""

    name: str
    path: str
    links: dict
    joints: tuple
    root: str
    package_dirs: tuple = field(default=(), compare=False)

    def children(self, link):
        """The joints that hang links from ``link``."""
        return [j for j in self.joints if j.parent == link]

    def zero_poses(self, base=None):
        """World (position, rotation) of every link's frame with all joints at zero and
        the root link's frame at ``base`` (the world origin by default)."""
        position, rotation = (np.zeros(3), np.eye(3)) if base is None else base
        poses = {self.root: (np.asarray(position, float), np.asarray(rotation, float))}
        for joint in self.tree_order():
            p, R = poses[joint.parent]
            poses[joint.child] = (p + R @ joint.position, R @ joint.rotation)
        return poses

    def tree_order(self):
        """The joints, each after the joint that hangs its parent link (root first)."""
        order, frontier = [], [self.root]
        while frontier:
            link = frontier.pop(0)
            for joint in self.children(link):
                order.append(joint)
                frontier.append(joint.child)
        return order


# a principal moment below −max(INERTIA_RTOL × the largest, INERTIA_ATOL) is negative, not rounding
# (icub's head has moments of ±2.4e-35 kg m²: zero, printed with noise; URDF units are SI)
INERTIA_RTOL, INERTIA_ATOL = 1e-12, 1e-15


def read_urdf(path, package_dirs=()):
    """The Description of the URDF file at ``path``; ``package://`` mesh files are looked
    up in ``package_dirs`` (each holding package folders) and beside the file."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as err:
        raise ModelError(f"cannot read URDF {path}: {err}") from None
    if root.tag != "robot":
        raise ModelError(f"{path}: not a URDF file (the root element is <{root.tag}>, not <robot>)")
    dirs = tuple(package_dirs) + _default_package_dirs(path)
    materials = {m.get("name"): _color(m) for m in root.findall("material")}
    links = {}
    for element in root.findall("link"):
        link = _link(element, path, dirs, materials)
        if link.name in links:
            raise ModelError(f"{path}: link '{link.name}' is defined twice")
        links[link.name] = link
    joints = tuple(_joint(element, path, links) for element in root.findall("joint"))
    children = [j.child for j in joints]
    twice = sorted({c for c in children if children.count(c) > 1})
    if twice:
        raise ModelError(f"{path}: links {twice} hang from more than one joint")
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise ModelError(f"{path}: expected one root link (a link no joint hangs), found {roots or 'none'}")
    description = Description(root.get("name") or _stem(path), str(path), links, joints, roots[0], dirs)
    if len(description.tree_order()) != len(joints):
        raise ModelError(f"{path}: the joints do not form a tree from the root link '{roots[0]}'")
    return description


def _default_package_dirs(path):
    """Beside the file, and two levels up (a ROS package ``pkg/urdf/robot.urdf``)."""
    here = os.path.dirname(os.path.abspath(path))
    return (here, os.path.dirname(here), os.path.dirname(os.path.dirname(here)))


def _origin(element):
    """(position, rotation) of an ``<origin>`` child (identity when absent)."""
    origin = element.find("origin") if element is not None else None
    if origin is None:
        return np.zeros(3), np.eye(3)
    return _floats(origin.get("xyz", "0 0 0")), rpy_matrix(*_floats(origin.get("rpy", "0 0 0")))


def _floats(text, count=3):
    values = np.array([float(x) for x in text.split()])
    if values.size != count:
        raise ValueError(f"expected {count} numbers, got {text!r}")
    return values


def _link(element, path, dirs, materials):
    name = element.get("name")
    inertial = element.find("inertial")
    try:
        if inertial is None:
            mass, com, inertia = 0.0, np.zeros(3), np.zeros((3, 3))
        else:
            com, R = _origin(inertial)
            mass_element = inertial.find("mass")
            mass = float(mass_element.get("value")) if mass_element is not None else 0.0
            node = inertial.find("inertia")
            i = {k: float(node.get(k, 0.0)) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")} if node is not None \
                else dict.fromkeys(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), 0.0)
            local = np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]],
                              [i["ixz"], i["iyz"], i["izz"]]])
            inertia = R @ local @ R.T  # from the inertial frame to link axes
    except (TypeError, ValueError) as err:
        raise ModelError(f"{path}: link '{name}': bad <inertial>: {err}") from None
    if mass < 0:
        raise ModelError(f"{path}: link '{name}' has a negative mass {mass}")
    eigenvalues = np.linalg.eigvalsh(inertia)
    if not np.all(np.isfinite(eigenvalues)) or eigenvalues.min() < -max(INERTIA_RTOL * abs(eigenvalues).max(),
                                                                        INERTIA_ATOL):
        raise ModelError(f"{path}: link '{name}': its inertia is not positive semi-definite (principal moments "
                         f"{', '.join(f'{x:.3g}' for x in eigenvalues)}); no rigid body has it — fix the "
                         "<inertia> of the file")
    visuals = tuple(v for v in (_visual(x, path, dirs, materials) for x in element.findall("visual")) if v)
    return Link(name, mass, com, inertia, visuals)


def _joint(element, path, links):
    name, kind = element.get("name"), element.get("type")
    if kind not in KINDS:
        raise ModelError(f"{path}: joint '{name}' is of type {kind!r}; supported: {', '.join(KINDS)}")
    parent, child = element.find("parent").get("link"), element.find("child").get("link")
    for link in (parent, child):
        if link not in links:
            raise ModelError(f"{path}: joint '{name}' names an unknown link '{link}'")
    position, rotation = _origin(element)
    axis_element = element.find("axis")
    axis = _floats(axis_element.get("xyz")) if axis_element is not None else np.array([1.0, 0.0, 0.0])
    if kind != "fixed" and np.linalg.norm(axis) == 0:
        raise ModelError(f"{path}: joint '{name}' has a zero axis")
    limit = element.find("limit")
    limits = effort = None
    if limit is not None:
        effort = float(limit.get("effort", "nan"))
        if kind in ("revolute", "prismatic") and "lower" in limit.attrib and "upper" in limit.attrib:
            limits = (float(limit.get("lower")), float(limit.get("upper")))
    return UrdfJoint(name, kind, parent, child, position, rotation,
                     axis / (np.linalg.norm(axis) or 1.0), limits, effort)


def _color(material):
    color = material.find("color") if material is not None else None
    return [float(x) for x in color.get("rgba").split()] if color is not None else None


def _visual(element, path, dirs, materials):
    """A geometry dict (io/parts.py) in link axes, or None for one that cannot be drawn."""
    geometry = element.find("geometry")
    if geometry is None or len(geometry) == 0:
        return None
    shape = geometry[0]
    position, rotation = _origin(element)
    material = element.find("material")
    color = _color(material) or (materials.get(material.get("name")) if material is not None else None)
    out = {"position": position.tolist(), "rotation": rotation.tolist(), "color": color or [0.7, 0.7, 0.7, 1.0]}
    if shape.tag == "box":
        return dict(out, shape="box", size=_floats(shape.get("size")).tolist())
    if shape.tag == "sphere":
        return dict(out, shape="sphere", size=[float(shape.get("radius"))])
    if shape.tag == "cylinder":
        return dict(out, shape="cylinder", size=[float(shape.get("radius")), float(shape.get("length"))])
    if shape.tag == "mesh":
        file = resolve_mesh(shape.get("filename", ""), path, dirs)
        scale = _floats(shape.get("scale")) if shape.get("scale") else np.ones(3)
        return dict(out, shape="mesh", file=file, scale=scale.tolist()) if file else None
    return None


def resolve_mesh(filename, urdf_path, dirs):
    """The file a URDF mesh name refers to (``package://pkg/...``, ``file://...`` or a path
    relative to the URDF file), or None when it is not found."""
    if filename.startswith("package://"):
        candidates = [os.path.join(d, filename[len("package://"):]) for d in dirs]
    elif filename.startswith("file://"):
        candidates = [filename[len("file://"):]]
    else:
        candidates = [os.path.join(os.path.dirname(os.path.abspath(urdf_path)), filename)]
    return next((c for c in candidates if os.path.isfile(c)), None)


def _stem(path):
    return os.path.splitext(os.path.basename(str(path)))[0]
