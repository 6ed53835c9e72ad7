"""Sphinx configuration of stabctl's documentation site (built in CI with warnings as
errors: `sphinx-build -W --keep-going -b html docs docs/_build/html`)."""

project = "stabctl"
author = "stabctl developers"
extensions = [
    "myst_parser",  # the markdown pages
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",  # the docstrings: NumPy and Google sections
    "sphinx.ext.mathjax",
    "sphinx_click",  # the command-line reference, generated from click
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build"]
myst_heading_anchors = 3
# the pages were written as plain markdown files first: headings need not start at H1
suppress_warnings = ["myst.header"]
autosummary_generate = True
autodoc_default_options = {"members": False}
autodoc_typehints = "none"  # the docstrings state shapes and units
napoleon_numpy_docstring = True
napoleon_google_docstring = True
html_theme = "alabaster"
html_title = "stabctl"
