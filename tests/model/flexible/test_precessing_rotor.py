"""A spinning, precessing flexible rotor (models/flexible/precessing_rotor.yaml: a cantilever
blade whose hub spins about its axis while that axis precesses, the frame's motion prescribed)
is bent out of its spin plane by the floating frame's quadratic-velocity and Euler terms alone.
Its tip follows the unreduced FE model in the turning frame, written independently from the
nodal kinetic energy (tests/helpers/prescribed_frame.py: no reduction, no inertia invariants).
benchmarks/flexible_3d.py runs the same scene over 2 s at 2 to 36 modes and in Exudyn."""

from pathlib import Path

import numpy as np

import mbsynth as mb
from mbsynth.model.flexible.beam import beam
from tests.helpers.prescribed_frame import tip_history, tumbling_rates, tumbling_rotation
from tests.model.flexible.test_flexible_pendulum import ELEMENTS, SECTION

MODEL = Path(__file__).resolve().parents[3] / "models" / "flexible" / "precessing_rotor.yaml"
SPIN, PRECESSION, TAU = 10.0, 2.0, 0.3  # the model file's Omega, P, tau
T_END, SAMPLES = 0.6, 31
# 4 modes (the file's: both planes' first two bending modes) leave out the axial stretch (27 µm
# at the tip over 2 s) and the higher bending modes: over 2 s the tip is 6.4e-5 m from the
# unreduced model, 5.8e-5 with 8 modes (benchmarks/flexible_3d_results.md)
REDUCTION_ERROR = 1e-4  # m
OUT_OF_PLANE_ERROR = 2e-3  # of the largest out-of-plane deflection (0.04 % over 2 s)


def test_the_precessing_rotor_follows_the_unreduced_fe_model():
    """The tip's elastic displacement in the frame's axes stays within REDUCTION_ERROR of the
    unreduced model's, and its out-of-plane part within OUT_OF_PLANE_ERROR of its largest
    value (some centimetres: a wrong Coriolis or gyroscopic term is off by tens of per cent,
    as Exudyn's frame on Tait–Bryan angles is, benchmarks/flexible_3d_results.md)."""
    times = np.linspace(0.0, T_END, SAMPLES)
    fe = beam(1.0, ELEMENTS, **SECTION)
    reference = tip_history(fe, tumbling_rates(SPIN, PRECESSION, TAU), times, rtol=1e-8, atol=1e-11)
    run = mb.simulate(mb.load(MODEL), T_END, dt=T_END / (SAMPLES - 1), rtol=1e-9, atol=1e-9)
    assert run.status == "completed" and np.allclose(run.t, times)
    rotation = tumbling_rotation(SPIN, PRECESSION, TAU)
    world = np.stack([run.column(f"tip[{c}]") for c in "xyz"], axis=1)
    tip = np.array([rotation(t).T @ p for t, p in zip(times, world)]) - fe.nodes[-1]
    assert np.abs(reference[:, 2]).max() > 0.01  # bent out of its spin plane by centimetres
    assert np.linalg.norm(tip - reference, axis=1).max() < REDUCTION_ERROR
    assert np.abs(tip[:, 2] - reference[:, 2]).max() < OUT_OF_PLANE_ERROR * np.abs(reference[:, 2]).max()
