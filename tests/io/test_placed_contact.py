"""A rolling disk's ground in a placed file: the contact plane z = ground is the file's, so a
placement raises it with the disk (a disk placed 0.5 m up rolls on z = 0.5, as the same
disk written out flat with ``ground: 0.5``); a placement that tilts the plane is refused
(a contact's ground is horizontal)."""

import subprocess
import sys
from pathlib import Path

import numpy as np

import mbsynth as mb

ROOT = Path(__file__).resolve().parents[2]
TURN = 0.7  # the placement's turn about z
DISK = """name: disk
parameters: {R: 0.1, m: 1.0}
gravity: [0, 0, -9.81]
parts:
  disk:
    type: rigid_body
    mass: m
    inertia: [m*R**2/4, m*R**2/4, m*R**2/2]
    frames: {hub: {axis: [0, 1, 0]}}
    initial: {position: [0, 0, R], velocity: [1, 0, 0], angular_velocity: [0, 10, 0]}
joints:
  - {name: contact, type: rolling_disk, child: disk.hub, radius: R}
"""
PLACED = f"""name: placed
gravity: [0, 0, -9.81]
parts:
  d: {{type: model, file: disk.yaml, placement: {{position: [1, 0, 0.5], rpy: [0, 0, {TURN}]}}}}
"""
# the same disk written out: its pose and velocities turned by TURN about z and raised 0.5 m
FLAT = f"""name: flat
parameters: {{R: 0.1, m: 1.0}}
gravity: [0, 0, -9.81]
parts:
  disk:
    type: rigid_body
    mass: m
    inertia: [m*R**2/4, m*R**2/4, m*R**2/2]
    frames: {{hub: {{axis: [0, 1, 0]}}}}
    initial: {{position: [1, 0, 0.5 + R], velocity: [cos({TURN}), sin({TURN}), 0],
               angular_velocity: [-10*sin({TURN}), 10*cos({TURN}), 0], rpy: [0, 0, {TURN}]}}
joints:
  - {{name: contact, type: rolling_disk, child: disk.hub, radius: R, ground: 0.5}}
"""


def test_a_placed_rolling_disk_rolls_on_its_placed_ground(tmp_path):
    (tmp_path / "disk.yaml").write_text(DISK)
    (tmp_path / "placed.yaml").write_text(PLACED)
    placed, flat = mb.load(tmp_path / "placed.yaml"), mb.loads(FLAT, name="flat")
    q, qd = placed.initial_state()
    qf, qdf = flat.initial_state()
    np.testing.assert_allclose(q, qf, atol=1e-15)
    np.testing.assert_allclose(qd, qdf, atol=1e-15)
    phi, _ = placed.constraint_residuals(0.0, q, qd)
    assert np.nanmax(np.abs(phi)) < 1e-15  # the contact's height row among them: on the raised ground
    np.testing.assert_allclose(placed.motion(0.0, q, qd).qdd, flat.motion(0.0, qf, qdf).qdd, atol=1e-12)
    run = mb.simulate(placed, 0.5, dt=0.1)
    z = run.column("d.disk.z")
    assert run.status == "completed" and np.abs(z - 0.6).max() < 1e-9  # rolls upright along the turned x


def test_a_placement_that_tilts_a_rolling_contact_is_refused(tmp_path):
    (tmp_path / "disk.yaml").write_text(DISK)
    (tmp_path / "tilted.yaml").write_text(PLACED.replace(f"rpy: [0, 0, {TURN}]", "rpy: [0.2, 0, 0]"))
    result = subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(tmp_path / "tilted.yaml")],
                            capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 2 and result.stdout == ""
    err = result.stderr.strip()
    assert "\n" not in err
    assert err.startswith(f"error: {tmp_path / 'disk.yaml'}:12: at joints[0]:")
    assert "may turn it about the vertical and shift it, not tilt it" in err
    assert err.endswith(f"(in 'd', included from {tmp_path / 'tilted.yaml'}:4)")
