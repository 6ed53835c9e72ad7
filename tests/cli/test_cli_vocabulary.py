"""One vocabulary on the command line: an option name means one thing everywhere.

Introspects the click commands (subcommands of `estimate` included): every option whose
name appears on more than one command has the same type, default, flag-ness, unit (the
first parenthesised unit of its help) and metavar, except for the differences listed (and justified)
in DIFFERENCES; --scheduler comes wherever --workers does; the deprecated aliases still
work and are hidden.
"""

import re
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from stabctl.cli import main

UNIT = re.compile(r"\((s|ms|Hz|Hz/s|pu|rad|MW|cycles|frames/s|%[^);]*)[;)]")

#: (command, option) -> why its signature may differ from the other commands'
DIFFERENCES = {
    ("screen", "--t-max"): "bus faults cleared without loss of a line: CCTs above 0.5 s "
    "are recorded as robust, not searched",
    ("cct", "--coi"): "critical too: only cct finds the fault's critical machines",
    ("place", "--coi"): "critical too: the law armed per contingency, each contingency's "
    "critical machines found by the workers",
    ("sweep-cct", "--esd-pct"): "a list of ratings (repeatable, comma-separated, 'none')",
    ("import-andes", "--dyr-conventions"): "an ANDES case is read as ANDES solves it (a "
    "RAW + DYR pair as PSS/E states it, as import-psse) unless told otherwise",
    ("estimate track", "--frames"): "optional there: one of the two ends a TCP source needs "
    "(--until or --frames); pmu record's only end",
}
#: options whose default and metavar are each command's own (an output file's name and kind)
OWN_DEFAULT = {"--out"}


def _commands(group=main, prefix=()):
    for name, cmd in sorted(group.commands.items()):
        if isinstance(cmd, click.Group):
            yield from _commands(cmd, prefix + (name,))
        else:
            yield " ".join(prefix + (name,)), cmd


def _options(cmd):
    return {p.opts[0]: p for p in cmd.params if isinstance(p, click.Option)}


def _signature(name, p) -> dict:
    t = p.type
    kind = type(t).__name__
    if isinstance(t, click.Choice):
        kind += repr(sorted(t.choices))
    elif isinstance(t, click.Path):
        kind += f"(file_okay={t.file_okay}, dir_okay={t.dir_okay})"
    elif isinstance(t, click.Tuple):
        kind += repr([type(x).__name__ for x in t.types])
    m = UNIT.search(p.help or "")
    sig = {
        "type": kind,
        "multiple": p.multiple,
        "flag": p.is_flag,
        # a required option has no default (declared without one: click >= 8.3 does not
        # enforce required=True beside default=None), as one left out means none
        "default": None if p.required else p.default,
        "unit": m and m.group(1),
        # the name of its value in --help (``--seed S``): one name for one value
        "metavar": None if p.is_flag else p.make_metavar(click.Context(click.Command(name))),
    }
    if name in OWN_DEFAULT:
        del sig["default"], sig["metavar"]
    return sig


COMMANDS = dict(_commands())


def test_every_command_is_introspected():
    assert {
        "simulate",
        "cct",
        "sweep-cct",
        "screen",
        "place",
        "eig",
        "paper",
        "omib",
        "cases",
        "import-psse",
        "import-andes",
        "estimate rmse",
        "estimate closed-loop",
        "estimate cct",
    } <= set(COMMANDS)


def test_an_option_name_has_one_type_default_and_unit():
    seen = {}
    for cname, cmd in COMMANDS.items():
        for oname, p in _options(cmd).items():
            if (cname, oname) not in DIFFERENCES:
                seen.setdefault(oname, {})[cname] = _signature(oname, p)
    clashes = []
    for oname, by_cmd in seen.items():
        first_cmd, first = next(iter(by_cmd.items()))
        clashes += [
            f"{oname}: {cname} {sig} != {first_cmd} {first}"
            for cname, sig in by_cmd.items()
            if sig != first
        ]
    assert not clashes, "\n".join(clashes)


