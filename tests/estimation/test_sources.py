"""The estimators fed from C37.118.2 streams (stabctl.estimation.sources): Kundur's fault
run served over loopback TCP, as one stream or split into two, and as a recording, gives
the estimators exactly the figures of the same seed's frames encoded and parsed back in
process, and figures within the wire's quantisation of those drawn in process."""

import contextlib
import dataclasses

import numpy as np
import pytest

pytest.importorskip("pyc37")

import stabctl
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import InputError
from stabctl.estimation import c37, sources
from stabctl.estimation import pmu as pm
from stabctl.estimation.c37_tcp import StreamServer
from stabctl.estimation.settings import PMUSettings
from stabctl.studies import estimation as study

SETTINGS = PMUSettings(drop_prob=0.05)
WINDOW = (1.0 + 7 / 60 + 0.1, 6.0)  # 100 ms after the clearing to the end
#: FREQ is sent in whole mHz: a rounding error uniform in +-0.5 mHz, RMS 1 / sqrt(12) mHz,
#: bounds how far an RMSE of the raw frequency can move (triangle inequality)
FREQ_ROUNDING_RMS_MHZ = 1 / np.sqrt(12)


@pytest.fixture(scope="module")
def kundur_run():
    """Kundur, bus-3 fault on line 3-101 cleared after 7 cycles, 6 s; its PMU stream of
    seed 3 with 5 % of the frames lost."""
    case = stabctl.load_case("kundur")
    res = stabctl.Simulator(case).run([fault_with_clearing(case, 3, 101, 1.0, 7)], t_end=6.0)
    pmus = pm.machine_pmus(case)
    drawn = pm.measure(pm.phasor_truth(case, res, pmus), SETTINGS, seed=3)
    return case, res, pmus, drawn


def figures(case, res, frames):
    return study.received_errors(case, res, SETTINGS, frames, 3, WINDOW)


def read(case, pmus, servers, idcode=1):
    """The frames of servers read over TCP as `--source tcp://...` reads them, each
    addressed with `idcode` (one for all, or one per server: `--idcode`)."""
    with contextlib.ExitStack() as stack:
        for server in servers:
            stack.enter_context(server)
        src = sources.Source(servers=tuple(s.address for s in servers))
        return sources.read_frames(src, case, pmus, SETTINGS.rate, timeout=20, idcode=idcode)


def test_over_tcp_equals_the_same_frames_in_process(kundur_run):
    """Every figure of every estimator received over TCP equals that of the frames encoded
    and parsed back in process (nothing lost or changed in transport); the raw frequency's
    RMSE is within the FREQ rounding of the frames as drawn."""
    case, res, pmus, drawn = kundur_run
    cfg = c37.stream_config(case, pmus, SETTINGS.rate)
    got = read(case, pmus, [StreamServer.of_frames(cfg, drawn, speed=float("inf"))])
    assert got.summary() == {
        "streams": 1,
        "frames": len(drawn),
        "data_frames": len(drawn),
        "absent": int((~drawn.valid).sum()),
        "flagged": {"test mode or absent (STAT bits 15-14 = 10)": int((~drawn.valid).sum())},
        "missing": 0,
        "gaps": [],
        "unsent": [],
        "short": [],
    }
    assert got.absent > 0
    assert [f.t for f in got.frames] == list(drawn.t)  # the reporting instants k / 60
    received = figures(case, res, got.frames)
    assert received == figures(case, res, c37.on_wire(cfg, drawn))
    in_process = study.monte_carlo(case, res, SETTINGS, 1, 3, WINDOW)
    for metric in ("speed_rmse_mhz", "rel_rmse_mhz"):
        moved = abs(received["raw"][metric]["mean"] - in_process["raw"][metric]["mean"])
        assert moved <= FREQ_ROUNDING_RMS_MHZ
    ekf = received["ekf"]["rel_rmse_mhz"]["mean"]
    assert ekf == pytest.approx(in_process["ekf"]["rel_rmse_mhz"]["mean"], rel=0.02)


