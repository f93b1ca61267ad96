"""A model without geometry drawn as its structure, and a camera that follows it.

The expected poses are written out here from the model's numbers and the rows of
coordinates (quaternions turned into matrices by scipy), not read from the scene: wheels
of the contacts' radii about the hub frames' z axes, rods from each centre of mass to the
body's frames, particles sized by the cube root of their mass, and camera targets at the
mass-weighted centre of mass. The saved HTML is decoded (meshcat's msgpack commands) to
check that its animation moves the world by minus that centre.
"""

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.view import viewer
from mbsynth.view.scene import build_scene
from tests.helpers.scenes import animation_clips, node, segment_ends, trajectory_of

ROOT = Path(__file__).resolve().parents[2]
DISK = ROOT / "models" / "rolling" / "rolling_disk.yaml"

# A bicycle-like model without geometry: rear wheel, frame, fork, front wheel; revolute
# hubs and steer; both wheels rolling (hub frames' z along the axle, body y).
TWO_WHEELER = """
name: two_wheeler
parameters: {rR: 0.3, rF: 0.35}
gravity: [0, 0, -9.81]
parts:
  rear_wheel:
    type: rigid_body
    mass: 2
    inertia: [0.06, 0.12, 0.06]
    frames:
      hub: {axis: [0, 1, 0]}
    initial: {position: [0, 0, rR]}
  frame:
    type: rigid_body
    mass: 85
    inertia: [9.2, 11, 2.8]
    frames:
      rear_hub: {position: [-0.3, 0, rR - 0.9], axis: [0, 1, 0]}
      steer: {position: [0.7, 0, -0.1], axis: [-0.3, 0, 1]}
    initial: {position: [0.3, 0, 0.9]}
  fork:
    type: rigid_body
    mass: 4
    inertia: [0.06, 0.06, 0.007]
    frames:
      steer: {position: [0.1, 0, 0.1], axis: [-0.3, 0, 1]}
      front_hub: {position: [0.1, 0, rF - 0.7], axis: [0, 1, 0]}
    initial: {position: [0.9, 0, 0.7]}
  front_wheel:
    type: rigid_body
    mass: 3
    inertia: [0.14, 0.28, 0.14]
    frames:
      hub: {axis: [0, 1, 0]}
    initial: {position: [1.0, 0, rF]}
joints:
  - {name: rear_hub, type: revolute, parent: frame.rear_hub, child: rear_wheel.hub}
  - {name: steer, type: revolute, parent: frame.steer, child: fork.steer}
  - {name: front_hub, type: revolute, parent: fork.front_hub, child: front_wheel.hub}
  - {name: rear_contact, type: rolling_disk, child: rear_wheel.hub, radius: rR}
  - {name: front_contact, type: rolling_disk, child: front_wheel.hub, radius: rF}
"""
MASSES = {"rear_wheel": 2.0, "frame": 85.0, "fork": 4.0, "front_wheel": 3.0}
RODS = {("frame", "rear_hub"): [-0.3, 0, 0.3 - 0.9], ("frame", "steer"): [0.7, 0, -0.1],
        ("fork", "steer"): [0.1, 0, 0.1], ("fork", "front_hub"): [0.1, 0, 0.35 - 0.7]}
WHEELS = {"rear_contact": ("rear_wheel", 0.3), "front_contact": ("front_wheel", 0.35)}


def matrix(u):
    """The rotation of a quaternion (w, x, y, z) of any norm."""
    return Rotation.from_quat([u[1], u[2], u[3], u[0]]).as_matrix()


def moved_rows(system, count, step):
    """``count`` rows: each body at its initial position shifted by k·``step`` and turned
    by its own random quaternion (of norm 2 at odd rows); returns (rows, {body: (r, u)})."""
    q0, _ = system.initial_state()
    index = {c: i for i, c in enumerate(system.coordinates)}
    rng = np.random.default_rng(7)
    rows, poses = [], []
    for k in range(count):
        q, pose = q0.copy(), {}
        for body in MASSES:
            r = q0[[index[f"{body}.{a}"] for a in "xyz"]] + k * np.asarray(step)
            u = rng.normal(size=4)
            u *= (2 if k % 2 else 1) / np.linalg.norm(u)
            q[[index[f"{body}.{c}"] for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]] = [*r, *u]
            pose[body] = (r, u)
        rows.append(q)
        poses.append(pose)
    return np.array(rows), poses


