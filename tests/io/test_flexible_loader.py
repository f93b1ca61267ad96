"""``type: flexible_body`` in model files: an FE bundle file relative to the model file gives
the same part as the beam generator it was written from, and each fault is refused with the
model file, the line and the key."""

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.model.flexible.beam import beam
from mbsynth.model.flexible.files import write_fe

BEAM = "{length: 1.0, elements: 4, area: 1e-4, Iy: 2e-9, Iz: 1e-9, J: 2e-9, E: 2e8, nu: 0.3, density: 1000}"


def model(body, rest=""):
    return f"parts:\n  rod:\n    type: flexible_body\n{body}{rest}"


def error(text, tmp_path):
    with pytest.raises(mb.ModelError) as caught:
        mb.loads(text, name="rod.yaml", folder=tmp_path)
    return str(caught.value)


def test_an_fe_bundle_beside_the_model_file_is_the_beams_part(tmp_path):
    """write_fe(beam) to rod.npz, read back through ``fe: {bundle: rod.npz}``: the part's M and
    Q at a random state equal those of the same beam given by ``beam:`` (bit for bit: the
    same matrices)."""
    write_fe(beam(1.0, 4, area=1e-4, Iy=2e-9, Iz=1e-9, J=2e-9, E=2e8, nu=0.3, density=1000.0), tmp_path / "rod.npz")
    reduction = "    reduction: {method: craig_bampton, interface: [0, 4], modes: 2, reference: 4}\n"
    from_file = mb.loads(model("    fe: {bundle: rod.npz}\n" + reduction), name="a.yaml", folder=tmp_path)
    generated = mb.loads(model(f"    beam: {BEAM}\n" + reduction), name="b.yaml", folder=tmp_path)
    assert from_file.coordinates == generated.coordinates and len(from_file.coordinates) == 7 + 6 + 2
    rng = np.random.default_rng(1)
    q, qd = rng.normal(size=15), rng.normal(size=15)
    q[3:7] /= np.linalg.norm(q[3:7])
    a, b = from_file.evaluate(0.0, q, qd), generated.evaluate(0.0, q, qd)
    np.testing.assert_array_equal(a.M, b.M)
    np.testing.assert_array_equal(a.Q, b.Q)
    assert sorted(from_file.parts[0].frames) == ["node_0", "node_4"]


@pytest.mark.parametrize("body, line, where, words", [
    ("    reduction: {method: craig_bampton, interface: [0], modes: 1}\n", 2, "parts.rod",
     "exactly one of beam (the beam generator) and fe"),
    (f"    beam: {BEAM}\n    reduction: {{method: craig_bampton, interface: [0, 9], modes: 1}}\n", 5,
     "parts.rod.reduction", "node 9 is not one of its 5 nodes"),
    (f"    beam: {BEAM}\n    reduction: {{method: craig_bampton, interface: [0], modes: 1, reference: 3}}\n", 5,
     "parts.rod.reduction.reference", "must be one of the interface nodes [0]"),
    (f"    beam: {BEAM}\n    reduction: {{method: guyan, interface: [0], modes: 1}}\n", 5,
     "parts.rod.reduction.method", "craig_bampton or free_interface"),
    (f"    beam: {BEAM}\n    reduction: {{method: free_interface}}\n", 5, "parts.rod.reduction",
     "exactly one of modes (a count) and max_frequency"),
    ("    fe: {mass: m.mtx, stiffness: k.mtx, nodes: nodes.csv}\n    reduction: {method: free_interface, modes: 1}\n",
     4, "parts.rod.fe.mass", "file 'm.mtx' not found"),
    (f"    beam: {BEAM}\n    reduction: {{method: craig_bampton, interface: [0], modes: 2}}\n"
     "    initial: {amplitudes: [0.1]}\n", 6, "parts.rod.initial.amplitudes", "a list of 2 numbers"),
    (f"    beam: {BEAM}\n    reduction: {{method: craig_bampton, interface: [0], modes: 1}}\n"
     "    frames: {tip: {node: 7}}\n", 6, "parts.rod.frames.tip.node", "0 to 4; got 7"),
    (f"    beam: {BEAM}\n    reduction: {{method: craig_bampton, interface: [0], modes: 1}}\n"
     "    damping: {rayleigh: [0.1, -1]}\n", 6, "parts.rod.damping.rayleigh", "must be ≥ 0"),
    ("    beam: {length: 1.0, elements: 4, area: 1e-4, Iy: 2e-9, Iz: 1e-9, J: 2e-9, E: 2e8, nu: 0.3, density: 1000, "
     "theory: timoshenko}\n    reduction: {method: free_interface, modes: 1}\n", 4, "parts.rod.beam",
     "needs shear_factor"),
])
def test_faults_are_named_with_file_line_and_key(body, line, where, words, tmp_path):
    message = error(model(body), tmp_path)
    assert message.startswith(f"rod.yaml:{line}: at {where}:"), message
    assert words in message, message
