"""The storage loop closed over C37.118.2 on loopback TCP (stabctl.estimation.c37_loop):
the paper's Case 2 with the EKF controller subscribing to miniWECC's 34 PMUs runs exactly
as the in-process loop with the frames through the codec, stays stable as in process, and
every frame's round trip is measured; the answer frame decoded by hand; a broken loop is
named."""

import struct
import threading
import time

import numpy as np
import pytest

pytest.importorskip("pyc37")

from c37_check import crc_ccitt

import stabctl
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import InputError
from stabctl.estimation import c37, c37_loop
from stabctl.estimation import closed_loop as cl
from stabctl.studies.cases import CASE2

T_END = 10.0


@pytest.fixture(scope="module")
def case2_runs():
    """Case 2 (miniWECC, bus-83 fault on line 83-33 cleared after 6 cycles) with 5 % ESDs
    commanded by the EKF, by each transport."""
    case = stabctl.load_case("miniwecc")
    sim = stabctl.Simulator(case)
    events = CASE2.fault.events(CASE2.cycles["figure"] / case.freq_hz)
    return {
        t: cl.run_closed_loop(sim, events, T_END, cl.LoopOptions(5, "ekf", transport=t))
        for t in cl.TRANSPORTS
    }


def test_case2_over_tcp_is_the_loop_in_process_through_the_codec(case2_runs):
    tcp, codec = case2_runs["tcp"], case2_runs["codec"]
    np.testing.assert_array_equal(tcp.result.speed, codec.result.speed)
    np.testing.assert_array_equal(tcp.diagnostics.modes, codec.diagnostics.modes)
    np.testing.assert_array_equal(tcp.diagnostics.t, codec.diagnostics.t)
    assert tcp.result.meta["switchings"] == codec.result.meta["switchings"]


def test_case2_over_tcp_is_stable_as_in_process(case2_runs):
    """Stable with the same switchings and no false action; the speeds within 1e-5 pu of
    the loop fed float64 frames (the codec's 1 mHz FREQ and float32 phasors only)."""
    tcp, process = case2_runs["tcp"], case2_runs["process"]
    assert tcp.result.stable and process.result.stable
    assert cl.false_actions(tcp) == cl.false_actions(process) == 0
    assert len(tcp.result.meta["switchings"]) == len(process.result.meta["switchings"])
    assert np.max(np.abs(tcp.result.speed - process.result.speed)) < 1e-5


def test_every_frame_of_the_loop_is_answered_and_timed(case2_runs):
    """One frame per reporting instant after the start (60 frames/s for 10 s), each
    answered; the round trips are wall-clock figures, all positive, counted late against
    the modelled 50 ms latency."""
    link = case2_runs["tcp"].link
    assert link["frames"] == round(T_END * 60)
    rt = link["round_trip_ms"]
    assert 0 < rt["median"] <= rt["p99"] <= rt["max"]
    late = link["late"]
    assert (late == 0) == (rt["max"] <= 50.0)
    assert case2_runs["process"].link is None


def test_the_answer_frame_decoded_by_hand():
    """SYNC 0xAA41 (command frame, version 1), FRAMESIZE, IDCODE, SOC, FRACSEC of the
    answered data frame, CMD 0x0008 (extended frame), one signed byte per ESD, CHK."""
    data = c37_loop.modes_frame(7, 1_700_000_001, 250_000, [1, 0, -1, 1])
    sync, size, idcode, soc, fracsec, cmd = struct.unpack(">HHHIIH", data[:16])
    assert (sync, size, idcode, soc, fracsec, cmd) == (0xAA41, 22, 7, 1_700_000_001, 250_000, 8)
    assert struct.unpack(">4b", data[16:20]) == (1, 0, -1, 1)
    assert struct.unpack(">H", data[-2:])[0] == crc_ccitt(data[:-2])
    stamp, modes = c37_loop.read_modes(data, 4)
    assert stamp == 1_700_000_001 * c37.TIME_BASE + 250_000 and modes.tolist() == [1, 0, -1, 1]
    with pytest.raises(InputError, match="not the modes of 3 ESDs"):
        c37_loop.read_modes(data, 3)
    with pytest.raises(InputError, match="not readable"):
        c37_loop.read_modes(data[:-1] + bytes([data[-1] ^ 1]), 4)


@pytest.fixture
def kundur_loop():
    case = stabctl.load_case("kundur")
    sim = stabctl.Simulator(case)
    return sim, [fault_with_clearing(case, 3, 101, 1.0, 7)]


