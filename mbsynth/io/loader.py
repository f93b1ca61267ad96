"""Model files (YAML) to Systems.

Every mistake in a file raises ``ModelError`` reading ``file:line: at key.path: why``.
Expressions are parsed by ``mbsynth.core.expressions`` (never evaluated as code).
"""

import difflib
import functools
import keyword
from dataclasses import replace
from pathlib import Path

import numpy as np
import sympy as sp

from ..model.balances import close
from ..model.connectors.joints import Joint
from ..model.connectors.base import Connector
from ..model.joint_values import constraint_symbols, value_expressions, value_names
from ..core.expressions import CONSTANTS, FUNCTIONS, ExpressionError, parse
from ..core.errors import ModelError
from ..model.parts import LagrangianPart
from ..symbolic.derive import T_SYMBOL, joint_values_in
from ..model.system import System
from .flexible import read_flexible_body
from .forces import read_forces
from .joints import read_joints, read_world
from .outputs import read_outputs
from .parts import read_frames, read_geometry, read_particle, read_planar_body, read_rigid_body, read_spring
from .robot import connect_robots, read_robot, read_robots
from .schema import SECTIONS
from .source import Document, LineDict, LineList, read_document

RESERVED = set(FUNCTIONS) | set(CONSTANTS) | {"t"}
ASSEMBLED = 1e-6  # a joint whose rows are all below this at the initial state is assembled there


def load(path, parameters=None):
    """Read the model file at ``path`` and return its ``System``; ``parameters`` ({name:
    value}): values instead of the file's (what the file builds from them, e.g. a flexible
    body's FE model, is built with them)."""
    return replace(build(read_document(path), parameters), source_file=str(Path(path).resolve()))


def loads(text, name="<string>", folder=None, parameters=None):
    """Build a ``System`` from model text (``name`` is used in error messages); file names
    in it (meshes, URDFs) are relative to ``folder`` (default: the working folder);
    ``parameters``: as in ``load``."""
    return build(Document(name, text, folder), parameters)


def build(doc, parameters=None):
    """Build the System described by a parsed Document (``parameters``: as in ``load``)."""
    return _Builder(doc, parameters).system()


