"""The package is built in floors: each folder imports only from its own floor and the floors
below it, and no module comes back to itself through a circle of imports. Read from the
sources with ``ast``, imports inside functions included (a function-level import is still
a dependency)."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "mbsynth"
# bottom to top
FLOORS = ("core", "symbolic", "compiled", "model", "analysis", "robots", "io", "view", "studies", "cli")
ROOF = ("mbsynth", "mbsynth.__main__")  # the package's lazy front door and the program may import any floor


def modules():
    """{dotted name: (path, is a package)} of every module, ``__main__`` programs included
    (a program lives on its package's floor)."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        package = parts[-1] == "__init__"
        found[".".join(parts[:-1] if package else parts)] = (path, package)
    return found


def imports(name, path, package, known):
    """The mbsynth modules ``name`` imports (a name imported from a package that is one of
    its modules counts as that module; ``known``: every module)."""
    base = name.split(".") if package else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] == "mbsynth"}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                target = ".".join(base[:len(base) - node.level + 1] + ([node.module] if node.module else []))
            else:
                target = node.module
            if target.split(".")[0] != "mbsynth":
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in known else target)
    # importing a.b.c runs the packages a.b (and a) first: a package the importer is outside of
    # counts as imported too (an __init__ that imports its modules can close a circle)
    for target in list(found):
        parts = target.split(".")
        for k in range(2, len(parts)):
            package = ".".join(parts[:k])
            if package in known and not (name + ".").startswith(package + "."):
                found.add(package)
    return found - {name}


def floor(name):
    parts = name.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in FLOORS else None


def graph():
    known = modules()
    return {name: imports(name, path, package, known) for name, (path, package) in known.items()}


def test_every_module_lives_on_a_floor():
    homeless = [name for name in graph() if name not in ROOF and floor(name) is None]
    assert homeless == []


def test_no_import_from_a_higher_floor():
    uphill = [f"{name} -> {target}" for name, targets in graph().items() if name not in ROOF
              for target in sorted(targets)
              if floor(target) is None or FLOORS.index(floor(target)) > FLOORS.index(floor(name))]
    assert uphill == []


def test_no_circle_of_imports():
    edges = graph()
    circles, state = [], {}

    def visit(node, trail):
        state[node] = "open"
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == "open":
                circles.append(trail[trail.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, trail + [nxt])
        state[node] = "done"

    for start in sorted(edges):
        if start not in state:
            visit(start, [start])
    assert circles == []


def test_the_floor_reader_sees_what_it_must():
    """The reader itself: a known uphill import in a made-up module is found, relative and
    absolute, at module level and inside a function."""
    known = {"mbsynth.core.errors": None, "mbsynth.model.system": None, "mbsynth.core": None}
    source = "from ..model import system\n\ndef f():\n    from mbsynth.model.system import System\n"
    path = Path(__file__).with_name("_floor_probe.py")
    try:
        path.write_text(source)
        found = imports("mbsynth.core.probe", path, False, known)
    finally:
        path.unlink()
    assert found == {"mbsynth.model.system"}
    assert FLOORS.index(floor("mbsynth.model.system")) > FLOORS.index(floor("mbsynth.core.probe"))


def test_programs_are_on_their_floor():
    """Every ``__main__`` program is read like any module (``python -m mbsynth.cli`` on cli's
    floor), so that a program imports uphill no more than its package may."""
    programs = {".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
                for path in PACKAGE.rglob("__main__.py")}
    assert "mbsynth.cli.__main__" in programs and programs <= set(modules())
    assert all(name in ROOF or floor(name) is not None for name in programs)
