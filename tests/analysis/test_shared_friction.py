"""Sticking contacts that share a load their rows do not determine (statically indeterminate
friction, analysis/cones.py): the group sticks while some split of the forces lies in every
exact Coulomb cone, against the closed forms of a box on four corners."""

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import OptimizeResult, linprog

import mbsynth as mb
from mbsynth.analysis import cones
from mbsynth.analysis.cones import Cone, Shared, program
from mbsynth.model.reactions import indeterminate, multipliers

MODEL = Path(__file__).resolve().parents[2] / "models" / "contact" / "box_on_four_corners.yaml"
G = 9.81


def test_a_box_on_four_corners_below_tan_alpha_mu_stays_at_rest():
    """tan α < μ: the four (three held, the fourth touching) sticking corners share the load
    down the slope, m g sin α, which their rows leave free; the minimum-norm split puts one
    corner outside its cone, another split holds them all, so the box stays where it is."""
    system = mb.load(MODEL, parameters={"alpha": 0.3, "mu": 0.5})
    traj = mb.simulate(system, 20.0, rtol=1e-10, atol=1e-10)
    assert {ev.kind for ev in traj.events} == {"contact", "stick"}
    assert np.abs(traj.q - traj.q[0]).max() < 1e-10
    assert np.abs(traj.qd).max() < 1e-10


@pytest.mark.parametrize("moved", [1e-16, 3e-15, 1e-14])
def test_the_box_at_rest_stays_there_from_states_moved_by_rounding(moved):
    """The same box from its initial q moved by rounding: a run at rest has velocities of
    rounding (1e-24 to 1e-12), which neither lift a touching corner nor make its dependent
    rows (three corners' nine, on seven velocities) look unmet after the velocity step; the
    box stays where it is, its corners stuck."""
    system = mb.load(MODEL, parameters={"alpha": 0.3, "mu": 0.5})
    q0, qd0 = system.initial_state()
    traj = mb.simulate(system, 20.0, rtol=1e-10, atol=1e-10, q0=q0 + moved * np.cos(1.7 * np.arange(q0.size)), qd0=qd0)
    assert {ev.kind for ev in traj.events} == {"contact", "stick"}
    assert np.abs(traj.q - traj.q[0]).max() < 1e-10
    assert np.abs(traj.qd).max() < 1e-10


def test_a_box_on_four_corners_above_tan_alpha_mu_slides_down_as_a_whole():
    """tan α > μ: the group breaks away at t = 0 and slides without turning, its centre as
    a block's, x = ½ g (sin α − μ cos α) t²: the corners' friction adds up to μ m g cos α
    whatever the split of the normal forces. Its slips start along the load's push (from
    the minimum-norm forces they would turn the box)."""
    alpha, mu = 0.5, 0.3
    system = mb.load(MODEL, parameters={"alpha": alpha, "mu": mu})
    traj = mb.simulate(system, 1.0, rtol=1e-10, atol=1e-10)
    assert {ev.kind for ev in traj.events} == {"contact", "slip"}
    assert {ev.t for ev in traj.events} == {0.0}
    a = G * (np.sin(alpha) - mu * np.cos(alpha))
    assert np.abs(traj.q[:, 0] - 0.5 * a * traj.t**2).max() < 1e-9
    assert np.abs(traj.qd[:, 0] - a * traj.t).max() < 1e-9
    assert np.abs(traj.q[:, 1:3] - traj.q[0, 1:3]).max() < 1e-10
    assert np.abs(traj.q[:, 4:]).max() < 1e-10  # the quaternion's vector part: no turning


