"""Every registered part type works end to end: each model-file ``type:`` (io/part_types.py
FILE_TYPES) is read from a model file, drawn, linearized and compiled, and together they build
every part type (model/parts PART_TYPES). A type registered without an example here fails."""

import textwrap

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.analysis.trajectory import Trajectory
from mbsynth.compiled.layout import EXTRA_NODE, build as build_layout, sources
from mbsynth.io.part_types import FILE_TYPES
from mbsynth.model.parts import PART_TYPES
from mbsynth.model.parts.part_type import PartType, check
from mbsynth.view.scene import build_scene

# per file type, model files made of one entry of it (``{entry}``) and what holds it
EXAMPLES = {
    "lagrangian": ["""
        parts:
          p: {type: lagrangian, coordinates: [x], T: 0.5*x_dot**2, V: 2*x**2, frames: {bob: {position: [x, 0, 0]}}}
        initial: {p.x: 0.1}
        """],
    "rigid_body": [f"""
        gravity: [0, 0, -9.81]
        parts:
          b: {{type: rigid_body, mass: 1.2, inertia: [0.1, 0.2, 0.3], {rotation}frames: {{top: {{position: [0, 0, 0.5]}}}},
              initial: {{position: [0, 0, -0.5]}}}}
        joints:
          - {{name: pin, type: revolute, parent: world, child: b.top}}
        """ for rotation in ("", "rotation: zxy, ")],
    "particle": ["""
        gravity: [0, 0, -9.81]
        parts:
          p: {type: particle, mass: 1.0, initial: {position: [0.6, 0, -0.8]}}
        joints:
          - {name: rod, type: distance, parent: world, child: p, length: 1.0}
        """],
    "planar_body": ["""
        gravity: [0, -9.81, 0]
        parts:
          p: {type: planar_body, mass: 1.0, inertia: 0.1, frames: {tip: {position: [0.5, 0, 0]}}}
        """],
    "spring": ["""
        parts:
          s: {type: spring, stiffness: 10, rest_length: 0.5, mass: 0.3, initial: {end2: [0.6, 0, 0]}}
        """],
    "robot": ["""
        gravity: [0, 0, -9.81]
        parts:
          arm: {type: robot, robot: double_pendulum, initial: {}}
        """],
    "solid": ["""
        gravity: [0, 0, -9.81]
        parts:
          s: {type: solid, shape: {capsule: [0.05, 0.4]}, density: 1000, frames: {top: {position: [0, 0, 0.25]}},
              initial: {position: [0, 0, -0.25]}}
        joints:
          - {name: pin, type: spherical, parent: world, child: s.top}
        """],
    "flexible_body": ["""
        gravity: [0, 0, -9.81]
        parts:
          strip:
            type: flexible_body
            beam: {length: 1.0, elements: 4, area: 1e-4, Iy: 4e-9, Iz: 1e-9, J: 5e-9, E: 2.1e11, nu: 0.3, density: 7850}
            reduction: {method: craig_bampton, interface: [0], modes: 2}
        joints:
          - {name: clamp, type: fixed, parent: world, child: strip.node_0}
        """],
}


def test_every_file_type_has_an_example_and_every_part_type_is_built():
    assert set(EXAMPLES) == set(FILE_TYPES)
    built = {t.name for file_type in FILE_TYPES.values() for t in file_type.builds}
    assert built == set(PART_TYPES)


def test_a_record_that_leaves_a_question_open_fails_at_import():
    """A part type must answer every field, with a value the floors know: no default."""
    rigid = PART_TYPES["rigid_body"]
    with pytest.raises(TypeError, match="drawing"):
        PartType(*rigid[:-1])
    with pytest.raises(ValueError, match="node 'kernel'"):
        check(rigid._replace(node="kernel"))
    with pytest.raises(ValueError, match="quaternion slice"):
        check(rigid._replace(quaternion=None))


CASES = [(name, i, text) for name, texts in EXAMPLES.items() for i, text in enumerate(texts)]


@pytest.mark.parametrize("name, i, text", CASES, ids=[f"{name}-{i}" for name, i, _ in CASES])
def test_each_type_is_read_drawn_linearized_and_compiled(name, i, text):
    system = mb.loads(textwrap.dedent(text), name=f"{name}.yaml")
    assert {p.type_name for p in system.parts} <= {t.name for t in FILE_TYPES[name].builds}
    q, qd = system.initial_state()
    # drawn: every part has a node at its own pose or its frames (a spring: its line)
    rows = np.array([q, q + 0.01])
    trajectory = Trajectory(system.coordinates, np.arange(2.0), rows, np.zeros_like(rows), *np.zeros((4, 2)))
    scene = build_scene(system, trajectory)
    drawn = {n.path.rpartition("/")[2].split(".")[0] for n in scene.nodes}
    assert {p.name.split(".")[0] for p in system.parts} <= drawn
    # linearized: a finite first-order system of the model's size
    lin = mb.linearize(system, 0.0, q, qd)
    assert np.all(np.isfinite(lin.A)) and lin.A.shape[0] == lin.A.shape[1] > 0
    # compiled: the kernels take the model, each part where its type's ``node`` says (their motion against
    # (2.14) on a bundled model of every type: tests/compiled/test_fast.py::test_every_model_file)
    built = build_layout(system)
    assert built is not None
    nodes, _ = sources(built[0], system)
    assert {p.name for p in nodes} == {p.name for p in system.parts if p.part_type.node != EXTRA_NODE}
