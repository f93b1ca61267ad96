"""Linearization with non-holonomic rows about steady motions (analysis/linearization.py):
the stability exponents of rolling disks, a sleigh on a massless blade and the Whipple
bicycle, against closed forms, an independent derivation by Kane's method (sympy), and
the bicycle benchmark's published eigenvalues and self-stable speeds."""

from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from scipy.optimize import brentq

import mbsynth as mb
from mbsynth.analysis.modes import to_dict

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"
from benchmarks import iftomm_reference as ref

# J. P. Meijaard, J. M. Papadopoulos, A. Ruina, A. L. Schwab, Proc. R. Soc. A 463 (2007)
# 1955-1982, Table 2: the benchmark bicycle's eigenvalues (1/s) at 4, 5 and 10 m/s, and its
# weave and capsize speeds (m/s), printed to 14 decimals (benchmarks/iftomm_reference.py).
TABLE_2 = ref.WHIPPLE_TABLE_2
WEAVE_SPEED, CAPSIZE_SPEED = ref.WHIPPLE_WEAVE_SPEED, ref.WHIPPLE_CAPSIZE_SPEED
STILL = [-5.53094371765393, -3.13164324790656, 3.13164324790656, 5.53094371765393]  # Table 2 at v = 0


def _nonzero(values):
    return np.sort_complex(values[values != 0])


@pytest.fixture(scope="module")
def bicycle():
    return mb.load(MODELS / "rolling" / "bicycle.yaml")


def _bicycle_at(bicycle, v):
    moving = bicycle.with_parameters(v=v)
    return mb.linearize(moving, 0.0, *moving.initial_state())


@pytest.mark.parametrize("v", sorted(TABLE_2))
def test_bicycle_eigenvalues_equal_table_2(bicycle, v):
    lin = _bicycle_at(bicycle, v)
    assert lin.k == 7 and lin.A.shape == (10, 10)  # x, y, heading, lean, steer, two wheel angles; 3 speeds
    got = _nonzero(lin.eigenvalues)
    assert np.abs(got - np.sort_complex(TABLE_2[v])).max() < 1e-8
    assert np.count_nonzero(lin.eigenvalues == 0) == 6  # position, heading, wheel angles, forward speed


@pytest.mark.parametrize("v", [0.5, 2.0, 4.6, 6.5, 8.0])
def test_bicycle_eigenvalues_equal_the_benchmarks_linear_equations(bicycle, v):
    """At any speed: the roots of det(s² M + s v C1 + g K0 + v² K2) with the matrices the paper
    prints (its eq. 5.4, 14 digits), as the first-order companion form's eigenvalues."""
    M, C1 = ref.WHIPPLE_M, ref.WHIPPLE_C1
    K = 9.81 * ref.WHIPPLE_K0 + v * v * ref.WHIPPLE_K2
    companion = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), -v * np.linalg.solve(M, C1)]])
    expected = np.sort_complex(np.linalg.eigvals(companion))
    assert np.abs(_nonzero(_bicycle_at(bicycle, v).eigenvalues) - expected).max() < 1e-9 * np.abs(expected).max()


def test_bicycle_standing_still_is_two_inverted_pendulums(bicycle):
    lin = mb.linearize(bicycle, 0.0, bicycle.initial_q, np.zeros(bicycle.n))
    assert np.abs(_nonzero(lin.eigenvalues) - np.array(STILL)).max() < 1e-8


def test_bicycle_self_stable_speeds(bicycle):
    """The weave speed (the weave pair crosses the imaginary axis) and the capsize speed
    (the capsize eigenvalue crosses zero), found from mb.linearize by root finding."""
    def least_stable(v):
        return _nonzero(_bicycle_at(bicycle, v).eigenvalues).real.max()

    assert least_stable(5.0) < 0 < least_stable(4.0) and 0 < least_stable(7.0)
    assert abs(brentq(least_stable, 4.0, 5.0, xtol=1e-12) - WEAVE_SPEED) < 1e-7
    assert abs(brentq(least_stable, 5.5, 7.0, xtol=1e-12) - CAPSIZE_SPEED) < 1e-7


