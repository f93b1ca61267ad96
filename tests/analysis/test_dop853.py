"""The run loop's DOP853 (mbsynth.analysis.dop853) against scipy's ``scipy.integrate.DOP853``:
the same steps, bit for bit — first step, rejected trials, step sizes, states, derivatives —
the same interpolant, the same failures and errors."""

import numpy as np
import pytest
import scipy.integrate

from mbsynth.analysis.dop853 import DOP853
from mbsynth.core import dop853_tableau as tableau
from scipy.integrate._ivp import dop853_coefficients, rk


TOL = dict(rtol=1e-6, atol=1e-6)


class Counted:
    """A right-hand side that counts its calls: a rejected trial step costs twelve."""

    def __init__(self, fun):
        self.fun, self.calls = fun, 0

    def __call__(self, t, y):
        self.calls += 1
        return self.fun(t, y)


def van_der_pol(t, y):
    """μ = 30: stiff enough that some trial steps are rejected at these tolerances."""
    return np.array([y[1], 30.0 * (1 - y[0] ** 2) * y[1] - y[0] + 0.1 * np.sin(t)])


def forced_oscillator(t, y):
    return np.array([y[1], -y[0] - 0.2 * y[1] + np.sin(3 * t)])


def run_both(t0, y0, t_bound, fun=van_der_pol, **options):
    """Both solvers stepped side by side to the end, each step's state compared exactly;
    returns (ours, theirs, steps, calls)."""
    mine_f, theirs_f = Counted(fun), Counted(fun)
    mine = DOP853(mine_f, t0, np.array(y0), t_bound, **options)
    theirs = scipy.integrate.DOP853(theirs_f, t0, np.array(y0), t_bound, **options)
    first = 1 if options.get("first_step") else 2  # f at the start, and the trial of the initial step's choice
    assert mine.h_abs == theirs.h_abs and mine_f.calls == theirs_f.calls == first
    steps = 0
    while theirs.status == "running":
        assert mine.step() == theirs.step()
        steps += 1
        assert (mine.status, mine.t, mine.t_old, mine.h_abs, mine.h_previous) == \
            (theirs.status, theirs.t, theirs.t_old, theirs.h_abs, theirs.h_previous)
        assert np.array_equal(mine.y, theirs.y) and np.array_equal(mine.f, theirs.f)
        assert np.array_equal(mine.y_old, theirs.y_old) and mine_f.calls == theirs_f.calls
    return mine, theirs, steps, mine_f.calls


def test_the_tableau_and_step_control_are_scipys():
    for name in ("A", "B", "C", "E3", "E5", "D", "N_STAGES", "N_STAGES_EXTENDED", "INTERPOLATOR_POWER"):
        assert np.array_equal(getattr(tableau, name), getattr(dop853_coefficients, name)), name
    assert (tableau.SAFETY, tableau.MIN_FACTOR, tableau.MAX_FACTOR) == (rk.SAFETY, rk.MIN_FACTOR, rk.MAX_FACTOR)


@pytest.mark.parametrize("options, rejecting", [
    (dict(rtol=1e-6, atol=1e-8), True), (dict(rtol=1e-10, atol=np.array([1e-12, 1e-9])), True),
    (dict(rtol=1e-4, atol=1e-6, max_step=0.05, first_step=1e-3), False)])
def test_every_step_is_scipys_bit_for_bit(options, rejecting):
    """Van der Pol at μ = 30 over 3 s: every step equal, rejected trials included (the call
    counts agree; where ``rejecting``, they exceed twelve a step), and capped steps."""
    mine, theirs, steps, calls = run_both(0.0, [2.0, 0.0], 3.0, **options)
    assert mine.status == "finished" and mine.t == 3.0
    assert (calls > 12 * steps + 2) == rejecting


def test_a_run_backwards_in_time_is_scipys():
    mine, theirs, steps, _ = run_both(1.0, [1.5, -0.5], -2.5, forced_oscillator, rtol=1e-8, atol=1e-8)
    assert mine.status == "finished" and mine.t == -2.5 and steps > 5