@pytest.mark.slow  # about a minute: the slide's first milliseconds take thousands of steps (docstring)
def test_a_pushed_box_sticks_up_to_mu_m_g_then_slides_as_a_block():
    """A push k t along x on level ground: the corners stick until k t = μ m g (s* reaches
    zero with no acceleration yet: the slide starts along the push), then the box moves as
    a block, x = k (t − t_b)³ / 6m. (Held at first on a diagonal pair, the least set, it
    tips onto a third corner as the push begins, in its first millisecond.) Within
    the first milliseconds of the slide the slip is slow and its direction stiff (a yaw
    perturbation's rate grows as μ g / |slip|): explicit steps crawl there, and the closed
    form holds to 1e-8 in x and ẋ."""
    m, mu, k = 2.0, 0.3, 100.0
    t_b = mu * m * G / k
    system = mb.load(MODEL, parameters={"alpha": 0.0, "mu": mu, "k": k})
    traj = mb.simulate(system, t_b + 0.14, rtol=1e-10, atol=1e-10)
    first_slip = min(ev.t for ev in traj.events if ev.kind == "slip" and ev.t > 0.1 * t_b)
    assert abs(first_slip - t_b) < 1e-9
    after = np.maximum(traj.t - t_b, 0.0)
    assert np.abs(traj.q[:, 0] - k * after**3 / (6 * m)).max() < 1e-8
    assert np.abs(traj.qd[:, 0] - k * after**2 / (2 * m)).max() < 1e-8
    assert np.abs(traj.q[:, 4:]).max() < 1e-10


def _table(push, mu, m=2.0, a=0.2, b=0.1, h=0.05):
    """Shared forces of a table (legs at (±a/2, ±b/2), centre of mass h above the floor)
    pushed along x at its centre of mass: its rows are each foot's normal and two tangents
    on the body's six motions (force; moment about the centre of mass)."""
    rows, cones = [], []
    for x, y in [(a / 2, b / 2), (-a / 2, b / 2), (a / 2, -b / 2), (-a / 2, -b / 2)]:
        r = np.array([x, y, -h])
        start = len(rows)
        rows += [np.concatenate([d, np.cross(r, d)]) for d in np.eye(3)[[2, 0, 1]]]
        cones.append(Cone(start, (start + 1, start + 2), mu))
    A = np.array(rows)
    load = np.array([push, 0.0, -m * G, 0.0, 0.0, 0.0])  # the floor's forces hold the push and the weight
    lam = multipliers(A, -load)[0]
    return Shared(lam, indeterminate(A), cones, [], m * G), A, load


def test_a_pushed_table_sticks_up_to_mu_m_g_and_its_friction_equals_the_push():
    """Breakaway at push = μ m g (the closed form, whatever the legs' split): s* < 0 below it
    (though the minimum-norm split already has the rear legs outside their cones), > 0 above;
    the split chosen holds the table (Aᵀλ = −load: total friction = −push, normals = m g)."""
    mu, m = 0.5, 2.0
    below, A, load = _table(0.99 * mu * m * G, mu)
    assert below.violation(below.lam) > 0  # the minimum-norm split breaks a leg
    s, lam = below.margin()
    assert s < 0
    assert below.violation(lam) <= 1e-9 * m * G
    assert np.abs(A.T @ lam + load).max() < 1e-9 * m * G
    assert abs(sum(lam[c.tangential[0]] for c in below.cones) + 0.99 * mu * m * G) < 1e-9 * m * G
    assert abs(sum(lam[c.normal] for c in below.cones) - m * G) < 1e-9 * m * G
    assert _table(1.01 * mu * m * G, mu)[0].margin()[0] > 0
    assert abs(_table(mu * m * G, mu)[0].margin()[0]) < 1e-8 * m * G


