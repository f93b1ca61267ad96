"""Plots of a trajectory: the joint coordinates (or the model's outputs, or named
columns), kinetic and potential energy, and the constraint residuals."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

from ..core.files import write_atomically  # noqa: E402
from ..core.tolerances import LOG_PLOT_FLOOR

MAX_LINES = 12


def plot_trajectory(traj, path, title=None, system=None, names=None):
    """Write a three-panel figure of ``traj`` to ``path`` (PNG, PDF or SVG, by its suffix
    in any case), whole or not at all (core.files.write_atomically).

    Top panel: the columns ``names`` (coordinates ``part.c``, velocities ``part.c_dot``,
    outputs); else the model's declared outputs; else, for a ``system`` with joints, the
    joint coordinates (angles unwrapped); else its first coordinates. Middle: kinetic and
    potential energy, the work of the forces that derive from no potential, and the change
    of T + V beyond that work, labelled "energy drift" only where nothing else changes the
    energy (``System.unaccounted_work``). Bottom: the constraint residuals."""
    fig, (ax_q, ax_e, ax_r) = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    series, label = _series(traj, system, names)
    for name, values in series[:MAX_LINES]:
        ax_q.plot(traj.t, values, label=name)
    ax_q.set_ylabel(label)
    ax_q.legend(fontsize="small", ncol=3, loc="upper right")
    if len(series) > MAX_LINES:
        ax_q.set_title(f"first {MAX_LINES} of {len(series)} {label}", fontsize="small")
    _energy(ax_e, traj, system)
    for values, name in ((traj.residual_position, "position |φ|"), (traj.residual_velocity, "velocity |φ̇|")):
        ax_r.semilogy(traj.t, np.maximum(values, LOG_PLOT_FLOOR), label=name)
    ax_r.set_ylabel("max constraint residual")
    ax_r.set_xlabel("t [s]")
    ax_r.legend(fontsize="small")
    fig.suptitle(title or "trajectory")
    fig.tight_layout()
    try:
        write_atomically(path, lambda temporary: fig.savefig(temporary, dpi=110))
    finally:
        plt.close(fig)


def _series(traj, system, names):
    """([(label, values)], what they are) for the top panel."""
    outputs = dict(zip(getattr(traj, "output_names", ()), np.asarray(getattr(traj, "outputs", np.zeros((0, 0)))).T))
    if names:
        return [(n, outputs[n] if n in outputs else traj.column(n)) for n in names], "values"
    if outputs:
        return list(outputs.items()), "outputs"
    if system is not None and system.joint_kinematics():
        from ..model.joint_values import along
        joints = along(system, traj.t, traj.q, traj.qd)
        kinematics = system.joint_kinematics()
        found = [(f"{joint}.{name}", values.position[:, i]) for joint, values in joints.items()
                 for i, name in enumerate(kinematics[joint].position_names)]
        if found:
            return found, "joint coordinates"
    return [(name, traj.q[:, i]) for i, name in enumerate(traj.coordinates)], "coordinates"


def _energy(axes, traj, system):
    """Kinetic and potential energy, the work W of the forces that derive from no potential
    (where the model has any), and the change of T + V beyond it: named drift only where
    nothing else changes the energy (``System.unaccounted_work``)."""
    potential = traj.energy - traj.kinetic
    axes.plot(traj.t, traj.kinetic, label="kinetic T")
    axes.plot(traj.t, potential, label="potential V")
    working = system.working_forces() if system is not None else None
    unaccounted = system.unaccounted_work() if system is not None else None
    accounted = [name for name in working or () if name not in (unaccounted or ())]
    work = traj.work
    if accounted:
        axes.plot(traj.t, work, label=f"work W of {_names(accounted)}")
    change = traj.energy - traj.energy[0] - work
    beyond = " − W(t)" if accounted else ""
    if unaccounted == []:
        axes.plot(traj.t, change, label=f"energy drift (T + V)(t) − (T + V)(0){beyond}")
    else:
        doing = f" (not conserved: work of {_names(unaccounted)})" if unaccounted else ""
        axes.plot(traj.t, change, label=f"(T + V)(t) − (T + V)(0){beyond}{doing}")
    axes.set_ylabel("energy [J]")
    axes.legend(fontsize="small")


def _names(names, shown=3):
    """The first ``shown`` of ``names``, joined."""
    return ", ".join(names[:shown]) + (", ..." if len(names) > shown else "")
