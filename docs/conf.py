"""Sphinx configuration of the mbsynth documentation (``make docs``)."""

import os
import sys
from pathlib import Path

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import mbsynth  # noqa: E402

project = "mbsynth"
author = "the mbsynth authors"
copyright = "2026, the mbsynth authors"
release = version = mbsynth.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into _static/mathjax: the math typesets offline
    "sphinx.ext.viewcode",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "mbsynth_reference",  # docs/_ext: model-files.md and cli.md from the schema and the parsers
]

# The pages load MathJax from the site itself (sphinx-mathjax-offline copies its files into
# _build/html/_static/mathjax when a build succeeds), never from a CDN:
# tests/test_docs.py checks the built pages.
mathjax_path = "mathjax/tex-chtml.js"

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "gallery"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autosummary_generate = False
napoleon_numpy_docstring = True
napoleon_google_docstring = False

sphinx_gallery_conf = {
    "examples_dirs": "gallery",
    "gallery_dirs": "auto_gallery",
    "filename_pattern": r"/plot_",  # every plot_*.py runs at build time
    "image_scrapers": ("matplotlib",),
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
}

html_theme = "pydata_sphinx_theme"
html_title = "mbsynth"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
html_static_path = []
smartquotes = False  # "--t-end" stays two hyphens
