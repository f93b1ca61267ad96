"""The model-file schema (mbsynth/io/schema.py) is what the loader accepts: every key a
section lists is taken where that section applies, and a key it does not list is refused
with a ModelError naming the file, the line and the key."""

import copy

import pytest
import yaml

import mbsynth as mb
from mbsynth.io.part_types import SECTIONS

URDF = """<robot name="arm">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="link"><inertial><origin xyz="0 0 0.5"/><mass value="1"/>
    <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="link"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
</robot>
"""

BASE = {"parameters": {"m": 1.0, "k": 10.0, "L": 0.5, "R": 0.2, "g": 9.81, "F": 1.0, "tau": 0.1, "f": 0.1},
        "parts": {
            "body": {"type": "rigid_body", "mass": "m", "inertia": [0.1, 0.1, 0.2],
                     "frames": {"tip": {"position": [0, 0, -0.5]}, "top": {}}},
            "link": {"type": "planar_body", "mass": 1, "inertia": 0.1, "frames": {"top": {"position": [0, 0.5, 0]}}},
            "point": {"type": "particle", "mass": 1}}}

# a flexible body of one mode (the section examples' beam has 20 elements)
ROD = {"type": "flexible_body", "beam": {"length": 1.0, "elements": 20, "area": 1e-4, "Iy": 1e-9, "Iz": 1e-9, "J": 2e-9,
                                         "E": 2.1e11, "nu": 0.3, "density": 7850},
       "reduction": {"method": "craig_bampton", "interface": [0], "modes": 2}}  # a round section: its bending pair whole

# Where each section's mapping sits: (path of the mapping in the model, its minimal valid
# content, the model's other entries it needs). Keys are then added to that mapping.
LEG = "parameters: {L: 0.4, m: 1}\nparts: {foot: {type: particle, mass: m}}\n"  # a file to include
HOSTS = {
    "model": ((), None, {}),
    "world": (("world",), {}, {}),
    "frame": (("world", "frames", "anchor"), {}, {}),
    "lagrangian": (("parts", "cart"), {"type": "lagrangian", "coordinates": ["x"], "T": "0.5*m*x_dot**2"}, {}),
    "rigid_body": (("parts", "body"), None, {}),
    "particle": (("parts", "point"), None, {}),
    "planar_body": (("parts", "link"), None, {}),
    "spring": (("parts", "coil"), {"type": "spring", "stiffness": 1, "rest_length": 1}, {}),
    "robot": (("parts", "arm"), {"type": "robot", "robot": "arm.urdf"}, {}),
    "initial_rigid_body": (("parts", "body", "initial"), {}, {}),
    "initial_particle": (("parts", "point", "initial"), {}, {}),
    "initial_planar_body": (("parts", "link", "initial"), {}, {}),
    "initial_spring": (("parts", "coil", "initial"), {},
                       {("parts", "coil"): {"type": "spring", "stiffness": 1, "rest_length": 1}}),
    "pose": (("parts", "arm", "base"), {}, {("parts", "arm"): {"type": "robot", "robot": "arm.urdf"}}),
    "geometry": (("parts", "body", "frames", "tip", "geometry"), {}, {}),
    "constraint": (("constraints", 0), {}, {}),
    "acceleration_row": (("constraints", 0, "acceleration"), {"A": {"point.x": 1}}, {("constraints", 0): {}}),
    "joint": (("joints", 0), {"name": "pin", "type": "revolute", "parent": "world", "child": "body.top"}, {}),
    "rolling_disk": (("joints", 0), {"name": "roll", "type": "rolling_disk", "child": "body", "radius": "R"}, {}),
    "knife_edge": (("joints", 0), {"name": "blade", "type": "knife_edge", "child": "link"}, {}),
    "contact_plane": (("contacts", 0), {"name": "floor", "type": "plane", "child": "point"}, {}),
    "contact_spheres": (("contacts", 0), {"name": "touch", "type": "spheres", "between": ["point", "body"],
                                          "radius": [0.1, 0.1]}, {}),
    "cone_limit": (("joints", 0, "limits"), {"cone": 0.5},
                   {("joints", 0): {"name": "ball", "type": "spherical", "parent": "world", "child": "body.top"}}),
    "joint_actuation": (("joints", 0, "actuation"), {},
                        {("joints", 0): {"name": "pin", "type": "cylindrical", "parent": "world", "child": "body"}}),
    "joint_spring": (("joints", 0, "spring"), {"stiffness": "k"},
                     {("joints", 0): {"name": "pin", "type": "revolute", "parent": "world", "child": "body"}}),
    "joint_friction": (("joints", 0, "friction"), {},
                       {("joints", 0): {"name": "pin", "type": "revolute", "parent": "world", "child": "body"}}),
    "force_spring": (("forces", 0), {"type": "spring", "between": ["body.tip", "world"], "stiffness": "k",
                                     "rest_length": "L"}, {}),
    "force_damper": (("forces", 0), {"type": "damper", "between": ["body.tip", "world"], "damping": 0.1}, {}),
    "force_force": (("forces", 0), {"type": "force", "at": "body.tip", "value": [0, 0, 1]}, {}),
    "force_torque": (("forces", 0), {"type": "torque", "part": "body", "value": [0, 0, 1]}, {}),
    "output": (("outputs", "watch"), {}, {}),
    "model_part": (("parts", "leg"), {"type": "model", "file": "leg.yaml"}, {}),
    "placement": (("parts", "leg", "placement"), {}, {("parts", "leg"): {"type": "model", "file": "leg.yaml"}}),
    "flexible_body": (("parts", "rod"), dict(ROD), {}),
    "solid": (("parts", "block"), {"type": "solid", "shape": {"box": [0.2, 0.1, 0.1]}, "density": 1000}, {}),
    "flexible_beam": (("parts", "rod", "beam"), dict(ROD["beam"]), {("parts", "rod"): dict(ROD)}),
    "flexible_fe": (("parts", "rod", "fe"), {}, {("parts", "rod"): {k: v for k, v in ROD.items() if k != "beam"}}),
    "flexible_reduction": (("parts", "rod", "reduction"), dict(ROD["reduction"]), {("parts", "rod"): dict(ROD)}),
    "flexible_damping": (("parts", "rod", "damping"), {}, {("parts", "rod"): dict(ROD)}),
    "flexible_frame": (("parts", "rod", "frames", "tip"), {"node": 20}, {("parts", "rod"): dict(ROD)}),
    "initial_flexible_body": (("parts", "rod", "initial"), {}, {("parts", "rod"): dict(ROD)}),
}
# Keys of which a mapping takes at most one: each is tried in a model of its own.
EXCLUSIVE = [{"rpy", "axis", "quaternion"}, {"box", "sphere", "cylinder", "capsule", "mesh", "line"},
             {"holonomic", "nonholonomic", "acceleration"}, {"reaction", "position", "velocity", "energy"},
             {"beam", "fe"}, {"G", "nu"}, {"modes", "max_frequency"}, {"rayleigh", "modal"}]


