"""The FE loader under hostile input: every malformed ``fe:`` file (its bytes, its arrays, its
Matrix Market text) and every hostile value of a ``beam:``, ``fe:`` or ``reduction:`` key
loads, or is refused with a ModelError ``rod.yaml:LINE: at parts.rod.<key>: ...`` at
that key, naming the data file where the fault is in one; never another exception.

Property-based (hypothesis), derandomized and of a fixed number of cases: the same cases in
every run.
"""

import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mbsynth import ModelError, loads
from mbsynth.model.flexible.beam import beam
from mbsynth.model.flexible.files import write_fe

MODEL = "rod.yaml"
BEAM = dict(length="1.0", elements="4", area="1e-4", Iy="2e-9", Iz="1e-9", J="2e-9", E="2e8", nu="0.3",
            density="1000")
REDUCTION = dict(method="craig_bampton", interface="[0]", modes="1")
FE = beam(1.0, 4, area=1e-4, Iy=2e-9, Iz=1e-9, J=2e-9, E=2e8, nu=0.3, density=1000.0)
SOURCE_LINE, REDUCTION_LINE = 5, 6  # the lines of fe:/beam: and reduction: in ``model``


def fuzz(examples):
    """The same ``examples`` cases in every run, no time limit on one (a case that loads builds
    the part)."""
    return settings(max_examples=examples, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def flow(mapping):
    return "{" + ", ".join(f"{k}: {v}" for k, v in mapping.items()) + "}"


def model(source, reduction=REDUCTION):
    """The model text of a rod from ``source`` ("fe: {...}" or "beam: {...}", one line)."""
    return (f"name: rod\nparts:\n  rod:\n    type: flexible_body\n    {source}\n"
            f"    reduction: {flow(reduction)}\n")


def refused_or_loaded(text, folder, keys, names=()):
    """Load ``text`` as rod.yaml in ``folder``. A refusal must read ``rod.yaml:LINE: at
    parts.rod.KEY...`` with KEY one of ``keys`` and LINE that key's line, and name one of
    the data files ``names`` (if any). Returns the error's message, or None when it loaded."""
    try:
        loads(text, name=MODEL, folder=folder)
    except ModelError as err:
        message = str(err)
        match = re.match(r"rod\.yaml:(\d+): at parts\.rod\.(\w+)[.:]", message)
        assert match and match.group(2) in keys, message
        assert int(match.group(1)) == (REDUCTION_LINE if match.group(2) == "reduction" else SOURCE_LINE), message
        assert not names or any(name in message for name in names), message
        return message
    return None


# ------------------------------------------------------------------ hostile key values

NOT_NUMBERS = ["~", "true", "[1]", "{a: 1}", "nosuch", "'1 +'", ".nan", ".inf", "-.inf", "1/0", "sqrt(-1)",
               "1e999", "''", "'x'"]  # refused wherever a number, a name, a vector or a count goes
EDGES = ["0", "-1", "1e-320", "1e-30", "1e30", "10**400", "1.5", "-0.5", "0.5", "-0.999999"]  # may be fine


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """rod.npz (write_fe's COO bundle of the beam), mass.mtx, stiffness.mtx, nodes.csv, and a
    folder ``sub``."""
    path = tmp_path_factory.mktemp("fe")
    write_fe(FE, path / "rod.npz")
    write_fe(FE, path)
    np.savetxt(path / "nodes.csv", FE.nodes, delimiter=",")
    (path / "sub").mkdir()
    return path


def test_every_key_refuses_every_value_that_is_no_number(folder):
    """Each of NOT_NUMBERS at each beam and reduction key (all of them, not a sample): refused
    at that section's line (but ``interface: [1]``, a list of one node); and each at
    ``fe.dofs_per_node`` at that key."""
    for key in sorted(BEAM) + ["theory", "mass", "axis", "up", "G", "shear_factor"]:
        for value in NOT_NUMBERS:
            message = refused_or_loaded(model("beam: " + flow(BEAM | {key: value})), folder, ("beam",))
            assert message is not None or value == "~", (key, value)
    for key in ("method", "interface", "modes", "max_frequency", "reference"):
        for value in set(NOT_NUMBERS) - {"[1]"} if key == "interface" else NOT_NUMBERS:  # [1]: node 1, fine
            assert refused_or_loaded(model("fe: {bundle: rod.npz}", REDUCTION | {key: value}), folder,
                                     ("reduction",)) is not None, (key, value)
    for value in NOT_NUMBERS + ["4", "0", "6.0", "[6]", "six"]:
        message = refused_or_loaded(model(f"fe: {{bundle: rod.npz, dofs_per_node: {value}}}"), folder, ("fe",))
        assert value == "~" or "at parts.rod.fe.dofs_per_node: dofs_per_node must be 3 or 6" in message, value


BEAM_KEYS = st.sampled_from(sorted(BEAM) + ["theory", "mass", "axis", "up", "G", "shear_factor"])


@fuzz(100)
@given(changes=st.dictionaries(BEAM_KEYS, st.sampled_from(NOT_NUMBERS + EDGES), min_size=1, max_size=2))
def test_hostile_beam_keys(folder, changes):
    """A value that is no number where a beam's number, name or vector goes is refused at
    ``beam`` (its message naming the key); any other value loads or is refused there or, if the
    beam it makes has no modes to keep, at ``reduction``."""
    message = refused_or_loaded(model("beam: " + flow(BEAM | changes)), folder, ("beam", "reduction"))
    if set(changes.values()) & set(NOT_NUMBERS) - {"~"}:
        assert message is not None and message.startswith(f"rod.yaml:{SOURCE_LINE}: at parts.rod.beam"), changes


REDUCTION_KEYS = st.sampled_from(["method", "interface", "modes", "max_frequency", "reference"])
REDUCTION_EDGES = [e for e in EDGES if e != "1e30"] + ["[0]", "[4]", "[0, 4]", "[0, 0]", "[-1]", "[true]", "[0, 9]",
                                                       "[]", "4", "free_interface", "guyan"]  # 1e30 Hz: every mode, slow


@fuzz(100)
@given(changes=st.dictionaries(REDUCTION_KEYS, st.sampled_from(NOT_NUMBERS + REDUCTION_EDGES), min_size=1,
                               max_size=2))
def test_hostile_reduction_keys(folder, changes):
    """``reduction:`` of the bundle's rod with hostile values: refused at ``reduction`` (a
    reduction that leaves no elastic coordinate too), or loaded."""
    reduction = REDUCTION | changes
    if "max_frequency" in changes and "modes" not in changes:
        del reduction["modes"]
    message = refused_or_loaded(model("fe: {bundle: rod.npz}", reduction), folder, ("reduction",))
    if set(changes.values()) & set(NOT_NUMBERS) - {"~"}:
        assert message is not None, changes


FE_VALUES = {"bundle": ["rod.yaml", "sub", "mass.mtx", "missing.npz", "..", "/dev/null", "nodes.csv", "rod.npz"],
             "dofs_per_node": ["3", "6", "4", "0", "-6", "6.0", "[6]", "six", "true"],
             "mass": ["mass.mtx", "stiffness.mtx", "rod.npz", "nodes.csv", "sub"],
             "stiffness": ["stiffness.mtx", "mass.mtx", "nodes.csv", "sub"],
             "nodes": ["nodes.csv", "mass.mtx", "rod.npz", "sub"]}


@fuzz(60)
@given(bundle=st.booleans(), keys=st.sets(st.sampled_from(sorted(FE_VALUES)), max_size=2), data=st.data())
def test_hostile_fe_keys(folder, bundle, keys, data):
    """``fe:`` naming a bundle or three files, each key given a hostile value or another file
    (a folder, the model file, a table where a matrix goes, one that is absent)."""
    fe = {"bundle": "rod.npz"} if bundle else {"mass": "mass.mtx", "stiffness": "stiffness.mtx", "nodes": "nodes.csv"}
    for key in sorted(keys):
        fe[key] = data.draw(st.sampled_from(FE_VALUES[key] + NOT_NUMBERS))
    refused_or_loaded(model("fe: " + flow(fe)), folder, ("fe", "reduction"))


# ------------------------------------------------------------------ hostile data files


def coo_arrays():
    """write_fe's arrays of the beam: nodes, COO triplets of mass and stiffness, dofs_per_node."""
    arrays = {"nodes": FE.nodes, "dofs_per_node": np.int64(6)}
    for name in ("mass", "stiffness"):
        coo = getattr(FE, name).tocoo()
        arrays |= {f"{name}_rows": coo.row, f"{name}_cols": coo.col, f"{name}_values": coo.data}
    return arrays


def dense_arrays():
    return {"nodes": FE.nodes, "mass": FE.mass.toarray(), "stiffness": FE.stiffness.toarray()}


# what an array of a bundle may be replaced by: a function of the array it replaces
HOSTILE_ARRAYS = [
    lambda a: np.array("x"), lambda a: a.astype(str), lambda a: a.astype(complex), lambda a: a + 1e-3j,
    lambda a: a.astype(bool), lambda a: np.zeros(0), lambda a: np.zeros((0, 0)), lambda a: a[:-1],
    lambda a: a[..., None], lambda a: a.T, lambda a: np.float64(1.0), lambda a: np.full(a.shape, np.nan),
    lambda a: -a, lambda a: np.where(a != 0, np.inf, 0.0), lambda a: a.astype(np.float32), lambda a: a + 0.5,
    lambda a: a - 100, lambda a: a + 10**12, lambda a: a[::-1], lambda a: np.array(4), lambda a: np.array([6, 6]),
    lambda a: np.array(6.0), lambda a: np.array(True), lambda a: np.array([[1, 2, 3]] * 40, dtype=float),
    lambda a: np.int8(a) if a.dtype.kind in "iu" else a.astype(np.float16),
]


@fuzz(80)
@given(dense=st.booleans(), data=st.data())
def test_hostile_bundle_arrays(folder, dense, data):
    """A bundle whose arrays were deleted, replaced by hostile ones (text, complex, booleans,
    empty, of another shape, NaN, overflowing, negative or fractional indices) or joined by
    junk: loaded, or refused at ``fe.bundle`` (or ``reduction``) naming the file."""
    arrays = dense_arrays() if dense else coo_arrays()
    for _ in range(data.draw(st.integers(1, 2))):
        key = data.draw(st.sampled_from(sorted(arrays) + ["junk"]))
        operation = data.draw(st.sampled_from(["delete", "replace"]))
        if operation == "delete" and key in arrays:
            del arrays[key]
        else:
            arrays[key] = data.draw(st.sampled_from(HOSTILE_ARRAYS))(np.asarray(arrays.get(key, FE.nodes)))
    np.savez(folder / "hostile.npz", **arrays)
    refused_or_loaded(model("fe: {bundle: hostile.npz}"), folder, ("fe", "reduction"), ["hostile.npz"])


@fuzz(100)
@given(cut=st.integers(0, 10**6), flips=st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), max_size=3),
       head=st.sampled_from([b"", b"\x00", b"PK\x03\x04", b"\x93NUMPY", b"junk"]))
