"""Seeing the motion: the drawn poses, and pictures of the HTML export and the live page.

The poses are checked against rotations written out by hand. The pictures are taken by
headless Chromium (installed by ``make test`` when run as root) and compared with a
picture of the same scene without the model: the model must change many pixels.
"""

import os
import re
import signal
import socket
import struct
import subprocess
import sys
from pathlib import Path
from urllib.parse import urlparse

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.view import viewer
from mbsynth.cli import main
from mbsynth.view import screenshot as screenshot_module
from mbsynth.view.screenshot import chromium, screenshot
from mbsynth.analysis.trajectory import Trajectory
from mbsynth.view.scene import build_scene, drawn_rows
from tests.helpers.processes import HANG, ended_within, needs_proc, proc_stat, running
from tests.helpers.scenes import node, trajectory_of

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE3 = ROOT / "models" / "paper" / "example3_two_masses.yaml"
CHANGED = 40  # a pixel differs when one of its channels moves by more than this (of 255)

BODIES = """
name: bodies
parameters: {a: 0.5}
parts:
  body:
    type: rigid_body
    mass: 1
    inertia: [1, 1, 1]
    frames:
      tip: {position: [a, 0, 0]}
    geometry: {box: [0.2, 0.1, 0.1]}
  slab:
    type: planar_body
    mass: 1
    inertia: 1
    frames:
      corner: {position: [a, 0, 0]}
"""


def rotation_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_rigid_and_planar_bodies_are_drawn_at_their_pose():
    system = mb.loads(BODIES)
    half = np.pi / 6  # u = (cos 30°, 0, 0, sin 30°): 60° about z
    u = [np.cos(half), 0, 0, np.sin(half)]
    rows = [[1, 2, 3, *u, 0.4, -0.2, np.pi / 2],
            [1, 2, 3, *(2 * np.array(u)), 0.4, -0.2, np.pi / 2]]  # the same turn, a quaternion of norm 2
    scene = build_scene(system, trajectory_of(system, rows), axes=True)  # frames drawn as triads
    R = rotation_z(np.pi / 3)
    expected = np.eye(4)
    expected[:3, :3], expected[:3, 3] = R, [1, 2, 3]
    for T in node(scene, "body").transforms:
        np.testing.assert_allclose(T, expected, atol=1e-12)
    tip = node(scene, "body.tip").transforms[:, :3, 3]
    np.testing.assert_allclose(tip, [[1 + 0.5 * np.cos(np.pi / 3), 2 + 0.5 * np.sin(np.pi / 3), 3]] * 2, atol=1e-12)
    slab = node(scene, "slab").transforms[0]
    np.testing.assert_allclose(slab[:3, :3], rotation_z(np.pi / 2), atol=1e-12)
    np.testing.assert_allclose(slab[:3, 3], [0.4, -0.2, 0], atol=1e-12)
    np.testing.assert_allclose(node(scene, "slab.corner").transforms[0, :3, 3], [0.4, 0.3, 0], atol=1e-12)
    assert node(scene, "slab").shapes == [] and node(scene, "slab").axes  # no geometry: axes, as the body has some


def test_bodies_without_geometry_show_their_structure_when_nothing_is_drawn():
    system = mb.loads(BODIES.replace("    geometry: {box: [0.2, 0.1, 0.1]}\n", ""))
    scene = build_scene(system, trajectory_of(system, system.initial_state()[0]))
    assert [(n.path, n.shapes[0]["shape"]) for n in scene.nodes] == [
        ("body", "sphere"), ("slab", "sphere"), ("structure/body.tip", "line"), ("structure/slab.corner", "line")]


def test_three_js_quaternion_of_a_turn_about_z():
    T = np.eye(4)
    T[:3, :3] = rotation_z(np.pi / 3)
    position, quaternion, scale = viewer.decompose(T[None])
    np.testing.assert_allclose(quaternion[0], [0, 0, np.sin(np.pi / 6), np.cos(np.pi / 6)], atol=1e-12)
    np.testing.assert_allclose(scale[0], [1, 1, 1])


def test_example3_frames_and_spring_lines_follow_the_coordinates():
    system = mb.load(EXAMPLE3)
    x1, q1, q2, d = 1.05, 1.25, 0.9, system.parameters["d"]
    scene = build_scene(system, trajectory_of(system, [x1, q1, q2]))
    np.testing.assert_allclose(node(scene, "body1.mass").transforms[0, :3, 3], [x1 + d / 2, 0, 0])
    np.testing.assert_allclose(node(scene, "body2.mass").transforms[0, :3, 3], [q1 + q2 + d / 2, 0, 0])
    for path, start, end in (("lines/body1.wall-face", 0.0, x1), ("lines/body2.start-face", q1, q1 + q2)):
        T = node(scene, path).transforms[0]
        np.testing.assert_allclose(T @ [0, 0, 0, 1], [start, 0, 0, 1], atol=1e-12)  # the unit segment's ends
        np.testing.assert_allclose(T @ [1, 0, 0, 1], [end, 0, 0, 1], atol=1e-12)


