"""Model files (YAML) to Systems.

Every mistake in a file raises ``ModelError`` reading ``file:line: at key.path: why``.
Expressions are parsed by ``mbsynth.core.expressions`` (never evaluated as code).
"""

import contextlib
import difflib
import functools
import keyword
from dataclasses import replace
from pathlib import Path

import numpy as np
import sympy as sp

from ..model.balances import append_balances
from ..model.constraints.joints import Joint
from ..model.constraints.base import Constraint
from ..model.joint_values import constraint_symbols, value_expressions, value_names
from ..core.expressions import CONSTANTS, FUNCTIONS, ExpressionError, parse
from ..core.errors import ModelError
from ..symbolic.derive import T_SYMBOL, joint_values_in
from ..model.system import Substructure, System
from .forces import read_forces
from .joints import read_joints, read_ports, read_world
from .outputs import read_outputs
from .part_types import FILE_TYPES, SECTIONS
from .robot import connect_robots, read_robots
from .placement import Placement, place_initial
from .unilateral import check_initial, read_contacts, read_limits
from .source import Document, LineDict, LineList, read_document
from .substructures import Scoped, included_from, read_includes
from ..core.tolerances import ASSEMBLED_TOL

RESERVED = set(FUNCTIONS) | set(CONSTANTS) | {"t"}


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
    return _Builder(doc, Assembly(parameters)).system()


class Assembly:
    """What every file of a model adds to, the model file's own and those it includes as
    substructures (substructures.py): the parameters, parts, coordinates and names, each
    under its full name (``left_leg.thigh.x``)."""

    def __init__(self, overrides=None):
        self.overrides = dict(overrides or {})  # load()'s parameters, by full name
        self.values = {}  # parameter symbol -> value, in the model's order
        self.definitions = {}  # parameter name -> expression of earlier ones
        self.fixed = {}  # parameter name -> where a file builds something from its value at load
        self.parameter_symbols = ()
        self.parts = {}  # full name -> part, in the model's order
        self.owners = {}  # full part name -> (its builder, its entry name there)
        self.ports = {}  # full port name -> (part, frame)
        self.welded = {}  # full part name a merged robot link would have -> its RobotEntry (io/robot.py)
        self.welded_joints = {}  # full name a merged fixed joint of a robot would have -> its link
        self.documents = {}  # resolved path -> Document: a file used N times is read once
        self.q, self.qd = [], []
        self.index = {}  # coordinate symbol -> its place in q
        self.known = {}  # expression of parameters -> its value (every file's builder finds each once)
        self.global_symbols = None
        self.constraint_symbols = None