def test_numeric_options_state_their_unit_the_same_way_everywhere():
    # every float option with a unit in one command has it in all (checked above); and
    # the ones the vocabulary is about have one at all
    for cname, cmd in COMMANDS.items():
        for oname, p in _options(cmd).items():
            if oname in (
                "--tf",
                "--t-fault",
                "--step",
                "--t-max",
                "--tol-ms",
                "--deadband-hz",
                "--hysteresis-hz",
                "--v-gate",
                "--esd-pct",
                "--clear-cycles",
            ):
                assert UNIT.search(p.help or ""), (cname, oname, p.help)


def test_scheduler_wherever_workers():
    for cname, cmd in COMMANDS.items():
        names = set(_options(cmd))
        assert ("--workers" in names) == ("--scheduler" in names), cname


def test_tf_states_one_rule():
    for cname, cmd in COMMANDS.items():
        tf = _options(cmd).get("--tf")
        if tf is not None:
            assert tf.default is None and "default: the fault start + 5 s" in tf.help, cname


def test_out_is_a_file_out_dir_a_directory():
    for cname, cmd in COMMANDS.items():
        opts = _options(cmd)
        if "--out" in opts:
            assert not opts["--out"].type.dir_okay, cname
            assert opts["--out"].help.startswith("Output file"), cname
        if "--out-dir" in opts:
            assert opts["--out-dir"].metavar == "DIR", cname
            assert opts["--out-dir"].help.startswith("Output directory"), cname


@pytest.mark.parametrize(
    "command,alias",
    [
        ("place", "--contingencies"),
        ("eig", "--out"),
        ("paper", "--out"),
        ("import-psse", "--conventions"),
        ("import-andes", "--conventions"),
    ],
)
def test_deprecated_aliases_are_hidden_but_accepted(command, alias):
    res = CliRunner().invoke(main, [command, "--help"])
    assert res.exit_code == 0 and f"{alias} " not in res.output.replace("--out-dir", "")
    assert any(alias in p.opts for p in COMMANDS[command].params)


def test_old_estimate_form_goes_to_the_subcommands():
    for args, doc in (
        (["kundur", "--fault", "3"], "Errors of the speed estimators"),
        (["kundur", "--closed-loop", "--fault", "3"], "commanded by each"),
        (["kundur", "--fault", "3", "--cct"], "CCT of the fault line"),
    ):
        res = CliRunner().invoke(main, ["estimate", *args, "--help"])
        assert res.exit_code == 0 and doc in res.output, res.output


def test_examples_in_help_keep_their_lines():
    """An example block (click's ``\\b``) right after a paragraph was rewrapped into it
    ("...exit status 2).  Example:   stabctl estimate track miniwecc --source ..."): every
    example line is a line of its own in ``--help``."""
    for name, _ in _commands():
        out = CliRunner().invoke(main, [*name.split(), "--help"]).output
        for line in out.splitlines():
            assert not re.search(r"\S\s+Examples?:", line), (name, line)
            assert not re.search(r"Examples?:\s+\S", line), (name, line)


def test_examples_in_help_name_only_options_of_their_command():
    """`stabctl omib --help` showed ``stabctl omib --clear-s 0.2``: no such option.  Every
    option an example line of a command's help gives is one of that command's."""
    for name, cmd in _commands():
        known = {o for p in cmd.params for o in (*p.opts, *p.secondary_opts)} | {"--help"}
        out = CliRunner().invoke(main, [*name.split(), "--help"]).output
        for line in out.splitlines():
            words = line.split()
            if words[: 1 + len(name.split())] != ["stabctl", *name.split()]:
                continue
            given = {w.split("=")[0] for w in words if w.startswith("-") and w[1:2].isalpha()}
            given |= {w for w in words if w.startswith("--") and len(w) > 2}
            assert given <= known, (name, line, sorted(given - known))


