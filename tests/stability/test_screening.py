"""Contingency screening: CCT of a fault at every bus, resumable, with a map."""

import dataclasses
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
    # a robust fault is a verdict (its own status), told apart from a failed search
    assert by_bus[101]["status"] == "verdict" and "above the search limit" in by_bus[101]["reason"]
    assert by_bus[3]["verdict"] == "cct" and by_bus[101]["verdict"] == "above t_max"
    assert by_bus[101]["t_max_s"] == 0.4 and "error" not in by_bus[101]
    assert (tmp_path / "m.png").stat().st_size > 10000
    assert [r["run_now"] for r in rows] == [True, True]
    # as after an interrupted screening: one record kept, the other search runs again
    out = tmp_path / "s.jsonl"
    out.write_text(out.read_text().splitlines(keepends=True)[0])
    again = ["screen", "kundur", "--buses", "3,101", "--t-max", "0.4", "--workers", "1"]
    text = CliRunner().invoke(main, [*again, "--out", str(out)]).stdout
    assert ">0.400" in text and "robust: stable when cleared there" in text
    assert (
        f"2 fault(s): 1 run now, 1 already in {out}; 1 CCT(s) found, 1 above the search "
        "limit (robust), 0 N-1 insecure (CCT 0), 0 failed" in text
    )
    rows = json.loads(CliRunner().invoke(main, [*again, "--out", str(out), "--json"]).stdout)
    assert [r["run_now"] for r in rows] == [False, False]


def test_a_screening_map_is_written_whole_or_not_at_all(tmp_path, monkeypatch):
    """Round 47: `screen --plot` wrote its figure in place: a reader saw the old map
    truncated to 0 bytes while it was drawn, an interrupt left a fragment, and a write
    cut by the file size limit left a truncated PNG with "error: File too large".  The
    map is written as every output is (`stabctl.parallel.atomic_write`): a write that
    fails leaves the old map as it was and names it."""
    from stabctl.plotting import figures

    args = ["screen", "kundur", "--buses", "3", "--t-max", "0.4", "--workers", "1"]
    args += ["--out", str(tmp_path / "s.jsonl"), "--plot", str(tmp_path / "m.png")]
    old = b"an old map"
    (tmp_path / "m.png").write_bytes(old)

    def cut(fig, path):  # a part written, then the file size limit (`ulimit -f`)
        with open(path, "wb") as f:
            f.write(b"\x89PNG part")
        raise OSError(27, "File too large")

    monkeypatch.setattr(figures, "save_figure", cut)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2 and f"{tmp_path / 'm.png'}" in res.stderr, res.output
    assert (tmp_path / "m.png").read_bytes() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.png", "s.jsonl"]


def test_a_screening_with_a_failed_search_exits_1_after_its_results(tmp_path):
    """Every search of a screening failed (Kundur at --step 0.0185 s: its exciters swing at
    the step's period, a numerical instability) and it exited 0, which a script checking
    the status took for a success.  Its results are printed, recorded and JSON as before,
    then exit status 1 with a line saying why; a screening whose searches all reach a
    verdict (robust, a CCT) exits 0 (above), and so does one with an N-1 insecure fault
    (`test_n1_insecure_is_a_verdict_not_a_failure`)."""
    out = tmp_path / "f.jsonl"
    args = ["screen", "kundur", "--buses", "3", "--step", "0.0185", "--workers", "1"]
    res = CliRunner().invoke(main, [*args, "--tol-ms", "20", "--out", str(out), "--json"])
    assert res.exit_code == 1, res.output
    (row,) = json.loads(res.stdout)
    assert row["verdict"] == "failed" and row["error"].startswith("NumericalInstabilityError")
    assert json.loads(out.read_text())["status"] == "failed"
    assert (
        f"\n1 search failed (listed above with the reasons, recorded in {out}; --retry-failed "
        "reruns them): exit status 1\n" in res.stderr
    )
    assert res.stderr.count("warning: step 0.0185 s is above the fastest time constant") == 1


def test_spectral_layout_is_finite_and_distinct():
    xy = spectral_layout(load_case("miniwecc"))
    assert xy.shape == (122, 2) and (abs(xy) < 1e6).all()
    assert len({tuple(p.round(9)) for p in xy}) > 100


#: Kundur's transformer 3-4 faulted at bus 3: its trip cuts load bus 4 from every
#: generator (976 MW shed) and area 1 then loses synchronism however fast the fault is
#: cleared (N-1 insecure; tests/dynamics/test_islands.py)
LOAD_TRANSFORMER = LineFault(3, 4)


