"""The Pinocchio model equivalent to a System of rigid bodies and joints, and the maps
between the two descriptions of a state.

Pinocchio describes a mechanism by a tree of joints in reduced coordinates (q, v) and
closes loops with ``RigidConstraintModel``s; mbsynth gives every body seven coordinates
joined by constraints. The twin of a System is built as follows:

- each robot (``System.robots``) is Pinocchio's own model of its URDF (Pinocchio's
  parser, not ours), with a free-flyer root when floating, grafted at its base;
- every other rigid body hangs from a body already placed by the joint between them:
  fixed (welded to that body), revolute (``JointModelRZ``) or prismatic (``JointModelPZ``)
  in the joint's frame; a body no such joint reaches is a free-flyer;
- the remaining joints close loops: fixed → ``CONTACT_6D``, spherical → ``CONTACT_3D``,
  revolute → two ``CONTACT_3D`` at two points of its axis (the frame origin and one
  metre along z), which hold the same five freedoms (one of the six rows is redundant,
  as Pinocchio's proximal solver allows).

State maps. Pinocchio → mbsynth is forward kinematics: a body at placement X in joint i
has the world pose oMᵢ X and the spatial velocity X⁻¹ vᵢ in its own axes. mbsynth →
Pinocchio reads each Pinocchio joint off the bodies as expressions of their coordinates:
a revolute joint's ``angle`` and ``angle_rate`` (constraints.joints; a continuous joint's
q is (cos θ, sin θ)), a prismatic joint's ``displacement`` and its rate, a free-flyer's
frame origin p, quaternion (x, y, z, w — Pinocchio's order) and spatial velocity in its
own axes (Rᵀṗ, Rᵀω). Joint accelerations are the time derivatives of these rates,
v̇ = (∂w/∂q̇) q̈ + (∂w/∂q) q̇, compiled once per joint: for a free-flyer,
d/dt(Rᵀṗ) = Rᵀp̈ − ω_local × v_local and d/dt(Rᵀω) = Rᵀω̇, which is Pinocchio's spatial
(not classical) acceleration of a free-flyer joint.
"""

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import sympy as sp

from ..model.constraints.joints import Joint
from ..core.errors import ModelError
from ..core.joint_kinds import KINDS, WELD
from ..core.kinematics import body_rate_matrix, rotation
from ..compiled.nodes import RIGID_NODE
from ..model.parts import LINK_FRAME, Frame
from ..model.parts.base import frame_velocity
from ..symbolic.derive import compile_function, jacobian
from ..core.tolerances import PROXIMAL_ACCURACY, PROXIMAL_MU

# per kind its Pinocchio counterparts (core/joint_kinds.py: a kind's ``pinocchio``): the joint
# models that hang a body (WELD: on its parent's joint) and the rigid constraints that close a
# loop (type, point offsets along the frame's z)
TREE_JOINTS = {name: kind.pinocchio.tree for name, kind in KINDS.items() if kind.pinocchio.tree}
LOOPS = {name: (getattr(pin.ContactType, kind.pinocchio.loop[0]), kind.pinocchio.loop[1])
         for name, kind in KINDS.items() if kind.pinocchio.loop}
PROXIMAL = (PROXIMAL_ACCURACY, PROXIMAL_MU, 200)  # constraintDynamics: accuracy, μ, iterations


def no_twin(system, why):
    return ModelError(f"model '{system.name}' has no equivalent Pinocchio model: {why}")


@dataclass(frozen=True)
class Placed:
    """A body in the Pinocchio tree: its frame (centre of mass, body axes) at
    ``placement`` in the frame of joint ``joint``."""

    joint: int
    placement: pin.SE3


@dataclass(frozen=True)
class Loop:
    """A loop-closing mbsynth joint ``name``: Pinocchio's constraints ``first`` … ``first +
    len(offsets) − 1``, one per point at ``offsets`` along the joint frame's z (``LOOPS``),
    their rows ``rows`` of ``data.lambda_c``, and whether its child is the world."""

    name: str
    first: int
    offsets: tuple
    rows: slice
    to_world: bool


