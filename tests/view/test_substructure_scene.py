"""The viewer on a model made of model files: each top-level substructure drawn under a
meshcat path of its own, its parts in one colour of the palette, each copy in the next.

The N-four-bar (tests/helpers/n_four_bar_files.py) declares no geometry, so it is drawn as its
structure: rods from each body's centre of mass to its frames, in the part's colour."""

import base64
import re

import umsgpack

import mbsynth as mb
from mbsynth.io.parts import COLORS
from mbsynth.view import viewer
from mbsynth.view.scene import PALETTE, build_scene
from tests.helpers.n_four_bar_files import write_n_four_bar
from tests.helpers.scenes import trajectory_of

N = 3


def rods(scene):
    """{path: colour} of the rods (the nodes whose path has a 'structure' folder)."""
    return {node.path: node.shapes[0]["color"] for node in scene.nodes if "structure/" in node.path}


def test_each_copy_is_a_group_of_its_own_colour(tmp_path):
    system = mb.load(write_n_four_bar(tmp_path), parameters={"N": N})
    scene = build_scene(system, trajectory_of(system, system.initial_state()[0]))
    drawn = rods(scene)
    # a cell's two bodies: v with frames bottom and top, h with left and right; the model's own v
    expected = {f"cell[{k}]/structure/cell[{k}].{body}.{frame}": k
                for k in range(N) for body, frames in (("v", ("bottom", "top")), ("h", ("left", "right")))
                for frame in frames}
    expected.update({"structure/v.bottom": N, "structure/v.top": N})
    assert set(drawn) == set(expected)
    for path, turn in expected.items():
        assert drawn[path] == [*COLORS[PALETTE[turn]], 1.0], path
    colours = {tuple(drawn[f"cell[{k}]/structure/cell[{k}].v.top"]) for k in range(N)}
    assert len(colours | {tuple(drawn["structure/v.top"])}) == N + 1
    groups = {node.path.split("/")[0] for node in scene.nodes if node.path.startswith("cell[")}
    assert groups == {f"cell[{k}]" for k in range(N)}
    # every node of a cell's parts sits under that cell, the model's own outside every cell
    for node in scene.nodes:
        name = node.path.rpartition("/")[2]
        if name.startswith("cell["):
            assert node.path.startswith(name.partition(".")[0] + "/"), node.path
        else:
            assert not node.path.startswith("cell["), node.path


def test_the_html_export_nests_each_copy_under_its_path(tmp_path):
    """The meshcat commands saved in the HTML (msgpack, base64) set each cell's objects under
    /meshcat/model/cell[k]/."""
    system = mb.load(write_n_four_bar(tmp_path), parameters={"N": N})
    html = viewer.to_html(system, trajectory_of(system, system.initial_state()[0]), tmp_path / "run.html").read_text()
    paths = {command.get("path") for command in
             (umsgpack.unpackb(base64.b64decode(blob))
              for blob in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html))}
    for k in range(N):
        assert f"/meshcat/model/cell[{k}]/structure/cell[{k}].h.right" in paths
    assert "/meshcat/model/structure/v.top" in paths