def test_spring_parts_are_lines_between_their_ends():
    system = mb.load(ROOT / "models" / "forces" / "spring_part_chain.yaml")
    q, _ = system.initial_state()
    scene = build_scene(system, trajectory_of(system, q))
    index = {c: i for i, c in enumerate(system.coordinates)}
    T = node(scene, "lines/spring2").transforms[0]
    for corner, end in (([0, 0, 0, 1], "end1"), ([1, 0, 0, 1], "end2")):
        c = end[-1]
        expected = [q[index[f"spring2.{axis}{c}"]] for axis in "xyz"]
        np.testing.assert_allclose((T @ corner)[:3], expected, atol=1e-12)
    assert node(scene, "mass1").shapes[0]["shape"] == "sphere"  # a particle without geometry


def test_drawn_rows_keep_at_most_fps_per_second_and_the_last():
    t = np.linspace(0, 1, 101)
    rows = drawn_rows(t, fps=30)
    assert rows[0] == 0 and rows[-1] == 100
    assert np.diff(t[rows])[:-1].min() >= 1 / 30 - 1e-12
    assert len(rows) == 26  # every 4th of 0.01 s steps (0.04 ≥ 1/30), plus the last


def test_trajectory_of_another_model_is_refused():
    system = mb.load(EXAMPLE3)
    other = Trajectory(("a.x",), np.zeros(1), np.zeros((1, 1)), np.zeros((1, 1)), *np.zeros((4, 1)))
    with pytest.raises(mb.ModelError, match="coordinates"):
        build_scene(system, other)


def test_line_to_a_frame_the_part_lacks_is_a_model_error(tmp_path):
    text = EXAMPLE3.read_text().replace("{line: face}]", "{line: nowhere}]")
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(mb.ModelError, match=r"bad\.yaml:\d+: at parts\.body1\.frames\.wall\.geometry\[1\]\.line"):
        mb.load(path)


def write_tetrahedron_stl(path):
    """A binary STL of the tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1)."""
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    data = b"mbsynth test".ljust(80) + struct.pack("<I", len(faces))
    for f in faces:
        normal = np.cross(v[f[1]] - v[f[0]], v[f[2]] - v[f[0]])
        data += struct.pack("<12fH", *(normal / np.linalg.norm(normal)), *v[f[0]], *v[f[1]], *v[f[2]], 0)
    path.write_bytes(data)


def mesh_model(tmp_path):
    (tmp_path / "meshes").mkdir()
    write_tetrahedron_stl(tmp_path / "meshes" / "tetra.stl")
    model = tmp_path / "tetra.yaml"
    model.write_text("""
name: tetra
parts:
  body:
    type: rigid_body
    mass: 1
    inertia: [1, 1, 1]
    geometry: {mesh: meshes/tetra.stl, scale: [0.5, 0.5, 0.5], color: green}
    initial: {angular_velocity: [0, 0, 1]}
""")
    return model


def test_mesh_paths_are_relative_to_the_model_file(tmp_path, monkeypatch):
    model = mesh_model(tmp_path)
    monkeypatch.chdir(ROOT)
    system = mb.load(model)
    assert system.parts[0].geometry[0]["file"] == str((tmp_path / "meshes" / "tetra.stl").resolve())
    model.write_text(model.read_text().replace("meshes/tetra.stl", "meshes/missing.stl"))
    with pytest.raises(mb.ModelError, match=r"tetra\.yaml:\d+: at parts\.body\.geometry\.mesh: mesh file"):
        mb.load(model)


def test_meshcat_imports_without_the_zmq_deprecation_warning():
    plain = subprocess.run([sys.executable, "-W", "error::DeprecationWarning", "-c", "import meshcat"],
                           capture_output=True, text=True)
    assert "zmq.eventloop.ioloop is deprecated" in plain.stderr  # the quirk is there ...
    ours = subprocess.run([sys.executable, "-W", "error::DeprecationWarning", "-c",
                           "from mbsynth import viewer; viewer.import_meshcat()"], capture_output=True, text=True)
    assert ours.returncode == 0, ours.stderr  # ... and handled


def test_an_interrupted_serve_still_lets_close_stop_the_server():
    """Ctrl-C may land anywhere in serve(): close() then still stops the server."""
    def interrupt(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, interrupt)
    try:
        with viewer.MeshcatView() as view:
            for k in range(100):
                with pytest.raises(KeyboardInterrupt):
                    signal.setitimer(signal.ITIMER_REAL, 1e-5 * (1 + k % 20))
                    view.serve()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    assert view.process.returncode is not None


