"""The planner's placement: the MWh sizing against the OMIB's first swing (energy
conservation gives its duration as a quadrature), load scaling against the power balance,
requirements and costs on their definitions, constraint generation adding a contingency
the first solve missed (checked by independent simulation), and infeasible requirements
naming the contingency and the load level.  Simulation-based tests use Kundur only."""

import json
from dataclasses import replace

import numpy as np
import pytest
from click.testing import CliRunner
from plan_checks import stable_when_cleared
from scipy.integrate import quad

from stabctl.cli import main
from stabctl.cli.format import _plan_verdict
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.options import ModelOptions
from stabctl.errors import InputError, PowerFlowError
from stabctl.io import load_case
from stabctl.network.powerflow import scale_load, solve_powerflow
from stabctl.placement.context import PlanContext
from stabctl.placement.energy import ENERGY_MARGIN
from stabctl.placement.evaluation import (
    Contingency,
    Evaluator,
    VerifyOptions,
    _fleet,
    check,
    controller_dict,
    evaluate,
    verify,
)
from stabctl.placement.loop import Study, check_damping_model
from stabctl.placement.plan import PlanOptions, plan
from stabctl.placement.program import InfeasibleError, candidate_sites
from stabctl.placement.requirements import CostModel, Requirement
from stabctl.smib.omib import PAPER_OMIB, simulate
from stabctl.stability.cct import LineFault, fault_inputs
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import StorageDevice, StorageFleet, energy_excursion, model_inputs

BASE_MVA = 100.0


# -- MWh sizing: the OMIB's first swing in closed form ------------------------------------


def first_swing_duration(system, delta_cl, omega_cl, P_C):
    """Time from clearing to the end of the first swing (omega = 0) with the device
    absorbing P_C throughout: energy conservation M omega^2 / 2 = M omega_cl^2 / 2 +
    integral (Pm - Pmax sin x - P_C) dx gives omega(delta), and t = integral d delta /
    omega (substitution delta = delta_max - u^2 removes the end singularity)."""
    M = system.M

    def w2(d):
        work = (system.Pm - P_C) * (d - delta_cl) + system.Pmax_post * (
            np.cos(d) - np.cos(delta_cl)
        )
        return omega_cl**2 + 2 * work / M

    lo, hi = delta_cl, np.pi - np.arcsin((system.Pm - P_C) / system.Pmax_post)
    for _ in range(200):  # delta_max: first zero of omega^2
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if w2(mid) > 0 else (lo, mid)
    d_max = lo
    t, _ = quad(
        lambda u: 2 * u / np.sqrt(max(w2(d_max - u * u), 1e-300)),
        0,
        np.sqrt(d_max - delta_cl),
        limit=200,
    )
    return t


def test_energy_of_a_bang_bang_device_over_the_first_swing_is_its_rating_times_its_duration():
    P_C, t_clear = 0.2, 0.2  # pu, s (CCT 0.243 s)
    law = lambda f, w, M: ((f - P_C * np.sign(w)) / M, P_C * np.sign(w))  # noqa: E731
    run = simulate(PAPER_OMIB, t_clear, t_end=t_clear + 0.6, law=law, max_step=2e-5)
    assert run.stable
    t1 = first_swing_duration(PAPER_OMIB, run.delta_cl, run.omega_cl, P_C)
    # the run up to the end of the first swing (omega back to 0)
    end = np.nonzero((run.t > t_clear) & (run.omega <= 0))[0][0]
    e = energy_excursion(run.t[: end + 1], run.P_C[: end + 1] * BASE_MVA)
    closed_mj = P_C * BASE_MVA * t1
    assert e["absorbed_mj"] == pytest.approx(closed_mj, rel=2e-3)
    assert e["soc_high_mj"] == pytest.approx(closed_mj, rel=2e-3)
    assert e["delivered_mj"] <= P_C * BASE_MVA * 2e-5  # the last half step only
    # started half full, the device needs twice its largest excursion
    assert e["need_mwh"] == pytest.approx(2 * closed_mj / 3600, rel=2e-3)
    # over the whole run (back swing injecting) the state of charge is the running
    # integral: highest at the end of the first swing, absorbed - delivered at the end
    whole = energy_excursion(run.t, run.P_C * BASE_MVA)
    assert whole["soc_high_mj"] == pytest.approx(closed_mj, rel=2e-3)
    assert whole["absorbed_mj"] - whole["delivered_mj"] == pytest.approx(
        np.trapezoid(run.P_C, run.t) * BASE_MVA, rel=1e-9, abs=1e-9
    )


def test_a_device_sized_by_its_excursion_follows_the_unlimited_trajectory(kundur):
    """The simulator clips a device only at a full or empty store: one started half full
    with twice the largest excursion of the unlimited run (plus margin) runs the same."""
    fault = LineFault(3, 101)
    free = StorageFleet((StorageDevice(110, 3, 100.0),), BangBangCOI())
    r = kundur.run(fault.events(0.15), 4.0, storage=free)
    need = energy_excursion(r.t, r.pesd[:, 0] * BASE_MVA)["need_mwh"]
    sized = StorageFleet(
        (StorageDevice(110, 3, 100.0, energy_mj=1.05 * need * 3600),), BangBangCOI()
    )
    small = StorageFleet(
        (StorageDevice(110, 3, 100.0, energy_mj=0.5 * need * 3600),), BangBangCOI()
    )
    np.testing.assert_allclose(
        kundur.run(fault.events(0.15), 4.0, storage=sized).pesd, r.pesd, atol=1e-12
    )
    assert not np.allclose(kundur.run(fault.events(0.15), 4.0, storage=small).pesd, r.pesd)


# -- load levels ------------------------------------------------------------------------------


