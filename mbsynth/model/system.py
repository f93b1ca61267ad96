"""A System: the model — parts, their coordinate layout, the constraints joining them,
the force elements, parameter names and default values.

A System is a value: immutable (tuples, read-only arrays and mappings), equal to another
with the same content (``==`` and ``hash``: two loads of one file are equal), holding no
cache and no work. What a computation keeps between calls (parameter values as an array,
evaluators, the compiled engine and its path) lives in a Data made from it
(``system.data(path=)``, data.py); what models of one structure share, in the one cache
(core/memo.py). The algorithms are functions of the Data (``data.motion(t, q, q̇)``, …);
the System's own methods (``evaluate``, ``motion``, ``reactions``, …) compute at its
parameter values, each through the Data of the default path.
"""

import functools
import math
import numbers
import warnings
from dataclasses import dataclass, field, fields, replace

import numpy as np
import sympy as sp

from .constraints.joints import Joint
from ..compiled.background import default_path
from .data import Data, shared
from ..core.errors import ModelError
from ..core.memo import MEMO
from ..core.values import freeze, frozen_mapping, read_only, shared_if_equal
from .joint_values import JointKinematics, value_expressions
from .parts import LINK_FRAME, Frame
from ..symbolic.derive import T_SYMBOL
from ..core.tolerances import DIVISION_GUARD, MASS_NEGATIVE_RTOL


@dataclass(frozen=True)
class AppendedBalance:
    """A force balance wᵀ(Q + C) = 0 appended by ``balances: auto`` (see model/balances.py)."""

    constraint: str
    equation: str
    direction: dict
    state_dependent: bool


@dataclass(frozen=True)
class Substructure:
    """A model file included in another (``type: model``): ``name`` its prefix in the
    model's names (``robot.left_leg``), ``file`` its path, ``parts`` the full names of the
    parts its own ``parts:`` give, ``children`` the substructures it includes."""

    name: str
    file: str
    parts: tuple
    children: tuple = ()


DEFAULT_DATA_KEPT = 16  # models whose default-path Data (``System._data``) the one cache keeps
FLOAT = np.dtype(float)  # the dtype of a state ``_state`` passes on as given


class Structure:
    """What models that differ only in parameter values share: their parts, constraints,
    force elements and parameter names, equal by content (``core.values``); the key of
    the one cache's ``model structures`` table (data.py)."""

    __slots__ = ("parts", "constraints", "forces", "names", "_hash")

    def __init__(self, parts, constraints, forces, names):
        self.parts, self.constraints, self.forces, self.names = parts, constraints, forces, names
        self._hash = None

    def __eq__(self, other):
        return self is other or (isinstance(other, Structure) and hash(self) == hash(other) and
                                 (self.parts, self.constraints, self.forces, self.names) ==
                                 (other.parts, other.constraints, other.forces, other.names))

    def __hash__(self):
        if self._hash is None:  # a hash of immutable content, kept as str keeps its own
            self._hash = hash((self.parts, self.constraints, self.forces, self.names))
        return self._hash


