"""A servo row on a joint that turns many times, written plainly (``hub.angle − W t``): the
joint's angle is read in (−π, π], and the row's residual is taken modulo the turn
(symbolic.derive.turn_residual), so the run passes ±π as often as it turns."""

import numpy as np
import pytest

import mbsynth as mb

DISK = """
name: spun_disk
parameters: {W: 10.0, m: 2.0, r: 0.3}
gravity: [0, -9.81, 0]
parts:
  disk:
    type: rigid_body
    mass: m
    inertia: [m*r**2/4, m*r**2/4, m*r**2/2]
joints:
  - {name: hub, type: revolute, parent: world, child: disk}
constraints:
  - {name: servo, holonomic: 'ROW'}
outputs:
  hub: hub.angle
  rate: hub.rate
"""


@pytest.mark.parametrize("row", ["hub.angle - W*t", "-(hub.angle - W*t)"])
def test_a_plain_servo_row_turns_the_disk_past_pi_again_and_again(row):
    t_end, W = 3.0, 10.0  # 30 rad: the reading wraps at ±π five times
    run = mb.simulate(mb.loads(DISK.replace("ROW", row)), t_end, dt=0.01)
    assert run.status == "completed"
    wrapped = np.angle(np.exp(1j * W * run.t))  # W t read in (−π, π]
    assert np.abs(np.angle(np.exp(1j * (run.column("hub") - wrapped)))).max() < 1e-9
    assert np.abs(run.column("rate") - W).max() < 1e-9
    assert run.residual_position.max() < 1e-12
    jumps = np.abs(np.diff(run.column("hub"))) > np.pi
    assert jumps.sum() == 5  # it did pass ±π that often


def test_the_plain_row_moves_the_disk_as_the_sine_written_one_does():
    plain = mb.simulate(mb.loads(DISK.replace("ROW", "hub.angle - W*t")), 1.0, dt=0.05)
    sine = mb.simulate(mb.loads(DISK.replace("ROW", "sin(hub.angle - W*t)")), 1.0, dt=0.05)
    assert np.abs(plain.q - sine.q).max() < 1e-9