def _place(model, path, value):
    """Set ``value`` at ``path`` (keys and list indices), making the mappings and lists on the way."""
    node = model
    for key, below in zip(path, path[1:]):
        if isinstance(node, list):
            node.extend({} for _ in range(key + 1 - len(node)))
        elif key not in node:
            node[key] = [] if isinstance(below, int) else {}
        node = node[key]
    if isinstance(node, list):
        node.extend({} for _ in range(path[-1] + 1 - len(node)))
    node[path[-1]] = value


def _mapping(model, path):
    node = model
    for key in path:
        node = node[key]
    return node


def _variants(section):
    """Groups of keys that one mapping can hold together, covering every key."""
    keys = [key.name for key in section.keys]
    shared = [k for k in keys if not any(k in group for group in EXCLUSIVE)]
    alone = [k for k in keys if k not in shared]
    return [shared + [k] for k in alone] or [shared]


def _model(name, keys, extra=None):
    section = SECTIONS[name]
    path, minimal, needs = HOSTS[name]
    model = copy.deepcopy(BASE)
    for where, value in needs.items():
        _place(model, where, copy.deepcopy(value))
    if minimal is not None:
        _place(model, path, copy.deepcopy(minimal))
    target = _mapping(model, path)
    examples = {key.name: yaml.safe_load(key.example) for key in section.keys}
    for key in keys:
        target.setdefault(key, examples[key])
    if extra:
        target.update(extra)
    return yaml.safe_dump(model, sort_keys=False)


def _error(text, tmp_path):
    (tmp_path / "arm.urdf").write_text(URDF)
    (tmp_path / "leg.yaml").write_text(LEG)
    try:
        mb.loads(text, name="schema_case.yaml", folder=tmp_path)
    except mb.ModelError as err:
        return str(err)
    return None


@pytest.mark.parametrize("name", list(SECTIONS))
def test_every_listed_key_is_accepted(name, tmp_path):
    for keys in _variants(SECTIONS[name]):
        error = _error(_model(name, keys), tmp_path) or ""
        # a later error (a file not found, a mapping of the model's own names) is no refusal of these keys
        refused = [key for key in keys if f"unknown key '{key}'" in error]
        assert not refused and "missing required key" not in error, (keys, error)


@pytest.mark.parametrize("name", list(SECTIONS))
def test_an_unlisted_key_is_refused_with_file_and_line(name, tmp_path):
    text = _model(name, [], extra={"bogus_key": 1})
    line = next(i for i, row in enumerate(text.splitlines(), 1) if "bogus_key" in row)
    error = _error(text, tmp_path)
    assert error is not None and error.startswith(f"schema_case.yaml:{line}:"), (text, error)
    assert "unknown key 'bogus_key'" in error


@pytest.mark.parametrize("name", [n for n, s in SECTIONS.items() if s.required and HOSTS[n][1]])
def test_each_required_key_is_required(name, tmp_path):
    path, minimal, _ = HOSTS[name]
    for key in SECTIONS[name].required:
        if key == "type":  # the type selects the section: without it the mapping is another one
            continue
        text = _model(name, [])
        model = yaml.safe_load(text)
        del _mapping(model, path)[key]
        error = _error(yaml.safe_dump(model, sort_keys=False), tmp_path)
        assert error is not None and f"missing required key '{key}'" in error, (key, error)
