"""Sphinx configuration of the spherecal documentation (built by .ci/run with warnings as errors)."""

from __future__ import annotations

from importlib.metadata import version as _version

project = "spherecal"
author = "spherecal developers"
release = _version("spherecal")
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "_api_build"]
templates_path = ["_templates"]

# The API reference: one page per public module, generated from the docstrings (Google style).
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False

myst_enable_extensions = ["dollarmath"]
myst_heading_anchors = 3

html_theme = "alabaster"
html_title = f"spherecal {release}"


def _no_inline_attribute_type(app, what, name, obj, options, lines) -> None:
    """Our ``#:`` comments on constants are prose (``Largest length [m]: an arm is not 10 m long``),
    not Google's ``type: description``: an empty type before the first colon keeps napoleon from
    reading the words before it as a type."""
    if what in ("attribute", "data", "property") and lines and ":" in lines[0]:
        lines[0] = ": " + lines[0]


def setup(app) -> None:
    app.connect("autodoc-process-docstring", _no_inline_attribute_type, priority=100)  # before napoleon (500)