def test_two_streams_merge_into_the_one_stream(kundur_run, tmp_path):
    """The PMUs split over two servers (two PMUs each, as two PDCs would send them, their
    streams IDCODE 1 and 10, each addressed by its own) give the frames of the one
    stream; a recording of the one stream gives them too."""
    case, res, pmus, drawn = kundur_run
    cfg = c37.stream_config(case, pmus, SETTINGS.rate)
    one = read(case, pmus, [StreamServer.of_frames(cfg, drawn, speed=float("inf"))])
    halves = []
    for cols, idcode in (([0, 1], 1), ([2, 3], 10)):
        sub = c37.stream_config(case, [pmus[c] for c in cols], SETTINGS.rate, idcode)
        frames = [f.of(cols) for f in drawn]
        halves.append(StreamServer.of_frames(sub, frames, speed=float("inf")))
    two = read(case, pmus, halves, idcode=[1, 10])
    assert two.streams == 2 and two.data_frames == 2 * len(drawn) and two.missing == 0
    path = tmp_path / "kundur.c37"
    c37.record(path, cfg, drawn)
    recorded = sources.read_frames(sources.parse_source(str(path)), case, pmus, SETTINGS.rate)
    for got in (two, recorded):
        assert figures(case, res, got.frames) == figures(case, res, one.frames)


def encoded(case, pmus, cols, idcode, frames, data_s=0.0, cfg_s=0):
    """(CFG-2, data frames) of a stream of the PMUs cols; its data frames stamped data_s
    s later, its CFG-2 cfg_s s later (a whole number)."""
    cfg = c37.stream_config(case, [pmus[c] for c in cols], SETTINGS.rate, idcode)
    cfg2 = c37.config_frame(dataclasses.replace(cfg, epoch=cfg.epoch + cfg_s))
    return cfg2, [c37.data_frame(cfg, cfg2, f._replace(t=f.t + data_s).of(cols)) for f in frames]


def test_a_stream_missing_time_stamps_marks_them_missing(kundur_run):
    """A stream that skips every tenth time stamp the other sends: those PMU values are
    missing (NaN, invalid), counted apart from those flagged absent."""
    case, _res, pmus, drawn = kundur_run
    frames = list(drawn)
    a = encoded(case, pmus, [0, 1], 1, frames)
    b = encoded(case, pmus, [2, 3], 10, [f for k, f in enumerate(frames) if k % 10])
    got = sources.merge(case, pmus, SETTINGS.rate, [a, b])
    assert len(got.frames) == len(drawn)
    assert got.missing == 2 * len(range(0, len(drawn), 10))
    sent = np.arange(len(drawn)) % 10 != 0
    assert got.absent == (~drawn.valid[:, :2]).sum() + (~drawn.valid[sent][:, 2:]).sum()
    k = 10  # a time stamp the second stream skipped
    assert not got.frames[k].valid[2:].any() and np.isnan(got.frames[k].freq[2:]).all()
    assert np.array_equal(got.frames[k].valid[:2], drawn.valid[k, :2])


