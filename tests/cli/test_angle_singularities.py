"""A body that turns by angles (``rotation: zxy``) at or towards its angles' singular position
(the middle angle at ±π/2): ``check`` names the part, its angles and what to do instead of a
force balance, and ``simulate`` stops in bounded time with one line naming them."""

import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.helpers.processes import HANG

ROOT = Path(__file__).resolve().parents[2]

BODY = """
name: lock
parameters: {{m: 1.0, g: 9.81}}
gravity: [0, 0, -g]
parts:
  body:
    type: rigid_body
    rotation: {rotation}
    mass: m
    inertia: [0.3, 0.2, 0.4]
{extra}
{initial}
"""
SPRING = "  spring: {type: lagrangian, coordinates: [s], T: '0', V: 3*s**2/2}"  # no mass: a balance 3 s = 0


def mbsynth(*args, env=None):
    return subprocess.run([sys.executable, "-m", "mbsynth.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=HANG, env=env)


def model(tmp_path, rotation="zxy", initial="initial: {body.angle_x: pi/2}", extra=""):
    path = tmp_path / "lock.yaml"
    path.write_text(BODY.format(rotation=rotation, initial=initial, extra=extra))
    return path


def test_check_names_the_angles_singular_position_not_a_balance(tmp_path):
    """zxy at angle_x = π/2: angle_z and angle_y turn about one axis, M = blockdiag(m I, HᵀJH)
    loses rank along (angle_z: +1, angle_y: −1). That is the coordinates' fault: exit 1 with
    the part, its angles and the advice, and no balance to add."""
    done = mbsynth("check", model(tmp_path))
    assert done.returncode == 1, done.stderr
    assert "motion: NOT unique, 1 indeterminate direction(s)" in done.stdout
    assert "direction (body.angle_z: +1, body.angle_y: -1)" in done.stdout
    assert ("part body (angle_x = 1.5708): its zxy angles are at their singular position (singular at "
            "angle_x = ±π/2, where angle_z and angle_y turn about one axis") in done.stdout
    assert "use a quaternion body (rotation: quaternion) or another sequence" in done.stdout
    assert "balance needed" not in done.stdout and "balances: auto" not in done.stdout


def test_check_json_lists_the_part_and_a_proper_euler_sequence_at_zero(tmp_path):
    """zxz (proper Euler) is singular where its middle angle is 0: at the default initial state."""
    done = mbsynth("check", model(tmp_path, rotation="zxz", initial=""), "--json")
    assert done.returncode == 1, done.stderr
    report = json.loads(done.stdout)
    assert report["balances"] == [] and report["suggested_constraints"] == []
    [singular] = report["angle_singularities"]
    assert singular["part"] == "body" and singular["coordinate"] == "body.angle_x" and singular["value"] == 0.0
    assert singular["direction"] == {"body.angle_z": 1.0, "body.angle_z2": -1.0}  # R_z(a) R_z(c) = R_z(a + c)
    assert "singular at angle_x = 0 and ±π" in singular["message"]


def test_check_keeps_a_real_balance_beside_the_angles(tmp_path):
    """A massless spring coordinate beside the locked body: its balance 3 s = 0 is still asked
    for, the body's direction is not."""
    done = mbsynth("check", model(tmp_path, extra=SPRING))
    assert done.returncode == 1, done.stderr
    assert "NOT unique, 2 indeterminate direction(s)" in done.stdout
    assert "its zxy angles are at their singular position" in done.stdout
    [balance] = [line for line in done.stdout.splitlines() if "balance needed" in line]
    assert "spring.s" in balance and "body." not in balance


def test_the_same_orientation_in_another_sequence_is_unique(tmp_path):
    """The advice holds: the turn by π/2 about x, as xyz angles (π/2, 0, 0), is far from their
    singular position (angle_y = ±π/2): unique, exit 0."""
    done = mbsynth("check", model(tmp_path, rotation="xyz", initial="    initial: {rpy: [pi/2, 0, 0]}"))
    assert done.returncode == 0, done.stdout + done.stderr
    assert "motion: unique" in done.stdout and "singular position" not in done.stdout


@pytest.mark.slow  # a 3-second bicycle run in a fresh process, without the kernels
def test_a_falling_bicycle_stops_at_its_angles_singular_position():
    """The user's command: at 0.5 m/s with a lean kick the bicycle falls, its lean (the zxy
    angles' angle_x) towards π/2, where the steps crawled without end. It stops within the
    bound with exit 1 (the run had to stop) and one line naming the parts (a wheel file's part
    by its full name, rear.wheel), their angles by the names within a part and their singular
    value. Without the compiled kernels (MBSYNTH_COMPILED=off): the same path in every process."""
    started = time.monotonic()
    done = mbsynth("simulate", ROOT / "models/rolling/bicycle.yaml", "--set", "v=0.5", "--set", "kick=0.3",
                   "--t-end", "4", env=dict(os.environ, MBSYNTH_COMPILED="off"))
    assert time.monotonic() - started < HANG
    assert done.returncode == 1, done.stderr
    [line] = done.stderr.splitlines()
    assert line.startswith("error: run stopped at t = 3.19")
    assert "the steps crawl at the singular position of a part's angles" in line
    leans = dict(re.findall(r"([\w.]+) \(angle_x = ([-\d.e]+)\)", line))  # a wheel file's part: rear.wheel
    assert sorted(leans) == ["front.wheel", "front_frame", "rear.wheel", "rear_frame"]
    assert all(abs(math.cos(float(lean))) < 0.01 for lean in leans.values())  # the crawl's bound: |det H| < 0.01
    assert "zxy angles are approaching their singular position (singular at angle_x = ±π/2" in line
    assert "use a quaternion body (rotation: quaternion)" in line
    assert "(failed)" in done.stdout

