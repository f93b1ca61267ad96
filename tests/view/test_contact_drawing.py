"""The viewer draws a run's contacts (view/contacts.py): at each impact a point where it
struck and an arrow along the contact normal whose length is proportional to the impulse,
in the scene and in the saved HTML (meshcat's commands decoded, no browser)."""

import base64
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import umsgpack

import mbsynth as mb
from mbsynth.view import viewer
from mbsynth.view.contacts import EVENT_SHOW, IMPULSE_LENGTH
from mbsynth.view.scene import build_scene
from tests.helpers.scenes import animation_clips, node, segment_ends

MODELS = Path(__file__).resolve().parents[2] / "models" / "contact"
E = 0.5  # bouncing_ball.yaml's restitution


@pytest.fixture(scope="module")
def ball():
    """The bouncing ball until just after its third impact (at t1, 2 t1, 2.5 t1: each flight
    e times the one before, the first 2 e t1)."""
    system = mb.load(MODELS / "bouncing_ball.yaml")
    t1 = np.sqrt(2 * (1.0 - 0.05) / 9.81)
    return system, mb.simulate(system, 2.5 * t1 + 0.05, dt=0.01)


def test_each_impact_draws_an_arrow_up_from_the_ground_proportional_to_its_impulse(ball):
    """The impulses of successive bounces are m (1 + e) v_k with v_{k+1} = e v_k, so the
    arrows shrink by e from one to the next; the largest is IMPULSE_LENGTH of the model's
    length; each starts at the contact point on the ground under the ball and points up."""
    system, traj = ball
    impacts = [ev for ev in traj.events if ev.kind == "impact"]
    assert len(impacts) == 3
    scene = build_scene(system, traj)
    arrow, point = node(scene, "contacts/floor/impulse"), node(scene, "contacts/floor/point")
    lengths = []
    for ev in impacts:
        row = int(np.flatnonzero(scene.times >= ev.t)[0])
        start, end = segment_ends(arrow.transforms[row])
        assert np.allclose(start, 0.0, atol=1e-12)  # on the ground under the ball (a free fall's cubic is exact)
        assert np.allclose(point.transforms[row][:3, 3], start)
        direction = (end - start) / np.linalg.norm(end - start)
        assert np.allclose(direction, [0, 0, 1], atol=1e-12)
        lengths.append(np.linalg.norm(end - start))
    assert lengths[0] == pytest.approx(IMPULSE_LENGTH * scene.length, rel=1e-12)
    assert lengths[1] / lengths[0] == pytest.approx(E, rel=1e-9)
    assert lengths[2] / lengths[1] == pytest.approx(E, rel=1e-9)


def test_the_arrow_shows_for_a_while_after_its_impact_and_vanishes_between(ball):
    system, traj = ball
    scene = build_scene(system, traj)
    arrow = node(scene, "contacts/floor/impulse")
    size = np.linalg.norm(arrow.transforms[:, :3, 0], axis=1)
    t1 = traj.events[0].t
    assert (size[scene.times < t1] < 1e-6).all()  # nothing struck yet
    shown = (scene.times >= t1) & (scene.times < t1 + EVENT_SHOW)
    assert shown.any() and (size[shown] > 0.1 * scene.length).all()


def test_the_saved_html_holds_the_contact_objects_and_the_arrow_lengths(ball, tmp_path):
    """The meshcat commands in the page: a sphere and an arrow (a shaft and a cone) set
    under /meshcat/model/contacts/floor/, and the arrow's animated scale along x, at the
    first drawn time after each impact, in the ratio of the impulses."""
    system, traj = ball
    html = viewer.to_html(system, traj, tmp_path / "ball.html").read_text()
    commands = [umsgpack.unpackb(base64.b64decode(blob))
                for blob in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)]
    objects = {c["path"]: c["object"] for c in commands if c["type"] == "set_object"}
    base = "/meshcat/model/contacts/floor"
    assert objects[f"{base}/point/0.0"]["geometries"][0]["type"] == "SphereGeometry"
    shaft, cone = (objects[f"{base}/impulse/0.{j}"]["geometries"][0] for j in (0, 1))
    assert shaft["type"] == cone["type"] == "CylinderGeometry"
    assert cone["radiusTop"] == 0 and cone["radiusBottom"] > shaft["radiusBottom"]
    times, scales = animation_clips(html)[f"{base}/impulse"]["scale"]
    impacts = [ev for ev in traj.events if ev.kind == "impact"]
    start = traj.t[0]
    lengths = [scales[np.flatnonzero(times >= ev.t - start - 1e-12)[0], 0] for ev in impacts]
    assert [x / lengths[0] for x in lengths] == pytest.approx([ev.impulse / impacts[0].impulse for ev in impacts],
                                                              rel=1e-6)


def test_mbsynth_view_writes_the_contacts_into_its_html(tmp_path):
    """``mbsynth view models/contact/bouncing_ball.yaml --t-end 0.6 --html FILE``: its one
    impact (t1 = 0.44 s) drawn under /meshcat/model/contacts/floor/."""
    out = tmp_path / "ball.html"
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "view", str(MODELS / "bouncing_ball.yaml"),
                           "--t-end", "0.6", "--html", str(out)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert f"wrote {out}" in done.stdout
    paths = {umsgpack.unpackb(base64.b64decode(blob)).get("path")
             for blob in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", out.read_text())}
    assert {"/meshcat/model/contacts/floor/point/0.0", "/meshcat/model/contacts/floor/impulse/0.1"} <= paths
