"""The compiled path (mbsynth.compiled): its hand-differentiated rows and body blocks against the
sympy-compiled ones, its accelerations against the reference (2.14) on every model file and
on random chains, trees and loops, its fallback to the exact treatment, and the batch.

The kernels compile once per machine (numba's cache); ``engine_for(...)``
builds an Engine synchronously, so each test knows the tree path answered.
"""

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.model.constraints.joints import Joint
from mbsynth.core.equations import constrained_acceleration, equilibrate_rows
from mbsynth.core.joint_kinds import JOINT_KINDS, KINDS
from mbsynth.core.tolerances import RANK_RTOL
from mbsynth.core.errors import SolveError
from mbsynth.compiled import engine_for
from mbsynth.compiled.bodies import body_force, rate_transpose
from mbsynth.compiled.joints import vector_work
from mbsynth.compiled.joints import joint_rows as kernel_rows
from mbsynth.compiled.assembly import make_work, nodes
from mbsynth.compiled.layout import build as build_layout
from mbsynth.compiled.packing import pack
from mbsynth.compiled.rate_rows import rate_rows
from mbsynth.compiled.rows import Rows
from mbsynth.compiled.tree import _components_closed, _null_space_components
from mbsynth.core import kinematics
from mbsynth.core.kinematics import body_rate_matrix

from mbsynth.analysis.velocity_form import VelocityForm
from tests.helpers.compare import rel
from tests.helpers.free_spin import free_spin
from tests.helpers.rotations import E
from tests.helpers.literal import literal_2_14
from tests.helpers.states import random_state

MODELS = sorted((Path(__file__).resolve().parents[2] / "models").glob("**/*.yaml"))
# the longest cases, run by make test-slow and CI: the largest model, and two capsules' rows (a minute to derive cold)
SLOW_MODELS = ("quadruped.yaml", "crossed_capsules.yaml")
TREE = "tree (Baraff)"

# Every joint kind (core/joint_kinds.py) once, between bodies, a particle and the world, with
# frames turned and offset (rpy, axis), and a loop: a revolute joint from the last body back to
# the world.
ALL_JOINTS = """
name: all_joints
parameters: {m: 1.3, L: 0.4}
gravity: [0.3, -0.2, -9.81]
world:
  frames:
    pivot: {position: [0.1, -0.2, 1.5], rpy: [0.3, -0.2, 0.5]}
    hook: {position: [0.7, 0.4, 0.2], axis: [1, 1, 0]}
parts:
  b0: {type: rigid_body, mass: m, inertia: [[0.05, 0.01, 0], [0.01, 0.04, 0.002], [0, 0.002, 0.03]],
       frames: {top: {position: [0, 0, L], rpy: [0.1, 0.2, 0.3]}, low: {position: [0.1, 0, -L], axis: [0, 1, 1]}}}
  b1: {type: rigid_body, mass: 0.7, inertia: [0.02, 0.03, 0.04],
       frames: {a: {position: [0.05, 0.1, 0.2], rpy: [-0.4, 0.1, 0.2]}, b: {position: [0, -0.1, -0.3]}}}
  b2: {type: rigid_body, mass: 0.9, inertia: [0.03, 0.02, 0.02],
       frames: {a: {position: [0.1, 0, 0.1], axis: [1, 0, 1]}, b: {position: [-0.1, 0.2, 0], rpy: [0.5, 0, 0]}}}
  b3: {type: rigid_body, mass: 1.1, inertia: [0.04, 0.05, 0.02],
       frames: {a: {position: [0, 0.1, 0.1], rpy: [0, 0.3, -0.2]}, b: {position: [0.2, 0, 0]}}}
  b4: {type: rigid_body, mass: 0.5, inertia: [0.01, 0.02, 0.02],
       frames: {a: {position: [0, 0, 0.2], rpy: [0.2, 0.2, 0.2]}, b: {position: [0.1, 0.1, 0], axis: [0, 0, 1]}}}
  bob: {type: particle, mass: 0.3}
  b5: {type: rigid_body, mass: 0.6, inertia: [0.02, 0.02, 0.01], frames: {a: {position: [0, 0.1, 0.3]}}}
joints:
  - {name: j_spherical, type: spherical, parent: world.pivot, child: b0.top}
  - {name: j_revolute, type: revolute, parent: b0.low, child: b1.a}
  - {name: j_universal, type: universal, parent: b1.b, child: b2.a}
  - {name: j_cylindrical, type: cylindrical, parent: b2.b, child: b3.a}
  - {name: j_prismatic, type: prismatic, parent: b3.b, child: b4.a}
  - {name: j_fixed, type: fixed, parent: b4.b, child: b5.a}
  - {name: j_distance, type: distance, parent: b4, child: bob, length: 0.35}
  - {name: j_world_revolute, type: revolute, parent: world.hook, child: b5}
"""


def loads(text):
    return mb.loads(textwrap.dedent(text), name="model.yaml")


@pytest.fixture(scope="module")
def all_joints():
    return loads(ALL_JOINTS)