class Coordinate:
    """One Pinocchio joint read off mbsynth's state: ``positions`` (its nq entries of q)
    and ``rates`` (its nv entries of v) as expressions of the model's symbols, compiled
    with the rates' time derivatives. ``kind``: revolute, continuous, prismatic or free;
    ``limits``: (lower, upper) of its q entries; ``torque``: the parameter driving it;
    ``sign``: −1 where Pinocchio's joint runs from the mbsynth joint's child to its parent."""

    def __init__(self, name, joint_id, model, kind, positions, rates, system, limits=None, torque=None, sign=1):
        self.name, self.joint_id, self.kind, self.torque = name, joint_id, kind, torque
        self.sign = sign  # −1: the mbsynth joint walked from child to parent (its values and reaction reversed)
        joint = model.joints[joint_id]
        self.idx_q, self.nq, self.idx_v, self.nv = joint.idx_q, joint.nq, joint.idx_v, joint.nv
        self.limits = limits
        q, qd = list(system.q_symbols), list(system.qd_symbols)
        qdd = [sp.Symbol(f"{s}_ddot") for s in system.coordinates]
        rates = sp.Matrix(rates)
        dots = jacobian(rates, qd) * sp.Matrix(qdd) + jacobian(rates, q) * sp.Matrix(qd)
        exprs = [sp.Matrix(positions), rates, dots]
        used = set().union(*(e.free_symbols for e in exprs))
        self.indices = np.array([i for i in range(len(q)) if {q[i], qd[i], qdd[i]} & used], dtype=int)
        local = [int(i) for i in self.indices]
        self._evaluate = compile_function(([q[i] for i in local], [qd[i] for i in local], [qdd[i] for i in local],
                                           list(system.parameter_symbols)), exprs)

    def evaluate(self, q, qd, qdd, p):
        """(q entries, v entries, v̇ entries) of this joint at the maximal state."""
        i = self.indices
        return tuple(x.ravel() for x in self._evaluate(q[i], qd[i], qdd[i], p))


