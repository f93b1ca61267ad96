"""Reactions of loop-closing joints: mbsynth's ``System.reactions``
against Newton–Euler about a fixed point and against Pinocchio's ``lambda_c`` of
``constraintDynamics`` (``Twin.loop_wrench_maps``; validate.loop_reaction_error)."""

import textwrap

import numpy as np
import pinocchio as pin
import pytest

import mbsynth as mb
from mbsynth.cli.validate import format_validation
from mbsynth.core.kinematics import matrix_quaternion, quaternion_matrix, rpy_matrix
from mbsynth.robots.twin import Twin
from mbsynth.robots.validate import (Validation, _consistent_sample, determined_projector, loop_reaction_error,
                              self_stresses, validate_system)

M, G = 1.3, np.array([0.0, -2.0, -9.81])
INERTIA = np.array([0.02, 0.035, 0.05])
PIVOT, PIVOT_RPY = np.array([0.1, -0.2, 0.3]), (0.3, -0.2, 0.5)
TIP, TIP_RPY = np.array([0.05, -0.1, 0.4]), (0.7, 0.1, -0.4)


def pinned_body(tmp_path):
    """A heavy top: one rigid body whose frame ``tip`` is joined to the world's ``pivot``
    by a spherical joint. No revolute, prismatic or fixed joint reaches the body, so its
    twin is a free-flyer and the joint closes a loop (CONTACT_3D)."""
    path = tmp_path / "pinned_top.yaml"
    path.write_text(textwrap.dedent(f"""\
        name: pinned_top
        gravity: {G.tolist()}
        world: {{frames: {{pivot: {{position: {PIVOT.tolist()}, rpy: {list(PIVOT_RPY)}}}}}}}
        parts:
          body:
            type: rigid_body
            mass: {M}
            inertia: {INERTIA.tolist()}
            frames: {{tip: {{position: {TIP.tolist()}, rpy: {list(TIP_RPY)}}}}}
        joints:
          - {{name: pin, type: spherical, parent: world.pivot, child: body.tip}}
        """))
    return mb.load(path)


def _state(rng):
    """A random (q, q̇) with the tip at the pivot, the body turning about it, and its
    (R, ω) in the world."""
    R, omega = pin.exp3(rng.normal(size=3)), rng.normal(size=3)
    p = PIVOT - R @ TIP
    u = matrix_quaternion(R)
    G_u = np.column_stack([-u[1:], u[0] * np.eye(3) + pin.skew(u[1:])])  # ω = 2 G(u) u̇, G Gᵀ = I
    return np.r_[p, u], np.r_[np.cross(omega, p - PIVOT), G_u.T @ omega / 2], R, omega


def newton_euler(R, omega, axis=None):
    """(force, torque) the pivot exerts on the body, at the pivot, in the world, by Euler's
    equations about the fixed point P: I_P α + ω × I_P ω = τ + r × m g, r = c − P, and
    m a_c = F + m g, a_c = α × r + ω × (ω × r). A ball joint has τ = 0; a hinge about
    ``axis`` e (ω ∥ e) has eᵀτ = 0, so α = e eᵀ(r × m g − ω × I_P ω) / eᵀ I_P e."""
    r = -R @ TIP
    I_P = R @ np.diag(INERTIA) @ R.T + M * (r @ r * np.eye(3) - np.outer(r, r))
    moment = np.cross(r, M * G) - np.cross(omega, I_P @ omega)
    alpha = np.linalg.solve(I_P, moment) if axis is None else axis * (axis @ moment) / (axis @ I_P @ axis)
    return M * (np.cross(alpha, r) + np.cross(omega, np.cross(omega, r))) - M * G, I_P @ alpha - moment


