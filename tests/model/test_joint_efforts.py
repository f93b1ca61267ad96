"""The efforts along a joint (actuation, joint springs and dampers: model/joint_forces.py)
act along the joint's values (model/joint_values.py): for every kind with free motions, an
actuation's power is Σ effort · rate, a spring's potential ½ k (position − rest)² and its
damper's power −c · rate², with the positions and rates the joint values report."""

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.core.joint_kinds import EFFORTS, JOINT_KINDS, KINDS
from tests.helpers.states import random_state

MOVING = [k for k in JOINT_KINDS if KINDS[k].motions]
EFFORT = {"torque": 0.7, "force": -1.3}
SPRING = {"stiffness": 3.0, "damping": 0.4, "rest": 0.2}


def effort_chain():
    """A hanging chain with one joint of every kind that has free motions, each actuated
    along all of them and, where it has one motion, sprung."""
    bodies = "\n".join(f"  b{i}: {{type: rigid_body, mass: 1.0, inertia: [0.02, 0.03, 0.04], "
                       f"frames: {{top: {{position: [0, 0, 0.2]}}, bottom: {{position: [0, 0, -0.2]}}}}, "
                       f"initial: {{position: [0, 0, {-0.2 - 0.4 * i:.1f}]}}}}" for i in range(len(MOVING)))
    joints = []
    for i, kind in enumerate(MOVING):
        efforts = {EFFORTS[m]: EFFORT[EFFORTS[m]] for m in KINDS[kind].motions}
        spring = f", spring: {SPRING}" if len(efforts) == 1 else ""
        joints.append(f"  - {{name: j_{kind}, type: {kind}, parent: {'world' if i == 0 else f'b{i - 1}.bottom'}, "
                      f"child: b{i}.top, actuation: {efforts}{spring}}}")
    return mb.loads(f"name: effort_chain\nsubsystems:\n{bodies}\njoints:\n" + "\n".join(joints) + "\n")


def test_efforts_act_along_the_joint_values():
    """At seeded states (on the constraints and off them), every kind with free motions."""
    system = effort_chain()
    data = system.data()
    elements = {element.name: element for element in system.forces}
    assert sorted(elements) == sorted([f"j_{k}.actuation" for k in MOVING]
                                      + [f"j_{k}.spring" for k in MOVING if len(KINDS[k].motions) == 1])
    rng = np.random.default_rng(61)
    states = [system.initial_state()] + [random_state(system, rng) for _ in range(5)]
    for q, qd in states:
        qd = qd + 0.3  # every joint moves at the initial state too
        values = data.joint_values(0.0, q, qd)
        for kind in MOVING:
            motions = KINDS[kind].motions
            position, rate = (getattr(values[f"j_{kind}"], x)[:len(motions)] for x in ("position", "rate"))
            actuation = elements[f"j_{kind}.actuation"].power(0.0, q, qd, data.parameter_values)
            expected = sum(EFFORT[EFFORTS[m]] * w for m, w in zip(motions, rate))
            assert actuation == pytest.approx(expected, rel=1e-12, abs=1e-12)
            if len(motions) == 1:
                spring = elements[f"j_{kind}.spring"]
                assert spring.potential(0.0, q, qd, data.parameter_values) == pytest.approx(
                    SPRING["stiffness"] * (position[0] - SPRING["rest"]) ** 2 / 2, rel=1e-12, abs=1e-12)
                assert spring.power(0.0, q, qd, data.parameter_values) == pytest.approx(-SPRING["damping"] * rate[0] ** 2,
                                                                         rel=1e-12, abs=1e-12)
