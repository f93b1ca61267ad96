"""projection._least_change: the least-norm step of a sparse J, checked against dense least
squares (numpy's SVD-based lstsq, an independent computation); a projection that fails
names the rows at fault (a servo no configuration meets, a loop at a singular position)."""

import re
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse

import mbsynth as mb
from mbsynth.analysis.projection import _least_change, consistent_initial_state
from mbsynth.cli import main

RNG = np.random.default_rng(3)
ROOT = Path(__file__).resolve().parents[2]


def tree_rows(count, width=5):
    """Rows like a chain's joints: each block of ``width`` rows touches two neighbouring bodies."""
    J = scipy.sparse.lil_matrix((width * count, 7 * count))
    for i in range(count):
        J[width * i:width * (i + 1), 7 * i:7 * (i + 1)] = RNG.normal(size=(width, 7))
        if i:
            J[width * i:width * (i + 1), 7 * (i - 1):7 * i] = RNG.normal(size=(width, 7))
    return J.tocsr()


def weighted_least_norm(J, r):
    """numpy's minimum of ‖diag(c) Δ‖ subject to J Δ = r, c_j = ‖J_:j‖ (the metric of
    projection._least_change): Δ = D (J D)⁺ r with D = diag(1/c)."""
    J = J.toarray()
    D = 1.0 / np.linalg.norm(J, axis=0)
    return D * np.linalg.lstsq(J * D, r, rcond=1e-12)[0]


def test_independent_rows_give_the_least_norm_step():
    J = tree_rows(40)
    J = (J @ scipy.sparse.diags(RNG.uniform(1e-3, 1e3, size=J.shape[1]))).tocsr()  # coordinates in mixed units
    r = RNG.normal(size=J.shape[0])
    step = _least_change(J, r, np.arange(J.shape[1]))
    expected = weighted_least_norm(J, r)
    assert np.linalg.norm(step - expected) < 1e-10 * np.linalg.norm(expected)


def test_the_step_does_not_depend_on_the_coordinates_units():
    """Rescaling a coordinate (metres to millimetres, a quaternion beside lengths of a
    kilometre) rescales its share of the step and nothing else: the same physical move."""
    J = tree_rows(10)
    r = RNG.normal(size=J.shape[0])
    units = RNG.uniform(1e-3, 1e3, size=J.shape[1])
    scaled = _least_change((J @ scipy.sparse.diags(1.0 / units)).tocsr(), r,
                         np.arange(J.shape[1]))  # coordinate j counted in 1/units_j
    np.testing.assert_allclose(scaled / units, _least_change(J, r, np.arange(J.shape[1])), rtol=1e-9, atol=1e-12)


def test_dependent_rows_still_give_the_least_norm_step():
    J = tree_rows(10)
    J = scipy.sparse.vstack([J, J[3] + 2 * J[17]]).tocsr()  # a redundant row, as a planar loop in 3D has
    r = J @ RNG.normal(size=J.shape[1])  # consistent right side
    step = _least_change(J, r, np.arange(J.shape[1]))
    expected = weighted_least_norm(J, r)
    assert np.linalg.norm(step - expected) < 1e-9 * np.linalg.norm(expected)
    assert np.linalg.norm(J @ step - r) < 1e-9 * np.linalg.norm(r)


def test_a_small_system_takes_the_dense_route_to_the_same_step():
    """Below DENSE_ENTRIES the step is solved densely: still the weighted least-norm step."""
    from mbsynth.analysis.projection import DENSE_ENTRIES
    J = tree_rows(4)
    assert J.shape[0] * J.shape[1] <= DENSE_ENTRIES
    r = RNG.normal(size=J.shape[0])
    expected = weighted_least_norm(J, r)
    assert np.linalg.norm(_least_change(J, r, np.arange(J.shape[1])) - expected) < 1e-10 * np.linalg.norm(expected)


def test_a_quaternion_component_near_zero_does_not_throw_the_projection_off():
    """A free body whose quaternion is u = (1 + 5e-12, 0, 0, 1e-14): the unit-norm row's
    column for u_z is 2u_z = 2e-14, so in the equilibrated metric u_z looks free to move
    and the least-norm step moves it by about r/(4 u_z) — Newton then diverges. The
    projection must land on |u| = 1 by the obvious small move (u_w by about −5e-12)."""
    import mbsynth as mb
    from mbsynth.analysis.projection import project_positions

    system = mb.loads("name: spinner\nparts:\n  body: {type: rigid_body, mass: 1.0, "
                      "inertia: [1.0, 2.0, 3.0]}\n", name="spinner")
    q = system.initial_state()[0]
    u = [system.coordinates.index(f"body.q{c}") for c in "wxyz"]
    q[u] = [1 + 5e-12, 0.0, 0.0, 1e-14]
    projected = project_positions(system, 0.0, q)
    assert abs(np.linalg.norm(projected[u]) - 1) < 2e-16
    assert np.abs(projected - q).max() < 1e-11


