"""Rigid bodies with angles (``rotation: zxy`` …, model/parts/euler_body.py): their M and Q
against Euler's equations, their motion against the same body with a quaternion, and the
errors a model file gets."""

from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import mbsynth as mb
from mbsynth.core.kinematics import euler_rate_matrix, euler_rotation
from mbsynth.model.parts.euler_body import SEQUENCES

MODELS = Path(__file__).resolve().parents[2] / "models"

FREE_BODY = """
name: spinning
parameters: {m: 2.0}
parts:
  body:
    type: rigid_body
    rotation: {sequence}
    mass: m
    inertia: [[0.3, 0.02, -0.01], [0.02, 0.5, 0.04], [-0.01, 0.04, 0.7]]
"""


@pytest.mark.parametrize("sequence", SEQUENCES)
def test_angular_acceleration_obeys_eulers_equations(sequence):
    """Torque-free: ω̇ = J⁻¹(−ω × Jω) in body axes, with ω = H α̇ and ω̇ = H α̈ + Ḣ α̇
    (Ḣ by a central difference of H along α̇); the rotation R is orthonormal."""
    body = mb.loads(FREE_BODY.replace("{sequence}", sequence))
    rng = np.random.default_rng(7)
    J = np.array([[0.3, 0.02, -0.01], [0.02, 0.5, 0.04], [-0.01, 0.04, 0.7]])
    a = sp.symbols("a0:3")
    H = sp.lambdify(a, euler_rate_matrix(sequence, a))
    R = sp.lambdify(a, euler_rotation(sequence, a))
    for _ in range(3):
        q = np.concatenate([rng.normal(size=3), rng.uniform(-1.0, 1.0, 3)])
        qd = rng.normal(size=6)
        qdd = body.motion(0.0, q, qd).qdd
        angles, rates = q[3:], qd[3:]
        h = 1e-6
        H_dot = (np.array(H(*(angles + h * rates))) - np.array(H(*(angles - h * rates)))) / (2 * h)
        omega = np.array(H(*angles)) @ rates
        omega_dot = np.array(H(*angles)) @ qdd[3:] + H_dot @ rates
        assert np.allclose(omega_dot, np.linalg.solve(J, -np.cross(omega, J @ omega)), rtol=1e-7, atol=1e-8)
        assert np.allclose(qdd[:3], 0.0, atol=1e-14)
        assert np.allclose(np.array(R(*angles)).T @ np.array(R(*angles)), np.eye(3), atol=1e-14)


def test_rolling_disk_with_angles_moves_as_with_a_quaternion():
    """models/rolling/rolling_disk.yaml (quaternion) and the same disk in angles z, x, z run
    the same steady circle: the centres agree over 3 s."""
    text = (MODELS / "rolling" / "rolling_disk.yaml").read_text()
    quaternion = mb.load(MODELS / "rolling" / "rolling_disk.yaml")
    angles = mb.loads(text.replace("    type: rigid_body\n", "    type: rigid_body\n    rotation: zxz\n"))
    assert angles.coordinates[3:] == ("disk.angle_z", "disk.angle_x", "disk.angle_z2")
    a, b = mb.simulate(quaternion, 3.0), mb.simulate(angles, 3.0)
    centre_a = a.q[:, [quaternion.coordinates.index(f"disk.{c}") for c in "xyz"]]
    centre_b = b.q[:, [angles.coordinates.index(f"disk.{c}") for c in "xyz"]]
    assert np.abs(centre_a - centre_b).max() < 1e-9
    assert np.ptp(centre_b[:, 2]) < 1e-12  # the lean stays constant: the centre's height too


def test_model_file_errors_name_the_key():
    with pytest.raises(mb.ModelError, match=r"parts\.body\.rotation.*quaternion or one of"):
        mb.loads(FREE_BODY.replace("{sequence}", "xxz"))
    singular = FREE_BODY.replace("{sequence}", "zxz") + "    initial: {angular_velocity: [1, 0, 0]}\n"
    with pytest.raises(mb.ModelError, match="singular position"):
        mb.loads(singular)