def test_streams_are_merged_on_one_clock(kundur_run):
    """Two streams, each read from its own CFG-2's time stamp: the second's clock 10 s
    off (its CFG-2 and data frames alike) was merged as if simultaneous, and its CFG-2
    alone stamped 1 s later moved its frames 1 s.  On one clock (t = 0 the earliest
    CFG-2's) the first is refused naming the offset, the second is the merge of the
    streams on time; and the time stamps a stream did not send (its data frames 0.5 s
    late: 30 at each end), NaN without a word, are named."""
    case, _res, pmus, drawn = kundur_run
    frames = list(drawn)[:121]
    a = encoded(case, pmus, [0, 1], 1, frames)
    same = sources.merge(case, pmus, SETTINGS.rate, [a, encoded(case, pmus, [2, 3], 10, frames)])
    assert same.unsent == () and same.missing == 0
    moved = sources.merge(case, pmus, 60, [a, encoded(case, pmus, [2, 3], 10, frames, cfg_s=1)])
    assert figures(case, _res, moved.frames) == figures(case, _res, same.frames)
    b = encoded(case, pmus, [2, 3], 10, frames, data_s=10.0, cfg_s=10)
    with pytest.raises(
        InputError,
        match=r"^stream 2 shares no time stamp with stream 1: its first is \+10\.000000 s "
        r"from stream 1's \(t = 10\.000000 s and 0\.000000 s",
    ):
        sources.merge(case, pmus, SETTINGS.rate, [a, b])
    late = sources.merge(
        case, pmus, SETTINGS.rate, [a, encoded(case, pmus, [2, 3], 10, frames, data_s=0.5)]
    )
    assert len(late.frames) == 151 and late.missing == 2 * 30 + 2 * 30
    assert late.unsent == (
        sources.Unsent("stream 1", 30, 121 / 60, 150 / 60),
        sources.Unsent("stream 2", 30, 0.0, 29 / 60),
    )
    assert str(late.unsent[1]) == (
        "stream 2 sent no frame at 30 time stamp(s) the other streams sent, t = 0.0000 s to "
        "0.4833 s (its PMUs' values missing there)"
    )
    assert late.summary()["unsent"][1] == {
        "stream": "stream 2", "instants": 30, "first": 0.0, "last": 29 / 60
    }  # fmt: skip


def test_track_names_the_time_stamps_a_stream_did_not_send(kundur_run, tmp_path):
    """`estimate track` of two servers, the second's frames 0.5 s late: its line names the
    time stamps each server did not send, by server."""
    from click.testing import CliRunner

    from stabctl.cli import main

    case, _res, pmus, drawn = kundur_run
    frames = list(drawn)[:121]
    halves = [
        StreamServer(*encoded(case, pmus, [0, 1], 1, frames), speed=float("inf")),
        StreamServer(*encoded(case, pmus, [2, 3], 10, frames, 0.5), speed=float("inf")),
    ]
    with contextlib.ExitStack() as stack:
        for server in halves:
            stack.enter_context(server)
        (h1, p1), (h2, p2) = (s.address for s in halves)
        res = CliRunner().invoke(
            main,
            ["estimate", "track", "kundur", "--source", f"tcp://{h1}:{p1},{h2}:{p2}",
             "--idcode", "1,10", "--frames", "121", "--out", str(tmp_path / "t.csv")],
        )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert res.stdout.startswith("tracked 151 frames")
    assert (
        f"; stream 1 ({h1}:{p1}) sent no frame at 30 time stamp(s) the other streams sent, "
        "t = 2.0167 s to 2.5000 s (its PMUs' values missing there); "
        f"stream 2 ({h2}:{p2}) sent no frame at 30 time stamp(s) the other streams sent, "
        "t = 0.0000 s to 0.4833 s (its PMUs' values missing there); wrote"
    ) in res.stdout, res.stdout


@pytest.mark.parametrize(
    "change, needle",
    [
        # named with the run's PMUs and --pmu-at (a stream of HV-bus PMUs read as terminal)
        ("foreign", "station 'B9:G9' is not a PMU of this run (its PMUs are B1:G1, B2:G2, "),
        ("twice", "station 'B1:G1' is in streams 1 and 2"),
        ("rate", "stream 1: its CFG-2 DATA_RATE 30, not the 60 expected"),
        ("half", "PMU B3:G3, B4:G4 in no stream"),
    ],
)
def test_streams_that_do_not_fit_the_run_are_named(kundur_run, change, needle):
    case, _res, pmus, _drawn = kundur_run
    cfg = c37.stream_config(case, pmus, 60)
    streams = [(c37.config_frame(cfg), [])]
    if change == "foreign":
        other = pm.PMU(bus=int(case.buses.number[0]))  # a voltage-only PMU
        streams = [(c37.config_frame(c37.stream_config(case, [*pmus, other], 60)), [])]
        needle = needle.replace("B9:G9", other.label)
    elif change == "twice":
        streams = streams * 2
        needle = needle.replace("B1:G1", pmus[0].label)
    elif change == "rate":
        streams = [(c37.config_frame(c37.stream_config(case, pmus, 30)), [])]
    else:
        streams = [(c37.config_frame(c37.stream_config(case, pmus[:2], 60)), [])]
        needle = f"PMU {pmus[2].label}, {pmus[3].label} in no stream"
    with pytest.raises(InputError, match=needle.replace("(", r"\(")):
        sources.merge(case, pmus, 60, streams)


