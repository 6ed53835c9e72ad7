"""The SIME-guided CCT search and the runs' early verdicts (`stabctl.stability.sime`):
each early verdict equals the full run's (the reference: the run to fault + 5 s judged by
the pi-from-the-COI criterion), and the search ends in the bisection's 1 ms cell."""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.errors import InputError, SimulationError
from stabctl.io import load_case
from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time
from stabctl.stability.screening import screening_faults
from stabctl.stability.sime import EarlyVerdict

#: clearing times (s) every screened fault is run at, full and with early verdicts
CLEARING_S = (0.05, 0.1, 0.2)


def early_and_full(sim, fault: LineFault, tc: float):
    """(verdict of the monitored run, its end s, the full run's verdict, its end s)."""
    t_end = fault.t_fault + 5.0
    full = sim.run(fault.events(tc), t_end, stop_at_separation=True)
    early = sim.run(
        fault.events(tc), t_end, stop_at_separation=True, monitor=EarlyVerdict(fault.t_fault + tc)
    )
    verdict = early.meta.get("early_verdict")
    ok = verdict == "stable" if verdict else early.stable
    return ok, float(early.t[-1]), full.stable, float(full.t[-1])


def mismatches(name: str, every: int = 1):
    """Screened faults (buses and lines, every `every`-th) whose early verdict differs
    from the full run's, and the fraction of simulated time the early stops saved."""
    sim = Simulator(load_case(name))
    bad, t_early, t_full = [], 0.0, 0.0
    for fault in screening_faults(sim.case, lines=True)[::every]:
        for tc in CLEARING_S:
            try:
                ok, te, ok_full, tf = early_and_full(sim, fault, tc)
            except (SimulationError, InputError):  # no verdict either way (e.g. islanding)
                continue
            t_early, t_full = t_early + te - fault.t_fault, t_full + tf - fault.t_fault
            if ok != ok_full:
                bad.append((fault, tc, ok, ok_full))
    return bad, 1 - t_early / t_full


def test_monitored_run_is_the_same_trajectory_up_to_its_stop(kundur):
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
    assert stopped.meta["early_verdict"] == "stable" and 2 < stopped.t[-1] < 2.1
    assert np.array_equal(stopped.angle, full.angle[:n])


def test_early_verdicts_equal_full_runs_on_kundurs_screening():
    bad, saved = mismatches("kundur")
    assert bad == []
    assert saved > 0.3  # simulated time saved


def test_early_verdicts_equal_full_runs_on_a_third_of_miniweccs_screening():
    """Every third fault of miniWECC's bus and line screening (the whole screening:
    ``benchmarks/bench_cct.py --verify``)."""
    bad, saved = mismatches("miniwecc", every=3)
    assert bad == []
    assert saved > 0.3


@pytest.mark.parametrize(
    ("bus", "far_bus"), [(3, 101), (13, 120), (13, 101), (3, None), (110, 120)]
)
def test_sime_search_ends_in_the_bisections_cell(kundur, bus, far_bus):
    fault = LineFault(bus, far_bus)
    ref = critical_clearing_time(kundur, fault, SearchOptions(method="bisection", early_stop=False))
    res = critical_clearing_time(kundur, fault)
    assert res.bracket == ref.bracket and res.cct_half_step_s == ref.cct_half_step_s
    assert res.n_simulations == len(res.probes) + len(res.half_step_probes)
    assert res.to_dict()["n_simulations"] == res.n_simulations
