"""Joint friction as the non-ideal force C of (2.6), not as a force in Q.

A revolute joint rubs along its rate w = ``angle_rate``, a prismatic joint along
w = ``displacement_rate``; friction acts along the generalized direction ∂w/∂q̇:

    viscous   C = −c w ∂w/∂q̇                 (a function of the state: the joint's own C)
    Coulomb   C = −μ r N sign(w) ∂w/∂q̇       (r the pin radius; r = 1 for a prismatic joint)

N is the load the joint carries, which depends on the constraint force and so on q̈:
Coulomb friction is a non-ideal constraint (Udwadia & Kalaba 2001). ``coulomb_motion``
finds N by a fixed-point iteration: solve (2.14) with C for the current N, take the
joint's multipliers λ from Q_c − C = −Aᵀλ (with Q_c = M q̈ − Q of (2.5), the
minimum-norm λ), update N, repeat until N changes by less than ``COULOMB_LOAD_RTOL`` of itself
(or than the rounding error of λ, for a joint that carries next to no load).
The load rows are the joint's translational ones, whose gradient with respect to the
child's point p_B is a unit vector: for a revolute joint φ = p_B − p_A, so the
reaction force on the child is −λ and N = |λ| (axial and radial load alike); for a
prismatic joint φ = (p_B − p_A)·x_A, (p_B − p_A)·y_A, so the force across the axis is
−(λ_x x_A + λ_y y_A) and N = |λ| (the reaction moment of the orientation rows is not
counted).

Not modelled: sticking. At w = 0 exactly the Coulomb term is zero, so a joint at rest
never holds against a load — a block at rest on any slope starts to slide, and friction
acts from its first motion on. Where the constraints are redundant λ is not unique and
the minimum-norm λ decides N. Where μ is so large that a unit of load, through the
friction it causes, changes the load by more than a unit (Painlevé's paradox: then the
equations may have no solution, or several), the iteration does not converge and
``SolveError`` names the joints.
"""

from dataclasses import dataclass, replace

import numpy as np
import sympy as sp

from ..core.equations import equilibrate_rows
from ..core.errors import SolveError
from ..core.joint_kinds import FRICTION_KINDS, KINDS
from ..symbolic.derive import T_SYMBOL, compile_function
from ..core.tolerances import COULOMB_LOAD_RTOL, COULOMB_NOISE, RANK_RTOL

MAX_ITERATIONS = 50


@dataclass(frozen=True)
class Friction:
    """Friction coefficients of one joint (sympy expressions of parameters): ``viscous``
    c, ``coulomb`` μ and ``radius`` r, the pin radius of a revolute joint."""

    viscous: sp.Expr = sp.S.Zero
    coulomb: sp.Expr = sp.S.Zero
    radius: sp.Expr = sp.S.One

    def viscous_force(self, joint, qd):
        """C = −c w ∂w/∂q̇ (a column over all coordinates)."""
        w = rate(joint)
        return -self.viscous * w * sp.Matrix([w]).jacobian(sp.Matrix(qd)).T

    def coulomb_force(self, joint, q, qd, params):
        """The joint's ``CoulombFriction``, or None without Coulomb friction."""
        return None if self.coulomb == 0 else CoulombFriction(joint, self.coulomb * self.radius, q, qd, params)


def rate(joint):
    """The rate w friction opposes at ``joint`` (its kind's ``friction.rate``, core/joint_kinds.py:
    revolute: angle_rate; prismatic: displacement_rate)."""
    if joint.joint_kind not in FRICTION_KINDS:
        raise ValueError(f"only {' and '.join(FRICTION_KINDS)} joints take friction, not a {joint.joint_kind} joint")
    return getattr(joint, KINDS[joint.joint_kind].friction.rate)


class CoulombFriction:
    """Coulomb friction at one joint: w, the direction μ r ∂w/∂q̇ of its C per unit load
    (on ``indices``), and ``load_rows``, the joint's rows whose λ is the load."""

    def __init__(self, joint, scale, q, qd, params):
        self.joint = joint.name
        w = rate(joint)
        used = w.free_symbols
        self.indices = np.array([i for i in range(len(q)) if q[i] in used or qd[i] in used], dtype=int)
        local_q, local_qd = [q[i] for i in self.indices], [qd[i] for i in self.indices]
        direction = scale * sp.Matrix([w]).jacobian(sp.Matrix(local_qd)).T
        self._evaluate = compile_function((T_SYMBOL, local_q, local_qd, list(params)), [w, direction])
        labels = [f"{joint.name}[{label}]" for label in KINDS[joint.joint_kind].friction.load_rows]
        self.load_rows = np.array([joint.row_names.index(x) for x in labels if x in joint.row_names], dtype=int)

    def evaluate(self, t, q, qd, p):
        """(w, μ r ∂w/∂q̇ on ``indices``) at the full state (q, q̇)."""
        w, direction = self._evaluate(t, q[self.indices], qd[self.indices], p)
        return float(w), direction.ravel()


def coulomb_motion(constraints, arrays, solve, t, q, qd, p):
    """The Motion with the Coulomb friction of the joints among ``constraints``.

    ``arrays`` is the system's Assembly at (t, q, q̇) and ``solve(C)`` the solver of
    (2.14) for a given C; the loads N are iterated to a fixed point (module docstring)."""
    n, sliding, rows, start = len(q), [], [], 0
    for con in constraints:
        coulomb = getattr(con, "coulomb", None)
        if coulomb is not None:
            w, direction = coulomb.evaluate(t, q, qd, p)
            if w != 0:
                force = np.zeros(n)
                force[coulomb.indices] = -np.sign(w) * direction
                sliding.append((coulomb.joint, force, slice(len(rows), len(rows) + len(coulomb.load_rows))))
                rows.extend(start + coulomb.load_rows)
        start += con.size
    if not sliding:
        return solve(arrays.C)
    Ae, norms = equilibrate_rows(arrays.A)
    # λ of the load rows from Aᵀλ = Q + C − M q̈, solved on the rows of A scaled to unit norm
    L = (np.linalg.pinv(Ae.T, rcond=RANK_RTOL) / norms[:, None])[rows]
    noise = COULOMB_NOISE * np.array([np.linalg.norm(L[s]) for _, _, s in sliding])
    N = np.zeros(len(sliding))
    for _ in range(MAX_ITERATIONS):
        C = arrays.C + sum(load * force for load, (_, force, _) in zip(N, sliding))
        motion = solve(C)
        inertial = arrays.M @ motion.qdd
        lam = L @ (arrays.Q + C - inertial)
        new = np.array([np.linalg.norm(lam[s]) for _, _, s in sliding])
        scale = np.linalg.norm(arrays.Q) + np.linalg.norm(C) + np.linalg.norm(inertial)
        change = np.abs(new - N)
        if np.all(change <= COULOMB_LOAD_RTOL * new + noise * scale):
            return replace(motion, C=C)
        N = new
    names = [name for (name, _, _), dN, load in zip(sliding, change, new) if dN > COULOMB_LOAD_RTOL * load]
    raise SolveError(f"Coulomb friction at joint(s) {', '.join(names)}: the joint load N did not settle "
                     f"in {MAX_ITERATIONS} iterations (last change {change.max():.3g} at N = {new.max():.3g}); "
                     "the friction coefficient may be too large for the friction force to be determined "
                     "(Painlevé's paradox)", constraints=names)
