"""Speed estimators: synthetic swings with known truth (bias, RMSE, NIS consistency), dropped
frames, the filterpy reference against the compiled path, COI and relative speeds with
variances, latency forecast, a real Kundur run, false ESD actions and `stabctl estimate`."""

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from click.testing import CliRunner

import stabctl
from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import InputError
from stabctl.estimation import pmu
from stabctl.estimation.filters import FrequencyKF, SwingEKF, nis_bounds
from stabctl.estimation.models import (
    FrequencyTuning,
    Governors,
    LinearSystems,
    MachineModels,
    QAxis,
    SwingTuning,
    coi_speed,
    machine_models,
    relative_speeds,
)
from stabctl.estimation.reference import FrequencyKFReference, SwingEKFReference
from stabctl.io import load_case
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import pack, uniform_fleet
from stabctl.studies import estimation as study

F0, WB = 60.0, 2 * np.pi * 60.0
H, X, EMAG, VMAG, PM = 5.0, 0.3, 1.1, 1.0, 0.8


def linear_swing(t_end=10.0, f_m=1.0, zeta=0.05, dP=0.5, t_on=1.0, t_off=1.1, amp=1.0):
    """A classical machine's linearised swing with known truth on a 1 ms grid.

    2H dw/dt = P_m - P_ag, P_ag = P_m + K (delta - delta0) + De w - dP (t_on <= t < t_off):
    a power pulse (a fault) rings the swing mode at f_m Hz with damping ratio zeta.  Its
    terminal phasors: E = EMAG at delta behind X, V = VMAG at delta - asin(P_ag X / (E V)).
    Returns t, speed (pu), P_ag and the PhasorTruth of its PMU.
    """
    wn = 2 * np.pi * f_m
    K, De = wn**2 * 2 * H / WB, 4 * H * zeta * wn / WB
    A = np.array([[0.0, WB], [-K / (2 * H), -De / (2 * H)]])
    dt = 1e-3
    t = np.round(np.arange(0, t_end + dt / 2, dt), 9)
    E = scipy.linalg.expm(
        np.block([[A * dt, np.array([[0.0], [dt / (2 * H)]])], [np.zeros((1, 3))]])
    )
    x, xs = np.zeros(2), []
    for tk in t:
        xs.append(x)
        x = E[:2, :2] @ x + E[:2, 2] * (amp * dP if t_on <= tk < t_off else 0.0)
    dd, w = np.array(xs).T
    pulse = np.where((t >= t_on) & (t < t_off), amp * dP, 0.0)
    pag = PM + K * dd + De * w - pulse
    delta = 0.5 + dd
    theta = delta - np.arcsin(pag * X / (EMAG * VMAG))
    e, v = EMAG * np.exp(1j * delta), VMAG * np.exp(1j * theta)
    cur = (e - v) / (1j * X)
    truth = pmu.angle_truth(
        t,
        (pmu.PMU(bus=1, machine=1),),
        v[:, None],
        cur[:, None],
        F0,
        pmu.PMUSettings().window_s(F0),
    )
    return t, 1 + w, pag, truth


def classical_models():
    """MachineModels of the synthetic machine: classical, no governor, system base."""
    z1 = np.zeros(1)
    gov = Governors(
        LinearSystems(np.zeros((1, 3, 3)), np.zeros((1, 3))),
        np.zeros((1, 3)),
        np.zeros((1, 3)),
        np.ones(1),
        z1,
        np.full(1, np.inf),
        np.zeros(1, bool),
    )
    qax = QAxis(
        LinearSystems(np.zeros((1, 2, 2)), np.zeros((1, 2))),
        np.zeros((1, 2)),
        np.ones(1),
        np.zeros(1, bool),
        np.zeros(1, int),
        z1,
        z1,
        z1,
        np.full(1, X),
    )
    return MachineModels(
        numbers=np.array([1]),
        pmu=np.array([0]),
        H=np.full(1, H),
        D=z1,
        pot=np.ones(1),
        ra=z1,
        z_emf=np.full(1, 1j * X),
        per_speed=np.zeros(1, bool),
        psse_swing=np.zeros(1),
        inertia=np.full(1, H * 100.0),
        f0=F0,
        governor=gov,
        qaxis=qax,
    )


def feed(f, stream):
    """Speeds, variances and NIS (n_f, n) of an estimator fed every frame."""
    rows = [(*f.step(fr), f.nis.copy()) for fr in stream]
    return tuple(np.array(a) for a in zip(*rows))


@pytest.fixture(scope="module")
def swing():
    t, speed, _, truth = linear_swing()
    return truth, lambda tt: np.interp(tt, t, speed)