@dataclass(frozen=True, eq=False)
class System:
    """An assembled model. Build it with ``mbsynth.load`` or ``System.build``."""

    name: str
    parts: tuple  # the model file's ``parts:``
    constraints: tuple  # the model file's ``constraints:`` and ``joints:``, and the parts' own rows
    coordinates: tuple
    q_symbols: tuple
    qd_symbols: tuple
    parameters: dict
    initial_q: np.ndarray
    initial_qd: np.ndarray
    forces: tuple = ()
    appended_balances: tuple = ()
    initial_given: frozenset = frozenset()
    initial_fixed: frozenset = frozenset()
    definitions: dict = None  # parameter name -> sympy expression of earlier parameters
    initial_definitions: dict = None  # initial value name -> sympy expression of parameters
    source: str = field(default="", compare=False)  # the model file's text, for workers that rebuild
    # the System (no part of its value: a comment or a key's old name changes no model)
    source_folder: str = ""  # the folder its file names (meshes, URDFs) are relative to
    source_file: str = ""  # the model file it was read from (mbsynth.load), its absolute path
    substructures: tuple = ()  # Substructure: the model files this one includes, as a tree
    robots: tuple = ()  # robots.Robot: the robots decomposed into parts, for validate.py
    outputs: tuple = ()  # outputs.Output: named quantities evaluated along a run
    unilaterals: tuple = ()  # unilateral.Unilateral: joint limits and contacts, gaps g(q) ≥ 0 (analysis/impacts.py)
    fixed_parameters: dict = None  # parameter name -> where the model file built something from it at load
    load_parameters: dict = None  # the values given to ``load`` (``parameters=``), built in at load
    built_parameters: dict = None  # every parameter's value as the model was built at load
    # derived from the fields above as the System is made (no part of its value)
    structure: "Structure" = field(init=False, repr=False)
    coordinate_groups: np.ndarray = field(init=False, repr=False)
    constraint_names: tuple = field(init=False, repr=False)
    parameter_index: dict = field(init=False, repr=False)
    parameter_symbols: tuple = field(init=False, repr=False)
    coulomb: bool = field(init=False, repr=False)

    def __post_init__(self):
        """Freeze what was given (read-only arrays and mappings) and derive the rest."""
        put = functools.partial(object.__setattr__, self)
        put("parameters", frozen_mapping(self.parameters))
        for name in ("definitions", "initial_definitions", "fixed_parameters", "load_parameters", "built_parameters"):
            put(name, frozen_mapping(getattr(self, name)))
        put("initial_q", read_only(self.initial_q))
        put("initial_qd", read_only(self.initial_qd))
        put("structure", Structure(self.parts, self.constraints, self.forces, tuple(self.parameters)))
        put("coordinate_groups", read_only(_coordinate_groups(self.parts)))
        # one name per row of A (a joint with k rows names them ``joint[label]``)
        put("constraint_names", tuple(row for c in self.constraints for row in c.row_names))
        put("parameter_index", frozen_mapping({name: i for i, name in enumerate(self.parameters)}))
        put("parameter_symbols", tuple(sp.Symbol(name) for name in self.parameters))
        # whether a constraint has Coulomb friction (its C depends on q̈)
        put("coulomb", any(getattr(con, "coulomb", None) for con in self.constraints))

    def _content(self):
        return tuple(getattr(self, f.name) for f in fields(self) if f.init and f.compare)

    def __eq__(self, other):
        if self is other:
            return True
        if type(other) is not type(self):
            return NotImplemented
        return hash(self) == hash(other) and shared_if_equal(self._frozen(), other, other._frozen(), "_frozen_content")

    def _frozen(self):
        """``freeze`` of each compared field, kept as the hash is (the content is immutable)."""
        found = self.__dict__.get("_frozen_content")
        if found is None:
            found = self.__dict__["_frozen_content"] = tuple(freeze(x) for x in self._content())
        return found

    def __hash__(self):
        found = self.__dict__.get("_hash")  # a hash of immutable content, kept as str keeps its own
        if found is None:
            found = hash((self.name, self.source_file, self.structure, self.coordinates,
                          tuple(self.parameters.values()), self.initial_q.tobytes(), self.initial_qd.tobytes()))
            self.__dict__["_hash"] = found
        return found

    @classmethod
    def build(cls, name, parts, constraints, q_symbols, qd_symbols, parameters, initial=None, forces=(),
              initial_fixed=()):
        """Lay out the parts' coordinates in order, check names, set the initial state.

        ``initial`` maps ``part.coordinate`` and ``part.coordinate_dot`` to values;
        the rest start at the parts' defaults (zero, or the identity orientation).
        ``initial_given`` records the names the model set, ``initial_fixed`` those that
        must not change when the initial state is made consistent (projection.py).
        """
        coordinates = tuple(f"{s.name}.{c}" for s in parts for c in s.coordinates)
        if len(set(coordinates)) != len(coordinates):
            raise ModelError(f"model '{name}': duplicate coordinate names in {coordinates}")
        names = [c.name for c in constraints]
        duplicates = sorted({x for x in names if names.count(x) > 1})
        if duplicates:
            raise ModelError(f"model '{name}': duplicate constraint names {duplicates}")
        q0 = np.array([float(s.defaults.get(c, 0.0)) for s in parts for c in s.coordinates])
        qd0 = np.zeros(len(coordinates))
        index = {c: i for i, c in enumerate(coordinates)}
        for key, value in (initial or {}).items():
            if key in index:
                q0[index[key]] = value
            elif key.endswith("_dot") and key[:-4] in index:
                qd0[index[key[:-4]]] = value
            else:
                raise ModelError(f"model '{name}': initial value for unknown coordinate '{key}'")
        return cls(name, tuple(parts), tuple(constraints), coordinates, tuple(q_symbols),
                   tuple(qd_symbols), dict(parameters), q0, qd0, tuple(forces),
                   initial_given=frozenset(initial or ()), initial_fixed=frozenset(initial_fixed))

    @property
    def n(self):
        return len(self.coordinates)

    @property
    def connectors(self):  # the old name of constraints
        """``constraints`` under its old name (a DeprecationWarning)."""
        warnings.warn("System.connectors is the old name of System.constraints", DeprecationWarning, stacklevel=2)
        return self.constraints

    @property
    def parameter_values(self):
        return np.array(list(self.parameters.values()), dtype=float)

    def initial_state(self, p=None):
        """(q, q̇) from the model's ``initial:`` mapping (copies); ``p``: parameter values (an
        array in the model's order) at which the initial values written as expressions of
        parameters are taken (default: the model's own)."""
        q0, qd0 = self.initial_q.copy(), self.initial_qd.copy()
        if p is None or not self.initial_definitions:
            return q0, qd0
        subs = {sp.Symbol(name): sp.Float(float(value)) for name, value in zip(self.parameters, p)}
        index = {c: i for i, c in enumerate(self.coordinates)}
        for key, expr in self.initial_definitions.items():
            target, i = (qd0, index[key[:-4]]) if key not in index else (q0, index[key])
            target[i] = float(expr.xreplace(subs))
        return q0, qd0

    def with_parameters(self, **values):
        """A new System with some parameter values changed (the original is unchanged).

        Parameters defined by expressions of others, and initial values written as
        expressions of parameters, follow the new values. Balances appended at
        load time are kept as derived; they stay valid while the masses that were zero
        stay zero. A parameter the file built something from at load (``fixed_parameters``:
        a flexible body's FE model) cannot change here: ModelError naming where (load the
        file again with ``parameters=``). The new System shares this one's compiled path (``mbsynth.compiled``:
        parameters are arguments of its code), so a sweep compiles once."""
        p = self.resolved_parameters(values, check_parts=False)
        new = dict(zip(self.parameters, p.tolist()))
        q0, qd0 = self.initial_state(p)
        changed = replace(self, parameters=new, initial_q=q0, initial_qd=qd0)
        same_start = np.array_equal(q0, self.initial_q) and np.array_equal(qd0, self.initial_qd)
        moved = {sp.Symbol(name) for name, value in new.items() if value != self.parameters[name]}
        problems = changed.part_problems(moved if same_start else None)  # a moved start: every part
        if problems:
            given = values if len(values) <= 3 else f"{len(values)} new parameter values"
            raise ModelError(f"model '{self.name}' with {given}: {problems[0][1]}")
        return changed

    def resolved_parameters(self, values, p=None, check_parts=True):
        """The parameter values (an array in the model's order) with ``values`` ({name:
        value}) set over ``p`` (default: the model's): parameters defined by expressions of
        others follow. A value is a real number or a real array of one element (its scalar).
        Raises ModelError for a name the model has no parameter of, a value that is no real
        number (a string, a complex number, an array of more elements) or not finite, or
        (``check_parts``) a part that reads a changed parameter and
        whose M or Q is then not finite or M not positive semi-definite at the initial state."""
        index = self.parameter_index
        unknown = sorted(name for name in values if name not in index)
        if unknown:
            raise ModelError(f"model '{self.name}' has no parameter(s) {unknown}; "
                             f"it has {sorted(self.parameters)}")
        values = {name: self._parameter_value(name, x) for name, x in values.items()}
        bad = sorted(name for name, x in values.items() if not math.isfinite(x))
        if bad:
            raise ModelError(f"model '{self.name}': non-finite values for parameter(s) {bad}")
        old = self.parameter_values if p is None else np.asarray(p, dtype=float)
        new = old.copy()
        for name, x in values.items():
            new[index[name]] = x
        if self.definitions:  # parameters defined by expressions of earlier ones follow, in order
            subs = {}
            for i, name in enumerate(self.parameters):
                if name in self.definitions and name not in values:
                    new[i] = float(self.definitions[name].xreplace(subs))
                subs[sp.Symbol(name)] = sp.Float(new[i])
        changed = np.flatnonzero(old != new)
        if self.fixed_parameters:
            names = tuple(self.parameters)
            fixed = sorted(set(self.fixed_parameters) & {names[i] for i in changed})
            if fixed:
                raise ModelError(f"model '{self.name}': parameter '{fixed[0]}' was built into the model when it was "
                                 f"loaded (at {self.fixed_parameters[fixed[0]]}): load the file again with the new "
                                 f"value, mb.load(path, parameters={{'{fixed[0]}': ...}}) (the CLI's --set does)")
        if check_parts and changed.size:
            problems = self.part_problems({self.parameter_symbols[i] for i in changed}, new)
            if problems:
                raise ModelError(f"model '{self.name}' with {values}: {problems[0][1]}")
        return new

    def _parameter_value(self, name, x):
        """x as a float: a real number, or a real array of one element taken as its scalar
        (a joint value is an array, ``-2*jv["hinge"].position`` one of shape (1,)). ModelError
        naming the parameter for a string (even "3"), a complex number, a boolean, an array
        of another size or anything else."""
        if type(x) is float or type(x) is np.float64:  # the common cases, at every control sample
            return float(x)
        if isinstance(x, numbers.Real) and not isinstance(x, bool):  # a sympy or fractions number too
            return float(x)
        kind = np.asarray(x).dtype.kind if not isinstance(x, (str, bytes)) else "U"
        size = np.size(x) if kind in "iuf" else 1
        if kind in "iuf" and size == 1:
            return float(np.reshape(x, ()))
        got = {"U": f"the string {x!r}", "S": f"the bytes {x!r}", "c": f"the complex number {x!r}",
               "b": f"the boolean {x!r}"}.get(kind, f"an array of shape {np.shape(x)}" if kind in "iuf" else
                                          f"a {type(x).__name__}")
        raise ModelError(f"model '{self.name}': parameter '{name}' takes a real number (or a real array of one "
                         f"element), got {got}")

    def data(self, path=None):
        """A new workspace for computations on this System (data.Data): its parameter
        values, evaluators and compiled engine. ``path``: "compiled" or "kkt" (data.PATHS);
        None: the default (``mbsynth.compiled.background.default_path``)."""
        return Data(self, path)

    @property
    def _data(self):
        """The Data of the default path behind this System's own methods, kept in the one
        cache (core/memo.py) so that repeated calls share its evaluators and engine."""
        path = default_path()
        return _DEFAULT_DATA.get((self, path), lambda: Data(self, path))

    def part_problems(self, parameters=None, p=None):
        """[(part name, message)] for each part whose M or Q is not finite, or whose M is not
        positive semi-definite, at the initial state — a model no equation of motion fits.
        ``parameters``: only the parts written in these parameter symbols (those whose values
        changed: ``with_parameters``); every part by default. ``p``: the parameter values
        (default: the model's), at which the initial state is taken too."""
        if parameters is not None and not any(part.reads(parameters) for part in self.parts):
            return []  # a controller's torques: read by forces alone
        q, qd = self.initial_state(p)
        p = self.parameter_values if p is None else p
        problems, start = [], 0
        for part in self.parts:
            stop = start + len(part.coordinates)
            if parameters is not None and not part.reads(parameters):
                start = stop
                continue
            with np.errstate(all="ignore"):
                M, Q = part.evaluate(0.0, q[start:stop], qd[start:stop], p)
            if not (np.all(np.isfinite(M)) and np.all(np.isfinite(Q))):
                problems.append((part.name, f"part '{part.name}': M or Q is not finite at the initial state"))
            elif np.linalg.eigvalsh(M).min() < -MASS_NEGATIVE_RTOL * max(np.abs(M).max(), DIVISION_GUARD):
                problems.append((part.name, f"part '{part.name}': the mass matrix is not positive "
                                            "semi-definite at the initial state (a negative mass or inertia, "
                                            "or a T that is no kinetic energy)"))
            start = stop
        return problems

    def branch_problems(self, q=None, t=0.0, p=None):
        """[(joint name, message)] for each joint whose frames meet its rows at ``q`` (the
        initial state by default) in a pose it does not mean: a fixed joint's frames turned
        180° (constraints/joints.py). ``p``: the parameter values (default: the model's)."""
        q = self.initial_q if q is None else q
        values = dict(zip(self.q_symbols, np.asarray(q, dtype=float)))
        values.update(zip(self.parameter_symbols, self.parameter_values if p is None else p))
        values[T_SYMBOL] = t
        return [(c.name, message) for c in self.constraints if (message := c.wrong_branch(values))]

    def check_branches(self, q, t=0.0):
        """Raise SolveError naming the first joint whose frames, at the state q, are in a
        pose the joint does not mean (``branch_problems``)."""
        self._data.check_branches(q, t)

    def with_constraints(self, extra, balances=()):
        """A new System with ``extra`` constraints appended (the original is unchanged)."""
        return replace(self, constraints=self.constraints + tuple(extra),
                       appended_balances=self.appended_balances + tuple(balances))

    def _state(self, q, qd):
        """(q, q̇) as 1-d contiguous, writeable float arrays of n entries (the arrays given,
        where they are such: no copy), or ValueError naming the shapes. A read-only array (a
        model's ``initial_q``) is copied: the compiled kernels are compiled for writeable
        arrays, and numba would compile them all again for read-only ones."""
        if (type(q) is np.ndarray and type(qd) is np.ndarray and q.dtype is FLOAT and qd.dtype is FLOAT
                and q.shape == qd.shape == (self.n,) and q.flags.c_contiguous and qd.flags.c_contiguous
                and q.flags.writeable and qd.flags.writeable):
            return q, qd  # an integrator's or a controller's own arrays, every call
        return self._state_copies(q, qd)

    def _state_copies(self, q, qd):
        """(q, q̇) as new 1-d float arrays of n entries, copies of what was given (whatever
        the caller does to its arrays later), or ValueError naming the shapes."""
        q, qd = np.array(q, dtype=float).ravel(), np.array(qd, dtype=float).ravel()
        if q.shape != (self.n,) or qd.shape != (self.n,):
            raise ValueError(f"model '{self.name}' has {self.n} coordinates; got q of shape "
                             f"{q.shape} and qd of shape {qd.shape}")
        return q, qd

    def evaluate(self, t, q, qd):
        """Assemble M (block diagonal), Q, A, b and C at the state (t, q, q̇)."""
        return self._data.evaluate(t, q, qd)

    def constraint_rows(self, t, q, qd):
        """A (m × n, scipy.sparse CSR) and b at (t, q, q̇) — the rows alone, without M:
        what projection.py needs, in memory proportional to the rows' entries."""
        return self._data.constraint_rows(t, q, qd)

    def constraint_arrays(self, t, q, qd, sparse=True):
        """A, b, C, φ and φ̇ at (t, q, q̇) from one evaluation of the constraints
        (``evaluation.ConstraintArrays``): A scipy.sparse CSR, or dense (sparse=False), or
        dense where that is faster (sparse=None: few rows and coordinates)."""
        return self._data.constraint_arrays(t, q, qd, sparse)

    def motion(self, t, q, qd, method="kkt", baumgarte=None, drift=False):
        """The constrained acceleration at (t, q, q̇): a ``Motion`` (qdd, unique, nullspace,
        Qc, residual). ``method``: "kkt" or "reference" (the literal pseudo-inverse of
        (2.14); "fast" is the old name of "kkt"). "kkt" solves the KKT form of (2.14) on the
        Data's path (data.py: by default the linear-time compiled path of ``mbsynth.compiled``
        where it covers the model and its checks pass, else a factorization of the KKT
        matrix); both fall back to the exact treatment when the problem is not well posed.
        ``baumgarte=(α, β)`` replaces b by b − 2α φ̇ − β² φ on the rows that have those
        residuals (drift control during integration; b itself when they are zero).
        Coulomb friction at joints makes C depend on q̈: then ``friction.coulomb_motion``
        iterates, and Qc includes the friction.
        ``drift=True``: the state may lie off the constraint manifold (an integrator's
        stage): b is judged by the drift rule of ``equations`` (least squares where the
        drift explains an inconsistency, near-singular directions the drift dominates set
        aside) instead of raising SolveError for contradictory constraints.
        The Motion's ``lam`` (the multipliers, reactions.py) is computed when first read."""
        return self._data.motion(t, q, qd, method, baumgarte, drift)

    def motion_batch(self, t, q_batch, qd_batch):
        """q̈ at many states, one per row of ``q_batch`` and ``qd_batch`` (t: a number or one
        per row), in parallel: (qdd (B × n), unique (B,)); ``Data.motion_batch``."""
        return self._data.motion_batch(t, q_batch, qd_batch)

    def energy(self, t, q, qd):
        """(kinetic, potential) energy: the parts' T and V plus the force elements' potentials."""
        return self._data.energy(t, q, qd)

    def constraint_residuals(self, t, q, qd):
        """(φ, φ̇) per row of A: position and velocity residuals (NaN where not defined)."""
        return self._data.constraint_residuals(t, q, qd)

    def symbolic(self):
        """(M, Q, A, b, C) as sympy matrices in the model's symbols."""
        blocks = [part.symbolic() for part in self.parts]
        M = sp.diag(*[blk[0] for blk in blocks]) if blocks else sp.zeros(0, 0)
        Q = sum((f.symbolic() for f in self.forces), sp.Matrix.vstack(*[blk[1] for blk in blocks]))
        n = self.n
        A = sp.Matrix.vstack(sp.zeros(0, n), *[con.a for con in self.constraints])
        b = sp.Matrix.vstack(sp.zeros(0, 1), *[con.b for con in self.constraints])
        C = sum((con.C for con in self.constraints), sp.zeros(n, 1))
        return M, Q, A, b, C

    def joint_kinematics(self):
        """{name: joint_values.JointKinematics} of every joint (reaction frames; fixed and
        distance joints have no values) and of each floating robot's root link
        (``<prefix>root_joint``, a free joint, as Pinocchio names it), compiled on first use
        and shared by the models of one structure (data.Shared)."""
        held = shared(self)
        if held.joint_kinematics is None:
            held.joint_kinematics = _joint_kinematics(self)
        return held.joint_kinematics

    def joint_values(self, t, q, qd, qdd=None):
        """{joint name: JointValues(position, rate, acceleration)} of every joint that has
        values (joint_values.py: revolute ``angle``, prismatic ``displacement``, …, a
        floating robot's ``root_joint``), in model order; acceleration None without q̈."""
        return self._data.joint_values(t, q, qd, qdd)

    def reactions(self, t, q, qd, motion=None):
        """{constraint name: reactions.Reaction} at (t, q, q̇) for ``motion`` (by default
        ``self.motion(t, q, qd)``): the multipliers of each constraint's rows, and for each
        joint the wrench (``force``, ``torque``) the parent exerts on the child through it —
        its rows, its friction, its actuation and spring — at the child's reaction frame
        (the frame B of the joint; a robot's child link frame), in that frame's axes."""
        return self._data.reactions(t, q, qd, motion)

    def expression_names(self):
        """{name: sympy expression} of what expressions about this model may use: t, the
        parameters, coordinates ``part.c``, velocities ``part.c_dot`` and joint values
        ``joint.angle``, ``joint.rate``, … (joint_values.value_expressions; a robot joint
        named like a part has none)."""
        names = {"t": T_SYMBOL, **{str(s): s for s in (*self.parameter_symbols, *self.q_symbols, *self.qd_symbols)}}
        parts = {p.name for p in self.parts}
        for con in self.constraints:
            if isinstance(con, Joint) and con.name not in parts:
                names.update({f"{con.name}.{key}": expr for key, expr in value_expressions(con).items()})
        return names

    def working_forces(self, p=None):
        """The names of what can change the total energy T + V at the parameter values ``p``
        (default: the model's): force elements with efforts not all zero there
        (actuation, dampers), parts with forces beyond T and V (generalized forces, modal or
        Rayleigh damping, a spring's damper) or an explicit t, constraints with a non-ideal C
        not zero there (friction) or an explicit t (a prescribed motion), limits and contacts whose impacts
        lose energy (restitution below 1). Empty: the energy is conserved, and its change
        along a run is drift."""
        return list(_working_forces(self, tuple(float(v) for v in (self.parameter_values if p is None else p))))

    def unaccounted_work(self):
        """The names among ``working_forces`` whose work a run does not integrate
        (``Data.power``): an explicit t in a potential, a kinetic energy or a constraint,
        Coulomb friction (its force depends on q̈) and inelastic impacts (their loss is a jump)."""
        found = [e.name for e in self.forces if T_SYMBOL in e.V.free_symbols]
        found += [part.name for part in self.parts if _time_in_part(part)]
        found += [con.name for con in self.constraints if getattr(con, "coulomb", None) or _time_in_rows(con)]
        return found + self._inelastic()

    def _inelastic(self, p=None):
        """The names of the limits and contacts whose impacts lose energy (restitution below 1
        at the parameter values ``p``, default the model's)."""
        p = self.parameter_values if p is None else p
        return [u.name for u in self.unilaterals if u.restitution_at(self, p) < 1]