class _Builder:
    def __init__(self, doc, assembly, include=None):
        """``include``: substructures.Include when this builder reads a file included by
        another (its names prefixed, its poses placed), None for the model file itself."""
        self.doc = doc
        self.root = doc.root
        self.assembly = assembly
        self.include = include
        self.prefix = include.prefix if include else ""
        self.placement = include.placement if include else Placement()
        self.children = []  # (entry name, [child builders]) of the file's ``type: model`` entries
        self.chain = include.chain if include else ()  # (file, line) of the entries that include this file
        self.bound = {}  # the extra_names in effect: {name: value}
        self.values = assembly.known  # expression of parameters -> its value, each found once (``checked``)
        self.limited = []  # (entry, path, Joint, name in the file, its for: names) of the file's joints, for their limits

    # -- generic checks -------------------------------------------------------------
    def fail(self, path, message):
        """Raise ModelError ``file:line: at key.path: message``, naming the values of the
        ``extra_names`` in effect (``for:``'s ``i``, a copy's ``index``); in an included file,
        with the chain of entries that included it."""
        if self.bound:
            message += f" (with {', '.join(f'{name} = {value}' for name, value in self.bound.items())})"
        error = self.doc.error(path, message)
        if self.include:
            error = ModelError(f"{error}{included_from(self.prefix[:-1], self.chain)}")
        raise error

    @contextlib.contextmanager
    def extra_names(self, names):
        """Expressions of parameters read meanwhile may use ``names`` too ({name: value}:
        a copy's ``index``, a ``for:`` entry's name)."""
        saved, saved_bound = self.param_symbols, self.bound
        self.param_symbols, self.bound = {**saved, **names}, {**saved_bound, **names}
        try:
            yield
        finally:
            self.param_symbols, self.bound = saved, saved_bound

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
        variables = sorted(expr.free_symbols - set(self.parameter_symbols), key=str)
        derived = [expr.diff(v) for v in variables]
        derived += [d.diff(v) for d in derived for v in (variables if second is None else second)]
        if any(d.has(sp.Derivative, sp.DiracDelta) for d in derived):
            self.fail(path, "cannot be differentiated in closed form: abs() and sign() of a coordinate, velocity "
                            "or t have no derivative, min() and max() no second one; write it smoothly, "
                            "e.g. sqrt(x**2 + eps**2) for abs(x)")
        return expr

    def constant(self, text, path):
        """An expression of parameters only (a mass, a length), checked finite and real."""
        return self.checked(self.expression(text, path, self.param_symbols), text, path)

    def checked(self, expr, text, path):
        """``expr`` (read from ``text`` at ``path``), checked to have a finite real value,
        which ``value`` then finds again without computing it."""
        if expr in self.values:
            return expr
        value = float(expr) if expr.is_Number else _real(expr, self.param_values)
        if value is None:
            self.fail(path, f"{text!r} is not a finite real number")
        self.values[expr] = value
        return expr

    def value(self, expr):
        """The float value of an expression of parameters."""
        if isinstance(expr, (int, float)):
            return float(expr)
        expr = sp.sympify(expr)
        found = self.values.get(expr)
        return float(_at(expr, self.param_values)) if found is None else found

    def fixed_value(self, expr, path):
        """``value(expr)`` for something built once at load (an FE model): its parameters
        are recorded as fixed there (``System.fixed_parameters``)."""
        where = f"{self.doc.name}:{self.doc.line_of(path)}, key {'.'.join(map(str, path))}"
        for symbol in sp.sympify(expr).free_symbols:
            self.assembly.fixed.setdefault(str(symbol), where)
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

    def numbers(self, node, path, size, fixed=True):
        """A list of ``size`` floats (expressions of parameters allowed). They are built into
        the model at load, so their parameters are recorded as fixed there (``fixed_value``:
        ``with_parameters`` refuses to change them, naming this line); ``fixed`` False only
        for numbers the model does not compute with (a drawing's sizes and colours)."""
        return [self.fixed_value(x, path) if fixed else self.value(x) for x in self.constants(node, path, size)]

    def initial_values(self, node, path, size):
        """A list of ``size`` initial coordinate values: expressions of parameters, which
        follow ``with_parameters`` (``read_initial``'s definitions)."""
        return list(self.constants(node, path, size))

    def constants(self, node, path, size):
        """A sympy column of ``size`` expressions of parameters, each finite and real."""
        node = self.sized_list(node, path, size)
        return sp.Matrix([self.constant(x, path + (i,)) for i, x in enumerate(node)])

    def part_symbols(self, name, coordinates):
        """The model's symbols of a part's coordinates and velocities."""
        return ([sp.Symbol(f"{name}.{c}") for c in coordinates],
                [sp.Symbol(f"{name}.{c}_dot") for c in coordinates])

    # -- names of a file included as a substructure --------------------------------
    def full_name(self, name):
        """The model's name of this file's ``name`` (``left_leg.thigh`` for ``thigh``)."""
        return self.prefix + name

    def own_name(self, name):
        """This file's name for the model's ``name`` (the inverse of ``full_name``)."""
        return name[len(self.prefix):]

    @property
    def parameter_symbols(self):
        """Every parameter symbol of the model, in order: the arguments of compiled code."""
        return self.assembly.parameter_symbols

    @property
    def param_values(self):
        return self.assembly.values

    @property
    def builders(self):
        """This builder and those of the files it includes, depth first (files in entry order)."""
        yield self
        for _, copies in self.children:
            for child in copies:
                yield from child.builders

    @property
    def included_first(self):
        """``builders`` with every file after those it includes (its joints join theirs)."""
        for _, copies in self.children:
            for child in copies:
                yield from child.included_first
        yield self

    # -- sections -------------------------------------------------------------------
    def system(self):
        root = self.section(self.root, (), "model")
        name = root.get("name", _stem(self.doc.name))
        if not isinstance(name, str):
            self.fail(("name",), f"expected a string, got {_kind(name)}")
        self.plan()
        model = self.assembly
        unknown = sorted(set(model.overrides) - {str(s) for s in model.values})
        if unknown:
            raise ModelError(f"{self.doc.name}: the model has no parameter(s) {unknown}; "
                             f"it has {sorted(str(s) for s in model.values)}")
        model.parameter_symbols = tuple(model.values)
        self.gravity = self.constants(root.get("gravity", LineList([0, 0, 0])), ("gravity",), 3)
        for builder in self.builders:
            builder.gravity = self.gravity  # a substructure's gravity is the model's
            builder.world_frames = {f.name: f for f in read_world(builder)}
        parts = self.read_parts()
        model.q += [sym for part in parts for sym in part.q]
        model.qd += [sym for part in parts for sym in part.qd]
        model.global_symbols = Names({str(s): s for s in model.parameter_symbols}, t=T_SYMBOL)
        for part in parts:
            for c, qs, qds in zip(part.coordinates, part.q, part.qd):
                model.global_symbols[f"{part.name}.{c}"] = qs
                model.global_symbols[f"{part.name}.{c}_dot"] = qds
        model.constraint_symbols = Names(model.global_symbols)  # joint angles as JointValue symbols (symbolic.py)
        model.index = {s: i for i, s in enumerate(model.q)}
        model.coordinate_set, model.velocity_set = set(model.q), set(model.qd)
        for builder in self.builders:
            builder.scope_names(parts)
        args = (model.q, model.qd, model.parameter_symbols)
        constraints = [c for part in parts for c in part.own_constraints(*args)]
        forces = []
        for builder in self.included_first:  # a substructure's joints before those that join it
            more_constraints, more_forces = builder.connect()
            constraints, forces = constraints + more_constraints, forces + more_forces
        self.check_names(constraints)
        values, definitions, given = self.read_initial()
        initial = {key: self.value(value) for key, value in values.items()}
        fixed = set().union(*(builder.read_initial_fixed(given) for builder in self.builders))
        system = System.build(name, parts, constraints, model.q, model.qd, self.parameters_by_name(), initial,
                              initial_fixed=fixed, forces=forces)
        unilaterals = [(u, path, builder) for builder in self.included_first for u, path in builder.unilaterals()]
        gaps = [u.name for u, _, _ in unilaterals]
        outputs = [output for builder in self.included_first for output in read_outputs(builder, constraints, gaps)]
        system = replace(system, definitions=model.definitions, initial_definitions=definitions,
                         initial_given=frozenset(given), source=self.doc.text, source_folder=str(self.doc.folder),
                         robots=tuple(entry.robot for b in self.builders for entry in b.robots.values()),
                         outputs=tuple(outputs), fixed_parameters=dict(model.fixed),
                         load_parameters=dict(model.overrides), built_parameters=dict(system.parameters),
                         substructures=self.substructures())
        if unilaterals:
            system = replace(system, unilaterals=tuple(u for u, _, _ in unilaterals))
        self.check_parts(system)
        self.check_branches(system)
        check_initial(system, unilaterals)
        auto = [builder for builder in self.builders if builder.read_balances() == "auto"]
        return append_balances(system) if auto else system

    def plan(self):
        """This file's parameters, robots and included files (theirs in turn), before any
        part is built: every part's compiled code takes all the model's parameters."""
        self.read_parameters()
        self.robots = read_robots(self)  # their torque parameters join the model's
        for name, value in self.robots_parameters():
            self.add_parameter(name, sp.Float(value) if name not in self.assembly.overrides
                               else sp.Float(self.assembly.overrides[name]), None)
        self.check_part_entries()
        self.children = read_includes(self)

    def robots_parameters(self):
        """(full name, default) of the robots' torque parameters this file has not set."""
        return [(name, value) for entry in self.robots.values() for name, value in entry.parameters.items()
                if sp.Symbol(name) not in self.assembly.values]

    def parameters_by_name(self):
        return {str(symbol): value for symbol, value in self.assembly.values.items()}

    def add_parameter(self, name, expr, path):
        """Parameter ``name`` (full name) = ``expr`` (an expression of earlier ones, in full
        names); ``path``: where the file gives it (None: no line to name)."""
        value = self.values.get(expr)
        value = _real(expr, self.assembly.values) if value is None else value
        if value is None:
            given = self.assembly.overrides.get(name, expr)
            message = f"parameter '{name}' = {given!r} is not a finite real number"
            if path is None:
                raise ModelError(f"{self.doc.name}: {message}")
            self.fail(path, message)
        symbol = sp.Symbol(name)
        self.assembly.values[symbol] = value
        if expr.free_symbols:
            self.assembly.definitions[name] = expr
        return symbol

    def read_parameters(self):
        """Parameter values in order (the model's ``definitions`` keep the expression of
        each one defined by earlier ones, which follows them in ``System.with_parameters``;
        a number is no definition: its value stays until changed itself). A value given to
        ``load`` wins, then one given by the including file's entry (its ``parameters:``)."""
        node = self.root.get("parameters", LineDict())
        node = self.mapping(node, ("parameters",), set(node) if isinstance(node, dict) else set())
        given = self.include.parameters if self.include else {}
        self.parameters = {}  # this file's name -> value
        self.param_symbols = {}  # this file's name -> the model's symbol
        for key, text in node.items():
            path = ("parameters", key)
            self.identifier(key, path, "parameter")
            name = self.full_name(key)
            if name in self.assembly.overrides:
                expr = sp.Float(self.assembly.overrides[name])
            elif key in given:
                expr = given[key]
            else:
                expr = self.expression(text, path, self.param_symbols)
            symbol = self.add_parameter(name, expr, path)
            self.parameters[key] = self.assembly.values[symbol]
            self.param_symbols[key] = symbol

    def read_parts(self):
        """The parts of this file and of the files it includes, in the file's order."""
        node = self.root["parts"]
        parts, included = [], dict(self.children)
        self.own_parts = []
        for name, spec in node.items():
            path = ("parts", name)
            if name in included:
                for child in included[name]:
                    parts += child.read_parts()
                continue
            type_name = spec.get("type")
            if type_name not in FILE_TYPES:
                self.fail(path + ("type",), f"unknown part type {type_name!r}; known: "
                                            f"{', '.join((*FILE_TYPES, 'model'))}")
            made = FILE_TYPES[type_name].read(self, self.full_name(name), spec, path)
            made = made if isinstance(made, list) else [made]  # a robot gives one part per link
            for part in made:
                self.assembly.parts[part.name] = part
                self.assembly.owners[part.name] = (self, name)
            self.own_parts += made
            parts += made
        return parts

    def check_part_entries(self):
        """The ``parts:`` mapping: a mapping of named entries, each a mapping."""
        node = self.root["parts"]
        if node is not None and not isinstance(node, LineDict):
            self.fail(("parts",), f"expected a mapping of named parts, e.g. 'wheel: {{type: lagrangian, ...}}', "
                                       f"got {_kind(node)}")
        if not node:
            self.fail(("parts",), "the mapping is empty: a model needs at least one part, e.g. "
                                       "'wheel: {type: lagrangian, ...}'")
        for name, spec in node.items():
            path = ("parts", name)
            self.identifier(name, path, "part name")
            if name in self.parameters or name == "world":
                self.fail(path, f"part '{name}' has the name of a parameter or of the world")
            if not isinstance(spec, LineDict):
                self.fail(path, f"expected a mapping with 'type' and the part's data, got {_kind(spec)}")
        return node

    def scope_names(self, parts):
        """This file's view of the model's names: its parts, coordinates, parameters and
        joint values under the names the file uses (those of the model file itself: all)."""
        model = self.assembly
        if not self.prefix:
            self.parts = model.parts
            self.global_symbols, self.constraint_symbols = model.global_symbols, model.constraint_symbols
            self.coordinates = [(str(s), i) for i, s in enumerate(model.q)]
            return
        parts = self.all_parts()
        self.parts = {self.own_name(part.name): part for part in parts}
        self.global_symbols = Scoped(model.global_symbols, self.prefix)
        self.constraint_symbols = Scoped(model.constraint_symbols, self.prefix)
        self.coordinates = [(self.own_name(str(s)), model.index[s]) for part in parts for s in part.q]

    def connect(self):
        """(constraints, force elements) this file adds once every part is known: its
        robots' joints, its constraints and joints, its force elements."""
        read_ports(self)
        robot_joints, robot_forces = connect_robots(self)
        self.register_joints(robot_joints, robot=True)
        joints, joint_forces = read_joints(self)
        return robot_joints + self.read_constraints() + joints, robot_forces + read_forces(self) + joint_forces

    def unilaterals(self):
        """(Unilateral, path of its entry) of this file's joint limits and contacts."""
        limits = []
        for spec, path, joint, own, loop in self.limited:
            with self.extra_names(loop):
                limits += read_limits(self, spec, path, joint, own)
        return limits + read_contacts(self)

    def read_balances(self):
        balances = self.root.get("balances", "none")
        if balances not in ("auto", "none"):
            self.fail(("balances",), f"expected 'auto' or 'none', got {balances!r}")
        return balances

    def substructures(self):
        """The tree of files this model is made of (model/system.py's Substructure)."""
        return tuple(Substructure(child.prefix[:-1], str(child.doc.name), tuple(p.name for p in child.own_parts),
                                  child.substructures())
                     for _, copies in self.children for child in copies)

    def read_constraints(self):
        node = self.root.get("constraints", LineList())
        if not isinstance(node, LineList):
            self.fail(("constraints",), f"expected a list of constraints, got {_kind(node)}")
        kinds = ("holonomic", "nonholonomic", "acceleration")
        constraints, names = [], set()
        coordinates, velocities = self.assembly.coordinate_set, self.assembly.velocity_set
        for i, spec in enumerate(node):
            path = ("constraints", i)
            spec = self.section(spec, path, "constraint")
            name = spec.get("name", f"constraint_{i + 1}")
            if not isinstance(name, str) or not name.strip():
                self.fail(path + ("name",), f"constraint name must be a string, got {_kind(name)}")
            if name in names:
                self.fail(path + ("name",), f"duplicate constraint name '{name}'")
            names.add(name)
            name = self.full_name(name)
            given = [k for k in kinds if k in spec]
            if len(given) != 1:
                self.fail(path, f"constraint '{name}' needs exactly one of {', '.join(kinds)}; got {given or 'none'}")
            kind = given[0]
            C = self.read_nonideal(spec, path) if "C" in spec else None
            args = (self.q, self.qd, self.parameter_symbols)
            kpath = path + (kind,)
            if kind == "acceleration":
                a, b = self.read_acceleration_row(spec[kind], kpath)
                constraints.append(Constraint.acceleration(name, a, b, *args, C=C))
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
            make = getattr(Constraint, kind)
            constraints.append(make(name, [expr], *args, C=C))
        return constraints

    def read_acceleration_row(self, node, path):
        node = self.section(node, path, "acceleration_row")
        coords = [name for name, _ in self.coordinates]
        row = node["A"]
        if isinstance(row, LineList):
            if len(row) != len(coords):
                self.fail(path + ("A",), f"a row of A needs {len(coords)} entries (one per coordinate: "
                                         f"{', '.join(coords)}), got {len(row)}")
            entries = dict(zip(coords, row))
            where = {c: path + ("A", i) for i, c in enumerate(coords)}
        else:
            entries = self.mapping(row, path + ("A",), set(coords))
            where = {c: path + ("A", c) for c in coords}
        a = self.over_coordinates({c: self.expression(x, where[c], self.global_symbols) for c, x in entries.items()})
        b = self.expression(node.get("b", 0), path + ("b",), self.global_symbols)
        if all(x == 0 for x in a):
            self.fail(path + ("A",), "the row of A is all zero")
        return a, b

    def read_nonideal(self, spec, path):
        node = self.mapping(spec["C"], path + ("C",), {name for name, _ in self.coordinates})
        return self.over_coordinates({c: self.expression(x, path + ("C", c), self.global_symbols)
                                      for c, x in node.items()})

    def over_coordinates(self, entries):
        """A list over every coordinate of the model from {this file's coordinate name:
        expression}, zero elsewhere."""
        row = [sp.S.Zero] * len(self.q)
        for name, i in self.coordinates:
            if name in entries:
                row[i] = entries[name]
        return row

    @property
    def q(self):
        return self.assembly.q

    @property
    def qd(self):
        return self.assembly.qd

    def register_joints(self, joints, robot=False):
        """Put the joints' values (``<joint>.angle``, ``<joint>.rate``, …: joint_values.py)
        among the names expressions may use; a joint and a part share one namespace. A
        URDF may give a joint its child link's name: such a robot joint has no values in
        expressions (its part's coordinates keep the name)."""
        model = self.assembly
        for joint in joints:
            if not isinstance(joint, Joint) or (robot and joint.name in model.parts):
                continue
            own = self.own_name(joint.name)
            if joint.name in model.parts:
                self.fail(self.entry_of(own) or ("parts", own),
                          f"joint '{own}' has the name of part '{own}': joints and parts share one "
                          f"namespace ('{own}.angle', '{own}.x'), rename one of them")
            base = own.split("[")[0]  # a for: entry's joints are base[i]
            if base in dict(self.children):
                entry = self.entry_of(own)
                self.fail(entry + ("name",) if entry else ("joints",),
                          f"joint '{base}' has the name of the substructure '{base}' (its names are "
                          f"'{base}.<name>'): rename the joint")
            if own in self.parameters or own == "world":
                entry = self.entry_of(own)
                clash = "the world (its frames are 'world.<frame>')" if own == "world" else "a parameter"
                self.fail(entry + ("name",) if entry else ("parts",),
                          f"joint '{own}' has the name of {clash}: rename the joint")
            values = functools.cache(functools.partial(value_expressions, joint))
            symbols = functools.cache(functools.partial(constraint_symbols, joint))
            for key in value_names(joint):  # derived only when an expression uses them (a sympy derivation)
                model.global_symbols[f"{joint.name}.{key}"] = _Deferred(values, key)
                model.constraint_symbols[f"{joint.name}.{key}"] = _Deferred(symbols, key)

    def read_initial(self):
        """(values, definitions, given) of the initial state in this file's axes, by full
        name: each part's own ``initial:``, those of the included files placed (their
        ``placement:``), then the file's ``initial:`` mapping by coordinate name (one
        place per coordinate). ``definitions``: the values given by expressions (which
        follow ``with_parameters``); ``given``: the names the files set."""
        values = {f"{part.name}.{k}": v for part in self.own_parts for k, v in part.initial.items()}
        definitions = {k: v for k, v in values.items() if isinstance(v, sp.Basic) and v.free_symbols}
        given = set(values)
        for _, copies in self.children:
            for child in copies:
                more, more_definitions, more_given = child.read_initial()
                placed = child.placed_initial(more)
                values.update(placed)
                definitions.update({k: placed.get(k, v) for k, v in more_definitions.items()})
                if placed is not more:  # placed by expressions of parameters: they follow them too
                    definitions.update({k: v for k, v in placed.items() if sp.sympify(v).free_symbols})
                given |= more_given | {k for k, v in placed.items() if k not in more and not k.endswith("_dot")}
        coords = [name for name, _ in self.coordinates]
        allowed = set(coords) | {c + "_dot" for c in coords}
        node = self.mapping(self.root.get("initial", LineDict()), ("initial",), allowed)
        for key, text in node.items():
            name = self.full_name(key)
            if name in given:
                self.fail(("initial", key), f"'{key}' is already set by the part's own initial: mapping")
            definitions[name] = values[name] = self.constant(text, ("initial", key))
            given.add(name)
        return values, definitions, given

    def placed_initial(self, values):
        """The initial ``values`` of this file's parts (this file's axes) in the including
        file's axes: moved by this file's ``placement:`` (placement.py)."""
        relative = self.include.relative
        if relative.identity:
            return values
        where = self.include.path + ("placement",)
        placed = {}
        for part in self.all_parts():
            start = len(part.name) + 1
            own = {k[start:]: v for k, v in values.items() if k.startswith(part.name + ".")}
            moved = place_initial(part, own, relative, lambda why: self.include.parent.fail(where, why))
            placed.update({f"{part.name}.{k}": v for k, v in moved.items()})
        return placed

    def all_parts(self):
        """The parts of this file and of the files it includes."""
        return [part for builder in self.builders for part in builder.own_parts]

    def read_initial_fixed(self, given):
        """Names whose initial values must be kept exactly (a list; each must be set)."""
        node = self.root.get("initial_fixed", LineList())
        if not isinstance(node, list):
            self.fail(("initial_fixed",), f"expected a list of names from 'initial:', got {_kind(node)}")
        for i, key in enumerate(node):
            if not isinstance(key, str) or self.full_name(key) not in given:
                self.fail(("initial_fixed", i), f"'{key}' has no initial value to keep")
        return {self.full_name(key) for key in node}

    def check_names(self, constraints):
        """A name given to a constraint or joint must not be another one's (nor a part's own
        constraint's, such as ``body.unit_quaternion``)."""
        seen = set()
        for con in constraints:
            if con.name in seen:
                builder, place = self.entry_named(con.name)
                builder.fail(place + ("name",) if place else ("constraints",),
                             f"the name '{builder.own_name(con.name)}' is given to two constraints or joints")
            seen.add(con.name)

    def entry_named(self, name):
        """(the builder of the file, the path of its last constraint or joint entry) that
        gives the model's constraint ``name``; (this builder, None) when none does."""
        for builder in reversed(list(self.builders)):  # the longest prefix first
            if name.startswith(builder.prefix):
                place = builder.entry_of(builder.own_name(name))
                if place:
                    return builder, place
        return self, None

    def entry_of(self, name):
        """The path of this file's last constraint or joint entry named ``name`` (a joint
        of a ``for:`` entry: ``name[i]``), or None."""
        base = name.split("[")[0]
        places = [(key, i) for key in ("constraints", "joints") for i, spec in enumerate(self.root.get(key) or ())
                  if isinstance(spec, dict) and spec.get("name") in (name, base)]
        return places[-1] if places else None

    def check_parts(self, system):
        """Each part's M must be finite and positive semi-definite at the initial state."""
        for part, problem in system.part_problems():
            builder, own = self.assembly.owners.get(part, (self, part))
            spec = (builder.root.get("parts") or {}).get(own)
            energy = "semi-definite" in problem and isinstance(spec, dict) and "T" in spec  # a lagrangian part's T
            builder.fail(("parts", own) + (("T",) if energy else ()), problem)

    def check_branches(self, system):
        """No joint may be assembled at the initial state (its rows hold) in a pose its rows
        allow but it does not mean (a fixed joint's frames turned 180°): System.branch_problems.
        A joint whose rows do not hold yet is left to the state made consistent. One state:
        evaluated on the KKT path (numpy), which compiles nothing."""
        q, qd = system.initial_state()
        phi, _ = system.data("kkt").constraint_residuals(0.0, q, qd)
        apart = {row.split("[")[0] for row, r in zip(system.constraint_names, phi) if abs(r) > ASSEMBLED_TOL}
        for joint, problem in system.branch_problems(q):
            if joint not in apart:
                builder, place = self.entry_named(joint)
                builder.fail(place or ("initial",), problem)


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
