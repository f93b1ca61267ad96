"""The run loop's hold on its integrators (mbsynth.analysis.stepper) against their own
public results: the interpolant read as one product equals ``dense_output()``, and an
explicit pair moved and resumed steps exactly as a new one started there."""

import numpy as np
import pytest
import scipy.integrate

import mbsynth as mb
from mbsynth.analysis import stepper


def damped(t, y):
    return np.array([y[1], -np.sin(y[0]) - 0.1 * y[1], np.cos(3 * t) * y[0]])


@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_rows_read_the_integrators_own_interpolant(method):
    """The states within a step (DOP853's interpolant compiled) equal scipy's dense output of
    the same step, at its ends too."""
    solver = stepper.integrator(method)(damped, 0.0, np.array([1.0, 0.3, 0.2]), 10.0, rtol=1e-10, atol=1e-10)
    theirs = getattr(scipy.integrate, method)(damped, 0.0, np.array([1.0, 0.3, 0.2]), 10.0, rtol=1e-10, atol=1e-10)
    for _ in range(5):
        solver.step(), theirs.step()
    assert solver.t == theirs.t
    times = np.linspace(solver.t_old, solver.t, 17)
    rows = np.full((times.size, 3), np.nan)
    stepper.interpolate(solver, list(times), rows)
    assert np.abs(rows - theirs.dense_output()(times).T).max() <= 4 * np.finfo(float).eps
    assert np.abs(rows[-1] - solver.y).max() <= 4 * np.finfo(float).eps


@pytest.mark.implementation
@pytest.mark.parametrize("method", stepper.RESUMABLE)
def test_a_moved_and_resumed_pair_steps_as_a_new_one(method):
    """Run to a bound, move the state (as a projection does), resume towards a farther bound
    with a proposed step: every later step equals, bit for bit, that of a new solver
    started at the moved state with that first step."""
    method = stepper.integrator(method)
    solver = method(damped, 0.0, np.array([1.0, 0.3, 0.2]), 2.0, rtol=1e-9, atol=1e-9)
    while solver.status == "running":
        solver.step()
    assert solver.status == "finished" and solver.t == 2.0
    y = solver.y + np.array([1e-6, -2e-6, 0.0])
    stepper.move(solver, y, None)  # moved, its derivative not known yet
    assert not stepper.stands_at(solver, y)
    stepper.move(solver, y, damped(solver.t, y))
    assert stepper.stands_at(solver, y) and not stepper.stands_at(solver, y + 1e-9)
    stepper.resume(solver, 5.0, first_step=0.05)
    fresh = method(damped, 2.0, y, 5.0, rtol=1e-9, atol=1e-9, first_step=0.05)
    while fresh.status == "running":
        solver.step()
        fresh.step()
        assert solver.t == fresh.t and np.array_equal(solver.y, fresh.y)
    assert solver.status == "finished" and solver.t == 5.0


@pytest.mark.implementation
def test_a_rewound_step_is_taken_again_shorter():
    """``rewind`` puts the solver back where ``saved`` found it, its steps capped: the step
    taken again is the capped one, from the same state."""
    solver = stepper.integrator("DOP853")(damped, 0.0, np.array([1.0, 0.3, 0.2]), 10.0, rtol=1e-9, atol=1e-9)
    solver.step()
    state = stepper.saved(solver)
    solver.step()
    taken = solver.t - state[0]
    stepper.rewind(solver, state, taken / 4)
    solver.step()
    assert solver.t == pytest.approx(state[0] + taken / 4, rel=1e-15)
    fresh = stepper.integrator("DOP853")(damped, state[0], state[1], 10.0, rtol=1e-9, atol=1e-9, first_step=taken / 4)
    fresh.step()
    assert np.array_equal(solver.y, fresh.y)


@pytest.mark.implementation
@pytest.mark.parametrize("method", stepper.RESUMABLE)
def test_a_step_aimed_at_a_time_ends_there_as_one_bound_there_would(method):
    """``step_to`` takes the step a solver takes towards a bound at that time (bit for bit: the
    same state, the same proposal for the next step) and leaves the solver running towards
    its own bound."""
    method = stepper.integrator(method)
    solver = method(damped, 0.0, np.array([1.0, 0.3, 0.2]), 10.0, rtol=1e-9, atol=1e-9)
    solver.step()
    t, y, f = solver.t, solver.y.copy(), solver.f.copy()
    aim = t + 0.6 * stepper.proposed_step(solver)
    stepper.step_to(solver, aim)
    fresh = method(damped, t, y, aim, rtol=1e-9, atol=1e-9, first_step=aim - t)
    assert np.array_equal(fresh.f, f)
    fresh.step()
    assert solver.t == fresh.t == aim and np.array_equal(solver.y, fresh.y)
    assert solver.h_abs == fresh.h_abs and solver.status == "running" and solver.t_bound == 10.0


@pytest.mark.parametrize("method", sorted(stepper.METHODS))
def test_every_method_runs_a_pendulum_to_its_exact_motion(method):
    """mb.simulate with each integrator it accepts (the implicit ones restart at each output,
    LSODA keeping its step inside its own state): a pendulum from 1 rad for 2 s ends within 1e-5
    rad of θ̈ = −(g/L) sin θ solved by solve_ivp at rtol 1e-12."""
    model = mb.loads("""
parameters: {g: 9.81, L: 0.5}
parts:
  bob:
    type: lagrangian
    coordinates: [theta]
    T: 0.5*L**2*theta_dot**2
    V: -g*L*cos(theta)
initial: {bob.theta: 1.0}
""")
    run = mb.simulate(model, 2.0, dt=0.5, method=method, rtol=1e-9, atol=1e-9)
    exact = scipy.integrate.solve_ivp(lambda t, y: (y[1], -9.81 / 0.5 * np.sin(y[0])), (0.0, 2.0), (1.0, 0.0),
                                      method="DOP853", rtol=1e-12, atol=1e-12).y[0, -1]
    assert abs(run.q[-1, 0] - exact) < 1e-5
