"""``type: solid``: mass and inertia from a shape and a density (io/solid.py), against closed
forms; a mesh's centre of mass moves its frames and drawing; mistakes named at their line."""

import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.analysis.trajectory import Trajectory
from mbsynth.view.scene import build_scene

RHO = 2700.0
MODEL = Path(__file__).resolve().parents[2] / "models" / "rigid" / "solid_pendulum.yaml"


def solid(shape, extra="", folder=None, parameters=""):
    text = textwrap.dedent(f"""\
        parameters: {{rho: {RHO}{parameters}}}
        parts:
          s: {{type: solid, shape: {shape}, density: rho{extra}}}
        """)
    return mb.loads(text, name="solid.yaml", folder=folder)


def mass_properties(system):
    (part,) = system.parts
    values = dict(zip(system.parameter_symbols, system.parameter_values))
    return float(part.mass.xreplace(values)), np.array(part.inertia.xreplace(values), dtype=float)


def capsule_inertia(m_cylinder, m_cap, r, h):
    """(I_xx, I_zz) of a capsule, a cylinder of length h and two hemispherical caps of mass
    m_cap each: a hemisphere's I about its own centroid across its axis is 83/320 m r², its
    centroid 3r/8 from its flat face (parallel axes: Steiner), along its axis 2/5 m r²."""
    d = h / 2 + 3 * r / 8
    across = m_cylinder * (3 * r**2 + h**2) / 12 + 2 * m_cap * (83 / 320 * r**2 + d**2)
    along = m_cylinder * r**2 / 2 + 2 * m_cap * 2 / 5 * r**2
    return across, along


def test_primitives_have_their_closed_form_mass_and_inertia():
    a, b, c = 0.4, 0.2, 0.1
    m, J = mass_properties(solid(f"{{box: [{a}, {b}, {c}]}}"))
    assert m == pytest.approx(RHO * a * b * c, rel=1e-12)
    assert np.allclose(J, np.diag([b**2 + c**2, a**2 + c**2, a**2 + b**2]) * m / 12, rtol=1e-12, atol=0)
    r = 0.15
    m, J = mass_properties(solid(f"{{sphere: {r}}}"))
    assert m == pytest.approx(RHO * 4 / 3 * np.pi * r**3, rel=1e-12)
    assert np.allclose(J, np.eye(3) * 2 / 5 * m * r**2, rtol=1e-12, atol=0)
    r, h = 0.1, 0.5
    m, J = mass_properties(solid(f"{{cylinder: [{r}, {h}]}}"))
    assert m == pytest.approx(RHO * np.pi * r**2 * h, rel=1e-12)
    assert np.allclose(J, np.diag([m * (3 * r**2 + h**2) / 12] * 2 + [m * r**2 / 2]), rtol=1e-12, atol=0)
    m, J = mass_properties(solid(f"{{capsule: [{r}, {h}]}}"))
    m_cylinder, m_cap = RHO * np.pi * r**2 * h, RHO * 2 / 3 * np.pi * r**3
    assert m == pytest.approx(m_cylinder + 2 * m_cap, rel=1e-12)
    across, along = capsule_inertia(m_cylinder, m_cap, r, h)
    assert np.allclose(J, np.diag([across, across, along]), rtol=1e-12, atol=0)


def test_a_turned_shape_turns_its_inertia():
    """A box whose origin turns it 90° about z swaps its x and y moments."""
    m, J = mass_properties(solid("{box: [0.4, 0.2, 0.1], origin: {rpy: [0, 0, pi/2]}}"))
    assert np.allclose(np.diag(J), np.array([0.4**2 + 0.1**2, 0.2**2 + 0.1**2, 0.4**2 + 0.2**2]) * m / 12,
                       rtol=1e-12, atol=1e-15)