def test_damaged_bundle_bytes(folder, cut, flips, head):
    """rod.npz truncated, with bytes changed, or behind junk (an empty file, a zip that is not
    whole, a damaged member): refused at ``fe.bundle`` naming the file, or loaded (a change the
    archive's checksums do not see)."""
    data = bytearray((folder / "rod.npz").read_bytes())
    data = data[:cut % (len(data) + 1)]
    for at, value in flips:
        if data:
            data[at % len(data)] = value
    (folder / "damaged.npz").write_bytes(head + bytes(data))
    refused_or_loaded(model("fe: {bundle: damaged.npz}"), folder, ("fe", "reduction"), ["damaged.npz"])


MTX_JUNK = ["", "%%MatrixMarket matrix coordinate complex symmetric", "%%MatrixMarket matrix array real general",
            "%%MatrixMarket matrix coordinate pattern symmetric", "%%MatrixMarket tensor", "1 2", "x y z",
            "99999999999999999999 1 1.0", "0 0 1.0", "-1 3 2.0", "30 30 1", "3 3 nan", "1 1 1e999", "\x00"]


@fuzz(100)
@given(which=st.sampled_from(["mass.mtx", "stiffness.mtx", "nodes.csv"]), data=st.data())
def test_hostile_matrix_market_and_table_text(folder, which, data):
    """One of the three files with a line deleted, replaced or added (another header, junk,
    indices out of range, complex or pattern fields): refused at ``fe`` (or ``reduction``)
    naming that file, or loaded."""
    lines = (folder / which).read_text().splitlines()
    for _ in range(data.draw(st.integers(1, 3))):
        at = data.draw(st.integers(0, len(lines)))
        operation = data.draw(st.sampled_from(["delete", "replace", "insert"]))
        if operation == "delete" and at < len(lines):
            del lines[at]
        elif operation == "replace" and at < len(lines):
            lines[at] = data.draw(st.sampled_from(MTX_JUNK))
        else:
            lines.insert(at, data.draw(st.sampled_from(MTX_JUNK)))
    files = {"mass": "mass.mtx", "stiffness": "stiffness.mtx", "nodes": "nodes.csv"}
    files = {k: ("hostile_" + v if v == which else v) for k, v in files.items()}
    (folder / ("hostile_" + which)).write_text("\n".join(lines) + "\n")
    refused_or_loaded(model("fe: " + flow(files)), folder, ("fe", "reduction"), ["hostile_" + which])


def test_the_files_and_keys_to_break_load(folder):
    """The unbroken bundle, the three files and the beam give the same rod: 7 frame coordinates
    and one mode."""
    for source in ("fe: {bundle: rod.npz}", "fe: {mass: mass.mtx, stiffness: stiffness.mtx, nodes: nodes.csv}",
                   "beam: " + flow(BEAM)):
        assert loads(model(source), name=MODEL, folder=folder).n == 8
