"""Every ```python block of the tutorials (docs/tutorials/*.md) runs, in order, one
namespace per tutorial, from the repository root: the snippets' own asserts compare with
the paper's closed forms, conservation laws or Pinocchio, so a page that no longer tells
the truth fails here."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
TUTORIALS = sorted(p for p in (ROOT / "docs" / "tutorials").glob("*.md") if p.name != "index.md")
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.S | re.M)


def python_blocks(path):
    """The code of each ```python fence of ``path``, in order."""
    return BLOCK.findall(path.read_text())


def test_every_tutorial_has_code_and_a_place_in_the_index():
    index = (ROOT / "docs" / "tutorials" / "index.md").read_text()
    assert TUTORIALS
    for path in TUTORIALS:
        assert python_blocks(path), f"{path.name} has no python block"
        assert path.stem in index, f"{path.name} is not in docs/tutorials/index.md"


def test_blocks_are_found_in_a_sample(tmp_path):
    text = "intro\n```python\nx = 1\n```\n```yaml\na: 1\n```\n```python\ny = x + 1\n```\n"
    sample = tmp_path / "sample.md"
    sample.write_text(text)
    assert python_blocks(sample) == ["x = 1\n", "y = x + 1\n"]


@pytest.mark.slow  # each tutorial's whole code: simulations, sweeps on a Dask cluster, robots
@pytest.mark.parametrize("path", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_tutorial_runs(path, monkeypatch):
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("MPLBACKEND", "agg")
    namespace = {"__name__": f"tutorial_{path.stem}"}
    for number, code in enumerate(python_blocks(path), start=1):
        try:
            exec(compile(code, f"{path.name} block {number}", "exec"), namespace)
        except Exception as err:
            raise AssertionError(f"{path.name}, python block {number} failed: {type(err).__name__}: {err}") from err