_DEFAULT_DATA = MEMO.table("default data", DEFAULT_DATA_KEPT)


def _joint_kinematics(system):
    """``System.joint_kinematics`` made anew."""
    found = {c.name: JointKinematics(c.name, c.joint_kind, *c.parts[:1], c.frames[0], c.parts[1], c.frames[1],
                                     c.report_frame, system)
             for c in system.constraints if isinstance(c, Joint)}
    parts = {p.name: p for p in system.parts}
    for robot in system.robots:
        if robot.floating:
            root = parts[robot.parts[robot.description.root]]
            frame = root.frames[LINK_FRAME]
            world = Frame("world", "origin", sp.zeros(3, 1), sp.eye(3))
            name = f"{robot.prefix}root_joint"
            found[name] = JointKinematics(name, "free", None, world, root, frame, frame, system)
    return found


def _coordinate_groups(parts):
    """One label per coordinate, equal for the coordinates that move together (a part's
    ``groups``: a point's x, y, z, a quaternion's four numbers), for projection.py's metric."""
    labels, start = [], 0
    for part in parts:
        group = {c: start + k for k, members in enumerate(part.groups) for c in members}
        labels += [group.get(c, start + len(part.groups) + i) for i, c in enumerate(part.coordinates)]
        start += len(part.groups) + len(part.coordinates)
    return np.array(labels)