def test_n1_insecure_is_a_verdict_not_a_failure(tmp_path):
    """A contingency unstable even when cleared at once is recorded by a sweep as the
    verdict "N-1 insecure" (status "verdict", CCT 0), never as failed: the sweep counts no
    failure, a rerun with retry_failed does not run it again, and `stabctl cct` exits 0
    with CCT 0 s."""
    from stabctl.parallel import run_sweep
    from stabctl.stability.cct import cct_jobs
    from stabctl.stability.screening import INSECURE, verdict

    out = tmp_path / "r.jsonl"
    jobs = cct_jobs("kundur", [LOAD_TRANSFORMER], search=SearchOptions(t_max=0.5))
    rep = run_sweep(jobs, out, workers=1)
    (rec,) = rep.records.values()
    assert rep.failed == 0 and rec["status"] == "verdict" and verdict(rec) == INSECURE
    assert "unstable even when cleared instantly" in rec["reason"]
    again = run_sweep(jobs, out, workers=1, retry_failed=True)
    assert (again.ran, again.skipped) == (0, 1)
    # a record of the older form (status failed with the exception's text) reads the same
    old = {"status": "failed", "error": "InputError: " + rec["reason"]}
    assert verdict(old) == INSECURE
    args = ["cct", "kundur", "--fault", 3, "--far-bus", 4]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    got = json.loads(res.stdout)
    assert (got["cct_s"], got["verdict"]) == (0.0, "N-1 insecure")
    # screen --json gives a verdict's simulations, as its record and cct --json do
    scr = ["screen", "kundur", "--buses", "3", "--t-max", "0.2", "--workers", "1", "--json"]
    (row,) = json.loads(CliRunner().invoke(main, [*scr, "--out", str(tmp_path / "s.jsonl")]).stdout)
    (rec,) = map(json.loads, (tmp_path / "s.jsonl").read_text().splitlines())
    assert row["verdict"] == "above t_max" and row["n_simulations"] == rec["n_simulations"] == 3


def test_a_contingency_that_islands_a_load_bus_names_it_in_its_verdict(tmp_path, capsys):
    """Kundur's 3-4 trip cuts load bus 4 from every generator (its 976 MW shed, as PSS/E
    does; tests/dynamics/test_islands.py): the search's verdict (N-1 insecure: area 1
    loses its load) names the islanded bus in the sweep record and the screening table,
    and the summary counts it; a contingency that islands nothing names none."""
    from stabctl.cli.format import print_screening
    from stabctl.parallel import run_sweep
    from stabctl.stability.cct import cct_jobs
    from stabctl.stability.screening import INSECURE, islanded_buses, verdict

    faults = [LineFault(3, 4), LineFault(3, 101)]
    rep = run_sweep(
        cct_jobs("kundur", faults, search=SearchOptions(t_max=0.5)), tmp_path / "r.jsonl", workers=1
    )
    trip, tie = rep.records.values()
    assert trip["status"] == "verdict" and verdict(trip) == INSECURE
    assert islanded_buses(trip) == [4]
    assert trip["islanded"][0]["load_shed_pu"] == [9.76, 1.0]
    assert islanded_buses(tie) == [] and tie["status"] == "ok"
    rows = [
        {"bus": 3, "far_bus": 4, "status": "verdict", "verdict": INSECURE, "islanded": [4]},
        {
            "bus": 3,
            "far_bus": 101,
            "status": "ok",
            "verdict": "cct",
            "islanded": [],
            "cct_s": 0.154,
            "cct_cycles": 9.24,
            "numerical_error_s": 0.0,
            "separated": [1, 2],
        },
    ]
    capsys.readouterr()
    print_screening(load_case("kundur"), rows)
    text = capsys.readouterr().out
    assert "bus 3 line to 4        islands bus(es) [4] (their load shed)" in text
    assert "1 N-1 insecure (CCT 0), 0 failed; 1 fault(s) island load bus(es) (1 in all;" in text


def rest_after_trip_stable(sim, machine, t_clear):
    """Independent check: a fault at the machine's bus cleared after t_clear s without
    loss of a line, the machine tripped then; whether the other machines stay within pi
    of their own COI (paper eq. 40, H * MVA weights, computed here) until 6 s."""
    import numpy as np

    from stabctl.dynamics.events import Fault, GeneratorTrip

    i = int(np.flatnonzero(sim.case.machines.number == machine)[0])
    t_cl = 1.0 + t_clear
    events = [Fault(bus=int(sim.case.machines.bus[i]), t=1.0, clear_near=t_cl)]
    res = sim.run([*events, GeneratorTrip(machine, t_cl)], 6.0)
    rest = [k for k in range(len(sim.case.machines)) if k != i]
    M, a = res.inertia[rest], res.angle[:, rest]
    return np.abs(a - (a @ M / M.sum())[:, None]).max() < np.pi


