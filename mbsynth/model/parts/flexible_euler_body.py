"""A flexible body whose floating frame turns by three angles of an intrinsic sequence
(``rotation: zxy`` in a model file, as a rigid body's, model/parts/euler_body.py) instead
of a quaternion: coordinates x, y, z, the three angles and eta1 … etar.

The choice for a part that spins steadily (a rotor blade): with the spin axis last in the
sequence and the part held on that axis (a revolute joint), its M and Q depend on the spin
angle only through rows the joint's reactions take up, so the spin angle is cyclic and a
blade spinning at a constant rate is a steady motion (analysis/steady.py): ``modes
--steady`` gives its frequencies, centrifugal stiffening included. The equations are the
quaternion part's (flexible_body.py) with B = blockdiag(Aᵀ, H(α), I), ω = H(α) α̇, and
Ḃq̇ = (−ω × V, Ḣ α̇, 0): the same compiled kernel, given the sequence's axes
(compiled/flexible.py). No unit-norm row; singular where H loses rank (the middle turn at
±90° for Tait–Bryan, 0 and 180° for proper Euler).
"""

import numpy as np
import sympy as sp

from ...core.kinematics import euler_rate_matrix, euler_rotation
from .euler_body import SEQUENCES, coordinates as angle_coordinates
from .flexible_body import FlexibleBody
from .part_type import ANGLES, EXTRA_NODE, FE_MESH, PartType, check


def coordinates(sequence, modes):
    """The coordinate names of a flexible body turned by ``sequence`` with ``modes`` reduced
    coordinates: x, y, z, the angles (euler_body.py's names), eta1 … eta<modes>."""
    return (*angle_coordinates(sequence), *(f"eta{k + 1}" for k in range(modes)))


class EulerFlexibleBody(FlexibleBody):
    """FlexibleBody (its arguments) turned by the angles of ``sequence`` (one of SEQUENCES)."""

    content_fields = FlexibleBody.content_fields + ("sequence",)

    part_type = check(PartType("flexible_euler_body", node=EXTRA_NODE, orientation=ANGLES, quaternion=None,
                               points=(("x", "y", "z"),), elastic=True, body_rates=False, origin=True,
                               shared_pose=False, drawing=FE_MESH))
    groups = (("x", "y", "z"),)
    defaults = {}

    def __init__(self, name, sequence, q, qd, reduction, gravity, params, **options):
        if sequence not in SEQUENCES:
            raise ValueError(f"rotation sequence {sequence!r}: one of {', '.join(SEQUENCES)}")
        self.sequence = sequence
        self.axes = np.array(["xyz".index(a) for a in sequence], np.int64)
        super().__init__(name, q, qd, reduction, gravity, params, **options)

    def coordinate_names(self, modes):
        return coordinates(self.sequence, modes)

    def frame_axes(self):
        return euler_rotation(self.sequence, self.q[3:6])

    def turning(self):
        alpha, rates = self.q[3:6], sp.Matrix(self.qd[3:6])
        H = euler_rate_matrix(self.sequence, alpha)
        H_dot = sum((H.diff(a) * r for a, r in zip(alpha, rates)), sp.zeros(3, 3))
        return self.frame_axes(), H, H_dot * rates

    def axes_of(self, q):
        from scipy.spatial.transform import Rotation  # scipy: flexible parts load it already
        return Rotation.from_euler(self.sequence.upper(), np.asarray(q, float)[3:6]).as_matrix()

    def own_constraints(self, q, qd, params):
        """None: the angles are independent."""
        return []

    def angular_velocity(self):
        return self.frame_axes() * euler_rate_matrix(self.sequence, self.q[3:6]) * sp.Matrix(self.qd[3:6])

    def idle_directions(self, q):
        return np.zeros((len(self.coordinates), 0))

    def singular_direction(self, angles):
        """The unit null vector of H at the numeric ``angles`` (euler_body.py's)."""
        H = np.array(euler_rate_matrix(self.sequence, [float(a) for a in angles]), dtype=float)
        return np.linalg.svd(H)[2][-1]