def test_tracking_frames_runs_the_estimator_the_study_evaluates(kundur_run):
    """`closed_loop.track` (`estimate track`, no truth needed) on the stream's frames: the
    relative speeds it forecasts over the latency have, against the simulated truth at
    arrival, the RMSE `received_errors` reports for the EKF's forecast (one filter, one
    set of frames, two paths to it)."""
    case, res, _pmus, drawn = kundur_run
    from stabctl.estimation import closed_loop as cl
    from stabctl.estimation.models import relative_speeds
    from stabctl.storage.devices import uniform_fleet

    ctrl = cl.LoopController(case, uniform_fleet(case, 10).devices, "ekf", SETTINGS, 0, 1.0)
    d = cl.track(ctrl, list(drawn))
    assert d.t.size == len(drawn) and d.freq.shape == (len(drawn), 4)
    sel = study.in_window(d.t, WINDOW)
    late = res.speed_at(d.t[sel] + SETTINGS.latency_s)
    true_rel = relative_speeds(late, late, res.inertia, "system")[0] * case.freq_hz
    rms = 1e3 * np.sqrt(np.mean((d.rel[sel] - true_rel) ** 2))
    study_fig = figures(case, res, list(drawn))["ekf"]["rel_forecast_rmse_mhz"]["mean"]
    assert rms == pytest.approx(study_fig, rel=1e-9)
    with pytest.raises(InputError, match="a frame of 2 PMUs for a controller of 4"):
        cl.track(ctrl, [f.of([0, 1]) for f in drawn])


def test_frames_of_another_run_are_refused(kundur_run):
    """The frames of the 7-cycle clearing against the truth of a 12-cycle one: their
    frequency is far beyond the PMUs' stated accuracy from it, and the error says so."""
    case, _res, _pmus, drawn = kundur_run
    other = stabctl.Simulator(case).run([fault_with_clearing(case, 3, 101, 1.0, 12)], t_end=6.0)
    with pytest.raises(InputError, match="the frames do not measure this run"):
        study.received_errors(case, other, SETTINGS, list(drawn), 3, WINDOW)


def test_a_port_range_is_one_server_per_port():
    src = sources.parse_source("tcp://10.0.0.1:4712-4714,pdc:4800")
    assert src.servers == (
        ("10.0.0.1", 4712),
        ("10.0.0.1", 4713),
        ("10.0.0.1", 4714),
        ("pdc", 4800),
    )
    assert str(src) == "tcp://10.0.0.1:4712-4714,pdc:4800"
    src = sources.parse_source("tcp://[::1]:4712-4713")
    assert src.servers == (("::1", 4712), ("::1", 4713)) and str(src) == "tcp://[::1]:4712-4713"


@pytest.mark.parametrize(
    "text, needle",
    [
        ("tcp://localhost", "'localhost' is not HOST:PORT"),
        ("tcp://a:1,b:70000", "'b:70000': port 70000 is out of range"),
        ("no/such.c37", "no such recording"),
        ("tcp://a:4714-4712", "'a:4714-4712': the port range 4714-4712 is empty"),
        ("tcp://a:0-3", "'a:0-3': port 0 is out of range"),
        ("tcp://a:1,tcp://a:1", "'tcp://a:1': write tcp:// once"),
        ("tcp://a:1-3,a:2", "a:2 given twice"),
        # an unclosed bracket was looked up as a host name ("[[::1]:4712: Name or service
        # not known")
        ("tcp://[::1:4712", r"'\[::1:4712' is not HOST:PORT \(an IPv6 address in brackets"),
        ("tcp://[::1]]:4712", r"'\[::1\]\]:4712' is not HOST:PORT"),
        # an IPv6 host without brackets: '::1:4712' is itself an IPv6 address (it was read
        # as [::1]:4712 without a word)
        ("tcp://::1:4712", r"'::1:4712' is not HOST:PORT \(an IPv6 address in brackets"),
    ],
)
def test_bad_sources_are_named(text, needle):
    with pytest.raises(InputError, match=needle):
        sources.parse_source(text)


