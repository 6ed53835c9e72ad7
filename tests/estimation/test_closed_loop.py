"""ESD control with the speed estimator in the loop (stabctl.estimation.closed_loop)."""

import numpy as np
import pytest

from stabctl.estimation import closed_loop as cl
from stabctl.io import load_case
from stabctl.dynamics.events import fault_with_clearing
from stabctl.dynamics.simulation import Simulator
from stabctl.estimation.ambient import AmbientLoad
from stabctl.storage.devices import StorageFleet, uniform_fleet
from stabctl.storage.control import ExternalCommands


@pytest.fixture(scope="module")
def kundur():
    case = load_case("kundur")
    # PSTess conventions: the 17- and 20-cycle faults are calibrated on PSTess 1.1's CCTs
    return case, Simulator(case, conventions="pstess"), [fault_with_clearing(case, 3, 101, 1.0, 17)]


def test_ekf_in_the_loop_keeps_the_17_cycle_fault_stable_like_the_ideal_controller(kundur):
    case, sim, ev = kundur
    ekf = cl.run_closed_loop(sim, ev, 6.0, 5, "ekf", rate=60, latency=0.05, seed=3)
    ideal = cl.run_closed_loop(sim, ev, 6.0, 5, "ideal", rate=60, latency=0.05)
    assert ekf.result.stable and ideal.result.stable
    assert not sim.run(ev, t_end=6.0).stable                      # without storage
    assert len(ekf.result.meta["switchings"]) >= 8
    assert ekf.diagnostics.modes.shape == (361, 4)


def test_ideal_closed_loop_reproduces_the_internal_controller_verdict(kundur):
    case, sim, ev = kundur
    loop = cl.run_closed_loop(sim, ev, 6.0, 5, "ideal", rate=120, latency=0.0)
    inner = sim.run(ev, t_end=6.0, storage=uniform_fleet(case, 5))
    assert loop.result.stable == inner.stable is True
    assert np.abs(loop.result.speed[-1] - inner.speed[-1]).max() < 2e-3


def test_same_seed_same_switchings_other_seed_other_noise(kundur):
    case, sim, ev = kundur
    runs = [cl.run_closed_loop(sim, ev, 3.0, 5, "kf", seed=s) for s in (7, 7, 8)]
    assert runs[0].result.meta["switchings"] == runs[1].result.meta["switchings"]
    assert np.array_equal(runs[0].diagnostics.rel, runs[1].diagnostics.rel)
    assert not np.array_equal(runs[0].diagnostics.rel, runs[2].diagnostics.rel)
    with pytest.raises(Exception, match="estimator"):
        cl.run_closed_loop(sim, ev, 3.0, 5, "oracle")


def test_stop_at_separation_ends_the_commanded_run_where_run_does(kundur):
    case, sim, ev = kundur
    fleet = StorageFleet(uniform_fleet(case, 5).devices, ExternalCommands())
    frames = np.arange(361) / 60
    idle = sim.run_commanded(ev, 6.0, fleet, frames, lambda t, p: np.zeros(4),
                             stop_at_separation=True)
    plain = sim.run(ev, t_end=6.0, stop_at_separation=True)
    assert not idle.stable and not plain.stable
    assert idle.t[-1] == idle.t_separation < 6.0
    assert abs(idle.t_separation - plain.t_separation) <= 0.01          # one step
    assert idle.separated == plain.separated
    assert len(idle.meta["storage"]) == 4                                 # kept when stopped


def test_kf_in_the_loop_keeps_the_20_cycle_fault_at_20_percent_stable(kundur):
    # analysis/kf_loop_diagnosis.py: a KF extrapolating its ROCOF over the latency loses
    # synchronism here (limit cycle on the bus-angle steps of ESD switching)
    case, sim, _ = kundur
    ev = [fault_with_clearing(case, 3, 101, 1.0, 20)]
    assert not sim.run(ev, t_end=6.0, storage=uniform_fleet(case, 5)).stable
    assert cl.run_closed_loop(sim, ev, 6.0, 20, "kf", seed=0).result.stable


def test_no_false_action_in_the_loop_under_ambient_load_noise(kundur):
    case, sim, _ = kundur
    amb = AmbientLoad(pct=1.0, tau_s=2.0, seed=1)
    for est in ("raw", "kf", "ekf"):
        run = cl.run_closed_loop(sim, [], 10.0, 5, est, seed=1, ambient=amb)
        res = run.result
        assert [s["switchings"] for s in res.meta["storage"][:4]] == [0, 0, 0, 0]
        assert cl.false_actions(run) == 0
        assert np.abs(run.diagnostics.rel).max() < 0.1                    # Hz, the deadband
    rel = (res.speed - res.coi_speed[:, None]) * case.freq_hz
    assert np.abs(rel).max() > 1e-3                    # the loads do move the machines (Hz)


def test_search_from_finds_the_bracket_of_a_monotone_verdict_from_any_hint():
    # stable up to cell 37: the bracket (37, 38) from below, above, at the CCT, and in
    # 2 runs when the hint is the CCT itself
    stable = lambda k: k <= 37  # noqa: E731
    for hint in (0, 5, 36, 37, 38, 60, 240):
        lo, hi, n = cl.search_from(stable, hint, 240)
        assert (lo, hi) == (37, 38)
    assert cl.search_from(stable, 37, 240)[2] == 2
    with pytest.raises(Exception, match="search limit"):
        cl.search_from(lambda k: True, 3, 10)
    with pytest.raises(Exception, match="cleared instantly"):
        cl.search_from(lambda k: False, 3, 10)


def test_warm_started_cct_equals_the_cold_bisection_where_the_verdict_is_monotone():
    # stabctl.stability.cct.critical_clearing_time (bisection from scratch) against the
    # chain job warm-started from hints below and above: Kundur, line 3-101, 5 % ESDs,
    # ideal speeds in the loop (cold CCT 12 cycles, reports/estimation_kundur.md)
    from stabctl.stability.cct import LineFault, cached_simulator, critical_clearing_time

    runner = cl.LoopRunner(cached_simulator("kundur"), 5.0, "ideal")
    cold = critical_clearing_time(runner, LineFault(3, 101, 1.0), tol=1 / 240,
                                  error_check=False)
    warm = cl.cct_chain_job("kundur", 3, 101, 5.0, "ideal", [0, 1], hint_cycles=10.0)
    assert cold.cct_cycles == 12.0
    assert warm["cct_cycles"] == [12.0, 12.0]
    assert warm["n_simulations"][1] == 2 < cold.n_simulations      # from the previous seed
    assert 0 < warm["latest_separation_s"] < 5.0
