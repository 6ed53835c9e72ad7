"""The SIME-guided CCT search and the runs' early verdicts (`stabctl.stability.sime`):
each early verdict equals the full run's (the reference: the run to fault + 5 s judged by
the pi-from-the-COI criterion), and the search ends in the bisection's 1 ms cell."""

import json

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.results import LOSS_OF_SYNCHRONISM, STOPPED, SimulationResult
from stabctl.errors import InputError, SimulationError
from stabctl.io import load_case
from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time
from stabctl.stability.screening import screening_faults
from stabctl.stability.sime import EarlyVerdict

#: clearing times (s) every screened fault is run at, full and with early verdicts, beside
#: the ends of its bisection bracket and 5 ms above it (where late separations hide)
CLEARING_S = (0.05, 0.1, 0.2)


def early_and_full(sim, fault: LineFault, tc: float):
    """(verdict of the monitored run, its end s, the full run's verdict, its end s)."""
    t_end = fault.t_fault + 5.0
    full = sim.run(fault.events(tc), t_end, stop_at_separation=True)
    early = sim.run(
        fault.events(tc),
        t_end,
        stop_at_separation=True,
        monitor=EarlyVerdict(fault.t_fault + tc, t_end, sim.case.freq_hz),
    )
    verdict = early.meta.get("early_verdict")
    ok = verdict == "stable" if verdict else early.stable
    return ok, float(early.t[-1]), full.stable, float(full.t[-1])


def mismatches(name: str, every: int = 1):
    """Screened faults (buses and lines, every `every`-th) whose early verdict differs
    from the full run's at CLEARING_S and around the bisection's CCT, and the fraction
    of simulated time the early stops saved."""
    sim = Simulator(load_case(name))
    bisection = SearchOptions(method="bisection", early_stop=False, error_check=False)
    bad, t_early, t_full = [], 0.0, 0.0
    for fault in screening_faults(sim.case, lines=True)[::every]:
        times = list(CLEARING_S)
        try:
            ref = critical_clearing_time(sim, fault, bisection)
            times += [ref.t_stable, ref.t_unstable, ref.t_unstable + 0.005]
        except InputError:  # N-1 insecure, above t_max: no bracket
            pass
        for tc in times:
            try:
                ok, te, ok_full, tf = early_and_full(sim, fault, tc)
            except (SimulationError, InputError):  # no verdict either way (e.g. islanding)
                continue
            t_early, t_full = t_early + te - fault.t_fault, t_full + tf - fault.t_fault
            if ok != ok_full:
                bad.append((fault, tc, ok, ok_full))
    return bad, 1 - t_early / t_full


def test_monitored_run_is_the_same_trajectory_up_to_its_stop(kundur, tmp_path):
    fault = LineFault(3, 101)
    full = kundur.run(fault.events(0.1), 6.0)
    seen = []
    part = kundur.run(fault.events(0.1), 6.0, monitor=lambda r: seen.append(r.t[-1]))
    assert np.array_equal(part.angle, full.angle) and np.array_equal(part.vmag, full.vmag)
    assert len(seen) > 50 and "early_verdict" not in part.meta
    stopped = kundur.run(
        fault.events(0.1), 6.0, monitor=lambda r: "stable" if r.t[-1] > 2 else None
    )
    n = stopped.t.size
    assert stopped.meta["early_verdict"] == "stable" and 2 < stopped.t[-1] < 2.2
    assert np.array_equal(stopped.angle, full.angle[:n])
    # round 30: a run its monitor stopped read "stable" (a 30-cycle fault, unstable, stopped
    # at 1.5 s); a monitor's 5 or 0 stopped the run as a string does
    long_fault = kundur.run(
        fault.events(0.5), 6.0, monitor=lambda r: "stop" if r.t[-1] > 1.5 else None
    )
    assert long_fault.verdict == STOPPED and long_fault.summary()["stable"] is None
    # round 43: written to .npz and read back it said "stable" (the monitor's word was in
    # `meta`, which the file did not hold)
    back = SimulationResult.from_npz(long_fault.to_npz(tmp_path / "stopped.npz"))
    assert back.verdict == STOPPED and back.meta == {"early_verdict": "stop"}
    again = SimulationResult.from_npz(full.to_npz(tmp_path / "full.npz"))
    assert again.verdict == "stable" and again.meta == {}
    assert kundur.run(fault.events(0.5), 6.0).verdict == LOSS_OF_SYNCHRONISM
    for odd in (5, 0, b"stop"):
        with pytest.raises(TypeError, match=r"run\(monitor\): a monitor returns None .* got"):
            kundur.run(fault.events(0.1), 2.0, monitor=lambda r, odd=odd: odd)


