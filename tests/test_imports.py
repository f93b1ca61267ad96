"""Every module of mbsynth can be the first one imported: no import cycle hidden by the
order in which ``mbsynth/__init__.py`` happens to import its submodules."""

import subprocess
import sys
from pathlib import Path

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


def test_every_submodule_imports_first_in_a_fresh_interpreter():
    names = module_names()
    assert "mbsynth.subsystems" in names and "mbsynth.connectors.joints" in names
    result = subprocess.run([sys.executable, "-c", FIRST_IMPORTS, str(PACKAGE), *names],
                            capture_output=True, text=True, timeout=600, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == ""

