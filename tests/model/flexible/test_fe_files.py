"""FE models from files: every layout round-trips a generated beam to the last bit of its
matrices (and its frequencies with them), and bad input is refused with the file's name
and what is wrong: shape, NaN, asymmetry, an eigenvalue below zero, nodes that do not fit."""

import re

import numpy as np
import pytest
import scipy.io
import scipy.sparse

from tests.helpers.flexible_beams import strip
from mbsynth.core.errors import ModelError
from mbsynth.model.flexible.files import read_fe, write_fe
from mbsynth.model.flexible.matrices import fe_model


@pytest.fixture(scope="module")
def fe():
    return strip(6, mass="lumped")  # singular M: semidefinite, not definite


def same(a, b):
    assert a.dofs_per_node == b.dofs_per_node
    np.testing.assert_array_equal(a.nodes, b.nodes)
    for name in ("mass", "stiffness"):
        assert abs(getattr(a, name) - getattr(b, name)).max() == 0.0, name


def test_the_npz_bundle_round_trips(fe, tmp_path):
    same(read_fe(write_fe(fe, tmp_path / "strip.npz")), fe)


def test_matrix_market_files_round_trip(fe, tmp_path):
    folder = write_fe(fe, tmp_path / "strip")
    assert scipy.io.mminfo(folder / "mass.mtx")[4:] == ("real", "symmetric")
    same(read_fe(mass=folder / "mass.mtx", stiffness=folder / "stiffness.mtx", nodes=folder / "nodes.mtx"), fe)


def test_one_array_per_file_in_npz_csv_and_dense_bundles(fe, tmp_path):
    scipy.sparse.save_npz(tmp_path / "K.npz", scipy.sparse.csr_matrix(fe.stiffness))
    np.savez(tmp_path / "M.npz", fe.mass.toarray())
    np.savetxt(tmp_path / "nodes.csv", fe.nodes, delimiter=",", header="x,y,z", fmt="%.17g")
    same(read_fe(mass=tmp_path / "M.npz", stiffness=tmp_path / "K.npz", nodes=tmp_path / "nodes.csv"), fe)
    np.savez(tmp_path / "dense.npz", mass=fe.mass.toarray(), stiffness=fe.stiffness.toarray(), nodes=fe.nodes)
    same(read_fe(tmp_path / "dense.npz"), fe)


def refused(match, M, K, X):
    with pytest.raises(ModelError, match=match):
        fe_model(M, K, X, where=dict(mass="m.mtx", stiffness="k.mtx", nodes="n.csv"))


def test_bad_matrices_are_refused_naming_the_file_and_the_fault(fe):
    M, K, X = fe.mass.toarray(), fe.stiffness.toarray(), fe.nodes
    refused(r"^k\.mtx: the stiffness matrix must be square, got shape \(42, 41\)", M, K[:, :-1], X)
    refused(r"^m\.mtx: the mass matrix is 42 × 42 but the stiffness matrix \(k\.mtx\) is 36 × 36", M, K[:36, :36], X)
    bad = K.copy()
    bad[3, 4] = np.nan
    refused(r"^k\.mtx: the stiffness matrix has 1 NaN or infinite entries", M, bad, X)
    bad = K.copy()
    bad[5, 1] *= 1.001
    refused(r"^k\.mtx: the stiffness matrix is not symmetric: entry \((1, 5|5, 1)\)", M, bad, X)
    bad = M.copy()
    bad[10, 10] = -1e-3 * M.max()  # a negative mass on a rotation
    refused(r"^m\.mtx: the mass matrix is not positive semidefinite: an eigenvalue -", bad, K, X)
    bad = K.copy()
    bad[:6, :6] -= 1e-6 * np.abs(K).max() * np.eye(6)  # nodes pulled apart by a negative spring
    refused(r"^k\.mtx: the stiffness matrix is not positive semidefinite", M, bad, X)
    refused(r"^n\.csv: 6 nodes do not fit 42 DOFs", M, K, X[:-1])
    refused(r"^n\.csv: node coordinates must be N × 3", M, K, X[:, :2])


def test_bad_files_are_refused_by_name(fe, tmp_path):
    missing = tmp_path / "none.mtx"
    with pytest.raises(ModelError, match=re.escape(f"{missing}: no such file (the mass)")):
        read_fe(mass=missing, stiffness=missing, nodes=missing)
    np.savez(tmp_path / "b.npz", mass=fe.mass.toarray(), nodes=fe.nodes)
    with pytest.raises(ModelError, match=re.escape(f"{tmp_path / 'b.npz'}: no 'stiffness' array and no COO triplets")):
        read_fe(tmp_path / "b.npz")
    (tmp_path / "k.mtx").write_text("not a matrix\n")
    with pytest.raises(ModelError, match=re.escape(f"{tmp_path / 'k.mtx'}: not a readable Matrix Market file")):
        read_fe(mass=tmp_path / "k.mtx", stiffness=tmp_path / "k.mtx", nodes=tmp_path / "k.mtx")
    rows = np.array([0, 50])
    np.savez(tmp_path / "c.npz", nodes=fe.nodes, mass_rows=rows, mass_cols=rows, mass_values=[1.0, 1.0],
             stiffness=fe.stiffness.toarray(), dofs_per_node=6)
    with pytest.raises(ModelError, match=re.escape("c.npz: mass has an entry at index 50 but the nodes give 42 DOFs")):
        read_fe(tmp_path / "c.npz")
