"""Model files: Lagrange's equations from T and V, constraints from expressions, and
mistakes reported with file:line and the key path."""

import textwrap

import numpy as np
import pytest

import mbsynth as mb

PENDULUM_XY = """\
name: pendulum_xy
parameters: {m: 1.5, L: 2.0, g: 9.81}
parts:
  bob:
    type: lagrangian
    coordinates: [x, y]
    T: 0.5*m*(x_dot**2 + y_dot**2)
    V: m*g*y
constraints:
  - name: rod
    holonomic: bob.x**2 + bob.y**2 - L**2
initial: {bob.x: 1.2, bob.y: -1.6, bob.x_dot: 0.8, bob.y_dot: 0.6}
"""


def loads(text):
    return mb.loads(textwrap.dedent(text), name="model.yaml")


def test_cartesian_pendulum_matches_the_angle_form():
    """A point mass on a rod, in x and y with the holonomic rod constraint, has
    θ̈ = −g/L sin θ and a radial acceleration −L θ̇² (independent closed form)."""
    system = loads(PENDULUM_XY)
    q, qd = system.initial_state()
    L, g = 2.0, 9.81
    theta = np.arctan2(q[0], -q[1])
    theta_dot = (q[0] * qd[1] - q[1] * qd[0]) / L**2  # x ẏ − y ẋ = L² θ̇
    motion = system.motion(0.0, q, qd)
    theta_dd = -g / L * np.sin(theta)
    # x = L sin θ, y = −L cos θ
    expected = [L * (np.cos(theta) * theta_dd - np.sin(theta) * theta_dot**2),
                L * (np.sin(theta) * theta_dd + np.cos(theta) * theta_dot**2)]
    np.testing.assert_allclose(motion.qdd, expected, rtol=1e-12)
    phi, phidot = system.constraint_residuals(0.0, q, qd)
    assert abs(phi[0]) < 1e-12 and abs(phidot[0]) < 1e-12


def test_velocity_dependent_kinetic_energy_terms_and_forces():
    """A bead on a hoop spinning at rate w: T = m/2 (R² θ̇² + R² w² sin²θ) gives
    R θ̈ = R w² sinθ cosθ − g sinθ + F/(mR) for a generalized force F."""
    system = loads("""\
        parameters: {m: 0.7, R: 0.5, w: 3.0, g: 9.81, F: 0.2}
        parts:
          bead:
            type: lagrangian
            coordinates: [theta]
            T: 0.5*m*(R**2*theta_dot**2 + R**2*w**2*sin(theta)**2)
            V: -m*g*R*cos(theta)
            forces: {theta: F}
        initial: {bead.theta: 0.9, bead.theta_dot: 1.1}
        """)
    q, qd = system.initial_state()
    m, R, w, g, F = 0.7, 0.5, 3.0, 9.81, 0.2
    th = q[0]
    expected = w**2 * np.sin(th) * np.cos(th) - g / R * np.sin(th) + F / (m * R**2)
    np.testing.assert_allclose(system.motion(0.0, q, qd).qdd, [expected], rtol=1e-12)


def test_nonholonomic_and_time_dependent_constraints():
    """A particle driven along x = v t (holonomic in t) and constrained by ẏ = a ẋ
    (non-holonomic form of a line): ẍ = 0, ÿ = 0, with both constraints reported."""
    system = loads("""\
        parameters: {m: 1.0, v: 2.0, a: 0.5, g: 9.81}
        parts:
          p:
            type: lagrangian
            coordinates: [x, y]
            T: 0.5*m*(x_dot**2 + y_dot**2)
            V: m*g*y
        constraints:
          - {name: drive, holonomic: p.x - v*t - 0.1*sin(3*t)}
          - {name: slope, nonholonomic: p.y_dot - a*p.x_dot}
        """)
    t = 0.7
    motion = system.motion(t, [2 * t, 0.0], [2.0, 1.0])
    xdd = -0.9 * np.sin(3 * t)  # d²/dt² (v t + 0.1 sin 3t)
    np.testing.assert_allclose(motion.qdd, [xdd, 0.5 * xdd], rtol=1e-12)


def test_acceleration_rows_and_nonideal_C_enter_2_14():
    """A sliding block with viscous friction through C (2.6): the constraint y = 0 and
    C = −c ẋ along x give ẍ = (F − c ẋ)/m."""
    system = loads("""\
        parameters: {m: 2.0, c: 0.3, F: 1.0}
        parts:
          block:
            type: lagrangian
            coordinates: [x, y]
            T: 0.5*m*(x_dot**2 + y_dot**2)
            forces: {x: F}
        constraints:
          - name: floor
            acceleration: {A: {block.y: 1}, b: 0}
            C: {block.x: -c*block.x_dot}
        """)
    motion = system.motion(0.0, [0.0, 0.0], [2.0, 0.0])
    np.testing.assert_allclose(motion.qdd, [(1.0 - 0.3 * 2.0) / 2.0, 0.0], rtol=1e-12)


