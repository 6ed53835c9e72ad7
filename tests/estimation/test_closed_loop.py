"""ESD control with the speed estimator in the loop (stabctl.estimation.closed_loop)."""

import json

import numpy as np
import pytest

from stabctl.dynamics.driver import CommandFrames, Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import InputError
from stabctl.estimation import closed_loop as cl
from stabctl.estimation.ambient import AmbientLoad
from stabctl.estimation.settings import PMUSettings
from stabctl.io import load_case
from stabctl.parallel import RunnerOptions
from stabctl.stability.cct import LineFault
from stabctl.storage.control import ExternalCommands
from stabctl.storage.devices import StorageFleet, uniform_fleet


@pytest.fixture(scope="module")
def kundur():
    case = load_case("kundur")
    # PSTess conventions: the 17- and 20-cycle faults are calibrated on PSTess 1.1's CCTs
    return case, Simulator(case, conventions="pstess"), [fault_with_clearing(case, 3, 101, 1.0, 17)]


def test_ekf_in_the_loop_keeps_the_17_cycle_fault_stable_like_the_ideal_controller(kundur):
    _case, sim, ev = kundur
    ekf = cl.run_closed_loop(
        sim, ev, 6.0, cl.LoopOptions(5, "ekf", PMUSettings(rate=60, latency_s=0.05), 3)
    )
    ideal = cl.run_closed_loop(
        sim, ev, 6.0, cl.LoopOptions(5, "ideal", PMUSettings(rate=60, latency_s=0.05))
    )
    assert ekf.result.stable and ideal.result.stable
    assert not sim.run(ev, t_end=6.0).stable  # without storage
    assert len(ekf.result.meta["switchings"]) >= 8
    assert ekf.diagnostics.modes.shape == (361, 4)


def test_ideal_closed_loop_reproduces_the_internal_controller_verdict(kundur):
    case, sim, ev = kundur
    loop = cl.run_closed_loop(
        sim, ev, 6.0, cl.LoopOptions(5, "ideal", PMUSettings(rate=120, latency_s=0.0))
    )
    inner = sim.run(ev, t_end=6.0, storage=uniform_fleet(case, 5))
    assert loop.result.stable == inner.stable is True
    assert np.abs(loop.result.speed[-1] - inner.speed[-1]).max() < 2e-3


def test_the_ideal_closed_loop_takes_each_island_s_coi_as_the_simulator_does(kundur):
    """Round 35: after Kundur's line 10-1 cleared, G1 alone in its island at 1.17 pu, and
    the closed loop took one COI of every machine: every device switched on its speed,
    device 1 (G1's, in the main grid) absorbing 45 MW to the end, and the "ideal" CCT was
    21.5 cycles against the simulator's own law's 27.6.  Each island's COI is taken now,
    as the simulator's law takes it: G1's device idles, and the speeds and powers are the
    internal controller's."""
    case, sim, _ = kundur
    ev = [fault_with_clearing(case, 10, 1, 1.0, 6)]
    opts = cl.LoopOptions(5, "ideal", PMUSettings(rate=120, latency_s=0.0))
    loop = cl.run_closed_loop(sim, ev, 6.0, opts)
    inner = sim.run(ev, t_end=6.0, storage=uniform_fleet(case, 5))
    assert loop.result.pesd[-1, 0] == inner.pesd[-1, 0] == 0.0  # G1's device, idle
    assert np.all(loop.result.pesd[loop.result.t > 1.1, 0] == 0.0)
    assert np.abs(loop.result.speed[-1] - inner.speed[-1]).max() < 2e-3
    assert loop.result.speed[-1, 0] > 1.1  # G1 runs away alone: lost, not a COI member


def test_same_seed_same_switchings_other_seed_other_noise(kundur):
    _case, sim, ev = kundur
    runs = [cl.run_closed_loop(sim, ev, 3.0, cl.LoopOptions(5, "kf", seed=s)) for s in (7, 7, 8)]
    assert runs[0].result.meta["switchings"] == runs[1].result.meta["switchings"]
    assert np.array_equal(runs[0].diagnostics.rel, runs[1].diagnostics.rel)
    assert not np.array_equal(runs[0].diagnostics.rel, runs[2].diagnostics.rel)
    with pytest.raises(Exception, match="estimator"):
        cl.run_closed_loop(sim, ev, 3.0, cl.LoopOptions(5, "oracle"))


