"""A model's workspace: ``data = system.data(path=)``, as Pinocchio's Data beside its Model.

A System (system.py) is the model, a value: parts, constraints, forces, the coordinate
layout, parameter names and default values. What a computation keeps between calls lives
in a Data made from it (``data.model`` is that System):

- the parameter values, an array ``p`` in the model's parameter order (a controller writes
  them: ``set_parameters``; parameters defined by expressions of others follow);
- its path, chosen when it is made: "compiled" (the kernels of mbsynth.compiled where they
  cover the model, built at the first use and waited for) or "kkt" ((2.14) in its KKT form
  throughout); by default ``mbsynth.compiled.background.default_path()`` ("compiled";
  "kkt" where MBSYNTH_COMPILED=off). The path never depends on what a background build or a
  file on disk happens to have finished, so equal models give equal results;
- the Evaluator of the constraints and parts (evaluation.py) and the compiled Engine at
  its parameter values.

The algorithms compute with a Data (``data.motion``, ``data.reactions``, …; the run loop,
projection.py, outputs.py, linearize, equilibrium, modes and steady motions): they read the
model's description from ``data.model`` and the parameter values from the Data, never from
the model. ``workspace`` gives a model's default-path Data where a function is handed a
model, ``model_of`` the model of either.

What models of one structure share (``Shared``: the compiled Template, the Evaluators, the
joint kinematics, linearize's derivatives) is kept in the one cache (core/memo.py): it
changes how fast a Data is made, never what it computes.
"""

import functools
import warnings
from dataclasses import dataclass

import numpy as np

from ..compiled import background
from ..core import equations, solvers
from ..core.memo import MEMO
from ..core.errors import SolveError
from ..core.values import read_only
from . import friction, reactions
from .evaluation import Evaluator
from .joint_values import JointValuesBatch

UNSET = object()  # a Data's engine before its first use
PATHS = ("compiled", "kkt")  # the compiled kernels (mbsynth.compiled) where they cover the model, or (2.14)'s KKT form
STRUCTURES_KEPT = 16  # model structures whose compiled Template and evaluators MEMO keeps
# the KKT form of (2.14), solved on the Data's path, or the literal pseudo-inverse of (2.14)
METHODS = {"kkt": solvers.kkt_acceleration, "reference": equations.constrained_acceleration}
OLD_METHODS = {"fast": "kkt"}  # old name -> the method's name (a DeprecationWarning)


@dataclass(frozen=True)
class Assembly:
    """The arrays of (2.1), (2.4) and (2.6) for the whole system at one state."""

    M: np.ndarray
    Q: np.ndarray
    A: np.ndarray
    b: np.ndarray
    C: np.ndarray


class Shared:
    """What the models of one structure (equal parts, constraints and forces, the same
    parameter names; any parameter values) share, kept in ``MEMO``: the compiled Template's
    slot, the Evaluators (one per path), the joint kinematics and the derivatives of
    linearize. Made from the first model of the structure asked for."""

    def __init__(self, system):
        self.system = system
        self.compiled = background.TemplateSlot()
        self.evaluators = {}
        self.joint_kinematics = None
        self.derivatives = None

    def evaluator(self, compiled):
        found = self.evaluators.get(compiled)
        if found is None:
            found = Evaluator(self.system, compiled)
            self.evaluators[compiled] = found
        return found


def workspace(model_or_data):
    """The Data an algorithm computes with: ``model_or_data`` itself when it is a Data, a
    model's Data of the default path otherwise (its parameter values, ``System._data``)."""
    return model_or_data if isinstance(model_or_data, Data) else model_or_data._data


def model_of(model_or_data):
    """The model (System) of ``model_or_data``, a System or a Data: for what reads the
    model's description alone (coordinates, parts, names)."""
    return model_or_data.model if isinstance(model_or_data, Data) else model_or_data


