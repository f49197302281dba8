"""Sphinx configuration of the book (``bash scripts/docs``): the executed notebooks as stored (never
re-executed), the claims ledger, the guides, the API reference and the report schema; warnings are
errors (scripts/book.py)."""
import sys
from pathlib import Path

# the package documented is the one of this checkout (docs/_build/source -> the project root)
sys.path.insert(0, str(Path(__file__).resolve().parents[3]))

project = "replication"
author = "the replication project"
copyright = "the replication project"
extensions = ["myst_nb", "sphinx.ext.autodoc", "sphinx.ext.napoleon"]
exclude_patterns = ["_build", "**.ipynb_checkpoints"]

# the notebooks are rendered from their stored outputs; a notebook with an error output fails the
# build
nb_execution_mode = "off"
nb_execution_raise_on_error = True
# the claim records' own output type (application/vnd.replication.claim+json, read by `claims`) is
# shown as the text/plain line stored beside it; MyST-NB parses every type of a bundle before
# choosing one and warns about a type it has no renderer for: that warning only (the notebooks hold
# no other unknown type: tests/study/test_book.py checks)
nb_mime_priority_overrides = [("html", "application/vnd.replication.claim+json", None)]
suppress_warnings = ["mystnb.unknown_mime_type"]
myst_heading_anchors = 6
myst_enable_extensions = ["colon_fence"]

autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"
napoleon_google_docstring = False
napoleon_numpy_docstring = True

html_theme = "sphinx_book_theme"
html_title = "Cameras and IMU alignment calibration: a replication"
html_theme_options = {"show_toc_level": 2, "use_download_button": False, "use_fullscreen_button": False}
# the theme logs a console error for a reader with no stored mode unless it has a default one
html_context = {"default_mode": "light"}
html_static_path = ["_static"]
html_css_files = ["book.css"]
html_favicon = "_static/favicon.svg"  # else the browser's request for /favicon.ico is a 404 in its console
html_copy_source = False
html_last_updated_fmt = None
html_show_sourcelink = False