def test_a_long_track_keeps_its_frames_and_rows_in_blocks_frame_for_frame(kundur_run):
    """A recording of 2 ROW_BLOCK + 3 frames (whose rows the controller stacks in blocks)
    read back as one column-held `Frames`: each frame equals the one recorded (FREQ sent
    in whole mHz), and the raw estimator's track, which holds each machine's measured
    frequency, gives every frame's own time stamp and frequency, in order, across the
    blocks' seams."""
    case, _res, pmus, _drawn = kundur_run
    from stabctl.estimation import closed_loop as cl

    n = 2 * cl.ROW_BLOCK + 3
    k = np.arange(n)
    freq = case.freq_hz + 1e-3 * np.round(300 * np.sin(k / 50))[:, None] * np.ones(len(pmus))
    one = np.ones(len(pmus), complex)
    frames = [
        pm.Frame(j / 60, np.ones(len(pmus), bool), one, one, freq[j], np.zeros(len(pmus)))
        for j in range(n)
    ]
    cfg = c37.stream_config(case, pmus, 60)
    data = [c37.data_frame(cfg, c37.config_frame(cfg), f) for f in frames]
    got = sources.merge(case, pmus, 60, [(c37.config_frame(cfg), data)])
    assert isinstance(got.frames, pm.Frames) and len(got.frames) == n
    assert got.missing == got.absent == 0 and not got.gaps
    assert got.frames[-1].t == pytest.approx((n - 1) / 60, abs=1e-6)
    assert np.allclose(got.frames[5:9].freq, freq[5:9], atol=5e-4)
    ctrl = cl.LoopController(case, (), "raw", SETTINGS, 0, 1.0)
    d = cl.track(ctrl, got.frames)
    assert len(ctrl.rows) == 2 + 3  # two blocks, three rows
    assert np.array_equal(d.t, got.frames.t)
    assert np.allclose(d.freq, got.frames.freq, rtol=1e-14, atol=0)  # f / f0 * f0


def test_a_value_beyond_any_measurement_is_not_used(kundur_run):
    """One frame whose first PMU's voltage reads 1e30 pu (CRC valid: a byte error the CRC
    did not catch, or a PMU's fault) drove the EKF to 1e28 Hz and held a device at -1 to
    the end.  Such a value (|V| above 3 pu of the rated kV) is not used, as a STAT saying
    absent data makes it, and counted by its reason; the track's speeds are those of the
    stream without that frame's PMU value (the EKF predicts across it)."""
    case, _res, pmus, drawn = kundur_run
    from stabctl.estimation import closed_loop as cl

    frames = list(drawn)[:120]
    spiked = list(frames)
    f = spiked[70]
    spiked[70] = f._replace(v=np.where(np.arange(len(pmus)) == 0, 1e30, f.v))
    holed = list(frames)
    holed[70] = f._replace(
        valid=f.valid & (np.arange(len(pmus)) != 0),
        **{
            x: np.where(np.arange(len(pmus)) == 0, np.nan, getattr(f, x))
            for x in ("v", "i", "freq", "rocof")
        },
    )
    # one FREQ sample 15 Hz off a 60 Hz case (round 38: the raw estimator commanded every
    # device for its frame)
    fast = list(frames)
    fast[70] = f._replace(freq=np.where(np.arange(len(pmus)) == 0, 75.0, f.freq))
    cfg = c37.stream_config(case, pmus, 60)
    cfg2 = c37.config_frame(cfg)
    tracks = []
    for stream in (spiked, holed, fast):
        got = sources.merge(
            case, pmus, 60, [(cfg2, [c37.data_frame(cfg, cfg2, x) for x in stream])]
        )
        tracks.append(cl.track(cl.LoopController(case, (), "ekf", SETTINGS, 0, 1.0), got.frames))
        if stream is not holed:
            assert got.flagged[c37.IMPLAUSIBLE] == 1 and not got.frames[70].valid[0]
            absent = got.flagged["test mode or absent (STAT bits 15-14 = 10)"]  # the frames dropped
            assert sources.unused_values(got.flagged) == (
                f"{absent + 1} PMU values not used by their STAT, or beyond any measurement "
                f"({absent} test mode or absent (STAT bits 15-14 = 10), 1 |V| > 3 pu, "
                "|I| > 1000 pu, |ROCOF| > 327.67 Hz/s or a frequency more than 10 Hz from "
                "nominal)"
            )
    assert np.array_equal(tracks[0].freq, tracks[1].freq)
    assert np.array_equal(tracks[2].freq, tracks[1].freq)
    assert np.abs(tracks[0].rel).max() < 1.0  # Hz


