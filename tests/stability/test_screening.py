"""Contingency screening: CCT of a fault at every bus, resumable, with a map."""

import json

from click.testing import CliRunner

from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.io import load_case
from stabctl.parallel import RunnerOptions
from stabctl.plotting.layout import spectral_layout
from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time
from stabctl.stability.screening import screen, screening_faults


def test_screening_faults_cover_every_bus_and_every_circuit():
    case = load_case("kundur")
    faults = screening_faults(case, lines=True)
    assert [f.bus for f in faults[: case.n_bus]] == list(case.buses.number)
    assert all(f.far_bus is None for f in faults[: case.n_bus])
    lines = faults[case.n_bus :]
    assert len(lines) == len(case.branches)
    assert sorted(f.circuit for f in lines if (f.bus, f.far_bus) == (3, 101)) == [1, 2]


def test_screening_rows_match_single_searches_and_resume(tmp_path):
    out = tmp_path / "s.jsonl"
    rows = screen(
        "kundur",
        out,
        buses=[3, 12],
        search=SearchOptions(t_max=0.5),
        runner=RunnerOptions(workers=1, progress=False),
    )
    sim = Simulator(load_case("kundur"))
    for row in rows:
        ref = critical_clearing_time(sim, LineFault(row["bus"], None), SearchOptions(t_max=0.5))
        assert row["status"] == "ok" and row["cct_s"] == ref.cct_s
    n = len(out.read_text().splitlines())
    screen(
        "kundur",
        out,
        buses=[3, 12],
        search=SearchOptions(t_max=0.5),
        runner=RunnerOptions(workers=1, progress=False),
    )
    assert len(out.read_text().splitlines()) == n  # resumed: nothing rerun


def test_cli_screen_writes_map_and_reports_failures(tmp_path):
    res = CliRunner().invoke(
        main,
        [
            "screen",
            "kundur",
            "--buses",
            "3,101",
            "--t-max",
            "0.4",
            "--workers",
            "1",
            "--out",
            str(tmp_path / "s.jsonl"),
            "--plot",
            str(tmp_path / "m.png"),
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    by_bus = {r["bus"]: r for r in rows}
    assert by_bus[3]["status"] == "ok" and by_bus[3]["separated"] == [1, 2]
    assert by_bus[101]["status"] == "failed" and "above the search limit" in by_bus[101]["error"]
    # a robust fault is a verdict, told apart from a failed search
    assert by_bus[3]["verdict"] == "cct" and by_bus[101]["verdict"] == "above t_max"
    assert by_bus[101]["t_max_s"] == 0.4 and by_bus[101]["error"].startswith("AboveSearchLimit")
    assert (tmp_path / "m.png").stat().st_size > 10000
    again = ["screen", "kundur", "--buses", "3,101", "--t-max", "0.4", "--workers", "1"]
    text = CliRunner().invoke(main, [*again, "--out", str(tmp_path / "s.jsonl")]).stdout
    assert ">0.400" in text and "robust: stable when cleared there" in text
    assert "2 fault(s): 1 CCT(s) found, 1 above the search limit (robust), 0 failed" in text


def test_spectral_layout_is_finite_and_distinct():
    xy = spectral_layout(load_case("miniwecc"))
    assert xy.shape == (122, 2) and (abs(xy) < 1e6).all()
    assert len({tuple(p.round(9)) for p in xy}) > 100
