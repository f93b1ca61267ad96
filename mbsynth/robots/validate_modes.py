"""The linearization of a robot checked against Pinocchio's analytical derivatives.

At a random configuration q (within the joint limits: validate.sample_pinocchio_state) the
robot is held at rest by the gravity-compensating torques τ = rnea(q, 0, 0), set as its
``tau_*`` parameters. Pinocchio's ``computeABADerivatives`` gives ∂v̇/∂q, ∂v̇/∂v and
∂v̇/∂τ = M⁻¹ in joint space; the eigenvalues of [[0, I], [∂v̇/∂q, ∂v̇/∂v]] must equal
those of mbsynth's A (linearization.py, in maximal coordinates reduced to the tangent
space; compared in s²: ``eigenvalue_error``), and the accelerations B gives per unit
torque, mapped to the model's coordinates (δq̈ = N δü), must equal Pinocchio's mapped by
the velocity map S (q̇ = S v, at rest q̈ = S v̇), relative to the largest entry of S M⁻¹.
"""

import time
from dataclasses import asdict, dataclass

import numpy as np
import pinocchio as pin
import scipy.optimize

from ..analysis.linearization import linearize
from .twin import Twin
from .validate import sample_pinocchio_state


@dataclass(frozen=True)
class ModesValidation:
    """The worst relative errors over ``samples`` held configurations of one robot."""

    robot: str
    nv: int
    samples: int
    eigenvalue_error: float
    input_error: float
    linearize_s: float  # mean seconds per linearization (after the first, which compiles)
    first_s: float  # seconds of the first linearization (derivation and compilation included)

    def to_dict(self):
        return asdict(self)


def hold(system, twin, q):
    """(τ, the system with τ as its tau_* parameters, the model's coordinates) of the robot
    held at rest at Pinocchio's configuration q by τ = rnea(q, 0, 0)."""
    zero = np.zeros(twin.model.nv)
    tau = pin.rnea(twin.model, twin.data, q, zero, zero)
    held = system.with_parameters(**{c.torque: tau[c.idx_v] for c in twin.coordinates if c.torque})
    return tau, held, twin.to_maximal(q, zero)[0]


def pinocchio_linearization(twin, q, tau):
    """(eigenvalues of [[0, I], [∂v̇/∂q, ∂v̇/∂v]], ∂v̇/∂τ) at (q, v = 0, τ)."""
    nv = twin.model.nv
    zero = np.zeros(nv)
    pin.computeABADerivatives(twin.model, twin.data, q, zero, tau)
    J = np.block([[np.zeros((nv, nv)), np.eye(nv)], [twin.data.ddq_dq, twin.data.ddq_dv]])
    Minv = np.array(twin.data.Minv)
    return np.linalg.eigvals(J), np.triu(Minv) + np.triu(Minv, 1).T


def eigenvalue_error(ours, theirs):
    """The largest difference of the squares s² of two spectra matched one to one, relative
    to the largest |s|² (at least 1 s⁻²). Squares, because at rest A = [[0, I], [K, D]] and
    a zero-stiffness direction (a vertical joint axis) has a double zero eigenvalue that a
    rounding error δ of K splits into ±√δ, while s² moves by δ only; the floor of 1 s⁻²
    (a 10 m pendulum) keeps a spectrum of zeros (a robot moving in a horizontal plane)
    from being judged relative to zero."""
    if len(ours) != len(theirs):
        return float("inf")
    if not len(ours):
        return 0.0
    ours, theirs = np.asarray(ours) ** 2, np.asarray(theirs) ** 2
    distance = np.abs(ours[:, None] - theirs[None, :])
    rows, cols = scipy.optimize.linear_sum_assignment(distance)
    return float(distance[rows, cols].max() / max(np.abs(theirs).max(), 1.0))


def validate_modes(system, samples=3, seed=0, label=None):
    """The ModesValidation of a fixed-base robot ``system`` (module docstring)."""
    twin = Twin(system)
    rng = np.random.default_rng(seed)
    worst_eig = worst_input = 0.0
    seconds = []
    order = [c.torque for c in twin.coordinates if c.torque]
    index = {c.torque: c.idx_v for c in twin.coordinates if c.torque}
    for _ in range(samples):
        q = sample_pinocchio_state(twin, rng)[0]
        tau, held, qm = hold(system, twin, q)
        started = time.perf_counter()
        lin = linearize(held, 0.0, qm, np.zeros(system.n), inputs=order)
        seconds.append(time.perf_counter() - started)
        theirs, Minv = pinocchio_linearization(twin, q, tau)
        worst_eig = max(worst_eig, eigenvalue_error(lin.eigenvalues, theirs))
        if order:
            reference = twin.velocity_map(q) @ Minv[:, [index[u] for u in order]]
            ours = lin.basis @ lin.B[lin.k:]
            worst_input = max(worst_input, float(np.abs(ours - reference).max() / np.abs(reference).max()))
    later = seconds[1:] or seconds
    return ModesValidation(label or system.name, twin.model.nv, samples, worst_eig, worst_input,
                           round(float(np.mean(later)), 3), round(seconds[0], 3))
