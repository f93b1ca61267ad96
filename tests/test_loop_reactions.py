"""Reactions of loop-closing joints (issue 19, item 3): mbsynth's ``System.reactions``
against Newton–Euler about a fixed point and against Pinocchio's ``lambda_c`` of
``constraintDynamics`` (``Twin.loop_wrench_maps``; validate.loop_reaction_error)."""

import textwrap

import numpy as np
import pinocchio as pin

import mbsynth as mb
from mbsynth.cli.validate import format_validation
from mbsynth.kinematics import matrix_quaternion, rpy_matrix
from mbsynth.twin import Twin
from mbsynth.validate import (Validation, _consistent_sample, determined_projector, loop_reaction_error,
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
        subsystems:
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


def newton_euler(R, omega):
    """The force the pivot exerts on the body, in the world (Euler's equations about the
    fixed point P): I_P α + ω × I_P ω = r × m g, r = c − P, and m a_c = F + m g with
    a_c = α × r + ω × (ω × r)."""
    r = -R @ TIP
    I_P = R @ np.diag(INERTIA) @ R.T + M * (r @ r * np.eye(3) - np.outer(r, r))
    alpha = np.linalg.solve(I_P, np.cross(r, M * G) - np.cross(omega, I_P @ omega))
    return M * (np.cross(alpha, r) + np.cross(omega, np.cross(omega, r))) - M * G


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
        expected = np.r_[(R @ R_tip).T @ newton_euler(R, omega), np.zeros(3)]
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
