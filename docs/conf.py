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


#: the families with one module per type (title, package, family declaration)
_TYPED = (
    ("Exciters", "stabctl.models.exciters", "EXCITER"),
    ("Power system stabilisers", "stabctl.models.pss", "PSS"),
    ("Governors and turbines", "stabctl.models.governors", "GOVERNOR"),
)


def type_pages() -> dict[str, str]:
    """One markdown page per model type of the typed families, from its module: what it
    is (the module's docstring), its named states, its DYR records with the table
    columns each fills, and those columns' units, defaults and ranges; plus the index
    page ``models/index.md``.  Returns file name (under ``models/``) -> text."""
    import importlib
    import inspect
    import re

    pages: dict[str, str] = {}
    index = [
        "# Model types",
        "",
        "One page per model type, generated from its module (`stabctl.models.<family>."
        "<type>`) when the site is built: its equations' source, named states, DYR records "
        "and parameters. How to add a type: docs/simulator.md.",
    ]
    for title, module, name in _TYPED:
        pkg = importlib.import_module(module)
        fam = getattr(pkg, name)
        params = {p.name: p for p in fam.params}
        alt = {p.alt: p for p in fam.params if p.alt}
        index += ["", f"## {title} (`{fam.table}`)", ""]
        for code, mod in pkg.TYPES.items():
            kind = mod.KINDS[code]
            slug = re.sub(r"[^a-z0-9]+", "_", kind.split()[0].lower()).strip("_")
            page = f"{fam.table}_{code}_{slug}"
            index.append(f"- [{kind}]({page}.md): `{fam.table}` type {code}, `{mod.__name__}`")
            doc = inspect.getdoc(mod) or ""
            out = [f"# {kind} (`{fam.table}` type {code})", "", f"Module `{mod.__name__}`.", ""]
            out += [doc, ""]
            out += ["## States", ""]
            out += [f"{j}. `{n}`" for j, n in enumerate(pkg.STATE_NAMES.get(code, ()), 1)] or [
                "none"
            ]
            records = [m for m in mod.DYR if m.kind in (None, code)]
            used: list = []
            for m in records:
                andes = f" (ANDES: {', '.join(m.andes)})" if m.andes else ""
                out += ["", f"## DYR record `{m.name}`{andes}", ""]
                out += [f"Fields after the machine id: {', '.join(m.fields)}.", ""]
                if m.copy:
                    out += ["| table column | DYR field |", "|---|---|"]
                    out += [f"| `{c}` | {f} |" for c, f in m.copy.items()]
                used += [params.get(c) or alt.get(c) for c in m.copy]
            used = [p for p in dict.fromkeys(used) if p is not None]
            if used:
                out += ["", "## Parameters read", ""]
                out += [
                    "| col | name | unit | default | range | meaning |",
                    "|---|---|---|---|---|---|",
                ]
                for p in used:
                    span = (
                        ", ".join(f"{c:g}" for c in p.choices) if p.choices else _span(p.lo, p.hi)
                    )
                    out.append(
                        f"| {p.col} | `{_cell(p.name)}` | {_cell(p.unit)} | {p.default:g} | "
                        f"{_cell(span)} | {_cell(p.doc)} |"
                    )
            pages.setdefault(f"{page}.md", "\n".join(out) + "\n")
    index += ["", "```{toctree}", ":hidden:", "", *sorted(p[:-3] for p in pages), "```"]
    pages["index.md"] = "\n".join(index) + "\n"
    return pages


def _write(path, text: str) -> None:
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def _write_model_reference(app):
    from pathlib import Path

    _write(Path(app.srcdir) / "models_reference.md", model_reference())
    folder = Path(app.srcdir) / "models"
    folder.mkdir(exist_ok=True)
    for name, text in type_pages().items():
        _write(folder / name, text)


def setup(app):
    app.connect("builder-inited", _write_model_reference)
