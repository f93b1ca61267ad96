"""Files mbsynth writes (core/files.py): whole or not at all."""

import numpy as np
import pytest

from mbsynth.core.files import write_atomically


def test_a_file_is_replaced_whole(tmp_path):
    path = tmp_path / "table.csv"
    path.write_text("old\n")
    write_atomically(path, lambda temporary: temporary.write_text("new\n"))
    assert path.read_text() == "new\n" and sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "table.csv"
    path.write_text("old\n")

    def half(temporary):
        temporary.write_text("ne")
        raise OSError(28, "No space left on device")
    with pytest.raises(OSError, match="No space left"):
        write_atomically(path, half)
    assert path.read_text() == "old\n" and sorted(p.name for p in tmp_path.iterdir()) == ["table.csv"]


def test_the_suffix_is_kept_for_writers_that_add_their_own(tmp_path):
    """np.savez appends .npz to a name without it: the temporary keeps the suffix, so the
    rename finds what savez wrote."""
    path = tmp_path / "run.npz"
    write_atomically(path, lambda temporary: np.savez(temporary, t=np.arange(3.0)))
    with np.load(path) as data:
        assert list(data["t"]) == [0.0, 1.0, 2.0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.npz"]