def test_heavy_top_loop_reaction_is_newton_euler_and_lambda_c(tmp_path):
    """A heavy top whose pivot closes a loop, at random orientations and rates: mbsynth's
    reaction, and the wrench of Pinocchio's lambda_c (its sign and LOCAL frame convention),
    both equal the force of Euler's equations at the pivot, in the child frame's axes,
    and no moment."""
    system = pinned_body(tmp_path)
    twin = Twin(system)
    assert [c.kind for c in twin.coordinates] == ["free"] and [loop.name for loop in twin.loops] == ["pin"]
    rng = np.random.default_rng(11)
    R_tip = rpy_matrix(*TIP_RPY)
    for _ in range(3):
        q, qd, R, omega = _state(rng)
        force, torque = newton_euler(R, omega)
        assert np.abs(torque).max() < 1e-12 * np.abs(force).max()
        expected = np.r_[(R @ R_tip).T @ force, np.zeros(3)]
        scale = np.abs(expected).max()
        motion = system.motion(0.0, q, qd)
        reaction = system.reactions(0.0, q, qd, motion)["pin"]
        assert not reaction.redundant
        assert np.abs(np.r_[reaction.force, reaction.torque] - expected).max() < 1e-9 * scale
        qp, v, _ = twin.to_pinocchio(q, qd)
        twin.accelerations(qp, v, np.zeros(twin.model.nv))
        loop = twin.loops[0]
        theirs = twin.loop_wrench_maps()["pin"] @ twin.data.lambda_c[loop.rows]
        assert np.abs(theirs - expected).max() < 1e-8 * scale
        error, free = loop_reaction_error(system, twin, (q, qd), motion)
        assert error < 1e-8 and free == 0


GANTRY = f"""\
name: gantry_hinge
gravity: {G.tolist()}
world:
  frames:
    px: {{axis: [1, 0, 0]}}
    pivot: {{position: {PIVOT.tolist()}, rpy: {list(PIVOT_RPY)}}}
parts:
  s1: {{type: rigid_body, mass: 0, inertia: [0, 0, 0], frames: {{px: {{axis: [1, 0, 0]}}, py: {{axis: [0, 1, 0]}}}}}}
  s2: {{type: rigid_body, mass: 0, inertia: [0, 0, 0], frames: {{py: {{axis: [0, 1, 0]}}, pz: {{axis: [0, 0, 1]}}}}}}
  s3: {{type: rigid_body, mass: 0, inertia: [0, 0, 0], frames: {{pz: {{axis: [0, 0, 1]}}, rx: {{axis: [1, 0, 0]}}}}}}
  g1: {{type: rigid_body, mass: 0, inertia: [0, 0, 0], frames: {{rx: {{axis: [1, 0, 0]}}, ry: {{axis: [0, 1, 0]}}}}}}
  g2: {{type: rigid_body, mass: 0, inertia: [0, 0, 0], frames: {{ry: {{axis: [0, 1, 0]}}, rz: {{axis: [0, 0, 1]}}}}}}
  body:
    type: rigid_body
    mass: {M}
    inertia: {INERTIA.tolist()}
    frames: {{rz: {{axis: [0, 0, 1]}}, tip: {{position: {TIP.tolist()}, rpy: {list(TIP_RPY)}}}}}
joints:
  - {{name: slide_x, type: prismatic, parent: world.px, child: s1.px}}
  - {{name: slide_y, type: prismatic, parent: s1.py, child: s2.py}}
  - {{name: slide_z, type: prismatic, parent: s2.pz, child: s3.pz}}
  - {{name: turn_x, type: revolute, parent: s3.rx, child: g1.rx}}
  - {{name: turn_y, type: revolute, parent: g1.ry, child: g2.ry}}
  - {{name: turn_z, type: revolute, parent: g2.rz, child: body.rz}}
  - {{name: hinge, type: revolute, parent: world.pivot, child: body.tip}}
"""


