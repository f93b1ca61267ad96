"""The README's pictures of the viewer, made the way a user sees them: the HTML animation
written by ``mb.viewer.to_html``, photographed by headless Chromium (mbsynth.view.screenshot).

    .venv/bin/python scripts/readme_pictures.py        # writes docs/viewer_*.png
"""

import sys
import tempfile
from pathlib import Path

from PIL import Image

import mbsynth as mb
from mbsynth.view.screenshot import screenshot

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"


def picture(system, trajectory, name, budget_ms):
    """docs/<name>.png: the page after ``budget_ms`` of its animation."""
    with tempfile.TemporaryDirectory() as folder:
        page = mb.viewer.to_html(system, trajectory, Path(folder) / f"{name}.html")
        shot = screenshot(page, Path(folder) / f"{name}.png", budget_ms=budget_ms)
        out = DOCS / f"{name}.png"
        Image.open(shot).convert("RGB").save(out, optimize=True)
    print(f"wrote {out} ({out.stat().st_size // 1024} kB)")


def main():
    DOCS.mkdir(exist_ok=True)
    system = mb.load(ROOT / "models" / "paper" / "example3_two_masses.yaml")
    picture(system, mb.simulate(system, 4.0, dt=1 / 30), "viewer_example3", budget_ms=1500)
    from mbsynth.robots.build import from_robot

    robot = from_robot("ur5")  # unpowered: it falls from its zero configuration
    picture(robot, mb.simulate(robot, 0.6, dt=1 / 30), "viewer_ur5", budget_ms=400)


if __name__ == "__main__":
    sys.exit(main())
