"""Rotations and frames, as sympy expressions of a part's coordinates.

Quaternions are scalar-first, u = (w, x, y, z) = (w, v). The formulas are homogeneous
of degree two, so they stay polynomial (and exact for unit u):

    R(u) = (w² − vᵀv) I + 2 v vᵀ + 2 w [v]×        body → world rotation
    ω_body  = 2 E(u) u̇,   E(u) = [−v, w I − [v]×]     (3 × 4)
    ω_world = 2 G(u) u̇,   G(u) = [−v, w I + [v]×]     (3 × 4)

E(u) u = G(u) u = 0 for every u: the fourth direction of a quaternion is its norm,
which carries no rotation — why a rigid body's 4 × 4 rotational mass block 4 EᵀJE
has rank 3.
"""

import numpy as np
import sympy as sp


def skew(v):
    """[v]×, the matrix of v × (·)."""
    return sp.Matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def rotation(u):
    """R(u) of a scalar-first quaternion (homogeneous quadratic form)."""
    w, v = u[0], sp.Matrix(u[1:])
    return (w**2 - (v.T * v)[0]) * sp.eye(3) + 2 * v * v.T + 2 * w * skew(v)


def body_rate_matrix(u):
    """E(u): ω_body = 2 E(u) u̇."""
    w, v = u[0], sp.Matrix(u[1:])
    return sp.Matrix.hstack(-v, w * sp.eye(3) - skew(v))


def world_rate_matrix(u):
    """G(u): ω_world = 2 G(u) u̇."""
    w, v = u[0], sp.Matrix(u[1:])
    return sp.Matrix.hstack(-v, w * sp.eye(3) + skew(v))


def rotation_z(theta):
    c, s = sp.cos(theta), sp.sin(theta)
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rpy_matrix(roll, pitch, yaw):
    """R = Rz(yaw) Ry(pitch) Rx(roll), the URDF convention, as a numpy array."""
    cr, sr, cp, sp_, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return np.array([[cy * cp, cy * sp_ * sr - sy * cr, cy * sp_ * cr + sy * sr],
                     [sy * cp, sy * sp_ * sr + cy * cr, sy * sp_ * cr - cy * sr],
                     [-sp_, cp * sr, cp * cr]])


def axis_matrix(axis):
    """A rotation whose z column is the unit vector along ``axis`` (numpy)."""
    z = np.asarray(axis, dtype=float)
    z = z / np.linalg.norm(z)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = helper - z * (helper @ z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def quaternion_rotation(u):
    """R(u) as a numpy array, in the homogeneous form of ``rotation`` (|u|² R for u not unit)."""
    w, v = float(u[0]), np.asarray(u[1:], dtype=float)
    skew = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return (w * w - v @ v) * np.eye(3) + 2 * np.outer(v, v) + 2 * w * skew


def quaternion_matrix(u):
    """R of a unit scalar-first quaternion, as a numpy array."""
    u = np.asarray(u, dtype=float)
    return quaternion_rotation(u / np.linalg.norm(u))


def matrix_quaternion(R):
    """A unit scalar-first quaternion of the rotation matrix R (numpy), w ≥ 0."""
    R = np.asarray(R, dtype=float)
    K = np.array([[R[0, 0] + R[1, 1] + R[2, 2], R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]],
                  [R[2, 1] - R[1, 2], R[0, 0] - R[1, 1] - R[2, 2], R[0, 1] + R[1, 0], R[0, 2] + R[2, 0]],
                  [R[0, 2] - R[2, 0], R[0, 1] + R[1, 0], R[1, 1] - R[0, 0] - R[2, 2], R[1, 2] + R[2, 1]],
                  [R[1, 0] - R[0, 1], R[0, 2] + R[2, 0], R[1, 2] + R[2, 1], R[2, 2] - R[0, 0] - R[1, 1]]]) / 3
    vals, vecs = np.linalg.eigh(K)
    u = vecs[:, -1]
    return u if u[0] >= 0 else -u


def axis_rotation(axis, angle):
    """The rotation by ``angle`` about the coordinate axis ``axis`` ("x", "y" or "z"), sympy."""
    c, s = sp.cos(angle), sp.sin(angle)
    return {"x": sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]]),
            "y": sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "z": sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def euler_rotation(sequence, angles):
    """R = R_a(α₁) R_b(α₂) R_c(α₃) of the intrinsic sequence ``sequence`` = "abc" (each turn
    about the axis the previous ones carried along), sympy."""
    R = sp.eye(3)
    for axis, angle in zip(sequence, angles):
        R = R * axis_rotation(axis, angle)
    return R


def euler_rate_matrix(sequence, angles):
    """H(α): ω_body = H(α) α̇ for the intrinsic sequence ``sequence``: the column of α̇ᵢ is
    the axis of turn i in the body's axes, R_c(α₃)ᵀ … R_{i+1}(α_{i+1})ᵀ eᵢ."""
    columns = []
    for i, axis in enumerate(sequence):
        column = sp.Matrix([1 if a == axis else 0 for a in "xyz"])
        for later, angle in zip(sequence[i + 1:], angles[i + 1:]):
            column = axis_rotation(later, angle).T * column
        columns.append(column)
    return sp.Matrix.hstack(*columns)
