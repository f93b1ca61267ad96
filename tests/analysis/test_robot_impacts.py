"""A robot's foot striking the ground against Pinocchio's impulse dynamics, and a robot
standing on its feet against its constraint dynamics.

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
from mbsynth.core.solvers import kkt_acceleration
from mbsynth.model.reactions import multipliers
from mbsynth.model.unilateral import Gaps
from mbsynth.robots.twin import Twin
from mbsynth.robots.validate import sample_pinocchio_state

MODEL = """
name: solo_strike
parameters: {h: -1.0, e: 0.0}
gravity: [0, 0, -9.81]
parts:
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
    gaps = Gaps(system, data.parameter_values)
    g, gd = gaps.values(0.0, q, qd, data.parameter_values)
    A_gap = gaps.rows(0.0, q, qd, data.parameter_values)[0]
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


FEET = ("FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT")


def test_standing_on_four_feet_equals_pinocchio_constraint_dynamics(solo):
    """solo12 with its four feet held on the ground (each foot's gap row and its slip rows,
    the contact of a sticking foot) at a random state whose feet are at rest: q̈ and the
    contact forces equal ``pinocchio.constraintDynamics`` with a CONTACT_3D per foot
    (LOCAL_WORLD_ALIGNED: its force in world axes, the gap row's λ its z, the slip rows' λ
    its x and y, the tangents of the plane z = h being e_x, e_y)."""
    system, twin, model = solo
    feet = "\n".join(f"  - {{name: {f}, type: plane, child: solo_{f}.link, ground: h_{f}, friction: 1}}"
                     for f in FEET)
    standing = mb.loads(MODEL.split("contacts:")[0].replace("parameters: {h: -1.0, e: 0.0}", "parameters: {"
                        + ", ".join(f"h_{f}: -1.0" for f in FEET) + "}") + "contacts:\n" + feet + "\n")
    q, v = sample_pinocchio_state(twin, np.random.default_rng(4))
    data = model.createData()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    ids = [model.getFrameId(f) for f in FEET]
    J = np.vstack([pin.getFrameJacobian(model, data, i, pin.LOCAL_WORLD_ALIGNED)[:3] for i in ids])
    _, s, Vt = np.linalg.svd(J)
    v = Vt[len(s):].T @ Vt[len(s):] @ v  # the feet at rest
    contacts = [pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, model.frames[i].parentJoint,
                                         model.frames[i].placement, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
                for i in ids]
    contact_data = [c.createData() for c in contacts]
    pin.initConstraintDynamics(model, data, contacts, contact_data)
    a = pin.constraintDynamics(model, data, q, v, np.zeros(model.nv), contacts, contact_data,
                               pin.ProximalSettings(1e-14, 1e-12, 100))
    forces = np.array(data.lambda_c).reshape(4, 3)
    heights = {f"h_{f}": float(data.oMf[i].translation[2]) for f, i in zip(FEET, ids)}
    held = standing.with_parameters(**heights)
    qm, qdm = twin.to_maximal(q, v)
    kept = held.data()
    gaps = Gaps(held, kept.parameter_values)
    arrays = kept.evaluate(0.0, qm, qdm)
    A_gaps, b_gaps = gaps.rows(0.0, qm, qdm, kept.parameter_values)
    slips = [gaps.slip_arrays(0.0, qm, qdm, kept.parameter_values, i) for i in range(4)]
    A = np.vstack([arrays.A, A_gaps, *(T for T, _ in slips)])
    b = np.concatenate([arrays.b, b_gaps, *(b_slip for _, b_slip in slips)])
    motion = kkt_acceleration(arrays.M, arrays.Q, A, b, arrays.C)
    lam = multipliers(A, arrays.M @ motion.qdd - arrays.Q - arrays.C)[0]
    scale = np.abs(a).max()
    assert np.abs(twin.to_pinocchio(qm, qdm, motion.qdd)[2] - a).max() < 1e-10 * scale
    k = len(arrays.b)
    ours = np.column_stack([lam[k + 4:].reshape(4, 2), lam[k:k + 4]])  # (x, y, z) per foot
    assert np.abs(ours - forces).max() < 1e-10 * np.abs(forces).max()