def test_joint_rows_equal_the_sympy_rows(all_joints):
    """joints.joint_rows (differentiated by hand) against Joint.evaluate (sympy), every kind
    of the table, at random states with quaternions of any length (the forms are homogeneous)."""
    system = all_joints
    L = build_layout(system)[0]
    kernel_joints = [c for c in system.constraints if isinstance(c, Joint)]
    assert len(L.joint_k) == len(kernel_joints) == 8
    assert sorted({c.joint_kind for c in kernel_joints}) == sorted(JOINT_KINDS)  # a new kind joins ALL_JOINTS
    V, R, Jt = vector_work()
    A, b = np.zeros((6, 14)), np.zeros(6)
    rng = np.random.default_rng(3)
    for trial in range(5):
        q, qd = random_state(system, rng, norm=1.0 if trial % 2 == 0 else (0.7, 1.4))
        for j, con in enumerate(kernel_joints):
            a_ref, b_ref, _ = con.evaluate(0.0, q, qd, system.parameter_values)
            k = int(L.joint_k[j])
            kernel_rows(L.joint_program[j], k, L.joint_kinds[j], L.joint_start[j], L.joint_s[j], L.joint_R[j],
                        L.joint_length[j], q, qd, V, R, Jt, A, b)
            full = np.zeros((k, system.n))
            for e in range(2):
                if L.joint_kinds[j, e]:
                    width = 7 if L.joint_kinds[j, e] == 1 else 3
                    full[:, L.joint_start[j, e]:L.joint_start[j, e] + width] += A[:k, 7 * e:7 * e + width]
            expected = np.zeros((k, system.n))
            expected[:, con.indices] = a_ref
            assert np.abs(full - expected).max() <= 1e-12 * max(1.0, np.abs(expected).max()), con.joint_kind
            assert np.abs(b[:k] - b_ref).max() <= 1e-12 * max(1.0, np.abs(b_ref).max()), con.joint_kind


def test_rate_rows_equal_the_sympy_rows_in_body_rates(all_joints):
    """rate_rows.rate_rows (rows on (r̈, α) of the bodies) against Joint.evaluate (sympy)
    mapped through q̈ = (r̈, (u s + EᵀBᵀα)/ν), B = R(u)/(2ν), s = −u̇·u̇/ν, for every joint
    without a particle, quaternions of any length."""
    system = all_joints
    L = build_layout(system)[0]
    kernel_joints = [c for c in system.constraints if isinstance(c, Joint)]
    A, b = np.zeros((6, 14)), np.zeros(6)
    Rs = make_work(L).Rs  # with the world's slot
    rng = np.random.default_rng(4)
    for trial in range(4):
        q, qd = random_state(system, rng, norm=1.0 if trial % 2 == 0 else (0.7, 1.4))
        mu = nodes(q, qd, np.zeros(0), L.node_kind, L.node_q, L.node_mass, L.node_mg, L.node_J, L.quat_row,
                   np.zeros(system.n), np.zeros(system.n), np.zeros((len(L.node_kind), 6, 6)),
                   np.zeros((len(L.node_kind), 6)), np.zeros(len(L.node_kind)), np.zeros(len(L.node_kind)),
                   np.zeros(7), Rs)
        assert mu > 0
        for j, con in enumerate(kernel_joints):
            if 2 in L.joint_kinds[j]:  # a particle end: joints.py
                continue
            a_ref, b_ref, _ = con.evaluate(0.0, q, qd, system.parameter_values)
            k = int(L.joint_k[j])
            rate_rows(L.joint_program[j], k, L.joint_kinds[j], L.joint_node[j], L.joint_start[j], L.joint_s[j],
                      L.joint_R[j], L.joint_length[j], q, qd, Rs, A, b)
            full = np.zeros((k, system.n))
            full[:, con.indices] = a_ref
            expected_b = b_ref.astype(float).copy()
            for e in range(2):
                if L.joint_kinds[j, e] == 0:
                    continue
                o = L.joint_start[j, e]
                u, ud = q[o + 3:o + 7], qd[o + 3:o + 7]
                nu = np.linalg.norm(u)
                B = np.array(kinematics.rotation(u), dtype=float) / (2 * nu)
                E = np.array(kinematics.body_rate_matrix(u), dtype=float)
                c_r, c_u = full[:, o:o + 3], full[:, o + 3:o + 7]
                expected_a = c_u @ E.T @ B.T / nu  # (E c_u / ν)·Bᵀα
                assert np.abs(A[:k, 6 * e:6 * e + 3] - c_r).max() <= 1e-12, con.joint_kind
                assert np.abs(A[:k, 6 * e + 3:6 * e + 6] - expected_a).max() <= 1e-12, con.joint_kind
                expected_b -= c_u @ u * (-(ud @ ud) / nu) / nu
            assert np.abs(b[:k] - expected_b).max() <= 1e-12 * max(1.0, np.abs(expected_b).max()), con.joint_kind