class Twin:
    """Pinocchio's ``model`` of a System, its loop ``constraints``, and the state maps."""

    def __init__(self, system):
        self.system = system
        self.model = pin.Model()
        self.bodies, self.coordinates, self.constraints, self.loops = {}, [], [], []
        parts = {p.name: p for p in system.parts}
        # a Pinocchio body is what a kernel rigid node is: mass, inertia about the centre of mass, a quaternion
        odd = [p.name for p in system.parts if p.part_type.node != RIGID_NODE]
        if odd:
            raise no_twin(system, f"parts {odd} are not rigid bodies")
        own = {f"{p.name}.unit_quaternion" for p in system.parts}
        joints = [c for c in system.constraints if c.name not in own]
        odd = [c.name for c in joints if not isinstance(c, Joint) or any(x != 0 for x in c.C)]
        if odd:
            raise no_twin(system, f"constraints {odd} are not ideal joints")
        self.model.gravity = pin.Motion(self._gravity(), np.zeros(3))
        used = set()
        for robot in system.robots:
            used |= self._add_robot(robot, parts)
        self._add_tree([j for j in joints if j.name not in used], parts, used)
        self._add_loops([j for j in joints if j.name not in used])
        self.data = self.model.createData()
        self.constraint_data = [c.createData() for c in self.constraints]
        if self.constraints:
            pin.initConstraintDynamics(self.model, self.data, self.constraints, self.constraint_data)
        torques = {c.name for c in self.coordinates if c.torque}
        self.torque_elements = {f"{name}.actuation" for name in torques}

    # -- building -------------------------------------------------------------------
    def _gravity(self):
        values = {sp.Symbol(k): v for k, v in self.system.parameters.items()}
        found = {tuple(float(x.subs(values)) for x in p.gravity) for p in self.system.parts}
        if len(found) > 1:
            raise no_twin(self.system, f"its bodies feel different gravities {sorted(found)}")
        return np.array(found.pop() if found else (0.0, 0.0, 0.0))

    def _value(self, expr):
        return float(sp.sympify(expr).subs({sp.Symbol(k): v for k, v in self.system.parameters.items()}))

    def _se3(self, frame):
        """A frame's placement on its part (or in the world) as a Pinocchio SE3."""
        R = np.array([[self._value(x) for x in row] for row in frame.rotation.tolist()])
        return pin.SE3(R, np.array([self._value(x) for x in frame.position]))

    def _inertia(self, part, placement):
        """The body's inertia in Pinocchio, as seen from the joint frame it is placed in."""
        J = np.array([[self._value(x) for x in row] for row in part.inertia.tolist()])
        return placement.act(pin.Inertia(self._value(part.mass), np.zeros(3), J))

    def _add_robot(self, robot, parts):
        """Graft Pinocchio's model of the robot's URDF; returns the constraints it replaces."""
        urdf = robot.description.path
        source = (pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer()) if robot.floating
                  else pin.buildModelFromUrdf(urdf))
        base = pin.SE3.Identity() if robot.floating else pin.SE3(robot.base[1], robot.base[0])
        ids = {0: 0}
        root = parts[robot.parts[robot.description.root]]
        for i in range(1, source.njoints):
            name, parent = source.names[i], source.parents[i]
            placement = base * source.jointPlacements[i] if parent == 0 else source.jointPlacements[i]
            joint_name = robot.joints.get(name, robot.prefix + name)
            ids[i] = self.model.addJoint(ids[parent], source.joints[i], placement, joint_name)
            self.model.appendBodyToJoint(ids[i], source.inertias[i], pin.SE3.Identity())
            j = source.joints[i]
            limits = (source.lowerPositionLimit[j.idx_q:j.idx_q + j.nq], source.upperPositionLimit[j.idx_q:j.idx_q + j.nq])
            if j.shortname() == "JointModelFreeFlyer":
                self._free_flyer(joint_name, ids[i], root, root.frames[LINK_FRAME])
            else:
                constraint = next(c for c in self.system.constraints if c.name == robot.joints[name])
                self.coordinates.append(_joint_coordinate(joint_name, ids[i], self.model, constraint, 1, self.system,
                                                          _kind(j), limits, robot.torques.get(name)))
        for link, part in robot.parts.items():
            frame = source.frames[source.getFrameId(link, pin.FrameType.BODY)]
            placement = frame.placement * pin.SE3(np.eye(3), robot.description.links[link].com)
            if frame.parentJoint == 0:
                placement = base * placement
            self.bodies[part] = Placed(ids[frame.parentJoint], placement)
        return set(robot.joints.values()) | ({robot.base_joint} if not robot.floating else set())

    def _free_flyer(self, name, joint_id, part, frame):
        """A free-flyer joint at ``frame`` (identity axes) of ``part``."""
        p = part.pose(frame)[0]
        u = sp.Matrix(part.q[3:])
        R = rotation(u)
        v_local = R.T * frame_velocity(p, self.system.q_symbols, self.system.qd_symbols)
        w_local = 2 * body_rate_matrix(u) * sp.Matrix(part.qd[3:])
        positions = [*p, u[1], u[2], u[3], u[0]]  # Pinocchio's quaternion order (x, y, z, w)
        self.coordinates.append(Coordinate(name, joint_id, self.model, "free", positions, [*v_local, *w_local],
                                           self.system))

    def _add_tree(self, joints, parts, used):
        """Hang every body not yet placed from a placed one by a revolute, prismatic or
        fixed joint, breadth first; a body no such joint reaches becomes a free-flyer (its
        spherical joints then close loops)."""
        self.bodies.setdefault(None, Placed(0, pin.SE3.Identity()))  # the world
        while len(self.bodies) <= len(parts):
            edges = [(j, side) for j in joints if j.name not in used and j.joint_kind in TREE_JOINTS
                     for side in (0, 1)
                     if _name(j.parts[side]) in self.bodies and _name(j.parts[1 - side]) not in self.bodies]
            edge = edges[0] if edges else None
            if edge is None:
                part = next(p for name, p in parts.items() if name not in self.bodies)
                jid = self.model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), f"{part.name}.free")
                self.model.appendBodyToJoint(jid, self._inertia(part, pin.SE3.Identity()), pin.SE3.Identity())
                self.bodies[part.name] = Placed(jid, pin.SE3.Identity())
                self._free_flyer(f"{part.name}.free", jid, part, Frame(part.name, "origin", sp.zeros(3, 1), sp.eye(3)))
                continue
            joint, side = edge
            used.add(joint.name)
            self._hang(joint, side)

    def _hang(self, joint, side):
        """Place the body on side 1 − ``side`` of ``joint`` from the placed body on ``side``
        (a joint walked from child to parent moves with the opposite sign)."""
        placed = self.bodies[_name(joint.parts[side])]
        at = placed.placement * self._se3(joint.frames[side])  # the joint frame on the placed side, in its joint
        part = joint.parts[1 - side]
        body = self._se3(joint.frames[1 - side]).inverse()  # the new body's frame in the joint frame
        if TREE_JOINTS[joint.joint_kind] == WELD:
            self.bodies[part.name] = Placed(placed.joint, at * body)
            self.model.appendBodyToJoint(placed.joint, self._inertia(part, at * body), pin.SE3.Identity())
            return
        jid = self.model.addJoint(placed.joint, getattr(pin, TREE_JOINTS[joint.joint_kind])(), at, joint.name)
        self.model.appendBodyToJoint(jid, self._inertia(part, body), pin.SE3.Identity())
        self.bodies[part.name] = Placed(jid, body)
        self.coordinates.append(_joint_coordinate(joint.name, jid, self.model, joint, 1 if side == 0 else -1,
                                                  self.system, joint.joint_kind))

    def _add_loops(self, joints):
        for joint in joints:
            if joint.joint_kind not in LOOPS:
                raise no_twin(self.system, f"joint '{joint.name}' ({joint.joint_kind}) is neither a tree joint "
                                           f"({', '.join(TREE_JOINTS)}) nor one that Pinocchio's rigid "
                                           f"constraints close ({', '.join(LOOPS)})")
            kind, offsets = LOOPS[joint.joint_kind]
            ends = [self.bodies[_name(part)] for part in joint.parts]
            frames = [end.placement * self._se3(frame) for end, frame in zip(ends, joint.frames)]
            start = self.loops[-1].rows.stop if self.loops else 0
            size = len(offsets) * (6 if kind == pin.ContactType.CONTACT_6D else 3)
            self.loops.append(Loop(joint.name, len(self.constraints), offsets, slice(start, start + size),
                                   joint.parts[1] is None))
            for offset in offsets:
                at = [frame * pin.SE3(np.eye(3), np.array([0.0, 0.0, offset])) for frame in frames]
                self.constraints.append(pin.RigidConstraintModel(kind, self.model, ends[0].joint, at[0],
                                                                 ends[1].joint, at[1], pin.ReferenceFrame.LOCAL))

    # -- maps -----------------------------------------------------------------------
    def to_maximal(self, q, v):
        """mbsynth's (q, q̇) of Pinocchio's (q, v), by forward kinematics."""
        pin.forwardKinematics(self.model, self.data, q, v)
        qm, qdm = [], []
        for part in self.system.parts:
            placed = self.bodies[part.name]
            pose = self.data.oMi[placed.joint] * placed.placement
            velocity = placed.placement.actInv(self.data.v[placed.joint])
            R = pose.rotation
            x, y, z, w = pin.Quaternion(R).coeffs()
            u = np.array([w, x, y, z])
            omega = R @ velocity.angular
            G = np.column_stack([-u[1:], u[0] * np.eye(3) + pin.skew(u[1:])])  # world_rate_matrix
            qm += [*pose.translation, *u]
            qdm += [*(R @ velocity.linear), *(G.T @ omega / 2)]  # ω = 2 G u̇, G Gᵀ = I, G u = 0
        return np.array(qm), np.array(qdm)

    def to_pinocchio(self, q, qd, qdd=None):
        """Pinocchio's (q, v, v̇) of mbsynth's (q, q̇, q̈) (v̇ is zero without q̈)."""
        qdd = np.zeros_like(q) if qdd is None else qdd
        p = self.system.parameter_values
        qp, v, a = np.zeros(self.model.nq), np.zeros(self.model.nv), np.zeros(self.model.nv)
        for c in self.coordinates:
            qp[c.idx_q:c.idx_q + c.nq], v[c.idx_v:c.idx_v + c.nv], a[c.idx_v:c.idx_v + c.nv] = c.evaluate(q, qd, qdd, p)
        return qp, v, a

    def velocity_map(self, q):
        """S = ∂q̇/∂v at Pinocchio's q (q̇ = S v, mbsynth's velocities are linear in v)."""
        return np.column_stack([self.to_maximal(q, e)[1] for e in np.eye(self.model.nv)])

    def accelerations(self, q, v, tau):
        """Pinocchio's v̇: ``aba``, or ``constraintDynamics`` when loops are closed."""
        if not self.constraints:
            return pin.aba(self.model, self.data, q, v, tau)
        settings = pin.ProximalSettings(*PROXIMAL)
        return pin.constraintDynamics(self.model, self.data, q, v, tau, self.constraints, self.constraint_data,
                                      settings)

    def loop_wrench_maps(self):
        """{loop joint name: W}, W (6 × the loop's rows of ``data.lambda_c``): the wrench
        [force; torque] the joint's parent exerts on its child, at the child frame's
        origin, in its axes, is W λ — at the configuration of the last
        ``accelerations`` (``constraintDynamics``). A loop whose child is the world has none.

        Pinocchio's convention (constrained-dynamics.hxx; M v̇ = τ − b + Jᵀλ): a
        constraint's λ, in the LOCAL axes of its frame c1 on joint1 (the mbsynth joint's
        parent), acts on joint1 at c1 and, reversed, on joint2 (the child) at c2: a
        CONTACT_3D's force −λ at the point c2, a CONTACT_6D's wrench −λ carried from c1
        to c2. A revolute joint's two points, the frame origin and one metre along its z,
        add up to one wrench at the origin; the split of their forces along z is Pinocchio's
        (any split gives the same wrench)."""
        maps = {}
        for loop in (loop for loop in self.loops if not loop.to_world):
            blocks = []
            for k, offset in enumerate(loop.offsets):
                model = self.constraints[loop.first + k]
                oMc1 = self.data.oMi[model.joint1_id] * model.joint1_placement
                oMc2 = self.data.oMi[model.joint2_id] * model.joint2_placement
                c2Mc1 = oMc2.actInv(oMc1)
                if model.type == pin.ContactType.CONTACT_6D:
                    on_c2 = -c2Mc1.toDualActionMatrix()  # the wrench −λ moved from c1 to c2
                else:
                    on_c2 = np.vstack([-c2Mc1.rotation, np.zeros((3, 3))])  # the force −λ at the point c2
                at_origin = pin.SE3(np.eye(3), np.array([0.0, 0.0, offset])).toDualActionMatrix()
                blocks.append(at_origin @ on_c2)
            maps[loop.name] = np.hstack(blocks)
        return maps


def _joint_coordinate(name, joint_id, model, joint, sign, system, kind, limits=None, torque=None):
    """A revolute, continuous or prismatic Pinocchio joint read off an mbsynth Joint."""
    motion, = KINDS[joint.joint_kind].motions  # a tree joint's one free motion: angle or displacement
    position, rate = getattr(joint, motion), getattr(joint, f"{motion}_rate")
    positions = [sp.cos(position), sp.sin(position)] if kind == "continuous" else [sign * position]
    return Coordinate(name, joint_id, model, kind, positions, [sign * rate], system, limits, torque, sign)


def _kind(joint_model):
    name = joint_model.shortname()
    if name.startswith("JointModelRUB") or name == "JointModelRevoluteUnboundedUnaligned":
        return "continuous"
    if name.startswith("JointModelR"):
        return "revolute"
    if name.startswith("JointModelP"):
        return "prismatic"
    raise ValueError(f"unexpected Pinocchio joint {name}")


def _name(part):
    return None if part is None else part.name


