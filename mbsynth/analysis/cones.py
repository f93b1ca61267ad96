"""Friction cones of held contacts whose forces their rows do not determine.

Held contacts that share a load through dependent rows (a table on four legs, a box on
several corners: their gap and slip rows outnumber the motions they stop) have a unique
motion (Result 3: q̈ is unique while [M; A] has full column rank) but forces
λ = λ₀ + W z with z free (Aᵀ W = 0, reactions.indeterminate). They stick when some z puts
every sticking contact's force in its Coulomb cone ‖λ_t‖ ≤ μ λ_n and every other held gap's
λ_n ≥ 0. ``Shared.margin`` decides it: the least over z of the largest violation

    s* = min_z max( ‖λ_t,i‖ − μ_i λ_n,i ,  −λ_n,j ),

a convex problem (second-order cones) solved by outer approximation: linear programs
(HiGHS) over polygons circumscribing each cone, each refined by the cone's tangent plane at
the force the last program chose, until the true violation there is within CONE_TOL of the
program's value (or, well inside the cones, until that violation is below −CONE_DEPTH: only
its sign matters there, the events' roots are where s* is near zero). The polygons contain the cones, so each program's value is a lower bound
on s* (a positive one proves that no distribution of the forces sticks) and the true
violation at its force an upper bound. The exact circular cone is kept, not a pyramid: a
contact breaks away at μ λ_n along every direction, as a single determinate contact does
(impacts.py), and s* is a continuous function of the state, so a group's breakaway is an
event found by root finding on it.

The forces reported where they are not determined: the minimum-norm λ₀ where it lies in
the cones (then nothing changes where it already did), otherwise the program's force at
s* (deterministic: HiGHS's simplex on the same data gives the same vertex; where it gives
none, its interior point method's crossover: ``program``).
"""

from typing import NamedTuple

import numpy as np
from scipy.optimize import linprog

from ..core.errors import SolveError
from ..core.tolerances import CONE_DEPTH, CONE_TOL, DEPENDENT_RTOL, LP_FEASIBILITY_TOL

CONE_CUTS = 8  # the first polygon circumscribing each friction cone has this many sides
CONE_ROUNDS = 100  # cutting-plane programs at most (each halves the angle of the polygon's worst corner)
LP_METHODS = ("highs-ds", "highs-ipm")  # ``program``: HiGHS's dual simplex, its interior point where it fails


class Cone(NamedTuple):
    """A sticking contact: the index of its gap's force in λ, those of its slip rows' (its
    tangential force), its μ."""

    normal: int
    tangential: tuple
    mu: float


class Shared:
    """The held rows' forces λ = λ₀ + W z of one motion (module docstring): ``cones`` the
    sticking contacts, ``normals`` the indices in λ of the other held gaps (λ_n ≥ 0),
    ``scale`` the size of the forces (the programs are solved in its units)."""

    def __init__(self, lam, W, cones, normals, scale):
        self.lam, self.W, self.cones, self.normals = lam, W, list(cones), list(normals)
        self.scale = max(scale, np.abs(lam).max(initial=0.0)) or 1.0

    def violation(self, lam, with_cones=True):
        """The largest of ‖λ_t,i‖ − μ_i λ_n,i (``with_cones``) and −λ_n,j over the rows."""
        found = [-lam[j] for j in self.normals]
        if with_cones:
            found += [np.linalg.norm(lam[list(c.tangential)]) - c.mu * lam[c.normal] for c in self.cones]
        else:
            found += [-lam[c.normal] for c in self.cones]
        return max(found, default=-np.inf)

    def margin(self, with_cones=True):
        """(s*, the forces λ chosen): ``with_cones`` False: with the gaps' signs only (the
        contact set, impacts.py's ``_contact_sets``). s* ≤ 0: some distribution holds."""
        if self.violation(self.lam, with_cones) <= 0:
            return self._optimum(with_cones)[0], self.lam
        return self._optimum(with_cones)

    def _optimum(self, with_cones):
        """(s*, λ at s*) by the cutting-plane programs (module docstring)."""
        lam0, W = self.lam / self.scale, self.W
        k = W.shape[1]
        cones = self.cones if with_cones else []
        normals = self.normals + ([] if with_cones else [c.normal for c in self.cones])
        angles = 2 * np.pi * np.arange(CONE_CUTS) / CONE_CUTS
        cuts = {i: [np.array([np.cos(a), np.sin(a)]) for a in angles] for i in range(len(cones))}
        best = (np.inf, self.lam)
        for _ in range(CONE_ROUNDS):
            rows, rhs = [], []
            for j in normals:  # −λ_j − s ≤ 0
                rows.append(np.append(-W[j], -1.0))
                rhs.append(lam0[j])
            for i, c in enumerate(cones):  # u·λ_t − μ λ_n − s ≤ 0
                t = list(c.tangential)
                for u in cuts[i]:
                    rows.append(np.append(u @ W[t] - c.mu * W[c.normal], -1.0))
                    rhs.append(-(u @ lam0[t] - c.mu * lam0[c.normal]))
            found = program(np.array(rows), np.array(rhs))
            lam = lam0 + W @ found.x[:k]
            true = self.violation(lam * self.scale, with_cones) / self.scale
            if true < best[0]:
                best = (true, lam * self.scale)
            if true - found.fun <= CONE_TOL or true <= -CONE_DEPTH:  # met, or well inside: its sign suffices
                break
            for i, c in enumerate(cones):
                tangential = lam[list(c.tangential)]
                size = np.linalg.norm(tangential)
                if size - c.mu * lam[c.normal] > found.fun + CONE_TOL and size > 0:
                    cuts[i].append(tangential / size)
        return best[0] * self.scale, best[1]


def program(rows, rhs):
    """linprog's result for min s over (z, s) subject to rows · (z, s) ≤ rhs, s ≥ −1: by
    HiGHS's dual simplex, or where it ends without a solution (it may stop "Not Set" on a
    program it solves at other tolerances), by HiGHS's interior point method (its crossover
    ends at a vertex too). SolveError where neither gives one: the program always has one
    (s large enough is feasible, s ≥ −1 bounds it)."""
    k = rows.shape[1] - 1
    for method in LP_METHODS:
        found = linprog(np.append(np.zeros(k), 1.0), A_ub=rows, b_ub=rhs, bounds=[(None, None)] * k + [(-1.0, None)],
                        method=method, options={"primal_feasibility_tolerance": LP_FEASIBILITY_TOL,
                                                "dual_feasibility_tolerance": LP_FEASIBILITY_TOL})
        if found.x is not None:
            return found
    raise SolveError(f"the friction cones' linear program ({rows.shape[0]} rows over {k} free forces) got no "
                     f"solution from HiGHS: {found.message}")


def shared_rows(W, rows):
    """Whether the free forces W (columns) reach any of the indices ``rows`` of λ."""
    if not W.shape[1]:
        return False
    weight = np.abs(W).max(axis=1)
    return bool((weight[list(rows)] > DEPENDENT_RTOL * weight.max()).any())
