"""The documentation site builds with no warning: Sphinx with the markdown pages (myst),
the API reference from the docstrings (autosummary, napoleon) and the command-line
reference from click (sphinx-click); broken internal references are warnings too."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

DOCS = Path(__file__).parents[1] / "docs"


@pytest.mark.heavy
def test_docs_build_without_warnings(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    pytest.importorskip("sphinx_click")
    src = tmp_path / "docs"
    shutil.copytree(DOCS, src, ignore=shutil.ignore_patterns("_build", "api"))
    shutil.copytree(DOCS.parent / "examples", tmp_path / "examples")  # literalinclude
    res = subprocess.run(
        [sys.executable, "-m", "sphinx", "-q", "-W", "--keep-going", "-b", "html", str(src)]
        + [str(tmp_path / "html")],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, res.stderr[-3000:]
    assert res.stderr.strip() == "", res.stderr[-3000:]
    html = tmp_path / "html"
    cli = (html / "cli_reference.html").read_text()
    assert cli.count("stabctl simulate") > 0
    assert "\u2013" not in cli and "--fault" in cli  # options as typed, no en dashes
    assert (html / "api" / "stabctl.critical_clearing_time.html").exists()
    assert "critical_clearing_time" in (html / "examples.html").read_text()
    assert "exc_con" in (html / "models_reference.html").read_text()  # from the declarations
    # one page per model type, from its module: its states and its DYR record's columns
    tgov1 = (html / "models" / "tg_con_2_tgov1.html").read_text()
    assert "valve" in tgov1 and "VMAX" in tgov1 and "Tmax" in tgov1
    assert "PSS2A" in (html / "models" / "index.html").read_text()
