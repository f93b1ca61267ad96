"""Whether a run is stiff for an explicit integrator: the model's highest frequency against
the run's length (``mbsynth check`` suggests an implicit method where it is).

An explicit pair's step is bounded by the highest frequency ω of a mode the motion carries,
whatever accuracy is asked: DOP853 is stable for h ω ≤ 5.96 on the imaginary axis, and its
error control spends about ten steps on each period of such a mode (the flexible pendulum of
benchmarks/flexible.py: 1,520 steps for 138 periods of its 866 rad/s mode). The highest
frequency here is that of the flexible parts' reduced models (K and M of their elastic
coordinates, the frame held): the assembled model's stiffest mode is at least as fast.
"""

import numpy as np
import scipy.linalg

STIFF_PERIODS = 100  # periods of the highest mode in a run above which an implicit method is suggested:
# an explicit pair spends about ten steps on each, over a thousand on that mode alone


def highest_frequency(system):
    """(ω in rad/s, part name) of the fastest mode of the model's flexible parts' reduced
    models, or None where it has none."""
    found = None
    for part in system.parts:
        reduction = getattr(part, "reduction", None)
        if reduction is None:
            continue
        omega = float(np.sqrt(scipy.linalg.eigvalsh(np.asarray(reduction.stiffness, float),
                                                    np.asarray(reduction.mass, float))[-1]))
        if found is None or omega > found[0]:
            found = (omega, part.name)
    return found


def suggestion(system, t_span):
    """{method, omega, part, periods, threshold} where the highest frequency makes a run of
    length ``t_span`` stiff (more than STIFF_PERIODS periods of it), else None."""
    found = highest_frequency(system)
    if found is None:
        return None
    omega, part = found
    periods = omega * t_span / (2 * np.pi)
    if periods <= STIFF_PERIODS:
        return None
    return dict(method="Radau", omega=omega, part=part, periods=periods, threshold=STIFF_PERIODS)
