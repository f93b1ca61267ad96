"""Hard numerics for ``check`` and (2.14): wildly mixed scales, redundant loops,
constraints that become dependent at one configuration, near-singular masses. The
verdict (Result 3) stays right against a hand analysis, or the report says it is
uncertain; q̈ agrees with hand-derived equations of motion."""

import json

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.cli import main
from mbsynth.analysis.diagnose import diagnose
from mbsynth.core.tolerances import RANK_RTOL, VERDICT_MARGIN

G = 9.81


def accelerations(system, report):
    """q̈ of the report (reference (2.14)) and of the fast solver, as arrays."""
    q, qd = system.initial_state()
    return np.array(list(report.qdd.values())), system.motion(0.0, q, qd).qdd


MIXED = """\
# a 1 t cart with a 1 g bob on a 1 mm string; beside it a 2 g bob on a 1 km rope hung 2 km up
parameters: {Mc: 1000.0, m: 0.001, L: 0.001, mb: 0.002, R: 1000.0, h: 2000.0, g: 9.81, th0: 0.3, ph0: 0.2}
gravity: [0, 0, -g]
world: {frames: {top: {position: [0, 0, h]}}}
parts:
  cart: {type: lagrangian, coordinates: [X], T: 0.5*Mc*X_dot**2}
  bob: {type: particle, mass: m, initial: {position: [L*sin(th0), 0, -L*cos(th0)]}}
  big: {type: particle, mass: mb, initial: {position: [R*sin(ph0), 0, h - R*cos(ph0)]}}
constraints:
  - {name: string, holonomic: (bob.x - cart.X)**2 + bob.z**2 - L**2}
joints:
  - {name: rope, type: distance, parent: world.top, child: big, length: R}
"""


def test_grams_and_tonnes_millimetres_and_kilometres_in_one_model():
    """Cart–pendulum at rest (X, θ): (Mc + m) Ẍ + m L cos θ θ̈ = 0, m L cos θ Ẍ + m L² θ̈ =
    −m g L sin θ; the bob at (X + L sin θ, −L cos θ). Rope pendulum at rest: q̈ = −g sin φ
    (cos φ, 0, sin φ). With rows of A scaled to unit norm the lengths (1e-3 and 1e3) leave
    no trace in the conditioning: only the mass ratio m/Mc = 1e-6 does."""
    Mc, m, L, th, ph = 1000.0, 0.001, 0.001, 0.3, 0.2
    system = mb.loads(MIXED)
    report = diagnose(system)
    assert report.unique and report.rank_Mhat == system.n == 7 and report.warnings == []
    assert report.condition < 10 * Mc / m and report.verdict_margin > 1e4
    theta = -G * np.sin(th) / (L * (1 - m * np.cos(th) ** 2 / (Mc + m)))
    X = -m * L * np.cos(th) * theta / (Mc + m)
    expected = [X, X + L * np.cos(th) * theta, 0, L * np.sin(th) * theta,
                -G * np.sin(ph) * np.cos(ph), 0, -G * np.sin(ph) ** 2]
    for qdd in accelerations(system, report):
        np.testing.assert_allclose(qdd, expected, rtol=1e-8, atol=1e-12 * abs(theta))
    assert abs(expected[0]) < 1e-5 < abs(expected[1]) and abs(theta) > 1e3  # the scales do differ


