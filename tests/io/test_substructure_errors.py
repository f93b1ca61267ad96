"""Bad substructure input (``type: model`` entries, ports, copies, ``for:`` joints) is refused
by ``mbsynth check`` with exit 2 and one line naming FILE:LINE of the including entry, and of
the included file's own line where the problem is inside it, with the chain of entries that
led there."""

import contextlib
import io
import subprocess
import warnings

import pytest

from mbsynth.cli import main

BAD_INPUT = 2  # the CLI's exit status for a bad model file

CELL = """\
name: cell
parameters: {L: 1.0, m: 1.0}
parts:
  p: {type: particle, mass: m, initial: {position: [L, 0, 0]}}
joints:
  - {name: pin, type: spherical, parent: world, child: p}
ports: {tip: p}
"""
NEGATIVE_MASS = """\
name: negative
parameters: {m: 1}
parts:
  p: {type: particle, mass: -m}
"""


def entry(spec, rest=""):
    """A top file whose line 2 is the entry ``c: {type: model, SPEC}``, then ``rest``."""
    return f"parts:\n  c: {{type: model, {spec}}}\n{rest}"


JOIN_TO = "  q: {{type: particle, mass: 1}}\njoints:\n  - {{name: j, type: spherical, parent: \"{frame}\", child: q}}\n"
DISTANCES = """\
joints:
  - name: link
    for: {{i: [0, {last}]}}
    type: distance
    length: 1
    parent: c[i].tip
    child: c[i+1].tip
"""

