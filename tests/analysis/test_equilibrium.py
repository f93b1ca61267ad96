"""mb.equilibrium from far away (statics.py): the rest each start reaches, judged by criteria
the search does not use — closed forms of the configuration from the models' geometry, the
applied forces Q balanced by the constraints (Q orthogonal to the null space of A, taken
here by an SVD), the constraints met, and a minimum of V (no small move on the constraints
lowers it) — and its two contracts: the stable rest by default (also from a maximum or
saddle the steps come to or start at), the equilibrium near the start with ``nearest=True``."""

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq

import mbsynth as mb
from mbsynth.analysis.projection import project_positions

MODELS = Path(__file__).resolve().parents[2] / "models"
RODS = MODELS / "mechanisms" / "double_pendulum_rods.yaml"


def rods_start(system, first, second):
    """The particles of the double pendulum on rods with the rods along the unit vectors
    ``first`` and ``second`` from the pivot at the origin."""
    l = system.parameters["l"]
    p1 = l * np.asarray(first, dtype=float)
    return np.concatenate([p1, p1 + l * np.asarray(second, dtype=float)])


def tilted(degrees):
    """The unit vector turned ``degrees`` from straight down, in the x–z plane."""
    angle = np.radians(degrees)
    return [np.sin(angle), 0.0, -np.cos(angle)]


def assert_balanced(system, q):
    """The constraints hold, and Q (the applied forces at rest) has no share along the
    null space of A: the constraint forces −Aᵀλ balance it (the generalized force balance)."""
    zero = np.zeros(system.n)
    phi, _ = system.constraint_residuals(0.0, q, zero)
    assert np.abs(phi).max(initial=0.0) < 1e-10 * max(1.0, np.abs(q).max())
    arrays = system.evaluate(0.0, q, zero)
    A = arrays.A.toarray() if hasattr(arrays.A, "toarray") else np.asarray(arrays.A)
    N = scipy.linalg.null_space(A) if A.size else np.eye(system.n)
    Q = np.asarray(arrays.Q, dtype=float)
    assert np.abs(N.T @ Q).max() < 1e-8 * max(1.0, np.abs(Q).max())


def assert_minimum(system, q, rng, size=1e-3, tries=8):
    """No small move of q put back on the constraints lowers V: a stable rest."""
    zero = np.zeros(system.n)
    V = system.energy(0.0, q, zero)[1]
    for _ in range(tries):
        moved = project_positions(system, 0.0, q + size * rng.normal(size=system.n))
        assert system.energy(0.0, moved, zero)[1] >= V - 1e-12 * max(1.0, abs(V))


def test_double_pendulum_on_rods_from_37_degrees():
    """Both rods turned 37° from straight down (in one plane, and the second out of it):
    the rest is both rods vertical below the pivot, (0, 0, −l) and (0, 0, −2l)."""
    system = mb.load(RODS)
    l = system.parameters["l"]
    for second in (tilted(37), [0.0, np.sin(np.radians(37)), -np.cos(np.radians(37))]):
        q = mb.equilibrium(system, rods_start(system, tilted(37), second))
        assert q == pytest.approx([0, 0, -l, 0, 0, -2 * l], abs=1e-9)