PARALLELOGRAM = """\
# a parallelogram linkage (crank, rocker and a middle link, all of length a, on pivots
# b/2 apart) with the coupler of length b: the middle link repeats a constraint, so
# one joint's rows are redundant at every configuration
parameters: {a: 0.5, b: 1.2, m1: 0.7, I1: 0.02, m2: 1.5, I2: 0.3, g: 9.81, th: 0.8}
gravity: [0, -g, 0]
world:
  frames: {O: {position: [0, 0, 0]}, E: {position: [b/2, 0, 0]}, D: {position: [b, 0, 0]}}
parts:
  crank: &link
    type: planar_body
    mass: m1
    inertia: I1
    frames: {base: {position: [-a/2, 0, 0]}, tip: {position: [a/2, 0, 0]}}
    initial: {position: ['a/2*cos(th)', 'a/2*sin(th)'], theta: th}
  middle:
    <<: *link
    initial: {position: ['b/2 + a/2*cos(th)', 'a/2*sin(th)'], theta: th}
  rocker:
    <<: *link
    initial: {position: ['b + a/2*cos(th)', 'a/2*sin(th)'], theta: th}
  coupler:
    type: planar_body
    mass: m2
    inertia: I2
    frames: {A: {position: [-b/2, 0, 0]}, F: {position: [0, 0, 0]}, B: {position: [b/2, 0, 0]}}
    initial: {position: ['b/2 + a*cos(th)', 'a*sin(th)']}
joints:
  - {name: O, type: revolute, parent: world.O, child: crank.base}
  - {name: E, type: revolute, parent: world.E, child: middle.base}
  - {name: D, type: revolute, parent: world.D, child: rocker.base}
  - {name: A, type: revolute, parent: crank.tip, child: coupler.A}
  - {name: F, type: revolute, parent: middle.tip, child: coupler.F}
  - {name: B, type: revolute, parent: rocker.tip, child: coupler.B}
"""


def test_a_redundant_loop_gives_dependent_rows_and_the_right_motion():
    """One degree of freedom θ: the three links turn together, the coupler translates on a
    circle of radius a. (3 (I1 + m1 a²/4) + m2 a²) θ̈ = −(3 m1 a/2 + m2 a) g cos θ at rest."""
    system = mb.loads(PARALLELOGRAM)
    report = diagnose(system)
    assert report.unique and report.warnings == []
    assert report.rank_A == system.n - 1 < report.m  # 12 coordinates, 1 degree of freedom, dependent rows
    a, m1, I1, m2, th = 0.5, 0.7, 0.02, 1.5, 0.8
    theta = -(3 * m1 * a / 2 + m2 * a) * G * np.cos(th) / (3 * (I1 + m1 * a**2 / 4) + m2 * a**2)
    link = [-a / 2 * np.sin(th) * theta, a / 2 * np.cos(th) * theta, theta]
    expected = link * 3 + [-a * np.sin(th) * theta, a * np.cos(th) * theta, 0]
    for qdd in accelerations(system, report):
        np.testing.assert_allclose(qdd, expected, rtol=1e-9, atol=1e-12)


def parallelogram_four_bar(angle, a=0.4, b=1.0, m1=0.5, m2=1.2, m3=0.9, I2=0.15):
    """A parallelogram four-bar (crank = rocker = a, coupler = ground = b) with crank and
    rocker at ``angle``; at 0 it lies flat along x: a change point, where the rows of the
    four joints become dependent."""
    return f"""\
parameters: {{a: {a}, b: {b}, m1: {m1}, m2: {m2}, m3: {m3}, I2: {I2}, g: 9.81, th: {angle}}}
gravity: [0, -g, 0]
world: {{frames: {{O: {{position: [0, 0, 0]}}, D: {{position: [b, 0, 0]}}}}}}
parts:
  crank:
    {{type: planar_body, mass: m1, inertia: m1*a**2/12,
     initial: {{position: ['a/2*cos(th)', 'a/2*sin(th)'], theta: th}},
     frames: {{O: {{position: [-a/2, 0, 0]}}, B: {{position: [a/2, 0, 0]}}}}}}
  coupler:
    {{type: planar_body, mass: m2, inertia: I2, initial: {{position: ['a*cos(th) + b/2', 'a*sin(th)']}},
     frames: {{B: {{position: [-b/2, 0, 0]}}, C: {{position: [b/2, 0, 0]}}}}}}
  rocker:
    {{type: planar_body, mass: m3, inertia: m3*a**2/12,
     initial: {{position: ['b + a/2*cos(th)', 'a/2*sin(th)'], theta: th}},
     frames: {{D: {{position: [-a/2, 0, 0]}}, C: {{position: [a/2, 0, 0]}}}}}}
joints:
  - {{name: ground_O, type: revolute, parent: world.O, child: crank.O}}
  - {{name: crank_coupler, type: revolute, parent: crank.B, child: coupler.B}}
  - {{name: coupler_rocker, type: revolute, parent: coupler.C, child: rocker.C}}
  - {{name: ground_D, type: revolute, parent: world.D, child: rocker.D}}
"""


