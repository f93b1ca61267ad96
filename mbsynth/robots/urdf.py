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
from dataclasses import dataclass, field, replace

import numpy as np

from ..core.errors import ModelError
from ..core.joint_kinds import URDF_KINDS
from ..core.kinematics import quaternion_matrix, rpy_matrix
from ..core.tolerances import URDF_INERTIA_ATOL, URDF_INERTIA_RTOL


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
class Weld:
    """A link merged into its nearest ancestor on a movable joint (``Description.merged``):
    ``host`` that ancestor, ``joint`` the fixed joint that hung the link, ``position`` and
    ``rotation`` the link frame in the host's link frame, ``com`` the link's own centre of
    mass (its link axes), ``children`` the URDF joints that hung from it."""

    host: str
    joint: str
    position: np.ndarray
    rotation: np.ndarray
    com: np.ndarray
    children: tuple


@dataclass(frozen=True)
class Description:
    """A robot: links by name, joints in file order, and its root link; ``welded``: the
    links merged into an ancestor ({link: Weld}, empty unless ``merged``)."""

    name: str
    path: str
    links: dict
    joints: tuple
    root: str
    package_dirs: tuple = field(default=(), compare=False)
    welded: dict = field(default_factory=dict, compare=False)

    def children(self, link):
        """The joints that hang links from ``link``."""
        return [j for j in self.joints if j.parent == link]

    def poses(self, base=None, positions=None):
        """World (position, rotation) of every link's frame with the root link's frame at
        ``base`` (the world origin by default) and each joint at its value in ``positions``
        ({joint name: angle [rad] or displacement [m]}, 0 where not given): the child link's
        frame is the joint's origin turned about (revolute, continuous) or moved along
        (prismatic) the joint's axis, as URDF defines it."""
        position, rotation = (np.zeros(3), np.eye(3)) if base is None else base
        positions = positions or {}
        poses = {self.root: (np.asarray(position, float), np.asarray(rotation, float))}
        for joint in self.tree_order():
            p, R = poses[joint.parent]
            p, R = p + R @ joint.position, R @ joint.rotation
            x = float(positions.get(joint.name, 0.0))
            if joint.kind == "prismatic":
                p = p + R @ joint.axis * x
            elif joint.kind != "fixed":
                R = R @ quaternion_matrix([np.cos(x / 2), *(np.sin(x / 2) * joint.axis)])
            poses[joint.child] = (p, R)
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

    def merged(self):
        """This robot with each link hung by a fixed joint merged into its nearest ancestor
        on a movable joint (or the root), as Pinocchio's model does: masses added, centres of
        mass combined, inertias about the new centre by the parallel-axis rule, visuals
        carried over; the joints below re-expressed in the ancestor's link frame. The
        dynamics of the movable joints are those of the robot as it is."""
        links, joints, welded = dict(self.links), [], {}
        host = {self.root: (self.root, np.zeros(3), np.eye(3))}  # link → (its host, its frame in the host's)
        for joint in self.tree_order():
            name, p, R = host[joint.parent]
            p, R = p + R @ joint.position, R @ joint.rotation
            if joint.kind != "fixed":
                host[joint.child] = (joint.child, np.zeros(3), np.eye(3))
                joints.append(replace(joint, parent=name, position=p, rotation=R))
                continue
            host[joint.child] = (name, p, R)
            child = links.pop(joint.child)
            below = tuple(j.name for j in self.children(child.name))
            welded[joint.child] = Weld(name, joint.name, p, R, child.com, below)
            links[name] = _merged_link(links[name], child, p, R)
        return replace(self, links=links, joints=tuple(joints), welded=welded)


def _merged_link(a, c, p, R):
    """Link ``a`` carrying link ``c`` whose frame is at (``p``, ``R``) in ``a``'s: the mass
    of both, about their common centre of mass (parallel-axis rule), with both visuals."""
    mass, com_c = a.mass + c.mass, p + R @ c.com
    com = (a.mass * a.com + c.mass * com_c) / mass if mass > 0 else a.com

    def about(inertia, m, r):  # an inertia about a point r from the centre of mass
        return inertia + m * (r @ r * np.eye(3) - np.outer(r, r))
    inertia = about(a.inertia, a.mass, a.com - com) + about(R @ c.inertia @ R.T, c.mass, com_c - com)
    visuals = tuple(dict(v, position=(p + R @ np.asarray(v["position"])).tolist(),
                         rotation=(R @ np.asarray(v["rotation"])).tolist()) for v in c.visuals)
    return replace(a, mass=mass, com=com, inertia=inertia, visuals=a.visuals + visuals)




