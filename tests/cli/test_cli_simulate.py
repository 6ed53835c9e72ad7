"""The `cases` and `simulate` commands: JSON summaries, output files, PSTess agreement through
the CLI, and bad input (exit status 2, one `error:` line, no file written)."""

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.dynamics.results import SimulationResult
from stabctl.io import load_case
from stabctl.io import pst as pstio

DATA = Path(__file__).parents[1] / "data" / "pstess"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def assert_bad_input(res, directory: Path, *needles):
    """Exit 2, exactly one line on stderr starting with 'error:' (besides the notice of a
    first compile, which a cold kernel cache prints: the tests run in parallel, so any of
    them may be the first to need the kernels), nothing written."""
    assert res.exit_code == 2, res.output
    lines = [x for x in res.stderr.strip().splitlines() if not x.startswith("stabctl: ")]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    for n in needles:
        assert n in lines[0], (n, lines[0])
    assert res.stdout == ""
    assert list(directory.iterdir()) == [], list(directory.iterdir())


# ----------------------------------------------------------------------------- cases


def test_cases_json_lists_builtins_with_counts():
    res = run("cases", "--json")
    assert res.exit_code == 0, res.output
    rows = {r["name"]: r for r in json.loads(res.stdout)}
    assert set(rows) == {"kundur", "miniwecc"}
    k, w = rows["kundur"], rows["miniwecc"]
    assert (k["buses"], k["branches"], k["machines"]) == (13, 14, 4)
    assert (w["buses"], w["branches"], w["machines"], w["governors"]) == (122, 171, 34, 21)
    assert "Kundur" in k["description"] and k["freq_hz"] == 60.0
    assert "bus 3" in k["sw_con"] and "3-101" in k["sw_con"]


def test_python_dash_m_stabctl_is_the_command():
    """`python -m stabctl` runs the `stabctl` command, as `python -m stabctl.cli` does."""
    import subprocess
    import sys

    out = [
        subprocess.run([sys.executable, "-m", m, "cases", "--json"], capture_output=True, text=True)
        for m in ("stabctl", "stabctl.cli")
    ]
    assert [r.returncode for r in out] == [0, 0], [r.stderr for r in out]
    assert json.loads(out[0].stdout) == json.loads(out[1].stdout)
    assert {r["name"] for r in json.loads(out[0].stdout)} == {"kundur", "miniwecc"}


def test_cases_text():
    res = run("cases")
    assert res.exit_code == 0
    assert "kundur: 13 buses, 14 branches, 4 machines, 4 exciters, 4 PSS, 4 governors" in res.stdout
    assert "miniwecc: 122 buses, 171 branches, 34 machines" in res.stdout
    assert "66 non-conforming load buses" in res.stdout  # all its help promises


def test_cases_text_of_a_case_without_description_has_no_blank_line(psse_omib):
    """An imported PSS/E case has no description: its summary line stands alone (it was
    followed by a line of four blanks)."""
    res = run("cases", psse_omib)
    assert res.exit_code == 0
    lines = res.stdout.splitlines()
    assert len(lines) == 1 and lines[0].endswith("100 MVA base, 60 Hz"), lines


def test_cases_lists_one_cases_buses_and_lines_to_choose_a_fault():
    """`cases CASE --bus-table --line-table`: the numbers --fault, --far-bus and --circuit take,
    from the data file (Kundur's line 3-101 has two circuits)."""
    res = run("cases", "kundur", "--bus-table", "--line-table", "--json")
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["name"] == "kundur" and len(d["buses"]) == 13 and len(d["lines"]) == 14
    bus1 = d["buses"][0]
    assert (bus1["bus"], bus1["type"], bus1["kV"], bus1["machines"]) == (1, "swing", 22.0, "G1")
    # the data's voltage, named so: a PV or swing bus's set point (d2asbegp: 1.01 pu at
    # bus 1), not what the power flow solves where a Q limit binds
    assert (bus1["V_data_pu"], bus1["angle_data_deg"]) == (1.01, 18.5)
    # MW and Mvar on PSTess's 100 MVA base: bus 4's load 976 MW + 100 Mvar, bus 3's shunt
    # capacitor 300 Mvar (d2asbegp's bus matrix, 9.76 + j1.0 and b 3.0 pu)
    bus3, bus4 = d["buses"][2], d["buses"][3]
    assert (bus4["bus"], bus4["P_load_MW"], bus4["Q_load_Mvar"]) == (4, 976.0, 100.0)
    assert (bus3["bus"], bus3["B_shunt_Mvar"], bus3["G_shunt_MW"]) == (3, 300.0, 0.0)
    pairs = [(r["from"], r["to"], r["circuit"]) for r in d["lines"]]
    assert (3, 101, 1) in pairs and (3, 101, 2) in pairs
    text = run("cases", "kundur", "--line-table").stdout
    assert "lines:" in text and "circuit" in text and "buses:" not in text
    assert run("cases", "--bus-table").exit_code == 2


def test_help_texts_state_units():
    res = run("simulate", "--help")
    assert res.exit_code == 0
    for s in (
        "--fault BUS",
        "--far-bus",
        "--clear-cycles N",
        "--far-clear-cycles M",
        "--trip FROM TO[:K]",
        "--t-trip",
        "--bus-fault BUS[:R:X] T_ON T_OFF",
        "--close FROM TO[:K] T",
        "--trip-gen MACHINE T",
        "--load-step BUS T P Q",
        "--vref-step MACHINE T DV",
        "--pref-step MACHINE T DP",
        "--case-events",
        "--tf S",
        "--step H",
        "--pstess-default",
        "--stop-at-separation",
        "--out",
        "--plot",
        "--json",
        "(s)",
        "pu",
        "rad",
        "cycles",
    ):
        assert s in res.stdout, s
    assert run("cases", "--help").exit_code == 0


# --------------------------------------------------------------------------- simulate