class _Builder:
    def __init__(self, doc, parameters=None):
        self.doc = doc
        self.root = doc.root
        self.overrides = dict(parameters or {})
        self.fixed = {}  # parameter name -> where the file builds something from its value at load
        self.values = {}  # expression of parameters -> its value, each found once (``constant``)

    # -- generic checks -------------------------------------------------------------
    def fail(self, path, message):
        raise self.doc.error(path, message)

    def mapping(self, node, path, allowed, required=()):
        if node is None:
            node = LineDict()
        if not isinstance(node, dict):
            self.fail(path, f"expected a mapping, got {_kind(node)}")
        for key in node:
            if key not in allowed:
                close_match = difflib.get_close_matches(str(key), sorted(allowed), n=1)
                hint = f" (did you mean '{close_match[0]}'?)" if close_match else ""
                self.fail(path + (key,), f"unknown key '{key}'{hint}; allowed: {', '.join(sorted(allowed))}")
        for key in required:
            if key not in node:
                self.fail(path, f"missing required key '{key}'")
        return node

    def section(self, node, path, name):
        """``node`` checked against the schema's section ``name`` (schema.py): its allowed
        and required keys."""
        section = SECTIONS[name]
        return self.mapping(node, path, section.allowed, required=section.required)

    def identifier(self, name, path, what):
        if not isinstance(name, str) or not name.isidentifier() or keyword.iskeyword(name):
            self.fail(path, f"{what} {name!r} must be a plain name (letters, digits, _)")
        if name in RESERVED:
            self.fail(path, f"{what} '{name}' is reserved (a function, constant or time)")
        return name

    def expression(self, text, path, symbols):
        try:
            return parse(text, symbols)
        except ExpressionError as err:
            self.fail(path, str(err))

    def differentiable(self, expr, path, second=None):
        """``expr``, checked to have the derivatives the equations of motion take of it: by
        each coordinate, velocity and t, then of those by the symbols ``second`` (None: by
        each again). abs and sign of such a symbol have none sympy can evaluate (it takes
        their argument as complex), min and max no second one (a DiracDelta)."""
        if not expr.has(sp.Abs, sp.sign, sp.Min, sp.Max):
            return expr
        variables = sorted(expr.free_symbols - set(self.param_symbols.values()), key=str)
        derived = [expr.diff(v) for v in variables]
        derived += [d.diff(v) for d in derived for v in (variables if second is None else second)]
        if any(d.has(sp.Derivative, sp.DiracDelta) for d in derived):
            self.fail(path, "cannot be differentiated in closed form: abs() and sign() of a coordinate, velocity "
                            "or t have no derivative, min() and max() no second one; write it smoothly, "
                            "e.g. sqrt(x**2 + eps**2) for abs(x)")
        return expr

    def constant(self, text, path):
        """An expression of parameters only (a mass, a length), checked finite and real."""
        expr = self.expression(text, path, self.param_symbols)
        value = _real(expr, self.param_values)
        if value is None:
            self.fail(path, f"{text!r} is not a finite real number")
        self.values[expr] = value
        return expr

    def value(self, expr):
        """The float value of an expression of parameters."""
        expr = sp.sympify(expr)
        found = self.values.get(expr)
        return float(_at(expr, self.param_values)) if found is None else found

    def fixed_value(self, expr, path):
        """``value(expr)`` for something built once at load (an FE model): its parameters
        are recorded as fixed there (``System.fixed_parameters``)."""
        where = f"{self.doc.name}:{self.doc.line_of(path)}, key {'.'.join(map(str, path))}"
        for symbol in sp.sympify(expr).free_symbols:
            self.fixed.setdefault(str(symbol), where)
        return self.value(expr)

    def sized_list(self, node, path, size):
        if not isinstance(node, list) or len(node) != size:
            self.fail(path, f"expected a list of {size} numbers or expressions, got {_kind(node)}"
                            + (f" of {len(node)}" if isinstance(node, list) else ""))
        return node

    def vector(self, node, path, size, symbols):
        """A sympy column of ``size`` expressions."""
        node = self.sized_list(node, path, size)
        return sp.Matrix([self.expression(x, path + (i,), symbols) for i, x in enumerate(node)])

    def numbers(self, node, path, size, fixed=False):
        """A list of ``size`` floats (expressions of parameters allowed; ``fixed``: built
        from at load, as ``fixed_value``)."""
        return [self.fixed_value(x, path) if fixed else self.value(x) for x in self.constants(node, path, size)]

    def constants(self, node, path, size):
        """A sympy column of ``size`` expressions of parameters, each finite and real."""
        node = self.sized_list(node, path, size)
        return sp.Matrix([self.constant(x, path + (i,)) for i, x in enumerate(node)])

    def part_symbols(self, name, coordinates):
        """The model's symbols of a part's coordinates and velocities."""
        return ([sp.Symbol(f"{name}.{c}") for c in coordinates],
                [sp.Symbol(f"{name}.{c}_dot") for c in coordinates])

    # -- sections -------------------------------------------------------------------
    def system(self):
        root = self.section(self.root, (), "model")
        name = root.get("name", _stem(self.doc.name))
        if not isinstance(name, str):
            self.fail(("name",), f"expected a string, got {_kind(name)}")
        self.parameters = self.read_parameters()
        self.robots = read_robots(self)  # before any part is built: their torque parameters join the model's
        self.override_robot_parameters()
        self.param_symbols = {p: sp.Symbol(p) for p in self.parameters}
        self.param_values = {sp.Symbol(k): v for k, v in self.parameters.items()}
        self.gravity = self.constants(root.get("gravity", LineList([0, 0, 0])), ("gravity",), 3)
        self.world_frames = {f.name: f for f in read_world(self)}
        parts = self.read_subsystems()
        self.parts = {part.name: part for part in parts}
        self.q = [sym for part in parts for sym in part.q]
        self.qd = [sym for part in parts for sym in part.qd]
        self.global_symbols = Names(self.param_symbols, t=T_SYMBOL)
        for part in parts:
            for c, qs, qds in zip(part.coordinates, part.q, part.qd):
                self.global_symbols[f"{part.name}.{c}"] = qs
                self.global_symbols[f"{part.name}.{c}_dot"] = qds
        self.constraint_symbols = Names(self.global_symbols)  # joint angles as JointValue symbols (symbolic.py)
        args = (self.q, self.qd, self.param_symbols.values())
        constraints = [c for part in parts for c in part.own_constraints(*args)]
        robot_joints, robot_forces = connect_robots(self)
        self.register_joints(robot_joints, robot=True)
        joints, joint_forces = read_joints(self)
        constraints += robot_joints + self.read_constraints() + joints
        self.check_names(constraints)
        initial = self.read_initial(parts)
        system = System.build(name, parts, constraints, self.q, self.qd, self.parameters, initial,
                              initial_fixed=self.read_initial_fixed(initial),
                              forces=[*robot_forces, *read_forces(self), *joint_forces])
        system = replace(system, definitions=self.definitions, initial_definitions=self.initial_definitions,
                         source=self.doc.text, source_folder=str(self.doc.folder),
                         robots=tuple(entry.robot for entry in self.robots.values()),
                         outputs=read_outputs(self, constraints), fixed_parameters=dict(self.fixed),
                         load_parameters=dict(self.overrides), built_parameters=dict(system.parameters))
        self.check_parts(system)
        self.check_branches(system)
        closure = root.get("closure", "none")
        if closure not in ("auto", "none"):
            self.fail(("closure",), f"expected 'auto' or 'none', got {closure!r}")
        return close(system) if closure == "auto" else system

    def override_robot_parameters(self):
        """The given ``parameters`` of load() over the robots' torque parameters (the file's
        own took theirs in read_parameters); a name the model lacks is a ModelError."""
        unknown = sorted(set(self.overrides) - set(self.parameters))
        if unknown:
            raise ModelError(f"{self.doc.name}: the model has no parameter(s) {unknown}; "
                             f"it has {sorted(self.parameters)}")
        self.parameters.update(self.overrides)

    def read_parameters(self):
        """Parameter values in order; ``self.definitions`` keeps the expression of each one
        defined by earlier ones (which follows them in ``System.with_parameters``); a number
        is no definition: its value stays until changed itself."""
        self.definitions = {}
        node = self.root.get("parameters", LineDict())
        node = self.mapping(node, ("parameters",), set(node) if isinstance(node, dict) else set())
        values, symbols = {}, {}
        for key, text in node.items():
            path = ("parameters", key)
            self.identifier(key, path, "parameter")
            expr = sp.Float(self.overrides[key]) if key in self.overrides else self.expression(text, path, symbols)
            value = _real(expr, values)
            if value is None:
                given = self.overrides.get(key, text)
                self.fail(path, f"parameter '{key}' = {given!r} is not a finite real number")
            values[sp.Symbol(key)] = value
            symbols[key] = sp.Symbol(key)
            if expr.free_symbols:
                self.definitions[key] = expr
        return {str(k): v for k, v in values.items()}

    def read_subsystems(self):
        node = self.root["subsystems"]
        if node is not None and not isinstance(node, LineDict):
            self.fail(("subsystems",), f"expected a mapping of named parts, e.g. 'wheel: {{type: lagrangian, ...}}', "
                                       f"got {_kind(node)}")
        if not node:
            self.fail(("subsystems",), "the mapping is empty: a model needs at least one part, e.g. "
                                       "'wheel: {type: lagrangian, ...}'")
        parts = []
        for name, spec in node.items():
            path = ("subsystems", name)
            self.identifier(name, path, "subsystem name")
            if name in self.parameters or name == "world":
                self.fail(path, f"subsystem '{name}' has the name of a parameter or of the world")
            if not isinstance(spec, LineDict):
                self.fail(path, f"expected a mapping with 'type' and the part's data, got {_kind(spec)}")
            kind = spec.get("type")
            if kind not in SUBSYSTEM_TYPES:
                self.fail(path + ("type",), f"unknown subsystem type {kind!r}; known: {', '.join(SUBSYSTEM_TYPES)}")
            made = SUBSYSTEM_TYPES[kind](self, name, spec, path)
            parts += made if isinstance(made, list) else [made]  # a robot gives one part per link
        return parts

    def read_lagrangian(self, name, spec, path):
        self.section(spec, path, "lagrangian")
        coords = spec["coordinates"]
        if not isinstance(coords, LineList) or not coords:
            self.fail(path + ("coordinates",), "expected a non-empty list of coordinate names")
        for i, c in enumerate(coords):
            self.identifier(c, path + ("coordinates", i), "coordinate")
            if c.endswith("_dot"):
                self.fail(path + ("coordinates", i), f"coordinate '{c}' must not end in '_dot' (that names velocities)")
            if c in self.parameters:
                self.fail(path + ("coordinates", i), f"coordinate '{c}' has the name of a parameter")
            if coords.index(c) != i:
                self.fail(path + ("coordinates", i), f"coordinate '{c}' is listed twice")
        q, qd = self.part_symbols(name, coords)
        symbols = dict(self.param_symbols, t=T_SYMBOL)
        symbols.update(zip(coords, q))
        symbols.update(zip((f"{c}_dot" for c in coords), qd))
        T = self.differentiable(self.expression(spec["T"], path + ("T",), symbols), path + ("T",), qd)
        V = self.differentiable(self.expression(spec.get("V", 0), path + ("V",), symbols), path + ("V",), ())
        if V.free_symbols & set(qd):
            self.fail(path + ("V",), "potential energy V must not depend on velocities")
        forces_node = self.mapping(spec.get("forces", LineDict()), path + ("forces",), set(coords))
        forces = [self.expression(forces_node[c], path + ("forces", c), symbols) if c in forces_node
                  else sp.S.Zero for c in coords]
        frames = read_frames(self, name, spec.get("frames"), path + ("frames",), True, symbols)
        return LagrangianPart(name, coords, q, qd, T, V, forces, self.param_symbols.values(), frames,
                                   read_geometry(self, spec.get("geometry"), path + ("geometry",)))

    def read_constraints(self):
        node = self.root.get("constraints", LineList())
        if not isinstance(node, LineList):
            self.fail(("constraints",), f"expected a list of constraints, got {_kind(node)}")
        kinds = ("holonomic", "nonholonomic", "acceleration")
        constraints, names = [], set()
        coordinates, velocities = set(self.q), set(self.qd)
        for i, spec in enumerate(node):
            path = ("constraints", i)
            spec = self.section(spec, path, "constraint")
            name = spec.get("name", f"constraint_{i + 1}")
            if not isinstance(name, str) or not name.strip():
                self.fail(path + ("name",), f"constraint name must be a string, got {_kind(name)}")
            if name in names:
                self.fail(path + ("name",), f"duplicate constraint name '{name}'")
            names.add(name)
            given = [k for k in kinds if k in spec]
            if len(given) != 1:
                self.fail(path, f"constraint '{name}' needs exactly one of {', '.join(kinds)}; got {given or 'none'}")
            kind = given[0]
            C = self.read_nonideal(spec, path) if "C" in spec else None
            args = (self.q, self.qd, self.param_symbols.values())
            kpath = path + (kind,)
            if kind == "acceleration":
                a, b = self.read_acceleration_row(spec[kind], kpath)
                constraints.append(Connector.acceleration(name, a, b, *args, C=C))
                continue
            expr = self.expression(spec[kind], kpath, self.constraint_symbols)
            self.differentiable(expr, kpath, None if kind == "holonomic" else ())
            has_q = expr.free_symbols & coordinates or joint_values_in(expr)
            has_qd = expr.free_symbols & velocities
            if kind == "holonomic" and has_qd:
                self.fail(kpath, f"constraint '{name}' uses velocities {sorted(map(str, has_qd))}; "
                                 "write it as 'nonholonomic:'")
            if kind == "holonomic" and not has_q:
                self.fail(kpath, f"constraint '{name}' involves no coordinate")
            if kind == "nonholonomic" and not has_qd:
                self.fail(kpath, f"constraint '{name}' involves no velocity (name_dot); "
                                 "a constraint on positions is 'holonomic:'")
            make = getattr(Connector, kind)
            constraints.append(make(name, [expr], *args, C=C))
        return constraints

    def read_acceleration_row(self, node, path):
        node = self.section(node, path, "acceleration_row")
        coords = list(self.coordinate_names())
        row = node["A"]
        if isinstance(row, LineList):
            if len(row) != len(coords):
                self.fail(path + ("A",), f"a row of A needs {len(coords)} entries (one per coordinate: "
                                         f"{', '.join(coords)}), got {len(row)}")
            a = [self.expression(x, path + ("A", i), self.global_symbols) for i, x in enumerate(row)]
        else:
            entries = self.mapping(row, path + ("A",), set(coords))
            a = [self.expression(entries[c], path + ("A", c), self.global_symbols) if c in entries
                 else sp.S.Zero for c in coords]
        b = self.expression(node.get("b", 0), path + ("b",), self.global_symbols)
        if all(x == 0 for x in a):
            self.fail(path + ("A",), "the row of A is all zero")
        return a, b

    def read_nonideal(self, spec, path):
        coords = list(self.coordinate_names())
        node = self.mapping(spec["C"], path + ("C",), set(coords))
        return [self.expression(node[c], path + ("C", c), self.global_symbols) if c in node
                else sp.S.Zero for c in coords]

    def register_joints(self, joints, robot=False):
        """Put the joints' values (``<joint>.angle``, ``<joint>.rate``, …: joint_values.py)
        among the names expressions may use; a joint and a part share one namespace. A
        URDF may give a joint its child link's name: such a robot joint has no values in
        expressions (its part's coordinates keep the name)."""
        for joint in joints:
            if not isinstance(joint, Joint) or (robot and joint.name in self.parts):
                continue
            if joint.name in self.parts:
                self.fail(self.entry_named(joint.name) or ("subsystems", joint.name),
                          f"joint '{joint.name}' has the name of part '{joint.name}': joints and parts share one "
                          f"namespace ('{joint.name}.angle', '{joint.name}.x'), rename one of them")
            if joint.name in self.parameters or joint.name == "world":
                entry = self.entry_named(joint.name)
                clash = "the world (its frames are 'world.<frame>')" if joint.name == "world" else "a parameter"
                self.fail(entry + ("name",) if entry else ("subsystems",),
                          f"joint '{joint.name}' has the name of {clash}: rename the joint")
            values = functools.cache(functools.partial(value_expressions, joint))
            symbols = functools.cache(functools.partial(constraint_symbols, joint))
            for key in value_names(joint):  # derived when an expression uses them (sympy: tenths of a second)
                self.global_symbols[f"{joint.name}.{key}"] = _Deferred(values, key)
                self.constraint_symbols[f"{joint.name}.{key}"] = _Deferred(symbols, key)

    def coordinate_names(self):
        return (str(s) for s in self.q)

    def read_initial(self, parts):
        """Initial values: each part's own ``initial:``, then the model's ``initial:``
        mapping by coordinate name (one place per coordinate)."""
        values = {f"{part.name}.{k}": v for part in parts for k, v in part.initial.items()}
        self.initial_definitions = {}
        coords = list(self.coordinate_names())
        allowed = set(coords) | {c + "_dot" for c in coords}
        node = self.mapping(self.root.get("initial", LineDict()), ("initial",), allowed)
        for key, text in node.items():
            if key in values:
                self.fail(("initial", key), f"'{key}' is already set by the part's own initial: mapping")
            self.initial_definitions[key] = self.constant(text, ("initial", key))
            values[key] = self.value(self.initial_definitions[key])
        return values

    def read_initial_fixed(self, initial):
        """Names whose initial values must be kept exactly (a list; each must be set)."""
        node = self.root.get("initial_fixed", LineList())
        if not isinstance(node, list):
            self.fail(("initial_fixed",), f"expected a list of names from 'initial:', got {_kind(node)}")
        for i, key in enumerate(node):
            if key not in initial:
                self.fail(("initial_fixed", i), f"'{key}' has no initial value to keep")
        return set(node)

    def check_names(self, constraints):
        """A name given to a constraint or joint must not be another one's (nor a part's own
        constraint's, such as ``body.unit_quaternion``)."""
        seen = set()
        for con in constraints:
            if con.name in seen:
                place = self.entry_named(con.name)
                self.fail(place + ("name",) if place else ("constraints",),
                          f"the name '{con.name}' is given to two constraints or joints")
            seen.add(con.name)

    def entry_named(self, name):
        """The path of the last constraint or joint entry named ``name``, or None."""
        places = [(key, i) for key in ("constraints", "joints") for i, spec in enumerate(self.root.get(key) or ())
                  if isinstance(spec, dict) and spec.get("name") == name]
        return places[-1] if places else None

    def check_parts(self, system):
        """Each part's M must be finite and positive semi-definite at the initial state."""
        for part, problem in system.part_problems():
            spec = (self.root.get("subsystems") or {}).get(part)
            energy = "semi-definite" in problem and isinstance(spec, dict) and "T" in spec  # a lagrangian part's T
            self.fail(("subsystems", part) + (("T",) if energy else ()), problem)

    def check_branches(self, system):
        """No joint may be assembled at the initial state (its rows hold) in a pose its rows
        allow but it does not mean (a fixed joint's frames turned 180°): System.branch_problems.
        A joint whose rows do not hold yet is left to the state made consistent."""
        q, qd = system.initial_state()
        phi, _ = system.constraint_residuals(0.0, q, qd)
        apart = {row.split("[")[0] for row, r in zip(system.constraint_names, phi) if abs(r) > ASSEMBLED}
        for joint, problem in system.branch_problems(q):
            if joint not in apart:
                self.fail(self.entry_named(joint) or ("initial",), problem)