def test_a_frame_without_relative_speeds_gives_none_not_zero(kundur_run):
    """The library's track of frames whose first PMU is absent throughout: no relative
    speed can be formed (a COI needs every machine's speed), so `Diagnostics.rel` is nan
    in every frame (it held 0, the value the law acts on, idling the devices), while the
    other machines' speeds are estimated; the same frames with that PMU present form
    every relative speed."""
    case, _res, pmus, drawn = kundur_run
    from stabctl.estimation import closed_loop as cl

    frames = list(drawn)[:60]
    gone = np.arange(len(pmus)) == 0
    holed = [
        f._replace(
            valid=f.valid & ~gone,
            **{x: np.where(gone, np.nan, getattr(f, x)) for x in ("v", "i", "freq", "rocof")},
        )
        for f in frames
    ]
    for stream, whole in ((holed, False), (frames, True)):
        d = cl.track(cl.LoopController(case, (), "raw", SETTINGS, 0, 1.0), stream)
        assert d.formed.all() == whole and d.formed.any() == whole
        assert np.isfinite(d.rel).all() == whole and np.isnan(d.rel).all() != whole
        assert np.isfinite(d.freq[:, 1:]).all()


@pytest.mark.parametrize("estimator", ["ekf", "kf", "raw"])
def test_a_machine_unmeasured_longer_than_a_gap_has_no_speed_then_starts_again(
    kundur_run, estimator
):
    """G1's PMU values unusable (flagged) from 1.5 s to 5.5 s: the estimator predicted G1
    across all 4 s (the finding: 62.8 Hz, the ESDs commanded on it), where a gap of
    frames that long is not predicted across.  Once G1 has had no usable value for more
    than `sources.FILL_S` s it has no speed (no relative speed formed, the devices
    idle), and its estimate starts again at its next usable value: from 0.5 s after
    that, the track equals, within 20 mHz, that of the frames with G1 measured
    throughout."""
    from stabctl.estimation import closed_loop as cl
    from stabctl.storage.devices import uniform_fleet

    case, _res, pmus, drawn = kundur_run
    frames = list(drawn)
    g1 = np.arange(len(pmus)) == 0
    lost = set(range(90, 330))
    holed = [
        f._replace(
            valid=f.valid & ~g1,
            **{x: np.where(g1, np.nan, getattr(f, x)) for x in ("v", "i", "freq", "rocof")},
        )
        if k in lost
        else f
        for k, f in enumerate(frames)
    ]
    devices = uniform_fleet(case, 5).devices
    runs = [
        cl.track(cl.LoopController(case, devices, estimator, SETTINGS, 0, 6.0), x)
        for x in (holed, frames)
    ]
    d, whole = runs
    t = d.t
    usable = np.array([f.valid[0] for f in holed])
    seen = np.maximum.accumulate(np.where(usable, np.arange(t.size), -1))
    stale = t - t[np.maximum(seen, 0)] > sources.FILL_S + 1e-9
    assert stale.sum() >= 170 and np.array_equal(~d.formed, stale)
    assert (d.modes[stale] == 0).all() and np.isnan(d.freq[stale, 0]).all()
    after = t >= t[330] + 0.5
    assert np.abs(d.freq[after] - whole.freq[after]).max() < 0.02  # Hz


