"""The README's examples run and print what it shows: its Python block, and each command of
its one-minute start with the lines shown under it ("..." ends a shortened line)."""

import re
import shlex
from pathlib import Path

import pytest
from click.testing import CliRunner

from stabctl.cli import main

README = (Path(__file__).parents[1] / "README.md").read_text()


def _blocks(kind: str) -> list[str]:
    return re.findall(rf"```{kind}\n(.*?)```", README, flags=re.S)


def test_readme_is_short():
    """At most 8 KB: what stabctl is, install, a one-minute start, links into docs/."""
    assert len(README.encode()) <= 8192


def test_readme_python_example_runs(capsys):
    (code,) = _blocks("python")
    exec(compile(code, "README.md", "exec"), {})
    assert capsys.readouterr().out.strip() == "0.154"  # the comment beside the print


def _commands():
    (console,) = _blocks("console")
    out = []
    for chunk in console.split("$ ")[1:]:
        command, *shown = chunk.strip().splitlines()
        out.append((command, shown))
    return out


@pytest.mark.parametrize("command,shown", _commands(), ids=lambda c: str(c)[:40])
def test_readme_one_minute_start_prints_what_it_shows(command, shown):
    args = shlex.split(command)
    assert args[0] == "stabctl"
    res = CliRunner().invoke(main, args[1:])
    assert res.exit_code == 0, res.output
    for line in shown:
        text = line.split("...")[0].rstrip(" ,") if "..." in line else line
        if "wall" in text:  # timings vary
            text = text.split("wall")[0]
        assert text in res.stdout, (text, res.stdout)


def test_readme_links_point_at_existing_files():
    root = Path(__file__).parents[1]
    for target in re.findall(r"\]\(([^)#]+)\)", README):
        assert (root / target).exists(), target