def test_every_kind_agrees_in_every_interpreter(all_joints):
    """Per kind of the table (core/joint_kinds.py), at seeded states with quaternions of any
    length: the compiled φ, φ̇ (rows.residuals_energy) equal the sympy rows' (whose φ is the
    spec's, OPERATIONS); the joint has exactly its kind's free motions (what its efforts act
    along) and its joint values, one entry per position and rate its record names."""
    system = all_joints
    L = build_layout(system)[0]
    kernel_joints = [c for c in system.constraints if isinstance(c, Joint)]
    assert sorted({c.joint_kind for c in kernel_joints}) == sorted(JOINT_KINDS)  # a new kind joins ALL_JOINTS
    rows = Rows(L, pack(L), int(L.sizes[1]))
    rng = np.random.default_rng(61)
    for trial in range(4):
        q, qd = random_state(system, rng, norm=1.0 if trial % 2 == 0 else (0.7, 1.4))
        phi, psi = (x.copy() for x in rows(q, qd)[:2])
        values = system.joint_values(0.0, q, qd)
        for j, con in enumerate(kernel_joints):
            kind, at = KINDS[con.joint_kind], slice(L.joint_row[j], L.joint_row[j] + L.joint_k[j])
            phi_ref, psi_ref = con.residuals(0.0, q, qd, system.parameter_values)
            assert np.abs(phi[at] - phi_ref).max() <= 1e-12 * max(1.0, np.abs(phi_ref).max()), kind.name
            assert np.abs(psi[at] - psi_ref).max() <= 1e-12 * max(1.0, np.abs(psi_ref).max()), kind.name
            assert [m for m in ("angle", "displacement") if getattr(con, m) is not None] == list(kind.motions)
            if kind.rates:
                assert values[con.name].position.shape == (len(kind.positions),), kind.name
                assert values[con.name].rate.shape == (len(kind.rates),), kind.name
            else:
                assert con.name not in values


def test_closed_form_null_spaces_of_revolute_and_fixed_rows():
    """tree._components_closed (revolute and fixed rows in closed form) gives J S = 0,
    J Jr = I and the same S, Jr as the Cholesky-based _null_space_components, and
    refuses dependent dot rows as it does."""
    rng = np.random.default_rng(8)
    for k in (5, 6):
        for trial in range(20):
            J = np.zeros((k, 6))
            J[:3, :3] = np.diag(rng.uniform(0.2, 1.0, 3) * rng.choice([-1, 1], 3))
            J[:3, 3:] = rng.normal(size=(3, 3))
            J[3:, 3:] = rng.normal(size=(k - 3, 3))
            dependent = trial % 4 == 3
            if dependent:
                J[4, 3:] = 2.0 * J[3, 3:]
            S, Jr, S_ref, Jr_ref = np.zeros((6, 6)), np.zeros((6, 6)), np.zeros((6, 6)), np.zeros((6, 6))
            closed = _components_closed(J, 0, k, S, Jr)
            general = _null_space_components(J, 0, k, S_ref, Jr_ref, np.zeros((12, 12)))
            assert closed == general == (not dependent)
            if dependent:
                continue
            m = 6 - k
            assert np.abs(J @ S[:, :m]).max(initial=0.0) <= 1e-12 and np.abs(J @ Jr[:, :k] - np.eye(k)).max() <= 1e-11
            assert np.abs(S[:, :m] - S_ref[:, :m]).max(initial=0.0) <= 1e-12
            assert np.abs(Jr[:, :k] - Jr_ref[:, :k]).max() <= 1e-11 * np.abs(Jr_ref).max()


def test_body_blocks_equal_the_sympy_blocks(all_joints):
    """Q of bodies.body_force and the reduced mass blockdiag(0, 4ν²J) = U (4EᵀJE) Uᵀ with
    U = [uᵀ; E(u)]/ν, against RigidBody.evaluate."""
    system = all_joints
    rng = np.random.default_rng(5)
    part = system.parts[0]
    values = dict(zip(system.parameter_symbols, system.parameter_values))
    J = np.array(part.inertia.subs(values).tolist(), dtype=float)
    mg = np.array(part.Q[:3, 0].subs(values).tolist(), dtype=float).ravel()
    for _ in range(5):
        q, qd = rng.standard_normal(7), rng.standard_normal(7)
        M, Q = part.evaluate(0.0, q, qd, system.parameter_values)
        out = np.zeros(7)
        body_force(mg, J, q[3:], qd[3:], out)
        assert rel(out, Q) < 1e-13
        u = q[3:]
        nu = np.linalg.norm(u)
        E = np.array(body_rate_matrix(list(u)).tolist(), dtype=float)
        U = np.vstack([u, E]) / nu
        assert np.allclose(U @ U.T, np.eye(4), atol=1e-14)
        reduced = U @ M[3:, 3:] @ U.T
        assert np.abs(reduced[0]).max() < 1e-12 * np.abs(M).max()
        assert rel(reduced[1:, 1:], 4 * nu**2 * J) < 1e-13
        assert np.allclose(rate_transpose(u, (1.0, 2.0, 3.0)), E.T @ [1.0, 2.0, 3.0], atol=1e-14)


def assert_same_motion(system, t, q, qd, *, rtol=1e-10):
    """The compiled path answers, and as (2.15) does."""
    engine = engine_for(system)
    assert engine is not None
    fast = engine.motion(t, q, qd)
    ref = system.motion(t, q, qd, method="reference")
    assert ref.unique
    assert fast is not None and fast.method == TREE
    assert rel(fast.qdd, ref.qdd) < rtol
    assert rel(fast.Qc, ref.Qc) < 1e3 * rtol
    assert fast.unique and fast.nullspace.shape == (system.n, 0) and fast.residual < 1e-12
    return fast