@pytest.mark.parametrize("first, second", [(-27, 165), (-171, 29), (93, -139), (165, 173)])
def test_double_pendulum_on_rods_not_to_a_saddle(first, second):
    """Planar starts near the saddles (one rod up, one down) and the top, from which a Newton
    iteration on the force balance with steps only required to do work comes to a saddle:
    the hanging rest, V = −3 m g l."""
    system = mb.load(RODS)
    p = system.parameters
    q = mb.equilibrium(system, rods_start(system, tilted(first), tilted(second)))
    assert q == pytest.approx([0, 0, -p["l"], 0, 0, -2 * p["l"]], abs=1e-9)
    assert system.energy(0.0, q, 0 * q)[1] == pytest.approx(-3 * p["m"] * p["g"] * p["l"], rel=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_double_pendulum_on_rods_from_random_directions(seed):
    """Rods along random directions in space (upward ones too): the hanging rest."""
    system = mb.load(RODS)
    l = system.parameters["l"]
    rng = np.random.default_rng(seed)
    first, second = (v / np.linalg.norm(v) for v in rng.normal(size=(2, 3)))
    q = mb.equilibrium(system, rods_start(system, first, second))
    assert q == pytest.approx([0, 0, -l, 0, 0, -2 * l], abs=1e-9)


@pytest.mark.parametrize("seed", range(4))
def test_simple_pendulum_from_random_angles(seed):
    """A point on a circle of radius L under gravity −y, started anywhere but the top: (0, −L)."""
    system = mb.load(MODELS / "mechanisms" / "simple_pendulum.yaml")
    L = system.parameters["L"]
    angle = np.random.default_rng(seed).uniform(-3.0, 3.0)
    q = mb.equilibrium(system, np.array([L * np.sin(angle), -L * np.cos(angle)]))
    assert q == pytest.approx([0.0, -L], abs=1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_parallelogram_chain_hangs_from_random_starts(seed):
    """n_four_bar.yaml starts upright (a rest, unstable); from random moves of it the three
    verticals hang straight down (θ = π) and the two horizontals lie at y = −L: V = −3.5 m g L."""
    system = mb.load(MODELS / "mechanisms" / "n_four_bar.yaml")
    p = system.parameters
    rng = np.random.default_rng(seed)
    q = mb.equilibrium(system, system.initial_state()[0] + 0.3 * rng.normal(size=system.n))
    values = dict(zip(system.coordinates, q))
    for v in ("cell[0].v", "cell[1].v", "v"):
        assert np.cos(values[f"{v}.theta"]) == pytest.approx(-1.0, abs=1e-9)
        assert values[f"{v}.y"] == pytest.approx(-p["L"] / 2, abs=1e-9)
    for h in ("cell[0].h", "cell[1].h"):
        assert values[f"{h}.y"] == pytest.approx(-p["L"], abs=1e-9)
    assert system.energy(0.0, q, 0 * q)[1] == pytest.approx(-3.5 * p["m"] * p["g"] * p["L"], rel=1e-10)


@pytest.mark.parametrize("name", ["four_bar.yaml", "slider_crank.yaml"])
@pytest.mark.parametrize("seed", range(3))
def test_loops_come_to_a_balanced_minimum_from_random_starts(name, seed):
    """A four-bar and a slider-crank under gravity, started at random moves of their initial
    positions: a configuration on the constraints where Q is balanced and V is a minimum."""
    system = mb.load(MODELS / "mechanisms" / name)
    rng = np.random.default_rng(seed)
    q = mb.equilibrium(system, system.initial_state()[0] + 0.3 * rng.normal(size=system.n))
    assert_balanced(system, q)
    assert_minimum(system, q, rng)


@pytest.mark.parametrize("second", [180, 0], ids=["maximum", "saddle"])
def test_started_at_rest_upright_it_comes_down_to_the_stable_rest(second):
    """Rests exactly where the potential has a maximum (both rods up) or a saddle (the first
    up, the second hanging): the default contract is a stable rest, so the search leaves
    them along their negative curvature and ends hanging, a minimum of V."""
    system = mb.load(RODS)
    l = system.parameters["l"]
    start = rods_start(system, tilted(180), tilted(second))
    assert np.abs(mb.equilibrium(system, start, nearest=True) - start).max() < 1e-12  # it does rest there
    q = mb.equilibrium(system, start)
    assert q == pytest.approx([0, 0, -l, 0, 0, -2 * l], abs=1e-9)
    assert_minimum(system, q, np.random.default_rng(0))


def test_pd_pendulum_from_far_away():
    """A force V does not hold (the PD law on the hinge): from θ = −2.5 rad the rest is where
    kp (θ − target) = −m g (L/2) sin θ."""
    system = mb.load(MODELS / "joints" / "pd_pendulum.yaml")
    p = system.parameters
    theta = -2.5
    start = np.array([0, 0, 0, 1.0, 0, 0, 0])
    start[:3] = [-p["L"] / 2 * np.sin(theta), 0, -p["L"] / 2 * np.cos(theta)]
    start[3:] = [np.cos(theta / 2), 0, np.sin(theta / 2), 0]
    q = mb.equilibrium(system, start)
    angle = np.ravel(system.joint_values(0.0, q, 0 * q)["hinge"].position)[0]
    rest = brentq(lambda x: p["kp"] * (x - p["target"]) + p["m"] * p["g"] * p["L"] / 2 * np.sin(x), -1.0, 1.0)
    assert angle == pytest.approx(rest, abs=1e-9)


def test_near_the_top_nearest_finds_the_inverted_rest_and_default_the_hanging_one():
    """Rods 5° and 8° from straight up: ``nearest=True`` gives the upright rest (0, 0, l),
    (0, 0, 2l), unstable; the default comes down to the hanging one."""
    system = mb.load(RODS)
    l = system.parameters["l"]
    start = rods_start(system, tilted(175), tilted(-172))
    upright = mb.equilibrium(system, start, nearest=True)
    assert upright == pytest.approx([0, 0, l, 0, 0, 2 * l], abs=1e-9)
    assert not mb.modes(system, upright).stable
    assert mb.equilibrium(system, start) == pytest.approx([0, 0, -l, 0, 0, -2 * l], abs=1e-9)


DOUBLE_WELL = """
name: double_well
parameters: {m: 2.0}
parts:
  b:
    type: lagrangian
    coordinates: [x, y]
    T: 0.5*m*(x_dot**2 + y_dot**2)
    V: -x**2 + x**4 + 3*y**2
"""


def test_a_saddle_the_steps_come_to_is_left_downhill():
    """V = −x² + x⁴ + 3y² from (0, 1): the force has no x share along x = 0, so the steps come
    down to the saddle (0, 0); the default goes on down to a well, x = ±1/√2 (V' = 0),
    y = 0; ``nearest=True`` stops at the saddle, and from (0.8, 0.3) finds the well."""
    system = mb.loads(DOUBLE_WELL)
    well = mb.equilibrium(system, np.array([0.0, 1.0]))
    assert np.abs(well) == pytest.approx([1 / np.sqrt(2), 0.0], abs=1e-9)
    assert mb.equilibrium(system, np.array([0.0, 1.0]), nearest=True) == pytest.approx([0.0, 0.0], abs=1e-9)
    assert mb.equilibrium(system, np.array([0.1, 0.5]), nearest=True) == pytest.approx([0.0, 0.0], abs=1e-9)
    assert mb.equilibrium(system, np.array([0.8, 0.3]), nearest=True) == pytest.approx([1 / np.sqrt(2), 0], abs=1e-9)


def test_non_holonomic_rows_are_refused():
    """A knife edge (one row on its velocities): the search, which moves along every direction
    the holonomic rows allow, is refused with a SolveError that says why."""
    with pytest.raises(mb.SolveError, match=r"non-holonomic rows leave 2 of 3 speeds free"):
        mb.equilibrium(mb.load(MODELS / "rolling" / "knife_edge.yaml"))