def test_pstess_default_through_cli_matches_pstess(tmp_path):
    out, png = tmp_path / "kundur.csv", tmp_path / "kundur.png"
    res = run(
        "simulate",
        "kundur",
        "--pstess-default",
        "--out",
        out,
        "--plot",
        png,
        "--json",
        "--conventions",
        "pstess",
    )
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert summary["conventions"] == "pstess" and summary["step_s"] == 0.01
    assert summary["stable"] is True and summary["t_separation_s"] is None
    assert summary["separated_machines"] == [] and summary["t_end_s"] == 5.0
    assert summary["case"] == "kundur" and summary["wall_time_s"] > 0
    assert summary["files"] == [str(out), str(png)]
    assert png.stat().st_size > 20000
    header = out.read_text().splitlines()[0].split(",")
    assert header[:5] == ["t", "speed_pu.G1", "speed_pu.G2", "speed_pu.G3", "speed_pu.G4"]
    assert header[5] == "angle_rad.G1" and "efd_pu.G4" in header and "vmag_pu.B101" in header
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    ref = np.loadtxt(DATA / "kundur_d2asbegp_default_speed_pu.csv", delimiter=",", skiprows=1)
    assert data.shape[0] == ref.shape[0]
    np.testing.assert_allclose(data[:, 0], ref[:, 0], atol=1e-8)
    assert np.abs(data[:, 1:5] - ref[:, 1:5]).max() < 2e-4
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kundur.csv", "kundur.png"]


def test_case1_fault_json_and_stop_at_separation(tmp_path):
    out = tmp_path / "case1.npz"
    res = run(
        "simulate",
        "kundur",
        "--fault",
        3,
        "--far-bus",
        101,
        "--t-fault",
        1,
        "--clear-cycles",
        21,
        "--stop-at-separation",
        "--json",
        "--out",
        out,
    )
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["stable"] is False and s["separated_machines"] == [1, 2]
    assert s["t_separation_s"] > 1.35 and s["t_separation_s"] < 3.0
    assert s["t_end_s"] == pytest.approx(s["t_separation_s"])  # stopped there
    assert s["max_angle_from_coi_rad"] > np.pi
    assert "3-101" in s["events"][0] and "1.35 s" in s["events"][0]
    back = SimulationResult.from_npz(out)
    assert back.separated == [1, 2] and back.t[-1] == pytest.approx(s["t_separation_s"])


@pytest.mark.parametrize("conventions, t_sep", [("ieee", "1.96"), ("pstess", "2.07")])
def test_text_output_reports_verdict(conventions, t_sep):
    res = run(
        "simulate",
        "kundur",
        "--fault",
        3,
        "--far-bus",
        101,
        "--clear-cycles",
        21,
        "--far-clear-cycles",
        21,
        "--stop-at-separation",
        "--conventions",
        conventions,
    )
    assert res.exit_code == 0, res.output
    assert f"loss of synchronism at t = {t_sep}" in res.stdout
    assert (
        "machine(s) G1 (bus 1), G2 (bus 2) separate" in res.stdout
    )  # Kundur: G1, G2 at buses 1, 2
    assert f"{conventions} conventions" in res.stdout


def test_flat_run_and_line_trips(tmp_path):
    res = run("simulate", "kundur", "--tf", 2, "--json")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["stable"] and s["events"] == [] and s["t_end_s"] == 2.0
    res = run(
        "simulate",
        "kundur",
        "--trip",
        3,
        101,
        "--trip",
        13,
        101,
        "--t-trip",
        0.5,
        "--t-trip",
        1.0,
        "--tf",
        3,
        "--step",
        0.005,
        "--json",
    )
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["stable"] and s["step_s"] == 0.005 and s["n_steps"] == 600
    assert s["events"] == [
        "line 3-101 (circuit 1) tripped at 0.5 s",
        "line 13-101 (circuit 1) tripped at 1 s",
    ]


# -------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "args, needles",
    [
        (["kundur", "--fault", 999], ["bus 999"]),
        (["kundur", "--fault", 3, "--far-bus", 14], ["no branch between bus 3 and bus 14"]),
        (["kundur", "--trip", 1, 2], ["no branch between bus 1 and bus 2"]),
        (["kundur", "--fault", 3, "--far-bus", 101, "--circuit", 3], ["circuit 3"]),
        (["kundur", "--fault", 3, "--clear-cycles", -1], ["--clear-cycles"]),
        (
            [
                "kundur",
                "--fault",
                3,
                "--far-bus",
                101,
                "--clear-cycles",
                6,
                "--far-clear-cycles",
                3,
            ],
            ["far end"],
        ),
        (["kundur", "--far-bus", 101], ["without --fault"]),
        (["kundur", "--fault", 3, "--t-fault", 6, "--tf", 5], ["after the end of the run"]),
        (["kundur", "--trip", 3, 101, "--t-trip", -1], ["--t-trip"]),
        (["kundur", "--step", 0], ["--step"]),
        (["nonesuch"], ["unknown case 'nonesuch'"]),
    ],
)
def test_bad_input_exits_2_and_writes_nothing(tmp_path, args, needles):
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    res = run("simulate", *args, "--out", out_dir / "r.csv", "--plot", out_dir / "r.png")
    assert_bad_input(res, out_dir, *needles)


def test_bad_output_name_rejected_before_running(tmp_path):
    res = run("simulate", "kundur", "--out", tmp_path / "r.txt")
    assert_bad_input(res, tmp_path, "--out", ".csv")


def test_nonconvergent_powerflow_exits_2(tmp_path):
    case = load_case("kundur")
    buses = case.buses.replace(pload=case.buses.pload * 8, qload=case.buses.qload * 8)
    path = pstio.write_case_json(case.replace(buses=buses), tmp_path / "heavy.json")
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    res = run("simulate", path, "--out", out_dir / "r.csv")
    assert_bad_input(res, out_dir, "power flow")


def test_diverging_run_exits_2_reports_stop_time(tmp_path):
    """A real numerical divergence (machine 1 of Kundur with H = 1 ms, as in
    test_simulation): exit 2, nothing written, the stop time told."""
    case = load_case("kundur")
    H = case.machines.H.copy()
    H[0] = 1e-3
    path = pstio.write_case_json(
        case.replace(machines=case.machines.replace(H=H)), tmp_path / "tiny_h.json"
    )
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    res = run(
        "simulate",
        path,
        "--tf",
        3,
        "--out",
        out_dir / "r.csv",
        "--plot",
        out_dir / "r.png",
        "--json",
    )
    assert_bad_input(res, out_dir, "numerical instability", "t = ")


def test_simulate_method_trapezoid_runs_and_matches_heun_within_the_step(tmp_path):
    """--method trapezoid (ANDES's rule): the same fault's speeds within 1e-4 pu of Heun's
    at 5 ms (measured 1.7e-5: Heun is 2.0e-5 from a 0.25 ms run, the trapezoid 4.7e-6), the
    method in the JSON summary; with storage devices it is refused before any file is
    written."""
    args = ("simulate", "kundur", "--fault", 3, "--far-bus", 101, "--clear-cycles", 6)
    out = {}
    for method in ("heun", "trapezoid"):
        path = tmp_path / f"{method}.npz"
        res = run(*args, "--tf", 3, "--method", method, "--out", path, "--json")
        assert res.exit_code == 0, res.output
        s = json.loads(res.stdout)
        assert s["method"] == method and s["stable"]
        out[method] = SimulationResult.from_npz(path)
    assert np.max(np.abs(out["heun"].speed - out["trapezoid"].speed)) < 1e-4
    bad = tmp_path / "bad"
    bad.mkdir()
    res = run(*args, "--method", "trapezoid", "--esd-pct", 5, "--out", bad / "x.csv")
    assert_bad_input(res, bad, "--method trapezoid cannot be used with --esd-pct", "--method heun")