def test_rigid_transport_carries_the_parent_rows(all_joints):
    """For a body on a rigid parent, X = [[I, [ζ]×], [0, I]] (assembly.transports) satisfies
    J X = −P for its joint rows at any state, on or off the constraint manifold (tree.py
    relies on it): random states of the model with every joint kind."""
    engine = engine_for(all_joints)
    L, W = engine.L, engine.W
    rng = np.random.default_rng(5)
    checked = set()
    for trial in range(4):
        q, qd = random_state(all_joints, rng, norm=1.0 if trial % 2 == 0 else (0.7, 1.4))
        engine.motion(0.0, q, qd)
        for i in np.flatnonzero((L.node_transport != 0) & (L.node_parent >= 0)):
            r0, k = L.node_rows[i], L.node_k[i]
            zeta = W.zeta[i]
            X = np.eye(6)
            X[:3, 3:] = [[0, -zeta[2], zeta[1]], [zeta[2], 0, -zeta[0]], [-zeta[1], zeta[0], 0]]
            J, P = W.J[r0:r0 + k], W.P[r0:r0 + k]
            assert np.abs(J @ X + P).max() <= 1e-12 * max(1.0, np.abs(P).max())
            checked.add(int(L.node_transport[i]))
    assert checked == {1, 2}  # rows invariant under rotation, and world components of d


def test_all_joints_and_a_loop_agree_with_the_reference(all_joints):
    rng = np.random.default_rng(11)
    for _ in range(4):
        q, qd = random_state(all_joints, rng)
        assert_same_motion(all_joints, 0.0, q, qd)


@pytest.mark.parametrize("path", [pytest.param(p, marks=pytest.mark.slow) if p.name in SLOW_MODELS else p for p in MODELS],
                         ids=[f"{p.parent.name}/{p.name}" for p in MODELS])
def test_every_model_file(path):
    """Wherever the kernels cover a model: at its initial state and nearby states, the same
    acceleration as (2.15) when that is unique, the same verdict or error when not."""
    system = mb.load(path)
    engine = engine_for(system)
    if engine is None:
        assert build_layout(system) is None
        return
    rng = np.random.default_rng(1)
    q0, qd0 = system.initial_state()
    for trial in range(3):
        q = q0 if trial == 0 else q0 + 0.02 * rng.standard_normal(system.n)
        qd = qd0 if trial == 0 else qd0 + 0.3 * rng.standard_normal(system.n)
        try:
            ref = system.motion(0.25, q, qd, method="reference")
        except SolveError as err:
            with pytest.raises(SolveError) as caught:
                system.motion(0.25, q, qd)
            assert str(caught.value) == str(err)
            continue
        fast = engine.motion(0.25, q, qd)
        if not ref.unique:
            assert fast is None
            motion = system.motion(0.25, q, qd)
            assert not motion.unique and motion.nullspace.shape == ref.nullspace.shape
            arrays = system.evaluate(0.25, q, qd)
            assert rel(motion.qdd, literal_2_14(arrays.M, arrays.Q, arrays.A, arrays.b, arrays.C)) < 1e-8
            continue
        scale = max(np.linalg.norm(ref.qdd), acceleration_scale(system, 0.25, q, qd))
        if fast is None:  # the kernel defers a massless part to (2.14) (its pivot below the cut): only then
            assert has_massless_part(system, q, qd), path.name
            assert rel(system.motion(0.25, q, qd).qdd, ref.qdd) < 1e-12
            continue
        gap = np.linalg.norm(fast.qdd - ref.qdd) / scale
        if gap >= agreement(system, 0.25, q, qd):  # then the kernel's answer must solve the equations better
            mine, theirs = (equation_residual(system, 0.25, q, qd, x.qdd) for x in (fast, ref))
            assert mine <= max(theirs, 1e-14), f"{path.name}: gap {gap:.2e}, residuals {mine:.1e} vs {theirs:.1e}"


def has_massless_part(system, q, qd):
    """Whether a part's block of M is zero at (q, q̇): a link of zero mass and inertia."""
    M, start = system.evaluate(0.25, q, qd).M, 0
    for part in system.parts:
        stop = start + len(part.coordinates)
        if not np.any(M[start:stop, start:stop]):
            return True
        start = stop
    return False


def acceleration_scale(system, t, q, qd):
    """The size of the accelerations the terms of (2.14) stand for, where they cancel (a
    bicycle rolling steadily: q̈ = 0 from forces and rows of size v²/R): ‖b‖ over the
    largest entry of A, and ‖Q + C‖ over the largest entry of M."""
    arrays = system.evaluate(t, q, qd)
    parts = [np.linalg.norm(arrays.b) / np.abs(arrays.A).max(initial=0.0) if arrays.A.size and np.any(arrays.A) else 0.0,
             np.linalg.norm(arrays.Q + arrays.C) / np.abs(arrays.M).max() if np.any(arrays.M) else 0.0]
    return max(parts + [1e-300])


def agreement(system, t, q, qd):
    """How closely two backward-stable solves must agree at a state: 1e-10, or 1e3 ε κ
    where the rows of A are nearly dependent (Bricard's loop off its manifold) or [M; A] is
    ill-conditioned (a flexible part's light, stiff modal coordinates beside its frame);
    κ = σ₁/σ_r of the row-equilibrated matrix, σ_r its smallest singular value above the
    rank cut."""
    arrays = system.evaluate(t, q, qd)
    bound = 1e-10
    for matrix in (arrays.A, np.vstack([arrays.M, arrays.A])):
        s = np.linalg.svd(equilibrate_rows(matrix)[0], compute_uv=False) if matrix.size else np.zeros(0)
        if s.size and s[0] > 0:  # a model with rows (A), or any model ([M; A])
            kept = s[s > RANK_RTOL * s[0]]
            bound = max(bound, 1e3 * np.finfo(float).eps * kept[0] / kept[-1])
    return bound