def test_a_plant_without_controller_is_named(kundur_loop):
    sim, events = kundur_loop
    from stabctl.storage.devices import uniform_fleet

    ctrl = cl.LoopController(sim.case, uniform_fleet(sim.case, 10).devices, "ekf", *_rest())
    cfg = c37.stream_config(sim.case, ctrl.pmus, 60)
    with c37_loop.PlantLink(ctrl, cfg, timeout=0.3) as link:
        partial = sim.run(events, t_end=0.1)
        with pytest.raises(InputError, match=r"no controller connected within 0\.3 s"):
            link(0.05, partial)


def test_a_controller_of_other_pmus_is_refused(kundur_loop):
    sim, events = kundur_loop
    from stabctl.storage.devices import uniform_fleet

    ctrl = cl.LoopController(sim.case, uniform_fleet(sim.case, 10).devices, "ekf", *_rest())
    cfg = c37.stream_config(sim.case, ctrl.pmus, 60)
    other = c37.stream_config(sim.case, ctrl.pmus[:2], 60)
    with c37_loop.PlantLink(ctrl, cfg, timeout=1) as link:
        errors = []
        thread = threading.Thread(
            target=lambda: _catch(errors, c37_loop.serve_controller, ctrl, other, *link.address)
        )
        thread.start()
        with pytest.raises(InputError, match=r"1 peer.s. dropped, .*closed before 'start'"):
            link(0.05, sim.run(events, t_end=0.1))
        thread.join(timeout=10)
    assert "its CFG-2 station names" in str(errors[0])


def three_frames_then(kundur_loop, t_end, times=(1 / 60, 2 / 60, 3 / 60)):
    """A plant link answered by a remote controller for three frames (at `times`, s;
    1/60 to 3/60 s), then ended with the end-of-run header at `t_end` (None: closed
    without it); returns what the controller returned and what it raised."""
    sim, events = kundur_loop
    from stabctl.storage.devices import uniform_fleet

    partial = sim.run(events, t_end=0.1)
    devices = uniform_fleet(sim.case, 10).devices
    ctrl = cl.LoopController(sim.case, devices, "ekf", *_rest())
    remote = cl.LoopController(sim.case, devices, "ekf", *_rest())
    cfg = c37.stream_config(sim.case, ctrl.pmus, 60)
    out: list = []
    errors: list = []
    plant: list = []  # what the plant's end raised (a controller that hung up)
    with c37_loop.PlantLink(ctrl, cfg, timeout=5) as link:
        thread = threading.Thread(
            target=_catch, args=(errors, _serve_into, out, remote, cfg, *link.address)
        )
        thread.start()
        try:
            for t in times:
                link(t, partial)
            if t_end is not None:
                link.finish(t_end)
        except InputError as exc:
            plant.append(exc)
    thread.join(timeout=10)
    return out, errors + plant


def test_a_plant_that_stops_without_its_end_of_run_header_is_said(kundur_loop):
    """Three frames answered, then the plant closes: after its end-of-run header (a header
    frame, `end_of_run_frame`) the controller returns the count; without it (a plant
    killed mid-run: the finding, exit 0 with a partial result presented as whole) it
    raises PlantStopped naming the frames answered and the last time stamp."""
    for ends in (True, False):
        out, errors = three_frames_then(kundur_loop, 3 / 60 if ends else None)
        if ends:
            assert out == [3] and not errors
        else:
            assert not out and isinstance(errors[0], c37_loop.PlantStopped)
            assert "after 3 frame(s) answered, the last at t = 0.0500 s" in str(errors[0])


@pytest.mark.parametrize(
    "times, k",
    [((1 / 60, 2 / 60, 2.5 / 60), 3), ((1 / 60, 1.5 / 60, 2 / 60), 2)],
)
def test_a_plant_s_frames_off_its_rate_s_grid_are_refused(kundur_loop, times, k):
    """Frames stamped half a frame off the 60 frames/s grid, or every 1/120 s under a
    60 frames/s CFG-2, were answered (exit 0; the half-frame steps counted as gaps and fed
    to the estimator as missing frames): `estimate track` and `pmu record` refuse such a
    stream.  The controller now checks each frame on the grid of the plant's first, as
    they do, and names the frame."""
    out, errors = three_frames_then(kundur_loop, 3 / 60, times)
    assert not out and isinstance(errors[0], InputError)
    said = str(errors[0])
    assert f"its frame {k} after 'start': data frame {k} is stamped" in said
    assert "not a reporting instant of its CFG-2's DATA_RATE 60" in said
    assert f"after {k - 1} frame(s) answered" in said