def test_coi_offers_critical_only_where_it_is_taken():
    """`simulate`, `estimate *` and `pmu plant/control` offered --coi critical and then
    refused it ("cct only"): only `cct` and `place`, which find the critical machines
    (`place` per contingency), list it; elsewhere it is click's invalid choice (exit 2)."""
    choices = {
        c: _options(cmd)["--coi"].type.choices
        for c, cmd in COMMANDS.items()
        if "--coi" in _options(cmd)
    }
    assert {"simulate", "estimate rmse", "pmu plant", "pmu control", "place"} <= set(choices)
    assert {c for c, offered in choices.items() if "critical" in offered} == {"cct", "place"}
    assert "[system|rest|critical]" in CliRunner().invoke(main, ["cct", "--help"]).output
    help_ = CliRunner().invoke(main, ["simulate", "--help"]).output
    assert "[system|rest]" in help_ and "critical" not in help_.split("--coi")[1].split("--")[0]
    args = ["simulate", "kundur", "--fault", "3", "--esd-pct", "5", "--coi", "critical"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2 and "Invalid value for '--coi'" in res.output, res.output


def test_t_max_of_every_cct_search_is_a_verdict_not_an_error():
    """`cct`, `sweep-cct` and `place` said "a CCT above it is an error" of --t-max, where a
    fault still stable there is a verdict (robust, exit 0), as `screen` said."""
    with_t_max = {
        c: _options(cmd)["--t-max"].help
        for c, cmd in COMMANDS.items()
        if "--t-max" in _options(cmd)
    }
    assert {"cct", "sweep-cct", "screen", "place"} <= set(with_t_max)
    for cname, text in with_t_max.items():
        assert "a fault still stable there is a verdict: CCT above it, robust" in text, cname
        assert "error" not in text, cname


def test_help_keeps_acronyms_capitalised():
    """The --out help of `sweep-cct` and `screen` read "Output file: jSON lines" (the first
    letter of the text lowered after the colon)."""
    for name, _ in _commands():
        out = CliRunner().invoke(main, [*name.split(), "--help"]).output
        assert not re.search(r"Output (file|directory): [a-z][A-Z]", out), (name, out)
    for name in ("sweep-cct", "screen"):
        assert "Output file: JSON lines" in CliRunner().invoke(main, [name, "--help"]).output


def test_docs_synopses_show_the_defaults():
    """A number after an option in a synopsis of docs/cli.md's command table (``[--speed
    1]``) is that option's default in --help, as the synopses write it: a value shown
    there that is not the default reads as one."""
    text = (Path(__file__).parents[2] / "docs" / "cli.md").read_text()
    rows = [line for line in text.splitlines() if line.startswith("| `stabctl ")]
    assert rows
    wrong, checked = [], 0
    for row in rows:
        for span in re.findall(r"`(stabctl [^`]+)`", row.split("` |")[0] + "`"):
            words = span.split()
            cname = next(
                (" ".join(words[1:n]) for n in (3, 2) if " ".join(words[1:n]) in COMMANDS), None
            )
            if cname is None:
                continue
            opts = _options(COMMANDS[cname])
            for oname, value in re.findall(r"(--[a-z-]+) (-?[0-9][0-9.]*)(?=[ \]])", span):
                p = opts.get(oname)
                if p is None or not isinstance(p.default, (int, float)) or p.is_flag:
                    continue
                checked += 1
                if float(value) != float(p.default):
                    wrong.append(f"{cname} {oname}: {value} in docs/cli.md, {p.default} in --help")
    assert checked > 20 and not wrong, "\n".join(wrong)


def test_every_command_that_runs_the_case_takes_its_power_flow_without_q_limits():
    """A case that converges only with the PV buses' Q limits off (ANDES's converter
    cases) is refused with a hint to give --no-q-limits: every command that simulates the
    case (its --step) takes it, as do eig and pmu serve (their runs at the case's own
    step); place, estimate and pmu plant did not."""
    runs = {c for c, cmd in COMMANDS.items() if "--step" in _options(cmd)}
    runs |= {"eig", "pmu serve"}
    assert {"place", "estimate rmse", "estimate closed-loop", "estimate cct", "pmu plant"} <= runs
    assert [c for c in sorted(runs) if "--q-limits" not in _options(COMMANDS[c])] == []