def read_urdf(path, package_dirs=()):
    """The Description of the URDF file at ``path``; ``package://`` mesh files are looked
    up in ``package_dirs`` (each holding package folders) and beside the file. A mistake
    in the file is a ModelError naming the file and the link or joint."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError) as err:
        raise ModelError(f"cannot read URDF {path}: {err}") from None
    if root.tag != "robot":
        raise ModelError(f"{path}: not a URDF file (the root element is <{root.tag}>, not <robot>)")
    dirs = tuple(package_dirs) + _default_package_dirs(path)
    materials = _materials(root, path)
    links = _unique_names((_link(element, path, dirs, materials) for element in root.findall("link")), path, "link")
    joints = _unique_names((_joint(element, path, links) for element in root.findall("joint")), path, "joint")
    description = Description(root.get("name") or _stem(path), str(path), links, tuple(joints.values()),
                              _root_link(links, joints.values(), path), dirs)
    _check_tree(description)
    return description


def _unique_names(items, path, what):
    """{name: item} of links or joints, refusing a name given twice."""
    named = {}
    for item in items:
        if item.name in named:
            raise ModelError(f"{path}: {what} '{item.name}' is defined twice")
        named[item.name] = item
    return named


def _root_link(links, joints, path):
    """The one link no joint hangs (each link hangs from one joint at most)."""
    children = [j.child for j in joints]
    twice = sorted({c for c in children if children.count(c) > 1})
    if twice:
        raise ModelError(f"{path}: links {twice} hang from more than one joint")
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise ModelError(f"{path}: expected one root link (a link no joint hangs), found {roots or 'none'}")
    return roots[0]


def _check_tree(description):
    """Every joint hangs from the root link through other joints (no cycle)."""
    reached = {j.name for j in description.tree_order()}
    loose = [j.name for j in description.joints if j.name not in reached]
    if loose:
        raise ModelError(f"{description.path}: the joints do not form a tree from the root link "
                         f"'{description.root}': joints {loose} do not hang from it (a cycle)")


def _default_package_dirs(path):
    """Beside the file, and two levels up (a ROS package ``pkg/urdf/robot.urdf``)."""
    here = os.path.dirname(os.path.abspath(path))
    return (here, os.path.dirname(here), os.path.dirname(os.path.dirname(here)))


def _name(element, path):
    """The ``name`` of a <link> or <joint> element."""
    name = element.get("name")
    if not name:
        raise ModelError(f"{path}: a <{element.tag}> without a name")
    return name


def _attribute(element, key, where):
    """The text of a required attribute of ``element``."""
    text = element.get(key)
    if text is None:
        raise ModelError(f"{where}: <{element.tag}> has no '{key}'")
    return text


def _child(element, tag, where):
    """The required child element ``tag`` of ``element``."""
    child = element.find(tag)
    if child is None:
        raise ModelError(f"{where}: no <{tag}>")
    return child


def _floats(element, key, where, count=3, default=None):
    """The ``count`` finite numbers of the attribute ``key`` (``default`` when absent, if given)."""
    text = element.get(key, default)
    if text is None:
        raise ModelError(f"{where}: <{element.tag}> has no '{key}'")
    try:
        values = np.array([float(x) for x in text.split()])
    except ValueError:
        values = None
    if values is None or values.size != count or not np.all(np.isfinite(values)):
        raise ModelError(f"{where}: <{element.tag} {key}> must be {count} finite number{'s' * (count > 1)}, "
                         f"got {text!r}")
    return values


def _number(element, key, where, default=None):
    """The finite number of the attribute ``key``."""
    return float(_floats(element, key, where, 1, default)[0])


def _origin(element, where):
    """(position, rotation) of an ``<origin>`` child (identity when absent)."""
    origin = element.find("origin")
    if origin is None:
        return np.zeros(3), np.eye(3)
    return (_floats(origin, "xyz", where, default="0 0 0"),
            rpy_matrix(*_floats(origin, "rpy", where, default="0 0 0")))


def _link(element, path, dirs, materials):
    name = _name(element, path)
    where = f"{path}: link '{name}'"
    mass, com, inertia = _inertial(element.find("inertial"), where)
    if mass < 0:
        raise ModelError(f"{where} has a negative mass {mass}")
    if not np.all(np.isfinite(inertia)):
        raise ModelError(f"{where}: its inertia overflows (in link axes: {inertia.tolist()})")
    eigenvalues = np.linalg.eigvalsh(inertia)
    if eigenvalues.min() < -max(URDF_INERTIA_RTOL * abs(eigenvalues).max(),
                                                                        URDF_INERTIA_ATOL):
        raise ModelError(f"{where}: its inertia is not positive semi-definite (principal moments "
                         f"{', '.join(f'{x:.3g}' for x in eigenvalues)}); no rigid body has it — fix the "
                         "<inertia> of the file")
    visuals = tuple(v for v in (_visual(x, path, where, dirs, materials) for x in element.findall("visual")) if v)
    return Link(name, mass, com, inertia, visuals)


def _inertial(inertial, where):
    """(mass, centre of mass, inertia in link axes) of an <inertial> (zero when absent)."""
    if inertial is None:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com, R = _origin(inertial, where)
    mass_element = inertial.find("mass")
    mass = _number(mass_element, "value", where) if mass_element is not None else 0.0
    node = inertial.find("inertia")
    i = {k: _number(node, k, where, "0") if node is not None else 0.0
         for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    local = np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]],
                      [i["ixz"], i["iyz"], i["izz"]]])
    with np.errstate(over="ignore", invalid="ignore"):
        return mass, com, R @ local @ R.T  # from the inertial frame to link axes


def _joint(element, path, links):
    name = _name(element, path)
    where = f"{path}: joint '{name}'"
    kind = element.get("type")
    if kind not in URDF_KINDS:
        raise ModelError(f"{where} is of type {kind!r}; supported: {', '.join(URDF_KINDS)}")
    parent, child = (_attribute(_child(element, end, where), "link", where) for end in ("parent", "child"))
    for link in (parent, child):
        if link not in links:
            raise ModelError(f"{where} names an unknown link '{link}'")
    position, rotation = _origin(element, where)
    axis = _axis(element, kind, where)
    limits, effort = _limits(element.find("limit"), kind, where)
    return UrdfJoint(name, kind, parent, child, position, rotation, axis, limits, effort)


def _axis(element, kind, where):
    """The unit axis of a movable joint (x when absent); a fixed joint's is not read (x)."""
    axis_element = element.find("axis")
    if kind == "fixed" or axis_element is None:
        return np.array([1.0, 0.0, 0.0])
    axis = _floats(axis_element, "xyz", where)
    axis = axis / (np.abs(axis).max() or 1.0)  # no overflow in the norm
    if np.linalg.norm(axis) == 0:
        raise ModelError(f"{where} has a zero axis")
    return axis / np.linalg.norm(axis)