def test_ekf_on_a_linear_swing_is_unbiased_accurate_and_consistent(swing):
    truth, true_speed = swing
    st, models = pmu.PMUSettings(), classical_models()
    tun = SwingTuning(angle_model_rad=0.0)
    bias, rmse, inside = [], [], []
    for seed in range(4):
        stream = pmu.measure(truth, st, seed)
        speed, var, nis = feed(SwingEKF(models, st, tun), stream)
        sel = stream.t > 1.2
        err = (speed[sel, 0] - true_speed(stream.t[sel])) * F0 * 1e3  # mHz
        bias.append(err.mean())
        rmse.append(np.sqrt(np.mean(err**2)))
        lo, hi = nis_bounds(1)
        inside.append(np.mean((nis[sel] > lo) & (nis[sel] < hi)))
        # the filter's own variance matches its error
        assert np.mean(err**2 / (var[sel, 0] * (F0 * 1e3) ** 2)) == pytest.approx(1, abs=0.35)
    assert abs(np.mean(bias)) < 0.1 and np.mean(rmse) < 2.0  # mHz; the swing is 300 mHz
    assert np.mean(inside) == pytest.approx(0.95, abs=0.02)


def test_baseline_kf_smooths_the_pmu_frequency_consistently():
    t = np.linspace(0, 60, 60001)
    f = 60 + 0.05 * np.sin(2 * np.pi * 0.2 * t)  # 0.2 Hz, 50 mHz
    rocof = 0.05 * 2 * np.pi * 0.2 * np.cos(2 * np.pi * 0.2 * t)
    ones = np.ones((t.size, 1))
    truth = pmu.PhasorTruth(
        t=t,
        pmus=(pmu.PMU(bus=1),),
        v=ones + 0j,
        i=ones * np.nan,
        freq=f[:, None],
        rocof=rocof[:, None],
        f0=F0,
    )
    st = pmu.PMUSettings()
    stream = pmu.measure(truth, st, seed=2)
    speed, _var, nis = feed(FrequencyKF([0], st, FrequencyTuning(rocof_walk=0.001)), stream)
    sel = stream.t > 2
    e_kf = (speed[sel, 0] * F0 - stream.true.freq[sel, 0]) * 1e3
    e_raw = (stream.freq[sel, 0] - stream.true.freq[sel, 0]) * 1e3
    assert abs(e_kf.mean()) < 0.05
    assert np.sqrt(np.mean(e_kf**2)) < 0.3 * np.sqrt(np.mean(e_raw**2))
    lo, hi = nis_bounds(2)
    assert np.mean((nis[sel] > lo) & (nis[sel] < hi)) == pytest.approx(0.95, abs=0.02)


def test_dropped_frames_are_predicted_over(swing):
    truth, true_speed = swing
    st = pmu.PMUSettings(drop_prob=0.1)
    stream = pmu.measure(truth, st, seed=5)
    f = SwingEKF(classical_models(), st)
    speed, _var, nis = feed(f, stream)
    start = np.argmax(stream.valid[:, 0])
    assert np.all(np.isfinite(speed[start:]))
    assert np.all(np.isnan(nis[~stream.valid[:, 0]]))  # no update without a frame
    sel = stream.t > 1.2
    err = (speed[sel, 0] - true_speed(stream.t[sel])) * F0 * 1e3
    assert np.sqrt(np.mean(err**2)) < 4.0
    lo, hi = nis_bounds(1)
    n = nis[sel, 0][np.isfinite(nis[sel, 0])]
    assert 0.93 < np.mean((n > lo) & (n < hi)) < 0.99  # still consistent


def test_frames_must_come_in_time_order(swing):
    stream = pmu.measure(swing[0], seed=0)
    f = FrequencyKF([0], stream.settings)
    f.step(stream.frame(3))
    with pytest.raises(InputError, match="time-stamp order"):
        f.step(stream.frame(3))


def test_forecast_extrapolates_the_speed_over_the_latency(swing):
    truth, true_speed = swing
    stream = pmu.measure(truth, pmu.PMUSettings(tve=0, fe_hz=0, rfe_hz_s=0), seed=0)
    f = SwingEKF(classical_models(), stream.settings)
    late, ahead = [], []
    for fr in stream:
        s, _ = f.step(fr)
        if fr.t > 1.5:
            late.append(s[0] - true_speed(fr.t + 0.05))
            ahead.append(f.forecast(0.05)[0][0] - true_speed(fr.t + 0.05))
    assert np.sqrt(np.mean(np.square(ahead))) < 0.2 * np.sqrt(np.mean(np.square(late)))