def test_simulate_method_trapezoid_with_pstess_conventions_names_both_options(tmp_path):
    """--method trapezoid --conventions pstess was refused as "method 'trapezoid' takes
    the 'exact' event semantics only", naming neither option: both named,
    why, and what to give instead, before any work."""
    res = run(
        "simulate", "kundur", "--fault", 3, "--far-bus", 101, "--tf", 1.5,
        "--method", "trapezoid", "--conventions", "pstess", "--out", tmp_path / "x.csv",
    )  # fmt: skip
    assert_bad_input(
        res,
        tmp_path,
        "--method trapezoid cannot be used with --conventions pstess, whose event semantics "
        "are PSTess's",
        "give --conventions ieee (the default) with --method trapezoid, or --method heun",
    )


def test_pss_e_study_events_in_any_number_and_order():
    """Every study event on the command line, named in the summary in the order given; the
    bus fault through an impedance and the reclosure reach the run (a VREF step alone is a
    different run from one with it and a PREF step)."""
    args = [
        "simulate",
        "kundur",
        "--bus-fault",
        "3:0:0.05",
        1,
        1.1,
        "--trip",
        3,
        101,
        "--t-trip",
        1.1,
        "--close",
        3,
        101,
        1.6,
        "--load-step",
        13,
        2,
        0.5,
        0.1,
        "--vref-step",
        2,
        3,
        0.02,
        "--pref-step",
        1,
        4,
        0.05,
        "--trip-gen",
        4,
        4.5,
        "--tf",
        5,
        "--json",
    ]
    res = run(*args)
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    g = load_case("kundur").machine_name  # machines named as every output names them
    assert s["events"] == [  # in time order, whatever the order of the options
        "3-phase fault through 0+0.05j pu at bus 3 at 1 s, cleared at 1.1 s (after 100.0 ms)"
        " without loss of a line",
        "line 3-101 (circuit 1) tripped at 1.1 s",
        "line 3-101 (circuit 1) closed at 1.6 s",
        "load step 0.5+0.1j pu at bus 13 at 2 s",
        f"VREF of {g(2)} stepped by +0.02 pu at 3 s",
        f"PREF of {g(1)} stepped by +0.05 pu at 4 s",
        f"{g(4)} tripped at 4.5 s",
    ]
    text = run(*args[:-1])
    assert f"  PREF of {g(1)} stepped by +0.05 pu at 4 s" in text.stdout.splitlines()


def test_a_separation_limit_below_the_initial_angle_spread_is_refused(tmp_path):
    """`simulate kundur --separation-limit 0.3 --tf 1` (a flat run) reported "loss of
    synchronism at t = 0.0000 s: G1", exit 0: G1 starts 0.3632 rad from the COI."""
    out = tmp_path / "o.csv"
    res = run("simulate", "kundur", "--separation-limit", 0.3, "--tf", 1, "--out", out)
    assert_bad_input(
        res,
        tmp_path,
        "--separation-limit 0.3 rad is not above the angle of G1 (bus 1) from the centre "
        "of inertia at the start, 0.3632 rad",
        "give a limit above 0.3632 rad",
    )


def test_a_tripped_machine_is_named_and_not_a_separation():
    """`--trip-gen 4 1`: G4 out of service from 1 s.  The machines left in service stay
    within pi of their own COI (checked here from the angles): the run is stable, no
    machine separates, and --json and the text name G4 as tripped."""
    import numpy as np

    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import GeneratorTrip

    args = ("simulate", "kundur", "--trip-gen", 4, 1, "--tf", 3)
    res = run(*args, "--json")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["stable"] is True and s["separated_machines"] == []
    assert s["tripped"] == [{"t_s": 1.0, "machines": [4]}]
    lib = Simulator(load_case("kundur")).run([GeneratorTrip(4, 1.0)], 3.0)
    M, a = lib.inertia[:3], lib.angle[:, :3]
    rest = np.abs(a - (a @ M / M.sum())[:, None]).max()
    assert rest < np.pi and s["max_angle_from_coi_rad"] == pytest.approx(rest, rel=1e-12)
    text = run(*args).stdout
    assert "  at t = 1 s machine(s) G4 (bus 12) tripped: out of the loss-of-synchronism" in text
    assert "stable: largest angle from the COI 0.9477 rad" in text and "separate" not in text


def test_a_tripped_machine_delivers_nothing_and_its_states_are_held():
    """A machine out of service carries no current: its recorded P and Q are 0 from the
    trip and its speed and angle stay where the trip left them (PSS/E's and ANDES's models
    of a machine whose status is off).  Its node grounded, the network solution gave it
    |psi|^2 of power (Kundur's G4: 1.15-1.48 pu, 115-148 MW, summed with the others')."""
    import numpy as np

    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import GeneratorTrip

    r = Simulator(load_case("kundur")).run([GeneratorTrip(4, 1.0)], 3.0)
    after = r.t > 1.0
    assert r.pelect[r.t < 1.0, 3].min() > 6.9  # 700 MW before the trip
    assert np.all(r.pelect[after, 3] == 0.0) and np.all(r.qelect[after, 3] == 0.0)
    at_trip = np.flatnonzero(after)[0] - 1
    for x in (r.speed, r.angle):
        assert np.all(x[after, 3] == x[at_trip, 3])
    assert r.speed[after, :3].min() < 0.998  # the others slow down, 700 MW short


