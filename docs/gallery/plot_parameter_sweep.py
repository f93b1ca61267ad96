"""
A parameter sweep: where a PD-held pendulum comes to rest
=========================================================

``models/joints/pd_pendulum.yaml`` is a rod hinged at its top and driven by a PD law
written on the joint's own values, torque −kp (θ − target) − kd θ̇ with θ = ``hinge.angle``.
Gravity pulls it back, so it settles short of the target, where the law balances
gravity: kp (θ − target) = −m g (L/2) sin θ.

``mb.sweep`` runs one simulation per value of the gain kp on a Dask cluster and returns
one row per run with the metrics asked for. Left to itself it starts a local cluster of
worker *processes*; a script run by sphinx-gallery cannot start processes (they would
import the script again), so here the cluster is Dask's in-process one (``processes=False``,
one thread), handed to ``mb.sweep`` by its address as any cluster of yours would be
(``scheduler=``, ``mbsynth sweep --scheduler``). The metrics: the final angle
(``final:hinge.angle``, a joint value in an expression) and the energy book-keeping.
Each worker builds the model and its compiled engine once and only changes numbers
(``System.with_parameters``) from run to run. The root of the balance, found by scipy,
is the reference.
"""

# %%
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from distributed import LocalCluster
from scipy.optimize import brentq

import mbsynth as mb

MODELS = Path("../../models")  # sphinx-gallery runs each script in its own folder
with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                  dashboard_address=None) as cluster:
    table = mb.sweep(MODELS / "joints" / "pd_pendulum.yaml", {"kp": (25.0, 100.0, 6)}, t_end=8.0, dt=0.1,
                     metrics=["final:hinge.angle", "final:hinge.rate", "max_residual"],
                     scheduler=cluster.scheduler_address)
columns = ["kp", "status", "final:hinge.angle", "final:hinge.rate", "max_residual", "wall_time_s"]
print(table[columns].to_string(index=False, float_format=lambda x: f"{x:.6g}"))

# %%
# Against the balance kp (θ − target) = −m g (L/2) sin θ
# ------------------------------------------------------------
p = mb.load(MODELS / "joints" / "pd_pendulum.yaml").parameters


def rest_angle(kp):
    return brentq(lambda x: kp * (x - p["target"]) + p["m"] * p["g"] * p["L"] / 2 * np.sin(x), -np.pi / 2, np.pi / 2)


table = table.sort_values("kp")
expected = np.array([rest_angle(kp) for kp in table["kp"]])
error = np.abs(table["final:hinge.angle"].to_numpy() - expected).max()
print(f"largest difference from the balance: {error:.1e} rad")
assert error < 1e-6

kp_fine = np.linspace(5.0, 110.0, 200)
fig, ax = plt.subplots(figsize=(6.5, 4))
ax.plot(kp_fine, [rest_angle(k) for k in kp_fine], "k:", label="balance of the PD law and gravity")
ax.plot(table["kp"], table["final:hinge.angle"], "o", label="sweep: θ at t = 8 s")
ax.axhline(p["target"], color="grey", lw=0.8, label="target")
ax.set_xlabel("kp [N m / rad]")
ax.set_ylabel("rest angle θ [rad]")
ax.legend()
fig.tight_layout()