def test_scaled_load_keeps_the_power_balance_and_names_a_load_level_without_power_flow():
    case = load_case("kundur")
    up = scale_load(case, 1.05)
    b, u = case.buses, up.buses
    np.testing.assert_allclose(u.pload, 1.05 * b.pload)
    np.testing.assert_allclose(u.qload, 1.05 * b.qload)
    pv = b.kind == 2
    np.testing.assert_allclose(u.pgen[pv], 1.05 * b.pgen[pv])  # no governor at its limit
    pf = solve_powerflow(up)
    # conservation: generation - load = series losses + shunt conductance losses
    losses = float(pf.branch_flows()["loss"].real.sum()) + float(u.gshunt @ pf.vmag**2)
    assert pf.pgen.sum() - pf.pload.sum() == pytest.approx(losses, rel=1e-6, abs=1e-7)
    assert losses > 0
    assert scale_load(case, 1.0) is case
    with pytest.raises(InputError):
        scale_load(case, 0.0)
    with pytest.raises(PowerFlowError, match="load level 4"):
        scale_load(case, 4.0)


# -- requirements and costs -------------------------------------------------------------------


def test_the_strictest_requirement_wins_and_is_rounded_up_to_the_tolerance():
    assert Requirement(cycles=5).target_s(60.0, 1e-3) == pytest.approx(0.084)  # 83.3 ms
    both = Requirement(cycles=5, gain_pct=10, cct_s=0.09)
    assert both.target_s(60.0, 1e-3, base_cct_s=0.1) == pytest.approx(0.110)
    assert both.target_s(60.0, 1e-3, base_cct_s=0.05) == pytest.approx(0.090)
    with pytest.raises(InputError):
        Requirement()
    with pytest.raises(InputError):
        Requirement(cycles=-1)
    with pytest.raises(InputError):
        Requirement(gain_pct=5).target_s(60.0, 1e-3)


def test_cost_split_is_per_mw_per_mwh_and_per_used_site():
    sites = candidate_sites(load_case("kundur"))
    cost = CostModel(per_mw=2.0, per_mwh=300.0, per_site=50.0, overrides={3: {"per_mw": 5.0}})
    mw = np.array([10.0, 0.0, 20.0, 0.0])  # sites of G1..G4
    mwh = np.array([0.1, 0.0, 0.2, 0.0])
    got = cost.split(sites, mw, mwh)
    assert got == pytest.approx(
        {"mw": 10 * 2 + 20 * 5, "mwh": 300 * 0.3, "site": 100.0, "total": 120 + 90 + 100}
    )
    with pytest.raises(InputError):
        CostModel(per_mw=0.0, per_mwh=0.0)


# -- constraint generation and infeasibility (Kundur) ------------------------------------------


def independently_stable(case_name, fault, t_clear, rows, load=1.0):
    return stable_when_cleared(scale_load(load_case(case_name), load), fault, t_clear, rows)


def test_constraint_generation_adds_what_the_first_solve_missed_and_ends_verified():
    """Two faults with their own requirements, one solved for at first (n_active=1, the
    most binding): the other fails the check at that allocation, is added, and the end
    allocation holds both, as an independent simulation at each required time confirms."""
    faults = [LineFault(3, 101), LineFault(20, None)]
    over = {"20": Requirement(cycles=16)}  # 267 ms for the bus-20 fault
    said: list[str] = []
    res = plan(
        "kundur",
        faults,
        Requirement(cycles=12),
        PlanOptions(overrides=over, n_active=1, half_step_n=2, uniform=True),
        progress=said.append,
    )
    assert len(res.rounds) >= 2
    # each round's first line bounds what is left (a plan's progress named each batch
    # alone): rounds and iterations, PlanOptions' defaults
    starts = [m for m in said if " solving for " in m]
    assert (
        starts[0]
        == "round 1 of at most 6: solving for 1 contingency (3-101), in at most 6 iterations"
    )
    assert starts[1].startswith("round 2 of at most 6: solving for 2 contingencies (3-101, 20)")
    first = res.rounds[0]
    assert first["active"] == ["3-101"] and "20" in first["failing"]
    assert res.active == ["3-101", "20"]
    assert res.verified and res.total_mw > 0
    rows = res.allocation()
    for f, t in ((faults[0], 0.2), (faults[1], 16 / 60)):
        assert independently_stable("kundur", f, t, rows)
    assert all(c["met"] for c in res.contingencies)
    assert all(r["mwh"] > 0 for r in rows)
    # at half the step both stay stable at their required times and their CCTs move by
    # no more than the resolution (the ieee default step's convergence claim: CCTs within
    # the 1 ms tolerance of a step-halved run, docs/conventions.md)
    hs = res.half_step
    assert [r["name"] for r in hs["rows"]] == sorted(
        ["3-101", "20"],
        key=lambda n: next(c["margin_s"] for c in res.contingencies if c["name"] == n),
    )
    assert hs["all_stable"] and hs["max_cct_diff_s"] <= 1e-9
    assert hs["h_s"] == Simulator(load_case("kundur")).default_h
    # the sized energies converge too: the half-step change of each site's energy need is
    # inside the ENERGY_MARGIN added on top of it
    need = [e["need_mwh"] for e in res.energy if e]
    assert 0 <= hs["max_energy_diff_mwh"] <= ENERGY_MARGIN * min(need)
    assert hs["max_energy_diff_pct"] <= 100 * ENERGY_MARGIN and hs["energy_covered_half"]
    # the least uniform fleet (the reference row of the placement reports), checked the
    # same way: its sized energies (margin and rounding included) cover the needs at half
    # the step.  The change itself is larger there (about 5 % at two of its four sites: a
    # speed difference grazing the deadband edge switches G2's device 80 ms later at the
    # full step), and reported beside the figure rather than bounded here
    u = res.uniform
    assert u["verified"] and u["energy_covered_half"]
    assert len([e for e in u["energy"] if e]) == len(u["mw_by_site"])
    assert u["max_energy_diff_mwh"] > 0


