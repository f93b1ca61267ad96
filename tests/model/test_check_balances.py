"""Balances a person can read: ``mbsynth check`` names what a balance is physically (a
torque about a body's axis, a force along an axis) with its value at the state, and
prints the equation with short decimals, not the rationals of a numeric null vector."""

import json
import re
import time

import numpy as np
import pytest
import sympy as sp

from mbsynth.analysis.diagnose import diagnose
from mbsynth.cli import main
from mbsynth.model.balances import SYMBOLIC_SIZE_MAX, readable
from mbsynth.model.flexible.reduction import craig_bampton
from mbsynth.model.parts import FlexibleBody
from mbsynth.model.parts.flexible_body import coordinates
from mbsynth.model.system import System
from mbsynth.core.expressions import parse
from mbsynth.core.kinematics import rpy_matrix

from tests.helpers.flexible_beams import truss  # the FE tests' point-mass truss: a solid

L = 0.8
TILT = rpy_matrix(0.4, 0.3, 0.0)  # the rod's axes: not the world's, so its null direction is numeric
END = TILT @ [0, 0, L / 2]

# models/mechanisms/massless_rod.yaml's rod and particles, tilted, with a torque about the rod's own axis
ROD = f"""\
name: massless_rod_spun
parameters: {{m1: 0.7, m2: 1.9, L: {L}, g: 9.81, tau: {{tau}}}}
gravity: [0, 0, -g]
parts:
  p1: {{type: particle, mass: m1, initial: {{position: {END.tolist()}}}}}
  p2: {{type: particle, mass: m2, initial: {{position: {(-END).tolist()}}}}}
  rod:
    type: rigid_body
    mass: 0
    inertia: [0, 0, 0]
    frames:
      end1: {{position: [0, 0, L/2]}}
      end2: {{position: [0, 0, -L/2]}}
    initial: {{rpy: [0.4, 0.3, 0]}}
joints:
  - {{name: end1, type: spherical, parent: rod.end1, child: p1}}
  - {{name: end2, type: spherical, parent: rod.end2, child: p2}}
forces:
  - {{name: spin, type: torque, part: rod, value: [0, 0, tau], axes: body}}
"""

# a massless particle pushed along the world's y axis, held on that axis by a spring
PUSHED = """\
name: pushed
parameters: {k: 10.0, F: 2.5}
parts:
  bead:
    type: particle
    mass: 0
    frames: {c: {}}
    initial: {position: [0, 0.1, 0]}
constraints:
  - {name: on_y, holonomic: bead.x}
  - {name: level, holonomic: bead.z}
forces:
  - {name: push, type: force, at: bead.c, value: [0, F, 0]}
"""


def check(tmp_path, capsys, text, *flags):
    path = tmp_path / "model.yaml"
    path.write_text(text)
    code = main(["check", str(path), *flags])
    return code, capsys.readouterr().out


@pytest.mark.parametrize("tau", [0.3, -1.75])
def test_the_axial_torque_on_a_massless_rod_is_named_with_its_value(tmp_path, capsys, tau):
    code, out = check(tmp_path, capsys, ROD.replace("{tau}", str(tau)))
    assert code == 1
    (line,) = [x for x in out.splitlines() if "balance needed" in x]
    value = float(re.search(r"torque about rod's z axis: (\S+) ≠ 0", line).group(1))
    assert value == pytest.approx(tau, rel=1e-6)  # the model's torque, about the rod's own z axis
    assert not re.search(r"\d{8,}", out), out  # no rationals of many digits (was 23-digit ones)