def test_a_source_with_a_pmu_unusable_longer_than_a_gap_is_no_ground_for_error_figures(
    tmp_path,
):
    """`estimate rmse --source` of a recording whose G1 values are flagged (STAT bits
    15-14 = 11) from 0.5 s to 1.75 s presented its figures, where the same stretch of
    frames missing is refused: the estimators cannot be evaluated across either.  It is
    refused naming the PMU and the stretch; flagged for 0.75 s it is evaluated."""
    from click.testing import CliRunner
    from pmu_streams import kundur_stream

    from stabctl.cli import main

    _, _, cfg, frames = kundur_stream(t_end=2.0)
    g1 = np.arange(len(frames[0].valid)) == 0
    run = ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101"]
    run += ["--clear-cycles", "6", "--tf", "2", "--seed", "1", "--source"]
    for last, refused in ((105, True), (75, False)):
        flagged = [
            f._replace(
                valid=f.valid & ~g1,
                **{x: np.where(g1, np.nan, getattr(f, x)) for x in ("v", "i", "freq", "rocof")},
            )
            if 30 <= k <= last
            else f
            for k, f in enumerate(frames)
        ]
        path = tmp_path / f"g1_{last}.c37"
        c37.record(path, cfg, flagged)
        res = CliRunner().invoke(main, [*run, str(path)])
        if refused:
            assert res.exit_code == 2, res.output
            assert (
                f"error: --source {path}: B1:G1's values unusable from t = 0.5000 s to "
                "1.7500 s (1.28 s between usable values): longer than 1 s without a usable "
                "value, which the estimators cannot be evaluated across" in res.stderr
            )
        else:
            assert res.exit_code == 0, res.output


def _closing_server():
    """(host, port) of a server that accepts one peer and closes before any CFG-2."""
    import socket
    import threading

    srv = socket.create_server(("127.0.0.1", 0))

    def run():
        conn, _ = srv.accept()
        conn.close()
        srv.close()

    threading.Thread(target=run, daemon=True).start()
    return srv.getsockname()[:2]


def test_the_streams_received_are_kept_when_another_fails(kundur_run, tmp_path):
    """Of two servers, one sends its stream whole and the other closes before its CFG-2:
    the source is refused (a PMU has no stream), and the stream received, which was
    dropped (round 58 AZ17: three streams received whole, nothing kept), is handed on as
    on Ctrl-C, and `estimate track` writes it beside --out as a partial recording that
    reads back frame for frame."""
    from click.testing import CliRunner

    from stabctl.cli import main

    case, _res, pmus, drawn = kundur_run
    sub = c37.stream_config(case, [pmus[0], pmus[1]], SETTINGS.rate, 1)
    frames = [f.of([0, 1]) for f in drawn]
    with StreamServer.of_frames(sub, frames, speed=float("inf")) as server:
        src = sources.Source(servers=(server.address, _closing_server()))
        with pytest.raises(InputError, match="closed the connection before sending its CFG-2") as e:
            sources.read_frames(src, case, pmus, SETTINGS.rate, timeout=20, idcode=[1, 10])
    ((name, _cfg2, data),) = e.value.recordings
    assert name == f"127.0.0.1:{server.address[1]}" and len(data) == len(drawn)
    with StreamServer.of_frames(sub, frames, speed=float("inf")) as server:
        (h, p), (h2, p2) = server.address, _closing_server()
        args = ["--idcode", "1,10", "--frames", str(len(drawn)), "--out", str(tmp_path / "t.csv")]
        source = f"tcp://{h}:{p},{h2}:{p2}"
        res = CliRunner().invoke(main, ["estimate", "track", "kundur", "--source", source, *args])
    assert res.exit_code == 2, res.output
    assert "nothing is tracked, but" in res.output and "a partial recording" in res.output
    kept = tmp_path / "t.received.c37"
    assert not (tmp_path / "t.csv").exists()
    assert c37.recorded_frames(kept)[1] == [
        c37.data_frame(sub, c37.config_frame(sub), f) for f in frames
    ]