def test_a_four_bar_at_its_change_point_keeps_a_unique_verdict_and_the_right_motion():
    """Flat, the linkage has two instantaneous degrees of freedom, the crank and rocker
    angles θ1, θ3 (the coupler's ends rise by a θ̈1 and a θ̈3). At rest Gauss's principle
    gives the 2 × 2 system M2 θ̈ = F2 with M2 = [[I1 + m2 a²/4 + I2 a²/b², m2 a²/4 −
    I2 a²/b²], [sym., I3 + m2 a²/4 + I2 a²/b²]], F2 = −g a/2 [m1 + m2, m3 + m2]
    (I1, I3 about the pivots)."""
    a, b, m1, m2, m3, I2 = 0.4, 1.0, 0.5, 1.2, 0.9, 0.15
    system = mb.loads(parallelogram_four_bar(0))
    report = diagnose(system)
    assert report.unique and report.rank_Mhat == 9 and report.warnings == []
    assert report.rank_A == report.m - 1  # one row dependent here only
    I1, I3, k = m1 * a**2 / 3, m3 * a**2 / 3, I2 * a**2 / b**2
    M2 = np.array([[I1 + m2 * a**2 / 4 + k, m2 * a**2 / 4 - k], [m2 * a**2 / 4 - k, I3 + m2 * a**2 / 4 + k]])
    t1, t3 = np.linalg.solve(M2, -G * a / 2 * np.array([m1 + m2, m3 + m2]))
    expected = [0, a / 2 * t1, t1, 0, a / 2 * (t1 + t3), a * (t3 - t1) / b, 0, a / 2 * t3, t3]
    for qdd in accelerations(system, report):
        np.testing.assert_allclose(qdd, expected, rtol=1e-9, atol=1e-12)
    assert diagnose(mb.loads(parallelogram_four_bar(0.05))).rank_A == report.m  # independent again off it


SLIDER_CRANK = """\
parameters: {a: 0.3, b: 0.8, m1: 0.6, m2: 0.9, m3: 1.5, I3: 0.02, g: 9.81}
gravity: [0, -g, 0]
world: {frames: {O: {position: [0, 0, 0]}, rail: {position: [0, 0, 0], axis: [1, 0, 0]}}}
parts:
  crank:
    {type: planar_body, mass: m1, inertia: m1*a**2/12, initial: {position: [a/2, 0]},
     frames: {O: {position: [-a/2, 0, 0]}, B: {position: [a/2, 0, 0]}}}
  rod:
    {type: planar_body, mass: m2, inertia: m2*b**2/12, initial: {position: [a + b/2, 0]},
     frames: {B: {position: [-b/2, 0, 0]}, C: {position: [b/2, 0, 0]}}}
  slider:
    {type: planar_body, mass: m3, inertia: I3, initial: {position: [a + b, 0]},
     frames: {pin: {position: [0, 0, 0]}, guide: {position: [0, 0, 0], axis: [1, 0, 0]}}}
joints:
  - {name: ground_O, type: revolute, parent: world.O, child: crank.O}
  - {name: crank_rod, type: revolute, parent: crank.B, child: rod.B}
  - {name: rod_slider, type: revolute, parent: rod.C, child: slider.pin}
  - {name: rail, type: prismatic, parent: world.rail, child: slider.guide}
"""


def test_a_slider_crank_at_top_dead_centre():
    """Crank and rod along the rail, at rest: the slider cannot move (ṡ = 0 for any θ̇), the
    rod turns about the slider's pin at ω = a θ̇/b, so J θ̈ = −(m1 + m2) g a/2 with
    J = m1 a²/3 + m2 a²/3: θ̈ = −3 g/(2 a), whatever the masses."""
    a, b = 0.3, 0.8
    system = mb.loads(SLIDER_CRANK)
    report = diagnose(system)
    assert report.unique and report.warnings == []
    theta = -3 * G / (2 * a)
    expected = [0, a / 2 * theta, theta, 0, a / 2 * theta, -a / b * theta, 0, 0, 0]
    for qdd in accelerations(system, report):
        np.testing.assert_allclose(qdd, expected, rtol=1e-9, atol=1e-12)