def box_stl(path, size, centre):
    """An ASCII STL of a closed box of ``size`` about ``centre``, faces turned outward."""
    half, middle = np.asarray(size) / 2, np.asarray(centre, dtype=float)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half + middle
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    lines = ["solid box"]
    for quad in faces:
        for tri in ((quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])):
            p = corners[list(tri)]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            if normal @ (p.mean(axis=0) - middle) < 0:
                p, normal = p[::-1], -normal
            lines += [f"facet normal {' '.join(map(str, normal / np.linalg.norm(normal)))}", "outer loop",
                      *(f"vertex {' '.join(map(str, v))}" for v in p), "endloop", "endfacet"]
    path.write_text("\n".join(lines + ["endsolid box\n"]))


def test_a_mesh_weighs_as_its_box_and_its_frames_move_by_its_centre_of_mass(tmp_path):
    size, centre = np.array([0.4, 0.2, 0.1]), np.array([0.3, -0.1, 0.05])
    box_stl(tmp_path / "block.stl", size, centre)
    system = solid("{mesh: block.stl, color: blue}", ", frames: {corner: {position: [0, 0, 0]}}", folder=tmp_path)
    m, J = mass_properties(system)
    a, b, c = size
    single = 1e-6  # the mesh loader (assimp) keeps vertices in single precision
    assert m == pytest.approx(RHO * a * b * c, rel=single)
    assert np.allclose(J, np.diag([b**2 + c**2, a**2 + c**2, a**2 + b**2]) * m / 12, rtol=single, atol=single * m * a**2)
    (part,) = system.parts
    assert np.allclose(np.array(part.frames["corner"].position, dtype=float).ravel(), -centre, atol=single)
    # drawn with its own mesh, at the same offset from the body's centre of mass
    q, qd = system.initial_state()
    rows = np.array([q])
    scene = build_scene(system, Trajectory(system.coordinates, np.zeros(1), rows, np.zeros_like(rows),
                                           *np.zeros((4, 1))))
    (node,) = [n for n in scene.nodes if n.path == "s"]
    (shape,) = node.shapes
    assert shape["shape"] == "mesh" and shape["file"] == str(tmp_path / "block.stl")
    assert np.allclose(shape["position"], -centre, atol=single)


def test_density_is_a_parameter_and_the_shape_is_built_in():
    system = solid("{box: [L, 0.2, 0.1]}", parameters=", L: 0.4")
    heavier = system.with_parameters(rho=2 * RHO)
    assert mass_properties(heavier)[0] == pytest.approx(2 * mass_properties(system)[0], rel=1e-12)
    with pytest.raises(mb.ModelError, match="'L'.*load the file again"):
        system.with_parameters(L=0.5)


@pytest.mark.parametrize("entry, message", [
    ("shape: {line: top}, density: 1", "a line runs from a frame"),
    ("shape: [{box: [1, 1, 1]}, {sphere: 1}], density: 1", "a solid has one shape"),
    ("shape: {box: [1, 1, 1]}, density: -1", "density must be ≥ 0"),
    ("shape: {sphere: 0.1}, density: 1, mass: 2", "unknown key 'mass'"),
    ("shape: {sphere: 0.1}", "missing required key 'density'"),
])
def test_mistakes_name_the_line(entry, message):
    with pytest.raises(mb.ModelError) as caught:
        mb.loads(f"parts:\n  s: {{type: solid, {entry}}}\n", name="bad.yaml")
    assert "bad.yaml:2" in str(caught.value) and message in str(caught.value)


def test_an_open_mesh_is_refused_from_the_command_line(tmp_path):
    """One face of a box left out: coal would weigh what is left; the loader refuses it (exit 2, one line)."""
    box_stl(tmp_path / "box.stl", [0.4, 0.2, 0.1], [0, 0, 0])
    lines = (tmp_path / "box.stl").read_text().splitlines()
    (tmp_path / "open.stl").write_text("\n".join(lines[:1] + lines[15:]))  # two triangles (7 lines each) fewer
    (tmp_path / "open.yaml").write_text("parts:\n  s: {type: solid, shape: {mesh: open.stl}, density: 1000}\n")
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(tmp_path / "open.yaml")],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "open.yaml:2" in done.stderr and "is not closed" in done.stderr


def test_the_bundled_solid_checks_from_the_command_line():
    done = subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(MODEL), "--json"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert '"unique": true' in done.stdout