def test_early_verdicts_equal_full_runs_on_kundurs_screening():
    bad, saved = mismatches("kundur")
    assert bad == []
    assert saved > 0.05  # simulated time saved


@pytest.mark.heavy
def test_early_verdicts_equal_full_runs_on_a_twentieth_of_miniweccs_screening():
    """Every twentieth fault of miniWECC's bus and line screening, about a minute and a
    half of a core (the whole screening: the ``slow`` test below)."""
    bad, saved = mismatches("miniwecc", every=20)
    assert bad == []
    assert saved > 0.0


@pytest.mark.slow
@pytest.mark.timeout(3600)
def test_early_verdicts_equal_full_runs_on_miniweccs_whole_screening():
    """Every bus and line fault of miniWECC (about 20 minutes on one core)."""
    bad, _ = mismatches("miniwecc")
    assert bad == []


@pytest.mark.parametrize(("bus", "far_bus"), [(3, 101), (13, 101), (13, 14), (3, None), (1, None)])
def test_sime_search_ends_in_the_bisections_cell(kundur, bus, far_bus):
    fault = LineFault(bus, far_bus)
    ref = critical_clearing_time(kundur, fault, SearchOptions(method="bisection"))
    res = critical_clearing_time(kundur, fault, SearchOptions(method="sime", early_stop=True))
    assert res.bracket == ref.bracket and res.cct_half_step_s == ref.cct_half_step_s
    assert res.n_simulations == len(res.probes) + len(res.half_step_probes)
    assert res.to_dict()["n_simulations"] == res.n_simulations


def search_outcome(sim, fault: LineFault, options: SearchOptions):
    """A search's outcome: the result, or the verdict's name (N-1 insecure, above t_max)."""
    try:
        return critical_clearing_time(sim, fault, options)
    except InputError as exc:
        return type(exc).__name__


def test_sime_search_equals_the_bisection_on_kundurs_screening_with_fewer_runs(kundur):
    """Every bus and line fault of Kundur's screening: the same verdict, 1 ms cell and
    half-step CCT as the bisection (the reference search), in fewer simulations per CCT
    on average (the bound is the bisection's count on the same faults; 5 runs per CCT is
    out of reach: the two ends of the cell and their reruns at h/2 already make 4, and
    SIME's margins of runs far from the CCT place no probe within a cell of it,
    `benchmarks/bench_cct.py`).  Line 3-4 is N-1 insecure although stable when cleared
    at 30-67 ms: the check at 0 runs because the first probe, 0.1 s, is unstable."""
    runs = {"bisection": [], "sime": []}
    for fault in screening_faults(kundur.case, lines=True):
        ref = search_outcome(kundur, fault, SearchOptions(method="bisection"))
        res = search_outcome(kundur, fault, SearchOptions(method="sime"))
        if isinstance(ref, str):
            assert res == ref, fault
            continue
        assert not isinstance(res, str), fault
        assert (res.bracket, res.cct_half_step_s) == (ref.bracket, ref.cct_half_step_s), fault
        runs["bisection"].append(ref.n_simulations)
        runs["sime"].append(res.n_simulations)
    assert len(runs["sime"]) > 10
    assert np.mean(runs["sime"]) < np.mean(runs["bisection"])


def test_cli_cct_searches_agree_and_say_how():
    from click.testing import CliRunner

    from stabctl.cli import main

    out = {}
    for method in ("sime", "bisection"):
        args = ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--search", method]
        res = CliRunner().invoke(main, [*args, "--json"])
        assert res.exit_code == 0, res.output
        out[method] = json.loads(res.stdout)
    assert out["sime"]["cct_s"] == out["bisection"]["cct_s"]
    assert out["bisection"]["search"] == "bisection" and out["bisection"]["early_stops"] == 0
    assert out["sime"]["n_simulations"] < out["bisection"]["n_simulations"]