def test_bicycle_modes_cli_reports_the_steady_motion(capsys):
    from mbsynth.cli import main
    import json
    assert main(["modes", str(MODELS / "rolling" / "bicycle.yaml"), "--steady", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["steady_motion"] and result["zero_eigenvalues"] == 6
    values = np.array([complex(*x) for x in result["eigenvalues"]])
    assert np.abs(_nonzero(values) - np.sort_complex(TABLE_2[5.0])).max() < 1e-8
    assert result["stable"]


UPRIGHT_DISK = """
name: upright_disk
parameters: {m: 1.0, R: 0.1, g: 9.81, A: m*R**2/4, C: m*R**2/2, w: 12.0}
gravity: [0, 0, -g]
parts:
  disk:
    type: rigid_body
    rotation: zxz
    mass: m
    inertia: [A, A, C]
initial: {disk.z: R, disk.angle_x: -pi/2, disk.x_dot: R*w, disk.angle_z2_dot: w}
joints:
  - {name: contact, type: rolling_disk, child: disk, radius: R}
"""


@pytest.mark.parametrize("w", [6.0, 12.0, 30.0])
def test_upright_rolling_disk_closed_form(w):
    """A disk rolling straight and upright at spin rate w: (A + mR²) φ̈ + (C(C + mR²)w²/A − mgR) φ = 0
    for the lean φ; stable iff w² > mgRA/(C(C + mR²)) (g/3R for a uniform disk)."""
    disk = mb.loads(UPRIGHT_DISK).with_parameters(w=w)
    lin = mb.linearize(disk, 0.0, *disk.initial_state())
    m, R, g = 1.0, 0.1, 9.81
    A, C = m * R**2 / 4, m * R**2 / 2
    s2 = -(C * (C + m * R**2) * w**2 / A - m * g * R) / (A + m * R**2)
    expected = np.sort_complex(np.array([-1, 1]) * np.sqrt(complex(s2)))
    assert np.abs(_nonzero(lin.eigenvalues) - expected).max() < 1e-9 * abs(expected[0])
    assert set(lin.cyclic) >= {"disk.x", "disk.y", "disk.angle_z", "disk.angle_z2"}
    assert (w**2 > g / (3 * R)) == bool(np.all(lin.eigenvalues.real <= 1e-9))


def _kane_disk():
    """The rolling disk by Kane's method (sympy.physics.mechanics): yaw q1, lean q2 (of the
    disk's plane from the vertical), spin q3; body rates u1 (lean rate), u2 (along the
    axis), u3; rolling built into the velocity of the centre. Returns the reduced vector
    field f(θ, u1, u2, u3) and its Jacobian, with symbols (θ, a2, a3) for (q2, u2, u3) at u1 = 0."""
    from sympy.physics.mechanics import KanesMethod, Point, ReferenceFrame, RigidBody, dot, dynamicsymbols, inertia
    q1, q2, q3 = dynamicsymbols("q1 q2 q3")
    u1, u2, u3 = dynamicsymbols("u1 u2 u3")
    r, m, g = 0.1, 1.0, 9.81
    N = ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    D = L.orientnew("D", "Axis", [q3, L.y])
    w = D.ang_vel_in(N)
    D.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    contact = Point("contact")
    contact.set_vel(N, 0)
    centre = contact.locatenew("centre", r * L.z)
    centre.v2pt_theory(contact, N, D)
    method = KanesMethod(N, q_ind=[q1, q2, q3], u_ind=[u1, u2, u3], kd_eqs=[dot(D.ang_vel_in(N) - w, e) for e in L])
    method.kanes_equations([RigidBody("disk", centre, D, m, (inertia(L, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4),
                                                                 centre))], [(centre, -m * g * Y.z)])
    rates = method.kindiffdict()
    state = [q2, u1, u2, u3]
    f = sp.Matrix([rates[q2.diff()], *method.mass_matrix.LUsolve(method.forcing)]).subs(rates)
    theta, a2, a3 = sp.symbols("theta a2 a3")
    held = {q2: theta, u1: 0, u2: a2, u3: a3}
    return f.xreplace(held), f.jacobian(state).xreplace(held), (theta, a2, a3)


@pytest.mark.parametrize("omega", [2.0, 5.0])
def test_turning_disk_against_kanes_method(omega):
    """A disk rolling in a steady circle (models/rolling/turning_disk.yaml, lean 0.3 rad,
    heading rate Ω): its exponents are those of Kane's reduced equations linearized at the
    same steady motion, where the characteristic polynomial is s²(s² + K) and the closed
    form K(θ, Ω) > 0 is the condition of stability (a lean oscillation); K < 0 at Ω = 5."""
    f, J, (theta, a2, a3) = _kane_disk()
    turn = omega * np.cos(0.3)  # u3: the heading rate's component normal to the axis, in the disk's plane
    along = float(sp.solve(f[1].subs({theta: 0.3, a3: turn}), a2)[0])  # the steady condition
    jacobian = np.array(J.subs({theta: 0.3, a2: along, a3: turn}), dtype=float)
    s = sp.Symbol("s")
    K = sp.Poly(sp.Matrix(jacobian).charpoly(s).as_expr(), s).all_coeffs()[2]
    disk = mb.load(MODELS / "rolling" / "turning_disk.yaml").with_parameters(Omega=omega)
    q, qd = disk.initial_state()
    lin = mb.linearize(disk, 0.0, q, qd)
    got = _nonzero(lin.eigenvalues)
    expected = np.sort_complex(np.linalg.eigvals(jacobian)[np.abs(np.linalg.eigvals(jacobian)) > 1e-9])
    assert got.size == 2 and np.abs(got - expected).max() < 1e-9 * np.abs(expected).max()
    assert (float(K) > 0) == bool(np.all(np.abs(got.real) < 1e-9)) == (omega == 2.0)
    assert abs(abs(disk.parameters["w_axis"]) - abs(along)) < 1e-12 * abs(along)


SLEIGH = """
name: sleigh_on_a_massless_blade
parameters: {m: 1.0, I: 0.02, a: 0.2, u0: 1.0}
parts:
  carrier: {type: planar_body, mass: 0, inertia: 0, frames: {weld: {position: [-a, 0, 0]}}}
  sleigh: {type: planar_body, mass: m, inertia: I, frames: {weld: {position: [0, 0, 0]}}}
initial: {carrier.x: a, carrier.x_dot: u0, sleigh.x_dot: u0}
joints:
  - {name: weld, type: fixed, parent: sleigh.weld, child: carrier.weld}
  - {name: blade, type: knife_edge, child: carrier}
"""


@pytest.mark.parametrize("u0", [1.0, -0.5])
def test_sleigh_on_a_massless_blade(u0):
    """The Chaplygin sleigh with its blade on a massless part welded a ahead of the centre of
    mass, running straight at u: ω̇ = m a u ω/(I + m a²), so one exponent m a u/(I + m a²)
    (unstable forward, stable backward) and zeros for the position, heading and speed."""
    sleigh = mb.loads(SLEIGH).with_parameters(u0=u0)
    lin = mb.linearize(sleigh, 0.0, *sleigh.initial_state())
    m, I, a = 1.0, 0.02, 0.2
    assert np.allclose(_nonzero(lin.eigenvalues), [m * a * u0 / (I + m * a**2)], rtol=1e-12, atol=0)
    assert lin.eigenvalues.size == 5 and np.count_nonzero(lin.eigenvalues == 0) == 4


def test_acceleration_rows_are_still_refused():
    with pytest.raises(mb.SolveError, match="restrict accelerations only"):
        system = mb.load(MODELS / "paper" / "example3_m2_zero.yaml")
        mb.linearize(system, 0.0, *system.initial_state())


def test_speeds_can_be_chosen_and_are_checked(bicycle):
    v = 5.0
    moving = bicycle.with_parameters(v=v)
    chosen = mb.linearize(moving, 0.0, *moving.initial_state(),
                          speeds=["rear_frame.x", "rear_frame.angle_x", "front_frame.angle_z"])
    assert np.abs(_nonzero(chosen.eigenvalues) - np.sort_complex(TABLE_2[v])).max() < 1e-8
    with pytest.raises(mb.SolveError, match="do not fix the velocities"):
        mb.linearize(moving, 0.0, *moving.initial_state(), speeds=["rear_frame.x", "rear.wheel.x", "front.wheel.x"])


def test_speeds_take_the_names_modes_prints_and_refuse_one_string(bicycle):
    """``mbsynth modes --steady`` lists the independent speeds as rates (rear_frame.x_dot, …):
    those names choose the same speeds as the coordinates' (the same A), as does the list
    modes prints; one string, which would be read letter by letter, is refused."""
    moving = bicycle.with_parameters(v=5.0)
    state = moving.initial_state()
    printed = to_dict(mb.modes(moving, steady=True))["independent_speeds"]
    assert all(name.endswith("_dot") for name in printed) and len(printed) == 3
    default = mb.linearize(moving, 0.0, *state)
    np.testing.assert_array_equal(mb.linearize(moving, 0.0, *state, speeds=printed).A, default.A)
    chosen = ["rear_frame.x", "rear_frame.angle_x", "front_frame.angle_z"]
    np.testing.assert_array_equal(mb.linearize(moving, 0.0, *state, speeds=[f"{c}_dot" for c in chosen]).A,
                                  mb.linearize(moving, 0.0, *state, speeds=chosen).A)
    with pytest.raises(TypeError, match=r"speeds: a list of names, got the string 'rear_frame.x_dot'"):
        mb.linearize(moving, 0.0, *state, speeds="rear_frame.x_dot")
    with pytest.raises(TypeError, match=r"inputs: a list of names, got the string 'v'"):
        mb.linearize(moving, 0.0, *state, inputs="v")
    with pytest.raises(mb.SolveError, match=r"unknown speed\(s\) \['rear_frame.v_dot'\]: name coordinates or their "
                                            r"rates \(<coordinate>_dot"):
        mb.linearize(moving, 0.0, *state, speeds=["rear_frame.v_dot", "rear_frame.x", "front_frame.angle_z"])


def test_steady_motion_with_contradictory_rates_says_what_the_rows_allow():
    """Rates the velocity rows cannot meet are refused, naming the rows and what the model
    allows: a pendulum on a rod (position rows alone: the rate of one independent coordinate;
    nothing said of rolling) and a rolling disk (the slip rows: independent speeds)."""
    pendulum = mb.load(MODELS / "mechanisms" / "simple_pendulum.yaml")  # at (-1, 0): the rod row says x_dot = 0
    with pytest.raises(mb.SolveError) as err:
        mb.steady_motion(pendulum, {"bob.x": 1.0})
    assert str(err.value) == ("model 'simple_pendulum': the rates {'bob.x': 1.0} contradict the rows ['rod']: the "
                              "position rows fix every rate from 1 independent coordinate(s), e.g. ['bob.y']; give "
                              "rates the rows allow (those of independent ones; the others follow)")
    assert err.value.constraints == ("rod",)
    disk = mb.load(MODELS / "rolling" / "turning_disk.yaml")
    with pytest.raises(mb.SolveError) as err:
        mb.steady_motion(disk, {"disk.angle_z": 2.0, "disk.angle_z2": 0.0, "disk.x": 5.0}, q=disk.initial_state()[0])
    assert "contradict the rows ['contact[slip_x]']" in str(err.value)
    assert ("the position rows and the velocity rows ['contact[slip_x]', 'contact[slip_y]'] (rolling without "
            "slipping, a knife edge) leave 3 independent speed(s)") in str(err.value)


def test_steady_motion_from_a_forward_speed(bicycle):
    """mb.steady_motion from the rear wheel's spin rate v/rR alone: the bicycle rolls upright
    at v (the least-energy velocities leave no lean or steer rate), as the model file's
    initial state written by hand; its eigenvalues are Table 2's."""
    q, qd = mb.steady_motion(bicycle, {"rear.wheel.angle_y": 4.0 / 0.3})
    q0, qd0 = bicycle.with_parameters(v=4.0).initial_state()
    assert np.abs(q - q0).max() < 1e-12 and np.abs(qd - qd0).max() < 1e-12 * np.abs(qd0).max()
    lin = mb.linearize(bicycle, 0.0, q, qd)
    assert np.abs(_nonzero(lin.eigenvalues) - np.sort_complex(TABLE_2[4.0])).max() < 1e-8


def test_steady_motion_solves_for_a_disks_spin():
    """Given the lean (its initial angles) and the heading rate, the spin rate that makes the
    circle steady is the closed form the model file writes (the steady condition)."""
    disk = mb.load(MODELS / "rolling" / "turning_disk.yaml")
    q0, qd0 = disk.initial_state()
    q, qd = mb.steady_motion(disk, {"disk.angle_z": 2.0, "disk.angle_z2": 0.0}, q=q0, solve=["disk.angle_z2_dot"])
    spin = disk.coordinates.index("disk.angle_z2")
    assert abs(qd[spin] - disk.parameters["spin"]) < 1e-10 * abs(disk.parameters["spin"])
    with pytest.raises(mb.NoEquilibrium, match="does not move steadily"):
        mb.steady_motion(disk, {"disk.angle_z": 2.0, "disk.angle_z2": 0.0}, q=q0)