def test_study_events_match_the_library(tmp_path):
    """The CLI's events are the library's: a fault through j0.05 pu and a PREF step give the
    same trajectories as `Simulator.run` with Fault(r=0, x=0.05) and PrefStep."""
    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import Fault, PrefStep

    out = tmp_path / "r.npz"
    res = run(
        "simulate", "kundur", "--bus-fault", "3:0:0.05", 1, 1.1, "--pref-step", 1, 1.5, 0.05,
        "--tf", 3, "--out", out,
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    cli = SimulationResult.from_npz(out)
    lib = Simulator(load_case("kundur")).run(
        [Fault(bus=3, t=1.0, clear_near=1.1, x=0.05), PrefStep(1, 1.5, 0.05)], t_end=3.0
    )
    assert np.array_equal(cli.speed, lib.speed)
    bolted = Simulator(load_case("kundur")).run([Fault(bus=3, t=1.0, clear_near=1.1)], t_end=3.0)
    assert np.abs(bolted.speed - lib.speed).max() > 1e-4


def test_trip_and_close_name_a_circuit(tmp_path):
    """--trip FROM TO:K and --close FROM TO:K T act on circuit K of the line (Kundur's 3-101
    has two): the CLI's run is the library's with LineTrip/LineClose(circuit=2), and a
    close of circuit 2 after a trip of circuit 1 is refused (circuit 2 is not open)."""
    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import LineClose, LineTrip

    out = tmp_path / "r.npz"
    res = run(
        "simulate", "kundur", "--trip", 3, "101:2", "--t-trip", 1.0, "--close", 3, "101:2",
        1.5, "--tf", 3, "--out", out, "--json",
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout[: res.stdout.rindex("}") + 1])["events"] == [
        "line 3-101 (circuit 2) tripped at 1 s",
        "line 3-101 (circuit 2) closed at 1.5 s",
    ]
    lib = Simulator(load_case("kundur")).run(
        [LineTrip(3, 101, 1.0, circuit=2), LineClose(3, 101, 1.5, circuit=2)], t_end=3.0
    )
    assert np.array_equal(SimulationResult.from_npz(out).speed, lib.speed)
    res = run("simulate", "kundur", "--trip", 3, 101, "--close", 3, "101:2", 1.5, "--tf", 2)
    assert res.exit_code == 2 and "not open" in res.output
    for bad in ("101:x", "101:0"):
        res = run("simulate", "kundur", "--trip", 3, bad, "--tf", 2)
        assert res.exit_code == 2 and ("TO:K" in res.output or "K must be" in res.output)


@pytest.mark.parametrize(
    "args, needles",
    [
        (["--bus-fault", "3:0.1", 1, 1.1], ["BUS is a bus number or BUS:R:X"]),
        (["--bus-fault", "3", 1.2, 1.1], ["0 <= T_ON <= T_OFF"]),
        (["--bus-fault", "3:-1:0", 1, 1.1], ["R and X must be >= 0"]),
        (["--close", 3, 101, 1.0], ["closes it while it is not open"]),
        (["--trip", 3, 101, "--t-trip", 1.5, "--close", 3, 101, 1.0], ["not open"]),
        # a reclosure before the faulted line is open at both ends: said in plain words
        (
            ["--fault", 3, "--far-bus", 101, "--clear-cycles", 6, "--far-clear-cycles", 12]
            + ["--close", 3, 101, 1.15],
            [
                "--close 3 101 at 1.15 s comes at or before the far end of the fault at bus 3 "
                "(at 1 s) clears at 1.2 s: the circuit is open only from then"
            ],
        ),
        (["--trip-gen", 9, 1.0], ["machine 9"]),
        (["--trip-converter", 1, 1.0], ["converter 1 is not in case 'kundur'"]),
        (["--load-step", 999, 1.0, 0.1, 0.0], ["bus 999"]),
        (["--vref-step", 9, 1.0, 0.01], ["machine 9"]),
    ],
)
def test_bad_study_events_exit_2(tmp_path, args, needles):
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    res = run("simulate", "kundur", *args, "--tf", 2, "--out", out_dir / "r.csv")
    assert_bad_input(res, out_dir, *needles)


def test_case_events_runs_the_case_s_own_disturbance(tmp_path):
    """--case-events runs the events stored in a case file (as import-andes stores ANDES's
    Toggle records), before the options' own; without it the run is flat.  A record of an
    unknown kind, without a field its kind needs or with a value of the wrong kind makes
    the case file malformed: refused, with or without --case-events, naming the file, the
    record and its source."""
    from stabctl.dynamics.events import LineClose, LineTrip, as_record

    case = load_case("kundur")
    own = (as_record(LineTrip(3, 101, 1.0), "Toggle 1"), as_record(LineClose(3, 101, 1.5), "2"))
    path = pstio.write_case_json(case.replace(events=own), tmp_path / "own.json")
    res = run("simulate", path, "--case-events", "--vref-step", 1, 2.0, 0.01, "--json")
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["events"] == [
        "line 3-101 (circuit 1) tripped at 1 s",
        "line 3-101 (circuit 1) closed at 1.5 s",
        f"VREF of {case.machine_name(1)} stepped by +0.01 pu at 2 s",
    ]
    assert s["t_end_s"] == 6.0  # the first event + 5 s
    assert json.loads(run("simulate", path, "--tf", 2, "--json").stdout)["events"] == []
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    for record, needle in (
        ({"kind": "Reclose", "bus": 3}, "unknown event kind 'Reclose'"),
        ({"kind": "LineTrip", "from_bus": 3, "t": 1.0}, "missing 1 required positional"),
        ({"kind": "LoadStep", "bus": 4, "t": "1", "P": 0.1}, "field 't': '1' is not a finite"),
        ({"kind": "GeneratorTrip", "machine": 1.5, "t": 1.0}, "'machine': 1.5 is not an int"),
    ):
        d = pstio.case_to_dict(case)
        d["events"] = [{**record, "source": "Alter 7"}]
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps(d))
        # a malformed event is a malformed case, run or not
        for args in (["--case-events"], ["--tf", 1]):
            res = run("simulate", bad, *args, "--out", out_dir / "r.csv")
            assert_bad_input(res, out_dir, "bad.json: events[0] (Alter 7): ", needle)


