"""The flexible part's compiled kernel (compiled/flexible.py) against the same formulas in
sympy (``FlexibleBody.reference``, evaluated in sympy's floats): M, Q, the energies and the
linearization's Jacobians at seeded random states, with and without stiffening, damping and
gravity; and a flexible model built, run and linearized on both paths without its sympy form."""

from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import mbsynth as mb
from tests.helpers.flexible_beams import strip
from mbsynth.analysis.linearization import BlockFunction
from mbsynth.compiled import ahead, flexible
from mbsynth.model.data import Data
from mbsynth.model.flexible.reduction import craig_bampton
from mbsynth.model.parts.flexible_body import FlexibleBody, coordinates, rayleigh_damping
from mbsynth.model.parts.flexible_euler_body import EulerFlexibleBody, coordinates as angle_coordinates

MODELS = Path(__file__).resolve().parents[3] / "models" / "flexible"
G = sp.Symbol("g")
PARAMETERS, VALUES = [G], np.array([9.81])
STATES = 2  # random states per case


def body(r, stiffening, damping, gravity, seed=0, sequence=None):
    """A strip held at node 0 with r fixed-interface modes; a random S symmetric in (a, b)
    and in (k, l), Rayleigh damping, gravity (0.3, −g, 1.2) with g a parameter; its frame
    turned by a quaternion, or by the angles of ``sequence``."""
    reduction = craig_bampton(strip(6), [0], count=r).hold(0)
    rng = np.random.default_rng(seed)
    S = None
    if stiffening:
        S = rng.normal(size=(3, 3, r, r))
        S = (S + S.transpose(1, 0, 2, 3)) / 2
        S = (S + S.transpose(0, 1, 3, 2)) / 2
    names = coordinates(r) if sequence is None else angle_coordinates(sequence, r)
    q = [sp.Symbol(f"beam.{c}") for c in names]
    qd = [sp.Symbol(f"beam.{c}_dot") for c in names]
    g = sp.Matrix([0.3, -G, 1.2]) if gravity else sp.zeros(3, 1)
    options = dict(stiffening=S, damping=rayleigh_damping(reduction, 0.3, 2e-4) if damping else None)
    if sequence is None:
        return FlexibleBody("beam", q, qd, reduction, g, PARAMETERS, **options)
    return EulerFlexibleBody("beam", sequence, q, qd, reduction, g, PARAMETERS, **options)


def states(r, rng, turns=4):
    """(q, q̇): any quaternion (not of unit norm: the formulas hold for every u) or any
    ``turns`` = 3 angles, η and rates of the size a motion has."""
    for _ in range(STATES):
        q = np.concatenate([rng.normal(size=3 + turns), 1e-2 * rng.normal(size=r)])
        yield q, rng.normal(size=3 + turns + r)


def relative(found, expected):
    return np.abs(found - expected).max() / np.abs(expected).max()


CASES = [(r, s, d, g) for r in (1, 4, 8) for s, d, g in ((False, False, False), (True, True, True))] + [
    (4, True, False, False), (4, False, True, False), (4, False, False, True)]


@pytest.mark.parametrize("r, stiffening, damping, gravity", CASES)
def test_the_kernels_M_Q_and_energies_are_the_sympy_formulas(r, stiffening, damping, gravity):
    """M, Q, T, V and the damping's power at random states equal sympy's to 1e-12 relative."""
    same_as_sympy(body(r, stiffening, damping, gravity), r, 4)


@pytest.mark.parametrize("sequence, r", [("zxy", 4), ("xyz", 1), ("zxz", 4)])
def test_the_kernel_turned_by_angles_is_the_sympy_formulas(sequence, r):
    """A part turned by the angles of ``sequence`` (Tait–Bryan or proper Euler: the kernel's
    H(α) and Ḣα̇ against core/kinematics.py's sympy euler_rotation and euler_rate_matrix):
    M, Q, T, V at random states equal sympy's to 1e-12 relative, stiffening, damping and
    gravity on."""
    same_as_sympy(body(r, True, True, True, sequence=sequence), r, 3)


