"""A motion that is not unique: a heavy body turning on a spherical joint at its centre of
mass, a massless body on a spherical joint at its tip, free to spin (the compiled kernel
hands it back to the exact treatment)."""

import numpy as np

from mbsynth.io import loads

OMEGA, TIP = np.array([0.3, -0.5, 0.8]), np.array([0.0, 0.0, -0.5])


def free_spin():
    """(model, q, q̇, the q̈ of η = 0). The heavy body (spherical inertia, no torque) turns at
    a constant ω: ü = −|ω|²u/4 at u = (1, 0, 0, 0), u̇ = (0, ω)/2; the ghost's centre, at the
    tip r, has r̈ = ω × (ω × r); its own spin is free, and η = 0 gives it none."""
    model = loads("""
        name: free_spin
        parts:
          heavy: {type: rigid_body, mass: 1.0, inertia: [0.1, 0.1, 0.1], frames: {tip: {position: [0, 0, -0.5]}}}
          ghost: {type: rigid_body, mass: 0.0, inertia: [0, 0, 0]}
        gravity: [0, 0, -9.81]
        joints:
          - {name: hang, type: spherical, parent: world, child: heavy}
          - {name: tip, type: spherical, parent: heavy.tip, child: ghost}
        """)
    q, qd = model.initial_state()
    q[7:10] = TIP
    qd[3:7] = np.concatenate([[0.0], OMEGA / 2])
    qd[7:10] = np.cross(OMEGA, TIP)
    expected = np.zeros(model.n)
    expected[3:7] = -OMEGA @ OMEGA / 4 * q[3:7]
    expected[7:10] = np.cross(OMEGA, np.cross(OMEGA, TIP))
    return model, q, qd, expected