def testenergy_half_step_figures_by_hand():
    """`energy_half_step` on hand-made check results (energy_mj rows: absorbed, delivered,
    highest, lowest SOC, MJ; need = 2 max(high, -low) / 3600 MWh): changes in MWh and in %
    of each site's own need, a site with no need left out of the %, and the cover test
    against the sized MWh (margin and rounding included)."""
    from stabctl.placement.energy import energy_half_step

    mw = np.array([10.0, 0.0, 5.0, 2.0])
    energy = [
        {"set_by": "a", "need_mwh": 0.02},
        {},
        {"set_by": "b", "need_mwh": 0.01},
        {"set_by": "b", "need_mwh": 0.0},
    ]
    # the k-th site with storage reads row k of its setter's run (sites 0, 2, 3)
    half = {
        "a": {"energy_mj": [[0, 0, 36.0, -9.0], [], []]},  # need 0.02 -> 0.02
        "b": {
            "energy_mj": [
                [],
                [0, 0, 0.0, -27.0],  # 0.01 -> 0.015 (+50 %)
                [0, 0, 1.8, 0.0],
            ]
        },
    }  # 0 -> 0.001 (no %)
    e = energy_half_step(half, mw, np.array([0.03, 0.0, 0.02, 0.01]), energy)
    assert e["max_energy_diff_mwh"] == pytest.approx(0.005)
    assert e["max_energy_diff_pct"] == pytest.approx(50.0)
    assert e["energy_covered_half"]
    assert not energy_half_step(half, mw, np.array([0.03, 0.0, 0.012, 0.01]), energy)[
        "energy_covered_half"
    ]
    assert energy_half_step({}, np.zeros(4), np.zeros(4), [{}] * 4) == {
        "max_energy_diff_mwh": None,
        "max_energy_diff_pct": None,
        "energy_covered_half": None,
    }


def test_infeasible_requirement_names_the_contingency_and_its_load_level():
    sites = candidate_sites(load_case("kundur"), max_pct=0.5)  # 4.5 MW per site
    with pytest.raises(InfeasibleError, match=r"3-101@110%.*load 110 %") as exc:
        plan(
            "kundur",
            [LineFault(3, 101)],
            Requirement(cycles=12),
            PlanOptions(load_levels=(1.1,)),
            Study(sites=sites),
        )
    assert exc.value.contingencies == ("3-101@110%",)
    # set aside instead: named, and the rest planned for (9 cycles = 150 ms: the base load
    # needs no storage, CCT 154 ms; at 110 % the CCT without storage is 100 ms)
    res = plan(
        "kundur",
        [LineFault(3, 101)],
        Requirement(cycles=9),
        PlanOptions(load_levels=(1.0, 1.1), drop_infeasible=True),
        Study(sites=sites),
    )
    assert res.set_aside == ["3-101@110%"] and "load 110 %" in res.infeasible[0]
    assert [c["name"] for c in res.contingencies] == ["3-101"] and res.verified
    # every contingency set aside: nothing placed, and the message says so (it used to
    # read "verified on every contingency" with none left)
    res = plan(
        "kundur",
        [LineFault(3, 101)],
        Requirement(cycles=12),
        PlanOptions(load_levels=(1.1,), drop_infeasible=True),
        Study(sites=sites),
    )
    assert res.set_aside == ["3-101@110%"] and res.contingencies == []
    assert res.total_mw == 0 and "every contingency set aside" in res.message
    # and the printed label is not "VERIFIED" (nothing was verified: no plan)
    assert _plan_verdict(res.to_dict()) == "NOTHING TO PLACE"