def test_storage_settings_without_a_rating_are_refused(tmp_path):
    """--esd-model, --deadband-hz, ... without --esd-pct set nothing: refused by name (exit
    2, nothing written), never ignored; with --esd-pct the WECC batteries' run prints its
    JSON summary (the command trajectory pesd_command stays out of it)."""
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    for args in (["--esd-model", "wecc"], ["--deadband-hz", 0.2, "--coi", "rest"]):
        res = run("simulate", "kundur", *args, "--tf", 1, "--out", out_dir / "r.csv")
        names = [a for a in args if str(a).startswith("--")]
        assert_bad_input(res, out_dir, f"{', '.join(names)} given without --esd-pct")
    res = run("cct", "kundur", "--fault", 3, "--far-bus", 101, "--esd-model", "wecc")
    assert res.exit_code == 2 and "--esd-model given without --esd-pct" in res.output
    res = run(
        "simulate", "kundur", "--fault", 3, "--far-bus", 101, "--esd-pct", 5,
        "--esd-model", "wecc", "--tf", 2, "--json",
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["stable"] and s["esd"]["devices"] == 4 and "pesd_command" not in s


def test_cct_of_a_bus_fault_is_labelled_as_one():
    """`stabctl cct kundur --fault 3` without --far-bus is a bus fault cleared without
    loss of a line (its CCT 0.238 s, the screening's), not "line 3-None" with a line
    tripped (whose CCT is 0.154 s)."""
    res = run("cct", "kundur", "--fault", 3)
    assert res.exit_code == 0, res.output
    head = res.stdout.splitlines()[0]
    assert head == "case kundur: fault at bus 3 at 1 s, cleared without loss of a line; no storage"
    assert "CCT 0.238 s" in res.stdout and "None" not in res.stdout
    # round 46: with --trip, "cleared without loss of a line, 3-101 also opened"; the CCT
    # is the line fault's, and the head says the clearing opens the line
    res = run("cct", "kundur", "--fault", 3, "--trip", 3, 101)
    assert res.exit_code == 0, res.output
    head = res.stdout.splitlines()[0]
    assert head == "case kundur: fault at bus 3 at 1 s, cleared by opening 3-101; no storage"
    assert "CCT 0.154 s" in res.stdout


def test_a_closed_pipe_ends_a_command_quietly():
    """`stabctl cases | head -1`: the reader goes away; stabctl ends without an error line
    (exit status 141, as a process stopped by SIGPIPE), not "error: Broken pipe".  The
    pipe's reading end is closed before stabctl writes, so every write meets it closed."""
    import os
    import subprocess
    import sys

    read, write = os.pipe()
    os.close(read)
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "stabctl.cli", "cases"],
            stdout=write,
            stderr=subprocess.PIPE,
            text=True,
        )
    finally:
        os.close(write)
    assert (proc.returncode, proc.stderr) == (141, "")


@pytest.mark.parametrize("where", ["closed", "full"])
@pytest.mark.parametrize(
    "args",
    [["cases"], ["--version"], ["simulate", "kundur", "--fault", "3", "--tf", "1.2", "--json"]],
)
def test_output_that_cannot_reach_stdout_is_an_error(where, args):
    """stdout closed (``>&-``) or on a full disk (``> /dev/full``): one line saying that
    standard output cannot be written, and why, exit status 2; not exit 0 with the
    results lost without a word, nor the disk's error without saying whose."""
    import os
    import subprocess
    import sys

    if where == "full" and not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    cmd = [sys.executable, "-m", "stabctl.cli", *args]
    if where == "closed":
        proc = subprocess.run(
            cmd, stderr=subprocess.PIPE, text=True, preexec_fn=lambda: os.close(1)
        )
        reason = "it is closed"
    else:
        with open("/dev/full", "w") as full:
            proc = subprocess.run(cmd, stdout=full, stderr=subprocess.PIPE, text=True)
        reason = "No space left on device"
    said = [x for x in proc.stderr.splitlines() if not x.startswith(("stabctl: ", "  ("))]
    assert proc.returncode == 2, proc.stderr
    assert said == [f"error: cannot write to standard output (stdout): {reason}"], proc.stderr


@pytest.mark.parametrize("how", ["closed", "read-only"])
@pytest.mark.parametrize("command", ["screen", "sweep-cct"])
def test_a_study_runs_with_stderr_closed(tmp_path, how, command):
    """stderr closed (``2>&-``, a daemon; or, through pyenv's shim, descriptor 2 left on
    the shim's script, read-only): `screen` and `sweep-cct` stopped at their first
    progress bar, exit status 1, no records and no word.  The study runs: its records
    written, its table on stdout, exit status 0."""
    import os
    import subprocess
    import sys

    def stderr_gone():
        if how == "closed":
            os.close(2)
        else:
            fd = os.open(sys.executable, os.O_RDONLY)
            os.dup2(fd, 2)
            os.close(fd)

    # bus 3's fault; Kundur's two default line faults
    study, n = {"screen": (["--buses", "3"], 1), "sweep-cct": (["--faults", "DEFAULT"], 2)}[command]
    out = tmp_path / "r.jsonl"
    cmd = [sys.executable, "-m", "stabctl.cli", command, "kundur", *study]
    cmd += ["--tol-ms", "20", "--t-max", "0.3", "--workers", "1", "--out", str(out)]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, text=True, preexec_fn=stderr_gone)
    assert proc.returncode == 0, proc.stdout
    assert len(out.read_text().splitlines()) == n
    assert "0 failed" in proc.stdout


def test_a_trapezoid_step_above_one_cycle_is_a_warning():
    """`simulate --method trapezoid --step 0.25` (the finding: a stable fault reported
    unstable with angles of 13-26 rad, exit 0, no word): at 0.1 s Kundur's bus-3 fault
    cleared in 6 cycles is stable with 1.013 rad from the COI where the default step gives
    0.838 rad; it is printed with a warning to halve the step.  So is a step of 20 ms,
    at which the fault cleared in 9.2 cycles (1.2 ms below its CCT) is unstable where at
    5 and 10 ms it is stable; at one cycle there is none."""
    args = ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--tf", "3"]
    coarse = run(*args, "--method", "trapezoid", "--step", "0.1")
    assert coarse.exit_code == 0, coarse.output
    assert "warning: trapezoid step 0.1 s is above 0.01667 s (one cycle at 60 Hz)" in coarse.stderr
    assert "halve the step and compare (simulate --check-step; cct" in coarse.stderr
    fine = run(*args, "--method", "trapezoid", "--step", str(1 / 60))
    assert fine.exit_code == 0 and "warning" not in fine.stderr
    near = [*args[:-1], "5", "--clear-cycles", "9.2", "--method", "trapezoid", "--json"]
    at = {h: json.loads(run(*near, "--step", h).stdout)["stable"] for h in ("0.005", "0.01")}
    assert at == {"0.005": True, "0.01": True}
    coarse = run(*near, "--step", "0.02")
    assert "warning: trapezoid step 0.02 s is above 0.01667 s (one cycle at 60 Hz)" in coarse.stderr
    # the JSON carries the warnings too (round 38: its reader saw a wrong verdict, unmarked)
    said = json.loads(coarse.stdout)["warnings"]
    assert any(w.startswith("trapezoid step 0.02 s is above 0.01667 s") for w in said), said
    assert json.loads(run(*near, "--step", "0.005").stdout)["warnings"] == []


