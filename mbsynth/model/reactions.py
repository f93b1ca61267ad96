"""Reaction forces: the multipliers λ of the constraint rows and the wrench each joint carries.

The constraint force of (2.5) splits as Qc = M q̈ − Q = C + Aᵀλ: the non-ideal part C of
(2.6) and the ideal part Aᵀλ, which does no work on the virtual displacements (A v = 0)
and so lies in range(Aᵀ). λ has one entry per row of A; with the sign Qc − C = Aᵀλ, the
multiplier of a row φ = 0 is the effort along φ's gradient that the constraint applies — for
a row ``joint.angle − f(t)`` it is the torque about the joint's axis that makes the motion
(inverse dynamics by constraints). Where rows are dependent (a redundant loop) λ is not
unique: ``multipliers`` gives the minimum-norm one and marks the rows that share a
dependency.

A joint's wrench on its child is the generalized force its rows, its non-ideal C and its
force elements (actuation, springs, dampers: joint_forces.py) exert on the child's
coordinates, g = (Aᵀλ + C + Q_e) restricted to them, written as a force F and torque τ at
the reaction frame's origin: by virtual power g = Jᵀ[F; τ], J the frame's Jacobian
([ṗ; ω] = J q̇_child), solved on the child's motions (a quaternion's norm direction,
which moves nothing, left out: ``Part.idle_directions``). F and τ are given in the reaction
frame's axes: for a robot's joint, its child link frame, as Pinocchio's ``data.f``.
"""

import difflib
from dataclasses import dataclass

import numpy as np

from ..core.equations import equilibrate_rows
from ..core.tolerances import DEPENDENT_RTOL, RANK_RTOL



class Reactions(dict):
    """{constraint name: Reaction}; a name it lacks is a KeyError that says why: a robot's
    fixed joint merged away (``merge_fixed``: its link welded to its host, no joint left to
    carry a reaction), or the model's nearest constraint names."""

    def __init__(self, entries, merged):
        super().__init__(entries)
        self.merged = merged  # merged fixed joint's would-be constraint name -> its link

    def __missing__(self, name):
        if name in self.merged:
            raise KeyError(f"'{name}' is a fixed joint merged away with merge_fixed=True (its link "
                           f"'{self.merged[name]}' welded to its parent's body): no joint carries a reaction there; "
                           f"build the robot without merge_fixed to read it")
        near = difflib.get_close_matches(str(name), list(self), n=3)
        raise KeyError(f"no constraint named {name!r}" + (f"; nearest: {', '.join(near)}" if near else ""))


@dataclass(frozen=True)
class Reaction:
    """The reaction of one constraint: ``multipliers`` (λ of its rows), ``redundant`` (its rows
    share a dependency with others, so the split of λ among them is the minimum-norm one,
    not the only one), and for a joint ``force`` and ``torque``: the wrench the parent
    exerts on the child through the joint, at the reaction frame's origin, in its axes
    (None for other constraints)."""

    multipliers: np.ndarray
    redundant: bool
    force: np.ndarray = None
    torque: np.ndarray = None


def multipliers(A, f):
    """(λ, dependent): the minimum-norm λ with Aᵀλ = f (least squares when f ∉ range(Aᵀ)),
    and a mask of the rows that take part in a linear dependency among the rows of A. The
    rank is decided on the row-equilibrated A, by ``equations``' rank rule."""
    A, f = np.asarray(A, dtype=float), np.asarray(f, dtype=float)
    m = A.shape[0]
    if m == 0:
        return np.zeros(0), np.zeros(0, dtype=bool)
    U, s, Vt, rank, norms = _decomposed(A)
    mu = U[:, :rank] @ ((Vt[:rank] @ f) / s[:rank])  # Aeᵀ μ = f, μ = D λ
    lam = mu / norms
    basis = _left_null(U[:, rank:], norms)
    if basis.shape[1]:
        lam = lam - basis @ (basis.T @ lam)  # still a solution; now of least norm
        weight = np.abs(basis).max(axis=1)
        dependent = weight > DEPENDENT_RTOL * weight.max()
    else:
        dependent = np.zeros(m, dtype=bool)
    return lam, dependent


def indeterminate(A):
    """An orthonormal basis W (columns) of the λ with Aᵀλ = 0: the forces Aᵀλ = f leaves free
    (λ = λ₀ + W z), by ``multipliers``' rank rule; no columns where they are determined."""
    A = np.asarray(A, dtype=float)
    if A.shape[0] == 0:
        return np.zeros((0, 0))
    U, _, _, rank, norms = _decomposed(A)
    return _left_null(U[:, rank:], norms)


def _decomposed(A):
    """(U, s, Vᵀ, rank, row norms D) of the row-equilibrated Ae = D⁻¹A (its full SVD, the rank
    by ``equations``' rule)."""
    Ae, norms = equilibrate_rows(A)
    U, s, Vt = np.linalg.svd(Ae, full_matrices=True)
    return U, s, Vt, int(np.sum(s > RANK_RTOL * s[0])) if s.size and s[0] > 0 else 0, norms


def _left_null(U_null, norms):
    """The orthonormal basis of the left null space of A from that of its row-equilibrated
    form (wᵀA = 0 ⇔ D w in the left null space of Ae)."""
    null = U_null / norms[:, None]
    return np.linalg.qr(null)[0] if null.shape[1] else null


def wrench(pose, idle, generalized):
    """(force, torque) at the frame ``pose`` (joint_values.FramePose), in its axes, of the
    ``generalized`` force on the child's coordinates; ``idle``: the child's coordinate
    directions that carry no motion (columns, orthonormal)."""
    P = np.eye(len(generalized)) - idle @ idle.T
    w = np.linalg.lstsq(P @ pose.jacobian.T, P @ generalized, rcond=None)[0]
    R = pose.rotation
    return R.T @ w[:3], R.T @ w[3:]