def test_the_printed_equation_is_the_exact_balance_rounded(tmp_path, capsys):
    """The readable equation agrees with the exact one (--json ``equation``) at random
    states to the rounding of its numbers (6 digits)."""
    text = ROD.replace("{tau}", "0.3")
    _, out = check(tmp_path, capsys, text)
    printed = out.splitlines()[[i for i, x in enumerate(out.splitlines()) if "balance needed" in x][0] + 1]
    _, report = check(tmp_path, capsys, text, "--json")
    (balance,) = json.loads(report)["balances"]
    assert printed.strip().startswith(balance["readable"]) and len(balance["readable"]) < 160
    names = ["rod.qw", "rod.qx", "rod.qy", "rod.qz", "tau"]
    symbols = {name: sp.Symbol(name) for name in names}
    exact, rounded = (sp.lambdify(list(symbols.values()), parse(e.split("=")[0], symbols))
                      for e in (balance["equation"], balance["readable"]))
    rng = np.random.default_rng(1)
    for x in rng.normal(size=(5, 5)):
        assert rounded(*x) == pytest.approx(exact(*x), rel=1e-5)
    assert balance["effort"]["name"] == "torque about rod's z axis"


def test_a_force_on_a_massless_particle_is_named_along_its_world_axis(tmp_path, capsys):
    code, out = check(tmp_path, capsys, PUSHED)
    assert code == 1
    assert "balance needed: force on bead along the world's y axis: 2.5 ≠ 0" in out


@pytest.mark.parametrize("expression, text", [
    (sp.Rational(21135152575518886175783, 34162101276832371106912) * sp.Symbol("x"), "0.618672*x"),
    (sp.Symbol("x") / 3 - 2 * sp.Symbol("y"), "0.333333*x - 2*y"),
    (sp.Symbol("x") + sp.Rational(1, 10**12) * sp.Symbol("y"), "x"),  # a term 1e-12 of the largest: rounding
    (sp.Integer(3) * sp.Symbol("x") * (sp.Symbol("x") + 2 * sp.Symbol("y")), "6*x*(0.5*x + y)"),
])
def test_readable_rounds_numbers_and_drops_negligible_terms(expression, text):
    assert readable(expression) == text


def test_a_balance_too_large_to_write_is_reported_by_its_value_in_bounded_time():
    """A flexible part whose reduced coordinates repeat its frame's rotation (a solid, 3 DOFs
    per node, reduced by Craig–Bampton at three nodes and held at one: built through the API,
    which the loader refuses): its balances are expressions of tens of thousands of nodes, too
    large for sympy's factor, count_ops and printing. ``diagnose`` ends in bounded time and
    gives each balance by its value at the state, the direction's w · (Q + C) of
    ``System.evaluate``: zero to rounding at the undeformed state, where each indeterminate
    direction is the frame's rotation undone by the constraint modes' rigid one (no node moves,
    no force does work), whatever the velocities."""
    reduction = craig_bampton(truss(), [0, 1, 2], count=0).hold(0)
    q = [sp.Symbol(f"blob.{c}") for c in coordinates(reduction.size)]
    qd = [sp.Symbol(f"blob.{c}_dot") for c in coordinates(reduction.size)]
    part = FlexibleBody("blob", q, qd, reduction, sp.Matrix([0, 0, -9.81]), [])
    system = System.build("solid", [part], part.own_constraints(q, qd, []), q, qd, {})
    q0, qd0 = system.initial_state()
    qd0 = np.random.default_rng(3).normal(size=qd0.size)
    start = time.perf_counter()
    report = diagnose(system, q=q0, qd=qd0)
    assert time.perf_counter() - start < 60
    assert not report.unique and report.balances
    arrays = system.evaluate(0.0, q0, qd0)
    force = arrays.Q + arrays.C
    for balance in report.balances:
        assert balance["readable"] == balance["equation"]
        assert f"more than {SYMBOLIC_SIZE_MAX} symbols and operations, is not written out" in balance["readable"]
        w = np.array([balance["direction"].get(c, 0.0) for c in system.coordinates])
        value = float(re.search(r"direction, (\S+) at this state", balance["readable"]).group(1))
        assert abs(value) < 1e-9 * np.abs(force).max() and abs(w @ force) < 1e-9 * np.abs(force).max()