def _limits(limit, kind, where):
    """((lower, upper) or None, effort or NaN) of a <limit>; lower ≤ upper."""
    if limit is None:
        return None, None
    effort = _number(limit, "effort", where) if "effort" in limit.attrib else float("nan")
    if kind not in ("revolute", "prismatic") or "lower" not in limit.attrib or "upper" not in limit.attrib:
        return None, effort
    lower, upper = _number(limit, "lower", where), _number(limit, "upper", where)
    if lower > upper:
        raise ModelError(f"{where}: its <limit> has lower {lower} > upper {upper}")
    return (lower, upper), effort


def _materials(root, path):
    """{name: rgba or None} of the robot's named <material> elements."""
    return {_attribute(m, "name", f"{path}: a <material>"): _color(m, f"{path}: material '{m.get('name')}'")
            for m in root.findall("material")}


def _color(material, where):
    color = material.find("color") if material is not None else None
    return _floats(color, "rgba", where, 4).tolist() if color is not None else None


def _visual(element, path, where, dirs, materials):
    """A geometry dict (io/parts.py) in link axes, or None for one that cannot be drawn."""
    geometry = element.find("geometry")
    if geometry is None or len(geometry) == 0:
        return None
    shape = geometry[0]
    where = f"{where}: <visual>"
    position, rotation = _origin(element, where)
    material = element.find("material")
    color = _color(material, where) or (materials.get(material.get("name")) if material is not None else None)
    out = {"position": position.tolist(), "rotation": rotation.tolist(), "color": color or [0.7, 0.7, 0.7, 1.0]}
    if shape.tag == "mesh":
        file = resolve_mesh(_attribute(shape, "filename", where), path, dirs)
        scale = _floats(shape, "scale", where, default="1 1 1")
        return dict(out, shape="mesh", file=file, scale=scale.tolist()) if file else None
    if shape.tag not in SIZES:
        return None
    size = [float(x) for key, count in SIZES[shape.tag] for x in _floats(shape, key, where, count)]
    if min(size) < 0:
        raise ModelError(f"{where}: a <{shape.tag}> of negative size {size}")
    return dict(out, shape=shape.tag, size=size)


SIZES = {"box": (("size", 3),), "sphere": (("radius", 1),), "cylinder": (("radius", 1), ("length", 1))}


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