def test_a_plant_that_never_ends_its_run_is_refused_at_the_stream_cap(kundur_loop, monkeypatch):
    """A plant that streams on and on without its end-of-run header: the controller kept
    a row per frame answered without bound.  It answers at most the data frames a stream
    received may hold (`c37_tcp.MAX_STREAM_BYTES`, here two frames' bytes and one), then
    refuses the plant naming the cap; within it the run is answered to its end."""
    sim, _events = kundur_loop
    pmus = cl.LoopController(sim.case, (), "ekf", *_rest()).pmus
    cfg2 = c37.config_frame(c37.stream_config(sim.case, pmus, 60))
    one = c37.data_frame_size(cfg2)
    monkeypatch.setattr(c37_loop, "MAX_STREAM_BYTES", 2 * one + 1)
    out, errors = three_frames_then(kundur_loop, 3 / 60)
    assert not out and isinstance(errors[0], InputError), (out, errors)
    assert "sent more than 2 data frames (what a stream received may hold, " in str(errors[0])
    monkeypatch.setattr(c37_loop, "MAX_STREAM_BYTES", 3 * one)
    assert three_frames_then(kundur_loop, 3 / 60) == ([3], [])


@pytest.mark.parametrize(
    "t_end, whole",
    [(3 / 60, True), (3.9 / 60, True), (30.0, False), (4.5 / 60, False), (2 / 60, False)],
)
def test_an_end_of_run_that_is_not_the_last_frame_s_is_a_partial_run(kundur_loop, t_end, whole):
    """A plant that sent frames to 0.05 s and then the end-of-run header 'end of run at
    t = 30 s' was answered with exit 0 ('answered 3 frames'): the header was taken as the
    end whatever its t.  The last frame answered must be the last reporting instant at or
    before the announced end (within 1/60 s before it); else the run is named partial
    (PlantStopped, exit 2), with the end announced and the last frame answered."""
    out, errors = three_frames_then(kundur_loop, t_end)
    if whole:
        assert out == [3] and not errors
    else:
        assert not out and isinstance(errors[0], c37_loop.PlantStopped)
        assert f"announced the end of its run at t = {t_end:.4f} s, after 3 frame(s) " in str(
            errors[0]
        )
        assert "the last at t = 0.0500 s" in str(errors[0])


def test_a_paced_plant_sends_at_its_time_stamps(kundur_loop):
    """A plant at speed 2 with its own controller (`Listen`, as `pmu plant --speed`):
    the frames from 1/60 s to 1 s go out over at least (1 - 1/60) / 2 s of wall clock,
    every one answered."""
    sim, events = kundur_loop
    from stabctl.storage.devices import uniform_fleet

    remote = cl.LoopController(sim.case, uniform_fleet(sim.case, 10).devices, "ekf", *_rest())
    cfg = c37.stream_config(sim.case, remote.pmus, 60)
    started = []
    listen = c37_loop.Listen(
        on_listen=lambda a: started.append(c37_loop.controller_thread(remote, cfg, a)), speed=2.0
    )
    t0 = time.perf_counter()
    run = cl.run_closed_loop(
        sim, events, 1.0, cl.LoopOptions(10, "ekf", transport="tcp"), serve=listen
    )
    assert time.perf_counter() - t0 >= (1 - 1 / 60) / 2
    assert run.link["frames"] == 60 and not started[0][1]
    assert np.isnan(run.diagnostics.rel[1:]).all()  # the plant sees the modes, not the speeds
    np.testing.assert_array_equal(run.diagnostics.modes[1:], np.array(remote.diagnostics().modes))


def test_a_loop_of_the_ideal_estimator_has_no_stream(kundur_loop):
    sim, events = kundur_loop
    with pytest.raises(InputError, match="no PMU stream"):
        cl.run_closed_loop(sim, events, 1.0, cl.LoopOptions(10, "ideal", transport="tcp"))


def _rest():
    """LoopController's arguments after the estimator: settings, seed, t_end."""
    from stabctl.estimation.settings import PMUSettings

    return PMUSettings(), 0, 2.0


def _serve_into(out, *args):
    """`serve_controller(*args)`, its count of frames answered appended to out."""
    out.append(c37_loop.serve_controller(*args).frames)


def _catch(errors, func, *args):
    try:
        func(*args)
    except InputError as exc:
        errors.append(exc)
