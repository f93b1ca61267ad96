"""`mbsynth modes` lists a flexible body's modes in FE terms: each mode's nodal displacements
Φ δη in the part's axes. On the clamped strip (models/flexible/cantilever.yaml: 40 elements,
Iy = 4 Iz, clamped at node 0) the first four are the clamped–free Euler–Bernoulli beam's,
whose shape is written here in closed form."""

import json
from pathlib import Path

import numpy as np
import pytest

from mbsynth.cli import main

MODEL = Path(__file__).resolve().parents[2] / "models" / "flexible" / "cantilever.yaml"
LENGTH, ELEMENTS = 2.0, 40
# mode: (βL, the translation that bends (y: 1, z: 2), the rotation that goes with it, its sign: θz = +u'y, θy = −u'z)
MODES = {0: (1.8751041, 1, 2, 1.0), 1: (1.8751041, 2, 1, -1.0), 2: (4.6940911, 1, 2, 1.0), 3: (4.6940911, 2, 1, -1.0)}


def clamped_free(beta_L, x):
    """(φ, φ') of the clamped–free beam's mode at x: cosh βx − cos βx − σ (sinh βx − sin βx),
    σ = (cosh βL + cos βL)/(sinh βL + sin βL)."""
    b = beta_L / LENGTH
    sigma = (np.cosh(beta_L) + np.cos(beta_L)) / (np.sinh(beta_L) + np.sin(beta_L))
    shape = np.cosh(b * x) - np.cos(b * x) - sigma * (np.sinh(b * x) - np.sin(b * x))
    slope = b * (np.sinh(b * x) + np.sin(b * x) - sigma * (np.cosh(b * x) - np.cos(b * x)))
    return shape, slope


@pytest.fixture(scope="module")
def listed():
    """(the JSON of `mbsynth modes --json`, the text table) of the strip."""
    out = []
    for flags in (["--json"], []):
        with pytest.MonkeyPatch.context() as patch:
            printed = []
            patch.setattr("builtins.print", lambda *a, **k: printed.append(" ".join(map(str, a))))
            assert main(["modes", str(MODEL), *flags]) == 0
        out.append("\n".join(printed))
    return json.loads(out[0]), out[1]


@pytest.mark.parametrize("mode", sorted(MODES))
def test_the_strips_modes_are_the_clamped_free_beams_shapes_at_the_nodes(listed, mode):
    """Each node's translation along the bending direction, over the tip's, is φ(x_j)/φ(L)
    (1e-6 of the tip's: the 40-element mesh), its turn φ'(x_j)/φ(L) (1e-6 of the largest), the other
    translations and turns zero (1e-9), and the largest translation is the tip's."""
    beta_L, bends, turns, sign = MODES[mode]
    shape = listed[0]["modes"][mode]["node_shape"]["strip"]
    u, theta = np.array(shape["translations"]), np.array(shape["rotations"])
    x = np.linspace(0.0, LENGTH, ELEMENTS + 1)
    phi, slope = clamped_free(beta_L, x)
    tip = u[-1, bends]
    np.testing.assert_allclose(u[:, bends] / tip, phi / phi[-1], atol=1e-6)
    np.testing.assert_allclose(sign * theta[:, turns] / tip, slope / phi[-1], atol=1e-6 * np.abs(slope / phi[-1]).max())
    others = [k for k in range(3) if k != bends], [k for k in range(3) if k != turns]
    assert np.abs(u[:, others[0]]).max() < 1e-9 * abs(tip) and np.abs(theta[:, others[1]]).max() < 1e-9 * abs(tip)
    assert shape["largest_translation_node"] == ELEMENTS
    assert shape["largest_translation"] == pytest.approx(abs(tip), rel=1e-12)


def test_the_table_names_the_node_that_moves_most(listed):
    """Under each mode's row, the strip's line: node 40 moves most, across the strip in the
    mode's bending plane (y for the first, z for the second)."""
    lines = [line.strip() for line in listed[1].splitlines() if line.strip().startswith("strip:")]
    assert len(lines) == 4
    assert lines[0].startswith("strip: node 40 moves most, (0, ") and lines[0].split("(")[1].split(",")[2].strip() \
        .startswith("0)")
    assert lines[1].startswith("strip: node 40 moves most, (0, 0, ")
