"""Every module of mbsynth can be the first one imported: no import cycle hidden by the
order in which ``mbsynth/__init__.py`` happens to import its submodules; and what is
imported is only what is used (a light import)."""

import argparse
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

from mbsynth.cli import parser
from mbsynth.robots.build import share_dir

PACKAGE = Path(__file__).resolve().parent.parent / "mbsynth"

# In one fresh interpreter, for each module: forget every mbsynth module, stand in an empty
# package for mbsynth (so its __init__ does not choose the order), import the module first.
FIRST_IMPORTS = """\
import importlib, sys, types
failed = []
for name in sys.argv[2:]:
    for loaded in [m for m in sys.modules if m == "mbsynth" or m.startswith("mbsynth.")]:
        del sys.modules[loaded]
    package = types.ModuleType("mbsynth")
    package.__path__ = [sys.argv[1]]
    sys.modules["mbsynth"] = package
    try:
        importlib.import_module(name)
    except Exception as err:
        failed.append(f"{name}: {type(err).__name__}: {err}")
print("\\n".join(failed))
"""


def module_names():
    """mbsynth's submodules and subpackages, dotted, from the files."""
    names = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return [n for n in names if n != "mbsynth" and not n.endswith("__main__")]


@pytest.mark.slow  # each of the package's modules imported first, its dependencies afresh each time
def test_every_submodule_imports_first_in_a_fresh_interpreter():
    names = module_names()
    assert "mbsynth.model.parts" in names and "mbsynth.model.constraints.joints" in names
    result = subprocess.run([sys.executable, "-c", FIRST_IMPORTS, str(PACKAGE), *names],
                            capture_output=True, text=True, timeout=600, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == ""



# Libraries that load when their feature is used (a light import), never before.
HEAVY = ("pandas", "dask", "matplotlib", "meshcat", "pinocchio", "numba")
MODEL = PACKAGE.parent / "models" / "paper" / "example3_m1_zero.yaml"


def run_fresh(code):
    """Run ``code`` in a fresh interpreter; its stdout, then the heavy libraries it left loaded."""
    probe = f"import sys\n{code}\nprint('loaded:', *[m for m in {HEAVY!r} if m in sys.modules])"
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=600,
                            check=False, cwd=PACKAGE.parent)
    assert result.returncode == 0, result.stderr
    out, loaded = result.stdout.rsplit("loaded:", 1)
    return out, loaded.split()


def test_import_mbsynth_loads_no_heavy_library():
    out, loaded = run_fresh("import mbsynth")
    assert loaded == []


def test_check_loads_only_what_check_needs():
    """``mbsynth check`` (the paper's example 3 with m1 = 0, unique by Result 3) runs to
    its verdict without dask, pandas, matplotlib, meshcat or pinocchio."""
    out, loaded = run_fresh(f"from mbsynth.cli import main\nassert main(['check', {str(MODEL)!r}]) == 0")
    assert "motion: unique (Result 3)" in out
    assert set(loaded) <= {"numba"}, loaded


def test_public_names_resolve_after_any_import_order():
    """``mb.simulate`` and ``mb.sweep`` stay the functions even when their modules were
    imported first (importing a submodule binds its name on the package)."""
    out, _ = run_fresh("import types, mbsynth.studies.sweep, mbsynth.analysis.simulate, mbsynth as mb\n"
                       "for name in mb.__all__:\n"
                       "    value = getattr(mb, name)\n"
                       "    assert isinstance(value, types.ModuleType) == (name == 'viewer'), name\n"
                       "assert mb.simulate is sys.modules['mbsynth.analysis.simulate'].simulate\n"
                       "assert mb.sweep is sys.modules['mbsynth.studies.sweep'].sweep\n"
                       "print(sorted(set(mb.__all__) - set(dir(mb))))")
    assert out.strip() == "[]"


def test_every_command_of_the_parser_has_its_module():
    """``mbsynth.cli.parser()`` is the whole command line (the CLI reference is generated
    from it); main runs a command from the module of the same name."""
    commands = next(a for a in parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    assert {"check", "simulate", "sweep", "view", "validate", "robots"} <= set(commands)
    for name in commands:
        assert callable(importlib.import_module(f"mbsynth.cli.{name}").run), name



@pytest.mark.skipif(share_dir() is None, reason="example-robot-data is not installed")
def test_building_a_robot_loads_neither_scipy_nor_package_metadata():
    """``from_robot`` (the UR5 of example-robot-data, found beside the installed packages)
    builds with sympy and numpy alone: scipy loads with the first solve that needs it and
    importlib.metadata only where the robots are not on sys.path (loading it is a large share
    of a build). Checked on a build whose derivations are cached (a first build, in
    another process, keeps them): a cold derivation compiles with sympy's lambdify, which
    may load numpy.testing and through it importlib.metadata."""
    build = ("import mbsynth as mb\nsystem = mb.from_robot('ur5')\n"
             "print(len(system.coordinates), [m for m in ('scipy', 'importlib.metadata') if m in sys.modules])")
    run_fresh(build)
    out, _ = run_fresh(build)
    assert out.split(maxsplit=1) == ["77", "[]\n"]  # 11 bodies of 7 coordinates