@MEMO.function(256)
def _working_forces(system, p):
    """System.working_forces at the parameter values p (a tuple): asked by every run, and
    sympy's zero tests cost milliseconds on a robot's actuators."""
    values = {symbol: sp.Float(v) for symbol, v in zip(system.parameter_symbols, p)}
    found = [e.name for e in system.forces
             if not (e.conservative or e.idle_at(values)) or T_SYMBOL in e.V.free_symbols]
    found += [part.name for part in system.parts if part.working or _time_in_part(part)]
    found += [con.name for con in system.constraints if getattr(con, "coulomb", None)
              or any(not sp.sympify(x).xreplace(values).is_zero for x in con.C.values()) or _time_in_rows(con)]
    return tuple(found + system._inelastic(np.array(p)))


@MEMO.function(4096)
def _time_in_part(part):
    """Whether the part's T or V holds t (parts shared from a template hold neither)."""
    own = part.__dict__.get("_symbolic")
    return bool(own) and any(x.has(T_SYMBOL) for x in own[2:])


@MEMO.function(4096)
def _time_in_rows(con):
    """Whether the constraint's b or velocity residual ψ holds t: a prescribed motion
    (placed joint rows hold neither)."""
    own = con.__dict__.get("_symbolic")
    return bool(own) and any(x.has(T_SYMBOL) for x in (*own[1], *(own[4] if own[4] is not None else ())))
