"""Sphinx configuration of the prg documentation (``make docs``: ``docs/_build/html``).

Sphinx rather than MkDocs: the libraries prg is measured against document their numpydoc
docstrings with Sphinx (pingouin, MultiVae, numpy, scipy), so the API reference is generated
from the docstrings as they are written, and the pages are Markdown through MyST.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "src"), str(ROOT)]

project = "prg"
author = "prg developers"
copyright = "2026, prg developers"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "figures/README.md", "**/.ipynb_checkpoints"]
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence"]

templates_path = ["_templates"]
autosummary_generate = True
# each module's page documents what it defines (names a package re-exports stay on their
# defining module's page, so nothing is documented twice)
autodoc_default_options = {"ignore-module-all": True}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
autodoc_member_order = "bysource"
autodoc_inherit_docstrings = False  # Lightning's own docstrings are not ours to build
numpydoc_show_class_members = False
numpydoc_validation_checks: set[str] = set()
suppress_warnings = ["myst.xref_missing"]  # links to files of the repository, not pages

html_theme = "pydata_sphinx_theme"
html_title = "prg"
html_theme_options = {"navigation_with_keys": False, "show_toc_level": 2}