def test_a_trapezoid_step_whose_network_fails_names_the_step_and_its_check_no_trapezoid():
    """Round 38: at 0.5 s the trapezoid's network failed in words that did not name the
    step; and `--check-step` of a trapezoid run told it to use the trapezoid."""
    args = ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--clear-cycles", "6"]
    res = run(*args, "--method", "trapezoid", "--step", "0.5")
    assert res.exit_code == 2
    # where the network (or Newton's iteration) fails at so coarse a step depends on the
    # last bits of the libraries' arithmetic (2.08 s, or 5.02 s on another install): either
    # failure names the step
    said = "did not converge (a step of 0.49 s, 98 times the case's default: a smaller --step "
    assert said + "may converge)" in res.stderr, res.stderr
    args = [*args[:-1], "9.1", "--step", "0.0166", "--check-step", "--method", "trapezoid"]
    res = run(*args)
    assert res.exit_code == 0 and "it depends on the step by" in res.stdout, res.output
    assert "(halve it again)" in res.stdout and "--method trapezoid" not in res.stdout
    from types import SimpleNamespace

    from stabctl.cli.simulate import _step_check_line

    ran = SimpleNamespace(stable=True, de_energised_s=None, max_angle_from_coi=1.0)
    halved = {"step_s": 0.005, "verdict": "stable", "max_angle_from_coi_rad": 1.1}
    assert _step_check_line(ran, halved, "heun").endswith(
        "by 9.1% (halve it again, or --method trapezoid for a lightly damped swing)"
    )


def test_the_trapezoid_s_one_cycle_is_the_case_s_frequency_s():
    """Round 30: a 50 Hz case's trapezoid step of 0.019 s, within its cycle of 0.02 s, was
    warned of as above 0.01667 s (a 60 Hz cycle)."""
    from stabctl.dynamics.grid import check_step

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_step((1.0, "none"), 0.019, explicit=False, freq_hz=50.0)
    with pytest.warns(UserWarning, match=r"above 0.02 s \(one cycle at 50 Hz\)"):
        check_step((1.0, "none"), 0.021, explicit=False, freq_hz=50.0)


def test_tripping_every_machine_is_reported_as_de_energised_not_stable(tmp_path):
    """Every machine tripped (all load shed) printed 'stable: largest angle from the COI
    0.3632 rad' (the angle before the trips) and "stable": true."""
    trips = [a for m in (1, 2, 3, 4) for a in ("--trip-gen", m, 1)]
    res = run("simulate", "kundur", *trips, "--tf", 2)
    assert res.exit_code == 0, res.output
    assert "de-energised at t = 1 s: no machine left in service" in res.stdout
    assert "stable:" not in res.stdout
    plot = tmp_path / "run.png"
    res = run("simulate", "kundur", *trips, "--tf", 2, "--plot", plot)  # its title says so
    assert res.exit_code == 0 and plot.stat().st_size > 0, res.output
    res = run("simulate", "kundur", *trips, "--tf", 2, "--json")
    d = json.loads(res.stdout)
    assert d["stable"] is False and d["verdict"] == "de-energised" and d["de_energised_s"] == 1.0


def test_check_step_reports_the_verdict_at_half_the_step():
    """--check-step runs again at h/2.  Kundur's fault on line 3-101 at a 10 ms step has
    its CCT at 0.153 s and at 0.154 s at h/2 (`stabctl cct ... --step 0.01`: numerical
    error 1 ms), so a clearing at 0.154 s (9.24 cycles) separates at h and is stable at
    h/2: the verdict depends on the step, and simulate says so; at 6 cycles both are
    stable."""
    fault = ("kundur", "--fault", "3", "--far-bus", "101", "--step", "0.01", "--check-step")
    near = ("--clear-cycles", "9.24", "--far-clear-cycles", "9.24")
    res = run("simulate", *fault, *near)
    assert res.exit_code == 0, res.output
    assert "loss of synchronism" in res.output
    assert (
        "step check: stable at half the step (h = 5 ms), separated at the step: the verdict "
        "depends on the step" in res.output
    )
    res = run("simulate", *fault, *near, "--json")
    d = json.loads(res.stdout)
    assert not d["stable"]
    check = d["step_check"]
    assert check.pop("max_angle_from_coi_rad") > 1.0
    assert check == {"step_s": 0.005, "verdict": "stable", "t_separation_s": None}
    res = run("simulate", *fault, "--clear-cycles", "6", "--far-clear-cycles", "6")
    assert res.exit_code == 0, res.output
    assert "step check: stable at half the step (h = 5 ms) too; largest angle" in res.output
    assert "depends on the step by" not in res.output


def test_heun_s_growth_of_an_undamped_swing_is_warned_and_shown_by_the_step_check(tmp_path):
    """Heun multiplies an undamped swing by sqrt(1 + (w h)^4 / 4) a step.  PSS/E's SMIB
    with H = 0.5 s (a 3.9 Hz swing, no damping), 21 s at 8.3 ms: the largest angle 0.837
    rad against 0.773 at h/2 and 0.75 converged, with no word and "--check-step: stable
    too".  The run warns (the growth from the closed form, about 30 %), the step check
    gives both figures, and the trapezoid is near the converged figure."""
    data = Path(__file__).resolve().parents[1] / "data" / "psse"
    (tmp_path / "h.dyr").write_text(
        (data / "smib.dyr").read_text().replace("3.0  0.0 /", "0.5  0.0 /")
    )
    made = run("import-psse", data / "smib_v33.raw", tmp_path / "h.dyr", "-o", tmp_path / "h.json")
    assert made.exit_code == 0, made.output
    args = ("simulate", tmp_path / "h.json", "--bus-fault", 1, 1, 1.03, "--tf", 21)
    res = run(*args, "--check-step")
    assert res.exit_code == 0, res.output
    assert re.search(r"heun's step 0.00833333 s lets an undamped swing grow: one of about "
                     r"3.2 Hz \(G1 .*by about 30 % over the 21 s run", res.stderr)  # fmt: skip
    assert "stable: largest angle from the COI 0.8374 rad" in res.stdout
    assert re.search(
        r"0.7729 rad there \(-0.0645 rad\): it depends on the step by 8.3%", res.stdout
    )
    trap = run(*args, "--method", "trapezoid", "--json")
    assert "heun" not in trap.stderr
    assert json.loads(trap.stdout)["max_angle_from_coi_rad"] == pytest.approx(0.76, abs=0.02)


