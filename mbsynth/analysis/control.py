"""Sampled control: a control law in Python on joint values, for ``simulate(controller=...)``.

A law that is not an expression of the model (a lookup table, an estimator, a trained
policy) is a callable ``f(t, joint_values) -> {parameter: value}``: it reads the joint
values at a sample (``System.joint_values``: {joint: (position, rate, acceleration None)})
and returns new values for some of the model's parameters — a robot's ``tau_<joint>``,
an actuation's amplitude. It is called at t0 and every ``control_dt`` after, and its values
are held until the next call (zero-order hold, as a digital controller does); they are
written into the run's Data (``Data.set_parameters``: no System is built during a run),
and the integrator restarts at each sample, where the forces jump.
"""

import numpy as np

from ..core.errors import ModelError


class SampledControl:
    """The law ``law`` applied at its samples to a run's Data."""

    def __init__(self, law, control_dt):
        if not callable(law):
            raise TypeError(f"controller must be a callable f(t, joint_values) -> {{parameter: value}}, got {law!r}")
        if not control_dt > 0:
            raise ValueError(f"control_dt must be positive, got {control_dt}")
        self.law, self.dt = law, float(control_dt)

    def times(self, t0, t_end):
        """The sample times in [t0, t_end)."""
        return t0 + self.dt * np.arange(int(np.ceil((t_end - t0) / self.dt - 1e-9)))

    def apply(self, data, t, q, qd):
        """Write the law's parameter values at the sample (t, q, q̇) into ``data``."""
        values = self.law(t, data.joint_values(t, q, qd))
        if not isinstance(values, dict):
            raise ModelError(f"controller at t = {t:.6g}: expected a dict {{parameter: value}}, got "
                             f"{type(values).__name__}")
        try:  # unknown names, non-finite values, a part they make unusable (System.resolved_parameters)
            data.set_parameters(values)
        except ModelError as err:
            raise ModelError(f"controller at t = {t:.6g}: {err}") from None
