"""`mbsynth check` on a model made of model files: the tree of substructures with each one's
coordinates, constraint rows and degrees of freedom, copies alike on one line.

The expected numbers are counted by hand: a cell of the N-four-bar is two planar bodies
(3 coordinates each) and two revolute joints (2 rows each), so 6 coordinates, 4 rows and
2 degrees of freedom; the whole N-four-bar is 2N + 1 bodies and 3N + 1 revolute joints
with one degree of freedom (IFToMM A02)."""

import json
import subprocess
import sys
from dataclasses import replace

import mbsynth as mb
from mbsynth.analysis.diagnose import diagnose
from mbsynth.cli.check import format_check
from tests.helpers.n_four_bar_files import write_n_four_bar


def check(*args):
    return subprocess.run([sys.executable, "-m", "mbsynth.cli", "check", *map(str, args)],
                          capture_output=True, text=True)


def test_copies_of_a_cell_are_one_line_and_the_whole_has_one_degree_of_freedom(tmp_path):
    N = 10
    result = check(write_n_four_bar(tmp_path), "--set", f"N={N}")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert f"    n_four_bar: {3 * (2 * N + 1)} coordinates, {2 * (3 * N + 1)} rows, 1 DOF" in lines
    assert f"      cell[0…{N - 1}]: {N} copies of four_bar_cell.yaml, each 6 coordinates, 4 rows, 2 DOF" in lines
    assert not any(line.lstrip().startswith("cell[1]") for line in lines)
    assert "  motion: unique (Result 3)" in lines


def test_json_gives_every_substructure(tmp_path):
    result = check(write_n_four_bar(tmp_path), "--set", "N=3", "--json")
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["n"] - report["rank_A"] == 1
    assert [(s["name"], s["coordinates"], s["rows"], s["degrees_of_freedom"], s["children"])
            for s in report["substructures"]] == [(f"cell[{k}]", 6, 4, 2, []) for k in range(3)]
    assert all(s["file"] == str(tmp_path / "four_bar_cell.yaml") for s in report["substructures"])


def test_nested_copies_print_under_their_copies(tmp_path):
    """pairs: three copies of a pair (two cells, 12 coordinates, 8 + 2 rows of its cells and its
    link joint, 2 DOF) and one cell besides: 42 coordinates, 34 rows, 8 DOF."""
    write_n_four_bar(tmp_path)
    result = check(tmp_path / "pairs.yaml")
    assert result.returncode == 0, result.stderr
    tree = result.stdout.split("coordinates − rank of those rows):\n")[1].splitlines()[:4]
    assert tree == ["    pairs: 42 coordinates, 34 rows, 8 DOF",
                    "      pair[0…2]: 3 copies of pair.yaml, each 12 coordinates, 10 rows, 2 DOF",
                    "        pair[0…2].cell[0…1]: 2 copies of four_bar_cell.yaml, each 6 coordinates, 4 rows, 2 DOF",
                    "      extra: four_bar_cell.yaml, 6 coordinates, 4 rows, 2 DOF"]
    assert "  motion: unique (Result 3)" in result.stdout


def test_a_flat_model_prints_no_tree(tmp_path):
    write_n_four_bar(tmp_path)
    result = check(tmp_path / "four_bar_cell.yaml")
    assert result.returncode == 0, result.stderr
    assert "substructures" not in result.stdout


def test_a_thousand_copies_print_as_runs_of_alike_copies(tmp_path):
    """The text report of 1,000 copies (the counts of the N = 2 model's cells, copied; copy 500
    with one degree of freedom more) is three lines of copies, not 1,000."""
    report = diagnose(mb.load(write_n_four_bar(tmp_path)))
    cell = report.substructures[0]
    copies = [dict(cell, name=f"cell[{k}]", degrees_of_freedom=3 if k == 500 else 2) for k in range(1000)]
    text = format_check(replace(report, substructures=copies), tmp_path / "n_four_bar.yaml")
    assert [line.strip() for line in text.splitlines() if line.strip().startswith("cell[")] == [
        "cell[0…499]: 500 copies of four_bar_cell.yaml, each 6 coordinates, 4 rows, 2 DOF",
        "cell[500]: four_bar_cell.yaml, 6 coordinates, 4 rows, 3 DOF",
        "cell[501…999]: 499 copies of four_bar_cell.yaml, each 6 coordinates, 4 rows, 2 DOF"]
