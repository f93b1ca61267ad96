"""Tolerances are relative: the same mechanism in millimetres, metres or
kilometres, with masses in grams or tonnes, completes and moves alike after rescaling time.

Lengths ×s with g fixed scale time by √s (Froude similarity); masses scale no motion. The
references use no mbsynth: the pendulum's exact motion (Jacobi's sn) and the N-four-bar's
exact one-degree-of-freedom motion (benchmarks/iftomm_reference.py).
"""

import math
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.analysis.projection import project_positions

ROOT = Path(__file__).resolve().parents[2]
from benchmarks import iftomm_reference as ref

SCALES = [(1e-3, 1.0), (1.0, 1e-3), (1.0, 1e3), (1e3, 1.0), (1e3, 1e3)]  # (length ×, mass ×)


@pytest.mark.parametrize("length, mass", SCALES)
def test_pendulum_at_any_scale(length, mass):
    system = mb.load(ROOT / "models" / "mechanisms" / "simple_pendulum.yaml").with_parameters(L=length, m=mass)
    unit = math.sqrt(length)  # the time scale √(L/g) relative to L = 1 m
    traj = mb.simulate(system, 3.0 * unit)
    assert traj.status == "completed"
    x, y = ref.pendulum_exact(traj.t / unit, 1.0, 9.81, math.pi / 2)
    error = np.hypot(traj.column("bob.x") / length - x, traj.column("bob.y") / length - y)
    assert error.max() < 1e-6
    rod = traj.column("bob.x") ** 2 + traj.column("bob.y") ** 2 - length**2
    assert np.abs(rod).max() < 1e-10 * length**2


@pytest.mark.parametrize("length, mass", [(1e-3, 1e3), (1e3, 1e-3)])
def test_n_four_bar_through_its_singular_position_at_any_scale(length, mass):
    unit = math.sqrt(length)
    system = mb.loads(ref.n_four_bar_yaml(1, L=length, m=mass, v0=unit), name="n_four_bar_1")
    traj = mb.simulate(system, 1.5 * unit)  # the singular positions are near t = 0.71 √L and 1.22 √L
    crossings = ref.n_four_bar_singular_times(1, 1.5) * unit
    listed = traj.stats["singular_positions"]
    assert traj.status == "completed" and len(listed) == len(crossings) == 2
    for entry, t in zip(listed, crossings):
        assert entry["t_from"] - 1e-5 * unit <= t <= entry["t_to"] + 1e-5 * unit, (entry, t)
    theta = traj.column("v0.theta")
    bx = (traj.column("v0.x") - 0.5 * length * np.sin(theta)) / length
    by = (traj.column("v0.y") + 0.5 * length * np.cos(theta)) / length
    xr, yr = ref.n_four_bar_reference(traj.t / unit, 1)
    # of L; the benchmark asks 1e-3. Measured at the 1 m scale 3.2e-7, in millimetres 4.6e-8; in
    # kilometres 2.5e-6 with the constraints evaluated in Python and 1.0e-5 with their compiled
    # kernels (once `make install` has compiled them): the crossings amplify rounding there
    assert np.hypot(bx - xr, by - yr).max() < 3e-5


@pytest.mark.parametrize("length, mass", [(1e-3, 1e3), (1e3, 1e-3)])
def test_rigid_double_pendulum_at_any_scale(length, mass):
    """Rigid bodies with quaternions and revolute joints (the compiled tree path and its
    fallbacks): the 3D double pendulum scaled in length and mass, released from rest at the
    1 m model's consistent pose scaled alike (positions × length about the pivot at
    (0, 0, 2), orientations as they are),
    moves as the 1 m, 1 kg one after rescaling time, its angles alike to 1e-7 rad."""
    base = mb.load(ROOT / "models" / "rigid" / "double_pendulum_3d.yaml")
    p = base.parameters
    scaled = base.with_parameters(L1=p["L1"] * length, L2=p["L2"] * length, r=p["r"] * length,
                                  m1=p["m1"] * mass, m2=p["m2"] * mass)
    unit = math.sqrt(length)
    at_rest = np.zeros(base.n)
    q0 = project_positions(base, 0.0, base.initial_q)
    pivot = np.array([{"x": 0.0, "y": 0.0, "z": 2.0}.get(c.split(".")[1], np.nan) for c in base.coordinates])
    q0_scaled = np.where(np.isnan(pivot), q0, pivot + (q0 - pivot) * length)
    reference = mb.simulate(base, 2.0, dt=0.05, q0=q0, qd0=at_rest)
    traj = mb.simulate(scaled, 2.0 * unit, dt=0.05 * unit, q0=q0_scaled, qd0=at_rest)
    assert traj.status == reference.status == "completed"
    for link in ("link1", "link2"):
        # the angle about the pivot's y axis, from the quaternion (w, 0, y, 0): 2 atan2(y, w)
        angle = 2 * np.arctan2(traj.column(f"{link}.qy"), traj.column(f"{link}.qw"))
        expected = 2 * np.arctan2(reference.column(f"{link}.qy"), reference.column(f"{link}.qw"))
        assert np.abs(np.angle(np.exp(1j * (angle - expected)))).max() < 1e-7


def _scaled_urdf(source, length, mass, target):
    """The URDF ``source`` with every length ×``length`` and mass ×``mass`` (inertias ×
    mass·length²), written to ``target``."""
    import xml.etree.ElementTree as ET
    tree = ET.parse(source)
    for origin in tree.iter("origin"):
        if "xyz" in origin.attrib:
            origin.set("xyz", " ".join(str(float(x) * length) for x in origin.get("xyz").split()))
    for element in tree.iter("mass"):
        element.set("value", str(float(element.get("value")) * mass))
    for inertia in tree.iter("inertia"):
        for key, value in inertia.attrib.items():
            inertia.set(key, str(float(value) * mass * length**2))
    tree.write(target)
    return target


@pytest.mark.parametrize("length, mass", [(1e-3, 1e3), (1e3, 1e-3)])
def test_urdf_robot_at_any_scale(length, mass, tmp_path):
    """example-robot-data's double pendulum, its URDF scaled in length and mass: released
    at the same joint angles, its joints move as the original's after rescaling time
    (System.joint_values), to 1e-7 rad."""
    from mbsynth.robots.build import robot_files
    from mbsynth.robots.twin import Twin
    angles = np.array([0.8, -0.5])
    runs = []
    for s, k in ((1.0, 1.0), (length, mass)):
        system = mb.from_robot(_scaled_urdf(robot_files()["double_pendulum"], s, k, tmp_path / f"robot_{s}.urdf"))
        q0, qd0 = Twin(system).to_maximal(angles, np.zeros(2))
        unit = math.sqrt(s)
        traj = mb.simulate(system, 0.7 * unit, q0=q0, qd0=qd0, dt=0.1 * unit)  # before its chaos amplifies rtol
        assert traj.status == "completed" and traj.max_residual < 1e-9
        runs.append(np.array([[v.position[0] for v in system.joint_values(t, q, qd).values()]
                              for t, q, qd in zip(traj.t, traj.q, traj.qd)]))
    assert np.abs(runs[0] - angles).max() > 0.1  # it moves
    assert np.abs(runs[1] - runs[0]).max() < 1e-7