def test_a_quaternion_rate_is_projected_by_a_small_move_when_a_component_is_near_zero():
    """The velocity row u·u̇ = 0 of a body with u = (0.6, 0.8, 0, 1e-8) and ψ = 1e-9: a scale
    of u_z's column alone (2u_z) would take the projection almost entirely on u̇_z, about
    ψ/(3 u_z) = 0.03 rad/s, a kick to the spin. The quaternion's four columns share one
    scale (System.coordinate_groups), so u̇ moves along u by ψ/|u|² and no more."""
    import mbsynth as mb
    from mbsynth.analysis.projection import project_velocities

    system = mb.loads("name: spinner\nparts:\n  body: {type: rigid_body, mass: 1.0, "
                      "inertia: [1.0, 2.0, 3.0]}\n", name="spinner")
    q, qd = system.initial_state()
    u = [system.coordinates.index(f"body.q{c}") for c in "wxyz"]
    q[u] = [0.6, 0.8, 0.0, 1e-8]
    rate = np.array([-0.8, 0.6, 0.3, 0.2])  # ω of about 2 rad/s
    qd[u] = rate - (q[u] @ rate) * q[u] + 1e-9 * q[u]  # u·u̇ = 1e-9
    projected = project_velocities(system, 0.0, q, qd)
    assert abs(q[u] @ projected[u]) < 1e-15
    assert np.abs(projected - qd).max() < 1.5e-9


def test_a_pendulum_bob_near_the_vertical_is_moved_along_its_rod():
    """A01's bob (an energy-defined part, T = ½ m (ẋ² + ẏ²)) near the bottom, x = −0.0127,
    its rod 1e-9 too long: x and y have equal M_ii, hence the same units, and share one
    scale (parts/lagrangian.py, same_units), so the least change moves the bob along the
    rod, Δ ∥ (x, y). With a scale per coordinate the step went on x almost alone, by
    φ/(2 ∂φ/∂x) ≈ 20 φ, and its velocity projection changed the energy by 4e-7 of mg L."""
    import mbsynth as mb
    from mbsynth.analysis.projection import project

    system = mb.load(ROOT / "models" / "mechanisms" / "simple_pendulum.yaml")
    q = np.array([-0.0126790881960727, -0.9999196171187412]) * (1 + 5e-10)
    qd = np.array([-4.428912801894245, 0.05615909025580679])
    projected, _ = project(system, 0.0, q, qd)
    step = projected - q
    assert abs(np.hypot(*projected) - 1.0) < 1e-15
    assert abs(step[0] * q[1] - step[1] * q[0]) < 1e-6 * np.linalg.norm(step) * np.linalg.norm(q)


def test_coordinates_of_equal_mass_entries_share_a_scale_and_others_do_not():
    """same_units: x, y under ½ m (ẋ² + ẏ²) together; r, θ under ½ m (ṙ² + r² θ̇²) apart."""
    import mbsynth as mb

    cartesian = mb.loads("parts:\n  p: {type: lagrangian, coordinates: [x, y], "
                         "T: 0.5*(x_dot**2 + y_dot**2)}\n")
    polar = mb.loads("parts:\n  p: {type: lagrangian, coordinates: [r, th], "
                     "T: 0.5*(r_dot**2 + r**2*th_dot**2)}\n")
    assert len(set(cartesian.coordinate_groups)) == 1
    assert len(set(polar.coordinate_groups)) == 2


def test_term_scales_of_a_sparse_matrix_equal_the_sum_of_its_terms():
    """term_scales from a CSR matrix's arrays (rows without entries included) equals
    Σ_j |A_ij x_j| + floor Σ_j |A_ij| max|x| summed entry by entry."""
    from mbsynth.core.equations import term_scales

    A = scipy.sparse.random(40, 60, density=0.1, random_state=5, format="lil")
    A[7, :] = 0.0
    A = A.tocsr()
    A.data -= 0.5
    x = RNG.normal(size=60)
    dense = A.toarray()
    expected = [sum(abs(a * b) for a, b in zip(row, x)) + 1e-3 * sum(abs(row)) * max(abs(x)) for row in dense]
    np.testing.assert_allclose(term_scales(A, x), expected, rtol=1e-14)
    np.testing.assert_allclose(term_scales(dense, x), expected, rtol=1e-14)
    assert term_scales(A, x)[7] == 0.0


# -- a projection that fails names the rows at fault ------------------------------------------