def test_stop_at_separation_ends_the_commanded_run_where_run_does(kundur):
    case, sim, ev = kundur
    fleet = StorageFleet(uniform_fleet(case, 5).devices, ExternalCommands())
    frames = np.arange(361) / 60
    idle = sim.run_commanded(
        ev, 6.0, fleet, CommandFrames(frames, lambda t, p: np.zeros(4)), stop_at_separation=True
    )
    plain = sim.run(ev, t_end=6.0, stop_at_separation=True)
    assert not idle.stable and not plain.stable
    assert idle.t[-1] == idle.t_separation < 6.0
    assert abs(idle.t_separation - plain.t_separation) <= 0.01  # one step
    assert idle.separated == plain.separated
    assert len(idle.meta["storage"]) == 4  # kept when stopped


def test_kf_in_the_loop_keeps_the_20_cycle_fault_at_20_percent_stable(kundur):
    # analysis/kf_loop_diagnosis.py: a KF extrapolating its ROCOF over the latency loses
    # synchronism here (limit cycle on the bus-angle steps of ESD switching)
    case, sim, _ = kundur
    ev = [fault_with_clearing(case, 3, 101, 1.0, 20)]
    assert not sim.run(ev, t_end=6.0, storage=uniform_fleet(case, 5)).stable
    assert cl.run_closed_loop(sim, ev, 6.0, cl.LoopOptions(20, "kf", seed=0)).result.stable


def test_no_false_action_in_the_loop_under_ambient_load_noise(kundur):
    case, sim, _ = kundur
    amb = AmbientLoad(pct=1.0, tau_s=2.0, seed=1)
    for est in ("raw", "kf", "ekf"):
        run = cl.run_closed_loop(sim, [], 10.0, cl.LoopOptions(5, est, seed=1), ambient=amb)
        res = run.result
        assert [s["switchings"] for s in res.meta["storage"][:4]] == [0, 0, 0, 0]
        assert cl.false_actions(run) == 0
        assert np.abs(run.diagnostics.rel).max() < 0.1  # Hz, the deadband
    rel = (res.speed - res.coi_speed[:, None]) * case.freq_hz
    assert np.abs(rel).max() > 1e-3  # the loads do move the machines (Hz)


def test_seed_rule_half_width_is_student_t_with_the_lattice_floor():
    # Student t table: t_0.975,4 = 2.776; sample 8.5, 8.75, 8.5, 8.75, 8.75 cycles has
    # s = sqrt(0.075 / 4) = 0.1369, so the half-width is 2.776 * 0.1369 / sqrt(5) = 0.170
    rule = cl.SeedRule()
    assert rule.half_width([8.5, 8.75, 8.5, 8.75, 8.75], 0.25) == pytest.approx(0.170, abs=1e-3)
    # five equal CCTs: no sample spread, the binomial floor (1 - 0.05^(1/5)) / 4 = 0.1127
    assert rule.half_width([12.0] * 5, 0.25) == pytest.approx(0.1127, abs=1e-4)
    assert rule.half_width([12.0, np.nan], 0.25) == np.inf  # one finite value
    with pytest.raises(InputError, match="batch <= max_runs"):
        cl.SeedRule(batch=5, max_runs=4)
    with pytest.raises(InputError, match="confidence"):
        cl.SeedRule(confidence=1.0)


def test_cct_study_adds_seed_batches_until_the_interval_is_narrow(tmp_path):
    # Kundur line 3-101, 5 % ESDs, raw PMU frequency in the loop: every seed's CCT is 11.75
    # cycles (reports/estimation_kundur.md, 5 seeds).  With batches of 2 the lattice floor
    # is 0.194 cycle at 2 seeds, 0.132 at 4 and 0.099 at 6 (< 0.125): three rounds
    rule = cl.SeedRule(batch=2, max_runs=8)
    table = cl.cct_study(
        "kundur",
        LineFault(3, 101),
        [5.0],
        rule,
        tmp_path / "cct.jsonl",
        estimators=("ideal", "raw"),
        runner=RunnerOptions(progress=False),
    )[5.0]
    assert table["ideal"]["runs"] == 1 and table["ideal"]["half_width"] is None
    assert table["raw"]["runs"] == 6
    assert table["raw"]["values"] == [pytest.approx(11.75)] * 6
    assert table["raw"]["half_width"] == pytest.approx((1 - 0.05 ** (1 / 6)) / 4)