@needs_proc
def test_the_server_ends_with_a_process_that_never_closed_its_view():
    code = "import os; from mbsynth import viewer; print(viewer.MeshcatView().process.pid, flush=True); os._exit(0)"
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=HANG)
    assert child.returncode == 0, child.stderr
    pid = int(child.stdout)
    stat = proc_stat(pid)
    if stat is None:
        return  # ended and reaped already
    try:
        assert ended_within((pid, stat[19]), HANG)
    finally:
        if running(pid, stat[19]):
            os.kill(pid, signal.SIGKILL)


# -- pictures in a real browser ------------------------------------------------------

needs_chromium = pytest.mark.skipif(chromium() is None, reason="chromium is not installed: `make test` installs "
                                                               "it with apt-get when run as root")


def changed_pixels(a, b):
    """How many pixels of two same-sized PNGs differ by more than CHANGED in a channel."""
    from PIL import Image

    x = np.asarray(Image.open(a).convert("RGB"), dtype=int)
    y = np.asarray(Image.open(b).convert("RGB"), dtype=int)
    assert x.shape == y.shape == (600, 800, 3)
    return int((np.abs(x - y).max(axis=2) > CHANGED).sum())


def empty_scene_html(scene, path):
    """The same camera, grid and axes as the model's page, with no model."""
    with viewer.MeshcatView() as view:
        view.frame(scene)
        Path(path).write_text(view.html())
    return path


def simulated(path, t_end):
    system = mb.load(path)
    return system, mb.simulate(system, t_end, dt=1 / 30)


@needs_chromium
@pytest.mark.parametrize("model", ["example3", "mesh"])
def test_exported_html_draws_the_model(tmp_path, model):
    system, traj = simulated(EXAMPLE3 if model == "example3" else mesh_model(tmp_path), 1.0)
    page = viewer.to_html(system, traj, tmp_path / "model.html")
    html = page.read_text()
    assert set(url for url in _urls(html)) <= {"http://www.w3.org/1999/xhtml"}  # nothing to fetch
    empty = empty_scene_html(build_scene(system, traj), tmp_path / "empty.html")
    changed = changed_pixels(screenshot(page, tmp_path / "model.png"), screenshot(empty, tmp_path / "empty.png"))
    assert changed > 3000, changed  # of 480 000


@needs_chromium
def test_live_page_draws_the_model_and_the_server_stops(tmp_path):
    system, traj = simulated(EXAMPLE3, 1.0)
    view = viewer.show(system, traj, block=False)
    with view:
        assert urlparse(view.url).hostname == "127.0.0.1"
        shot = screenshot(view.url, tmp_path / "live.png")
    assert view.process.poll() is not None
    with pytest.raises(OSError):
        socket.create_connection((urlparse(view.url).hostname, urlparse(view.url).port), timeout=2).close()
    with viewer.MeshcatView() as empty:
        empty.frame(build_scene(system, traj))
        reference = screenshot(empty.url, tmp_path / "empty.png")
    assert changed_pixels(shot, reference) > 3000


@needs_chromium
def test_show_still_puts_the_page_on_the_axes_alone(tmp_path):
    import matplotlib.pyplot as plt

    page = tmp_path / "page.html"
    page.write_text("<html><body style='background: rgb(255, 0, 0)'></body></html>")
    fig, ax = plt.subplots()
    assert screenshot_module.show_still(ax, page, tmp_path / "page.png", budget_ms=100)
    (image,) = ax.get_images()
    pixels = image.get_array()
    assert pixels.shape[:2] == (600, 800) and np.allclose(pixels[300, 400, :3], [1, 0, 0], atol=0.02)
    assert not ax.axison and fig.subplotpars.left == 0 and fig.subplotpars.top == 1
    plt.close(fig)


def test_show_still_without_chromium_draws_nothing(tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    monkeypatch.setattr(screenshot_module, "chromium", lambda: None)
    fig, ax = plt.subplots()
    assert not screenshot_module.show_still(ax, tmp_path / "page.html", tmp_path / "page.png")
    assert ax.get_images() == [] and ax.axison and not (tmp_path / "page.png").exists()
    plt.close(fig)


def test_cli_writes_the_html_animation(tmp_path, capsys):
    out = tmp_path / "ex3.html"
    assert main(["view", str(EXAMPLE3), "--t-end", "0.3", "--html", str(out), "--axes", "--joints"]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    assert "new MeshCat.Viewer" in out.read_text()


def _urls(text):
    return re.findall(r"https?://[^\s\"'()<>]+", text)
