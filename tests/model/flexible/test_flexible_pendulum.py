"""A pinned flexible pendulum (a soft beam on a revolute joint at one end, released horizontal
under gravity) converges to the unreduced FE model as Craig–Bampton modes are added. The
reference is written here: the same FE beam's in-plane DOFs, clamped to a frame that turns
about the pin, every DOF's kinetic energy weighed by the full FE mass matrix, gravity on the
first moment, Lagrange's equations integrated by scipy."""

import numpy as np
import pytest
import scipy.integrate

import mbsynth as mb
from mbsynth.model.flexible.beam import beam

ELEMENTS, SIDE, T_END = 6, 0.02, 1.0
SECTION = dict(area=SIDE**2, Iy=SIDE**4 / 12, Iz=SIDE**4 / 12, J=0.141 * SIDE**4, E=1.518e9, nu=0.3, density=1000.0)
G = 9.81


def unreduced_tip(fe):
    """The tip's world place at T_END of the unreduced planar pendulum: q = (θ, u), u the in-plane
    DOFs (ux, uy, θz) of nodes 1…N in the turning frame, node 0 clamped at the pin. With
    w = (θ̇ e_θ at node 0, u̇ + θ̇ g(u)), g(u) the in-plane velocity of a unit turn of the
    deformed beam, T = ½ wᵀ M w; V = ½ uᵀKu − gᵀ R(θ) s(u), s the first moment Γᵀ M (x + u)."""
    n_nodes = len(fe.nodes)
    plane = np.array([j * 6 + c for j in range(n_nodes) for c in (0, 1, 5)])
    M, K = fe.mass.toarray()[np.ix_(plane, plane)], fe.stiffness.toarray()[np.ix_(plane, plane)]
    free = slice(3, None)
    n = 3 * (n_nodes - 1)
    x = np.zeros(3 * n_nodes)
    x[0::3] = fe.nodes[:, 0]
    turn = np.zeros((3 * n_nodes, 3 * n_nodes))  # g(u) = turn @ (x + u): (−y, x, 1) per node
    for j in range(n_nodes):
        turn[3 * j, 3 * j + 1], turn[3 * j + 1, 3 * j] = -1.0, 1.0
    spin = np.tile([0.0, 0.0, 1.0], n_nodes)
    first = np.zeros((2, 3 * n_nodes))
    first[0, 0::3], first[1, 1::3] = 1.0, 1.0
    first = first @ M  # s(u) = first @ (x + u)
    gravity = np.array([0.0, -G])

    def rates(t, y):
        theta, u, theta_dot, u_dot = y[0], y[1:n + 1], y[n + 1], y[n + 2:]
        full_u, full_u_dot = np.concatenate([np.zeros(3), u]), np.concatenate([np.zeros(3), u_dot])
        g = turn @ (x + full_u) + spin  # ∂w/∂θ̇
        w = full_u_dot + theta_dot * g
        p = M @ w
        Gu = turn @ full_u_dot  # ġ
        c, s = np.cos(theta), np.sin(theta)
        R, dR = np.array([[c, -s], [s, c]]), np.array([[-s, -c], [c, -s]])
        moment = first @ (x + full_u)
        # d/dt(gᵀp) + ∂V/∂θ = 0 and d/dt(p) − θ̇ turnᵀ p + ∂V/∂u = 0, on the free DOFs
        lhs = np.zeros((n + 1, n + 1))
        lhs[0, 0] = g @ M @ g
        lhs[0, 1:] = lhs[1:, 0] = (M @ g)[free]
        lhs[1:, 1:] = M[free, free]
        rhs = np.empty(n + 1)
        rhs[0] = gravity @ dR @ moment - Gu @ p - theta_dot * g @ M @ Gu
        rhs[1:] = (theta_dot * turn.T @ p - theta_dot * M @ Gu + first.T @ (R.T @ gravity))[free] - K[free, free] @ u
        return np.concatenate([[theta_dot], u_dot, np.linalg.solve(lhs, rhs)])

    run = scipy.integrate.solve_ivp(rates, (0, T_END), np.zeros(2 * n + 2), method="DOP853", rtol=1e-10, atol=1e-12)
    assert run.success
    theta, u = run.y[0, -1], run.y[1:n + 1, -1]
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]]) @ (fe.nodes[-1, :2] + u[-3:-1])


def pendulum_yaml(modes):
    """The model file of the pendulum as a flexible part with ``modes`` fixed-interface modes
    (both bending planes alike: half of them in the plane of the swing)."""
    numbers = ", ".join(f"{k}: {v!r}" for k, v in SECTION.items())
    return f"""
gravity: [0, -{G}, 0]
parts:
  rod:
    type: flexible_body
    beam: {{length: 1.0, elements: {ELEMENTS}, {numbers}}}
    reduction: {{method: craig_bampton, interface: [0], modes: {modes}}}
    frames: {{tip: {{node: {ELEMENTS}}}}}
joints:
  - {{name: pin, type: revolute, parent: world, child: rod.node_0}}
outputs:
  tip: {{position: rod.tip}}
"""


def reduced_tip(modes):
    """The tip at T_END of the flexible part with ``modes`` fixed-interface modes."""
    run = mb.simulate(mb.loads(pendulum_yaml(modes)), T_END, dt=T_END / 10, rtol=1e-8, atol=1e-10)
    return np.array([run.column("tip[x]")[-1], run.column("tip[y]")[-1]])


@pytest.mark.slow  # four 1-second runs, the unreduced model's among them
def test_a_pinned_flexible_pendulum_converges_to_the_unreduced_model():
    """With 1, 2 and 3 in-plane bending modes the tip's distance at 1 s (the rod swung to the
    other side, nearly horizontal) from the unreduced model's falls at least 2× per mode
    (2.3e-4, 8.3e-5, 2.1e-5 m; 6.1e-6 with 4)."""
    reference = unreduced_tip(beam(1.0, ELEMENTS, **SECTION))
    errors = [np.linalg.norm(reduced_tip(k) - reference) for k in (2, 4, 6)]
    assert errors[0] < 1e-3
    assert errors[1] < errors[0] / 2 and errors[2] < errors[1] / 2, errors
