"""Static equilibrium: a configuration where the model rests, q̈ = 0 at q̇ = 0 on its constraints.

Newton's method in the independent coordinates of the constraints' tangent space
(linearization.py): at an iterate q on φ(q, t) = 0, the acceleration at rest q̈ = f(q, 0)
is a tangent vector (A q̈ = b = 0 at rest for scleronomic rows), q̈ = N a with N the
tangent basis; its derivative along the tangent coordinates x is the block
K = ∂a/∂x of the linearization's A (the stiffness over the mass, in the tangent space).
The step solves K Δx = −a, moves q by N Δx (halved until max |q̈| decreases: a damped
Newton method) and puts q back on φ = 0 (projection.project_positions). Massless parts balance through their rows (a
``closure: auto`` balance is one of them), so their equilibrium comes with the rest.
"""

import numpy as np

from ..core.errors import SolveError
from .linearization import linearize
from .projection import project_positions
from ..core.tolerances import ACCELERATION_TOL, ISOLATED_RTOL

MAX_ITERATIONS = 50
HALVINGS = 20  # a Newton step is halved at most this often to lower |q̈|


def equilibrium(system, q=None, t=0.0, tolerance=ACCELERATION_TOL, max_iterations=MAX_ITERATIONS):
    """A static equilibrium of ``system`` near ``q`` (default: the initial positions), as
    an array in the model's coordinates. Raises SolveError when Newton's method finds none
    nearby, or when the equilibrium found is not isolated (a free direction: the
    coordinates along it are named)."""
    q = system.initial_state()[0] if q is None else np.array(q, dtype=float)
    zero = np.zeros(system.n)
    q = project_positions(system, t, q)
    size = np.inf
    for _ in range(max_iterations):
        lin = linearize(system, t, q, zero, inputs=())
        k = lin.k
        if k == 0:
            return q
        a = np.linalg.lstsq(lin.basis, lin.qdd, rcond=None)[0]
        K = lin.A[k:, :k]
        scale = 1.0 + np.abs(K).max()
        if np.abs(lin.qdd).max() <= tolerance * scale:
            _check_isolated(system, lin, K)
            return q
        step = lin.basis @ np.linalg.lstsq(K, -a, rcond=None)[0]
        q, size = _damped(system, t, q, step, np.abs(lin.qdd).max())
    raise SolveError(f"model '{system.name}': no static equilibrium found near the given configuration "
                     f"({max_iterations} Newton steps; last step {size:.3g}, largest q̈ "
                     f"{np.abs(lin.qdd).max():.3g} in {system.coordinates[int(np.argmax(np.abs(lin.qdd)))]})")


def _damped(system, t, q, step, worst):
    """(q moved by the largest of step, step/2, step/4 … that lowers max |q̈| at rest and
    can be put back on the constraints, that step's size): Newton's step damped."""
    zero = np.zeros(system.n)
    for _ in range(HALVINGS):
        try:
            moved = project_positions(system, t, q + step)
            if np.abs(system.motion(t, moved, zero).qdd).max() < worst:
                return moved, np.abs(step).max()
        except SolveError:
            pass
        step = step / 2
    return project_positions(system, t, q + step), np.abs(step).max()


def _check_isolated(system, lin, K):
    """SolveError when K is singular at the equilibrium: rest is possible along a direction."""
    _, s, Vt = np.linalg.svd(K)
    free = Vt[s <= ISOLATED_RTOL * max(s[0], np.finfo(float).tiny)] if s.size else Vt[:0]
    if len(free):
        directions = []
        for v in free:
            dq = lin.basis @ v
            dq = dq / dq[np.argmax(np.abs(dq))]
            directions.append({c: round(float(x), 6) for c, x in zip(system.coordinates, dq) if abs(x) > 1e-6})
        coordinates = sorted({c for d in directions for c in d})
        raise SolveError(f"model '{system.name}': the equilibrium is not isolated: it rests as well after a move "
                         f"along {len(free)} free direction(s) {directions}", coordinates=coordinates)
