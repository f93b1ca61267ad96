"""Where compiled code lives, in the cache directory (core/files.py).

numba's on-disk cache (``cache=True``) goes to ``<cache>/numba/<hash of this package's
sources>`` unless NUMBA_CACHE_DIR is already set: numba checks only the file of the function
it loads, so a kernel compiled against an older version of a module it calls would be
loaded stale; the generated source of each model's force/constraint function (codegen.py)
goes to ``<cache>/generated``. bodies.py, which every kernel module imports first, calls
``configure()`` before anything compiles. Each use marks its version's directory; the
directories of versions unused for ``STALE_DAYS`` are removed (each holds tens of MB).
"""

import os
from pathlib import Path

from ..core.files import cache_dir, mark_and_prune, sources_hash
from ..core.memo import MEMO

HERE = Path(__file__).resolve().parent  # the compiled path's sources: the kernels and all they call
# constants the kernels compile in: the tolerances and the joint kinds' row programs
CONSTANTS = (HERE.parent / "core" / "tolerances.py", HERE.parent / "core" / "joint_kinds.py")


def digest():
    """The digest that names this version of the compiled code: the sources beside this file
    and the constants the kernels read."""
    return sources_hash(HERE, salt="".join(path.read_text() for path in CONSTANTS))

def configure():
    """Point numba's cache at ``<cache>/numba/<digest()>`` unless NUMBA_CACHE_DIR is set
    (then mark it used and prune the stale versions)."""
    if not os.environ.get("NUMBA_CACHE_DIR"):
        version = cache_dir() / "numba" / digest()
        os.environ["NUMBA_CACHE_DIR"] = str(version)
        mark_and_prune(version)
    import sys
    config = sys.modules.get("numba.core.config")
    # numba imported before us: tell it directly (while another thread is still importing it,
    # it has no CACHE_DIR yet and reads the variable itself when done)
    if config is not None and hasattr(config, "CACHE_DIR") and not config.CACHE_DIR:
        config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]


def compiled_mark():
    """The file whose presence says that numba's cache holds the kernels of these sources
    (background.py writes it when an Engine has been warmed): ``<numba cache>/.compiled-<digest()>``."""
    sources = _sources_digest()
    return Path(os.environ.get("NUMBA_CACHE_DIR") or cache_dir() / "numba" / sources) / f".compiled-{sources}"


@MEMO.function(1)
def _sources_digest():
    """``digest()``, once per process."""
    return digest()


def generated_dir():
    path = cache_dir() / "generated"
    path.mkdir(parents=True, exist_ok=True)
    return path
