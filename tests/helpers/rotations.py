"""Quaternion kinematics in numpy for the tests, written from the formulas (not from
mbsynth.core.kinematics): u = (w, x, y, z) scalar-first, ω_body = 2 E(u) u̇, ω_world = 2 G(u) u̇."""

import numpy as np


def skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def E(u):
    return np.column_stack([-u[1:], u[0] * np.eye(3) - skew(u[1:])])


def G(u):
    return np.column_stack([-u[1:], u[0] * np.eye(3) + skew(u[1:])])


def R(u):
    """Body → world rotation of a unit quaternion."""
    w, v = u[0], u[1:]
    return (w * w - v @ v) * np.eye(3) + 2 * np.outer(v, v) + 2 * w * skew(v)


def R_rate(u, ud):
    """d/dt R(u) for the quadratic form of R (product rule)."""
    w, v, wd, vd = u[0], u[1:], ud[0], ud[1:]
    return (2 * (w * wd - v @ vd) * np.eye(3) + 2 * (np.outer(vd, v) + np.outer(v, vd))
            + 2 * wd * skew(v) + 2 * w * skew(vd))


def quaternion(Rm):
    """A unit quaternion of the rotation matrix Rm (Shepperd's method)."""
    t = np.trace(Rm)
    if t > 0:
        w = np.sqrt(1 + t) / 2
        return np.array([w, (Rm[2, 1] - Rm[1, 2]) / (4 * w), (Rm[0, 2] - Rm[2, 0]) / (4 * w),
                         (Rm[1, 0] - Rm[0, 1]) / (4 * w)])
    i = int(np.argmax(np.diag(Rm)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = np.sqrt(1 + Rm[i, i] - Rm[j, j] - Rm[k, k]) / 2
    u = np.empty(4)
    u[0] = (Rm[k, j] - Rm[j, k]) / (4 * s)
    u[1 + i], u[1 + j], u[1 + k] = s, (Rm[j, i] + Rm[i, j]) / (4 * s), (Rm[k, i] + Rm[i, k]) / (4 * s)
    return u


def rotation_about(axis, angle):
    """Rodrigues' formula."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = skew(a)
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def body_coordinates(position, rotation, velocity, omega_world):
    """(q, q̇) of a rigid body (x, y, z, qw, qx, qy, qz) from its pose and world velocities:
    u̇ = ½ G(u)ᵀ ω (G Gᵀ = I for a unit u)."""
    u = quaternion(rotation)
    return np.concatenate([position, u]), np.concatenate([velocity, G(u).T @ omega_world / 2])
