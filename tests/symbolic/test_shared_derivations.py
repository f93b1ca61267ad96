"""Joints alike share one derivation (constraints.joints' templates): the rows a joint gets
that way equal those of differentiating its own φ directly, and the derivation is done once."""

import numpy as np
import sympy as sp

from mbsynth.model.constraints.joints import Joint
from mbsynth.model.constraints import joints
from mbsynth.core.kinematics import rpy_matrix
from mbsynth.model.parts import Frame, RigidBody
from mbsynth.symbolic.derive import differentiate

RNG = np.random.default_rng(7)


def frame(part, name):
    """A frame at a random offset and orientation, exact rationals as the loaders give."""
    offset = [sp.Rational(int(x), 1000) for x in RNG.integers(-500, 500, 3)]
    rotation = sp.Matrix(rpy_matrix(*RNG.uniform(-3, 3, 3))).applyfunc(sp.nsimplify)
    return Frame(part, name, sp.Matrix(offset), rotation)


def two_bodies(count):
    q = sp.symbols(f"q0:{7 * count}")
    qd = sp.symbols(f"qd0:{7 * count}")
    bodies = [RigidBody(f"b{i}", q[7 * i:7 * i + 7], qd[7 * i:7 * i + 7], sp.Integer(1 + i), sp.diag(1, 2, 3),
                        (0, 0, -9.81), []) for i in range(count)]
    return list(q), list(qd), bodies


def test_joints_alike_share_one_derivation_and_keep_their_own_rows():
    q, qd, (b0, b1, b2) = two_bodies(3)
    first = Joint("j1", "revolute", b0, frame("b0", "f"), b1, frame("b1", "f"), q, qd, [])
    templates = dict(joints.TEMPLATES.kept)
    second = Joint("j2", "revolute", b1, frame("b1", "g"), b2, frame("b2", "g"), q, qd, [])
    assert joints.TEMPLATES.kept == templates
    state = dict(zip(q + qd, RNG.normal(size=len(q) + len(qd))))
    for joint in (first, second):
        for r, phi in enumerate(joint.phi):
            a, b, _ = differentiate(phi, q, qd)  # the joint's own φ, numbers in place
            for i in joint.indices:
                assert abs(float(joint.a[r, int(i)].subs(state)) - float(a[0, int(i)].subs(state))) < 1e-12
            assert abs(float(joint.b[r].subs(state)) - float(b.subs(state))) < 1e-10


def test_a_bodys_unit_norm_row_is_the_derivative_of_its_own_constraint():
    """The placed row uᵀü = −u̇ᵀu̇ (rigid_body.own_constraints) against differentiating
    φ = (uᵀu − 1)/2 in the body's own symbols, at a state off the unit sphere."""
    q, qd, (_, body) = two_bodies(2)
    (row,) = body.own_constraints(q, qd, [])
    u = sp.Matrix(body.q[3:])
    phi = ((u.T * u)[0] - 1) / 2
    a, b, psi = differentiate(phi, q, qd)
    x, xd = RNG.normal(size=len(q)), RNG.normal(size=len(q))
    state = dict(zip(q + qd, [*x, *xd]))
    got_a, got_b, _ = row.evaluate(0.0, x, xd, np.array([]))
    got_phi, got_psi = row.residuals(0.0, x, xd, np.array([]))
    assert list(row.indices) == [10, 11, 12, 13]
    assert np.allclose(got_a.ravel(), [float(a[0, i].subs(state)) for i in row.indices], rtol=1e-14)
    assert np.isclose(got_b[0], float(b.subs(state)), rtol=1e-14)
    assert np.isclose(got_phi[0], float(phi.subs(state)), rtol=1e-14)
    assert np.isclose(got_psi[0], float(psi.subs(state)), rtol=1e-14)
    assert row.row_names == ["b1.unit_quaternion"] and sp.simplify(row.phi[0] - phi) == 0
