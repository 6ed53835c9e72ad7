"""Every Python block of the docs pages runs, in page order in one namespace per page, and
prints what its comments say: `print(x)  # 0.154` must print 0.154 ("..." ends a shortened
value).  Blocks that are outlines, not programs, are marked `text`, not `python`."""

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).parents[1] / "docs"
PAGES = sorted(p for p in DOCS.glob("*.md") if "```python" in p.read_text())


def _expected_prints(code: str) -> list[str]:
    """The values the block's print lines promise, in order."""
    return [
        m[1].split("...")[0].strip()
        for m in re.finditer(r"^\s*print\(.*\)\s*#\s*(.+)$", code, flags=re.M)
    ]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_docs_python_blocks_run_and_print_what_they_say(page, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # blocks may write files (a screening's records)
    namespace: dict = {}
    for k, code in enumerate(re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)):
        exec(compile(code, f"{page.name} block {k + 1}", "exec"), namespace)
        printed = capsys.readouterr().out.splitlines()
        expected = _expected_prints(code)
        assert len(printed) == len(expected), (page.name, k + 1, printed)
        for line, want in zip(printed, expected):
            assert line.startswith(want), (page.name, k + 1, line, want)


def test_the_pages_with_python_are_found():
    assert {p.name for p in PAGES} >= {"library.md", "modal.md"}