def equation_residual(system, t, q, qd, qdd):
    """How far q̈ is from solving (2.4)–(2.5) with ideal forces: the largest of |A q̈ − b| and
    of the force balance Nᵀ(M q̈ − Q − C) along the rows' null space N, each relative to the
    size of its terms."""
    arrays = system.evaluate(t, q, qd)
    A, M, force = arrays.A, arrays.M, arrays.Q + arrays.C
    rows = np.abs(A @ qdd - arrays.b).max(initial=0.0) / max((np.abs(A) @ np.abs(qdd) + np.abs(arrays.b)).max(
        initial=0.0), 1e-300)
    null = np.linalg.svd(A)[2][np.linalg.matrix_rank(A):].T if A.size else np.eye(system.n)
    balance = np.abs(null.T @ (M @ qdd - force)).max(initial=0.0) / max(
        (np.abs(M) @ np.abs(qdd) + np.abs(force)).max(initial=0.0), 1e-300)
    return max(rows, balance)


def numbers(values):
    return "[" + ", ".join(f"{float(x):.6f}" for x in values) + "]"


def chain(count, kinds, masses, rng, loop=None):
    """A random open chain of rigid bodies hanging from the world; ``loop``: a distance rod
    (or a second spherical joint, 'redundant') from the last body back to the world."""
    lines = ["name: chain", "gravity: [0, 0, -9.81]", "parts:"]
    for i in range(count):
        moments = np.sort(rng.uniform(0.01, 0.05, 3))
        moments[2] = min(moments[2], 0.9 * (moments[0] + moments[1]))
        top, low = rng.uniform(-0.2, 0.2, 3) + [0, 0, 0.3], rng.uniform(-0.2, 0.2, 3) - [0, 0, 0.3]
        rpy_top, rpy_low = [rng.uniform(-0.5, 0.5), 0, 0], [0, 0, rng.uniform(-0.5, 0.5)]  # sparse: quick sympy
        lines.append(f"  b{i}: {{type: rigid_body, mass: {masses[i]:.6f}, inertia: {numbers(moments)}, frames: "
                     f"{{top: {{position: {numbers(top)}, rpy: {numbers(rpy_top)}}}, "
                     f"low: {{position: {numbers(low)}, rpy: {numbers(rpy_low)}}}}}}}")
    lines.append("joints:")
    for i, kind in enumerate(kinds):
        parent = "world" if i == 0 else f"b{i - 1}.low"
        extra = ", length: 0.3" if kind == "distance" else ""
        lines.append(f"  - {{name: j{i}, type: {kind}, parent: {parent}, child: b{i}.top{extra}}}")
    if loop == "rod":
        lines.append(f"  - {{name: closing, type: distance, parent: world, child: b{count - 1}.low, length: 1.0}}")
    elif loop == "redundant":
        lines.append("  - {name: again, type: spherical, parent: world, child: b0.top}")
    return loads("\n".join(lines) + "\n")


@pytest.mark.parametrize("seed", range(4))
def test_random_chains(seed):
    """Random joint kinds and frames; seed 1 has a massless body inside the chain (its block
    is singular alone, invertible with its child's fixed joint), seed 2 closes a loop with a
    rod, seed 3 repeats the first joint (three redundant rows)."""
    rng = np.random.default_rng(seed)
    count = 3
    kinds = list(rng.choice(["spherical", "revolute", "universal", "cylindrical", "prismatic"], count))
    masses = list(rng.uniform(0.5, 2.0, count))
    if seed == 1:
        masses[1], kinds[2] = 0.0, "fixed"
    if seed == 3:
        kinds[0] = "spherical"
    system = chain(count, kinds, masses, rng, loop={2: "rod", 3: "redundant"}.get(seed))
    for _ in range(2):
        q, qd = random_state(system, rng)
        assert_same_motion(system, 0.0, q, qd)


def test_a_rigid_tree_of_uneven_masses_is_solved_unchecked_and_its_residual_is_small():
    """A rigid tree's motion comes without the kernel's residual check per call (engine.py:
    the articulated elimination is backward stable, so the check is decided at layout time);
    on a chain whose masses span six decades its residual, computed when read by the checked
    kernel, is still within rounding, and the motion is (2.15)'s."""
    from mbsynth.compiled import kernel
    from mbsynth.core.tolerances import KERNEL_RESIDUAL_MAX

    rng = np.random.default_rng(4)
    system = chain(4, ["revolute", "spherical", "fixed", "universal"], [1.0, 1e-3, 1e-6, 1.0], rng)
    assert engine_for(system).mode == kernel.UNCHECKED
    for _ in range(3):
        q, qd = random_state(system, rng)
        fast = assert_same_motion(system, 0.0, q, qd, rtol=agreement(system, 0.0, q, qd))
        assert "residual" not in vars(system.motion(0.0, q, qd))  # not computed until read
        assert fast.residual < 1e-6 * KERNEL_RESIDUAL_MAX