def test_a_stable_run_that_ends_far_from_a_normal_operating_point_says_so(tmp_path):
    """Kundur's fault at bus 3 with line 3-20 tripped cuts area 1's machines off: the rest
    runs on at 0.59 pu and 59.1 Hz for 19 s, reported "stable" without a word.  The end
    state is given (`--json` `end_state`: the lowest energised bus voltage and the
    judged machines' frequency, as the CSV's last row has them) and a stable run below
    0.8 pu or beyond +-0.6 Hz says so in a note; a normal clearing says nothing."""
    import csv

    out = tmp_path / "k.csv"
    args = ["simulate", "kundur", "--fault", 3, "--far-bus", 20, "--clear-cycles", 6, "--tf", 20]
    res = run(*args, "--out", out, "--json")
    assert res.exit_code == 0, res.output
    end = json.loads(res.stdout)["end_state"]
    with open(out) as fh:
        rows = list(csv.DictReader(fh))
    last = rows[-1]
    volts = {int(k.split(".B")[1]): float(v) for k, v in last.items() if k.startswith("vmag_pu.B")}
    on = {b: v for b, v in volts.items() if v > 1e-3}
    bus = min(on, key=on.get)
    assert (end["lowest_voltage_bus"], end["lowest_voltage_pu"]) == (bus, pytest.approx(on[bus]))
    assert end["lowest_voltage_pu"] < 0.8 and abs(end["frequency_hz"] - 60.0) > 0.6
    assert len(end["concerns"]) == 2
    text = run(*args)
    assert "  note: at the end (t = 20 s) bus " in text.stdout, text.stdout
    assert "stable by the angle criterion, yet no normal operating point" in text.stdout
    normal = run("simulate", "kundur", "--fault", 3, "--far-bus", 101, "--clear-cycles", 6)
    assert normal.exit_code == 0 and "note: at the end" not in normal.stdout


def test_a_cct_whose_stable_run_ends_off_a_normal_operating_point_says_so():
    """`cct`'s verdict rests on a stable run (cleared at the CCT, or at --t-max for a
    robust fault) that may end as far from a normal operating point as `simulate` shows
    (above): line 13-120's trip leaves area 1 at 0.41 pu at bus 13 when cleared at 0.5 s,
    as `simulate` of that clearing ends; the search records no bus voltage yet says so,
    in text and in `--json` (`end_concerns`, `end_t_s`)."""
    sim = run("simulate", "kundur", "--fault", 13, "--far-bus", 120, "--clear-cycles", 30,
              "--tf", 6, "--json")  # fmt: skip
    end = json.loads(sim.stdout)["end_state"]
    said = f"bus {end['lowest_voltage_bus']} at {end['lowest_voltage_pu']:.3f} pu"
    args = ("cct", "kundur", "--fault", 13, "--far-bus", 120, "--t-max", 0.5, "--tol-ms", 20)
    res = run(*args)
    assert res.exit_code == 0, res.output
    assert f"note: cleared at the limit, at the end (t = 6 s) {said}: stable" in res.stdout
    d = json.loads(run(*args, "--json").stdout)
    assert (d["verdict"], d["end_concerns"], d["end_t_s"]) == ("above t_max", [said], 6.0)
    assert end["concerns"] == [said]


@pytest.mark.parametrize("failing", ["csv", "plot"])
def test_outputs_are_written_together_or_not_at_all(tmp_path, monkeypatch, failing):
    """Round 32: `simulate --out x.csv --plot x.png` under a file size limit failed on
    x.csv and left a new x.png: the outputs are renamed only once all are written, so a
    failure in either leaves neither (and no temporary file)."""
    import errno

    def too_large(*args, **kwargs):
        raise OSError(errno.EFBIG, "File too large")

    if failing == "csv":
        monkeypatch.setattr(SimulationResult, "to_csv", too_large)
    else:
        monkeypatch.setattr("stabctl.plotting.figures.simulation_overview", too_large)
    res = run(
        "simulate", "kundur", "--fault", "3", "--far-bus", "101", "--tf", "1.2",
        "--out", tmp_path / "x.csv", "--plot", tmp_path / "x.png",
    )  # fmt: skip
    assert res.exit_code == 2
    assert res.stderr.strip().startswith("error: ") and "File too large" in res.stderr
    assert sorted(tmp_path.iterdir()) == []


def test_a_long_eig_says_it_is_still_working(monkeypatch):
    """Round 35: eig of a planning case printed nothing for its whole linearisation (9-17
    s on WECC 240, about a minute on ACTIVSg2000).  A heartbeat says it is still at work
    after every HEARTBEAT_S of silence."""
    import time

    from stabctl import progress
    from stabctl.studies import eigenvalues

    real = eigenvalues.eig_study

    def slow(*a, **k):
        time.sleep(1.5)
        return real(*a, **k)

    monkeypatch.setattr(progress, "HEARTBEAT_S", 0.5)
    monkeypatch.setattr(eigenvalues, "eig_study", slow)
    res = run("eig", "kundur", "--json")
    assert res.exit_code == 0, res.output
    assert "eig: still linearising and analysing case kundur (4 machines)" in res.stderr
    json.loads(res.stdout)  # stdout stays the JSON alone


def test_the_storage_summary_counts_chattering(tmp_path):
    """PSS/E's ThreeBus GENROU case, line 102-103 cleared after 14 cycles, storage 50 %:
    8 of its device's 18 switchings come within 20 ms of the one before (JSON
    ``chattering``), which the text never said (round 37)."""
    data = Path(__file__).resolve().parents[1] / "data" / "psse_runs" / "GENROU"
    case = tmp_path / "three.json"
    made = run("import-psse", data / "ThreeBusMulti.raw", data / "ThreeBus_GENROU.dyr", "-o", case)
    assert made.exit_code == 0, made.output
    args = ("simulate", case, "--fault", 102, "--far-bus", 103, "--clear-cycles", 14)
    res = run(*args, "--esd-pct", 50, "--json")
    devices = json.loads(res.stdout)["storage"]
    n = sum(d["chattering"] for d in devices)
    assert n == 8 and sum(d["switchings"] for d in devices) == 18
    text = run(*args, "--esd-pct", 50).stdout
    assert "18 switchings, 1 of 1 device acted" in text
    assert "; 8 of the switchings chattering (within 20 ms of the device's previous one)" in text


def test_a_line_fault_s_steps_are_its_intervals():
    """Round 40: a line fault cleared at both ends at once printed "0-6 s, 1201 steps (h =
    5 ms" (6 s at 5 ms is 1200): the zero-length interval between the two ends' openings
    (its time recorded twice, as PSTess records it) was counted as a step."""
    res = CliRunner().invoke(main, ["simulate", "kundur", "--fault", "3", "--far-bus", "101"])
    assert res.exit_code == 0, res.output
    assert "0-6 s, 1200 steps (h = 5 ms" in res.stdout, res.stdout