def kundur_line_screening(tmp_path) -> list[dict]:
    """Every branch fault of Kundur screened at 20 ms up to 0.5 s, in one process."""
    return screen(
        "kundur",
        tmp_path / "s.jsonl",
        buses=[],
        lines=True,
        search=SearchOptions(tol=0.02, t_max=0.5),
        runner=RunnerOptions(workers=1, progress=False),
    )


def test_a_screening_names_the_generators_its_line_faults_island(tmp_path, capsys):
    """`screen kundur --lines`: a fault on a generator's step-up transformer (1-10, 2-20,
    11-110, 12-120) islands that generator at its bus.  Each row names the machine and
    the island's bus, and its verdict is the rest's, as tripping the machine at the
    clearing instant gives: 1-10 a CCT (0.44 s at 20 ms), 2-20 and 11-110 N-1 insecure
    (the rest separates even without the fault), 12-120 robust up to 0.5 s.  The table
    names them and the summary counts the 8 line faults that island machines (those
    four, 10-20 and 110-120 with their generator, 3-20 and 13-120 splitting an area off)."""
    from stabctl.cli.format import print_screening
    from stabctl.stability.screening import ABOVE, INSECURE

    rows = kundur_line_screening(tmp_path)
    by_line = {(r["bus"], r["far_bus"]): r for r in rows}
    expected = {(1, 10): (1, "cct"), (2, 20): (2, INSECURE), (11, 110): (3, INSECURE)}
    expected[(12, 120)] = (4, ABOVE)
    sim = Simulator(load_case("kundur"))
    for line, (machine, verdict) in expected.items():
        r = by_line[line]  # the machine at the line's near end, its bus the island
        assert (r["islanded_machines"], r["islanded_machine_buses"]) == ([machine], [line[0]])
        assert r["verdict"] == verdict and r["islanded"] == []
    assert by_line[(1, 10)]["cct_s"] == 0.44 and by_line[(1, 10)]["separated"] == [2]
    assert rest_after_trip_stable(sim, 1, 0.44) and not rest_after_trip_stable(sim, 1, 0.46)
    assert not rest_after_trip_stable(sim, 2, 0.0) and not rest_after_trip_stable(sim, 3, 0.0)
    assert rest_after_trip_stable(sim, 4, 0.5)
    assert sum(bool(r["islanded_machines"]) for r in rows) == 8
    capsys.readouterr()
    print_screening(load_case("kundur"), rows)
    text = capsys.readouterr().out
    assert (
        "bus 1 line to 10       islands machine(s) G1 (bus 1) with bus(es) [1] (lost; the rest "
        "judged):" in text
    )
    assert "bus 12 line to 120     islands machine(s) G4 (bus 12) with bus(es) [12]" in text
    # faults and distinct buses and machines apart (round 42: rows were called machines)
    n_buses = len({b for r in rows for b in r["islanded"]})
    n_machines = len({m for r in rows for m in r["islanded_machines"]})
    assert n_machines == 4  # each of Kundur's machines by its step-up transformer's fault
    assert (
        f"2 fault(s) island load bus(es) ({n_buses} in all; their load shed, counted in the "
        f"verdicts above), 8 fault(s) island machine(s) ({n_machines} in all; lost; " in text
    )


def test_a_robust_split_whose_rest_ends_off_a_normal_operating_point_says_so(tmp_path, capsys):
    """Kundur's fault at bus 13 with line 13-120 tripped cuts area 2's machines off; the
    rest (G1, G2) stays in synchronism when cleared at the search's limit, 0.5 s, so the
    fault is robust, but it ends at 0.41 pu (bus 13), as does line 13-14's trip (bus 14's
    1765 MW shed: area 2 at 62 Hz).  The screening's row and record say where each ends,
    and the lowest bus voltage is the one a run recording every bus's voltage ends with
    (the search's runs record none); a fault ending normally (3-101) says nothing."""
    from stabctl.cli.format import print_screening
    from stabctl.dynamics.results import END_VOLTAGE_PU
    from stabctl.stability.screening import ABOVE

    rows = kundur_line_screening(tmp_path)
    by_line = {(r["bus"], r["far_bus"], r["circuit"]): r for r in rows}
    split, shed, tie = by_line[(13, 120, 1)], by_line[(13, 14, 1)], by_line[(3, 101, 1)]
    assert split["verdict"] == shed["verdict"] == ABOVE and tie["verdict"] == "cct"
    assert tie["end_concerns"] == [] and tie["end_t_s"] is None
    full = Simulator(load_case("kundur")).run(LineFault(13, 120).events(0.5), 6.0)
    end = full.end_state(60.0)
    assert end["lowest_voltage_pu"] < END_VOLTAGE_PU
    said = f"bus {end['lowest_voltage_bus']} at {end['lowest_voltage_pu']:.3f} pu"
    assert (split["end_concerns"], split["end_t_s"]) == ([said], 6.0)
    assert said == "bus 13 at 0.412 pu"
    assert shed["end_concerns"] == ["the machines it judges at 62.14 Hz"]
    records = [json.loads(line) for line in (tmp_path / "s.jsonl").read_text().splitlines()]
    assert sum(r.get("end_concerns") == [said] for r in records) == 1  # in its record too
    capsys.readouterr()
    print_screening(load_case("kundur"), rows)
    text = capsys.readouterr().out
    assert f"bus 13 line to 120     ends off a normal operating point: {said} at t = 6 s" in text
    assert "; 3 stable by the angle criterion ending off a normal operating point" in text


