"""Where mbsynth keeps files: a writable per-user cache directory, versions of it keyed
by a digest of sources, pruned when unused; and the rules every output file follows:
its format is its suffix in any case (``file_format``), it is written whole or not at
all (``write_atomically``), and a path where it cannot be is found before any work
(``unwritable``).

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


def file_format(path):
    """The format of the file at ``path``: its suffix in lower case (``run.NPZ`` is an
    .npz file), for every file mbsynth writes or reads back."""
    return Path(path).suffix.lower()


def unwritable(path, folder=False):
    """Why ``write_atomically`` cannot make ``path`` (``folder``: why ``path`` cannot be
    made a folder and filled, as ``mkdir(parents=True)`` would), or None where it can.
    Tried by creating and removing a file where the output goes: the only test that holds
    for every user and file system (root may write anywhere by its mode bits, yet /proc
    takes no new file)."""
    path = Path(path)
    if not folder and path.is_dir():
        return f"{path} is a folder"
    if folder and path.exists() and not path.is_dir():
        return f"{path} is a file, not a folder"
    where = path if folder else path.parent
    if not folder and not where.is_dir():
        return f"the folder {where} does not exist" if not where.exists() else f"{where} is not a folder"
    while not where.exists():  # a folder to be made: its nearest existing ancestor must take it
        where = where.parent
    if not where.is_dir():
        return f"{where} is not a folder"
    try:
        tempfile.NamedTemporaryFile(dir=where, prefix=".mbsynth-probe-").close()
    except OSError as err:
        return f"no file can be created in {where} ({err.strerror or err})"
    return None


def write_atomically(path, write):
    """Make ``path`` by ``write(temporary)``, a path beside it unique to this
    process and thread, ending in its format (``file_format``: a writer that goes by the
    suffix reads ``x.NPZ``'s temporary as .npz), then a rename: a reader finds the old file
    or the whole new one, never a part, also when several processes write the same path.
    ``write``'s error leaves no temporary behind and is raised."""
    path = Path(path)
    temporary = path.with_name(f".{path.stem}.{os.getpid()}.{threading.get_ident()}.tmp{file_format(path)}")
    try:
        write(temporary)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
