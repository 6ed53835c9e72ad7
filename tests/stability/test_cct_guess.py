"""A CCT search started from a guessed clearing time (`SearchOptions.guess_s`): the same
verdict, 1 ms cell and half-step CCT as the search without it (the reference: the same
search from its own bracket) wherever the verdict is monotone, whatever the guess; and
the screening's use of it, each branch fault started from its bus fault's CCT."""

import json

import pytest

from stabctl.errors import InputError
from stabctl.parallel import RunnerOptions
from stabctl.stability.cct import (
    LineFault,
    SearchOptions,
    compared_inputs,
    critical_clearing_time,
)
from stabctl.stability.screening import ABOVE, INSECURE, screen, screening_faults


def outcome(sim, fault: LineFault, options: SearchOptions):
    """(verdict name or (bracket, half-step CCT), simulations at h or None)."""
    try:
        res = critical_clearing_time(sim, fault, options)
    except InputError as exc:  # N-1 insecure, above t_max
        return type(exc).__name__, None
    return (res.bracket, res.cct_half_step_s), len(res.probes)


@pytest.mark.parametrize("method", ["sime", "bisection"])
def test_every_line_fault_of_kundur_guessed_from_its_bus_fault_ends_in_the_same_cell(
    kundur, method
):
    """Kundur's line trips move the CCT far from the bus fault's (bus 3: 0.238 s, line
    3-101: 0.154 s), so the guesses are poor there: the cells must not depend on them."""
    faults = screening_faults(kundur.case, lines=True)
    bus_cct = {}
    for f in faults:
        if f.far_bus is None:
            ref, _ = outcome(kundur, f, SearchOptions(method=method))
            bus_cct[f.bus] = ref[0][0] if not isinstance(ref, str) else None
    guessed = 0
    for f in faults:
        if f.far_bus is None or bus_cct[f.bus] is None:
            continue
        ref, _ = outcome(kundur, f, SearchOptions(method=method))
        res, _ = outcome(kundur, f, SearchOptions(method=method, guess_s=bus_cct[f.bus]))
        assert res == ref, f
        guessed += 1
    assert guessed >= 6


@pytest.mark.parametrize("method", ["sime", "bisection"])
@pytest.mark.parametrize(("bus", "far_bus"), [(3, 101), (13, 101), (1, None), (3, 4)])
@pytest.mark.parametrize("guess", [0.0, 0.001, 0.154, 0.3, 0.999, 1.0, 2.5])
def test_any_guess_ends_in_the_cell_or_verdict_of_the_search_without_it(
    kundur, method, bus, far_bus, guess
):
    """Guesses at 0, at the range's ends, beyond it and inside it, on faults with a CCT
    (3-101: 0.154 s, 13-101, bus 1) and one N-1 insecure (3-4, whose verdict is not
    monotone: stable cleared at 30-67 ms)."""
    fault = LineFault(bus, far_bus)
    ref, _ = outcome(kundur, fault, SearchOptions(method=method))
    res, _ = outcome(kundur, fault, SearchOptions(method=method, guess_s=guess))
    assert res == ref


def test_a_guess_in_the_cct_s_cell_closes_it_in_two_runs(kundur):
    """Line 3-101's CCT is 0.154 s (the paper's Case 1): guessed there, the search runs
    0.154 s (stable) and 0.155 s (unstable) and nothing else at the step."""
    res = critical_clearing_time(
        kundur, LineFault(3, 101), SearchOptions(method="sime", guess_s=0.154)
    )
    assert res.probes == ((0.154, True), (0.155, False))
    assert res.cct_s == 0.154


@pytest.mark.parametrize("guess", [-0.1, float("nan"), float("inf")])
def test_a_guess_that_is_no_clearing_time_is_refused(kundur, guess):
    with pytest.raises(InputError, match="guess_s"):
        critical_clearing_time(kundur, LineFault(3, 101), SearchOptions(guess_s=guess))


