"""A flexible body drawn deformed: without geometry of its own, a polyline through its FE
nodes, node j at R + A (x_j + s Φ_j η) — written here from the reduction's basis and the
rows' coordinates (the quaternion turned into a matrix by scipy), the node frames' elastic
turn by the Cayley map — with s the deformation scale, which scales the node frames'
drawing too and nothing else; and the same through ``mbsynth view --deformation-scale``."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.view.scene import build_scene
from tests.helpers.scenes import animation_clips, node, segment_ends, trajectory_of

ELEMENTS = 10
STRIP = f"""
name: strip_alone
parts:
  strip:
    type: flexible_body
    beam: {{length: 2.0, elements: {ELEMENTS}, area: 1e-4, Iy: 4e-9, Iz: 1e-9, J: 5e-9, E: 2.1e11, nu: 0.3,
           density: 7850}}
    reduction: {{method: craig_bampton, interface: [0, {ELEMENTS}], modes: 2}}
    frames:
      quarter: {{node: 3, geometry: {{sphere: 0.01}}}}
"""


def rows(system, count, seed=0):
    """``count`` rows of coordinates: the frame anywhere, turned anyhow, η of a few cm."""
    rng = np.random.default_rng(seed)
    q = np.zeros((count, system.n))
    q[:, :3] = rng.normal(size=(count, 3))
    q[:, 3:7] = rng.normal(size=(count, 4))
    q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1)[:, None]
    q[:, 7:] = 0.02 * rng.normal(size=(count, system.n - 7))
    return q


def node_places(part, q, scale):
    """(rows, nodes, 3) world places R + A (x_j + s Φ_j η)."""
    basis, nodes = part.reduction.basis, part.reduction.fe.nodes
    shifts = np.array([basis[part.reduction.node_rows(j)[:3]] for j in range(len(nodes))])  # nodes × 3 × r
    A = Rotation.from_quat(q[:, [4, 5, 6, 3]]).as_matrix()
    local = nodes[None] + scale * np.einsum("jcr,tr->tjc", shifts, q[:, 7:])
    return q[:, None, :3] + np.einsum("tab,tjb->tja", A, local)


def cayley(theta):
    g = np.asarray(theta) / 2
    skew = np.array([[0, -g[2], g[1]], [g[2], 0, -g[0]], [-g[1], g[0], 0]])
    return ((1 - g @ g) * np.eye(3) + 2 * np.outer(g, g) + 2 * skew) / (1 + g @ g)


@pytest.mark.parametrize("scale", [1.0, 30.0])
def test_a_flexible_body_is_a_polyline_through_its_deformed_nodes(scale):
    """Segments j–j+1 run from node j's place to node j+1's, at true scale and scaled; the
    frame at node 3 sits at node 3's (scaled) place, turned by A · Cayley(s θ_3)."""
    system = mb.loads(STRIP)
    part = system.parts[0]
    q = rows(system, 3)
    scene = build_scene(system, trajectory_of(system, q), deformation_scale=scale)
    places = node_places(part, q, scale)
    assert sorted(n.path for n in scene.nodes if n.path.startswith("mesh/")) == \
        sorted(f"mesh/strip.{j}" for j in range(ELEMENTS))
    for j in range(ELEMENTS):
        for T, place in zip(node(scene, f"mesh/strip.{j}").transforms, places):
            start, end = segment_ends(T)
            np.testing.assert_allclose(start, place[j], atol=1e-12)
            np.testing.assert_allclose(end, place[j + 1], atol=1e-12)
    turns = part.reduction.basis[part.reduction.node_rows(3)[3:]]
    for T, place, row in zip(node(scene, "strip.quarter").transforms, places, q):
        np.testing.assert_allclose(T[:3, 3], place[3], atol=1e-12)
        A = Rotation.from_quat(row[[4, 5, 6, 3]]).as_matrix()
        np.testing.assert_allclose(T[:3, :3], A @ cayley(scale * turns @ row[7:]), atol=1e-12)


def test_the_scale_leaves_the_undeformed_body_alone():
    """At η = 0 every scale draws the same: the nodes where the frame puts them."""
    system = mb.loads(STRIP)
    q = rows(system, 2)
    q[:, 7:] = 0.0
    drawn = [np.array([n.transforms for n in build_scene(system, trajectory_of(system, q), deformation_scale=s).nodes
                       if n.path.startswith("mesh/")]) for s in (1.0, 50.0)]
    np.testing.assert_allclose(drawn[0], drawn[1], atol=1e-14)


def test_view_draws_the_scaled_deformation(tmp_path, capsys):
    """`mbsynth view --deformation-scale 20 --html` animates the mesh's segments from the run's
    scaled node places; a scale that is not positive is refused (exit 2)."""
    model = tmp_path / "strip.yaml"
    model.write_text(STRIP + "    initial: {amplitude_rates: [0, 0, 0, 0, 0, 0, 0.1, 0]}\n")
    run = tmp_path / "run.npz"
    assert main(["simulate", str(model), "--t-end", "0.1", "--dt", "0.05", "--out", str(run)]) == 0
    page = tmp_path / "strip.html"
    assert main(["view", str(model), "--trajectory", str(run), "--html", str(page), "--deformation-scale", "20"]) == 0
    system, traj = mb.load(model), mb.load_trajectory(run)
    places = node_places(system.parts[0], traj.q, 20.0)
    assert np.abs(places - node_places(system.parts[0], traj.q, 1.0)).max() > 1e-3  # the scale shows
    clips = animation_clips(page.read_text())
    for j in (0, ELEMENTS // 2, ELEMENTS - 1):
        np.testing.assert_allclose(clips[f"/meshcat/model/mesh/strip.{j}"]["position"][1], places[:, j], atol=1e-6)
    capsys.readouterr()
    assert main(["view", str(model), "--trajectory", str(run), "--html", str(page), "--deformation-scale", "0"]) == 2
    assert "--deformation-scale must be a positive number" in capsys.readouterr().err
