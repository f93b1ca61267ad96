"""A blade spinning at a constant rate (models/flexible/rotating_blade.yaml: a uniform
cantilever turned by angles, its spin cyclic, stiffening on) is a steady motion, and its
rotating frequencies from ``modes(steady=True)`` are those of the rotating Euler–Bernoulli
cantilever with zero hub radius, computed independently by Rayleigh–Ritz
(tests/helpers/rotating_beam.py: 3.5160 at λ = 0, the clamped-free (βL)², 3.6817 at λ = 1,
4.7973 at λ = 3 flapwise, as tabulated by Wright et al. 1982 and Hodges & Rutkowski 1981). Southwell's
coefficient, the slope dω²/dΩ² at Ω = 0, is that of the reference (1.1933 flapwise): the
test reports how far Southwell's ω² = ω₀² + 1.193Ω² lies from the converged frequencies.
"""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.model.data import Data
from tests.helpers.rotating_beam import EI, LENGTH, LINE_MASS, reference

MODEL = Path(__file__).resolve().parents[3] / "models" / "flexible" / "rotating_blade.yaml"
@pytest.fixture(scope="module")
def blade():
    return Data(mb.load(MODEL))


def lowest(result, axis):
    """The lowest frequency (rad/s) of the modes whose blade tip moves most along ``axis``."""
    for mode in result.modes:
        tip = mode.node_shape["blade"].translations[-1]
        if int(np.argmax(np.abs(tip))) == axis:
            return 2 * np.pi * mode.frequency
    raise AssertionError(f"no mode moves the tip along axis {axis}")


def test_the_reference_is_converged_and_gives_southwells_coefficient():
    """The Rayleigh–Ritz reference: 3.5160 and 3.6817, 4.7973 at λ = 1, 3 (tabulated) to
    1e-4, converged in its basis size, Southwell's slope 1.193 (flap) and 0.193 (lag)."""
    scale = np.sqrt(EI["flap"] / (LINE_MASS * LENGTH ** 4))
    for lam, tabulated in ((0.0, 3.5160), (1.0, 3.6817), (3.0, 4.7973)):
        assert reference(lam * scale, "flap") / scale == pytest.approx(tabulated, abs=1e-4)
    h = 1e-3 * scale
    for plane, coefficient in (("flap", 1.193), ("lag", 0.193)):
        slope = (reference(h, plane) ** 2 - reference(0.0, plane) ** 2) / h ** 2
        assert slope == pytest.approx(coefficient, abs=1e-3)


def test_the_spinning_blades_frequencies_are_the_rotating_cantilevers(blade):
    """Flapwise and lead-lag lowest frequencies of ``modes(steady=True)`` at spin rates up to
    the flapwise ω₀ equal the converged reference to 1e-3 relative (they are within 1.5e-4:
    the 20-element mesh's centrifugal tension, element by element, and 6 Craig–Bampton
    modes); the spin angle is the cyclic direction."""
    omega0 = reference(0.0, "flap")
    for ratio in (0.0, 0.25, 0.5, 0.75, 1.0):
        rate = ratio * omega0
        blade.set_parameters({"Omega": rate})
        result = mb.modes(blade, steady=True)
        assert result.cyclic == ("blade.angle_z",)
        for plane, axis in (("flap", 2), ("lag", 1)):
            assert lowest(result, axis) == pytest.approx(reference(rate, plane), rel=1e-3), (plane, ratio)


def test_southwells_formula_lies_above_the_converged_frequencies():
    """Southwell's ω² = ω₀² + 1.193 Ω² (flap), ω₀² + 0.193 Ω² (lag) against the reference over
    Ω ≤ ω₀ (flapwise): above it flapwise (Rayleigh's quotient of the non-rotating mode), by
    3.1e-4 at Ω = ω₀/2 and 2.9e-3 at ω₀: Southwell's form meets 1e-3 only up to about 0.6 ω₀;
    lead-lag within 3.9e-4 (its Ω² term is small)."""
    omega0 = {plane: reference(0.0, plane) for plane in EI}
    distance = {}
    for ratio in (0.25, 0.5, 0.75, 1.0):
        rate = ratio * omega0["flap"]
        for plane, K in (("flap", 1.193), ("lag", 0.193)):
            distance[plane, ratio] = np.sqrt(omega0[plane] ** 2 + K * rate ** 2) / reference(rate, plane) - 1
    assert 0 <= distance["flap", 0.5] < 1e-3 and 2e-3 < distance["flap", 1.0] < 4e-3
    assert all(abs(distance["lag", r]) < 5e-4 for r in (0.25, 0.5, 0.75, 1.0))


def test_the_spinning_blade_moves_alike_on_both_paths(blade):
    """The compiled path (flexible.py's kernel given the angles' axes) and the KKT path give the
    same q̈ (1e-9) at a bent, moving state of the spinning blade, and it is simulated."""
    blade.set_parameters({"Omega": 3.0})
    q, qd = blade.initial_state()
    rng = np.random.default_rng(3)
    q[6:] += 1e-2 * rng.normal(size=len(q) - 6)
    qd[6:] += 1e-1 * rng.normal(size=len(q) - 6)
    fast = Data(blade.model, "compiled")
    fast.set_parameters({"Omega": 3.0})
    assert fast.engine is not None
    kkt = Data(blade.model, "kkt")
    kkt.set_parameters({"Omega": 3.0})
    expected = kkt.motion(0.0, q, qd).qdd
    found = fast.motion(0.0, q, qd).qdd
    assert np.abs(expected).max() > 1 and np.abs(found - expected).max() < 1e-9 * np.abs(expected).max()


def test_campbell_follows_the_modes_and_leaves_the_parameter(blade):
    """``mb.campbell`` over 0 … 2ω₀: branch 1 is the flapwise mode throughout, branch 2 the
    lead-lag one, though the first overtakes the second (their frequencies the reference's
    at every value, 1e-3 flapwise, 2e-3 lead-lag at 2ω₀ with its two modes of 6); the Data's
    Omega is as it was."""
    blade.set_parameters({"Omega": 1.5})
    omega0 = reference(0.0, "flap")
    result = mb.campbell(blade, "Omega", np.linspace(0.0, 2 * omega0, 9), orders=2)
    assert blade.parameters["Omega"] == 1.5
    flap = 2 * np.pi * result.frequencies[:, 0]
    lag = 2 * np.pi * result.frequencies[:, 1]
    assert flap[0] < lag[0] and flap[-1] > lag[-1]
    for rate, f, g in zip(result.values, flap, lag):
        assert f == pytest.approx(reference(rate, "flap"), rel=1e-3) and g == pytest.approx(reference(rate, "lag"), rel=2e-3)


def test_the_modes_table_names_the_coordinates_a_mode_moves_where_it_moves_no_joint(blade):
    """The driven hub's joint does not move in the blade's bending modes (its rate is rounding,
    1e-17): the table's "largest motion" names the elastic coordinates, not the hub."""
    from mbsynth.analysis.modes import format_modes

    blade.set_parameters({"Omega": 3.0})
    rows = [line for line in format_modes(mb.modes(blade, steady=True)).splitlines() if "vibration" in line]
    assert len(rows) == 6 and all("hub" not in row for row in rows)
    assert rows[0].split("vibration")[1].split()[1:3] == ["blade.eta1", "1,"]
