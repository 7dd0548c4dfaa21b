"""Sphinx configuration of the hybrid documentation site (``make docs``).

Pages are MyST Markdown files under docs/; a new page needs one line in a
toctree of index.md (see docs/contributing-docs.md). The API reference is
generated from the numpydoc docstrings (autosummary over the ``__all__`` of the
modules in ``API_MODULES``), the command-line reference from
``hybrid.cli.main.build_parser()`` (docs/_ext/hybrid_docs.py), both at build time.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path[:0] = [str(ROOT), str(DOCS / "_ext")]

from hybrid.version import __version__  # noqa: E402

project = "hybrid"
author = "the hybrid authors"
copyright = "the hybrid authors"
version = release = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "hybrid_docs",
]

source_suffix = {".md": "markdown"}
root_doc = "index"
smartquotes = False  # quotes in commands and help texts stay as typed
exclude_patterns = ["_build", "_generated", "**/.ipynb_checkpoints"]
templates_path = ["_templates"]

# --- MyST: CommonMark, fenced code blocks, GitHub-style heading anchors -----------------
myst_heading_anchors = 4
myst_enable_extensions = ["colon_fence"]

# --- the API reference ------------------------------------------------------------------
API_MODULES = [
    "hybrid",
    "hybrid.simulation",
    "hybrid.simulation.inputs",
    "hybrid.analysis",
    "hybrid.export",
    "hybrid.progress",
    "hybrid.errors",
]
"""Modules users import; every name in their ``__all__`` gets a page (once)."""

autosummary_generate = False
autosummary_imported_members = True
autodoc_typehints = "none"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = False
numpydoc_xref_param_type = False

# --- HTML ---------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"hybrid {__version__}"
html_static_path = ["_static"]
html_favicon = "_static/favicon.svg"
html_css_files = ["hybrid.css"]
html_copy_source = False
html_show_sourcelink = False
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_context = {"default_mode": "light"}
