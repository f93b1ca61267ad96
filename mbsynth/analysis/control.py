"""Sampled control: a control law in Python on joint values, for ``simulate(controller=...)``.

A law that is not an expression of the model (a lookup table, an estimator, a trained
policy) is a callable ``f(t, joint_values) -> {parameter: value}``: it reads the joint
values at a sample (``System.joint_values``: {joint: (position, rate, acceleration None)})
and returns new values for some of the model's parameters — a robot's ``tau_<joint>``,
an actuation's amplitude. It is called at t0 and every ``control_dt`` after, and its values
are held until the next call (zero-order hold, as a digital controller does); they are
written into the run's Data (``Data.set_parameters``: no System is built during a run),
and the integrator restarts at each sample, where the forces jump. A law that fails stops
the run with a ControlError that holds the rows recorded before (``trajectory``).
"""

from ..core.errors import ControlError, ModelError


class SampledControl:
    """The law ``law`` applied at its samples to a run's Data."""

    def __init__(self, law, control_dt):
        if not callable(law):
            raise TypeError(f"controller must be a callable f(t, joint_values) -> {{parameter: value}}, got {law!r}")
        if not control_dt > 0:
            raise ValueError(f"control_dt must be positive, got {control_dt}")
        self.law, self.dt = law, float(control_dt)

    def apply(self, data, t, q, qd):
        """Write the law's parameter values at the sample (t, q, q̇) into ``data``. Raises
        ControlError where the law raises (the cause chained) or returns what the model
        cannot take: not a dict, an unknown name, a value that is no finite real number, a
        value that makes a part unusable (System.resolved_parameters)."""
        try:
            values = self.law(t, data.joint_values(t, q, qd))
        except Exception as err:
            raise ControlError(f"controller at t = {t:.6g} raised {type(err).__name__}: {err}", time=t) from err
        if not isinstance(values, dict):
            raise ControlError(f"controller at t = {t:.6g}: expected a dict {{parameter: value}}, got "
                               f"{type(values).__name__}", time=t)
        try:
            data.set_parameters(values)
        except ModelError as err:
            raise ControlError(f"controller at t = {t:.6g}: {err}", time=t) from None