def centre_of_mass(pose):
    return sum(MASSES[b] * pose[b][0] for b in MASSES) / sum(MASSES.values())


def test_two_wheeler_is_drawn_as_wheels_rods_and_centres_of_mass():
    system = mb.loads(TWO_WHEELER)
    rows, poses = moved_rows(system, 3, [0.0, 0.0, 0.0])
    scene = build_scene(system, trajectory_of(system, rows))
    kinds = {n.path: [s["shape"] for s in n.shapes] for n in scene.nodes}
    expected = {**{body: ["sphere"] for body in MASSES}, **{f"wheels/{c}": ["cylinder", "box"] for c in WHEELS},
                **{f"structure/{part}.{frame}": ["line"] for part, frame in RODS}}
    assert kinds == expected  # no default cubes; the hubs sit at the wheels' centres: no rods there
    for contact, (body, radius) in WHEELS.items():
        wheel = node(scene, f"wheels/{contact}")
        assert wheel.shapes[0]["size"][0] == pytest.approx(radius, rel=1e-12)
        assert wheel.shapes[0]["size"][1] < 0.2 * radius  # a thin disk
        for T, pose in zip(wheel.transforms, poses):
            r, u = pose[body]
            np.testing.assert_allclose(T[:3, 3], r, atol=1e-12)
            np.testing.assert_allclose(T[:3, 2], matrix(u) @ [0, 1, 0], atol=1e-12)  # the disk's axis: the axle
    for (part, frame), offset in RODS.items():
        for T, pose in zip(node(scene, f"structure/{part}.{frame}").transforms, poses):
            r, u = pose[part]
            start, end = segment_ends(T)
            np.testing.assert_allclose(start, r, atol=1e-12)
            np.testing.assert_allclose(end, r + matrix(u) @ offset, atol=1e-12)
    # the model's length is its own extent at one time (about 1.7 m wide with its wheels)
    assert 1.0 < scene.length < 2.5
    assert node(scene, "frame").shapes[0]["size"][0] < 0.05 * scene.length


def test_camera_follows_the_centre_of_mass_of_a_travelling_model():
    system = mb.loads(TWO_WHEELER)
    rows, poses = moved_rows(system, 12, [0.8, 0.1, 0.0])  # 8.8 m along x: far more than its length
    traj = trajectory_of(system, rows)
    expected = np.array([centre_of_mass(pose) for pose in poses])
    scene = build_scene(system, traj)
    assert scene.follow
    np.testing.assert_allclose(scene.targets, expected, atol=1e-12)
    tracks = viewer.world_tracks(scene)
    np.testing.assert_allclose(tracks["model"][1], -expected, atol=1e-12)
    np.testing.assert_allclose(tracks["model"][0], traj.t - traj.t[0])
    assert scene.size < 3 * scene.length  # the view holds the model, not its whole path
    still = build_scene(system, traj, follow=False)
    assert not still.follow
    np.testing.assert_allclose(still.targets, np.tile((still.lower + still.upper) / 2, (12, 1)), atol=1e-12)
    assert still.size > 8.0
    at_rest = build_scene(system, trajectory_of(system, moved_rows(system, 12, [0.0, 0.0, 0.0])[0]))
    assert not at_rest.follow  # it turns in place: its centre of mass stays


def test_grid_moves_by_whole_cells_under_a_followed_model():
    system = mb.loads(TWO_WHEELER)
    rows, poses = moved_rows(system, 12, [0.8, 0.1, 0.0])
    scene = build_scene(system, trajectory_of(system, rows))
    keys, grid = viewer.world_tracks(scene)["/Grid"]
    spacing = viewer.grid_spacing(scene.size)
    times = scene.times - scene.times[0]
    world = grid + np.array([np.interp(keys, times, scene.targets[:, i]) for i in range(3)]).T
    np.testing.assert_allclose(world[:, 2], min(0.0, scene.lower[2]), atol=1e-12)  # on the floor, or below the model
    cells = world[:, :2] / spacing
    np.testing.assert_allclose(cells, np.round(cells), atol=1e-9)  # lines where the floor's are
    assert len(keys) > len(times)  # it jumped, each jump keyed just before its drawn time