def test_each_round_of_more_seeds_has_a_bar_named_as_such(tmp_path, monkeypatch):
    """Round 57 AV: `paper --only estimation`'s bar reached 100 % and began again from 0/5
    under the same name, three times (each round of more seeds a sweep of its own).  A
    round after the first is named "more seeds, round k"."""
    from types import SimpleNamespace

    import stabctl.parallel as par

    labels = []

    def fake_sweep(jobs, out, **kw):
        labels.append(kw["label"])
        return SimpleNamespace(
            records={j.key: {"status": "ok", "result": {"cct_cycles": 11.75}} for j in jobs}
        )

    monkeypatch.setattr(par, "run_sweep", fake_sweep)
    cl.cct_study(
        "kundur",
        LineFault(3, 101),
        [5.0],
        cl.SeedRule(batch=2, max_runs=8),  # three rounds (the test above)
        tmp_path / "cct.jsonl",
        estimators=("ideal", "raw"),
        runner=RunnerOptions(progress=False, workers=1),
        label="estimate cct",
    )
    assert labels == [
        "estimate cct",
        "estimate cct: more seeds, round 2",
        "estimate cct: more seeds, round 3",
    ]


def test_cct_study_passes_the_pmu_window_to_every_run_and_names_it_when_not_default(
    tmp_path, monkeypatch
):
    # the default window keeps the records' keys and inputs as they were (committed records
    # stay valid); another window is part of both, and reaches the PMUs of every loop run
    from types import SimpleNamespace

    import stabctl.parallel as par

    seen = {}

    def fake_sweep(jobs, out, **kw):
        seen["jobs"] = jobs
        return SimpleNamespace(
            records={j.key: {"status": "ok", "result": {"cct_cycles": 12.0}} for j in jobs}
        )

    monkeypatch.setattr(par, "run_sweep", fake_sweep)
    for window, tail in ((2.0, "seed0"), (4.0, "seed0/w4c")):
        cl.cct_study(
            "kundur",
            LineFault(3, 101),
            [5.0],
            1,
            tmp_path / "cct.jsonl",
            estimators=("raw",),
            pmu=PMUSettings(window_cycles=window),
            runner=RunnerOptions(workers=1, progress=False),
        )
        (job,) = seen["jobs"]
        assert job.key.endswith(tail)
        assert job.inputs.get("window_cycles", 2.0) == window
        assert ("window_cycles" in job.inputs) == (window != 2.0)
    got = {}
    monkeypatch.setattr(
        cl,
        "run_closed_loop",
        lambda sim, ev, t, loop, **k: got.setdefault("w", loop.pmu.window_cycles),
    )
    with pytest.raises(AttributeError):  # the fake returns a float, not a run
        cl.cct_job(
            {
                "case": "kundur",
                "bus": 3,
                "far_bus": 101,
                "esd_pct": 5.0,
                "estimator": "raw",
                "seed": 0,
                "window_cycles": 4.0,
            }
        )
    assert got["w"] == 4.0


def test_cct_study_with_wecc_batteries_names_them_and_commands_them(tmp_path):
    """esd_model "wecc": every job carries it and a "/wecc" key suffix (the ideal default's
    keys and inputs unchanged), and the loop commands batteries: with exact measurements
    Kundur line 3-101 at 5 % has its CCT at 11.5 cycles, half a cycle below the ideal
    devices' 12 (docs/storage.md)."""
    table = cl.cct_study(
        "kundur",
        LineFault(3, 101),
        [5.0],
        1,
        tmp_path / "cct.jsonl",
        estimators=("ideal",),
        runner=RunnerOptions(workers=1, progress=False),
        esd_model="wecc",
    )[5.0]
    assert table["ideal"]["values"] == [pytest.approx(11.5)]
    keys = [json.loads(line)["key"] for line in (tmp_path / "cct.jsonl").read_text().splitlines()]
    assert keys == ["kundur/3-101/5%/ideal/60fps/0.05s/seed0/wecc"]


def test_a_50_hz_case_s_estimator_ccts_are_found_on_its_quarter_cycle():
    """Round 35: `estimate cct` of a 50 Hz case searched on 1/240 s (0.208 cycle) and said
    "4.17 ms grid, 1/4 cycle"; its lattice is the case's quarter cycle, 5 ms."""
    from stabctl.cli.format import estimator_cct_lines

    assert cl.cct_tol(60.0) == cl.CCT_TOL_S == 1 / 240 and cl.cct_tol(50.0) == 0.005
    row = {"mean": 16.75, "std": None, "min": 16.75, "max": 16.75, "runs": 1, "failed": 0}
    lines = estimator_cct_lines(
        {"ideal": row}, 2, 4, 20.0, PMUSettings(rate=50), 1, 0, freq_hz=50.0
    )
    assert "each found on a 5.00 ms grid, 1/4 cycle" in lines[0]