def test_the_storage_summary_says_when_the_network_took_no_power():
    """A device commanded while its bus is below PST's 0.5 pu low-voltage switch moves
    nothing (the network drops it); round 45: a device far beyond its bus switched and
    moved nothing without a word.  Kundur, fault at device 1's bus 10 for 30 cycles,
    ungated devices: the summary names the seconds of its command that took no power."""
    args = ("simulate", "kundur", "--fault", "10", "--clear-cycles", "30", "--v-gate", "0")
    res = CliRunner().invoke(main, [*args, "--esd-pct", "50"])
    assert res.exit_code == 0, res.output
    said = re.search(
        r"device 1 \(bus 10\): the network took none of its power for ([\d.]+) s of the "
        r"([\d.]+) s it was commanded \(its bus below the 0.5 pu low-voltage switch",
        res.stdout,
    )
    assert said, res.stdout
    idle, commanded = map(float, said.groups())
    assert 0.5 <= idle < commanded  # the fault holds bus 10 down 0.5 s; then it recovers
    data = json.loads(CliRunner().invoke(main, [*args, "--esd-pct", "50", "--json"]).stdout)
    dev = data["storage"][0]
    assert dev["commanded_idle_s"] == pytest.approx(idle, rel=2e-3)


def test_a_flat_run_that_does_not_stay_at_rest_is_said(monkeypatch):
    """Round 49 (AG12): Nordic 44 with its IEEET2 misread (the rate feedback of Efd, not
    of V_R) started at rest, drifted from round-off on (Efd 1.06 pu in 10 s) and was said
    "stable", exit 0, no warning.  `SimulationResult.drift` finds the largest move of a
    speed, field voltage or bus voltage from the start; a run without disturbance that
    moves more than FLAT_DRIFT_PU (1e-4 pu) is warned of, naming what moved, where and
    when; Kundur's flat run (at rest to 1e-12) is not."""
    from stabctl import Simulator
    from stabctl.dynamics.results import FLAT_DRIFT_PU

    case = load_case("kundur")
    res = Simulator(case).run([], 1.0)
    assert res.drift()["pu"] < 1e-10
    res.efd[50, 2] += 2e-4  # G3's field voltage away from its start at step 50
    assert res.drift() == pytest.approx(
        {"pu": 2e-4, "quantity": "efd", "where": 3, "t_s": float(res.t[50])}
    )
    out = run("simulate", "kundur", "--tf", "1", "--json")
    assert out.exit_code == 0 and json.loads(out.stdout)["warnings"] == []
    moved = {"pu": 1.06, "quantity": "efd", "where": 3, "t_s": 10.0}
    monkeypatch.setattr(SimulationResult, "drift", lambda self: moved)
    out = run("simulate", "kundur", "--tf", "1")
    said = (
        "warning: the flat run (no disturbance) did not stay at rest: the field voltage of "
        f"G3 (bus 11) moved 1.06e+00 pu by t = 10 s (more than {FLAT_DRIFT_PU:g} pu)"
    )
    assert said in " ".join(out.stderr.split()), out.stderr
    out = run("simulate", "kundur", "--tf", "1", "--trip-gen", "4", "0.5")
    assert "did not stay at rest" not in out.stderr  # a disturbance: moves are its answer


@pytest.mark.parametrize(("damping", "warned"), [(0.05, True), (0.5, False)])
def test_heun_warns_of_a_lightly_damped_swing_it_grows(tmp_path, damping, warned):
    """The five-bus case with its machines classical (H 5, 0.5 and 3 s), a 50 ms fault, 20
    s at heun's default 10 ms: with a damping D of 0.05 the largest angle was 0.5603 rad
    against 0.3021 at 1/480 s (85 %), and no word, as only D = 0 was judged (round 58
    BA95-97).  The swing's decay D / (4 H) is now set against Heun's growth: the warning
    comes at D = 0.05 (a net growth of a factor 3.15) and not at D = 0.5, whose run is
    within 1 % of 1/480 s's (0.2981 against 0.2967 rad)."""
    data = Path(__file__).parents[1] / "data" / "psse"
    (tmp_path / "c.dyr").write_text(
        f"    1 'GENCLS' 1   5.0  {damping} /\n    3 'GENCLS' 1   0.5  {damping} /\n"
        f"    3 'GENCLS' '2' 3.0  {damping} /\n"
    )
    case = tmp_path / "c.json"
    made = run("import-psse", data / "five_bus_v33.raw", tmp_path / "c.dyr", "-o", case)
    assert made.exit_code == 0, made.output
    res = run("simulate", case, "--bus-fault", "2:0:0.2", 1, 1.05, "--tf", 20)
    assert res.exit_code == 0, res.output
    said = "lets a lightly damped swing grow: one of about 4.5 Hz (G2 (bus 3, id '1')'s swing"
    assert (said in res.stderr) is warned, res.stderr


@pytest.mark.parametrize("method", ["heun", "trapezoid"])
def test_a_separated_machine_running_away_ends_the_run_with_its_verdict(tmp_path, method):
    """The PSS/E five-bus case (GENROU, no governor), its line 2-1 fault cleared after 15
    cycles: machines G2 and G3 lose synchronism at 1.47 s and, slipping with nothing to
    hold them, pass 1.5 pu speed near 10.4 s.  The run failed there, "numerical
    instability ... use a smaller step", exit 2, at every step and with both methods: the
    verdict lost (round 58 BA99-100).  The run now ends there with its verdict, loss of
    synchronism, and says why it stopped (`SimulationResult.ran_away`; JSON `runaway`)."""
    data = Path(__file__).parents[1] / "data" / "psse"
    case = tmp_path / "five.json"
    made = run("import-psse", data / "five_bus_v33.raw", data / "five_bus.dyr", "-o", case)
    assert made.exit_code == 0, made.output
    args = ("simulate", case, "--fault", 2, "--far-bus", 1, "--clear-cycles", 15, "--tf", 30)
    res = run(*args, "--step", 0.0020833, "--method", method)
    assert res.exit_code == 0, res.output
    assert "loss of synchronism at t = 1.4687 s: machine(s) G2 (bus 3, id '1'), G3" in res.stdout
    note = r"note: G[23] \(bus 3, id '[12]'\), separated, ran past 0.5 pu from synchronous speed"
    assert re.search(note + r" \(1.5 pu\) at t = 10.3\d+ s: the run stopped", res.stdout)
    out = json.loads(run(*args, "--step", 0.0020833, "--method", method, "--json").stdout)
    assert out["stable"] is False and "ran past 0.5 pu" in out["runaway"]