def test_coi_and_relative_speeds_with_variances():
    M = np.array([1.0, 2.0, 5.0])
    speed, var = np.array([1.001, 0.999, 1.0]), np.array([1e-8, 4e-8, 9e-8])
    c, cv = coi_speed(speed, var, M)
    assert c == pytest.approx((1.001 + 2 * 0.999 + 5) / 8)
    assert cv == pytest.approx((1e-8 + 4 * 4e-8 + 25 * 9e-8) / 64)
    rng = np.random.default_rng(0)
    draws = speed + rng.normal(size=(200000, 3)) * np.sqrt(var)
    for coi in ("system", "rest"):
        r, rv = relative_speeds(speed, var, M, coi)
        rd = relative_speeds(draws, draws, M, coi)[0]  # (..., n) stacks work
        np.testing.assert_allclose(rd.mean(axis=0), r, atol=2e-6)
        np.testing.assert_allclose(rd.var(axis=0), rv, rtol=0.02)
    rest0 = speed[0] - (2 * 0.999 + 5 * 1.0) / 7
    assert relative_speeds(speed, var, M, "rest")[0][0] == pytest.approx(rest0)
    with pytest.raises(InputError):
        relative_speeds(speed, var, M, "area")


# -- real Kundur run -----------------------------------------------------------------------
@pytest.fixture(scope="module")
def kundur():
    case = load_case("kundur")
    res = Simulator(case).run([fault_with_clearing(case, 3, 101, 1.0, 12)], t_end=8.0)
    pmus = pmu.machine_pmus(case)
    return case, res, pmus, machine_models(case, pmus), pmu.phasor_truth(case, res, pmus)


def test_kundur_relative_speed_well_inside_the_deadband(kundur):
    _case, res, _pmus, models, truth = kundur
    st = pmu.PMUSettings(drop_prob=0.02)
    stream = pmu.measure(truth, st, seed=3)
    tracks = study.run_estimators(stream, models)
    fig = {k: study.errors(v, res, stream, (1.3, 8.0)) for k, v in tracks.items()}
    assert fig["ekf"]["rel_rmse_mhz"] < 3.0  # deadband: 100 mHz
    assert fig["ekf"]["coi_rmse_mhz"] < 3.0
    assert fig["ekf"]["rel_rmse_mhz"] < fig["kf"]["rel_rmse_mhz"] / 3
    assert fig["ekf"]["rel_forecast_rmse_mhz"] < fig["ekf"]["rel_arrival_rmse_mhz"] / 2
    assert fig["ekf"]["nis_inside"] == pytest.approx(0.95, abs=0.03)


def test_compiled_filters_equal_the_filterpy_reference(kundur):
    _case, _res, _pmus, models, truth = kundur
    st = pmu.PMUSettings(drop_prob=0.1)
    stream = pmu.measure(truth, st, seed=1)
    for fast, ref in (
        (FrequencyKF(models.pmu, st), FrequencyKFReference(models.pmu, st)),
        (SwingEKF(models, st), SwingEKFReference(models, st)),
    ):
        a, b = feed(fast, stream), feed(ref, stream)
        for x, y in zip(a, b):  # round-off over 480 frames: 1.5e-13 on a 7.7e-5 variance
            np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-12)


def test_same_seed_same_estimates(kundur):
    _case, _res, _pmus, models, truth = kundur
    runs = [study.run_estimators(pmu.measure(truth, seed=9), models)["ekf"].speed for _ in range(2)]
    np.testing.assert_array_equal(*runs)


def test_false_actions_follow_table_3():
    case = load_case("kundur")
    sa = pack(uniform_fleet(case, 1.0, BangBangCOI()), case, np.arange(case.n_bus))
    db = 0.1 / 60
    rel = np.zeros((6, 4))
    rel[:, 0] = [0, 2 * db, 2 * db, 0, -2 * db, 0.5 * db]  # two actions
    rel[:, 3] = [0, 0.9 * db, -0.9 * db, 0, 0, 0]  # inside the band: none
    assert study._count_actions(sa, rel) == 2