def test_particles_grow_with_the_cube_root_of_their_mass():
    system = mb.loads("""
name: beads
parts:
  light: {type: particle, mass: 1, initial: {position: [0, 0, 0]}}
  heavy: {type: particle, mass: 8, initial: {position: [1, 0, 0]}}
  ghost: {type: particle, mass: 0, initial: {position: [0, 1, 0]}}
""")
    scene = build_scene(system, trajectory_of(system, system.initial_state()[0]))
    radius = {name: node(scene, name).shapes[0]["size"][0] for name in ("light", "heavy", "ghost")}
    assert radius["heavy"] == pytest.approx(2 * radius["light"], rel=1e-12)  # (8 / 1)^(1/3)
    assert 0 < radius["ghost"] < radius["light"]
    assert scene.length == pytest.approx(np.sqrt(2), rel=1e-12)  # the beads' spread
    assert not scene.follow  # a single row: nothing travels
    followed = build_scene(system, trajectory_of(system, system.initial_state()[0]), follow=True)
    np.testing.assert_allclose(followed.targets[0], [8 / 9, 0, 0], atol=1e-12)  # (0 + 8·1 + 0) / 9


def test_sizes_follow_the_models_own_length():
    small = mb.loads(TWO_WHEELER)
    big = mb.loads(TWO_WHEELER.replace("{rR: 0.3, rF: 0.35}", "{rR: 300, rF: 350}").replace(
        "-0.3, 0, rR - 0.9", "-300, 0, rR - 900").replace("0.7, 0, -0.1", "700, 0, -100").replace(
        "0.1, 0, 0.1", "100, 0, 100").replace("0.1, 0, rF - 0.7", "100, 0, rF - 700").replace(
        "[0.3, 0, 0.9]", "[300, 0, 900]").replace("[0.9, 0, 0.7]", "[900, 0, 700]").replace("[1.0, 0, rF]", "[1000, 0, rF]"))
    scenes = [build_scene(s, trajectory_of(s, s.initial_state()[0])) for s in (small, big)]
    assert scenes[1].length == pytest.approx(1000 * scenes[0].length, rel=1e-12)
    for path in ("frame", "structure/frame.steer", "wheels/rear_contact"):
        a, b = (node(s, path).shapes[0]["size"] for s in scenes)
        np.testing.assert_allclose(b, np.multiply(1000, a), rtol=1e-12)


def disk_rows(system, times):
    """The stripped disk's steady turning motion in closed form (the model file's comment):
    heading turning at Ω about the vertical, spin about the disk's axis; its centre on a
    circle of radius R w_axis / Ω about C. Returns (rows, centres, axes)."""
    p = system.parameters
    R, theta, Omega, w_axis = p["R"], p["theta"], p["Omega"], p["w_axis"]
    spin = w_axis - Omega * np.sin(theta)
    p0 = np.array([0, -R * np.sin(theta), R * np.cos(theta)])
    C = p0 + np.array([0, R * w_axis / Omega, 0])
    R0 = Rotation.from_euler("xyz", [theta - np.pi / 2, 0, 0])
    rows, centres, axes = [], [], []
    for t in times:
        heading = Rotation.from_rotvec([0, 0, Omega * t])
        turn = heading * R0 * Rotation.from_rotvec([0, 0, spin * t])
        x, y, z, w = turn.as_quat()
        centre = C + heading.apply(p0 - C)
        rows.append([*centre, w, x, y, z])
        centres.append(centre)
        axes.append(turn.apply([0, 0, 1]))
    return np.array(rows), np.array(centres), np.array(axes)


def stripped_disk(tmp_path):
    text = DISK.read_text()
    assert "geometry:" in text
    path = tmp_path / "disk.yaml"
    path.write_text(re.sub(r"\n\s*geometry:[^\n]*", "", text))
    return path