def test_a_guess_is_recorded_but_not_compared_on_resume():
    opts = SearchOptions(guess_s=0.2)
    inputs = opts.to_inputs()
    assert inputs["guess_s"] == 0.2 and SearchOptions.from_inputs(inputs).guess_s == 0.2
    assert "guess_s" not in SearchOptions().to_inputs()
    assert compared_inputs({**inputs, "t_fault": 1.0}) == compared_inputs(
        {**SearchOptions().to_inputs(), "t_fault": 1.0}
    )


def test_a_screening_starts_each_branch_fault_from_its_bus_fault_s_cct(kundur, tmp_path):
    """Kundur's bus faults 3 and 1 with every branch: the branch faults at 3 are searched
    from their bus fault's CCT (recorded as guess_s), the others without, among them 1-10,
    machine 1's only branch, and 3-20, area 1's only way to bus 3 (their trips cut
    machines off: the bus faults kept them); every row is the search's without a guess; a
    rerun runs nothing again."""
    out = tmp_path / "s.jsonl"
    opts = SearchOptions(method="sime")
    runner = RunnerOptions(workers=1, progress=False)
    rows = screen("kundur", out, buses=[3, 1], lines=True, search=opts, runner=runner)
    records = {json.loads(line)["key"]: json.loads(line) for line in out.read_text().splitlines()}
    bus_cct = {r["bus"]: r.get("cct_s") for r in rows if r["far_bus"] is None}
    assert bus_cct[3] == 0.238 and bus_cct[1] is not None
    label = {"AboveSearchLimit": ABOVE, "InsecureContingency": INSECURE}
    faults = screening_faults(kundur.case, [3, 1], lines=True)
    assert sum(f.bus == 3 for f in faults[2:]) >= 3 and (1, 10) in [
        (f.bus, f.far_bus) for f in faults
    ]
    for fault, row in zip(faults, rows, strict=True):
        guess = records[row["key"]]["inputs"].get("guess_s")
        guessed = fault.far_bus is not None and fault.bus == 3 and fault.far_bus != 20
        assert guess == (bus_cct[fault.bus] if guessed else None), row["key"]
        ref, _ = outcome(kundur, fault, opts)
        want = label[ref] if isinstance(ref, str) else ref[0][0]
        assert (row["verdict"] if isinstance(ref, str) else row["cct_s"]) == want, row["key"]
    n = len(out.read_text().splitlines())
    again = screen("kundur", out, buses=[3, 1], lines=True, search=opts, runner=runner)
    assert len(out.read_text().splitlines()) == n and not any(r["run_now"] for r in again)


def test_cli_screen_without_guesses_and_with_each_circuit_named(tmp_path):
    """`stabctl screen --lines --no-guess` searches every branch fault from scratch (no
    ``guess_s`` recorded); rows of parallel circuits name their circuit (`#2`), in the
    table and in --json."""
    from click.testing import CliRunner

    from stabctl.cli import main

    out = tmp_path / "s.jsonl"
    args = ["screen", "kundur", "--buses", "3", "--lines", "--workers", "1", "--out", str(out)]
    res = CliRunner().invoke(main, [*args, "--no-guess", "--json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert not any("guess_s" in r["inputs"] for r in records)
    assert {r["circuit"] for r in rows if (r["bus"], r["far_bus"]) == (3, 101)} == {1, 2}
    assert all(r["circuit"] is None for r in rows if r["far_bus"] is None)
    table = CliRunner().invoke(main, args)  # read back: nothing run again
    assert table.exit_code == 0 and "0 run now" in table.output
    assert "bus 3 line to 101 #2" in table.output and "bus 3 line to 101 " in table.output


@pytest.mark.parametrize("flag", ["--guess", "--no-guess"])
def test_cli_screen_refuses_a_guess_setting_without_branch_faults(tmp_path, flag):
    """`stabctl screen` without --lines has no branch fault to start from a guess: either
    form of the flag is refused by name (it ran, the flag dropped), nothing written."""
    from click.testing import CliRunner

    from stabctl.cli import main

    out = tmp_path / "s.jsonl"
    res = CliRunner().invoke(main, ["screen", "kundur", "--buses", "3", flag, "--out", str(out)])
    assert res.exit_code == 2
    assert (
        res.output
        == f"error: {flag} given without --lines (only branch faults start from a guess)\n"
    )
    assert not out.exists()