def test_estimate_command_json_and_bad_input():
    res = CliRunner().invoke(
        main,
        [
            "estimate",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--tf",
            "4",
            "--runs",
            "2",
            "--ambient-s",
            "3",
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert set(d["estimators"]) == {"raw", "kf", "ekf"} and d["runs"] == 2
    assert d["estimators"]["ekf"]["rel_rmse_mhz"]["mean"] < 3.0
    assert len(d["estimators"]["ekf"]["rel_rmse_mhz"]["runs"]) == 2
    assert d["false_actions"]["true"]["actions"]["mean"] == 0
    assert d["false_actions"]["true"]["std_rel_mhz"]["mean"] > 0  # the loads move it
    assert d["ambient"]["pct"] == 1.0 and d["ambient"]["runs"] == 5
    assert d["window_s"] == pytest.approx([1.2, 4.0])
    neg = CliRunner().invoke(
        main, ["estimate", "kundur", "--fault", "3", "--far-bus", "101", "--ambient-pct", "-1"]
    )
    assert neg.exit_code == 2 and neg.stderr.startswith(
        "error: --ambient-pct -1: must be in [0, 100] %"
    )
    bad = CliRunner().invoke(
        main, ["estimate", "kundur", "--fault", "3", "--far-bus", "101", "--rate", "50"]
    )
    assert bad.exit_code == 2 and bad.stderr.startswith("error: --rate 50: must be one of")


def test_baseline_kf_forecast_does_not_amplify_a_bus_angle_step():
    # An ESD switching steps the bus angle by dtheta: the P-class frequency over a window
    # w is then f0 + dtheta / (2 pi w) for one window, the ROCOF +-that / w.  The KF's
    # forecast over the 50 ms latency must stay at the pulse the PMU itself reports (an
    # extrapolated ROCOF would add 50 ms * A / w = 1.5 A) and return once both windows
    # have passed.
    st, w, dth, t_step = pmu.PMUSettings(), 2 / F0, 0.05, 1.0 + 1 / 240
    pulse = dth / (2 * np.pi * w)  # Hz, 239 mHz
    phase = lambda t: dth * (t >= t_step)  # noqa: E731
    freq = lambda t: F0 + (phase(t) - phase(t - w)) / (2 * np.pi * w)  # noqa: E731
    rng = np.random.default_rng(0)
    kf, out = FrequencyKF([0], st, f0=F0), []
    for t in np.arange(1, 150) / F0:
        z = freq(t) + rng.normal() * st.sigma_freq
        r = (freq(t) - freq(t - w)) / w + rng.normal() * st.sigma_rocof
        kf.step(
            pmu.Frame(
                t,
                np.array([True]),
                np.ones(1, complex),
                np.ones(1, complex),
                np.array([z]),
                np.array([r]),
            )
        )
        out.append((t, (kf.forecast(st.latency_s)[0][0] - 1) * F0))
    t, dev = np.array(out).T
    assert np.abs(dev).max() <= 1.1 * pulse
    assert np.abs(dev[t > t_step + 2 * w + 3 / F0]).max() < 6 * st.sigma_freq


def test_estimate_rmse_simulates_the_fault_run_with_wecc_batteries():
    """`estimate rmse --esd-model wecc`: the fault run's storage is WECC batteries.  Kundur
    line 3-101 cleared after 12 cycles with 5 % devices is stable with ideal devices and
    loses synchronism (at 3.3 s) with batteries, whose lags cost a quarter cycle of CCT.
    --esd-model takes ideal or wecc only (exit 2), here and in `estimate cct`."""
    args = ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101"]
    args += ["--clear-cycles", "12", "--esd-pct", "5", "--runs", "1", "--ambient-s", "0"]
    args += ["--tf", "3.5"]
    out = {}
    for model in ("ideal", "wecc"):
        res = CliRunner().invoke(main, [*args, "--esd-model", model, "--json"])
        assert res.exit_code == 0, res.output
        out[model] = json.loads(res.stdout)
    assert out["ideal"]["stable"] and not out["wecc"]["stable"]
    assert out["wecc"]["esd_model"] == "wecc" and out["ideal"]["esd_model"] == "ideal"
    text = CliRunner().invoke(main, [*args, "--esd-model", "wecc"])
    assert "storage 5 %, WECC batteries (true speeds); the run loses synchronism" in text.stdout
    for sub in (["rmse"], ["cct", "--esd-pct", "5"]):
        bad = CliRunner().invoke(
            main,
            ["estimate", *sub, "kundur", "--fault", "3", "--far-bus", "101", "--esd-model", "foo"],
        )
        assert bad.exit_code == 2 and "'foo' is not one of 'ideal', 'wecc'" in bad.output


def test_estimate_rmse_with_nearly_every_frame_lost_says_why_a_figure_is_missing():
    """--drop 0.999 (an issue-30 probe: a TypeError after half the table): a machine none
    of whose frames arrived has no estimate, so the COI and relative errors are "-", said
    in a footnote, with no numpy warning."""
    args = ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101", "--drop", "0.999"]
    res = CliRunner().invoke(main, [*args, "--runs", "2", "--ambient-s", "0", "--tf", "3"])
    assert res.exit_code == 0, res.output
    assert "-: no error to take (a COI or relative speed needs an estimate" in res.stdout
    assert "warning" not in res.stderr, res.stderr


def test_estimate_rmse_shows_the_fraction_of_its_runs_done():
    """Round 47: `estimate rmse --runs 30` ran minutes with nothing on stderr.  A bar of
    its noise and ambient runs (fraction done, time left) goes to stderr; the --json
    stdout stays the JSON alone."""
    args = ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101", "--runs", "3"]
    args += ["--ambient-s", "2", "--ambient-runs", "2", "--tf", "2", "--json"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    json.loads(res.stdout)
    last = res.stderr.replace("\r", "\n").strip().splitlines()[-1]
    assert last.startswith("estimate: noise and ambient runs: 100%") and " 5/5 [" in last


def test_estimate_rmse_of_one_run_has_no_spread_and_its_columns_stay_apart():
    """One run has no spread: its standard deviations are null in the JSON (not 0) and
    "+-n/a" in the text, said under the table.  With --k-sigma 0.001 the noise is a
    thousand sigma and the errors tens of thousands of mHz: every column is as wide as
    its widest cell, two spaces apart, so the header and each row split into the same
    columns and each cell reads back as the JSON's figure."""
    args = ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101", "--runs", "1"]
    args += ["--ambient-s", "0", "--tf", "3", "--k-sigma", "0.001"]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    figs = json.loads(res.stdout)["estimators"]
    assert all(m["std"] is None for fig in figs.values() for m in fig.values()), figs
    assert max(f["speed_rmse_mhz"]["mean"] for f in figs.values()) > 1e4  # cells widen
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("estimator"))
    head = lines[k].split("  ")
    head = [h.strip() for h in head if h.strip()]
    assert head[1:] == [
        "speed",
        "COI",
        "relative",
        "rel. max",
        "at arrival",
        "forecast",
        "NIS in 95%",
    ]
    keys = ["speed_rmse_mhz", "coi_rmse_mhz", "rel_rmse_mhz", "rel_max_mhz"]
    keys += ["rel_arrival_rmse_mhz", "rel_forecast_rmse_mhz", "nis_inside"]
    for line, (name, fig) in zip(lines[k + 1 :], figs.items()):
        cells = [c.strip() for c in line.split("  ") if c.strip()]
        assert cells[0] == name and len(cells) == 1 + len(keys), line
        for cell, key in zip(cells[1:], keys):
            if fig[key]["mean"] is None:  # the raw frequency has no NIS
                assert cell == "-"
                continue
            mean, spread = cell.split(" ")
            assert float(mean) == pytest.approx(fig[key]["mean"], abs=1e-3) and spread == "+-n/a"
    assert lines[k + 1 + len(figs)] == "n/a: no spread, one run gave the figure"
    assert "+-0.000" not in res.stdout and "; 1 run, seeds 0..0" in res.stdout


def test_a_cct_of_one_seed_has_no_spread():
    """`estimate cct --runs 1` printed "+- 0.00": one CCT found has no spread (null in the
    JSON, "n/a" in the text); two have one."""
    from stabctl.cli.format import estimator_cct_lines
    from stabctl.estimation.closed_loop import _spread
    from stabctl.estimation.settings import PMUSettings

    one, two = _spread([11.5]), _spread([11.5, 12.0, np.nan])
    assert one["std"] is None and one["mean"] == 11.5
    assert two["std"] == pytest.approx(0.25) and two["failed"] == 1
    lines = estimator_cct_lines({"ekf": one, "kf": two}, 3, 101, 5, PMUSettings(), 1, 0)
    assert lines[1] == "  ekf     11.50 +- n/a (one run) (11.50..11.50)  runs 1, failed 0"
    assert lines[2] == "  kf      11.75 +- 0.25 (11.50..12.00)  runs 3, failed 1"


def test_estimate_cct_commands_wecc_batteries():
    """`estimate cct --esd-model wecc`: every estimator's loop commands batteries, whose
    CCT with exact measurements is 11.5 cycles against the ideal devices' 12 (the
    estimators' 11.75; test_closed_loop), and the report names them."""
    res = CliRunner().invoke(
        main,
        ["estimate", "cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"]
        + ["--runs", "1", "--esd-model", "wecc", "--json"],
    )
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["esd_model"] == "wecc" and d["lines"][0].startswith(
        "CCT of line 3-101, WECC batteries"
    )
    assert d["cct_cycles"]["ideal"]["values"] == [pytest.approx(11.5)]
    assert all(max(r["values"]) < 11.75 for r in d["cct_cycles"].values())
    # the searches' fault time (round 41: null), their clearing searched (null)
    assert d["fault"] == {"bus": 3, "far_bus": 101, "t_fault_s": 1.0, "clear_cycles": None}


def test_swing_filter_accelerates_as_the_simulator_under_each_reading():
    """One model, one place: the swing filter's acceleration (`swing_acceleration`) is the
    simulator's own swing equation.  PSS/E's GENROU run (tests/data/psse_runs/GENROU,
    read as PSS/E: ((P_m - D w)/omega - P_ag)/2H, D = 0.05) after its line trip: the
    filter's acceleration from the recorded P_m, P_e (r_a = 0) and speed equals the
    simulator's d omega/dt (central difference, 0.5 ms) within 1e-9 pu/s (measured
    3.7e-11); PST's and the plain form differ by 2.7e-5 pu/s, 1.2 % of the largest."""
    from stabctl.dynamics.events import LineTrip
    from stabctl.estimation.filters import swing_acceleration
    from stabctl.io.psse import load_psse
    from stabctl.models.machines import machine_params

    run = Path(__file__).resolve().parents[1] / "data" / "psse_runs" / "GENROU"
    case = load_psse(run / "ThreeBusMulti.raw", run / "ThreeBus_GENROU.dyr")
    mp = machine_params(case)
    assert (mp.psse_swing[1], mp.speed_effects[1], mp.ra_network[1]) == (1, 0, 0)
    res = Simulator(case).run([LineTrip(101, 102, 1.0)], 3.0, h=5e-4)
    t, w = res.t, res.speed[:, 1] - 1
    k = np.nonzero((t > 1.2) & (t < 2.9))[0]
    dw = (w[k + 1] - w[k - 1]) / (t[k + 1] - t[k - 1])
    gaps = []
    for flags in ((0, 1), (1, 0), (0, 0)):
        acc = swing_acceleration.py_func(
            res.pmech[k, 1], res.pelect[k, 1], w[k], mp.H[1], mp.D0[1], *flags
        )[0]
        gaps.append(np.max(np.abs(acc - dw)))
    assert gaps[0] < 1e-9 and min(gaps[1:]) > 1e-5


def test_false_actions_of_an_estimator_that_estimated_nothing_are_no_figure():
    """--drop 0.999 with runs without fault: no estimator saw every machine at one time,
    yet each was reported with 0.00 false actions (its NaN speeds read as 0) and the text
    output then crashed on the None of the spreads; now there is no figure ('-'), the
    true speeds' figures stay."""
    res = CliRunner().invoke(
        main,
        ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101", "--runs", "1"]
        + ["--tf", "2", "--ambient-runs", "1", "--ambient-s", "2", "--drop", "0.999"],
    )
    assert res.exit_code == 0, res.output
    lines = res.stdout.splitlines()
    assert "  ekf          -  (-, -)" in lines and "  raw          -  (-, -)" in lines
    assert any(line.startswith("  true      0.00  (") for line in lines)
    assert "-: no run to take it from (no estimate of every machine at one time)" in lines


def test_estimate_cct_simulates_the_case_file_given(tmp_path):
    """An edited copy of Kundur's case file (every H halved) that keeps the name
    "kundur": `estimate cct` simulates the file, as `cct` does (it loaded the built-in
    case its name names, 12 cycles, without a word).  The ideal estimator's CCT is within
    one tolerance (1/240 s, a quarter cycle) of `cct`'s on the file at that tolerance."""
    import stabctl

    d = json.loads((Path(stabctl.__file__).parent / "case" / "data" / "kundur.json").read_text())
    m = d["tables"]["machines"]
    h = m["columns"].index("H")
    for row in m["rows"]:
        row[h] /= 2
    case = tmp_path / "kundur_half_h.json"
    case.write_text(json.dumps(d))
    line = ["--fault", "3", "--far-bus", "101", "--esd-pct", "5"]
    res = CliRunner().invoke(main, ["estimate", "cct", str(case), *line, "--runs", "1", "--json"])
    assert res.exit_code == 0, res.output
    ideal = json.loads(res.stdout)["cct_cycles"]["ideal"]["mean"]
    ref = CliRunner().invoke(main, ["cct", str(case), *line, "--tol-ms", str(1000 / 240), "--json"])
    assert ref.exit_code == 0, ref.output
    assert abs(ideal - json.loads(ref.stdout)["cct_cycles"]) <= 0.25 + 1e-6
    assert ideal < 10


def test_governors_other_than_tg_are_held_by_the_estimators_and_named(tmp_path):
    """ANDES's IEEE 14 (TGOV1 governors): `estimate` refused every case with a governor
    other than PST's tg.  The filters' model now holds those machines' mechanical power
    at its start (their random walk dPm takes what the governor moves), with a warning
    naming them and their models; the tg governors stay in the model."""
    andes = pytest.importorskip("andes")
    from stabctl.estimation.models import machine_models
    from stabctl.estimation.pmu import machine_pmus

    case_file = tmp_path / "ieee14.json"
    src = andes.get_case("ieee14/ieee14_full.xlsx")
    assert CliRunner().invoke(main, ["import-andes", src, "-o", str(case_file)]).exit_code == 0
    case = stabctl.load_case(str(case_file))
    with pytest.warns(UserWarning, match=r"holds the mechanical power of 5 machine\(s\) at its "):
        models = machine_models(case, machine_pmus(case))
    assert not models.governor.active.any()
    with pytest.warns(UserWarning, match=r"G1 \(bus 2\) \(TGOV1\)"):
        machine_models(case, machine_pmus(case))
    kundur = stabctl.load_case("kundur")  # PST tg: every governor in the model
    assert machine_models(kundur, machine_pmus(kundur)).governor.active.all()


def test_a_terminal_pmu_measures_the_machine_s_own_current_beside_a_load():
    """IEEE 14 and 39 have loads at generator terminals: the terminal PMU's current was
    the sum of the bus's branch currents, which holds the load's, and `estimate` refused
    ("not the sum of its terminal branch currents").  It is the machine's own current,
    S = V conj(I) with the machine's P and Q (a conservation check), and a PMU at the HV
    bus, whose step-up current is then not the machine's, is refused naming the load."""
    from stabctl.estimation.pmu import machine_pmus, phasor_truth

    base = stabctl.load_case("kundur")
    bus1 = base.bus_index(1)
    pload, qload = base.buses.pload.copy(), base.buses.qload.copy()
    pload[bus1], qload[bus1] = 0.5, 0.1  # 50 MW, 10 Mvar at G1's terminal
    case = base.replace(buses=base.buses.replace(pload=pload, qload=qload))
    sim = stabctl.Simulator(case, background_compile=False)
    res = sim.run([stabctl.fault_with_clearing(case, 3, 101, 1.0, 6)], t_end=2.0)
    truth = phasor_truth(case, res, machine_pmus(case))
    keep = np.r_[np.diff(res.t) > 0, True]
    s = truth.v * np.conj(truth.i)
    np.testing.assert_allclose(s.real, res.pelect[keep], atol=1e-12)
    np.testing.assert_allclose(s.imag, res.qelect[keep], atol=1e-12)
    with pytest.raises(
        InputError,
        match=r"PMU at bus 10: the terminal bus 1 of G1 \(bus 1\) "
        r"also has load, so .* \(--pmu-at terminal\)",
    ):
        phasor_truth(case, res, machine_pmus(case, at="hv"))


def test_estimator_cct_statistics_keep_failed_runs_as_json_null_with_their_errors():
    """A failed run's CCT is NaN in the study and None (JSON null, not NaN) in its
    statistics, counted, with its error printed under its estimator's line."""
    from stabctl.cli.format import estimator_cct_lines
    from stabctl.estimation.closed_loop import _spread
    from stabctl.estimation.settings import PMUSettings

    s = _spread([12.0, float("nan"), 11.5])
    assert s["values"] == [12.0, None, 11.5] and (s["failed"], s["runs"]) == (1, 3)
    assert s["mean"] == pytest.approx(11.75) and json.loads(json.dumps(s)) == s
    table = {"ekf": {**s, "errors": ["SimulationError: network singular"]}}
    lines = estimator_cct_lines(table, 3, 101, 5, PMUSettings(), 3, 0)
    assert lines[1].endswith("runs 3, failed 1\n        failed: SimulationError: network singular")


@pytest.mark.parametrize("cycles", [4, 5, 6, 7, 8])
def test_the_error_window_starts_on_its_frame_whatever_the_clearing(cycles):
    """A fault at 1 s cleared after `cycles` cycles, errors from 100 ms after the clearing
    to 6 s: the frame on the window's start (k / 60 s, k = 66 + cycles) is evaluated for
    every clearing, so the window holds 60 (6 - start) + 1 frames.  The start is
    computed as 1 + cycles / 60 + 0.1 s, which for 6 cycles is 1.2000000000000002 and
    would otherwise leave out the frame 72 / 60 = 1.2 s."""
    from stabctl.studies.estimate import error_window

    fault = fault_with_clearing(load_case("kundur"), 3, 101, 1.0, cycles)
    window = error_window(fault, 0.1, 6.0)
    t = pmu.frame_times(6.0, 60)
    sel = study.in_window(t, window)
    assert np.flatnonzero(sel)[0] == 66 + cycles
    assert sel.sum() == 60 * 6 - (66 + cycles) + 1


def _kundur_at(tmp_path, freq_hz: float) -> Path:
    """A copy of Kundur's case file at another nominal frequency."""
    d = json.loads((Path(stabctl.__file__).parent / "case" / "data" / "kundur.json").read_text())
    d["freq_hz"], d["name"] = freq_hz, f"kundur{freq_hz:g}"
    path = tmp_path / f"kundur{freq_hz:g}.json"
    path.write_text(json.dumps(d))
    return path


RMSE_QUICK = ["--fault", "3", "--far-bus", "101", "--tf", "1.5", "--runs", "1", "--ambient-s", "0"]


@pytest.mark.parametrize("rate, used", [(None, 50.0), ("25", 25.0), ("50", 50.0)])
def test_estimate_rmse_on_a_50_hz_case_takes_the_50_hz_rates(tmp_path, rate, used):
    """A 50 Hz copy of Kundur: --rate 50 and 25 (C37.118.1 Table 1 at 50 Hz) were refused
    as not 60 Hz rates, and the default 60 frames/s was taken; the default is now the
    case's nominal frequency, one frame per cycle."""
    k50 = _kundur_at(tmp_path, 50.0)
    given = [] if rate is None else ["--rate", rate]
    res = CliRunner().invoke(main, ["estimate", "rmse", str(k50), *RMSE_QUICK, *given, "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["pmu"]["rate"] == used and d["case"] == "kundur50"
    assert np.isfinite(d["estimators"]["ekf"]["rel_rmse_mhz"]["mean"])


@pytest.mark.parametrize(
    "args",
    [
        ["estimate", "rmse", "{case}", *RMSE_QUICK],
        ["estimate", "closed-loop", "{case}", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"],
        ["estimate", "cct", "{case}", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"],
        ["estimate", "track", "{case}", "--source", "{rec}", "--out", "t.csv"],
        ["pmu", "serve", "{case}", "--fault", "3", "--far-bus", "101", "--port", "0"],
        ["pmu", "plant", "{case}", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"],
        ["pmu", "control", "{case}", "127.0.0.1:1", "--esd-pct", "5"],
    ],
    ids=lambda a: " ".join(a[:2]),
)
@pytest.mark.parametrize(
    "freq_hz, rate, rates, fix",
    [
        (50.0, "60", "10, 25, 50, 100 frames/s on a 50 Hz system", "give --rate 50"),
        (60.0, "25", "10, 12, 15, 20, 30, 60, 120 frames/s on a 60 Hz system", "give --rate 60"),
    ],
)
def test_a_rate_not_of_the_case_s_frequency_is_refused_before_any_run(
    tmp_path, monkeypatch, args, freq_hz, rate, rates, fix
):
    """Every command with --rate checks it against the case's nominal frequency once the
    case is read: named with the frequency, its rates and the rate to give, exit status
    2, before any simulation, server or output file."""
    case = _kundur_at(tmp_path, freq_hz)
    rec = tmp_path / "r.c37"
    rec.write_bytes(b"")
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    argv = [a.format(case=case, rec=rec) for a in args] + ["--rate", rate]
    res = CliRunner().invoke(main, argv)
    assert res.exit_code == 2, res.output
    assert res.stderr.startswith(f"error: --rate {rate}: must be one of {rates} (C37.118.1")
    assert f"{fix}, one frame per cycle" in res.stderr
    assert list(work.iterdir()) == []


def test_the_api_refuses_a_rate_not_of_the_case_s_frequency(tmp_path):
    """`PMUSettings` takes the rates of 50 and 60 Hz systems (it knows no case); what
    takes a case with them refuses the default 60 frames/s on a 50 Hz case, before the
    fault run, naming the setting to pass."""
    from stabctl.estimation.ambient import AmbientLoad
    from stabctl.estimation.settings import PMUSettings
    from stabctl.studies.estimate import ErrorRuns, closed_loop_verdicts, estimator_errors

    mc = ErrorRuns(1, 0, "terminal", "system", BangBangCOI(), AmbientLoad(1.0, 2.0, 0), 0.0, 1)
    k50 = load_case(str(_kundur_at(tmp_path, 50.0)))
    ev = fault_with_clearing(k50, 3, 101, 1.0, 6)
    need = r"PMUSettings\(rate=60\): must be one of 10, 25, 50, 100 frames/s on a 50 Hz .*"
    need += r"pass PMUSettings\(rate=50\)"
    with pytest.raises(InputError, match=need):
        estimator_errors(k50, ev, mc, settings=PMUSettings(), esd_pct=None, settle_s=0.1, t_end=2)
    with pytest.raises(InputError, match=need):
        closed_loop_verdicts(
            k50,
            ev,
            t_end=2,
            settings=PMUSettings(),
            esd_pct=5,
            seed=0,
            control=BangBangCOI(),
            deadband_hz=0.1,
        )
    with pytest.raises(InputError, match=r"PMUSettings\(rate=25\): .* on a 60 Hz system"):
        estimator_errors(
            load_case("kundur"),
            fault_with_clearing(load_case("kundur"), 3, 101, 1.0, 6),
            mc,
            settings=PMUSettings(rate=25),
            esd_pct=None,
            settle_s=0.1,
            t_end=2,
        )


def test_the_baseline_kf_refuses_another_system_s_frequency():
    """FrequencyKF(f0=60) fed a 50 Hz system's frames estimated speeds of 0.84 pu without a
    word (docs/estimation.md shows it without f0): a rate that is not one of f0's is
    refused at once, and frames reading far from f0 at the first step."""
    with pytest.raises(InputError, match=r"rate=50\).*50 Hz systems.*FrequencyKF the case's f0"):
        FrequencyKF([0], pmu.PMUSettings(rate=50))
    kf = FrequencyKF([0, 1], pmu.PMUSettings(rate=10))  # a rate of 50 and of 60 Hz
    one, z = np.ones(2, bool), np.ones(2, complex)
    frame = pmu.Frame(0.1, one, z, z, np.array([50.01, 49.98]), np.zeros(2))
    with pytest.raises(InputError, match=r"t = 0.1 s reads 49.99 Hz .*not near f0"):
        kf.step(frame)
    speed, _ = FrequencyKF([0, 1], pmu.PMUSettings(rate=10), f0=50.0).step(frame)
    assert speed == pytest.approx([1.0002, 0.9996])
