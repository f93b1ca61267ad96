"""Plots of a trajectory: the coordinates, the energy drift and the constraint residuals."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

MAX_LINES = 12


def plot_trajectory(traj, path, title=None):
    """Write a three-panel figure of ``traj`` to ``path`` (PNG, PDF or SVG)."""
    fig, (ax_q, ax_e, ax_r) = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    for i, name in enumerate(traj.coordinates[:MAX_LINES]):
        ax_q.plot(traj.t, traj.q[:, i], label=name)
    ax_q.set_ylabel("coordinates")
    ax_q.legend(fontsize="small", ncol=3, loc="upper right")
    if len(traj.coordinates) > MAX_LINES:
        ax_q.set_title(f"first {MAX_LINES} of {len(traj.coordinates)} coordinates", fontsize="small")
    drift = traj.energy - traj.energy[0]
    ax_e.plot(traj.t, drift)
    ax_e.set_ylabel("E(t) − E(0) [J]")
    for values, label in ((traj.residual_position, "position |φ|"), (traj.residual_velocity, "velocity |φ̇|")):
        ax_r.semilogy(traj.t, np.maximum(values, 1e-18), label=label)
    ax_r.set_ylabel("max constraint residual")
    ax_r.set_xlabel("t [s]")
    ax_r.legend(fontsize="small")
    fig.suptitle(title or "trajectory")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
