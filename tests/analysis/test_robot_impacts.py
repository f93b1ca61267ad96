"""A robot's foot striking the ground against Pinocchio's impulse dynamics.

solo12 (example-robot-data, floating) is built by mbsynth as one rigid body per link with a
contact point at the origin of its FL_FOOT link against the plane z = h. Pinocchio,
independently, solves the same impact in reduced coordinates from its own model of the URDF
(``pinocchio.impulseDynamics``: M (v⁺ − v⁻) = JᵀΛ, J v⁺ = −e J v⁻, J the foot's normal row
of ``getFrameJacobian``). The states map between the two through the Pinocchio twin
(robots/twin.py), whose tree is Pinocchio's model of the same URDF joint for joint.
"""

import numpy as np
import pinocchio as pin
import pytest

import mbsynth as mb
from mbsynth.analysis.impulse import velocity_jump
from mbsynth.model.unilateral import Gaps
from mbsynth.robots.twin import Twin
from mbsynth.robots.validate import sample_pinocchio_state

MODEL = """
name: solo_strike
parameters: {h: -1.0, e: 0.0}
gravity: [0, 0, -9.81]
subsystems:
  solo: {type: robot, robot: solo12, floating: true}
contacts:
  - {name: foot, type: plane, child: solo_FL_FOOT.link, ground: h, restitution: e}
"""


@pytest.fixture(scope="module")
def solo():
    system = mb.loads(MODEL)
    twin = Twin(system)
    model = pin.buildModelFromUrdf(system.robots[0].description.path, pin.JointModelFreeFlyer())
    assert [twin.model.names[i] for i in range(1, twin.model.njoints)] == \
        ["solo_" + model.names[i] for i in range(1, model.njoints)]  # the same tree: the same q and v
    return system, twin, model


def _pinocchio_impact(model, q, v, e):
    """(v⁺, Λ, the foot's height, its normal row) of Pinocchio's impulse dynamics."""
    data = model.createData()
    foot = model.getFrameId("FL_FOOT")
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J = pin.getFrameJacobian(model, data, foot, pin.LOCAL_WORLD_ALIGNED)[2:3]
    if (J @ v)[0] > 0:
        v = -v  # the foot moves down: it strikes
    v_after = pin.impulseDynamics(model, data, q, v, J, e)
    return v, v_after.copy(), data.impulse_c.copy(), data.oMf[foot].translation[2], J


def _mbsynth_impact(system, q, qd):
    """q̇⁺ and Λ of the impulse form of (2.14) with the model's rows kept and Newton's law on
    the foot's gap row (what analysis/impacts.py solves for one striking gap)."""
    data = system.data()
    arrays = data.constraint_arrays(0.0, q, qd, sparse=False)
    gaps = Gaps(system, data.p)
    g, gd = gaps.values(0.0, q, qd, data.p)
    A_gap = gaps.rows(0.0, q, qd, data.p)[0]
    A = np.vstack([arrays.A, A_gap])
    v = np.concatenate([arrays.A @ qd - arrays.psi, -gaps.restitution * gd])
    jump = velocity_jump(data.evaluate(0.0, q, qd).M, qd, A, v)
    return jump.qd, jump.impulses[-1], g[0]


@pytest.mark.parametrize("e", [0.0, 0.6])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_foot_impact_equals_pinocchio_impulse_dynamics(solo, seed, e):
    system, twin, model = solo
    q, v = sample_pinocchio_state(twin, np.random.default_rng(seed))
    v, v_after, impulse, height, J = _pinocchio_impact(model, q, v, e)
    struck = system.with_parameters(h=float(height), e=e)
    qm, qdm = twin.to_maximal(q, v)
    qd_after, impulse_m, gap = _mbsynth_impact(struck, qm, qdm)
    assert abs(gap) < 1e-12  # the foot touches the plane in both descriptions
    assert abs((J @ v_after)[0] + e * (J @ v)[0]) < 1e-10  # Newton's law holds on Pinocchio's side
    v_mapped = twin.to_pinocchio(qm, qd_after)[1]
    scale = np.abs(v).max()
    assert np.abs(v_mapped - v_after).max() < 1e-10 * scale
    assert abs(impulse_m - impulse[0]) < 1e-10 * abs(impulse[0])


def test_a_run_from_the_striking_state_records_pinocchios_impulse(solo):
    """The run's own impact (event-driven, analysis/impacts.py) at the start of a run from
    the state of seed 1 records the impulse Pinocchio gives."""
    system, twin, model = solo
    q, v = sample_pinocchio_state(twin, np.random.default_rng(1))
    v, _, impulse, height, _ = _pinocchio_impact(model, q, v, 0.6)
    struck = system.with_parameters(h=float(height), e=0.6)
    qm, qdm = twin.to_maximal(q, v)
    traj = mb.simulate(struck, 1e-4, q0=qm, qd0=qdm, method="RK45")
    first = traj.events[0]
    assert (first.t, first.name, first.kind) == (0.0, "foot", "impact")
    assert abs(first.impulse - impulse[0]) < 1e-10 * abs(impulse[0])