# case: ({file: text} besides cell.yaml, the top file, [texts the message must hold])
CASES = {
    "includes itself": ({"top.yaml": "parameters: {a: 1}\nparts:\n  me: {type: model, file: top.yaml}\n"},
                        "top.yaml", ["top.yaml:3: at parts.me.file:", "includes itself: top.yaml:3 →"]),
    "includes itself through another": (
        {"a.yaml": "parts:\n  x: {type: model, file: b.yaml}\n",
         "b.yaml": "parameters: {z: 1}\nparts:\n  y: {type: model, file: a.yaml}\n"},
        "a.yaml", ["b.yaml:3: at parts.y.file:", "includes itself: a.yaml:2 →", "b.yaml:3 →"]),
    "missing file": ({"top.yaml": entry("file: nothere.yaml")}, "top.yaml",
                     ["top.yaml:2: at parts.c.file:", "no such model file 'nothere.yaml'"]),
    "folder as file": ({"top.yaml": entry("file: folder.yaml")}, "top.yaml",
                       ["top.yaml:2: at parts.c.file:", "'folder.yaml' is a folder"]),
    "no file key": ({"top.yaml": entry("count: 2")}, "top.yaml", ["top.yaml:2: at parts.c:", "'file'"]),
    "unknown port": ({"top.yaml": entry("file: cell.yaml", JOIN_TO.format(frame="c.nosuch"))}, "top.yaml",
                     ["top.yaml:5: at joints[0].parent:", "no port or part frame 'nosuch'", "its ports: tip"]),
    "part not in the child": ({"top.yaml": entry("file: cell.yaml", JOIN_TO.format(frame="c.arm.top"))},
                              "top.yaml", ["top.yaml:5: at joints[0].parent:", "no port or part frame 'arm.top'",
                                           "its parts: p"]),
    "frame not on the child's part": ({"top.yaml": entry("file: cell.yaml", JOIN_TO.format(frame="c.p.top"))},
                                      "top.yaml", ["top.yaml:5: at joints[0].parent:", "'c.p' has no frame 'top'"]),
    "index out of range": ({"top.yaml": entry("file: cell.yaml, count: 2", JOIN_TO.format(frame="c[2].tip"))},
                           "top.yaml", ["top.yaml:5: at joints[0].parent:", "'c[2]' is out of range",
                                        "c[0] … c[1]"]),
    "index on an entry without count": (
        {"top.yaml": entry("file: cell.yaml", JOIN_TO.format(frame="c[0].tip"))}, "top.yaml",
        ["top.yaml:5: at joints[0].parent:", "'c' is one file, not numbered copies", "without [0]"]),
    "copies named without index": ({"top.yaml": entry("file: cell.yaml, count: 2", JOIN_TO.format(frame="c.tip"))},
                                   "top.yaml", ["top.yaml:5: at joints[0].parent:", "'c' has 2 copies",
                                                "c[0] … c[1]"]),
    "substructure as a frame": ({"top.yaml": entry("file: cell.yaml", JOIN_TO.format(frame="c"))}, "top.yaml",
                                ["top.yaml:5: at joints[0].parent:", "'c'", "is a substructure, not a frame",
                                 "its ports: tip"]),
    "negative index": ({"top.yaml": entry("file: cell.yaml, count: 2", JOIN_TO.format(frame="c[0 - 1].tip"))},
                       "top.yaml", ["top.yaml:5: at joints[0].parent:", "whole number ≥ 0"]),
    "count 0": ({"top.yaml": entry("file: cell.yaml, count: 0")}, "top.yaml",
                ["top.yaml:2: at parts.c.count:", "whole number ≥ 1, got 0"]),
    "negative count": ({"top.yaml": entry("file: cell.yaml, count: -3")}, "top.yaml",
                       ["top.yaml:2: at parts.c.count:", "whole number ≥ 1, got -3"]),
    "fractional count": ({"top.yaml": entry("file: cell.yaml, count: 1.5")}, "top.yaml",
                         ["top.yaml:2: at parts.c.count:", "whole number ≥ 1, got 1.5"]),
    "count not a number": ({"top.yaml": entry("file: cell.yaml, count: yes")}, "top.yaml",
                           ["top.yaml:2: at parts.c.count:", "expected a number"]),
    "huge count": ({"top.yaml": entry("file: cell.yaml, count: 1e9")}, "top.yaml",
                   ["top.yaml:2: at parts.c.count:", "more than 100000 copies"]),
    "zero axis": ({"top.yaml": entry("file: cell.yaml, placement: {axis: [0, 0, 0]}")}, "top.yaml",
                  ["top.yaml:2: at parts.c.placement.axis:", "must not be zero"]),
    "zero quaternion": ({"top.yaml": entry("file: cell.yaml, placement: {quaternion: [0, 0, 0, 0]}")}, "top.yaml",
                        ["top.yaml:2: at parts.c.placement.quaternion:", "must not be zero"]),
    "quaternion not of unit norm": (
        {"top.yaml": entry("file: cell.yaml, placement: {quaternion: [1, 1, 0, 0]}")}, "top.yaml",
        ["top.yaml:2: at parts.c.placement.quaternion:", "not of unit norm"]),
    "two orientations": ({"top.yaml": entry("file: cell.yaml, placement: {rpy: [0, 0, 1], axis: [0, 0, 1]}")},
                         "top.yaml", ["top.yaml:2: at parts.c.placement:", "at most one of"]),
    "position not of 3": ({"top.yaml": entry("file: cell.yaml, placement: {position: [1, 0]}")}, "top.yaml",
                          ["top.yaml:2: at parts.c.placement.position:", "list of 3"]),
    "index without count": ({"top.yaml": entry("file: cell.yaml, placement: {position: [index, 0, 0]}")},
                            "top.yaml", ["top.yaml:2: at parts.c.placement.position[0]:", "'index'"]),
    "parameter given twice": (
        {"top.yaml": "parts:\n  c:\n    type: model\n    file: cell.yaml\n    parameters:\n"
                     "      L: 2\n      L: 3\n"}, "top.yaml", ["top.yaml:7:", "duplicate key 'L'", "line 6"]),
    "parameter the child lacks": ({"top.yaml": entry("file: cell.yaml, parameters: {Ls: 2}")}, "top.yaml",
                                  ["top.yaml:2: at parts.c.parameters.Ls:", "not a parameter of",
                                   "cell.yaml", "did you mean 'L'"]),
    "a parameter named index": ({"top.yaml": "parameters: {index: 1}\n" + entry("file: cell.yaml, count: 2")},
                                "top.yaml", ["top.yaml:3: at parts.c.count:", "parameter 'index'"]),
    "a copy's parameter not real": (
        {"top.yaml": entry("file: cell.yaml, count: 3, parameters: {L: sqrt(1 - index)}")}, "top.yaml",
        ["top.yaml:2: at parts.c.parameters.L:", "not a finite real number", "(with index = 2)"]),
    "unknown key of the entry": ({"top.yaml": entry("file: cell.yaml, mass: 3")}, "top.yaml",
                                 ["top.yaml:2: at parts.c.mass:", "unknown key 'mass'"]),
    "error inside the child": ({"child.yaml": NEGATIVE_MASS, "top.yaml": entry("file: child.yaml")}, "top.yaml",
                               ["child.yaml:4: at parts.p.mass:", "mass must be ≥ 0",
                                "(in 'c', included from top.yaml:2)"]),
    "error in the child's child": (
        {"leaf.yaml": NEGATIVE_MASS, "mid.yaml": "parts:\n  inner: {type: model, file: leaf.yaml}\n",
         "top.yaml": "name: top\nparts:\n  outer: {type: model, file: mid.yaml}\n"}, "top.yaml",
        ["leaf.yaml:4: at parts.p.mass:", "(in 'outer.inner', included from ", "mid.yaml:2, top.yaml:3)"]),
    "error in one copy's child": (
        {"leaf.yaml": NEGATIVE_MASS, "mid.yaml": "parts:\n  inner: {type: model, file: leaf.yaml}\n",
         "top.yaml": entry("file: mid.yaml, count: 2")}, "top.yaml",
        ["leaf.yaml:4: at parts.p.mass:", "(in 'c[0].inner', included from ", "mid.yaml:2, top.yaml:2)"]),
    "child not valid YAML": ({"child.yaml": "parts:\n  p: {type: particle, mass: [1,\n",
                              "top.yaml": entry("file: child.yaml")}, "top.yaml",
                             ["child.yaml:3: not valid YAML", "(in 'c', included from top.yaml:2)"]),
    "for: range not whole": ({"top.yaml": entry("file: cell.yaml, count: 3", DISTANCES.format(last=1.5))},
                             "top.yaml", ["top.yaml:5: at joints[0].for.i:", "whole numbers"]),
    "for: range backwards": ({"top.yaml": entry("file: cell.yaml, count: 3", DISTANCES.format(last="-2"))},
                             "top.yaml", ["top.yaml:5: at joints[0].for.i:", "runs backwards"]),
    "for: range beyond the bound": ({"top.yaml": entry("file: cell.yaml, count: 3", DISTANCES.format(last="1e9"))},
                                    "top.yaml", ["top.yaml:5: at joints[0].for.i:", "more than 100000 joints"]),
    "for: beyond the last copy": ({"top.yaml": entry("file: cell.yaml, count: 3", DISTANCES.format(last=2))},
                                  "top.yaml", ["top.yaml:9: at joints[0].child:", "'c[3]' is out of range",
                                               "(with i = 2)"]),
    "for: over a parameter's name": (
        {"top.yaml": "parameters: {i: 1}\n" + entry("file: cell.yaml, count: 3", DISTANCES.format(last=1))},
        "top.yaml", ["top.yaml:6: at joints[0].for.i:", "parameter"]),
    "joint named like a substructure": (
        {"top.yaml": entry("file: cell.yaml", JOIN_TO.format(frame="c.tip").replace("name: j,", "name: c,"))},
        "top.yaml", ["top.yaml:5: at joints[0].name:", "name of the substructure 'c'"]),
    "for: joints named like the copies": (
        {"top.yaml": entry("file: cell.yaml, count: 3", DISTANCES.format(last=1).replace("name: link", "name: c"))},
        "top.yaml", ["top.yaml:4: at joints[0].name:", "name of the substructure 'c'"]),
    "port named like a part": ({"child.yaml": "parts:\n  p: {type: particle, mass: 1}\nports: {p: p}\n",
                                "top.yaml": entry("file: child.yaml")}, "top.yaml",
                               ["child.yaml:3: at ports.p:", "name of a part", "(in 'c', included from top.yaml:2)"]),
    "port to an unknown frame": ({"child.yaml": "parts:\n  p: {type: particle, mass: 1}\nports: {tip: p.end}\n",
                                  "top.yaml": entry("file: child.yaml")}, "top.yaml",
                                 ["child.yaml:3: at ports.tip:", "'p' has no frame 'end'",
                                  "(in 'c', included from top.yaml:2)"]),
}