SUBSYSTEM_TYPES = {"lagrangian": _Builder.read_lagrangian, "rigid_body": read_rigid_body,
                   "particle": read_particle, "planar_body": read_planar_body, "spring": read_spring,
                   "robot": read_robot, "flexible_body": read_flexible_body}


def _real(expr, values):
    """The float value of ``expr`` at the parameter ``values``, or None when that is not a
    finite real number."""
    try:
        value = _at(expr, values)
        value = complex(value if value.is_Number else value.evalf())
    except (TypeError, ValueError, OverflowError):  # a value sympy cannot make a number
        return None
    return value.real if value.imag == 0 and np.isfinite(value.real) else None


def _at(expr, values):
    """``expr`` with the ``values`` ({symbol: number}) of its own symbols put in, as
    floats: a replacement of those alone, not a substitution of a model's thousands of
    parameters."""
    return expr.xreplace({s: sp.Float(values[s]) for s in expr.free_symbols if s in values})


def _kind(value):
    return {LineDict: "a mapping", LineList: "a list", str: "a string"}.get(type(value), type(value).__name__)


def _stem(name):
    return name.rsplit("/", 1)[-1].rsplit(".", 1)[0]


class Names(dict):
    """The names expressions may use (expressions.parse's ``symbols``): a ``_Deferred``
    value is derived at its first use."""

    def __getitem__(self, name):
        value = super().__getitem__(name)
        if isinstance(value, _Deferred):
            value = self[name] = value.derive()[value.key]
        return value


class _Deferred:
    """Entry ``key`` of the dict ``derive()`` returns (``derive`` caches it)."""

    def __init__(self, derive, key):
        self.derive, self.key = derive, key