def same_as_sympy(part, r, turns):
    """Assert M, Q, T, V and the power of ``part`` equal its sympy form's at random states."""
    eta_dot = sp.Matrix(part.qd[part.elastic])
    expressions = (*part.reference(), (-eta_dot.T * sp.Matrix(part.damping.tolist()) * eta_dot)[0])
    for q, qd in states(r, np.random.default_rng(r), turns):
        values = {s: sp.Float(v) for s, v in zip(part.q + part.qd + PARAMETERS, np.concatenate([q, qd, VALUES]))}
        M_ref, Q_ref, T_ref, V_ref, power = (x.xreplace(values) for x in expressions)
        M_found, Q_found = part.evaluate(0.0, q, qd, VALUES)
        assert relative(M_found, np.array(M_ref, float)) < 1e-12
        assert relative(Q_found, np.array(Q_ref, float).ravel()) < 1e-12
        T_found, V_found = part.energy(0.0, q, qd, VALUES)
        assert T_found == pytest.approx(float(T_ref), rel=1e-12)
        assert V_found == pytest.approx(float(V_ref), rel=1e-12, abs=1e-12 * abs(float(T_ref)))
        assert part.power(0.0, q, qd, VALUES) == pytest.approx(float(power), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("r, sequence", [(1, None), (4, None), (4, "zxy")])
def test_the_parts_jacobians_are_the_complex_step_of_its_sympy_form(r, sequence):
    """∂(M q̈ − Q)/∂q, ∂q̇ and ∂g of ``derivatives()`` equal the complex step through the
    sympy M and Q (linearization.py's BlockFunction) to 1e-10 relative."""
    part = body(r, True, True, True, sequence=sequence)
    M, Q, _, _ = part.reference()
    n = len(part.q)
    qdd = [sp.Symbol(f"qdd{i}") for i in range(n)]
    reference = BlockFunction(part.q, part.qd, qdd, [], PARAMETERS, M * sp.Matrix(qdd) - Q)
    rng = np.random.default_rng(7)
    for q, qd in states(r, rng, n - 3 - r):
        a = rng.normal(size=n)
        expected = reference.jacobians(0.0, q, qd, a, np.zeros(0), VALUES, [0])
        found = part.derivatives().jacobians(0.0, q, qd, a, np.zeros(0), VALUES, [0])
        for f, e in zip(found, expected):
            assert relative(f, e) < 1e-10


@pytest.fixture
def without_sympy_form(monkeypatch):
    """FlexibleBody.reference raising: whatever asks for the part's sympy M or Q fails."""
    def refused(self):
        raise AssertionError("the flexible part's sympy M and Q were asked for")
    monkeypatch.setattr(FlexibleBody, "reference", refused)


def test_a_flexible_model_runs_and_linearizes_on_both_paths_without_its_sympy_form(without_sympy_form):
    """The clamped strip (models/flexible/cantilever.yaml) is built, run 0.01 s on the compiled
    path and on the KKT path, and linearized, its part's sympy form never made; both paths'
    q̈ agree to 1e-9 (one state alone and in a batch) and the linearization's lowest frequency
    is the clamped–free strip's (βL)² √(EI/ρAL⁴) with βL = 1.8751 to 1e-4 (the 40-element mesh
    and 4 modes). The kernel's functions were called with the argument types compile-ahead
    compiles them for (ahead.PARTS)."""
    model = mb.load(MODELS / "cantilever.yaml")
    q, qd = model.initial_state()
    fast = Data(model, "compiled")
    assert fast.engine is not None
    compiled = fast.motion(0.0, q, qd).qdd
    kkt = Data(model, "kkt").motion(0.0, q, qd).qdd
    assert relative(compiled, kkt) < 1e-9
    batch, status = fast.engine.motion_batch(np.zeros(2), np.array([q, q]), np.array([qd, qd]))
    assert (status == 0).all() and relative(batch[1], kkt) < 1e-9
    run = mb.simulate(model, 0.01)
    assert run.status == "completed"
    lin = mb.linearize(model, 0.0, q, np.zeros_like(qd))
    omega = np.sort(np.abs(np.linalg.eigvals(lin.A).imag))
    expected = 1.8751041 ** 2 * np.sqrt(2.1e11 * 1e-9 / (7850 * 1e-4 * 2.0 ** 4))
    assert omega[omega > 1.0][0] == pytest.approx(expected, rel=1e-4)
    for module, name, spec in ahead.PARTS:
        assert ahead.argument_types(spec, None) in getattr(flexible, name).overloads, (name, spec)


@pytest.mark.parametrize("name", ["slider_crank", "spin_up_beam"])
def test_the_other_flexible_models_build_without_their_parts_sympy_form(without_sympy_form, name):
    """models/flexible's slider-crank (rigid bodies beside the flexible rod, joints at its
    node frames) and spin-up beam (stiffening, a servo) are built and give the same q̈ on both
    paths (1e-9) at their initial state and t = 1 s (the servo's hub accelerating: the spin-up
    beam rests at t = 0), the flexible part's sympy form never made."""
    model = mb.load(MODELS / f"{name}.yaml")
    q, qd = model.initial_state()
    fast = Data(model, "compiled")
    assert fast.engine is not None
    expected = Data(model, "kkt").motion(1.0, q, qd).qdd
    assert np.abs(expected).max() > 0 and relative(fast.motion(1.0, q, qd).qdd, expected) < 1e-9