def check(folder, top):
    """``mbsynth check TOP`` from ``folder``, in this process (main, as ``python -m mbsynth.cli``
    calls it): its exit status, stdout and stderr, where the warnings a fresh process would
    print (Python's default filters) follow the command's own lines."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.chdir(folder), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning):
            warnings.simplefilter("ignore", category)  # put before "default": these a process hides
        code = main(["check", top])
    shown = "".join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno) for w in caught)
    return subprocess.CompletedProcess(["mbsynth", "check", top], code, out.getvalue(), err.getvalue() + shown)


@pytest.mark.parametrize("case", CASES)
def test_refused_with_file_and_line(case, tmp_path):
    files, top, expected = CASES[case]
    (tmp_path / "cell.yaml").write_text(CELL)
    (tmp_path / "folder.yaml").mkdir()
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    result = check(tmp_path, top)
    message = result.stderr.strip()
    assert result.returncode == BAD_INPUT, message
    assert "\n" not in message and message.startswith("error: "), message
    for text in expected:
        assert text in message, f"{text!r} not in {message!r}"


def test_cell_alone_is_fine(tmp_path):
    """The cell every case includes is itself a valid model, and so are its copies joined by a
    ``for:`` entry, also over the empty range [0, -1] of one copy: the cases fail for their
    own reason."""
    (tmp_path / "cell.yaml").write_text(CELL)
    (tmp_path / "top.yaml").write_text(entry("file: cell.yaml, count: 3", DISTANCES.format(last=1)))
    (tmp_path / "one.yaml").write_text(entry("file: cell.yaml, count: 1", DISTANCES.format(last=-1)))
    for top in ("cell.yaml", "top.yaml", "one.yaml"):
        result = check(tmp_path, top)
        assert result.returncode == 0, result.stderr