def test_two_cases_screened_in_one_directory_keep_their_own_records(tmp_path, monkeypatch):
    """Without --out, `screen` wrote screening.jsonl whatever the case: a second case's
    screening in the same directory was refused ("another case's records") and a first
    case's resumed from an example's file.  Each case now has its own default records
    file, screening_<CASE>.jsonl (a case file's name without .json)."""
    from stabctl.io.pst import write_case_json

    monkeypatch.chdir(tmp_path)
    case = load_case("kundur")
    write_case_json(dataclasses.replace(case, name="k2"), "k2.json")
    scr = ["--buses", "3", "--t-max", "0.2", "--workers", "1"]
    for name in ("kundur", "k2.json"):
        res = CliRunner().invoke(main, ["screen", name, *scr])
        assert res.exit_code == 0, res.output
    assert sorted(p.name for p in tmp_path.glob("*.jsonl")) == [
        "screening_k2.jsonl",
        "screening_kundur.jsonl",
    ]
    again = CliRunner().invoke(main, ["screen", "kundur", *scr])
    assert "0 run now, 1 already in screening_kundur.jsonl" in again.stdout


def test_a_bus_fault_has_no_circuit_in_cct_and_screen_json(tmp_path):
    """A bus fault opens no line: `cct --json` gave it circuit 1 where `screen --json`
    gives none (round 34); both give null, and its CCT is Kundur's bus 3 fault's."""
    res = CliRunner().invoke(main, ["cct", "kundur", "--fault", "3", "--json"])
    assert res.exit_code == 0, res.output
    got = json.loads(res.stdout)
    assert got["fault"]["far_bus"] is None and got["fault"]["circuit"] is None
    assert got["cct_s"] == 0.238  # the bus fault's, not line 3-101's 0.154 s
    scr = ["screen", "kundur", "--buses", "3", "--workers", "1", "--json"]
    (row,) = json.loads(CliRunner().invoke(main, [*scr, "--out", str(tmp_path / "s.jsonl")]).stdout)
    assert row["circuit"] is None and row["cct_s"] == got["cct_s"]


def test_screen_says_a_cct_not_converged_in_the_run_s_end(tmp_path, monkeypatch):
    """Round 41: `screen` gave Kundur's 1-10 CCT 0.440 s as `cct` did, with no word that
    run 5 s longer the run cleared there loses synchronism (its trip islands G1 and the
    rest drifts out of step), and has no --tf: the row says so and how to search again;
    `--json` rows carry `run_end_check` (and the stiff step, `cct`'s too)."""
    monkeypatch.chdir(tmp_path)
    args = ["screen", "kundur", "--buses", "1", "--lines", "--out", "s.jsonl"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    said = [line for line in res.stdout.splitlines() if "NOT CONVERGED" in line]
    assert any(line.startswith("bus 1 line to 10 ") for line in said), said
    assert all(line.endswith("with `stabctl cct` and a later --tf") for line in said)
    rows = json.loads(CliRunner().invoke(main, [*args, "--json"]).stdout)
    got = {(r["bus"], r["far_bus"]): r for r in rows}
    assert got[1, 10]["run_end_check"]["t_separation_s"] > 6
    assert all("stiff_step_s" in r for r in rows if r["status"] == "ok")
    # each row names the searches' settings, as the text's settings line (round 41: none)
    assert rows[0]["settings"] == {
        "tol_s": 0.001,
        "t_max_s": 0.5,  # screen's default search limit
        "step_s": 0.005,
        "conventions": "ieee",
        "q_limits": True,
    }


def test_sweep_cct_says_a_cct_not_converged_in_the_run_s_end(tmp_path, monkeypatch):
    """Round 41: `sweep-cct` gave 1-10's CCT as `cct` did without its run's-end check."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f.csv").write_text("bus,far_bus\n1,10\n3,101\n")
    args = ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "w.jsonl", "--t-max", "0.5"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    k = next(
        i
        for i, line in enumerate(lines)
        if line.startswith("kundur/1-10/t1/esd-none ") and " 0.440 " in line
    )
    assert "NOT CONVERGED IN THE RUN'S END: cleared at the CCT (0.440 s)" in lines[k + 1]
    assert sum("NOT CONVERGED" in line for line in lines) == 1  # 3-101: not in question
