"""Flexible bodies in model files, joined and run like any other part: a clamped–free beam's
modes through mb.modes against the analytic Euler–Bernoulli frequencies, and a free flexible
body spinning in free flight keeping its energy."""

import numpy as np

import mbsynth as mb
from tests.helpers.flexible_beams import CLAMPED_FREE, FREE_FREE, LENGTH, STRIP, euler_bernoulli

STRIP_FILE = ", ".join(f"{k}: {v}" for k, v in STRIP.items())


def test_a_clamped_free_beams_modes_are_the_analytic_ones():
    """The strip (Iy = 4 Iz) of 100 elements, Craig–Bampton at its root with 8 fixed-interface
    modes, its frame held by a fixed joint at the root node: mb.modes linearizes the part (its
    quaternion closed by the unit-norm row) and its five lowest frequencies are those of
    ω = (βL)² √(EI/ρAL⁴), βL = 1.8751041, 4.6940911, 7.8547574 with I = Iz and the first two
    with I = Iy, to 1e-6 (the 100-element FE model's own error is ~4e-8)."""
    model = mb.loads(f"""
parts:
  beam:
    type: flexible_body
    beam: {{length: {LENGTH}, elements: 100, {STRIP_FILE}}}
    reduction: {{method: craig_bampton, interface: [0], modes: 8}}
joints:
  - {{name: clamp, type: fixed, parent: world, child: beam.node_0}}
""")
    found = mb.modes(model).frequencies
    expected = np.sort(np.concatenate([euler_bernoulli(CLAMPED_FREE, STRIP["Iz"]),
                                       euler_bernoulli(CLAMPED_FREE[:2], STRIP["Iy"])])) / (2 * np.pi)
    assert len(found) == 8
    np.testing.assert_allclose(found[:5], expected, rtol=1e-6)


def test_a_round_beams_repeated_modes_are_real_and_independent():
    """A round strip (Iy = Iz): each bending frequency is a repeated eigenvalue (both planes),
    split by rounding only. mb.modes lists it twice at the Euler–Bernoulli frequency (1e-6)
    with two real shapes (no imaginary part) that are independent: orthogonal in the elastic
    coordinates, and at the tip one bends the beam in the xy plane, the other in xz, as a
    repeated mode's basis may be chosen (nodal tip translations orthogonal to 1e-6)."""
    round_strip = ", ".join(f"{k}: {v}" for k, v in {**STRIP, "Iy": STRIP["Iz"]}.items())
    model = mb.loads(f"""
parts:
  beam:
    type: flexible_body
    beam: {{length: {LENGTH}, elements: 40, {round_strip}}}
    reduction: {{method: craig_bampton, interface: [0], modes: 4}}
joints:
  - {{name: clamp, type: fixed, parent: world, child: beam.node_0}}
""")
    modes = mb.modes(model).modes
    expected = euler_bernoulli(CLAMPED_FREE[:2], STRIP["Iz"]) / (2 * np.pi)
    np.testing.assert_allclose([m.frequency for m in modes], np.repeat(expected, 2), rtol=1e-6)
    for first, second in (modes[0:2], modes[2:4]):
        for mode in (first, second):
            assert np.abs(mode.shape.imag).max() == 0.0
        eta = [model.coordinates.index(f"beam.eta{i}") for i in range(1, 5)]
        assert abs(np.dot(first.shape[eta].real, second.shape[eta].real)) <= 1e-9
        tips = [mode.node_shape["beam"].translations[-1].real for mode in (first, second)]
        assert abs(np.dot(*tips)) <= 1e-6 * np.linalg.norm(tips[0]) * np.linalg.norm(tips[1])


def test_a_free_beams_modes_are_the_analytic_free_free_ones():
    """The same strip alone in space, six free-interface modes: mb.modes finds six free
    (rigid-body) modes of the frame and vibrations whose five lowest are the free–free
    βL = 4.7300407, 7.8532046, 10.9956078 with Iz and the first two with Iy, to 1e-6."""
    model = mb.loads(f"""
parts:
  beam:
    type: flexible_body
    beam: {{length: {LENGTH}, elements: 100, {STRIP_FILE}}}
    reduction: {{method: free_interface, modes: 6}}
""")
    modes = mb.modes(model).modes
    assert sum(m.kind == "free" for m in modes) == 6
    found = np.array([m.frequency for m in modes if m.kind == "vibration"])
    expected = np.sort(np.concatenate([euler_bernoulli(FREE_FREE, STRIP["Iz"]),
                                       euler_bernoulli(FREE_FREE[:2], STRIP["Iy"])])) / (2 * np.pi)
    assert len(found) == 6
    np.testing.assert_allclose(found[:5], expected, rtol=1e-6)


def test_a_spinning_free_flexible_body_keeps_its_energy():
    """A soft rod thrown spinning about all three axes with its four lowest free-interface modes
    excited, no gravity, no damping: its total energy (kinetic of every FE DOF plus elastic)
    stays within 1e-9 of the kinetic energy over 0.2 s, while the modes exchange energy with
    the spin (the elastic energy changes by more than 1e-4 of it)."""
    model = mb.loads("""
parts:
  rod:
    type: flexible_body
    beam: {length: 1.0, elements: 10, area: 1e-4, Iy: 2e-9, Iz: 1e-9, J: 2e-9, E: 2e8, nu: 0.3, density: 1000}
    reduction: {method: free_interface, modes: 4}
    initial: {velocity: [0.1, 0, 0], angular_velocity: [0.5, 2.0, 3.0], amplitudes: [1e-3, -1e-3, 5e-4, 2e-4]}
""")
    run = mb.simulate(model, 0.2)
    elastic = np.array([model.energy(t, q, qd)[1] for t, q, qd in zip(run.t, run.q, run.qd)])
    assert np.ptp(elastic) > 1e-4 * (run.energy - elastic).max()
    assert run.energy_drift < 1e-9
