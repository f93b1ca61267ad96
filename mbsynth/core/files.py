"""Where mbsynth keeps files: a writable per-user cache directory, versions of it keyed
by a digest of sources, pruned when unused.

``MBSYNTH_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/mbsynth``, else ``~/.cache/mbsynth``;
when none of them can be written, a directory under the system's temporary directory.
"""

import hashlib
import os
import shutil
import tempfile
import threading
import time
from pathlib import Path

STALE_DAYS = 30  # a version's directory unused this long is removed
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


def sources_hash(folder, pattern="*.py", salt=""):
    """A digest of sources: the files ``pattern`` of ``folder`` (their names and bytes) and
    ``salt``; what was made from them is kept under it."""
    folder = Path(folder)
    digest = hashlib.sha256(salt.encode())
    for path in sorted(folder.glob(pattern)):
        digest.update(path.relative_to(folder).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


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


def write_atomically(path, write):
    """Make ``path`` by ``write(temporary)``, a path beside it (its suffix kept) unique to this
    process and thread, then a rename: a reader finds the old file or the whole new one,
    never a part, also when several processes write the same path. ``write``'s error
    leaves no temporary behind and is raised."""
    path = Path(path)
    temporary = path.with_name(f".{path.stem}.{os.getpid()}.{threading.get_ident()}.tmp{path.suffix}")
    try:
        write(temporary)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
