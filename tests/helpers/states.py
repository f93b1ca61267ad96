"""Random states of a System for the tests."""

import numpy as np

from mbsynth.model.parts import RigidBody


def random_state(system, rng, norm=1.0, tangent=False):
    """(q, q̇) drawn standard normal from ``rng``, each rigid body's quaternion scaled to
    ``norm`` (a number, or (low, high): one drawn uniformly per body) and, where ``tangent``,
    its rate made tangent to it (uᵀu̇ = 0)."""
    q = rng.standard_normal(system.n)
    qd = rng.standard_normal(system.n)
    for part, start in zip(system.parts, np.cumsum([0] + [len(p.coordinates) for p in system.parts])):
        if isinstance(part, RigidBody):
            u = slice(start + 3, start + 7)
            q[u] *= (rng.uniform(*norm) if isinstance(norm, tuple) else norm) / np.linalg.norm(q[u])
            if tangent:
                qd[u] -= q[u] * (q[u] @ qd[u]) / (q[u] @ q[u])
    return q, qd


def quaternion_of(system, part):
    """The slice of ``part``'s quaternion (qw, qx, qy, qz) in ``system``'s coordinates."""
    start = system.coordinates.index(f"{part}.qw")
    return slice(start, start + 4)