def test_cli_screen_takes_the_search_and_keeps_the_bisection_s_cells(tmp_path):
    """`stabctl screen --search sime` ends each search in the bisection's 1 ms cell (the
    same CCT and verdict as `--search bisection`, Kundur's bus faults 3, 12, 13 and 101:
    CCTs of 0.24-0.84 s, and a robust one at --t-max 0.5) and its records say the search,
    so that a screening resumed with the other search runs its faults again."""
    from click.testing import CliRunner

    from stabctl.cli import main

    rows = {}
    for method in ("sime", "bisection"):
        out = tmp_path / f"{method}.jsonl"
        args = ["screen", "kundur", "--buses", "3,12,13,101", "--workers", "1"]
        res = CliRunner().invoke(main, [*args, "--search", method, "--out", str(out), "--json"])
        assert res.exit_code == 0, res.output
        rows[method] = {r["bus"]: r for r in json.loads(res.stdout)}
        records = [json.loads(line) for line in out.read_text().splitlines()]
        assert all(r["inputs"].get("method", "bisection") == method for r in records)
    assert rows["sime"].keys() == rows["bisection"].keys() == {3, 12, 13, 101}
    for bus, r in rows["sime"].items():
        assert r.get("cct_s") == rows["bisection"][bus].get("cct_s")
        assert r.get("verdict") == rows["bisection"][bus].get("verdict")
    assert rows["sime"][101].get("cct_s") is None  # 0.835 s: above t_max 0.5


def counting_runs(sim):
    """The simulator with its runs counted in ``sim.runs[0]`` (every run of a search, a
    verdict's too: whole runs and those started to be paused)."""
    run, start, sim.runs = sim.run, sim.start, [0]

    def counted(*args, **kw):
        sim.runs[0] += 1
        return run(*args, **kw)

    def counted_start(*args, **kw):
        sim.runs[0] += 1
        return start(*args, **kw)

    sim.run, sim.start = counted, counted_start
    return sim


@pytest.mark.parametrize(
    ("bus", "far_bus", "t_max"), [(3, None, 0.15), (3, None, 0.2), (3, 101, 0.13)]
)
def test_a_gentle_run_at_t_max_makes_a_fault_robust_in_one_run(bus, far_bus, t_max):
    """Kundur's bus-3 fault (CCT 0.238 s) and line 3-101 (0.154 s) under a t_max below
    their CCTs: the bisection's check at 0 and its doubling take 3 runs to the verdict;
    sime's first run, at t_max, is stable with no machine swung 1.5 rad from its angle to
    the COI before the fault (0.45-0.71 rad), which settles it.  The verdict carries the
    runs that reached it, as counted at the simulator."""
    from stabctl.errors import AboveSearchLimit
    from stabctl.stability.cct import ROBUST_SWING, largest_swing

    sim = counting_runs(Simulator(load_case("kundur")))
    fault = LineFault(bus, far_bus)
    for method, runs in (("bisection", 3), ("sime", 1)):
        sim.runs[0] = 0
        with pytest.raises(AboveSearchLimit) as verdict:
            critical_clearing_time(sim, fault, SearchOptions(method=method, t_max=t_max))
        assert sim.runs[0] == runs == verdict.value.n_simulations
    res = sim.run(fault.events(t_max), fault.t_fault + 5.0)
    assert 0.3 < largest_swing(res) < ROBUST_SWING


def test_the_swing_of_a_run_that_cuts_a_machine_off_is_that_of_the_machines_judged():
    """Kundur's fault at bus 1 on line 1-10, machine 1's only branch: the machine is lost
    from the fault's start (not judged), so the swing is the largest move of machines 2,
    11 and 12 against their own centre of inertia (H*MVA weights) from their angles to
    the four machines' before the fault."""
    from stabctl.stability.cct import largest_swing

    sim = Simulator(load_case("kundur"))
    fault = LineFault(1, 10)
    res = sim.run(fault.events(0.3), 3.0)
    assert res.partitions and not res.judged[0] and res.judged[1:].all()
    w, a = res.inertia, res.angle
    rel0 = a[0] - a[0] @ w / w.sum()
    kept = a[:, 1:] - (a[:, 1:] @ w[1:] / w[1:].sum())[:, None]
    moved = np.abs(kept - rel0[1:])[res.t >= fault.t_fault]
    before = np.abs(a - (a @ w / w.sum())[:, None] - rel0)[res.t < fault.t_fault]
    assert largest_swing(res) == pytest.approx(max(moved.max(), before.max()), abs=1e-12)


