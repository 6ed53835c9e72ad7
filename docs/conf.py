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
# docutils' SmartQuotes would print the options' "--" as en dashes in the command-line
# reference (sphinx-click writes rst), examples included: keep the characters typed
smartquotes = False
html_title = "stabctl"


# -- the model reference, generated from the parameter declarations --------------------

_FAMILIES = (
    ("Synchronous machines", "stabctl.models.machines", "MACHINE"),
    ("Exciters", "stabctl.models.exciters", "EXCITER"),
    ("Power system stabilisers", "stabctl.models.pss", "PSS"),
    ("Governors and turbines", "stabctl.models.governors", "GOVERNOR"),
    ("Converter-interfaced devices", "stabctl.models.converters", "CONVERTER"),
)


def _cell(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _span(lo, hi) -> str:
    if lo is None:
        return "" if hi is None else f"<= {hi:g}"
    return f">= {lo:g}" if hi is None else f"[{lo:g}, {hi:g}]"


def model_reference() -> str:
    """The markdown of models_reference.md: per family its table's columns (name, unit,
    default, range, meaning) and the PSS/E and ANDES models read into it, straight from
    the declarations (`stabctl.models.declaration`), so that the page cannot drift."""
    import importlib

    out = [
        "# Model reference",
        "",
        "Generated from the parameter declarations (`stabctl.models.declaration`: each "
        "parameter declared once, beside its model's kernels) when the site is built.",
    ]
    for title, module, name in _FAMILIES:
        fam = getattr(importlib.import_module(module), name)
        out += ["", f"## {title}: `{fam.table}`", ""]
        out += ["| col | name | unit | default | range | meaning |", "|---|---|---|---|---|---|"]
        for p in fam.params:
            span = _span(p.lo, p.hi)
            if p.choices:
                span = ", ".join(f"{c:g}" for c in p.choices)
            names = p.name + (f" / {p.alt}" if p.alt else "")
            out.append(
                f"| {p.col} | `{_cell(names)}` | {_cell(p.unit)} | {p.default:g} | {_cell(span)} "
                f"| {_cell(p.doc)} |"
            )
        if fam.dyr:
            out += [
                "",
                "Read from PSS/E DYR records (and the ANDES models with the same parameters):",
                "",
            ]
            for m in fam.dyr:
                andes = f" (ANDES: {', '.join(m.andes)})" if m.andes else ""
                out.append(f"- `{m.name}`{andes}: {', '.join(m.fields)}")
    return "\n".join(out) + "\n"


def _write_model_reference(app):
    from pathlib import Path

    path = Path(app.srcdir) / "models_reference.md"
    text = model_reference()
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def setup(app):
    app.connect("builder-inited", _write_model_reference)
