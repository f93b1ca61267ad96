"""Seeing the motion in meshcat: a live viewer and self-contained HTML animations.

    mb.viewer.to_html(system, trajectory, "run.html")   # plays offline in any browser
    mb.viewer.show(system, trajectory, ready=print)      # serves it live until interrupted

What is drawn and where comes from ``viewer_scene.build_scene``; this module turns it
into meshcat objects and one animation (key times in seconds of the motion). The static
export is meshcat's own (``static_html``: three.js inlined, the scene and animation
embedded), so the file needs no network.

meshcat 0.3.2 quirks, handled here: importing it warns that zmq's ``eventloop.ioloop`` is
deprecated (that warning alone is silenced); ``Visualizer.close()`` raises (its window has
no ``close``), so ``MeshcatView.close`` closes the socket and stops the server process
itself; the server that ``Visualizer()`` starts outlives a killed parent, so
``MeshcatView`` starts meshcat's server itself, with a thread that ends it when its stdin
closes; it has no camera helpers (``set_cam_pos``/``set_cam_target``, which Pinocchio's
viewer calls), so the camera is placed through the position property of
``/Cameras/default/rotated/<object>`` and the world is moved under it instead: the model,
the world axes and the grid are placed so that the scene's target (``Scene.targets``: the
middle of the whole motion, or the centre of mass when the view follows the model) sits
at the origin the camera looks at. Following, they move along the animation; the grid
moves by whole cells, so its lines stay where they are on the floor.
"""

import contextlib
import select
import signal
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np

from ..core.files import write_atomically
from ..core.kinematics import matrix_quaternion
from .scene import FPS, build_scene
from ..core.tolerances import GRID_SPACING_RTOL, VIEW_TIE_BREAK

FIELD_OF_VIEW = np.radians(75.0)  # meshcat's default camera
CAMERA = "/Cameras/default/rotated/<object>"
GRID_SPACING = 0.5  # meshcat's grid: 20 m wide, 40 divisions
AXES_LENGTH = 0.5  # meshcat's world axes
STOP_SECONDS = 5.0


def to_html(system, trajectory, path, *, axes=False, joints=False, fps=FPS, follow=None, deformation_scale=1.0):
    """Write the animation of ``trajectory`` as one self-contained HTML file, whole or not
    at all (core.files.write_atomically); returns its Path.

    follow: the camera follows the centre of mass (True), stays on the box that holds the
    whole motion (False), or (None) follows when the centre of mass travels further than
    the model's length (``scene.build_scene``); deformation_scale: flexible bodies' elastic
    displacements drawn times this (the drawing only)."""
    scene = build_scene(system, trajectory, axes=axes, joints=joints, fps=fps, follow=follow,
                        deformation_scale=deformation_scale)
    with MeshcatView() as view:
        view.draw(scene)
        html = view.html()
    path = Path(path)
    write_atomically(path, lambda temporary: temporary.write_text(html, encoding="utf-8"))
    return path


def show(system, trajectory, *, axes=False, joints=False, fps=FPS, follow=None, block=True, ready=None,
         deformation_scale=1.0):
    """Serve the animation of ``trajectory`` in a live meshcat viewer on this machine
    (``follow`` and ``deformation_scale`` as in ``to_html``).

    block=True serves until interrupted (Ctrl-C or SIGTERM), calling ``ready(url)`` once
    the scene is up, then stops the server and raises KeyboardInterrupt (the command
    exits 130). block=False returns the running ``MeshcatView`` (``.url``; ``close()`` it,
    or use it in a ``with`` block). The server also ends when this process dies.
    """
    scene = build_scene(system, trajectory, axes=axes, joints=joints, fps=fps, follow=follow,
                        deformation_scale=deformation_scale)
    if not block:
        view = MeshcatView()
        try:
            view.draw(scene)
        except BaseException:
            view.close()
            raise
        return view
    with _sigterm_interrupts(), MeshcatView() as view:
        view.draw(scene)
        if ready is not None:
            ready(view.url)
        view.serve()
    return None