def shared(system):
    """The Shared of ``system``'s structure (``System.structure``), from ``MEMO``."""
    return _STRUCTURES.get(system.structure, lambda: Shared(system))


_STRUCTURES = MEMO.table("model structures", STRUCTURES_KEPT)


class Data:
    """The workspace of computations on ``system`` at its ``parameter_values`` (an array in
    the model's parameter order, read-only: ``set_parameters`` replaces it; ``parameters``:
    the same as {name: value}), on the ``path`` "compiled" or "kkt" (``PATHS``; None:
    ``background.default_path()``)."""

    def __init__(self, system, path=None):
        path = background.default_path() if path is None else path
        if path not in PATHS:
            raise ValueError(f"path must be one of {PATHS}, got {path!r}")
        self.system = self.model = system
        self.path = path
        self.parameter_values = read_only(system.parameter_values)
        self._shared = shared(system)
        self._evaluator = None  # made on first use: a compiled run may never need it
        self._joint_values = None  # joint_values.JointValuesBatch, made on first use
        self._engine = UNSET  # the compiled Engine, made on first use on the compiled path
        # ``acceleration``'s block, rows as compiled/single.py's motion_into writes them (q, q̇, q̈, Qc: its
        # constants, not imported here: single.py loads numba's function types, and with them scipy), and
        # its q̈ row, the array ``acceleration`` returns
        self._block = np.zeros((4, system.n))
        self.qdd = self._block[2]

    def __repr__(self):
        return f"Data({self.system.name!r}, path={self.path!r})"

    @property
    def parameters(self):
        """{name: value} at this Data's parameter values."""
        return dict(zip(self.system.parameters, self.parameter_values.tolist()))

    @property
    def evaluator(self):
        if self._evaluator is None:
            self._evaluator = self._shared.evaluator(self.path == "compiled")
        return self._evaluator

    @property
    def engine(self):
        """The compiled Engine that serves ``motion`` on the compiled path (its Template built
        at the first use, waited for), or None: the KKT path, or a model the kernels do not
        cover."""
        if self._engine is UNSET:
            template = None if self.path == "kkt" else background.template(self.system, self._shared.compiled)
            self._engine = None if template is None else template.engine(self.parameter_values)
        return self._engine

    def set_parameters(self, values):
        """Write new values of some parameters ({name: value}, a controller's at a sample);
        those defined by expressions of others follow. Raises ModelError for an unknown
        name, a non-finite value, or a part whose M or Q the values make unusable
        (``System.resolved_parameters``)."""
        self.parameter_values = read_only(self.system.resolved_parameters(values, self.parameter_values))
        if self._engine is not None and self._engine is not UNSET:
            self._engine = self._engine.template.engine(self.parameter_values)

    def initial_state(self):
        """(q, q̇) from the model's ``initial:`` mapping at this Data's parameter values
        (``System.initial_state``)."""
        return self.system.initial_state(self.parameter_values)

    def _state(self, q, qd):
        return self.system._state(q, qd)

    # ---- the arrays of (2.1), (2.4), (2.6)

    def evaluate(self, t, q, qd):
        """Assemble M (block diagonal), Q, A, b and C at the state (t, q, q̇)."""
        q, qd = self._state(q, qd)
        evaluator = self.evaluator
        p = self.parameter_values
        return Assembly(*evaluator.parts(t, q, qd, p), *evaluator.dense_rows(t, q, qd, p))

    def constraint_rows(self, t, q, qd):
        """A (m × n, scipy.sparse CSR) and b at (t, q, q̇): the rows alone, without M."""
        arrays = self.constraint_arrays(t, q, qd)
        return arrays.A, arrays.b

    def constraint_arrays(self, t, q, qd, sparse=True):
        """A, b, C, φ and φ̇ at (t, q, q̇) from one evaluation of the constraints
        (``evaluation.ConstraintArrays``): A scipy.sparse CSR, or dense (sparse=False), or
        dense where that is faster (sparse=None: few rows and coordinates)."""
        q, qd = self._state(q, qd)
        return self.evaluator.constraints(t, q, qd, self.parameter_values, sparse)

    def constraint_residuals(self, t, q, qd):
        """(φ, φ̇) per row of A: position and velocity residuals (NaN where not defined)."""
        q, qd = self._state(q, qd)
        return self.evaluator.residuals(t, q, qd, self.parameter_values)

    def energy(self, t, q, qd):
        """(kinetic, potential) energy: the parts' T and V plus the force elements' potentials."""
        q, qd = self._state(q, qd)
        return self.evaluator.energies(t, q, qd, self.parameter_values)

    def power(self, t, q, qd):
        """The power of the forces that derive from no potential (``Evaluator.power``): the
        rate at which they change T + V."""
        q, qd = self._state(q, qd)
        return self.evaluator.power(t, q, qd, self.parameter_values)

    def powers(self, times, q, qd):
        """``power`` at each row of (times, q, q̇) (q, q̇: arrays of a row per time)."""
        return self.evaluator.powers(times, np.asarray(q, dtype=float), np.asarray(qd, dtype=float),
                                     self.parameter_values)

    def branch_problems(self, q=None, t=0.0):
        """``System.branch_problems`` at this Data's parameter values."""
        return self.system.branch_problems(q, t, self.parameter_values)

    def part_problems(self, parameters=None):
        """``System.part_problems`` at this Data's parameter values."""
        return self.system.part_problems(parameters, self.parameter_values)

    def check_branches(self, q, t=0.0):
        """Raise SolveError naming the first joint whose frames, at the state q, are in a
        pose the joint does not mean (``System.branch_problems``)."""
        problems = self.branch_problems(q, t)
        if problems:
            raise SolveError(f"model '{self.system.name}': {problems[0][1]}", constraints=[problems[0][0]])

    # ---- the motion (2.14)

    def motion(self, t, q, qd, method="kkt", baumgarte=None, drift=False):
        """The constrained acceleration at (t, q, q̇): a ``Motion`` (``System.motion`` says
        what each argument means) of its own arrays; its ``lam`` is computed when first read."""
        if method in OLD_METHODS:
            warnings.warn(f"method={method!r} is the old name of method={OLD_METHODS[method]!r}", DeprecationWarning,
                          stacklevel=2)
            method = OLD_METHODS[method]
        if method not in METHODS:
            raise ValueError(f"method must be one of {sorted(METHODS)}, got {method!r}")
        engine = self.engine if method == "kkt" and baumgarte is None else None
        found = None if engine is None or (drift and engine.closes_loops) else engine.motion_copied(t, q, qd, drift)
        if found is not None:  # one compiled call, which copies the state too
            motion, q, qd = found
            if motion is None:  # the kernel declined: the exact treatment's
                motion = self._kkt_motion(t, q, qd, method, baumgarte, drift)
        else:  # copies: the state its λ and residual are read at, whatever the caller does to q, q̇
            q, qd = self.system._state_copies(q, qd)
            motion = self._solved(t, q, qd, method, baumgarte, drift, (q, qd))
        return motion.with_multipliers(functools.partial(self._lam, t, q, qd))

    def acceleration(self, t, q, qd):
        """q̈ at (t, q, q̇) alone, ``motion(t, q, qd).qdd`` written into this Data's own array
        ``qdd`` and returned, as Pinocchio's ``aba`` writes ``data.ddq``: the next call
        overwrites it. On the compiled path (a state of float arrays) one compiled call that
        allocates nothing; no λ, residual or uniqueness, and errors as ``motion``'s. Like
        Pinocchio's Data, a Data serves one thread."""
        engine = self.engine
        found = None if engine is None else engine.motion_into(t, q, qd, self._block)
        if found is None:  # not a state of float arrays (or no engine): checked and copied
            self.qdd[:] = self.motion(t, q, qd).qdd
        elif not found[0]:  # the kernel declined: the exact treatment's, at the copies the call made
            self.qdd[:] = self._kkt_motion(t, self._block[0], self._block[1], "kkt", None, False).qdd
        return self.qdd

    def _lam(self, t, q, qd, motion):
        """λ of ``motion`` at (t, q, q̇): ``Motion.lam``'s source (it holds no Motion: no cycle)."""
        return self._multipliers(t, q, qd, motion)[0]

    def _solved(self, t, q, qd, method, baumgarte, drift, kept=None):
        """The Motion of ``motion``, without its multipliers (``kept``: Engine.motion's)."""
        if method == "kkt":
            engine = self.engine
            if engine is not None:
                shift = None if baumgarte is None else self._stabilized(t, q, qd, 0.0, *baumgarte)
                found = engine.motion(t, q, qd, shift, drift, kept)
                if found is not None:
                    return found
        return self._kkt_motion(t, q, qd, method, baumgarte, drift)

    def _kkt_motion(self, t, q, qd, method, baumgarte, drift):
        """The Motion of (2.14) (``method``: its KKT form or the literal pseudo-inverse)
        from the assembled M, Q, A, b, C, without its multipliers."""
        arrays = self.evaluate(t, q, qd)
        b = arrays.b if baumgarte is None else self._stabilized(t, q, qd, arrays.b, *baumgarte)
        off_manifold = (lambda: (self.constraint_residuals(t, q, qd)[0], q)) if drift else None
        system = self.system

        def solve(C):
            return METHODS[method](arrays.M, arrays.Q, arrays.A, b, C, coordinates=system.coordinates,
                                   constraints=system.constraint_names, drift=off_manifold)
        if system.coulomb:  # C depends on q̈ (friction.py)
            return friction.coulomb_motion(system.constraints, arrays, solve, t, q, qd, self.parameter_values)
        return solve(arrays.C)

    def stage_motion(self, baumgarte=None, drift=False, compiled=True):
        """``motion(t, q, q̇, baumgarte=, drift=)`` as a callable for an integrator's stages,
        without ``lam``: the compiled engine's own call where ``motion`` would make it anyway
        (no Baumgarte shift), skipping the checks and bookkeeping of each call. ``compiled``
        False: the KKT path alone (for stages the engine has declined already)."""
        engine = self.engine
        if not compiled:
            return lambda t, q, qd: self._kkt_motion(t, *self._state(q, qd), "kkt", baumgarte, drift)
        if engine is None or baumgarte is not None:
            return lambda t, q, qd: self._solved(t, *self._state(q, qd), "kkt", baumgarte, drift)

        def stage(t, q, qd):
            found = engine.motion(t, q, qd, None, drift)
            return found if found is not None else self._kkt_motion(t, q, qd, "kkt", None, drift)
        return stage

    def motion_batch(self, t, q_batch, qd_batch):
        """(qdd (B × n), unique (B,)) at many states, one per row of ``q_batch`` and
        ``qd_batch`` (t: a number or one per row): the compiled Engine's rows in threads
        (its Template waited for: a batch is worth it), each state it hands back and every
        state of a model it does not cover through ``motion``. A state with no motion raises
        SolveError naming its row."""
        system = self.system
        # no copy of states already in float64 rows (a copy of a large batch costs page faults, serially)
        q, qd = (np.atleast_2d(np.ascontiguousarray(x, dtype=float)) for x in (q_batch, qd_batch))
        q, qd = (x if x.flags.writeable else x.copy() for x in (q, qd))  # the kernels' arrays are writeable
        if q.ndim != 2 or q.shape != qd.shape or q.shape[1] != system.n:
            raise ValueError(f"model '{system.name}' has {system.n} coordinates: q_batch and qd_batch must both "
                             f"have shape (B, {system.n}), got {q.shape} and {qd.shape}")
        count = q.shape[0]
        t = np.broadcast_to(np.asarray(t, dtype=float), (count,)).copy()
        engine = self.engine
        if engine is None:
            qdd, done = np.zeros((count, system.n)), np.zeros(count, dtype=bool)
        else:
            qdd, status = engine.motion_batch(t, q, qd)
            done = status == 0
        unique = done.copy()
        for row in np.flatnonzero(~done):
            try:
                motion = self.motion(t[row], q[row], qd[row])
            except SolveError as err:
                raise SolveError(f"state {row} of the batch: {err}", constraints=err.constraints,
                                 coordinates=err.coordinates) from None
            qdd[row], unique[row] = motion.qdd, motion.unique
        return qdd, unique

    def _stabilized(self, t, q, qd, b, alpha, beta):
        phi, psi = self.constraint_residuals(t, q, qd)
        return b - 2 * alpha * np.nan_to_num(psi) - beta**2 * np.nan_to_num(phi)

    # ---- what the motion implies: multipliers, reactions, joint values

    def _multipliers(self, t, q, qd, motion, arrays=None):
        """(λ, dependent rows) of ``motion`` at (t, q, q̇): Qc − C = Aᵀλ (reactions.py)."""
        arrays = self.evaluate(t, q, qd) if arrays is None else arrays
        C = arrays.C if motion.C is None else motion.C
        return reactions.multipliers(arrays.A, arrays.M @ motion.qdd - arrays.Q - C)

    def joint_values(self, t, q, qd, qdd=None):
        """{joint name: JointValues(position, rate, acceleration)} (``System.joint_values``)."""
        q, qd = self._state(q, qd)
        qdd = None if qdd is None else np.asarray(qdd, dtype=float).ravel()
        if self._joint_values is None:
            self._joint_values = JointValuesBatch((k for k in self.system.joint_kinematics().values()
                                                   if k.position_names), self.path == "compiled")
        return self._joint_values(t, q, qd, qdd, self.parameter_values)

    def reactions(self, t, q, qd, motion=None):
        """{constraint name: reactions.Reaction} at (t, q, q̇) for ``motion`` (by default this
        Data's motion there): ``System.reactions`` says what they hold."""
        q, qd = self._state(q, qd)
        motion = self.motion(t, q, qd) if motion is None else motion
        arrays = self.evaluate(t, q, qd)
        lam, dependent = self._multipliers(t, q, qd, motion, arrays)
        kinematics, p = self.system.joint_kinematics(), self.parameter_values
        out, row = {}, 0
        for con in self.system.constraints:
            rows = slice(row, row + con.size)
            force = torque = None
            if con.name in kinematics:
                k = kinematics[con.name]
                g = self._joint_force(con, lam[rows], t, q, qd)
                force, torque = reactions.wrench(k.frame(t, q, qd, p), con.parts[1].idle_directions(q[k.child_indices]),
                                                 g[k.child_indices])
            out[con.name] = reactions.Reaction(lam[rows].copy(), bool(dependent[rows].any()), force, torque)
            row += con.size
        merged = {joint: link for robot in self.system.robots for joint, link in robot.welded_joints.items()}
        return reactions.Reactions(out, merged)

    def _joint_force(self, joint, lam, t, q, qd):
        """The generalized force of ``joint``: its rows' Aᵀλ, its C (viscous and, at the
        load λ gives, Coulomb friction: friction.py) and its force elements."""
        p = self.parameter_values
        g = np.zeros(self.system.n)
        a, _, c = joint.evaluate(t, q, qd, p)
        g[joint.indices] += a.T @ lam + c
        if joint.coulomb is not None:
            w, direction = joint.coulomb.evaluate(t, q, qd, p)
            g[joint.coulomb.indices] -= np.sign(w) * np.linalg.norm(lam[joint.coulomb.load_rows]) * direction
        for element in self.system.forces:
            if element.joint == joint.name:
                g[element.indices] += element.evaluate(t, q, qd, p)
        return g