def two_strings(offset):
    """A massless point on two strings from (±1, 0), lengths √(1 + offset²), at (0, offset):
    the rows (±1, offset) of A, parallel when offset = 0; the equilibrated A has singular
    values √2/√(1 + offset²) and √2·offset/√(1 + offset²), ratio exactly offset."""
    return mb.loads(f"""\
parameters: {{e: {offset!r}}}
parts:
  p: {{type: lagrangian, coordinates: [x, y], T: 0}}
constraints:
  - {{name: left, holonomic: (p.x + 1)**2 + p.y**2 - 1 - e**2}}
  - {{name: right, holonomic: (p.x - 1)**2 + p.y**2 - 1 - e**2}}
initial: {{p.y: e}}
""")


@pytest.mark.parametrize("offset, unique, warned", [
    (1e-3, True, False),     # margin 1e9: firm
    (1e-11, True, True),     # kept, but only 10 times the cut-off
    (1e-13, False, True),    # dropped, but only 10 times below the cut-off
    (0.0, False, False),     # exactly parallel: firmly not unique
])
def test_strings_that_become_parallel_make_the_verdict_uncertain_then_not_unique(offset, unique, warned):
    report = diagnose(two_strings(offset))
    assert report.unique == unique and report.consistent
    assert bool(report.warnings) == warned
    if offset:
        expected = offset / RANK_RTOL if unique else RANK_RTOL / offset
        assert report.verdict_margin == pytest.approx(expected, rel=1e-3)
    else:
        assert report.indeterminate == [{"p.y": 1.0}]


def masses(ratio):
    return mb.loads(f"""\
parameters: {{m: 2.0, r: {ratio!r}}}
parts:
  p: {{type: lagrangian, coordinates: [x, y], T: 0.5*m*x_dot**2 + 0.5*r*m*y_dot**2, forces: {{x: 3.0, y: 3.0*r}}}}
""")


def test_a_tiny_but_legitimate_mass_is_still_unique_and_exact():
    """Mass ratio 1e-9 (1e3 times the cut-off): unique, not flagged, and q̈ = F/m exactly."""
    report = diagnose(masses(1e-9))
    assert report.unique and report.warnings == []
    assert report.condition == pytest.approx(1e9, rel=1e-9)
    assert report.verdict_margin == pytest.approx(1e-9 / RANK_RTOL, rel=1e-9)
    assert report.verdict_margin > VERDICT_MARGIN
    np.testing.assert_allclose(list(report.qdd.values()), [1.5, 1.5], rtol=1e-12)


def test_a_mass_below_the_tolerance_is_reported_with_the_warning(capsys, tmp_path):
    """Mass ratio 1e-13: counted as zero, so the force on it meets no mass; the report says
    so, and warns that the verdict lies within 10 of the cut-off."""
    report = diagnose(masses(1e-13))
    assert not report.unique and report.rank_Mhat == 1 and report.condition == pytest.approx(1e13, rel=1e-6)
    assert report.verdict_margin == pytest.approx(10, rel=1e-6)
    assert len(report.warnings) == 1 and "may in fact be unique" in report.warnings[0]
    model = tmp_path / "tiny.yaml"
    model.write_text("parameters: {m: 2.0, r: 1.0e-13}\nparts:\n  p: {type: lagrangian, coordinates: "
                     "[x, y], T: 0.5*m*x_dot**2 + 0.5*r*m*y_dot**2, forces: {x: 3.0, y: 3.0*r}}\n")
    assert main(["check", str(model), "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["rank_tolerance"] == RANK_RTOL and data["verdict_margin"] == pytest.approx(10, rel=1e-6)
    assert data["condition"] == pytest.approx(1e13, rel=1e-6) and data["warnings"] == report.warnings
    main(["check", str(model)])
    text = capsys.readouterr().out
    assert "condition number of the equilibrated [M; A] = 1e+13" in text and "warning: uncertain verdict" in text