@contextlib.contextmanager
def _sigterm_interrupts():
    """Make SIGTERM a KeyboardInterrupt meanwhile: it stops the viewer as Ctrl-C does."""
    def interrupt(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def import_meshcat():
    """meshcat and its geometry and animation modules, without zmq's deprecation warning."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"zmq\.eventloop\.ioloop is deprecated", category=DeprecationWarning)
        import meshcat
        import meshcat.animation
        import meshcat.geometry
    return meshcat


# meshcat's server, ended by a thread of its own when its stdin closes: when its MeshcatView
# closes it, or when the process holding the other end ends, even by SIGKILL.
SERVER = ("import os, sys, threading\n"
          "threading.Thread(target=lambda: (sys.stdin.buffer.read(), os._exit(0)), daemon=True).start()\n"
          "from meshcat.servers.zmqserver import main\n"
          "main()\n")


class MeshcatView:
    """A meshcat server of our own on 127.0.0.1 and the scene drawn in it (a context manager).

    The server process ends when the view closes or when this process ends.
    """

    def __init__(self):
        self.meshcat = import_meshcat()
        self.process = subprocess.Popen([sys.executable, "-u", "-c", SERVER], stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            zmq_url, self.url = _server_urls(self.process)
        except BaseException:
            self._stop()
            raise
        window = object.__new__(self.meshcat.visualizer.ViewerWindow)  # meshcat's, on our server
        window.server_proc, window.zmq_url, window.web_url = self.process, zmq_url, self.url
        window.connect_zmq()
        self.vis = self.meshcat.Visualizer(window=window)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def draw(self, scene):
        """Draw every node at its first pose, frame the camera, and play the motion."""
        g = self.meshcat.geometry
        model = self.vis["model"]
        for node in scene.nodes:
            target = model[node.path]
            for i, shape in enumerate(node.shapes):
                for j, (geometry, inner) in enumerate(_pieces(shape, g)):
                    target[f"{i}.{j}"].set_object(geometry, _material(shape["color"], g))
                    target[f"{i}.{j}"].set_transform(inner)
            if node.axes:
                target["axes"].set_object(g.triad(0.04 * scene.length))
            target.set_transform(node.transforms[0])
        self.frame(scene)
        if len(scene.times) > 1:
            self.vis.set_animation(self._animation(scene), play=True, repetitions=float("inf"))

    def frame(self, scene):
        """Point the camera at the view box about the first target; keep the world axes (as
        long as a grid cell) at the world origin and the grid on the floor (z = 0, or lower
        when the motion goes lower), its cells 1, 2 or 5 × 10^k, about a fifth of the view."""
        spacing = grid_spacing(scene.size)
        tracks = world_tracks(scene)
        self.vis["model"].set_transform(_translation(tracks["model"][1][0]))
        self.vis["/Axes"].set_transform(_pose(tracks["/Axes"][1][0], scale=[spacing / AXES_LENGTH] * 3))
        self.vis["/Grid"].set_transform(_pose(tracks["/Grid"][1][0], scale=[spacing / GRID_SPACING] * 3))
        eye = view_direction(scene.view_upper - scene.view_lower) * 1.2 * scene.size / 2 / np.tan(FIELD_OF_VIEW / 2)
        self.vis[CAMERA].set_property("position", [eye[0], eye[2], -eye[1]])  # the camera's frame is y-up

    def html(self):
        """The scene as one self-contained HTML page (meshcat's static export)."""
        return self.vis.static_html()

    def serve(self):
        """Wait until the server ends (its output closes) or a signal handler raises.

        Not Popen.poll/wait, which a signal can interrupt while they hold its lock; a
        select with a timeout, as a signal can reach another thread and not wake this one."""
        out = self.process.stdout
        while not select.select([out], [], [], 0.5)[0] or out.read1():
            pass

    def close(self):
        """Close our socket and stop the server process (meshcat's own close() raises)."""
        self.vis.window.zmq_socket.close(linger=0)
        self._stop()

    def _stop(self):
        self.process.stdin.close()  # the server's cue to exit
        try:
            self.process.wait(STOP_SECONDS)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self.process.stdout.close()

    def _animation(self, scene):
        """One clip per node: position, quaternion (and scale for lines) at each drawn time;
        following, one per moved world object (``world_tracks``): its position."""
        animation = self.meshcat.animation
        clips = {}
        if scene.follow:
            for path, (keys, positions) in world_tracks(scene).items():
                track = animation.AnimationTrack("position", "vector3", list(keys), positions.tolist())
                clips[self.vis[path].path] = animation.AnimationClip({"position": track}, fps=1)
        times = list(scene.times - scene.times[0])
        for node in scene.nodes:
            position, quaternion, scale = decompose(node.transforms)
            tracks = {"position": animation.AnimationTrack("position", "vector3", times, position.tolist()),
                      "quaternion": animation.AnimationTrack("quaternion", "quaternion", times, quaternion.tolist())}
            if not np.allclose(scale, 1.0):
                tracks["scale"] = animation.AnimationTrack("scale", "vector3", times, scale.tolist())
            clips[self.vis["model"][node.path].path] = animation.AnimationClip(tracks, fps=1)  # times in s
        return animation.Animation(clips)


def _server_urls(process):
    """(zmq URL, web URL) that a starting meshcat server prints; RuntimeError if it exits first."""
    urls, said = {}, []
    for line in process.stdout:
        key, _, value = line.decode(errors="replace").strip().partition("=")
        if key in ("zmq_url", "web_url"):
            urls[key] = value
        else:
            said.append(line.decode(errors="replace").strip())
        if len(urls) == 2:
            return urls["zmq_url"], urls["web_url"]
    raise RuntimeError(f"the meshcat server exited before serving: {' | '.join(said[-3:]) or 'no output'}")


def decompose(transforms):
    """(positions, quaternions as three.js [x, y, z, w] without sign jumps, scales) of
    rows × 4 × 4 transforms whose 3 × 3 block is a rotation times a positive diagonal scale."""
    scale = np.linalg.norm(transforms[:, :3, :3], axis=1)
    quaternions = np.array([matrix_quaternion(T[:3, :3] / s) for T, s in zip(transforms, scale)])
    for k in range(1, len(quaternions)):
        if quaternions[k] @ quaternions[k - 1] < 0:
            quaternions[k] = -quaternions[k]
    return transforms[:, :3, 3], quaternions[:, [1, 2, 3, 0]], scale


GRID_JUMP = 1e-3  # a grid's jump by whole cells takes this fraction of the interval between two drawn times


def world_tracks(scene):
    """{meshcat path: (key times, positions)} of what is moved so that the scene's target
    sits at the origin: ``model`` and ``/Axes`` at −target; ``/Grid`` on the floor at the
    target's x, y rounded to whole cells, minus the target. A jump of the rounded x, y
    between two drawn times is keyed just before the later one, so the grid's lines stay
    put. Times are seconds from the first drawn time."""
    times = scene.times - scene.times[0]
    targets = scene.targets
    spacing = grid_spacing(scene.size)
    floor = min(0.0, scene.lower[2])
    cells = np.column_stack([np.round(targets[:, :2] / spacing) * spacing, np.full(len(times), floor)])
    keys, grid = [], []
    for k in range(len(times)):
        if k > 0 and np.any(cells[k] != cells[k - 1]):
            before = times[k] - GRID_JUMP * (times[k] - times[k - 1])
            target = targets[k] - GRID_JUMP * (targets[k] - targets[k - 1])
            keys.append(before)
            grid.append(cells[k - 1] - target)
        keys.append(times[k])
        grid.append(cells[k] - targets[k])
    return {"model": (times, -targets), "/Axes": (times, -targets), "/Grid": (np.array(keys), np.array(grid))}


def grid_spacing(size):
    """The largest of 1, 2, 5 × 10^k not above size / 5."""
    decade = 10.0 ** np.floor(np.log10(size / 5))
    return max(step * decade for step in (1, 2, 5) if step * decade <= size / 5 * (1 + GRID_SPACING_RTOL))


def view_direction(extent):
    """A unit vector from the model toward the camera: across its thinnest side, from
    slightly above and to the right (meshcat keeps z up)."""
    thin = int(np.argmin(extent + np.array([0.0, -VIEW_TIE_BREAK, VIEW_TIE_BREAK])))  # ties: look along y, then x
    direction = {0: [1.0, -0.35, 0.45], 1: [0.35, -1.0, 0.45], 2: [0.25, -0.5, 1.0]}[thin]
    return np.array(direction) / np.linalg.norm(direction)


def _translation(offset):
    T = np.eye(4)
    T[:3, 3] = offset
    return T


def _pose(position=(0, 0, 0), rotation=np.eye(3), scale=(1, 1, 1)):
    T = np.eye(4)
    T[:3, :3] = np.asarray(rotation, dtype=float) @ np.diag(scale)
    T[:3, 3] = position
    return T


ARROW_HEAD = 0.2  # an arrow's head, of its length
ARROW_WIDTH = 2.5  # an arrow's head, of its shaft's radius
ROTATE_Y_TO_Z = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # three.js cylinders lie along y
ROTATE_Y_TO_X = np.array([[0.0, 1, 0], [-1, 0, 0], [0, 0, 1]])


def _pieces(shape, g):
    """[(meshcat geometry, 4 × 4 transform in the node)] of one shape."""
    kind = shape["shape"]
    if kind == "line":  # a thin cylinder over the unit segment (0, 0, 0)-(1, 0, 0), scaled by its node
        return [(g.Cylinder(1.0, shape["size"][0]), _pose([0.5, 0, 0], ROTATE_Y_TO_X))]
    if kind == "arrow":  # a line whose last ARROW_HEAD is a cone ARROW_WIDTH times as wide, pointing to (1, 0, 0)
        r, shaft = shape["size"][0], 1.0 - ARROW_HEAD
        return [(g.Cylinder(shaft, r), _pose([shaft / 2, 0, 0], ROTATE_Y_TO_X)),
                (g.Cylinder(ARROW_HEAD, radiusTop=0.0, radiusBottom=ARROW_WIDTH * r),
                 _pose([shaft + ARROW_HEAD / 2, 0, 0], ROTATE_Y_TO_X))]
    origin = _pose(shape.get("position", (0, 0, 0)), shape.get("rotation", np.eye(3)))
    size = shape.get("size")
    if kind == "box":
        return [(g.Box(size), origin)]
    if kind == "sphere":
        return [(g.Sphere(size[0]), origin)]
    if kind == "cylinder":
        return [(g.Cylinder(size[1], size[0]), origin @ _pose(rotation=ROTATE_Y_TO_Z))]
    if kind == "capsule":
        r, length = size
        return [(g.Cylinder(length, r), origin @ _pose(rotation=ROTATE_Y_TO_Z)),
                (g.Sphere(r), origin @ _translation([0, 0, length / 2])),
                (g.Sphere(r), origin @ _translation([0, 0, -length / 2]))]
    if kind == "mesh":
        readers = {".stl": g.StlMeshGeometry, ".obj": g.ObjMeshGeometry, ".dae": g.DaeMeshGeometry}
        geometry = readers[Path(shape["file"]).suffix.lower()].from_file(shape["file"])
        return [(geometry, origin @ _pose(scale=shape["scale"]))]
    raise ValueError(f"unknown shape {kind!r}")


def _material(color, g):
    r, gr, b, a = (list(color) + [1.0])[:4]
    hex_color = (int(round(255 * r)) << 16) | (int(round(255 * gr)) << 8) | int(round(255 * b))
    return g.MeshLambertMaterial(color=hex_color, opacity=float(a))