def test_hinge_closing_a_loop_is_newton_euler_and_lambda_c(tmp_path):
    """A revolute loop that is not redundant: the body is carried by a massless gantry
    (three slides) and gimbal (three hinges), six joints that free all six motions and so
    carry no load, and hinged to the world's pivot by a revolute joint that closes the
    loop (two CONTACT_3D, one row of six redundant in Pinocchio, none in the wrench). At
    states on the constraints: mbsynth's hinge reaction, and the wrench of lambda_c (its
    two points added up), both equal Euler's equations about the hinge's axis — force,
    and the moment across the axis that holds it — and the gantry's joints carry nothing."""
    path = tmp_path / "gantry.yaml"
    path.write_text(GANTRY)
    system = mb.load(path)
    twin = Twin(system)
    assert [loop.name for loop in twin.loops] == ["hinge"] and twin.model.nv == 6
    rng = np.random.default_rng(3)
    axis, R_tip = rpy_matrix(*PIVOT_RPY)[:, 2], rpy_matrix(*TIP_RPY)
    body = system.coordinates.index("body.x")
    for _ in range(2):
        q, v, qm, qdm = _consistent_sample(system, twin, rng)
        u, u_dot = qm[body + 3:body + 7], qdm[body + 3:body + 7]
        R = quaternion_matrix(u)
        omega = 2 * np.column_stack([-u[1:], u[0] * np.eye(3) + pin.skew(u[1:])]) @ u_dot
        assert np.linalg.norm(np.cross(omega, axis)) < 1e-9 * np.linalg.norm(omega)
        force, torque = newton_euler(R, omega, axis)
        R_child = R @ R_tip
        expected = np.r_[R_child.T @ force, R_child.T @ torque]
        scale = np.abs(expected).max()
        assert abs(expected[5]) < 1e-12 * scale and np.abs(expected[3:5]).max() > 1e-3 * scale
        motion = system.motion(0.0, qm, qdm)
        reactions = system.reactions(0.0, qm, qdm, motion)
        assert not reactions["hinge"].redundant
        assert np.abs(np.r_[reactions["hinge"].force, reactions["hinge"].torque] - expected).max() < 1e-9 * scale
        for joint in ("slide_x", "slide_y", "slide_z", "turn_x", "turn_y", "turn_z"):
            assert np.abs(np.r_[reactions[joint].force, reactions[joint].torque]).max() < 1e-9 * scale
        twin.accelerations(q, v, np.zeros(twin.model.nv))
        theirs = twin.loop_wrench_maps()["hinge"] @ twin.data.lambda_c[twin.loops[0].rows]
        assert np.abs(theirs - expected).max() < 1e-8 * scale
        assert loop_reaction_error(system, twin, (qm, qdm), motion) == (pytest.approx(0, abs=1e-8), 0)


def test_heavy_top_validates_with_its_loop_reaction(tmp_path):
    """``validate_system`` compares the loop joint's whole wrench (nothing undetermined)."""
    result = validate_system(pinned_body(tmp_path), samples=3)
    assert result.passed and result.loop_reaction_error < 1e-8 and result.loop_free == 0, result


def test_four_bar_in_space_compares_only_the_determined_components():
    """four_bar_3d.yaml: a planar loop of parallel revolute axes (world z) in space is
    over-constrained; the force along the axes and the moments about in-plane axes that
    ground_D carries are a self-stress away from any other solution (statically
    indeterminate), the in-plane force and the moment about the axis are not. At a random
    state: the determined components are exactly those three (ground_D's child frame has
    the world's z axis), mbsynth marks the joint redundant, the two solvers' full
    wrenches differ, and the determined components agree."""
    system = mb.load("models/mechanisms/four_bar_3d.yaml")
    twin = Twin(system)
    q, v, qm, qdm = _consistent_sample(system, twin, np.random.default_rng(0))
    twin.accelerations(q, v, np.zeros(twin.model.nv))
    loop = twin.loops[0]
    W = twin.loop_wrench_maps()[loop.name]
    jacobian = pin.getConstraintsJacobian(twin.model, twin.data, twin.constraints, twin.constraint_data)
    P = determined_projector(W, self_stresses(jacobian)[loop.rows])
    np.testing.assert_allclose(P, np.diag([1.0, 1, 0, 0, 0, 1]), atol=1e-9)
    reaction = system.reactions(0.0, qm, qdm)[loop.name]
    assert reaction.redundant
    ours, theirs = np.r_[reaction.force, reaction.torque], W @ twin.data.lambda_c[loop.rows]
    scale = np.abs(theirs[:2]).max()
    assert np.abs(ours - theirs).max() > 1e-3 * scale  # a different, equally valid split
    assert np.abs(P @ (ours - theirs)).max() < 1e-9 * scale


def test_validate_table_has_the_loop_column():
    """``mbsynth validate``'s table: the loop error, with the components a redundant loop
    leaves free; '-' without loops."""
    row = dict(base="model", links=3, nv=3, samples=2, max_abs_error=0.0, max_rel_error=0.0, passed=True,
               tolerance=1e-9, build_s=0.0, motion_ms=0.0)
    redundant = Validation("four_bar_3d", **row, loop_reaction_error=1.4e-14, loop_free=3)
    tree = Validation("pendulum", **row)
    lines = format_validation([redundant, tree], "x.yaml").splitlines()
    assert "loops" in lines[1] and "1.4e-14 (3 free)" in lines[2] and "free" not in lines[3]
    assert lines[3].split()[-4] == "-"  # … reactions, loops, build s, motion ms, result
