"""Where compiled code lives: a writable per-user cache directory.

``MBSYNTH_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/mbsynth``, else ``~/.cache/mbsynth``;
when none of them can be written, a directory under the system's temporary directory.
numba's on-disk cache (``cache=True``) goes to ``<cache>/numba`` unless NUMBA_CACHE_DIR is
already set; the generated source of each model's force/constraint function (codegen.py)
goes to ``<cache>/generated``. Call ``configure()`` before numba is imported.
"""

import os
import tempfile
from pathlib import Path


def _writable(path):
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / f".probe-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
        return True
    except OSError:
        return False


def cache_dir():
    """The base cache directory (created)."""
    candidates = []
    if os.environ.get("MBSYNTH_CACHE_DIR"):
        candidates.append(Path(os.environ["MBSYNTH_CACHE_DIR"]))
    xdg = os.environ.get("XDG_CACHE_HOME")
    candidates.append(Path(xdg) / "mbsynth" if xdg else Path.home() / ".cache" / "mbsynth")
    candidates.append(Path(tempfile.gettempdir()) / f"mbsynth-{os.getuid() if hasattr(os, 'getuid') else 'user'}")
    for path in candidates:
        if _writable(path):
            return path
    raise OSError(f"no writable cache directory among {[str(p) for p in candidates]}")


def configure():
    """Point numba's cache at ``<cache>/numba`` unless NUMBA_CACHE_DIR is set already."""
    if not os.environ.get("NUMBA_CACHE_DIR"):
        os.environ["NUMBA_CACHE_DIR"] = str(cache_dir() / "numba")
    import sys
    config = sys.modules.get("numba.core.config")
    if config is not None and not config.CACHE_DIR:  # numba imported before us: tell it directly
        config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]


def generated_dir():
    path = cache_dir() / "generated"
    path.mkdir(parents=True, exist_ok=True)
    return path
