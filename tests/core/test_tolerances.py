"""Every tolerance lives in mbsynth/core/tolerances.py, under its own name with a one-line reason:
no module of mbsynth writes a small number (below SMALL) inline or defines a ``*_RTOL``/``*_TOL``
constant of its own. Read from the sources with ``ast``."""

import ast
import re
from pathlib import Path

import mbsynth.core.tolerances as tolerances
from mbsynth.core import dop853_tableau as tableau

PACKAGE = Path(__file__).resolve().parents[2] / "mbsynth"
TOLERANCES = PACKAGE / "core" / "tolerances.py"
SMALL = 1e-3  # a float literal below this (in size, not zero) is a tolerance, a step or a guard
TOLERANCE_NAME = re.compile(r"(RTOL|ATOL|_TOL|RCOND)(_|$)")
# Numbers below SMALL that are not tolerances (a unit conversion, a physical constant, a method's coefficient):
# {"folder/module.py": {value, ...}}
NOT_TOLERANCES = {"core/dop853_tableau.py": {-tableau.A[14, 10], tableau.A[14, 11], -tableau.A[14, 12]}}


def inline_tolerances(source, allowed=frozenset()):
    """[(line, value)] of the float literals below SMALL in ``source`` and of the module-level
    constants named like a tolerance (``name``, line) that it defines."""
    found = []
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if (isinstance(node, ast.Constant) and type(node.value) in (float, complex)
                and 0 < abs(node.value) < SMALL and node.value not in allowed):
            found.append((node.lineno, node.value))
    for node in tree.body:
        targets = {ast.Assign: lambda: node.targets, ast.AnnAssign: lambda: [node.target]}.get(type(node), list)()
        names = [n for t in targets for n in ([t] if isinstance(t, ast.Name) else getattr(t, "elts", []))]
        found += [(n.lineno, n.id) for n in names if isinstance(n, ast.Name) and TOLERANCE_NAME.search(n.id)]
    return found


def test_no_module_writes_a_tolerance_inline():
    inline = [f"{path.relative_to(PACKAGE)}:{line}: {what}"
              for path in sorted(PACKAGE.rglob("*.py")) if path != TOLERANCES
              for line, what in inline_tolerances(path.read_text(),
                                                  NOT_TOLERANCES.get(path.relative_to(PACKAGE).as_posix(), set()))]
    assert inline == [], "move these to mbsynth/core/tolerances.py under a name with a reason:\n" + "\n".join(inline)


def test_the_scan_finds_an_inline_tolerance():
    source = "import numpy as np\nLOCAL_RTOL = 0.5\n\ndef f(x):\n    return abs(x) < 1e-9 * np.max(x, 1e-300)\n"
    assert inline_tolerances(source) == [(5, 1e-9), (5, 1e-300), (2, "LOCAL_RTOL")]
    assert inline_tolerances("x = 2.5e-3 + 1e-3 + 0.0\n") == []


def test_each_tolerance_has_one_name_and_a_reason():
    lines = TOLERANCES.read_text().splitlines()
    assigned = [(node.lineno, target.id) for node in ast.parse(TOLERANCES.read_text()).body
                if isinstance(node, ast.Assign) for target in node.targets]
    names = [name for _, name in assigned]
    assert len(names) == len(set(names)), "a name is defined twice"
    unexplained = [name for line, name in assigned if "  # " not in lines[line - 1]]
    assert unexplained == []
    assert all(isinstance(getattr(tolerances, name), float) for name in names)
    values = {name: getattr(tolerances, name) for name in names}
    assert values["EPS"] == 2.0 ** -52  # the float spacing at 1 (IEEE 754 double)
