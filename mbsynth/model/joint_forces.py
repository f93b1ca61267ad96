"""Force elements along a joint's free motion (forces.ForceElement, added to Q).

A revolute joint turns by ``angle`` θ at ``angle_rate``, a prismatic joint slides by
``displacement`` s at ``displacement_rate`` (constraints.joints.Joint); a cylindrical
joint does both. Along these:

    actuation   effort τ(t) along the rate: a torque about the axis, a force along it
    spring      V = ½ k (θ − θ0)²  or  ½ k (s − s0)²,   damper effort −c · rate

θ is atan2 of the frames' x axes, in (−π, π]: a torsional spring holds over less than
a turn from θ = 0 (its potential jumps where θ wraps).
"""

import sympy as sp

from ..core.joint_kinds import EFFORTS, KINDS
from .forces import ForceElement

# the joint's (position, rate) attribute along which each effort acts (core/joint_kinds.EFFORTS)
MOTIONS = {effort: (motion, f"{motion}_rate") for motion, effort in EFFORTS.items()}


def joint_motion(joint):
    """What acts along the joint's one motion: "torque" (revolute), "force" (prismatic), else None
    (its kind's ``effort``, core/joint_kinds.py)."""
    return KINDS[joint.joint_kind].effort


def actuation(name, joint, efforts, q, qd, params):
    """A torque about / force along the joint's axis: ``efforts`` maps "torque" and/or
    "force" to expressions (of t, parameters, coordinates)."""
    rates = [MOTIONS[key][1] for key in efforts]
    gradients = [joint.rate_gradient(rate) for rate in rates]
    coordinates = set(q) | set(qd)
    if all(g is not None for g in gradients) and not any(sp.sympify(e).free_symbols & coordinates
                                                         for e in efforts.values()):
        return ForceElement.along_rates(name, list(efforts.values()), gradients, joint.placed, params, joint=joint.name)
    pairs = [(effort, getattr(joint, rate)) for effort, rate in zip(efforts.values(), rates)]
    return ForceElement(name, 0, pairs, q, qd, params, joint=joint.name)


def joint_spring(name, joint, stiffness, damping, rest, q, qd, params):
    """A torsional (revolute) or linear (prismatic) spring k with rest position ``rest``
    and a damper c along the joint's one motion."""
    position, rate = (getattr(joint, attr) for attr in MOTIONS[joint_motion(joint)])
    return ForceElement(name, stiffness * (position - rest) ** 2 / 2, [(-damping * rate, rate)], q, qd, params,
                        joint=joint.name)