def test_indeterminate_and_inconsistent_cases_fall_back():
    """A massless leaf body on a spherical joint can spin freely (not unique); a row
    contradicting a fixed joint (no motion); a force on a massless particle (no motion):
    the kernels hand them back, and the exact treatment answers as mechanics does. The
    heavy body turns about its fixed centre of mass (spherical inertia, no torque) at a
    constant ω: ü = −|ω|²u/4 (u̇ = u ⊗ (0, ω)/2), and the ghost's centre, at the tip
    r = (0, 0, −0.5), has ω × (ω × r); its own spin is free, η = 0 gives it none. The
    errors carry their numbers: z̈ = 1 against the weld's z̈ = 0, rows (1, 0) of b out of
    the range of two equal unit rows by 1/√2; the force 1 on the massless dot."""
    free, q, qd, expected = free_spin()
    assert engine_for(free).motion(0.0, q, qd) is None
    motion = free.motion(0.0, q, qd)
    assert not motion.unique and motion.nullspace.shape == (14, 3)
    assert np.abs(motion.nullspace[:10]).max() < 1e-12  # the ghost's spin alone
    assert rel(motion.qdd, expected) < 1e-10

    contradiction = loads("""
        name: contradiction
        parts:
          block: {type: rigid_body, mass: 1.0, inertia: [0.1, 0.1, 0.1]}
        joints:
          - {name: weld, type: fixed, parent: world, child: block}
        constraints:
          - {name: push, acceleration: {A: {block.z: 1}, b: 1}}
        """)
    pushed = loads("""
        name: pushed
        parts:
          dot: {type: particle, mass: 0.0}
        forces:
          - {name: shove, type: force, at: dot, value: [1, 0, 0]}
        """)
    expected = [(contradiction, f"component of norm {1 / np.sqrt(2):.3g} outside the range", ("push", "weld[z]"), ()),
                (pushed, "no mass resists: wᵀ(Q + C) = 1 ≠ 0", (), ("dot.x",))]
    for system, words, constraints, coordinates in expected:
        q, qd = system.initial_state()
        assert engine_for(system).motion(0.0, q, qd) is None
        with pytest.raises(SolveError) as fast:
            system.motion(0.0, q, qd)
        assert words in str(fast.value), str(fast.value)
        assert fast.value.constraints == constraints and fast.value.coordinates == coordinates


def test_batch_equals_single_states(all_joints):
    """motion_batch row by row equals (2.14) on the row's arrays (system.evaluate, solved by
    equations.constrained_acceleration, not by the kernels); a state the kernels hand back
    (a NaN) is reported as the exact path reports it, naming its row."""
    system = mb.load(next(p for p in MODELS if p.name == "spring_pendulum.yaml"))
    rng = np.random.default_rng(2)
    states = [random_state(system, rng) for _ in range(37)]
    q, qd = np.array([s[0] for s in states]), np.array([s[1] for s in states])
    t = rng.uniform(0, 2, len(states))
    qdd, unique = system.motion_batch(t, q, qd)
    assert unique.all()
    for row in range(len(states)):  # the reference's own rounding reaches 1e-10 here (its SVD)
        arrays = system.evaluate(t[row], q[row], qd[row])
        literal = constrained_acceleration(arrays.M, arrays.Q, arrays.A, arrays.b, arrays.C).qdd
        assert rel(qdd[row], literal) < 1e-9
    column_major = np.asfortranarray(q)  # made row-contiguous for the kernels, the caller's array untouched
    assert np.array_equal(system.motion_batch(t, column_major, qd)[0], qdd) and np.array_equal(column_major, q)
    q[5, 3] = np.nan  # a quaternion component: M is not finite
    with pytest.raises(SolveError, match="state 5 of the batch"):
        system.motion_batch(t, q, qd)
    q, qd = random_state(all_joints, rng)
    qdd, unique = all_joints.motion_batch(0.0, [q, q], [qd, qd])
    assert unique.all() and rel(qdd[1], all_joints.motion(0.0, q, qd, method="reference").qdd) < 1e-10


def test_an_integrators_stage_equals_the_motion(all_joints):
    """The compiled stage (staged.Stages.rates), what simulate's stages call, gives (q̇, q̈) with
    q̈ that of System.motion bit for bit, and (2.14)'s to 1e-10, also from a state in a
    strided array; None where the kernel hands the problem back (a NaN)."""
    stages = engine_for(all_joints).stages()  # y = (q, q̇) itself
    q, qd = random_state(all_joints, np.random.default_rng(11))
    y = np.concatenate([q, qd])
    found = stages.rates(0.7, y)
    assert np.array_equal(found[:q.size], qd)
    assert np.array_equal(found[q.size:], all_joints.motion(0.7, q, qd).qdd)
    assert rel(found[q.size:], all_joints.motion(0.7, q, qd, method="reference").qdd) < 1e-10
    strided = np.zeros(2 * y.size)
    strided[::2] = y
    assert np.array_equal(stages.rates(0.7, strided[::2]), found)
    y[3] = np.nan
    assert stages.rates(0.7, y) is None


def test_an_integrators_stage_in_its_own_form(all_joints):
    """The compiled stage in the integrator's form (analysis/velocity_form.py: y with each
    rigid body's angular velocity) gives ẏ = (q̇, v̇) in one call: q̇ of the state y stands
    for, each rigid body's v̇ = E(u) ü / |u|² from System.motion's ü there (E by hand,
    tests/helpers/rotations.py), the other entries q̈."""
    engine, form = engine_for(all_joints), VelocityForm(all_joints)
    q, qd = random_state(all_joints, np.random.default_rng(12))
    y = form.to_integrator(q, qd)
    q, qd = form.to_state(y)
    qdd = all_joints.motion(0.3, q, qd).qdd
    found = engine.stages(form.starts).rates(0.3, y)
    n, bodies = all_joints.n, list(form.starts)
    assert bodies and found.shape == (form.size,)
    assert np.array_equal(found[:n], qd)
    expected, j = [], 0
    for s in bodies:
        expected += list(qdd[j:s]) + list(E(q[s:s + 4]) @ qdd[s:s + 4] / (q[s:s + 4] @ q[s:s + 4]))
        j = s + 4
    expected += list(qdd[j:])
    assert rel(found[n:], np.array(expected)) < 1e-13


