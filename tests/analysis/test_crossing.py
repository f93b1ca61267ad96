"""The step plan near singular positions (mbsynth.analysis.crossing): where the steps end so
that the one across a singular position keeps its stages away from it, checked against the
methods' own nodes (scipy's Butcher tableaux)."""

import numpy as np
import pytest
import scipy.integrate

from mbsynth.analysis.crossing import PLAN_BELOW, Crossing, nodes


def nearest_node(crossing, start, length, t_star):
    """The distance from t* to the nearest node of a step from ``start`` of ``length``."""
    return np.abs(start + crossing.nodes * length - t_star).min()


@pytest.mark.parametrize("method", [scipy.integrate.DOP853, scipy.integrate.RK45, scipy.integrate.RK23])
def test_the_step_across_keeps_its_nodes_farthest_from_the_singular_position(method):
    """θ* lies at the centre of the widest gap between the method's nodes; a step planned
    from ends whose measure falls linearly to zero at t* ends first at t* − θ* h, then
    crosses t* with its nearest node as far from it as any step of length ≤ h can put it
    (brute force over lengths)."""
    crossing = Crossing(method)
    c = nodes(method)
    assert c[0] == 0.0 and c[-1] == 1.0 and set(method.C) <= set(c)
    gaps = np.diff(c)
    assert np.abs(c - crossing.theta).min() == pytest.approx(gaps.max() / 2)
    t_star, h, rate = 1.0, 0.02, 0.7
    for t in (0.97, 0.98):  # measure = rate (t* − t)
        crossing.passed(t, rate * (t_star - t))
    target, across = crossing.plan(0.98, h, bound=10.0)
    assert not across and target == pytest.approx(t_star - crossing.theta * h)
    crossing.passed(target, rate * (t_star - target))
    end, across = crossing.plan(target, h, bound=10.0)
    assert across and end - target == pytest.approx(h)
    assert nearest_node(crossing, target, end - target, t_star) == pytest.approx(gaps.max() / 2 * h)
    for d in (1e-5, 1e-3, 0.4 * crossing.theta * h):  # nearer than θ* h: the best step from here
        length = crossing.across(d, h)
        lengths = np.linspace(d * 1.0001, h, 20001)
        best = max(nearest_node(crossing, 0.0, x, d) for x in lengths)
        assert length <= h and nearest_node(crossing, 0.0, length, d) >= best * (1 - 1e-3)


def test_no_plan_far_from_a_singular_position_or_past_the_bound():
    """No plan where the measure rises, stays above PLAN_BELOW, puts t* beyond the next step,
    or where the step across would pass the integrator's bound."""
    crossing = Crossing(scipy.integrate.DOP853)
    crossing.passed(0.0, 0.2)
    crossing.passed(0.1, 0.3)
    assert crossing.plan(0.1, 0.05, 10.0) == (None, False)  # rising
    crossing.passed(0.2, PLAN_BELOW * 1.5)
    crossing.passed(0.3, PLAN_BELOW * 1.2)
    assert crossing.plan(0.3, 0.05, 10.0) == (None, False)  # above PLAN_BELOW
    crossing.restart()
    crossing.passed(0.0, 0.3)
    crossing.passed(0.1, 0.2)  # t* = 0.3
    assert crossing.plan(0.1, 0.05, 10.0) == (None, False)  # beyond the next step
    crossing.passed(0.29, 0.01)  # t* = 0.3 (slope 0.19/0.19 = 1)
    assert crossing.plan(0.29, 0.05, bound=0.295) == (None, False)
    assert crossing.plan(0.28, 0.05, bound=10.0) == (None, False)  # not where the last end is