def test_rolling_disk_without_geometry_is_a_wheel_that_the_camera_follows(tmp_path):
    system = mb.load(stripped_disk(tmp_path))
    times = np.arange(0, 1.0 + 1e-9, 1 / 30)
    rows, centres, axes = disk_rows(system, times)
    assert np.allclose(rows[0, :3], system.initial_state()[0][:3])  # the closed form starts where the file does
    traj = trajectory_of(system, rows)
    traj.t[:] = times
    scene = build_scene(system, traj)
    wheel = node(scene, "wheels/contact")
    assert wheel.shapes[0]["shape"] == "cylinder" and wheel.shapes[0]["size"][0] == pytest.approx(0.1, rel=1e-12)
    np.testing.assert_allclose(wheel.transforms[:, :3, 3], centres, atol=1e-12)
    np.testing.assert_allclose(wheel.transforms[:, :3, 2], axes, atol=1e-12)
    assert scene.follow  # its centre travels about a metre; the disk is 0.2 m across
    np.testing.assert_allclose(scene.targets, centres, atol=1e-12)

    out, saved = tmp_path / "disk.html", tmp_path / "disk.npz"
    traj.save(saved)
    assert main(["view", str(tmp_path / "disk.yaml"), "--trajectory", str(saved), "--html", str(out)]) == 0
    model = animation_clips(out.read_text())["/meshcat/model"]
    np.testing.assert_allclose(model["position"][0], times, atol=1e-9)
    np.testing.assert_allclose(model["position"][1], -centres, atol=1e-9)
    assert main(["view", str(tmp_path / "disk.yaml"), "--trajectory", str(saved), "--html", str(out),
                 "--no-follow"]) == 0
    assert "/meshcat/model" not in animation_clips(out.read_text())
    still = trajectory_of(system, np.repeat(rows[:1], len(times), axis=0))  # standing where it starts
    still.t[:] = times
    still.save(saved)
    assert main(["view", str(tmp_path / "disk.yaml"), "--trajectory", str(saved), "--html", str(out)]) == 0
    assert "/meshcat/model" not in animation_clips(out.read_text())  # nothing travels: the camera stays
    assert main(["view", str(tmp_path / "disk.yaml"), "--trajectory", str(saved), "--html", str(out),
                 "--follow"]) == 0
    np.testing.assert_allclose(animation_clips(out.read_text())["/meshcat/model"]["position"][1],
                               -np.repeat(centres[:1], len(times), axis=0), atol=1e-9)


def test_declared_geometry_wins():
    system = mb.load(DISK)  # its disk declares a cylinder
    scene = build_scene(system, trajectory_of(system, system.initial_state()[0]))
    assert [(n.path, [s["shape"] for s in n.shapes]) for n in scene.nodes] == [("disk", ["cylinder"])]
    assert node(scene, "disk").shapes[0]["size"] == pytest.approx([0.1, 0.01], rel=1e-12)  # [R, R/10]
    drawn = mb.loads(TWO_WHEELER.replace("      hub: {axis: [0, 1, 0]}\n    initial: {position: [0, 0, rR]}",
                                         "      hub: {axis: [0, 1, 0], geometry: {cylinder: [rR, 0.02]}}\n"
                                         "    initial: {position: [0, 0, rR]}"))
    scene = build_scene(drawn, trajectory_of(drawn, drawn.initial_state()[0]))
    assert [n.path for n in scene.nodes if n.shapes] == ["rear_wheel.hub"]  # the other bodies: only their axes
    assert all(n.axes for n in scene.nodes if n.path in MASSES and n.path != "rear_wheel")


def test_live_view_follows_too(tmp_path):
    system = mb.load(stripped_disk(tmp_path))
    times = np.arange(0, 0.5 + 1e-9, 1 / 30)
    rows, centres, _ = disk_rows(system, times)
    traj = trajectory_of(system, rows)
    traj.t[:] = times
    with viewer.show(system, traj, block=False, follow=True) as view:
        model = animation_clips(view.html())["/meshcat/model"]
    np.testing.assert_allclose(model["position"][1], -centres, atol=1e-9)