def test_cli_place_with_a_clearing_time_requirement_and_bad_input(tmp_path):
    faults = tmp_path / "f.csv"
    faults.write_text("bus,far_bus,required_clearing_cycles\n3,101,11\n")
    r = CliRunner().invoke(
        main,
        [
            "place",
            "kundur",
            "--faults",
            str(faults),
            "--required-clearing-cycles",
            "10",
            "--cost-mwh",
            "100",
            "--workers",
            "1",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["verified"] and d["total_mw"] > 0 and d["total_mwh"] > 0
    assert d["contingencies"][0]["required_s"] == pytest.approx(0.184)  # 11 cycles
    assert d["cost"]["total"] == pytest.approx(d["cost"]["mw"] + d["cost"]["mwh"])
    assert d["cost"]["mwh"] == pytest.approx(100 * d["total_mwh"])
    out = tmp_path / "never.json"
    for args in (
        ["--required-clearing-cycles", "0"],
        ["--load-levels", "1,-1", "--required-clearing-cycles", "5"],
        ["--cost-mw", "-1", "--required-clearing-cycles", "5"],
        [],
    ):
        bad = CliRunner().invoke(
            main, ["place", "kundur", "--faults", "DEFAULT", *args, "--out", str(out)]
        )
        assert bad.exit_code == 2, bad.output
        assert bad.output.startswith("error:") and bad.output.count("\n") == 1
        assert not out.exists()


def test_the_records_screen_writes_are_screening_records_to_place(tmp_path):
    """Round 48: since a bus fault's circuit is null in the records (2026-11-30), `place
    --screening` refused every file `stabctl screen` writes ("None is not a number >=
    1"), docs/placement.md's IEEE 39 example included.  A real screening's records,
    a bus fault's and a line fault's, give their brackets."""
    from click.testing import CliRunner

    from stabctl.cli import main
    from stabctl.placement.requirements import screening_brackets

    out = tmp_path / "s.jsonl"
    args = ["screen", "kundur", "--buses", "3", "--lines", "--t-max", "0.3", "--workers", "1"]
    res = CliRunner().invoke(main, [*args, "--out", str(out), "--json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    brackets = screening_brackets(out, "kundur", load_case("kundur").digest())
    assert brackets["3"] == pytest.approx((0.238, 0.239))  # the bus fault's CCT cell
    lines = [r for r in rows if r["far_bus"] is not None and r["verdict"] == "cct"]
    assert lines and all(f"{r['bus']}-{r['far_bus']}" in brackets for r in lines)


def test_screening_brackets_and_requirement_overrides_are_read_from_their_files(tmp_path):
    from stabctl.placement.requirements import read_requirements, screening_brackets

    rec = tmp_path / "s.jsonl"
    ok = {
        "key": "k1",
        "status": "ok",
        "inputs": {"esd_pct": None},
        "result": {
            "fault": {"bus": 3, "far_bus": 101, "t_fault": 1.0, "circuit": 1, "trips": []},
            "cct_s": 0.155,
            "cct_cycles": 9.3,
            "t_stable_s": 0.155,
            "t_unstable_s": 0.16,
            "n_simulations": 12,
            "separated_machines": [1],
        },
    }
    bus = {
        **ok,
        "key": "k2",
        "result": {
            **ok["result"],
            # records written since the fault's start is "t_fault_s" (ok's: before)
            "fault": {"bus": 1, "far_bus": None, "t_fault_s": 1.0, "circuit": 1, "trips": []},
        },
    }
    stored = {**ok, "key": "k3", "inputs": {"esd_pct": 5.0}}  # with storage
    failed = {"key": "k4", "status": "failed", "inputs": {"esd_pct": None}, "error": "x"}
    rec.write_text("\n".join(json.dumps(r) for r in (ok, bus, stored, failed)) + "\n")
    assert screening_brackets(rec, "kundur", "any") == {"3-101": (0.155, 0.16), "1": (0.155, 0.16)}
    # a record no search can have written (a CCT NaN): the file is refused, as sweep-cct
    # sets such a line aside as damaged
    damaged = {**ok, "key": "k5", "result": {**ok["result"], "cct_s": float("nan")}}
    rec.write_text("\n".join(json.dumps(r) for r in (ok, damaged)) + "\n")
    with pytest.raises(InputError, match=r"s\.jsonl.*2.*result\.cct_s NaN is not a clearing"):
        screening_brackets(rec, "kundur", "any")
    csv = tmp_path / "f.csv"
    csv.write_text(
        "bus,far_bus,required_clearing_cycles,target_cct_s\n3,101,6,\n1,,,0.3\n13,101,,\n"
    )
    req = read_requirements(csv)
    assert set(req) == {"3-101", "1"}
    assert req["3-101"].target_s(60.0, 1e-3) == pytest.approx(0.1)
    assert req["1"].target_s(60.0, 1e-3) == pytest.approx(0.3)
    csv.write_text("bus,far_bus,required_clearing_cycles\n3,101,-2\n")
    with pytest.raises(InputError, match=r"f\.csv:2: required_clearing_cycles -2 is outside"):
        read_requirements(csv)


def test_cli_place_with_wecc_batteries_sizes_them_by_their_own_runs(tmp_path):
    """`place --esd-model wecc`: the evaluations and checks simulate WECC batteries (their
    lags and current limit), so the least allocation for Kundur's 3-101 at 11 cycles is
    larger than with ideal devices (measured 120.1 MW against 87.8 MW, both at bus 110),
    and an independent run of the batteries cleared at the required time is stable, of
    batteries sized as the ideal devices unstable."""
    faults = tmp_path / "f.csv"
    faults.write_text("bus,far_bus,required_clearing_cycles\n3,101,11\n")
    args = ["place", "kundur", "--faults", str(faults), "--required-clearing-cycles", "10"]
    runs = {}
    for model in ("ideal", "wecc"):
        r = CliRunner().invoke(main, [*args, "--workers", "1", "--esd-model", model, "--json"])
        assert r.exit_code == 0, r.output
        runs[model] = json.loads(r.stdout)
    d = runs["wecc"]
    assert d["esd_model"] == "wecc" and d["verified"]
    assert d["total_mw"] > 1.1 * runs["ideal"]["total_mw"]
    devices = tuple(StorageDevice(a["bus"], a["machine"], a["mw"]) for a in d["allocation"])
    sim = Simulator(load_case("kundur"))
    fleet = StorageFleet(devices, BangBangCOI(), model="wecc")
    fault = LineFault(3, 101)
    assert sim.run(fault.events(0.184), 6.0, storage=fleet, stop_at_separation=True).stable
    ideal = runs["ideal"]["allocation"]  # batteries sized as ideal devices are too small
    small = StorageFleet(
        tuple(StorageDevice(a["bus"], a["machine"], a["mw"]) for a in ideal), model="wecc"
    )
    assert not sim.run(fault.events(0.184), 6.0, storage=small, stop_at_separation=True).stable


def test_placement_jobs_simulate_the_devices_of_their_esd_model():
    """The worker jobs build their fleet of the job's ``esd_model`` (default ideal), in
    `evaluate` and `check` alike: 88 MW at bus 110 (the ideal allocation for Kundur's
    3-101 at 11 cycles, 87.8 MW, rounded up) holds that fault at 11 cycles as an ideal
    device and not as a WECC battery, its CCT (bisection to 1 ms) 184 ms against
    180 ms."""
    ctrl = controller_dict(BangBangCOI())
    job = {
        "case": "kundur",
        "fault": fault_inputs(LineFault(3, 101)),
        "devices": [[110, 3, 88.0]],
        "sites": [[110, 3]],
        "controller": ctrl,
    }
    assert _fleet(job, BangBangCOI()).model == "ideal"
    fleet = _fleet({**job, "devices": [[110, 3, 88.0, 90.0]], "esd_model": "wecc"}, BangBangCOI())
    assert fleet.model == "wecc" and fleet.devices[0].energy_mj == 90.0
    assert _fleet({**job, "devices": [], "esd_model": "wecc"}, BangBangCOI()) is None
    cct = {}
    for model in ("ideal", "wecc"):
        j = {**job, **model_inputs(model)}
        assert check({**j, "t_clear": 11 / 60})["stable_at_check"] is (model == "ideal")
        search = {"beta": [[0.0]] * 4, "tol": 0.001, "t_max": 0.5, "gradient": False}
        cct[model] = evaluate({**j, **search})["cct_s"]
    assert cct == {"ideal": pytest.approx(0.184), "wecc": pytest.approx(0.180)}


def test_ideal_jobs_keep_their_inputs_and_wecc_jobs_name_their_model():
    """`verify` and `PlanContext.check` add ``esd_model`` to their jobs for batteries only:
    the ideal default's jobs are the inputs they were before the option."""
    sites = candidate_sites(load_case("kundur"))
    fault = Contingency(LineFault(3, 101), 0.2)
    jobs = []

    def run_map(func, batch):
        jobs.extend(batch)
        return [{"stable_at_check": True} for _ in batch]

    mw = [0.0, 0.0, 50.0, 0.0]
    for model in ("ideal", "wecc"):
        ev = Evaluator(run_map, "kundur", sites, np.zeros((4, 4)), BangBangCOI(), esd_model=model)
        verify(ev, [fault], mw)
        pl = PlanContext(
            "kundur", sites, CostModel(), BangBangCOI(), ModelOptions(), run_map, 0.001, 0.5, print
        )
        replace(pl, esd_model=model).check([fault], mw)
    assert ["esd_model" in j for j in jobs] == [False, False, True, True]
    assert {j.get("esd_model") for j in jobs[2:]} == {"wecc"}


def test_cli_place_rejects_an_unknown_esd_model_and_damping_rows_for_batteries():
    """--esd-model takes ideal or wecc (exit 2); --zeta-min with batteries is refused
    before any run (the damping model has ideal devices)."""
    args = ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "3"]
    r = CliRunner().invoke(main, [*args, "--esd-model", "foo"])
    assert r.exit_code == 2 and "'foo' is not one of 'ideal', 'wecc'" in r.output
    r = CliRunner().invoke(main, [*args, "--esd-model", "wecc", "--zeta-min", "0.05"])
    assert r.exit_code == 2 and r.output.startswith("error: --zeta-min with --esd-model wecc")
    check_damping_model(0.05, "ideal")
    check_damping_model(None, "wecc")
    with pytest.raises(InputError, match="not a WECC battery"):
        check_damping_model(0.0, "wecc")


def test_a_missing_sime_slope_falls_back_to_a_cct_difference(monkeypatch):
    """Where SIME's margin gives no slope near the CCT (WECC-179's fault 169-170 stopped a
    placement with "no SIME margin slope"), `evaluate` differences the CCT itself: the CCT
    again with the fleet's rating raised by 25 % (at least 50 MW) along its own direction,
    the slope given to every site.  Kundur's 3-101 with 88 MW at bus 110: the cut it
    gives is exact along that direction (the CCT at 138 MW, bisected independently, equals
    the cut's prediction), the slope positive (storage helps), the loop never stopped."""
    import stabctl.placement.evaluation as ev

    def no_slope(*args, **kwargs):
        raise ev.NoMarginSlope("no SIME margin slope (forced)")

    monkeypatch.setattr(ev, "cct_gradient", no_slope)
    job = {
        "case": "kundur",
        "fault": fault_inputs(LineFault(3, 101)),
        "devices": [[110, 3, 88.0]],
        "sites": [[110, 3], [120, 4]],
        "controller": controller_dict(BangBangCOI()),
        "beta": [[0.0, 0.0]] * 4,
        "tol": 0.001,
        "t_max": 0.5,
    }
    out = evaluate(job)
    assert out["slope_from"] == "CCT difference" and out["cct_s"] == pytest.approx(0.184)
    g = np.asarray(out["gradient_s_per_mw"])
    assert g.shape == (2,) and g[0] == g[1] > 0
    more = evaluate({**job, "devices": [[110, 3, 138.0]], "gradient": False})
    assert out["cct_s"] + 50.0 * g[0] == pytest.approx(more["cct_s"], abs=1e-12)


def test_a_round_whose_loop_verifies_nothing_restarts_from_the_least_uniform_fleet(monkeypatch):
    """The first round's loop is made to report no verified allocation (as WECC-179's
    75-77 did, storage lowering its CCT everywhere the loop looked): the plan finds the
    least uniform fleet meeting the active set by its check runs, starts the next round
    there, and ends verified with no more MW than that fleet (the loop from a feasible
    start returns nothing costlier); an independent run cleared at the required time is
    stable with the plan and unstable without storage."""
    import stabctl.placement.plan as plan_module

    real, calls = plan_module.place, []

    def first_unverified(*args, **kwargs):
        res = real(*args, **kwargs)
        calls.append(kwargs.get("warm", args[4] if len(args) > 4 else None))
        return res if len(calls) > 1 else replace(res, verified=False, message="forced")

    monkeypatch.setattr(plan_module, "place", first_unverified)
    fault = LineFault(3, 101)
    res = plan("kundur", [fault], Requirement(cycles=11), PlanOptions(max_rounds=3))
    first = res.rounds[0]
    assert not first["loop_verified"] and first["uniform_start_pct"] > 0
    assert len(calls) == 2 and res.verified
    start = np.asarray(calls[1].start)
    pct = first["uniform_start_pct"]
    mva = np.array([900.0] * 4)  # Kundur's four machines, 900 MVA each
    assert start == pytest.approx(np.ceil(pct / 100 * mva * 10 - 1e-6) / 10)
    assert res.total_mw <= start.sum() + 1e-9
    t = res.contingencies[0]["required_s"]
    assert independently_stable("kundur", fault, t, res.allocation())
    assert not independently_stable("kundur", fault, t, [])
    # with a single round the plan ends at that uniform fleet: checked there and verified
    # (it used to size the energies from the checks of the loop's allocation, other
    # sites: IndexError)
    calls.clear()
    one = plan("kundur", [fault], Requirement(cycles=11), PlanOptions(max_rounds=1))
    assert one.rounds[0]["uniform_start_pct"] == pct and len(calls) == 1
    assert one.verified and "the allocation the last round left" in one.message
    assert one.total_mw == pytest.approx(start.sum())
    assert independently_stable("kundur", fault, t, one.allocation())


def test_a_last_round_that_sets_aside_keeps_an_allocation_meeting_the_rest(monkeypatch):
    """The last round's loop proves a contingency infeasible (forced here for the bus-20
    fault, which fails its check at the first round's allocation): set aside, the
    allocation the round started from is checked on what is left.  It meets the 3-101
    fault (its loop verified it there), so the plan ends verified at that allocation,
    confirmed by an independent run cleared at the required time (stable with the plan,
    unstable without storage), instead of "not verified after 2 rounds"."""
    import stabctl.placement.plan as plan_module

    real, calls = plan_module.place, []

    def second_infeasible(*args, **kwargs):
        calls.append(args[1])
        if len(calls) > 1:
            raise InfeasibleError("infeasible: forced", ["20"])
        return real(*args, **kwargs)

    monkeypatch.setattr(plan_module, "place", second_infeasible)
    faults = [LineFault(3, 101), LineFault(20, None)]
    res = plan(
        "kundur",
        faults,
        Requirement(cycles=12),
        PlanOptions(
            overrides={"20": Requirement(cycles=16)},
            n_active=1,
            max_rounds=2,
            drop_infeasible=True,
        ),
    )
    assert [[c.name for c in active] for active in calls] == [["3-101"], ["3-101", "20"]]
    assert "20" in res.rounds[0]["failing"] and res.set_aside == ["20"]
    assert res.verified and "the allocation the last round left" in res.message
    assert res.total_mw == pytest.approx(res.rounds[0]["total_mw"])
    assert [c["name"] for c in res.contingencies] == ["3-101"] and res.contingencies[0]["met"]
    assert independently_stable("kundur", faults[0], 0.2, res.allocation())
    assert not independently_stable("kundur", faults[0], 0.2, [])


def test_sites_that_share_a_bus_are_counted_with_their_buses(capsys):
    """One site per machine: two machines behind one HV bus (as Nordic 44's five units at
    bus 6100) make two sites on one bus, and the plan's summary says so; a third site
    left at 0 MW counts neither."""
    from stabctl.cli.format import print_plan
    from stabctl.placement.plan import PlanResult
    from stabctl.placement.program import Site

    sites = (Site(6100, 1, 100.0), Site(6100, 2, 100.0), Site(10, 3, 100.0))
    res = PlanResult(
        case="x", requirement="CCT +5 %", load_levels=(1.0,), sites=sites,
        mw=np.array([10.0, 20.0, 0.0]), mwh=np.array([0.1, 0.2, 0.0]),
        cost={"total": 30.0, "mw": 30.0, "mwh": 0.0, "site": 0.0}, verified=True,
        contingencies=[], rounds=[], active=[], message="verified",
    )  # fmt: skip
    d = res.to_dict()
    assert (d["n_sites"], d["n_buses"]) == (2, 1)
    case = load_case("kundur")  # its machines 1-3 name the sites' machines
    print_plan(case, d)
    out = capsys.readouterr().out
    assert "0.30 MWh at 2 site(s) on 1 bus, cost 30.0" in out
    rows = [line.split() for line in out.splitlines() if line.startswith("  6100")]
    assert [" ".join(r[5:]) for r in rows] == [case.machine_name(1), case.machine_name(2)]


def test_a_law_armed_per_contingency_is_the_cct_command_s_critical_reference():
    """`Study(critical_reference=True)` (``place --coi critical``): each contingency's
    devices take the other group's COI, the group the machines its fault separates
    without storage.  Kundur 3-101 with 10 % of every machine's MVA at its HV bus: the
    CCT of the placement's evaluation equals `stabctl cct kundur --fault 3 --far-bus
    101 --esd-pct 10 --coi critical` (0.251 s, group machines 1 and 2), as without it the
    paper's law equals the command's (0.235 s); the check run at the CCT is stable, 1 ms
    later not."""
    from stabctl.placement.loop import evaluations

    case = load_case("kundur")
    sites = candidate_sites(case)
    mw = [0.2 * s.max_mw for s in sites]  # 10 % of MVA: the sites' bound is 50 %
    con = Contingency(LineFault(3, 101, 1.0), 0.3)
    study = Study(critical_reference=True)
    ev = evaluations("kundur", [con], mw, study, VerifyOptions(gradient=False))[con.name]

    def cct_command(*law):
        argv = ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "10"]
        return json.loads(CliRunner().invoke(main, [*argv, *law, "--json"]).output)

    d = cct_command("--coi", "critical")
    assert d["critical_group"]["machines"] == [1, 2]
    assert ev["cct_s"] == pytest.approx(d["cct_s"], abs=1e-12) == pytest.approx(0.251)
    paper = evaluations("kundur", [con], mw, Study(), VerifyOptions(gradient=False))
    assert paper[con.name]["cct_s"] == pytest.approx(cct_command()["cct_s"], abs=1e-12)
    assert paper[con.name]["cct_s"] == pytest.approx(0.235)
    ctx = PlanContext(
        "kundur", sites, CostModel(), BangBangCOI(), ModelOptions(), None, 1e-3, 1.0, print
    )
    ctx = replace(ctx, critical_reference=True, run_map=lambda f, jobs: [f(j) for j in jobs])
    for t, stable in ((0.251, True), (0.252, False)):
        c = Contingency(con.fault, t)
        assert ctx.check([c], mw)[c.name]["stable_at_check"] is stable


def test_a_law_armed_per_contingency_needs_a_critical_group():
    """A contingency still stable at the search limit without storage has no critical
    group: the armed law is refused naming the fault, as `cct --coi critical` refuses it."""
    job = {
        "case": "kundur",
        "fault": fault_inputs(LineFault(3, 101, 1.0)),
        "devices": [[10, 1, 90.0]],
        "sites": [[10, 1]],
        "controller": controller_dict(BangBangCOI(), {"tol": 1e-3, "t_max": 0.1}),
        "t_clear": 0.1,
    }
    with pytest.raises(
        InputError,
        match=r"--coi critical: fault at bus 3 on line 3-101 .*"
        r"no critical group without storage",
    ):
        check(job)
    argv = ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "5"]
    cli = CliRunner().invoke(main, [*argv, "--coi", "critical", "--t-max", "0.1"])
    assert cli.exit_code == 2 and "no critical group without storage" in cli.output


def test_place_coi_critical_names_its_law_in_its_header_and_json(tmp_path):
    """`place kundur --coi critical` for fault 3-101 at +20 % (0.154 s without storage,
    target 0.185 s on the 1 ms lattice): the plan is verified, its header names the law,
    its JSON records it (coi "critical"; the group, found per contingency: null)."""
    faults = tmp_path / "f.csv"
    faults.write_text("bus,far_bus\n3,101\n")
    argv = ["place", "kundur", "--faults", str(faults), "--target-cct-gain", "20"]
    argv += ["--coi", "critical", "--workers", "1"]
    d = json.loads(CliRunner().invoke(main, [*argv, "--json"]).output)
    assert d["settings"]["controller"]["coi"] == "critical"
    assert d["settings"]["controller"]["critical"] is None
    assert d["settings"]["step_s"] == 0.005  # the case's default step, as cct --json says
    (row,) = d["contingencies"]
    assert row["cct_no_storage_s"] == pytest.approx(0.154) and row["met"]
    assert row["cct_s"] >= row["required_s"] == pytest.approx(0.185)
    text = CliRunner().invoke(main, argv).output
    assert "each contingency's critical machines without storage (--coi critical)" in text


def test_a_stable_clearing_above_the_cct_meets_no_requirement(tmp_path):
    """Kundur's 13-101 at the default step: CCT 0.408 s, unstable cleared at 0.409-0.600 s
    and stable again at 0.601 s (its swing turns at 3.133 rad).  A required CCT of 0.601 s
    (47.3 % above its CCT) was 'VERIFIED (every contingency is stable without storage)',
    0 MW, from one run at 0.601 s: the requirement is refused by name, or the contingency
    set aside with its reason."""
    import json

    from click.testing import CliRunner

    from stabctl.cli import main

    faults = tmp_path / "f.csv"
    faults.write_text("bus,far_bus\n13,101\n")
    args = ["place", "kundur", "--faults", str(faults), "--workers", "1"]
    for req in (["--target-cct-gain", "47.3"], ["--target-cct-s", "0.601"]):
        res = CliRunner().invoke(main, [*args, *req])
        assert res.exit_code == 2, res.output
        assert (
            "error: not monotone: 13-101: stable cleared at its required 0.601 s without "
            "storage, yet its CCT without storage is 0.408 s" in res.output
        )
    res = CliRunner().invoke(main, [*args, "--target-cct-s", "0.601", "--set-aside-infeasible",
                                    "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    plan = json.loads(res.stdout)
    assert plan["set_aside"] == ["13-101"] and plan["total_mw"] == 0.0
    assert plan["infeasible"][0].startswith("not monotone: 13-101")


def test_a_plan_s_header_names_a_law_other_than_the_paper_s(tmp_path):
    """A plan sized for a 0.7 pu gate and a 50 mHz deadband printed like the paper's law:
    the header names each setting that is not the paper's (round 37)."""
    from click.testing import CliRunner

    from stabctl.cli import main

    faults = tmp_path / "f.csv"
    faults.write_text("bus,far_bus\n13,101\n")
    args = ["place", "kundur", "--faults", str(faults), "--target-cct-s", "0.3", "--workers", "1"]
    head = CliRunner().invoke(main, [*args, "--v-gate", "0.7", "--deadband-hz", "0.05"])
    assert head.exit_code == 0, head.output
    assert "ESDs, deadband 0.05 Hz (--deadband-hz), voltage gate 0.7 pu (--v-gate)):" in (
        head.output
    )
    paper = CliRunner().invoke(main, args)
    assert "(CCT 300 ms; load levels 1; ESDs):" in paper.output


def test_a_plan_s_verdicts_are_shown_at_half_the_step(tmp_path):
    """`place` never checked its plan at half the step (its margins are often 0 ms, 13-101
    required 0.449 s and met at 0.449 s): every contingency is run again at h/2, cleared at
    its required time with the allocation, and the text and JSON say so (round 37)."""
    import json

    from click.testing import CliRunner

    from stabctl.cli import main

    faults = tmp_path / "f.csv"
    faults.write_text("bus,far_bus\n3,101\n13,101\n")
    args = ["place", "kundur", "--faults", str(faults), "--target-cct-gain", "10", "--workers", "1"]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    hs = json.loads(res.stdout)["half_step"]
    assert hs["h_s"] == 0.005 and hs["all_stable"] and hs["energy_covered_half"]
    assert sorted(r["name"] for r in hs["rows"]) == ["13-101", "3-101"]
    assert all(r["stable_half"] and r["cct_half_s"] is None for r in hs["rows"])
    text = CliRunner().invoke(main, args).output
    assert "half the step (2.5 ms): 2 of 2 contingencies stable at their required time" in text


def test_a_plan_names_its_armed_groups_and_its_chattering():
    """A --coi critical plan did not record the machines its law was armed on, and a plan
    with no deadband never said that 293 of its fleet's 342 switchings on 3-101 came
    within 20 ms of the one before (round 37): each contingency's row carries both, from
    its run at the required time with the allocation, and the text says them."""
    import json

    from click.testing import CliRunner

    from stabctl.cli import main

    args = ["place", "kundur", "--faults", "DEFAULT", "--workers", "1"]
    armed = CliRunner().invoke(main, [*args, "--target-cct-gain", "10", "--coi", "critical"])
    assert armed.exit_code == 0, armed.output
    assert "  3-101: the law armed on G1 (bus 1), G2 (bus 2)" in armed.output
    res = CliRunner().invoke(
        main, [*args, "--target-cct-gain", "30", "--deadband-hz", "0", "--json"]
    )
    rows = {r["name"]: r for r in json.loads(res.stdout)["contingencies"]}
    # how many of a bang-bang law's switchings chatter without a deadband depends on the
    # last bits of the arithmetic (342/293 and 350/302 with other numpy, scipy releases):
    # most of hundreds of them
    n, chattering = rows["3-101"]["switchings"], rows["3-101"]["chattering"]
    assert n > 200 and 0.7 < chattering / n < 0.95, (n, chattering)
    assert rows["3-101"]["critical_group"] is None
    text = CliRunner().invoke(main, [*args, "--target-cct-gain", "30", "--deadband-hz", "0"])
    assert (
        f"  3-101: at its required time, {n} switchings; {chattering} of the switchings "
        "chattering (within 20 ms of the device's previous one)" in text.output
    )


def test_a_plan_s_total_is_summed_to_the_watt():
    """A plan's JSON gave total_mw 134.10000000000002 for three sites of 44.7 MW."""
    from stabctl.placement.program import total_mw

    assert sum([44.7, 44.7, 44.7]) != 134.1
    assert total_mw([44.7, 44.7, 44.7]) == 134.1 and total_mw([]) == 0.0


def test_a_plan_says_its_runs_end_and_sets_an_n1_insecure_fault_aside(tmp_path):
    """Round 42: `place` called VERIFIED, in the 5-s window of its checks, a plan whose
    allocation cleared at the required time loses synchronism run longer, where `cct`
    says NOT CONVERGED IN THE RUN'S END (Kundur's 1-10: its trip islands G1 and the rest
    drifts out of step 5-10 s after the fault); and an N-1 insecure fault (2-20) stopped
    the whole plan, --set-aside-infeasible or not.  Now 1-10's CCT without storage
    carries `cct`'s own check, its check run 5 s longer with the allocation loses
    synchronism where an independent simulation does, and the plan is "VERIFIED in the
    5-s window"; 2-20 is set aside as N-1 insecure (`critical_clearing_time`'s verdict),
    and without the flag the refusal says how to set it aside."""
    from stabctl.errors import InsecureContingency
    from stabctl.stability.cct import SearchOptions, critical_clearing_time
    from stabctl.storage.control import BangBangCOI
    from stabctl.storage.devices import StorageDevice, StorageFleet

    csv = tmp_path / "f.csv"
    csv.write_text("bus,far_bus\n2,20\n1,10\n")
    args = ["place", "kundur", "--faults", str(csv), "--target-cct-gain", "5", "--t-max", "0.5"]
    args += ["--workers", "1"]
    refused = CliRunner().invoke(main, args)
    assert refused.exit_code == 2 and "N-1 insecure" in refused.output, refused.output
    assert "--set-aside-infeasible" in refused.output
    res = CliRunner().invoke(
        main, [*args, "--set-aside-infeasible", "--out", str(tmp_path / "p.json")]
    )
    assert res.exit_code == 0, res.output
    d = json.loads((tmp_path / "p.json").read_text())
    case = load_case("kundur")
    sim = Simulator(case)
    with pytest.raises(InsecureContingency):
        critical_clearing_time(sim, LineFault(2, 20, 1.0), SearchOptions(t_max=0.5))
    assert list(d["n1_insecure"]) == ["2-20"] and "N-1 insecure" in d["n1_insecure"]["2-20"]
    assert "set aside as N-1 insecure: 2-20: " in res.stdout
    # the CCT without storage and its run's end, as `cct` gives them
    ref = json.loads(
        CliRunner()
        .invoke(
            main, ["cct", "kundur", "--fault", "1", "--far-bus", "10", "--t-max", "0.5", "--json"]
        )
        .stdout
    )
    (row,) = d["contingencies"]
    assert row["cct_no_storage_s"] == ref["cct_s"]
    assert row["cct_no_storage_run_end_check"] == ref["run_end_check"]
    # and its trip's islanding, G1 lost, as `cct` names it (round 59 BC03: "met" without
    # a word that the CCT judges the rest of the system)
    assert row["islanded"] == ref["islanded"] and row["islanded"][0]["machines"] == [1]
    assert "  1-10: the contingency's trip: " in res.stdout
    # the check run 5 s longer, against the same run simulated here
    fault = LineFault(1, 10, 1.0)
    rows = d["allocation"]
    fleet = StorageFleet(
        tuple(StorageDevice(r["bus"], r["machine"], r["mw"]) for r in rows), BangBangCOI()
    )
    longer = sim.run(fault.events(row["required_s"]), 11.0, storage=fleet, stop_at_separation=True)
    assert not longer.stable
    assert row["run_end_check"]["t_end_s"] == 11.0
    assert row["run_end_check"]["t_separation_s"] == pytest.approx(longer.t_separation)
    assert stable_when_cleared(case, fault, row["required_s"], rows) and row["met"]
    assert d["verified"] and d["run_end"]["not_converged"] == ["1-10"]
    assert d["run_end"]["window_s"] == 5.0
    head = res.stdout.splitlines()[0]
    assert "VERIFIED in the 5-s window" in head and "NOT CONVERGED IN THE RUN'S END (1-10)" in head
    assert (
        f"  1-10: NOT CONVERGED IN THE RUN'S END: cleared at its required "
        f"{row['required_s']:.3f} s with the allocation, the run to t = 11 s loses synchronism"
    ) in res.stdout


def test_a_contingency_met_without_storage_is_named_not_left_out():
    """Round 45: with 12 cycles required, Kundur's 13-101 (CCT 0.408 s without storage)
    needs nothing; the plan said "2 of 2 contingencies stable" and its table showed 3-101
    alone.  The text names it as met without storage; the JSON row holds both CCTs."""
    args = ["place", "kundur", "--faults", "DEFAULT", "--required-clearing-cycles", "12"]
    text = CliRunner().invoke(main, [*args, "--workers", "1"]).output
    assert "2 of 2 contingencies stable at their required clearing time" in text
    assert "met without storage (their CCT without storage at or above the required " in text
    assert text.split("met without storage", 1)[1].split("\n", 1)[0].endswith(": 13-101")
    d = json.loads(CliRunner().invoke(main, [*args, "--workers", "1", "--json"]).stdout)
    row = {r["name"]: r for r in d["contingencies"]}["13-101"]
    assert row["met"] and row["cct_s"] is None and row["cct_no_storage_s"] >= row["required_s"]