TWO_ARMS_AT_ZERO = """
name: two_arms_at_zero
parameters: {m: 1.5, L: 0.6, r: 0.02, g: 9.81}
gravity: [0, 0, -g]
parts:
  left: {type: robot, robot: ur5, base: {position: [0, 0, 1]}}
  right: {type: robot, robot: ur5, base: {position: [1.6345, 0.3829 + L, 1], rpy: [0, 0, pi]}}
  bar:
    type: rigid_body
    mass: m
    inertia: [m*L**2/12, m*L**2/12, m*r**2/2]
    frames:
      left: {position: [0, 0, -L/2]}
      right: {position: [0, 0, L/2], rpy: [0, pi, 0]}
    initial: {position: [0.81725, 0.19145 + L/2, 0.994509], rpy: [pi/2, 0, pi]}
joints:
  - {name: left_grip, type: fixed, parent: left_tool0, child: bar.left}
  - {name: right_grip, type: fixed, parent: right_tool0, child: bar.right}
"""


@pytest.mark.slow  # two UR5 arms built from their URDF and derived
def test_a_loop_at_a_singular_position_is_named_with_the_distance_to_a_closed_one():
    """Two UR5 arms at their zero pose welded to one bar: wrist 1 and wrist 3 turn about one
    axis and the elbows are stretched, so no joint turns the bar about its own axis; the
    URDF's π/2 to 11 digits (1.57079632679, 4.9e-12 short) leaves the loop 9.8e-12 rad
    apart along that axis. First-order steps cannot move that residual; one of second order
    meets it: |δ| = √(2 |wᵀφ| / |λ|), micro-radians away."""
    system = mb.loads(TWO_ARMS_AT_ZERO)
    with pytest.raises(mb.SolveError, match=r"dependent here \(a singular position.*lies about (\S+) away") as err:
        consistent_initial_state(system)
    distance = float(re.search(r"lies about (\S+) away", str(err.value)).group(1))
    assert 1e-7 < distance < 1e-4  # √(1e-11): far beyond rounding, far below a visible change
    assert {"left_grip[ry]", "right_grip[ry]", "left_wrist_3_joint[axis_y]"} <= set(err.value.constraints)


def test_the_bundled_two_arms_model_closes_its_loop_within_the_urdf_digits():
    """Posed away from that singular position (elbows bent, wrist 2 turned), the same loop
    closes: only the URDF's 11-digit angles move, by less than 1e-11."""
    q, qd, changes = consistent_initial_state(mb.load(ROOT / "models" / "robots" / "two_arms_bar.yaml"))
    assert changes and max(abs(a - b) for a, b in changes.values()) < 1e-11


def test_a_servo_beyond_the_joints_range_is_named(tmp_path, capsys):
    """``mbsynth simulate`` of a UR5 whose elbow's sine must be 2 (no angle gives it; a plain
    servo at 4 rad is met at 4 − 2π, a row affine in the angle being taken modulo the turn):
    exit 2 naming the servo, unmet from the start, not the joint rows Newton's steps break."""
    path = tmp_path / "servo.yaml"
    path.write_text("name: ur5_servo\nparameters: {g: 9.81}\ngravity: [0, 0, -g]\n"
                    "parts:\n  arm: {type: robot, robot: ur5, base: {position: [0, 0, 1]}}\n"
                    "constraints:\n  - {name: elbow_servo, holonomic: 'sin(arm_elbow_joint.angle) - 2'}\n")
    assert main(["simulate", str(path), "--t-end", "0.1"]) == 2
    err = capsys.readouterr().err
    assert "unmet elbow_servo (2);" in err and "(77 in all)" in err and "at best a residual of 1 " in err


def test_a_row_out_of_reach_says_it_is_at_its_least():
    """A pendulum of length 2 whose bob is held at x = 3: x² + y² − 4 ≥ 5, met nowhere;
    at y = 0 no change of y lowers it, to first or second order."""
    system = mb.loads(PENDULUM + "initial: {bob.x: 3.0}\ninitial_fixed: [bob.x]\n")
    with pytest.raises(mb.SolveError, match=r"unmet rod \(5\); the residual left \(5 in rod\) is the least the rows "
                                            r"rod reach near here") as err:
        consistent_initial_state(system)
    assert err.value.constraints == ("rod",)


PENDULUM = """\
name: pendulum
parameters: {m: 1.0, L: 2.0, g: 9.81}
parts:
  bob: {type: lagrangian, coordinates: [x, y], T: 0.5*m*(x_dot**2 + y_dot**2), V: m*g*y}
constraints:
  - {name: rod, holonomic: bob.x**2 + bob.y**2 - L**2}
"""