def test_parameters_may_be_expressions_of_earlier_ones():
    system = loads("""\
        parameters: {m: 2.0, R: 0.5, Ic: 0.5*m*R**2}
        parts:
          disk: {type: lagrangian, coordinates: [th], T: 0.5*Ic*th_dot**2}
        """)
    assert system.parameters["Ic"] == pytest.approx(0.25)


HINGED = """\
parameters: {k: 2.0}
world: {frames: {pivot: {axis: [0, 1, 0]}}}
parts:
  rod: {type: rigid_body, mass: 1, inertia: [1, 1, 1], frames: {top: {position: [0, 0, 1], axis: [0, 1, 0]}}}
joints:
  - {name: hinge, type: revolute, parent: world.pivot, child: rod.top}
"""

ERRORS = [
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: 0.5*m*x_dot**2}\n",
     2, "unknown name 'm'"),
    ("parameters: {m: 1}\nparts:\n  a:\n    type: lagrangian\n    coordinates: [x]\n    T: 0.5*m*x_dot**2\n"
     "    V: x +* 2\n", 7, "at parts.a.V: malformed expression"),
    ("parts:\n  a:\n    type: rigid\n", 3, "unknown part type 'rigid'"),
    ("parts:\n  a:\n    type: lagrangian\n    coordinates: [x]\n", 2, "missing required key 'T'"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\nconstraint: []\n", 3,
     "unknown key 'constraint' (did you mean 'constraints'?)"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\nconstraints:\n  - name: c\n"
     "    holonomic: a.x_dot\n", 5, "write it as 'nonholonomic:'"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\nconstraints:\n  - name: c\n"
     "    holonomic: b.x\n", 5, "unknown name 'b.x' (did you mean a.x?)"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\ninitial: {a.y: 1}\n", 3,
     "unknown key 'a.y'"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: -x_dot**2}\n", 2, "not positive semi-definite"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x, x], T: x_dot**2}\n", 2, "listed twice"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\n  a: {}\n", 3, "duplicate key 'a'"),
    ("parts: [1, 2]\n", 1, "expected a mapping of named parts"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2, V: x_dot}\n", 2,
     "V must not depend on velocities"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\nconstraints:\n  - {name: c, nonholonomic: a.x}\n",
     4, "involves no velocity"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\nconstraints:\n"
     "  - {name: c, acceleration: {A: [1, 2], b: 0}}\n", 4, "needs 1 entries"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2\n", 3, "not valid YAML"),
    ("- just\n- a list\n", 1, "must be a mapping"),
    ("parameters: {t: 1}\nparts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\n", 1, "reserved"),
    ("parts:\n  a: {type: lagrangian, coordinates: [x], T: x_dot**2}\nbalances: yes\n", 3,
     "expected 'auto' or 'none'"),
    ("parts: {}\n", 1, "the mapping is empty: a model needs at least one part"),
    (f"{HINGED}outputs: {{d: hinge.displacement}}\n", 7,
     "unknown name 'hinge.displacement' ('hinge' has angle, rate)"),  # a revolute joint's values
    (HINGED.replace("name: hinge", "name: world"), 6, "at joints[0].name: joint 'world' has the name of the world"),
    (HINGED.replace("name: hinge", "name: k"), 6, "at joints[0].name: joint 'k' has the name of a parameter"),
]


@pytest.mark.parametrize("text, line, fragment", ERRORS)
def test_mistakes_name_file_line_and_key(text, line, fragment):
    with pytest.raises(mb.ModelError) as err:
        mb.loads(text, name="bad.yaml")
    message = str(err.value)
    assert message.startswith(f"bad.yaml:{line}:"), message
    assert fragment in message, message


def test_an_unknown_reaction_joint_is_named_once_at_its_line():
    """Its file:line prefix was printed twice."""
    with pytest.raises(mb.ModelError) as err:
        mb.loads(f"{HINGED}outputs: {{f: {{reaction: hing.force}}}}\n", name="bad.yaml")
    message = str(err.value)
    assert message.startswith("bad.yaml:7: at outputs.f.reaction: unknown joint or constraint 'hing'") and \
        message.count("bad.yaml") == 1, message


def test_missing_file_is_a_model_error(tmp_path):
    with pytest.raises(mb.ModelError, match="no such model file"):
        mb.load(tmp_path / "absent.yaml")