def test_baumgarte_and_parameters(all_joints):
    """Baumgarte's shifted b and changed parameters reach the kernels."""
    rng = np.random.default_rng(9)
    q, qd = random_state(all_joints, rng)
    engine = engine_for(all_joints)
    phi, psi = all_joints.constraint_residuals(0.0, q, qd)
    shift = -2 * 3.0 * np.nan_to_num(psi) - 4.0**2 * np.nan_to_num(phi)
    fast = engine.motion(0.0, q, qd, shift)
    assert fast is not None
    assert rel(fast.qdd, all_joints.motion(0.0, q, qd, method="reference", baumgarte=(3.0, 4.0)).qdd) < 1e-10
    assert rel(all_joints.motion(0.0, q, qd, baumgarte=(3.0, 4.0)).qdd, fast.qdd) < 1e-12
    heavier = all_joints.with_parameters(m=4.0)
    assert_same_motion(heavier, 0.0, q, qd)
    assert rel(engine_for(heavier).motion(0.0, q, qd).qdd, fast.qdd) > 1e-3


@pytest.mark.implementation
def test_compiled_code_is_kept_per_version_of_the_sources(tmp_path):
    """numba checks only the file of the function it loads from its cache, so a kernel built
    against an older module it calls would come back stale: the cache directory is named by
    a digest of all the compiled path's sources, which any edit changes."""
    import shutil

    from mbsynth.compiled import cache

    copy = tmp_path / "fast"
    shutil.copytree(Path(cache.__file__).parent, copy, ignore=shutil.ignore_patterns("__pycache__"))
    before = cache.sources_hash(copy)
    assert before == cache.sources_hash(cache.HERE)
    (copy / "tree.py").write_text((copy / "tree.py").read_text() + "\n# edited\n")
    assert cache.sources_hash(copy) != before


