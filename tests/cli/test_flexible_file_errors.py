"""Mistakes in a flexible body's FE input, as a user makes them: ``mbsynth check`` exits 2
with one line naming the model file, the line and the key (and the data file where the
fault is in one), never exit 3 with a raw numpy, zipfile or sympy exception."""

import subprocess
import sys

import numpy as np
import pytest

from mbsynth.model.flexible.beam import beam
from mbsynth.model.flexible.files import write_fe

from tests.helpers.flexible_beams import truss

BEAM = "{length: 1.0, elements: 4, area: 1e-4, Iy: 2e-9, Iz: 1e-9, J: 2e-9, E: 2e8, nu: 0.3, density: 1000}"
CB = "{method: craig_bampton, interface: [0], modes: 1}"
FE = beam(1.0, 4, area=1e-4, Iy=2e-9, Iz=1e-9, J=2e-9, E=2e8, nu=0.3, density=1000.0)


def check(folder, source, reduction=CB):
    """``mbsynth check`` of a rod whose FE model is ``source`` (line 5) reduced by
    ``reduction`` (line 6): (exit status, stderr)."""
    path = folder / "rod.yaml"
    path.write_text(f"name: rod\nparts:\n  rod:\n    type: flexible_body\n    {source}\n"
                    f"    reduction: {reduction}\n")
    result = subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", str(path)], capture_output=True,
                            text=True, check=False, timeout=120)
    return result.returncode, result.stderr


def refused(folder, source, reduction, line, key, words):
    status, stderr = check(folder, source, reduction)
    assert status == 2 and stderr.count("\n") == 1, stderr
    assert stderr.startswith(f"error: {folder / 'rod.yaml'}:{line}: at parts.rod.{key}: "), stderr
    assert all(word in stderr for word in words), stderr
    return stderr


def test_max_frequency_below_the_first_mode_names_that_mode(tmp_path):
    """No mode up to 0.5 Hz: refused at max_frequency with the first fixed-interface mode, the
    clamped–free beam's (1.8751²/2π) √(EI/ρAL⁴) = 0.79138 Hz (the FE model's, 4 elements: a
    little higher)."""
    stderr = refused(tmp_path, f"beam: {BEAM}", "{method: craig_bampton, interface: [0], max_frequency: 0.5}", 6,
                     "reduction.max_frequency", ["max_frequency 0.5 Hz is below the first fixed-interface mode",
                                                 "no elastic coordinate"])
    first = float(stderr.split("fixed-interface mode, ")[1].split(" Hz")[0])
    assert first == pytest.approx(1.875104**2 / (2 * np.pi) * np.sqrt(2e8 * 1e-9 / (1000 * 1e-4)), rel=1e-3)


@pytest.mark.parametrize("reduction", ["{method: craig_bampton, interface: [0], modes: 0}",
                                       "{method: free_interface, interface: [0], modes: 0}"])
def test_no_mode_and_one_held_node_leave_no_elastic_coordinate(tmp_path, reduction):
    """Guyan's reduction with the one interface node held at the frame, or no free mode."""
    refused(tmp_path, f"beam: {BEAM}", reduction, 6, "reduction.modes", ["modes: 0 leaves the reduction no elastic"])


def test_a_count_of_modes_is_not_a_boolean(tmp_path):
    refused(tmp_path, f"beam: {BEAM}", "{method: craig_bampton, interface: [0], modes: true}", 6, "reduction.modes",
            ["modes must be a count (an integer ≥ 0), got True"])


def test_poissons_ratio_of_minus_one_is_refused(tmp_path):
    refused(tmp_path, "beam: " + BEAM.replace("nu: 0.3", "nu: -1"), CB, 5, "beam.nu",
            ["nu (Poisson's ratio) must be above -1 and at most 0.5"])


@pytest.mark.parametrize("value", ["[6]", "six", "4", "true"])
def test_dofs_per_node_is_3_or_6(tmp_path, value):
    write_fe(FE, tmp_path / "rod.npz")
    refused(tmp_path, f"fe: {{bundle: rod.npz, dofs_per_node: {value}}}", CB, 5, "fe.dofs_per_node",
            ["dofs_per_node must be 3 or 6"])


def test_a_folder_as_the_bundle_is_named_a_folder(tmp_path):
    (tmp_path / "rod.npz").mkdir()
    refused(tmp_path, "fe: {bundle: rod.npz}", CB, 5, "fe.bundle", ["'rod.npz' is a folder"])


@pytest.mark.parametrize("damage, words", [
    (lambda data: b"", ["rod.npz: not a readable .npz file (EOFError"]),
    (lambda data: data[:len(data) // 2], ["rod.npz: not a readable .npz file (BadZipFile"]),
])
def test_an_empty_or_truncated_bundle(tmp_path, damage, words):
    write_fe(FE, tmp_path / "whole.npz")
    (tmp_path / "rod.npz").write_bytes(damage((tmp_path / "whole.npz").read_bytes()))
    refused(tmp_path, "fe: {bundle: rod.npz}", CB, 5, "fe.bundle", words)


@pytest.mark.parametrize("mass, words", [
    (FE.mass.toarray().astype(str), ["rod.npz [mass]: the mass matrix must hold real numbers, not text"]),
    (FE.mass.toarray() + 0j, ["rod.npz [mass]: the mass matrix must hold real numbers, not complex numbers"]),
    (FE.mass.toarray() + 0.5, ["rod.npz [mass]: the mass matrix gives the body's rigid translations along x, y, z "
                               "the masses 12.6, 12.6, 12.6 and the couplings 12.5, 12.5, 12.5"]),
])
def test_text_complex_and_unphysical_mass_matrices_are_refused(tmp_path, mass, words):
    """Complex entries, even with zero imaginary parts, are not silently made real; a mass
    matrix whose rigid translations have other masses than the body's 0.1 kg (ρAL) in some
    direction (0.5 added to all 30 × 30 entries: 25 × 0.5 more on each x, y, z translation, as
    much between them) is no body's, whose part M(q) would not be positive semidefinite."""
    np.savez(tmp_path / "rod.npz", nodes=FE.nodes, mass=mass, stiffness=FE.stiffness.toarray())
    refused(tmp_path, "fe: {bundle: rod.npz}", CB, 5, "fe.bundle", words)


@pytest.mark.parametrize("interface", ["[0]", "[0, 1, 2]"])
def test_craig_bampton_of_a_solid_is_refused_with_the_right_advice(tmp_path, interface):
    """A solid (3 DOFs per node: a point-mass truss) reduced by Craig–Bampton: holding the
    reference node's translations at the frame leaves the rotation about it to the reduced
    coordinates. Refused at once (not "add interface nodes", not a long sympy derivation), and
    free-interface modes, the advice, give a model ``check`` finds unique."""
    write_fe(truss(), tmp_path / "rod.npz")
    refused(tmp_path, "fe: {bundle: rod.npz}", f"{{method: craig_bampton, interface: {interface}, modes: 2}}", 6,
            "reduction.method", ["these nodes have 3 (translations)", "Use method: free_interface"])
    status, stderr = check(tmp_path, "fe: {bundle: rod.npz}", "{method: free_interface, interface: [0], modes: 2}")
    assert status == 0, stderr


def test_an_unknown_rotation_sequence_is_refused_at_its_key(tmp_path):
    """``rotation:`` takes quaternion or an intrinsic sequence, as a rigid body's."""
    refused(tmp_path, f"beam: {BEAM}\n    rotation: xzq", CB, 6, "rotation",
            ["rotation 'xzq': quaternion or one of xyz"])
