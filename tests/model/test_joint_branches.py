"""Joints whose rows also hold in poses they do not mean (constraints/joints.py): a fixed
joint's orientation lock x_A·y_B = y_A·z_B = z_A·x_B = 0 holds with the frames turned
180° about an axis or 120° about a diagonal, a revolute joint's axis rows with
z_B = −z_A. A model starting there is refused, naming the joint; the meant pose loads."""

import textwrap
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.model.constraints.joints import _numeric, _rotation_at
from mbsynth.model.joint_templates import pose
from mbsynth.core.kinematics import matrix_quaternion, rpy_matrix
from mbsynth.analysis.projection import consistent_initial_state, project_positions
from mbsynth.symbolic.derive import T_SYMBOL

# a block hung from the world by one joint at its frame ``top`` (z up in the block)
MODEL = """\
name: one_joint
gravity: [0, 0, -9.81]
world:
  frames:
    mount: {{position: [0, 0, 1]}}
parts:
  block:
    type: rigid_body
    mass: 1.0
    inertia: [0.1, 0.2, 0.3]
    frames:
      top: {{position: [0, 0, 0.5]}}
    initial: {{position: {position}, quaternion: {quaternion}}}
joints:
  - {{name: hinge, type: {kind}, parent: world.mount, child: block.top}}
"""
CYCLIC = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]])  # x → y → z: 120° about (1, 1, 1), 0 at (0,1), (1,2), (2,0)


def model(kind, rotation):
    """The model with the block turned by ``rotation`` about its frame ``top``, which
    stays at the mount: the joint's position rows hold, its orientation rows hold exactly
    when they hold for ``rotation``."""
    position = np.array([0, 0, 1]) - rotation @ np.array([0, 0, 0.5])
    return MODEL.format(kind=kind, position=np.round(position, 15).tolist(),
                        quaternion=matrix_quaternion(rotation).tolist())


@pytest.mark.parametrize("kind, rotation, angle", [
    ("fixed", rpy_matrix(np.pi, 0, 0), "180°"), ("fixed", rpy_matrix(0, np.pi, 0), "180°"),
    ("fixed", rpy_matrix(0, 0, np.pi), "180°"), ("fixed", CYCLIC, "120°"),
    ("prismatic", np.diag([1, -1, -1]) @ CYCLIC, "120°"),
    ("revolute", rpy_matrix(np.pi, 0, 0), "180°"), ("revolute", rpy_matrix(0, np.pi, 0.7), "180°")])
def test_a_pose_the_rows_allow_but_the_joint_does_not_mean_is_refused(kind, rotation, angle):
    text = model(kind, rotation)
    with pytest.raises(mb.ModelError, match=rf"model\.yaml:15: .*{kind} joint 'hinge'.*{angle}.*'block'"):
        mb.loads(text, name="model.yaml")


@pytest.mark.parametrize("kind, rotation", [
    ("fixed", rpy_matrix(np.pi, 0, 0)), ("fixed", CYCLIC), ("revolute", rpy_matrix(np.pi, 0, 0))])
def test_the_refused_poses_meet_every_row_of_the_joint(kind, rotation):
    """Why they must be refused: nothing else would notice (the rows are met exactly)."""
    joint = textwrap.dedent(f"""\
        name: rows_only
        world: {{frames: {{mount: {{position: [0, 0, 1]}}}}}}
        parts:
          block: {{type: rigid_body, mass: 1.0, inertia: [0.1, 0.2, 0.3], frames: {{top: {{position: [0, 0, 0.5]}}}}}}
        joints:
          - {{name: hinge, type: {kind}, parent: world.mount, child: block.top}}
        """)
    system = mb.loads(joint)
    q = system.initial_q.copy()
    q[:3] = np.array([0, 0, 1]) - rotation @ np.array([0, 0, 0.5])
    q[3:] = matrix_quaternion(rotation)
    phi, _ = system.constraint_residuals(0.0, q, np.zeros(7))
    assert np.abs(phi).max() < 1e-15
    with pytest.raises(mb.SolveError, match=f"{kind} joint 'hinge'") as err:
        system.check_branches(q)
    assert err.value.constraints == ("hinge",)