# A program of the pushed box's cutting planes (test below) on which HiGHS's dual simplex at
# LP_FEASIBILITY_TOL ended "Not Set" without a solution (scipy 1.17.1): rows (z; the last column, s's, is −1)
NOT_SET_ROWS = np.array([
    [0.25678122268373216, 0.08366977695356423, 0.6668656768869002],
    [-0.2219640731642863, -0.04201039846913657, 0.7643698019656956],
    [-0.5706858251893873, -0.14308145219681873, 0.4141164637072444],
    [-0.5851075605497739, -0.16033733171914574, -0.17872068260310384],
    [-0.2567812222642873, -0.08366977684261466, -0.6668656769353102],
    [0.2219640735837312, 0.04201039858008616, -0.7643698020141056],
    [0.5706858256088322, 0.14308145230776828, -0.41411646375565453],
    [0.5851075609692188, 0.16033733183009535, 0.17872068255469373],
    [0.02421155362378954, -0.011201587247559978, -0.7815054774175373],
    [0.05879187017469085, -0.6968422874666679, -0.35861037553827324],
    [0.535893818933444, -0.36198630846997143, -0.3106277669189341],
    [0.6990764364352108, 0.18491634054133707, -0.08068362530548333],
    [0.45274955849099713, 0.6234975050742056, 0.19652388973315926],
    [-0.05879187057649848, 0.6968422871466659, 0.3586103754791006],
    [-0.5358938193352517, 0.36198630814996957, 0.31062776685976146],
    [-0.6990764368370185, -0.18491634086133896, 0.08068362524631068],
    [-0.4527495588928049, -0.6234975053942077, -0.19652388979233193],
    [-0.31557309285842305, 0.6131725105131035, -0.3082553013486267],
    [-0.3139297457691579, 0.40399670693910783, -0.4537420350467615],
    [-0.12839061124582368, -0.041834888344518546, -0.33343283840176136],
    [0.13235800205877665, -0.46316017335506005, -0.017803207130055756],
    [0.31557309284078583, -0.6131725103040512, 0.3082553014562094],
    [0.3139297457515207, -0.40399670673005555, 0.45374203515434425],
    [0.12839061122818643, 0.0418348885535708, 0.33343283850934413],
    [-0.13235800207641385, 0.4631601735641123, 0.01780320723763854],
    [-0.3396177858165004, 0.5290568408483023, -0.42517193138248816],
])
NOT_SET_RHS = np.array([
    0.14465944725149016, 0.1420202438803712, 0.1440554733762609,
    0.1495729259030088, 0.1553405526001957, 0.15797975597131464,
    0.15594452647542495, 0.15042707394867705, 0.15742894010605218,
    -0.005359426451988523, -0.001724779279995616, 0.0029533889975852257,
    0.005934670850810728, 0.0054726718033181855, 0.0018380246313252793,
    -0.0028401436462555632, -0.005821425499481065, 0.16220991476355776,
    0.16077222107559658, 0.1529911376263495, 0.1434247175704286,
    0.1376768400332344, 0.1391145337211956, 0.14689561717044267,
    0.15646203722636357, 0.162271931307723,
])


def test_a_program_the_dual_simplex_leaves_without_a_solution_gets_the_one_other_solvers_agree_on():
    """cones.program on NOT_SET_ROWS: the value HiGHS's dual simplex gives at its default
    tolerances (1e-7, not LP_FEASIBILITY_TOL), every row met, s above its bound."""
    rows = np.hstack([NOT_SET_ROWS, -np.ones((len(NOT_SET_ROWS), 1))])
    found = program(rows, NOT_SET_RHS)
    k = NOT_SET_ROWS.shape[1]
    reference = linprog(np.append(np.zeros(k), 1.0), A_ub=rows, b_ub=NOT_SET_RHS,
                        bounds=[(None, None)] * k + [(-1.0, None)], method="highs-ds")
    assert reference.status == 0 and found.status == 0
    assert abs(found.fun - reference.fun) < 1e-12 * abs(reference.fun) + 1e-15
    assert (rows @ found.x - NOT_SET_RHS).max() < 1e-12 and found.x[-1] >= -1.0


def test_a_program_no_method_solves_is_a_solve_error_naming_it(monkeypatch):
    monkeypatch.setattr(cones, "linprog", lambda *args, **kwargs: OptimizeResult(x=None, message="(Not Set)"))
    rows = np.hstack([NOT_SET_ROWS, -np.ones((len(NOT_SET_ROWS), 1))])
    with pytest.raises(mb.SolveError, match=r"friction cones' linear program \(26 rows over 3 free forces\) got no "
                                            r"solution from HiGHS: \(Not Set\)"):
        program(rows, NOT_SET_RHS)