@pytest.mark.implementation
def test_cache_configuration_tolerates_numba_half_imported(tmp_path):
    """A background build configures the cache while the caller's thread may be importing
    numba: its config module is then in sys.modules without its settings yet."""
    script = ("import sys, types\nsys.modules['numba.core.config'] = types.ModuleType('numba.core.config')\n"
              "from mbsynth.compiled import cache\ncache.configure()\nimport os\nprint(os.environ['NUMBA_CACHE_DIR'])")
    env = dict(os.environ, MBSYNTH_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert Path(out.stdout.strip()).is_relative_to(tmp_path / "numba")


@pytest.mark.implementation
def test_stale_versions_of_the_numba_cache_are_pruned(tmp_path):
    """configure() marks its version's directory and removes the versions unused for
    STALE_DAYS (by their mark, or the directory's own time when unmarked); recent ones stay."""
    from mbsynth.core.files import MARK

    root = tmp_path / "numba"
    days = 86400
    for name, age, marked in (("old", 40, True), ("recent", 2, True), ("unmarked_old", 40, False)):
        folder = root / name
        folder.mkdir(parents=True)
        (folder / "kernel.nbi").write_text("")
        stamped = folder / MARK if marked else folder
        if marked:
            stamped.write_text("")
        os.utime(stamped, (time.time() - age * days,) * 2)
    script = "from mbsynth.compiled import cache; cache.configure(); print(cache.digest())"
    env = dict(os.environ, MBSYNTH_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_CACHE_DIR", None)
    digest = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True,
                            check=True).stdout.strip()
    assert sorted(p.name for p in root.iterdir()) == sorted(["recent", digest])
    assert time.time() - (root / digest / MARK).stat().st_mtime < 600


@pytest.mark.implementation
def test_kernels_imported_first_still_cache_per_version(tmp_path):
    """Importing a kernel module directly (not through the Engine) must not put its compiled
    code in numba's default place beside the sources, where it would come back stale."""
    script = ("from mbsynth.compiled import kernel, cache, tree\n"
              "print(kernel.motion._cache._cache_path)\nprint(tree.factor._cache._cache_path)\n"
              "print(cache.digest())")
    env = dict(os.environ, MBSYNTH_CACHE_DIR=str(tmp_path))
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    kernel_path, tree_path, digest = out.stdout.split()
    for path in (kernel_path, tree_path):
        assert Path(path).is_relative_to(tmp_path / "numba" / digest)


@pytest.mark.slow  # numba compiles kernel.motion afresh, not from its cache
@pytest.mark.implementation
@pytest.mark.parametrize("name", ["rigid tree", "general"])
def test_helpers_compile_the_argument_types_motion_passes(name, all_joints):
    """ahead.py's helpers compile the kernel's largest parts ahead, each for argument types
    it names: a fresh compilation of kernel.motion (its callees loaded from the cache) asks
    each of them for exactly those, for a rigid tree and for the general variant."""
    from numba import njit

    from mbsynth.compiled import ahead, kernel
    system = mb.load(MODELS[0].parent.parent / "rigid" / "double_pendulum_3d.yaml") if name == "rigid tree" \
        else all_joints
    assert ahead.VARIANTS == {"rigid_tree": kernel.RIGID_TREE, "general": kernel.GENERAL}  # the helpers' names
    engine = engine_for(system)
    assert engine.general is (kernel.RIGID_TREE if name == "rigid tree" else kernel.GENERAL)
    fresh = njit(error_model="numpy")(kernel.motion.py_func)  # not cached: compiled here
    q, qd = random_state(system, np.random.default_rng(3))
    assert fresh(q, qd, engine.gen, np.zeros(0), *engine.buffers, kernel.CHECKED, -1.0, engine.general)[0] == kernel.OK
    for group in range(len(ahead.GROUPS)):
        for dispatcher, types in ahead.functions(group, engine.general):
            assert types in dispatcher.overloads, (dispatcher.py_func.__name__, list(dispatcher.overloads))
    assert rel(engine.W.qdd, system.motion(0.0, q, qd, method="reference").qdd) < 1e-10


@pytest.mark.implementation
def test_helper_processes_finish_and_failures_are_only_logged(monkeypatch, caplog):
    """``python -m mbsynth.compiled.ahead`` runs in this environment (here every group is in the
    cache already); a helper that fails is logged, not raised: numba compiles what it left."""
    import logging

    from mbsynth.compiled import ahead, kernel
    monkeypatch.setattr(ahead, "_started", set())
    monkeypatch.setattr(ahead, "_running", [])
    helpers = ahead.start(kernel.RIGID_TREE)
    assert len(helpers) == len(ahead.GROUPS) and ahead.start(kernel.RIGID_TREE) == []
    ahead.finish()
    assert ahead._running == []
    assert [h.returncode for h in helpers] == [0] * len(helpers)
    failing = subprocess.Popen([sys.executable, "-c", "import sys; sys.exit('no luck')"], stderr=subprocess.PIPE)
    with caplog.at_level(logging.INFO, logger="mbsynth.compiled.ahead"):
        ahead.wait([failing])
    assert "failed (1)" in caplog.text and "no luck" in caplog.text


@pytest.mark.implementation
def test_borrowed_arrays_share_the_callers_memory():
    """packing.borrowed drops only the reference count: its views read and write the
    caller's buffer, which numpy sees afterwards."""
    from numba import njit

    from mbsynth.compiled.packing import borrowed, view2

    @njit
    def fill(buf, index):
        view = view2(borrowed(buf), index, 0)
        view[1, :] = 7.0
        return view.sum()

    buf, index = np.arange(12.0), np.array([[2, 6, 2, 2, 3, 0, 0]])
    expected = buf[2:8].reshape(2, 3).copy()
    expected[1, :] = 7.0
    assert fill(buf, index) == expected.sum()
    assert np.array_equal(buf[2:8].reshape(2, 3), expected) and buf[1] == 1.0 and buf[8] == 8.0


@pytest.mark.implementation
def test_kernel_views_are_the_packed_fields():
    """packing.view1 … view4 (built without numba's slicing) see each packed field with
    numpy's shape and strides, int and float buffers alike, and write into the buffer."""
    from collections import namedtuple

    from numba import njit

    from mbsynth.compiled.packing import pack, view1, view2, view3, view4, views

    Fields = namedtuple("Fields", "a b c d e")
    arrays = Fields(np.arange(5.0), np.arange(6.0).reshape(2, 3), np.arange(24.0).reshape(2, 3, 4),
                    np.arange(3, dtype=np.int64), np.arange(120.0).reshape(2, 3, 4, 5))
    ints, floats, index = pack(arrays)

    @njit
    def read(ints, floats, index):
        a, b, c = view1(floats, index, 0), view2(floats, index, 1), view3(floats, index, 2)
        d, e = view1(ints, index, 3), view4(floats, index, 4)
        b[1, 2] = -1.0
        return a.copy(), b.copy(), c.copy(), d.copy(), e.copy(), (b.strides, c.strides, e.strides)

    *got, strides = read(ints, floats, index)
    expected = arrays._replace(b=np.array([[0.0, 1.0, 2.0], [3.0, 4.0, -1.0]]))
    for mine, theirs in zip(got, expected):
        assert mine.dtype == theirs.dtype and np.array_equal(mine, theirs)
    assert strides == (arrays.b.strides, arrays.c.strides, arrays.e.strides)
    assert views(Fields, arrays, ints, floats, index).b[1, 2] == -1.0  # written through


@pytest.mark.implementation
def test_motion_made_is_the_frozen_dataclass():
    """Motion.made (the compiled path's constructor) gives the same fields as Motion(...) and
    the same frozen object."""
    import dataclasses

    from mbsynth.core.equations import Motion

    fields = dict(qdd=np.arange(3.0), unique=True, nullspace=np.zeros((3, 0)), Qc=np.ones(3), residual=1e-16,
                  method="tree (Baraff)", singular=())
    made, built = Motion.made(**fields), Motion(**fields)
    assert [f.name for f in dataclasses.fields(made)] == [*fields, "C"]  # C: only from friction.coulomb_motion
    assert made.C is None and built.C is None
    for name, value in fields.items():
        assert np.array_equal(getattr(made, name), getattr(built, name))
    with pytest.raises(dataclasses.FrozenInstanceError):
        made.qdd = np.zeros(3)