@pytest.mark.parametrize("kind, rotation", [
    ("fixed", np.eye(3)), ("fixed", rpy_matrix(0.3, -0.2, 0.1)), ("prismatic", np.eye(3)),
    ("revolute", rpy_matrix(0, 0, np.pi)), ("revolute", rpy_matrix(0, 0, 2.5))])
def test_the_meant_pose_loads_and_a_slightly_off_one_is_left_to_projection(kind, rotation):
    """A revolute joint turns freely about its axis (even 180°); a fixed joint's frames
    turned 0.3 rad are off, not on another branch: projection brings them back."""
    system = mb.loads(model(kind, rotation))
    assert system.branch_problems() == []
    q, _, _ = consistent_initial_state(system)
    assert system.branch_problems(q) == []


def test_a_pose_where_the_rows_do_not_hold_yet_is_checked_once_consistent():
    """Turned 170° about x, the fixed joint's rows do not hold: loading leaves the pose to
    the state made consistent, and projection settles on the 180° flip, where
    consistent_initial_state (System.check_branches) refuses it, naming the joint."""
    system = mb.loads(model("fixed", rpy_matrix(np.radians(170), 0, 0)))
    q = project_positions(system, 0.0, system.initial_state()[0])
    phi, _ = system.constraint_residuals(0.0, q, np.zeros(system.n))
    assert np.abs(phi).max() < 1e-12  # consistent: every row holds
    with pytest.raises(mb.SolveError, match=r"fixed joint 'hinge': its frames are turned 180° about \(-?1, 0, 0\)") as info:
        consistent_initial_state(system)
    assert info.value.constraints == ("hinge",)
    with pytest.raises(mb.SolveError, match="hinge"):
        mb.simulate(system, 0.1)


@pytest.mark.parametrize("model", ["rigid/double_pendulum_spatial.yaml", "mechanisms/four_bar.yaml",
                                   "mechanisms/bricard.yaml", "mechanisms/slider_crank.yaml", "robots/ur5_payload.yaml",
                                   "rolling/bicycle.yaml"])
def test_frame_rotations_of_the_branch_check_equal_the_poses_sympy_gives(model):
    """The branch check's numeric rotations (R(u) R_frame, R_z(θ) R_frame, R_frame, and the
    Euler-angle bodies' R(angles) R_frame of the bicycle) against
    substitution into each part's sympy pose, at a random state off the manifold."""
    system = mb.load(Path(__file__).resolve().parents[2] / "models" / model)
    q = system.initial_state()[0] + 0.3 * np.random.default_rng(5).normal(size=system.n)
    values = {**dict(zip(system.q_symbols, q)), **dict(zip(system.parameter_symbols, system.parameter_values)),
              T_SYMBOL: 0.0}
    compared = 0
    for joint in system.constraints:
        for part, frame in zip(getattr(joint, "parts", ()), getattr(joint, "frames", ())):
            expected = _numeric(pose(part, frame)[1], values)
            np.testing.assert_allclose(_rotation_at(part, frame, values), expected, atol=1e-14)
            compared += 1
    assert compared >= 2


@pytest.mark.parametrize("scale", [1.0, 3.0, 0.2])
def test_the_turn_is_judged_alike_for_scaled_rotations(scale):
    """R_Aᵀ R_B of unnormalized quaternions is a turn scaled by |u_A|² |u_B|²: the quick test
    on its trace (no turn well below 90°) and the full one (the rotation vector) agree at any
    scale — 60° passes, 100° and 180° are refused."""
    from types import SimpleNamespace

    from mbsynth.model.constraints.joints import _turned
    joint = SimpleNamespace(joint_kind="fixed", name="weld", parts=(None, SimpleNamespace(name="block")))
    axis = np.array([1.0, 2.0, 2.0]) / 3
    for degrees, refused in ((60, False), (89, False), (100, True), (180, True)):
        from scipy.spatial.transform import Rotation
        relative = scale * Rotation.from_rotvec(np.radians(degrees) * axis).as_matrix()
        message = _turned(joint, relative)
        assert (message is not None) == refused, (degrees, message)
        if refused:
            assert f"{degrees:.3g}°" in message
