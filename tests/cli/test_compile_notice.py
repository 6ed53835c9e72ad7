"""The compile notice and `stabctl compile`'s parts, checked without compiling a kernel of
the package (each check takes well under a second).

A newcomer read the old notice, "compiling the simulator's kernels (once after
installation ...)", on `simulate`, again on `eig`, `estimate` and a converter case: each
of those compiles a kernel set of its own.  The notice now names the sets a command uses,
says each set compiles once and is then loaded from the on-disk cache, and points to
`stabctl compile`, which compiles every set."""

from types import SimpleNamespace

import click
import numba
from click.testing import CliRunner

import stabctl.cli as cli
from stabctl._jit.cache import cached
from stabctl.cli import compile_notice, main
from stabctl.cli.compile import _kernels, _warm_steps
from stabctl.io import load_case
from stabctl.models.converters import derivatives_at

SETS = {
    "simulate": ["the simulator"],
    "cct": ["the simulator"],
    "eig": ["the simulator's model", "the linearisation"],
    "estimate": ["the simulator", "the estimators"],
    "paper": ["the simulator", "the linearisation", "the estimators"],
}


def test_the_notice_names_the_kernel_sets_and_stabctl_compile_for_every_command():
    for command in sorted(cli._SIMULATING - {"compile"}):
        text = compile_notice(command)
        assert "once after installation" not in text, command
        assert "`stabctl compile` compiles every set at once" in text, command
        assert "each set compiles once" in text and "on-disk cache" in text, command
        assert len(text.splitlines()) <= 2, text
    for command, sets in SETS.items():
        first = compile_notice(command).splitlines()[0]
        assert all(s in first for s in sets), (command, first)
    assert "linearisation" not in compile_notice("simulate")
    # `stabctl compile` says it too, and every 10 s (it was silent for minutes on a cold
    # cache until its first part ended): its own words, every set
    assert "compile" in cli._SIMULATING
    assert compile_notice("compile").endswith(
        "a line as each part ends; minutes on an empty cache)"
    )
    assert "the simulator, the linearisation and the estimators" in compile_notice("compile")
    assert "estimators" not in compile_notice("eig")


def test_the_cli_prints_the_notice_when_a_stabctl_kernel_compiles(monkeypatch):
    """A command of the simulating set whose first stabctl kernel compiles prints
    `compile_notice` of that command on stderr (a command made for the test)."""

    def kernel(x):
        return x + 1

    kernel.__module__ = "stabctl.kernel_for_the_test"

    @click.command("probe-compile")
    def probe():
        numba.njit(kernel)(1)

    monkeypatch.setattr(cli, "_SIMULATING", {*cli._SIMULATING, "probe-compile"})
    main.add_command(probe)
    try:
        res = CliRunner().invoke(main, ["probe-compile"])
    finally:
        main.commands.pop("probe-compile")
    assert res.exit_code == 0, res.output
    assert compile_notice("probe-compile") in res.stderr


def test_stabctl_compile_warms_every_part_it_checks():
    """`stabctl compile`'s steps are its parts, in order (the simulator is built inside the
    model-evaluation step, so that its compile time is counted there; nothing is built
    or compiled here), among them `estimate`'s storage control and the converters'
    set-up, which a first `estimate` or converter case compiled after `stabctl compile`."""
    steps = [part for part, _ in _warm_steps(load_case("kundur"))]
    assert steps == list(_kernels())
    assert {"storage control", "converter set-up"} <= set(steps)


def test_a_kernel_of_a_package_init_is_found_in_the_cache(tmp_path):
    """numba names the cache entry of a kernel declared in a package's ``__init__.py``
    after that file (``__init__.<name>-<line>...nbi``), not after the package;
    `stabctl compile --check` said 'not cached' of such a kernel in a warm cache."""
    stand_in = SimpleNamespace(
        py_func=derivatives_at.py_func, stats=SimpleNamespace(cache_path=str(tmp_path))
    )
    assert not cached(stand_in)
    _entry(tmp_path, "converters.derivatives_at-609.py311")  # the old, wrong name
    assert not cached(stand_in)
    _entry(tmp_path, "__init__.derivatives_at-609.py311")
    assert cached(stand_in)


def _entry(where, name: str, index: bytes | None = None, data: bytes | None = None) -> None:
    """A cache entry as numba writes it: the index (numba's version, then the source
    stamp and overloads, two pickles) and a data file (one pickle); or the bytes given."""
    import pickle

    whole = pickle.dumps("0.60.0") + pickle.dumps((1.0, {}))
    (where / f"{name}.nbi").write_bytes(whole if index is None else index)
    (where / f"{name}.1.nbc").write_bytes(pickle.dumps(b"code") if data is None else data)


def test_a_damaged_cache_entry_is_not_called_cached(tmp_path):
    """A cache whose files were emptied, cut or garbled was called warm by `compile
    --check` (only the index file's name was looked at), and the next command then
    compiled for two minutes without the notice.  An entry is cached only if its index
    and a data file are whole pickles, read as opcodes, nothing unpickled."""
    import pickle

    stand_in = SimpleNamespace(
        py_func=derivatives_at.py_func, stats=SimpleNamespace(cache_path=str(tmp_path))
    )
    name = "__init__.derivatives_at-609.py311"
    whole = pickle.dumps("0.60.0") + pickle.dumps((1.0, {}))
    for index, data in (
        (b"", None),  # an emptied index
        (whole[:-5], None),  # cut
        (b"\x00garbage" * 8, None),  # not pickle opcodes
        (whole + b"more", None),  # something after the two pickles
        (None, b""),  # an emptied data file
        (None, pickle.dumps(b"code")[:-3]),  # a cut data file
    ):
        for f in tmp_path.iterdir():
            f.unlink()
        _entry(tmp_path, name, index, data)
        assert not cached(stand_in), (index, data)
    (tmp_path / f"{name}.1.nbc").unlink()  # no data file at all
    assert not cached(stand_in)
    _entry(tmp_path, name)
    assert cached(stand_in)
