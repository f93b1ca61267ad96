"""Outputs: named quantities a model declares, evaluated along a run.

    outputs:
      elbow: arm_elbow_joint.angle          # an expression of t, parameters, coordinates,
                                            #   velocities (part.c_dot) and joint values
      hinge_load: {reaction: hinge.force}   # a joint's force or torque (System.reactions),
                                            #   or a constraint's multipliers
      tip: {position: rod.tip}              # a frame's origin in the world (x, y, z)
      tip_velocity: {velocity: rod.tip}     # its velocity in the world
      kinetic: {energy: kinetic}            # kinetic, potential or total
      push: {contact: floor.force}          # a contact's or limit's normal force λ (0 while open)
      hits: {contact: floor.impulse}        #   and its normal impulses since the previous row
      drag: {contact: floor.friction}       #   and its friction force (world x, y, z; 0 while open)

An output with several components gives one column each, named ``tip[x]``, ``tip[y]``,
``tip[z]`` (``load[0]``, … for multipliers). Expressions, positions and velocities are
compiled together into one function of the state; reactions need the motion and are
computed from it (reactions.py). Contact forces and impulses come from the run
(analysis/impacts.py: the held gaps' forces, the impulses of its events), handed to
``evaluate`` as ``contacts``. An output that evaluates to inf or NaN is written as it
is, with a warning (logged once per output and run) naming it and the first such time.
"""

import logging
from dataclasses import dataclass

import numpy as np
import sympy as sp

from ..core.errors import ModelError
from ..symbolic.derive import T_SYMBOL, compile_function, time_derivative
from .data import workspace

AXES = ("x", "y", "z")
BUILT_IN_COLUMNS = ("t", "energy")  # a trajectory file's columns besides the coordinates and velocities
ENERGIES = ("kinetic", "potential", "total")
REACTION_PARTS = ("force", "torque", "multipliers")
CONTACT_PARTS = ("force", "impulse", "friction")
NO_CONTACT = (0.0, 0.0, (0.0, 0.0, 0.0))  # a gap neither held nor struck since the previous row

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Output:
    """One declared output: ``kind`` (expression, reaction, position, velocity, energy),
    the sympy ``expressions`` of its components (expression, position, velocity), and for
    a reaction its ``constraint`` and ``part`` (force, torque, multipliers), for an energy
    which one (``part``)."""

    name: str
    kind: str
    expressions: tuple = ()
    constraint: str = ""
    part: str = ""
    size: int = 1

    @property
    def columns(self):
        if self.size == 1 and self.kind in ("expression", "energy", "contact"):
            return [self.name]
        labels = AXES if self.kind in ("position", "velocity", "contact") or self.part in ("force", "torque") \
            else range(self.size)
        return [f"{self.name}[{label}]" for label in labels]


def expression_output(name, expr):
    return Output(name, "expression", (sp.sympify(expr),))


def frame_output(name, kind, part, frame, q, qd):
    """The world position or velocity of ``frame`` on ``part`` (None: the world)."""
    position = sp.Matrix(frame.position) if part is None else part.frame_position(frame)
    if kind == "velocity":
        position = sp.Matrix([time_derivative(x, q, qd) for x in position])
    return Output(name, kind, tuple(position), size=3)


def reaction_output(name, constraint, which):
    """``which`` (force, torque or multipliers) of ``constraint``'s reaction."""
    if which not in REACTION_PARTS:
        raise ModelError(f"output '{name}': a reaction is '<constraint>.force', '.torque' or '.multipliers', "
                         f"not '.{which}'")
    if which != "multipliers" and not hasattr(constraint, "joint_kind"):
        raise ModelError(f"output '{name}': '{constraint.name}' is no joint: it has multipliers, not a {which}")
    return Output(name, "reaction", constraint=constraint.name, part=which,
                  size=constraint.size if which == "multipliers" else 3)


def contact_output(name, gap, which):
    """``which`` (force, impulse or friction) of the unilateral gap named ``gap`` (a contact
    or a joint's limit): its normal force λ at each row (0 while it is open), the sum of its
    normal impulses (impact and contact events) since the previous row, or its friction
    force in the world (x, y, z; 0 while open or without friction)."""
    if which not in CONTACT_PARTS:
        raise ModelError(f"output '{name}': a contact output is '<contact>.force', '.impulse' or '.friction', "
                         f"not '.{which}'")
    return Output(name, "contact", constraint=gap, part=which, size=3 if which == "friction" else 1)


def energy_output(name, which):
    if which not in ENERGIES:
        raise ModelError(f"output '{name}': energy is one of {', '.join(ENERGIES)}, not {which!r}")
    return Output(name, "energy", part=which)


class OutputEvaluator:
    """The columns of a model's outputs at states of a run, computed with ``data`` (a Data,
    data.py: its parameter values; or a model: its default-path Data)."""

    def __init__(self, data):
        self.data = data = workspace(data)
        system = data.model
        self.outputs = tuple(system.outputs)
        self.names = [c for o in self.outputs for c in o.columns]
        exprs = [e for o in self.outputs for e in o.expressions]
        args = (T_SYMBOL, list(system.q_symbols), list(system.qd_symbols), list(system.parameter_symbols))
        self._compiled = compile_function(args, [sp.Matrix(exprs)]) if exprs else None
        self.needs_reactions = any(o.kind == "reaction" for o in self.outputs)
        self._not_finite = set()  # the outputs already warned of

    def __bool__(self):
        return bool(self.outputs)

    def evaluate(self, t, q, qd, motion=None, contacts=None):
        """One row: every output's columns at (t, q, q̇); ``motion`` (System.motion at that
        state) for reactions, computed when not given; ``contacts`` ({gap name: (force,
        impulse, friction)}, the run's; a gap not in it has neither) for contact outputs."""
        data, p = self.data, self.data.parameter_values
        compiled = iter(self._compiled(t, q, qd, p)[0].ravel()) if self._compiled else iter(())
        reactions = None
        if self.needs_reactions:
            reactions = data.reactions(t, q, qd, motion)
        energies = None
        row = []
        for output in self.outputs:
            if output.kind == "reaction":
                row += list(getattr(reactions[output.constraint], output.part))
            elif output.kind == "contact":
                value = (contacts or {}).get(output.constraint, NO_CONTACT)[CONTACT_PARTS.index(output.part)]
                row += list(value) if output.size > 1 else [value]
            elif output.kind == "energy":
                energies = data.energy(t, q, qd) if energies is None else energies
                kinetic, potential = energies
                row.append({"kinetic": kinetic, "potential": potential, "total": kinetic + potential}[output.part])
            else:
                row += [next(compiled) for _ in output.expressions]
        row = np.array(row, dtype=float)
        if not np.isfinite(row).all():
            self._warn_not_finite(t, row)
        return row

    def _warn_not_finite(self, t, row):
        """Log each output with an inf or NaN column in ``row`` at t, the first time only."""
        start = 0
        for output in self.outputs:
            values = row[start:start + len(output.columns)]
            start += len(output.columns)
            if output.name not in self._not_finite and not np.isfinite(values).all():
                self._not_finite.add(output.name)
                shown = values[0] if output.columns == [output.name] else ", ".join(
                    f"{c} = {v}" for c, v in zip(output.columns, values))
                log.warning("output '%s' is not finite at t = %.6g: %s (written as it is; not repeated for this "
                            "output)", output.name, t, shown)

    def table(self, t, q, qd):
        """The rows at each time of a trajectory (arrays t, q, q̇), one per row."""
        return np.array([self.evaluate(ti, qi, qdi) for ti, qi, qdi in zip(t, q, qd)]).reshape(len(t), len(self.names))
