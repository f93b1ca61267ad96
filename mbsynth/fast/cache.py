"""Where compiled code lives: a writable per-user cache directory.

``MBSYNTH_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/mbsynth``, else ``~/.cache/mbsynth``;
when none of them can be written, a directory under the system's temporary directory.
numba's on-disk cache (``cache=True``) goes to ``<cache>/numba/<hash of this package's
sources>`` unless NUMBA_CACHE_DIR is already set: numba checks only the file of the function
it loads, so a kernel compiled against an older version of a module it calls would be
loaded stale; the generated source of each model's force/constraint function (codegen.py)
goes to ``<cache>/generated``. bodies.py, which every kernel module imports first, calls
``configure()`` before anything compiles. Each use marks its version's directory; the
directories of versions unused for ``STALE_DAYS`` are removed (each holds tens of MB).
"""

import hashlib
import os
import shutil
import tempfile
import time
from pathlib import Path

STALE_DAYS = 30  # a version's numba directory unused this long is removed
MARK = ".last-used"


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


def sources_hash(folder=None, pattern="*.py", salt=""):
    """A digest of the fast path's sources (the kernels and everything they call): the files
    ``pattern`` of ``folder``, this package's .py files by default, and ``salt``."""
    folder = Path(folder or Path(__file__).resolve().parent)
    digest = hashlib.sha256(salt.encode())
    for path in sorted(folder.glob(pattern)):
        digest.update(path.relative_to(folder).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def configure():
    """Point numba's cache at ``<cache>/numba/<sources_hash()>`` unless NUMBA_CACHE_DIR is set
    (then mark it used and prune the stale versions)."""
    if not os.environ.get("NUMBA_CACHE_DIR"):
        version = cache_dir() / "numba" / sources_hash()
        os.environ["NUMBA_CACHE_DIR"] = str(version)
        mark_and_prune(version)
    import sys
    config = sys.modules.get("numba.core.config")
    # numba imported before us: tell it directly (while another thread is still importing it,
    # it has no CACHE_DIR yet and reads the variable itself when done)
    if config is not None and hasattr(config, "CACHE_DIR") and not config.CACHE_DIR:
        config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]


def mark_and_prune(version):
    """Touch ``version``'s mark, then remove its siblings whose mark (or, unmarked, whose
    directory) is older than STALE_DAYS. A cache that cannot be written is left alone."""
    try:
        version.mkdir(parents=True, exist_ok=True)
        (version / MARK).touch()
        cutoff = time.time() - STALE_DAYS * 86400
        for other in version.parent.iterdir():
            if other == version or not other.is_dir():
                continue
            mark = other / MARK
            if (mark if mark.exists() else other).stat().st_mtime < cutoff:
                shutil.rmtree(other, ignore_errors=True)
    except OSError:
        pass


def compiled_mark():
    """The file whose presence says that numba's cache holds the kernels of these sources
    (background.py writes it when an Engine has been warmed): ``<numba cache>/.compiled-<sources_hash()>``."""
    global _sources
    if _sources is None:
        _sources = sources_hash()
    return Path(os.environ.get("NUMBA_CACHE_DIR") or cache_dir() / "numba" / _sources) / f".compiled-{_sources}"


_sources = None  # sources_hash() of this package, once computed


def generated_dir():
    path = cache_dir() / "generated"
    path.mkdir(parents=True, exist_ok=True)
    return path