def test_a_lost_machine_s_slip_while_the_fault_is_on_is_no_swing():
    """Three machines of equal weight, machine 0 cut off by the clearing at 1 s and so
    not judged from the fault's start (0.5 s): it races 3 rad ahead while the fault is
    on, the others swing 0.3 rad about their own centre of inertia; the swing is 0.3
    rad (machine 0 against all three would be 2 rad)."""
    from types import SimpleNamespace

    from stabctl.dynamics.partition import Partition
    from stabctl.stability.cct import largest_swing

    one, everyone = np.ones(3), np.ones(3, bool)
    lost = np.array([False, True, True])

    def stage(t_s, island, judged):
        return Partition(t_s, np.array(island), one, judged, np.zeros(3, bool))

    parts = (stage(0.0, [0, 0, 0], everyone), stage(0.5, [0, 0, 0], lost))
    parts += (stage(1.0, [1, 0, 0], lost),)
    t = np.array([0.0, 0.25, 0.75, 1.25, 1.75])
    angle = np.array([[0, 0, 0], [0, 0, 0], [3, 0.3, -0.3], [6, -0.3, 0.3], [9, 0.2, -0.2]])
    res = SimpleNamespace(
        t=t, angle=angle.astype(float), inertia=one, island=np.zeros(3, int), partitions=parts
    )
    assert largest_swing(res) == pytest.approx(0.3, abs=1e-12)


def test_a_wide_swing_at_t_max_leaves_the_verdict_to_the_doubling(monkeypatch):
    """With the gentle bound at 0 rad no run at t_max settles a fault: sime then doubles
    from 0.1 s as the bisection does, reusing the run at t_max when it gets there (two
    runs for the robust bus-3 fault under t_max 0.2 s), and a CCT below t_max ends in
    the bisection's cell (line 3-101)."""
    import stabctl.stability.cct as cct

    monkeypatch.setattr(cct, "ROBUST_SWING", 0.0)
    sim = counting_runs(Simulator(load_case("kundur")))
    opts = SearchOptions(method="sime", t_max=0.2)
    assert search_outcome(sim, LineFault(3, None), opts) == "AboveSearchLimit"
    assert sim.runs[0] == 2
    fault = LineFault(3, 101)
    ref = critical_clearing_time(sim, fault, SearchOptions(method="bisection"))
    res = critical_clearing_time(sim, fault, SearchOptions(method="sime"))
    assert res.bracket == ref.bracket == (0.154, 0.155)
    assert res.probes[0] == (1.0, False)  # t_max first: unstable there


def test_a_run_at_t_max_that_fails_while_the_fault_is_on_is_left_to_the_doubling():
    """A network failure in the first run (the fault on for t_max, longer than the
    doubling may ever hold it) is not the search's verdict: the search goes on from
    0.1 s as without that run, to the bisection's verdict."""
    sim = counting_runs(Simulator(load_case("kundur")))
    run = sim.run

    def fails_first(*args, **kw):
        if sim.runs[0] == 0:
            sim.runs[0] += 1
            raise SimulationError("network singular while the fault is on")
        return run(*args, **kw)

    sim.run = fails_first
    opts = SearchOptions(method="sime", t_max=0.2)
    assert search_outcome(sim, LineFault(3, None), opts) == "AboveSearchLimit"
    assert sim.runs[0] == 3  # the failed run, 0.1 s, 0.2 s again


def test_sime_against_an_infinite_bus_is_the_machine_s_own_omib(psse_omib):
    """PSS/E's OMIB (machine 2 against the infinite bus, H = 0, of machine 1): SIME's
    equivalent is the machine itself, M = 2 H S / (S_base w_s) and delta its angle from
    the infinite bus's (the paper's Section 2 OMIB), and the sime search ends in the
    bisection's cell of the fault at bus 102 on line 102-101 (it raised in the
    centre of inertia of the infinite bus's group, which weighs nothing in the run's COI
    weights)."""
    from stabctl.dynamics.coi import machine_inertia
    from stabctl.stability.sime import omib_equivalent

    case = load_case(psse_omib)
    sim = Simulator(case)
    fault = LineFault(102, 101)
    ref = critical_clearing_time(sim, fault, SearchOptions(method="bisection"))
    res = critical_clearing_time(sim, fault, SearchOptions(method="sime"))
    assert res.bracket == ref.bracket
    run = sim.run(fault.events(ref.t_unstable), fault.t_fault + 5.0, stop_at_separation=True)
    assert not run.stable and list(run.inertia) == [1.0, 0.0]  # the COI weights
    h, mva = case.machines.H[1], case.machines.mva[1]
    ws = 2 * np.pi * case.freq_hz
    for critical in ([2], [1]):  # either group named critical: the same equivalent
        eq = omib_equivalent(run, critical, case.base_mva, case.freq_hz, machine_inertia(case))
        assert eq.M == pytest.approx(2 * h * mva / (case.base_mva * ws), rel=1e-12)
        gap = run.angle[:, 1] - run.angle[:, 0]
        assert np.allclose(eq.delta, gap if gap[-1] >= gap[0] else -gap, atol=1e-12)