def test_the_interpolant_is_scipys():
    """dense_output() of a step at scalar and array times equals scipy's to a few units of
    rounding (its sums compiled, in another order), and that of a step of no length exactly."""
    mine, theirs = DOP853(van_der_pol, 0.0, np.array([2.0, 0.0]), 3.0, rtol=1e-8, atol=1e-8), \
        scipy.integrate.DOP853(van_der_pol, 0.0, np.array([2.0, 0.0]), 3.0, rtol=1e-8, atol=1e-8)
    for _ in range(4):
        mine.step(), theirs.step()
    times = np.linspace(mine.t_old, mine.t, 9)
    close = 8 * np.finfo(float).eps * np.abs(theirs.dense_output()(times)).max()
    assert np.abs(mine.dense_output()(times) - theirs.dense_output()(times)).max() <= close
    assert mine.dense_output()(times).shape == theirs.dense_output()(times).shape == (2, 9)
    assert np.abs(mine.dense_output()(times[3]) - theirs.dense_output()(times[3])).max() <= close
    assert mine.dense_output()(times[3]).shape == (2,)
    with pytest.raises(ValueError, match="1-D"):
        mine.dense_output()(times[None, None, :])
    still, still_theirs = DOP853(van_der_pol, 1.0, np.array([1.0, 2.0]), 1.0, **TOL), \
        scipy.integrate.DOP853(van_der_pol, 1.0, np.array([1.0, 2.0]), 1.0, **TOL)
    still.step(), still_theirs.step()
    assert still.status == still_theirs.status == "finished"
    assert np.array_equal(still.dense_output()(np.array([1.0, 1.0])), still_theirs.dense_output()(np.array([1.0, 1.0])))
    assert np.array_equal(still.dense_output()(1.0), still_theirs.dense_output()(1.0))


def test_a_step_below_the_smallest_fails_with_scipys_message():
    mine, theirs = DOP853(van_der_pol, 1.0, np.array([2.0, 0.0]), 2.0, **TOL), \
        scipy.integrate.DOP853(van_der_pol, 1.0, np.array([2.0, 0.0]), 2.0, **TOL)
    mine.max_step = theirs.max_step = 1e-300
    assert mine.step() == theirs.step() == scipy.integrate.DOP853.TOO_SMALL_STEP
    assert mine.status == theirs.status == "failed"
    with pytest.raises(RuntimeError, match="failed or finished"):
        mine.step()
    with pytest.raises(RuntimeError, match="after a successful step"):
        DOP853(van_der_pol, 0.0, np.array([2.0, 0.0]), 1.0, **TOL).dense_output()


@pytest.mark.parametrize("arguments, message", [
    (dict(y0=np.zeros((2, 2))), "1-dimensional"), (dict(y0=np.array([np.nan, 0.0])), "finite"),
    (dict(max_step=0.0), "max_step"), (dict(first_step=-1.0), "first_step` must be positive"),
    (dict(first_step=5.0), "exceeds bounds"), (dict(atol=np.ones(3)), "atol` has wrong shape"),
    (dict(atol=-1.0), "atol` must be positive")])
def test_bad_arguments_raise_scipys_errors(arguments, message):
    given = dict(y0=np.array([2.0, 0.0])) | TOL | arguments
    y0 = given.pop("y0")
    for kind in (DOP853, scipy.integrate.DOP853):
        with pytest.raises(ValueError, match=message):
            kind(van_der_pol, 0.0, y0, 1.0, **given)


def test_a_tiny_rtol_is_raised_with_a_warning():
    with pytest.warns(UserWarning, match="rtol"):
        solver = DOP853(van_der_pol, 0.0, np.array([2.0, 0.0]), 1.0, rtol=1e-20, atol=1e-6)
    assert solver.rtol == 100 * np.finfo(float).eps
