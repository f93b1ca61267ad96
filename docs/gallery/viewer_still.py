"""A still picture of the meshcat scene, for the gallery's scripts (not an example itself).

The offline HTML animation is written by ``mb.viewer.to_html`` beside the scripts (the pages
link it); headless Chromium photographs it the way ``scripts/readme_pictures.py`` does
(``mbsynth.screenshot``). Without Chromium (``scripts/install-chromium.sh`` installs it) there
is no picture and the caller draws a plot instead.
"""

from pathlib import Path

import mbsynth as mb
from mbsynth.screenshot import chromium, screenshot


def still(system, trajectory, name, budget_ms):
    """Write ``<name>.html`` in the current folder; return (its path, a PNG of it or None)."""
    page = mb.viewer.to_html(system, trajectory, Path(f"{name}.html"))
    if chromium() is None:
        return page, None
    return page, screenshot(page, Path(f"{name}.png"), budget_ms=budget_ms)
