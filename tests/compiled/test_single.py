"""Data.motion's one compiled call (compiled/single.py) against the Engine's two calls
(the generated function, then kernel.motion_rates), which the rest of the compiled path
makes: the same kernel on the same state gives the same q̈ and Qc, bit for bit, and λ."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.compiled.single import WRONG_SIZE, motion_into
from tests.helpers.free_spin import free_spin

ROOT = Path(__file__).resolve().parents[2]


def _state(model, seed):
    rng = np.random.default_rng(seed)
    q, _ = model.initial_state()
    return q, rng.uniform(-1.0, 1.0, model.n)


@pytest.mark.parametrize("name", ["ur5", "talos"])
def test_one_call_equals_the_engines_two_calls(name):
    model = mb.from_robot(name, floating=name == "talos")
    data = model.data("compiled")
    q, qd = _state(model, 1)
    engine = data.engine
    expected = engine.motion(0.0, q.copy(), qd.copy())
    found = data.motion(0.0, q, qd)
    assert engine.single is not None, "Data.motion did not take the one call"
    np.testing.assert_array_equal(found.qdd, expected.qdd)
    np.testing.assert_array_equal(found.Qc, expected.Qc)
    lam = data.motion(0.0, list(q), qd).lam  # a list: the two calls (λ by BLAS: its rounding may follow alignment)
    assert np.abs(found.lam - lam).max() <= 1e-14 * np.abs(lam).max()
    reference = data.motion(0.0, q, qd, method="reference")
    assert np.abs(found.qdd - reference.qdd).max() <= 1e-9 * max(1.0, np.abs(reference.qdd).max())
    assert np.abs(found.lam - reference.lam).max() <= 1e-8 * max(1.0, np.abs(reference.lam).max())


def test_a_state_numba_would_type_otherwise_takes_the_checked_path():
    """A list, a strided view, a read-only array or float32 entries: the same motion as a
    plain copy, and no second compilation of the one call."""
    model = mb.from_robot("ur5")
    data = model.data("compiled")
    q, qd = _state(model, 2)
    expected = data.motion(0.0, q.copy(), qd.copy()).qdd
    strided = np.zeros((model.n, 2))
    strided[:, 0] = q
    frozen = qd.copy()
    frozen.flags.writeable = False
    for state in ((list(q), qd), (strided[:, 0], qd), (q, frozen)):
        np.testing.assert_array_equal(data.motion(0.0, *state).qdd, expected)
    single = q.astype(np.float32)
    np.testing.assert_array_equal(data.motion(0.0, single, qd).qdd, data.motion(0.0, single.astype(float), qd).qdd)
    assert len(motion_into.signatures) <= 2  # the rigid tree's and the general variant's


def test_a_state_of_the_wrong_size_is_named():
    model = mb.from_robot("ur5")
    data = model.data("compiled")
    q, qd = _state(model, 3)
    engine = data.engine
    data.motion(0.0, q, qd)
    block = np.full((4, model.n), 7.0)
    assert engine.single(0.0, q[:-1].copy(), qd, block)[0] == WRONG_SIZE
    assert (block == 7.0).all()
    with pytest.raises(ValueError, match=f"has {model.n} coordinates"):
        data.motion(0.0, q[:-1].copy(), qd)


def test_the_motion_keeps_the_state_it_was_asked_at():
    """The Motion's λ is read at the copies the one call made: the caller's arrays changed
    after the call change nothing (Qc − C = Aᵀλ at the state of the call)."""
    model = mb.from_robot("ur5")
    data = model.data("compiled")
    q, qd = _state(model, 4)
    arrays = data.evaluate(0.0, q.copy(), qd.copy())
    motion = data.motion(0.0, q, qd)
    q += 0.5
    qd[:] = 0.0
    force = arrays.M @ motion.qdd - arrays.Q - arrays.C
    assert np.abs(arrays.A.T @ motion.lam - force).max() <= 1e-12 * np.abs(force).max()
    assert motion.residual <= 1e-13


@pytest.mark.parametrize("path", ["compiled", "kkt"])
def test_acceleration_is_the_motions_qdd_in_the_datas_own_array(path):
    """Data.acceleration writes motion()'s q̈ (bit for bit) into data.qdd and returns it;
    the next call overwrites it; a state the one call does not take (a list) and a model
    closing loops give the motion's q̈ too."""
    model = mb.from_robot("ur5")
    data = model.data(path)
    q, qd = _state(model, 5)
    expected = data.motion(0.0, q, qd).qdd
    found = data.acceleration(0.0, q, qd)
    assert found is data.qdd
    np.testing.assert_array_equal(found, expected)
    q2, qd2 = _state(model, 6)
    data.acceleration(0.0, list(q2), qd2)
    np.testing.assert_array_equal(found, data.motion(0.0, q2, qd2).qdd)
    loop = mb.load(ROOT / "models" / "mechanisms" / "bricard.yaml")
    looped = loop.data(path)
    q, qd = loop.initial_state()
    np.testing.assert_array_equal(looped.acceleration(0.0, q, qd), looped.motion(0.0, q, qd).qdd)


def test_acceleration_raises_as_motion_does():
    model = mb.from_robot("ur5")
    data = model.data("compiled")
    q, qd = _state(model, 7)
    with pytest.raises(ValueError, match=f"has {model.n} coordinates"):
        data.acceleration(0.0, q[:-1].copy(), qd)


def test_a_state_the_kernel_declines_is_the_exact_treatments():
    """A massless body free to spin (helpers/free_spin.py): the kernel hands the state back,
    and motion() and acceleration() give the exact treatment's q̈ from the one call's copies
    of the state — the closed form of a body turning at constant ω, the ghost not spinning."""
    model, q, qd, expected = free_spin()
    data = model.data("compiled")
    assert data.engine.motion_into(0.0, q, qd, np.zeros((4, model.n))) == (False, 0.0)  # declined
    motion = data.motion(0.0, q, qd)
    assert not motion.unique
    assert np.abs(motion.qdd - expected).max() <= 1e-10 * np.abs(expected).max()
    np.testing.assert_array_equal(data.acceleration(0.0, q, qd), motion.qdd)
