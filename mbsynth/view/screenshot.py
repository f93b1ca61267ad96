"""Pictures of web pages with headless Chromium (Debian's ``chromium``), kept offline.

Used by the viewer's tests and by ``scripts/readme_pictures.py``. WebGL runs on the
CPU (SwiftShader); ``--virtual-time-budget`` lets the page's scripts and animation run
that many milliseconds before the picture is taken. Every host name but localhost
resolves to nothing and every other request goes to a closed local proxy port, so no
request leaves the machine; each run gets a fresh profile folder.
"""

import shutil
import subprocess
import tempfile
from pathlib import Path

FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
         "--disable-background-networking", "--no-first-run")
OFFLINE = ("--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE localhost, EXCLUDE 127.0.0.1",
           "--proxy-server=127.0.0.1:9", "--disable-component-update", "--disable-sync", "--no-default-browser-check")


def chromium():
    """The path of the ``chromium`` program, or None."""
    return shutil.which("chromium")


def screenshot(page, png, size=(800, 600), budget_ms=5000, timeout=120):
    """Save a PNG of ``page`` (a URL, or an HTML file) after ``budget_ms`` of virtual time."""
    program = chromium()
    if program is None:
        raise RuntimeError("chromium is not installed (make test installs it when run as root)")
    url = page if "://" in str(page) else Path(page).resolve().as_uri()
    png = Path(png).resolve()
    png.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory(prefix="mbsynth-chromium-") as profile:
        command = [program, *FLAGS, *OFFLINE, f"--virtual-time-budget={budget_ms}", f"--user-data-dir={profile}",
                   f"--screenshot={png}", f"--window-size={size[0]},{size[1]}", url]
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    if not png.is_file():
        raise RuntimeError(f"chromium wrote no screenshot (exit {done.returncode}): {done.stderr[-2000:]}")
    return png


def show_still(ax, page, png, budget_ms=1500):
    """Draw a still of ``page`` on the matplotlib axes ``ax``, filling its figure; False
    (and nothing drawn) when Chromium is not installed, so the caller can plot instead."""
    if chromium() is None:
        return False
    import matplotlib.pyplot as plt  # only a caller drawing figures needs matplotlib

    ax.imshow(plt.imread(screenshot(page, png, budget_ms=budget_ms)))
    ax.set_axis_off()
    ax.figure.subplots_adjust(0, 0, 1, 1)  # the picture alone, no margins
    return True
