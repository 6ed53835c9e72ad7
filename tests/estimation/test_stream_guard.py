"""C37.118.2 streams that end early, lie about time, or come from strangers (issue 54,
items 2, 3, 5, 7): a receiver knows its end (`c37_tcp.End`) and says what it got short of
it, keeping what arrived; a server obeys only CRC-valid commands, drops silent, foreign
or not-allowed peers without ending its session, and serves peers side by side; a plant
takes as controller only an allowed peer that completes the handshake and refuses modes
outside {-1, 0, +1}; recordings whose time stamps repeat or go back, or whose every value
is absent, are refused by name."""

import contextlib
import re
import socket
import threading
import time

import numpy as np
import pytest

pytest.importorskip("pyc37")

import stabctl
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import InputError
from stabctl.estimation import c37, c37_loop, sources
from stabctl.estimation import closed_loop as cl
from stabctl.estimation import pmu as pm
from stabctl.estimation.c37_tcp import End, Guard, StreamServer, receive
from stabctl.estimation.settings import PMUSettings

RATE = 60


@pytest.fixture(scope="module")
def kundur_stream():
    """Kundur's bus-3 fault, 1 s: its 4 PMUs' 61 frames (t = 0 .. 1 s)."""
    case = stabctl.load_case("kundur")
    res = stabctl.Simulator(case).run([fault_with_clearing(case, 3, 101, 0.5, 7)], t_end=1.0)
    pmus = pm.machine_pmus(case)
    frames = list(pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(), seed=1))
    cfg = c37.stream_config(case, pmus, RATE)
    cfg2 = c37.config_frame(cfg)
    return case, pmus, cfg, cfg2, frames


def _cut_server(cfg2, data, cut_last: bool):
    """A server that sends CFG-2 and the data frames, then (cut_last) half of one more
    frame, and closes."""
    srv = socket.create_server(("127.0.0.1", 0))

    def run():
        conn, _ = srv.accept()
        with conn:
            conn.recv(100)  # 'cfg2'
            conn.sendall(cfg2.convert2bytes())
            conn.recv(100)  # 'start'
            conn.sendall(b"".join(data))
            if cut_last:
                conn.sendall(data[0][: len(data[0]) // 2])
        srv.close()

    threading.Thread(target=run, daemon=True).start()
    return srv.getsockname()[:2]


def _encoded(cfg, cfg2, frames):
    return [c37.data_frame(cfg, cfg2, f) for f in frames]


def test_a_stream_shorter_than_its_end_keeps_what_came_and_says_so(kundur_stream):
    """A server with 61 frames asked for 100 (the finding: `pmu record --frames N` with N
    too large discarded every frame): the 61 are kept, `short` names the close, the count
    and the last time stamp (1 s); a frame cut in the middle is named as such."""
    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    with StreamServer(cfg2, data, speed=float("inf")) as server:
        got = receive(*server.address, End(frames=100), timeout=10)
    assert len(got.data) == 61 and got.data == data
    assert got.short == (
        "the server closed the connection after 61 data frames, the last stamped 1.0000 s, "
        "before 100 frames"
    )
    got = receive(*_cut_server(cfg2, data[:10], cut_last=True), End(tf=1.0), timeout=10)
    assert len(got.data) == 10
    assert "closed the connection in the middle of a frame after 10 data frames" in got.short


def test_a_stream_ends_at_its_end_and_the_server_is_told_stop(kundur_stream):
    """End(tf = 0.5 s) takes the frames stamped 0 .. 0.5 s (31) and says 'stop'; End(frames
    = 5) five; no end: every frame until the server closes, not short."""
    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    with StreamServer(cfg2, data, speed=float("inf")) as server:
        assert len(receive(*server.address, End(tf=0.5), timeout=10).data) == 31
        assert len(receive(*server.address, End(frames=5), timeout=10).data) == 5
        whole = receive(*server.address, timeout=10)
    assert len(whole.data) == 61 and not whole.short


def test_a_stream_holds_no_more_than_a_recording(kundur_stream, monkeypatch):
    """A source with neither a frame count nor a last time stamp keeps at most the data
    frames `c37_tcp.MAX_STREAM_BYTES` holds (the finding: an endless stream held 4.5 GB in
    11 min): past them one error naming the cap and what sets an end.  An end given was
    not bounded at all (``--frames 1000000000`` or ``--until 1e9`` against an endless
    server filled the memory as before): an end that needs more frames than the cap is
    refused before 'start', naming the frame size and the most frames and seconds; one
    within it is received.  The cap set to 5 data frames of Kundur's 4 PMUs against the
    61 frames of the fixture; streams of several servers share it."""
    from stabctl.estimation import c37, c37_tcp

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    size = c37.data_frame_size(cfg2)
    with StreamServer(cfg2, data, speed=float("inf")) as server:
        address = server.address
        with pytest.raises(
            InputError, match=r"more than 5 data frames \(what a stream received may hold\) "
        ):
            receive(*address, timeout=10, max_bytes=5 * size)
        for end, wanted in ((End(frames=20), 20), (End(tf=0.1), 7), (End(20, 0.05), 4)):
            if wanted > 5:
                with pytest.raises(
                    InputError,
                    match=rf"a stream to {re.escape(str(end))} is {wanted} data frames of "
                    rf"{size} bytes, more than the 0 MiB a stream received may hold \(at "
                    r"most 5 frames, 0 s of this stream; ",
                ):
                    receive(*address, end, timeout=10, max_bytes=5 * size + 3)
            else:
                assert len(receive(*address, end, timeout=10, max_bytes=5 * size).data) == 4
        assert len(receive(*address, End(frames=20), timeout=10).data) == 20
    assert c37_tcp.MAX_STREAM_BYTES == 256 * 2**20  # what a recording may hold


def test_server_drops_scans_silent_peers_bad_crc_and_strangers(kundur_stream):
    """A port scan (connect, close) does not end the server's session and is named; a
    silent peer is dropped after the time-out while a PDC beside it gets the whole stream;
    a 'start' whose CRC fails is not obeyed, and its peer named with it as it is dropped
    (silent after it, or closing); a peer not allowed is closed at once."""
    from pyc37.frame import CommandFrame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    with StreamServer(cfg2, data, speed=float("inf"), guard=Guard(timeout=0.5)) as server:
        socket.create_connection(server.address).close()  # a scan
        silent = socket.create_connection(server.address)
        time.sleep(0.2)
        assert not server.finished.is_set()
        got = receive(*server.address, timeout=10)  # served beside the silent peer
        assert len(got.data) == 61 and server.finished.wait(5)
        server.finished.clear()
        time.sleep(0.6)
        assert any(r.endswith(": silent for 0.5 s") for r in server.refused)
        assert any(r.endswith(": connected and closed the connection") for r in server.refused)
        silent.close()
        bad = bytearray(CommandFrame(1, "start").convert2bytes())
        bad[-1] ^= 0xFF
        ignored = "sent 1 frame this server ignores (no command, or its CRC fails), then "
        with socket.create_connection(server.address, timeout=2) as peer:
            peer.sendall(bytes(bad))
            peer.settimeout(2)
            try:
                assert peer.recv(100) == b""  # dropped when silent, nothing streamed
            except ConnectionError:
                pass  # nothing streamed
        said = ignored + "silent for 0.5 s"  # named as the peer is dropped (a loaded machine:
        deadline = time.monotonic() + 5  # the close may come before the words are kept)
        while time.monotonic() < deadline and not any(r.endswith(said) for r in server.refused):
            time.sleep(0.01)
        assert any(r.endswith(said) for r in server.refused), server.refused
        with socket.create_connection(server.address, timeout=2) as peer:
            peer.sendall(bytes(bad))
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and not server.refused[-1].endswith("connection"):
            time.sleep(0.01)
        assert server.refused[-1].endswith(ignored + "closed the connection")
    assert server.n_sent == 61  # from the PDC's session only
    with StreamServer(cfg2, data, speed=float("inf"), guard=Guard(allow=("10.9.9.9",))) as s:
        with socket.create_connection(s.address, timeout=2) as peer:
            peer.sendall(CommandFrame(1, "cfg2").convert2bytes())
            try:
                assert peer.recv(100) == b""  # closed, no CFG-2
            except ConnectionError:
                pass  # closed with the command unread
        time.sleep(0.1)
        assert s.refused and "not in the allowed peers" in s.refused[0]


def test_refused_peers_are_named_as_refused_and_a_scan_cannot_flood(kundur_stream):
    """Refused peers were named only once the server ended (and never after Ctrl-C): each
    is in `news` as it is refused.  Twenty refusals of one address name five
    (`NAMED_PER_WINDOW`); the fifteen others are counted, their count said as the server
    closes."""
    from stabctl.estimation.c37_tcp import NAMED_PER_WINDOW

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames[:5])
    with StreamServer(cfg2, data, speed=float("inf"), guard=Guard(allow=("10.9.9.9",))) as s:
        socket.create_connection(s.address).close()
        deadline = time.monotonic() + 5
        while not s.news and time.monotonic() < deadline:
            time.sleep(0.01)
        assert s.news and s.news[0].endswith(": not in the allowed peers")  # while serving
        for _ in range(19):
            socket.create_connection(s.address).close()
        while len(s.refused) < 20 and time.monotonic() < deadline:
            time.sleep(0.01)
        named = [x for x in s.news if x.endswith("not in the allowed peers")]
        assert len(s.refused) == 20 and len(named) == NAMED_PER_WINDOW == 5
    assert s.news[-1] == "dropped 127.0.0.1 15 more time(s) (not named above)"


def test_each_session_has_its_own_verdict(kundur_stream):
    """A peer that says 'start' and closes while a PDC streams set the server's one
    verdict (`short`) and ended its session: now its session is cut and named as its own,
    the PDC's is whole, and the server is done only once no session streams."""
    from pyc37.frame import CommandFrame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    with StreamServer(cfg2, data, speed=1.0, guard=Guard(timeout=2)) as server:
        got = {}
        pdc = threading.Thread(target=lambda: got.update(s=receive(*server.address, End(61))))
        pdc.start()
        time.sleep(0.3)
        with socket.create_connection(server.address, timeout=5) as stranger:
            stranger.sendall(CommandFrame(1, "start").convert2bytes())
            time.sleep(0.2)
            me = f"127.0.0.1:{stranger.getsockname()[1]}"
        time.sleep(0.2)
        assert not server.done() and not server.finished.is_set()
        pdc.join(10)
        assert server.finished.wait(5) and len(got["s"].data) == 61 and not got["s"].short
        deadline = time.monotonic() + 5
        while not server.done() and time.monotonic() < deadline:
            time.sleep(0.01)
    [cut] = server.cut
    assert cut.peer == me and cut.ended == "closed the connection" and 0 < cut.sent < 61
    assert [s.whole for s in server.sessions] == [False, True] and server.n_sent == 61


def _plant(case, timeout, allow=()):
    from stabctl.storage.devices import uniform_fleet

    ctrl = cl.LoopController(case, uniform_fleet(case, 10).devices, "ekf", PMUSettings(), 0, 2.0)
    cfg = c37.stream_config(case, ctrl.pmus, RATE)
    return ctrl, cfg, c37_loop.PlantLink(ctrl, cfg, timeout=timeout, allow=allow)


def test_a_peer_whose_handshake_ends_after_the_controller_s_is_dropped_and_named():
    """Two peers handshake at once: the one that says 'start' first takes the loop, and the
    other, closed when its own 'start' came, was dropped without a word (round 29: the
    summary named no second peer).  It is named among the dropped peers."""
    from pyc37.frame import CommandFrame

    case = stabctl.load_case("kundur")
    partial = stabctl.Simulator(case).run([fault_with_clearing(case, 3, 101, 1.0, 7)], t_end=0.1)
    ctrl, cfg, link = _plant(case, timeout=60)  # the handshakes' deadline: a first compile
    with link, socket.create_connection(link.address, timeout=5) as late:
        late.sendall(CommandFrame(1, "cfg2").convert2bytes())  # its handshake begun
        threading.Thread(
            target=lambda: c37_loop.serve_controller(ctrl, cfg, *link.address, timeout=60),
            daemon=True,
        ).start()
        link(0.05, partial)  # answered: the controller took the loop
        late.sendall(CommandFrame(1, "start").convert2bytes())
        me = f"127.0.0.1:{late.getsockname()[1]}"
        said = f"{me}: another peer took the loop first"
        assert _until(lambda: said in link.refused), link.refused


def test_a_plant_takes_no_stranger_as_controller():
    """The first peer of the plant is a stranger that never says 'start': it is dropped and
    the controller that connects next runs the loop; a peer not allowed is closed; an
    answer carrying mode +127 (the finding: it drove a 45 MW device at 57 pu) is
    refused by name."""
    case = stabctl.load_case("kundur")
    sim = stabctl.Simulator(case)
    events = [fault_with_clearing(case, 3, 101, 1.0, 7)]
    partial = sim.run(events, t_end=0.1)
    ctrl, cfg, link = _plant(case, timeout=5)  # (its first answer took 4.3 s under load)
    with link:
        stranger = socket.create_connection(link.address)
        thread = threading.Thread(
            target=lambda: (
                time.sleep(0.2),
                c37_loop.serve_controller(ctrl, cfg, *link.address, timeout=5),
            ),
            daemon=True,
        )
        thread.start()
        modes = link(0.05, partial)
        assert modes.shape == (ctrl.mode.size,) and not link.refused  # still waiting
        stranger.close()
        time.sleep(0.3)
        assert "closed before 'start'" in link.refused[0]
    _, _, link = _plant(case, timeout=0.5, allow=("10.9.9.9",))
    with (
        link,
        socket.create_connection(link.address),
        pytest.raises(InputError, match="not in the allowed peers"),
    ):
        link(0.05, partial)
    n = ctrl.mode.size
    answer = c37_loop.modes_frame(1, 0, 0, np.r_[127, np.zeros(n - 1, int)])
    with pytest.raises(InputError, match=r"mode\(s\) \[127\]: an ESD's mode is -1, 0 or \+1"):
        c37_loop.read_modes(answer, n)


def test_a_controller_at_another_rate_is_refused(kundur_stream):
    """`pmu control --rate 30` against a 60 frames/s plant: named, not accepted."""
    case = kundur_stream[0]
    ctrl, _, link = _plant(case, timeout=2)
    slow = c37.stream_config(case, ctrl.pmus, 30)
    with link:
        threading.Thread(target=lambda: _quiet(link, 0.05), daemon=True).start()
        with pytest.raises(InputError, match=r"its CFG-2 DATA_RATE 60, not the 30 expected"):
            c37_loop.serve_controller(ctrl, slow, *link.address, timeout=5)


def _quiet(link, t):
    case = link.ctrl.case
    sim = stabctl.Simulator(case)
    try:
        link(t, sim.run([fault_with_clearing(case, 3, 101, 1.0, 7)], t_end=0.1))
    except (InputError, OSError):  # the controller refused, the plant closed
        pass


@pytest.mark.parametrize(
    "edit, needle",
    [
        ("repeat", r"data frame 11 repeats the time stamp of frame 10"),
        ("back", r"data frame 11 goes back from the time stamp of frame 10"),
    ],
)
def test_recordings_whose_time_stamps_repeat_or_go_back_are_refused(
    kundur_stream, tmp_path, edit, needle
):
    """Two frames of one time stamp or one stamped backwards (the finding: the later frame
    replaced the earlier without a word, 548.7 mHz reported for 228.0)."""
    case, pmus, cfg, cfg2, frames = kundur_stream
    frames = list(frames)
    frames[10] = frames[9] if edit == "repeat" else frames[8]
    path = tmp_path / "r.c37"
    path.write_bytes(cfg2.convert2bytes() + b"".join(_encoded(cfg, cfg2, frames)))
    with pytest.raises(InputError, match=needle):
        sources.read_frames(sources.parse_source(str(path)), case, pmus, RATE)


def test_a_recording_given_twice_is_refused_even_when_read_to_an_end(kundur_stream, tmp_path):
    """Round 40: a recording concatenated with itself (its CFG-2 again, then stamps going
    back) was read by `estimate rmse` to the run's end, the rest never read nor named,
    where `estimate track` refused it.  Read to an end (`End(tf=0.5)`) it is refused too."""
    from stabctl.estimation.c37_tcp import End

    case, pmus, cfg, cfg2, frames = kundur_stream
    once = cfg2.convert2bytes() + b"".join(_encoded(cfg, cfg2, list(frames)))
    path = tmp_path / "twice.c37"
    path.write_bytes(once + once)
    source = sources.parse_source(str(path))
    for end in (None, End(tf=0.5)):
        with pytest.raises(InputError, match=r"data frame 62 goes back from the time stamp of"):
            sources.read_frames(source, case, pmus, RATE, end=end)


def _restamped(frame: bytes, soc: int, count: int) -> bytes:
    """A data frame's bytes with SOC and FRACSEC's count replaced, its CRC-CCITT redone
    (C37.118.2-2011 Table 2, Annex B)."""
    out = bytearray(frame)
    out[6:10], out[11:14] = soc.to_bytes(4, "big"), count.to_bytes(3, "big")
    crc = 0xFFFF
    for byte in out[:-2]:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    out[-2:] = crc.to_bytes(2, "big")
    return bytes(out)


@pytest.mark.parametrize(
    "edit, needle",
    [
        (
            "one count later",
            r"data frame 11 is on the reporting instant of frame 10 \(\d+\.\d+ s, UNIX\), "
            r"1e-06 s after it, within one FRACSEC count: its data would replace that frame's",
        ),
        (
            "a day ahead",
            r"data frame 12 goes back from the time stamp of frame 11 .*; frame 11 is the one "
            r"out of order, ahead of both its neighbours",
        ),
    ],
)
def test_a_frame_on_another_s_reporting_instant_is_refused_and_one_ahead_is_named(
    kundur_stream, tmp_path, edit, needle
):
    """A frame stamped one FRACSEC count after the one before (the finding: it passed the
    order check, being later, then was read on that frame's reporting instant, replacing
    its data, and its own instant was reported as a gap) is refused as a repeat is; a
    frame stamped a day ahead is named as the one out of order, not the frame after it."""
    case, pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    soc, count = int.from_bytes(data[9][6:10], "big"), int.from_bytes(data[9][11:14], "big")
    data[10] = (
        _restamped(data[10], soc, count + 1)
        if edit == "one count later"
        else _restamped(data[10], soc + 86400, int.from_bytes(data[10][11:14], "big"))
    )
    path = tmp_path / "r.c37"
    path.write_bytes(cfg2.convert2bytes() + b"".join(data))
    with pytest.raises(InputError, match=needle):
        sources.read_frames(sources.parse_source(str(path)), case, pmus, RATE)


def test_replay_refuses_what_a_reader_refuses_and_a_configuration_alone(kundur_stream, tmp_path):
    """`pmu replay` of a recording with a repeated time stamp served it (paced by stamps
    that go back) until a reader refused it; one with the CFG-2 alone was tracked as 0
    frames with exit 0.  Both are refused by name, by `pmu replay` before it listens."""
    from click.testing import CliRunner

    from stabctl.cli import main

    case, pmus, cfg, cfg2, frames = kundur_stream
    frames = list(frames)
    frames[10] = frames[9]
    dup = tmp_path / "dup.c37"
    dup.write_bytes(cfg2.convert2bytes() + b"".join(_encoded(cfg, cfg2, frames)))
    bare = tmp_path / "bare.c37"
    bare.write_bytes(cfg2.convert2bytes())
    for path, needle in (
        (dup, f"RECORDING {dup}: data frame 11 repeats the time stamp of frame 10"),
        (bare, f"RECORDING {bare}: no data frame (a configuration frame only)"),
    ):
        res = CliRunner().invoke(main, ["pmu", "replay", str(path), "--port", "0"])
        assert res.exit_code == 2 and needle in res.stderr, res.output
    with pytest.raises(InputError, match=f"--source {bare}: no data frame"):
        sources.read_frames(sources.parse_source(str(bare)), case, pmus, RATE)


def test_an_all_absent_recording_is_refused_and_ends_cut_it(kundur_stream, tmp_path):
    """A recording whose every value is flagged absent (the finding: reported as measured
    0 mHz) is refused; a recording read to an end it does not reach is short."""
    case, pmus, cfg, cfg2, frames = kundur_stream
    dead = [pm.Frame(f.t, np.zeros_like(f.valid), *f[2:]) for f in frames]
    path = tmp_path / "dead.c37"
    path.write_bytes(cfg2.convert2bytes() + b"".join(_encoded(cfg, cfg2, dead)))
    with pytest.raises(
        InputError,
        match=r"every PMU value of its 61 frames is missing or not used: 244 PMU values not "
        r"used by their STAT \(244 test mode or absent \(STAT bits 15-14 = 10\)\), 0 missing",
    ):
        sources.read_frames(sources.parse_source(str(path)), case, pmus, RATE)
    path = tmp_path / "r.c37"
    path.write_bytes(cfg2.convert2bytes() + b"".join(_encoded(cfg, cfg2, frames)))
    src = sources.parse_source(str(path))
    got = sources.read_frames(src, case, pmus, RATE, End(tf=0.5))
    assert len(got.frames) == 31 and not got.short
    got = sources.read_frames(src, case, pmus, RATE, End(tf=2.0))
    assert len(got.frames) == 61
    assert got.short == (f"{path}: 61 data frames, the last stamped 1.0000 s, before t = 2 s",)


def test_more_servers_than_pmus_are_refused(kundur_stream):
    """`--source tcp://127.0.0.1:1-65535` (the finding: a thread per port): refused before
    any connection, as Kundur has 4 PMUs."""
    case, pmus, *_ = kundur_stream
    src = sources.parse_source("tcp://127.0.0.1:1-65535")
    with pytest.raises(InputError, match="65535 servers for 4 PMUs"):
        sources.read_frames(src, case, pmus, RATE)


def _until(check, seconds=5.0):
    """Wait (polling) until check() is true, at most `seconds`; its last value."""
    deadline = time.monotonic() + seconds
    while not (ok := check()) and time.monotonic() < deadline:
        time.sleep(0.01)
    return ok


def _frames_until_close(conn, n=None):
    """The frames a raw peer reads from conn until the server closes (or n data
    frames)."""
    from stabctl.estimation.c37_tcp import _read_frame

    got = []
    while n is None or sum(f[1] & 0x70 == 0 for f in got) < n:
        frame = _read_frame(conn)
        if frame is None:
            break
        got.append(frame)
    return got


def test_a_server_ends_at_once_when_closed(kundur_stream):
    """`close` waited 5 s for the accept thread stuck in accept() (closing the listening
    socket does not wake it), and the command line closes each server twice: a server
    ended about 10 s after its stream was sent whole.  Now close returns at once, and a
    second close does nothing."""
    _case, _pmus, cfg, cfg2, frames = kundur_stream
    server = StreamServer(cfg2, _encoded(cfg, cfg2, frames[:5]), speed=float("inf"))
    time.sleep(0.05)  # the accept thread is in accept()
    t0 = time.monotonic()
    server.close()
    server.close()
    assert time.monotonic() - t0 < 1.0


def test_a_peer_that_reads_nothing_and_stays_is_not_whole(kundur_stream):
    """A peer that said 'start', read nothing and stayed connected was counted whole
    (every byte fitted its receive buffer and its kernel acknowledged it): the server
    ended on it and the real PDC coming next was reset.  Whole now needs the PDC's
    orderly close after the last frame: this peer's session is cut, named, and the real
    PDC is served whole."""
    from pyc37.frame import CommandFrame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    server = StreamServer(cfg2, data, speed=float("inf"), guard=Guard(timeout=0.5))
    with server, socket.create_connection(server.address, timeout=5) as stranger:
        stranger.sendall(CommandFrame(1, "cfg2").convert2bytes())
        stranger.sendall(CommandFrame(1, "start").convert2bytes())
        assert _until(lambda: server.sessions)
        assert not server.finished.is_set()
        [cut] = server.sessions
        assert cut.sent == 61 and "did not close the connection within 0.5 s" in cut.ended
        got = receive(*server.address, timeout=10)
        assert len(got.data) == 61 and server.finished.wait(5)
    assert [s.whole for s in server.sessions] == [False, True]


def test_silent_peers_give_their_places_to_a_pdc(kundur_stream):
    """Eight silent connections held every place (`Guard.max_peers`): the PDC coming next
    was closed and told its commands addressed another stream.  The peer silent longest
    now gives its place, named; with every place held by a peer that sent a command, the
    new one is refused and the client's message names the possible causes."""
    from pyc37.frame import CommandFrame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames[:10])
    guard = Guard(timeout=5, max_peers=2)
    with StreamServer(cfg2, data, speed=float("inf"), guard=guard) as server:
        silent = [socket.create_connection(server.address) for _ in range(2)]
        time.sleep(0.1)
        me = f"127.0.0.1:{silent[0].getsockname()[1]}"
        assert len(receive(*server.address, End(frames=10), timeout=5).data) == 10
        assert _until(lambda: any("its place given to a new peer" in r for r in server.refused))
        assert any(r.startswith(f"{me}: sent no command in ") for r in server.refused)
        for peer in silent:
            peer.close()
        # each sends its command before the next connects: a peer that has sent none yet
        # may give its place to the next (when the closed peers' are not freed yet)
        busy = []
        for _ in range(2):
            peer = socket.create_connection(server.address, timeout=5)
            busy.append(peer)
            peer.sendall(CommandFrame(1, "cfg2").convert2bytes())
            assert _frames_until_close(peer, 0) == [] and peer.recv(1000)  # the CFG-2
        with pytest.raises(InputError, match="serves no more peers at once, does not allow"):
            receive(*server.address, End(frames=10), timeout=5)
        full = "2 peers served, each streaming or within its first 5 s"
        assert _until(lambda: any(full in r for r in server.refused))
        for peer in busy:
            peer.close()


def test_peers_that_ask_and_never_stream_give_their_places_to_a_pdc(kundur_stream):
    """Round 38: peers asking for the header every half second, never 'start', held every
    place for as long as they kept on, and a PDC was refused.  Once connected beyond the
    time-out without a stream, the longest connected gives its place, named."""
    from pyc37.frame import CommandFrame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames[:10])
    stop = threading.Event()

    def ask(peer):
        while not stop.is_set():
            with contextlib.suppress(OSError):
                peer.sendall(CommandFrame(1, "header").convert2bytes())
                peer.recv(65536)
            stop.wait(0.5)

    guard = Guard(timeout=2, max_peers=2)
    with StreamServer(cfg2, data, speed=float("inf"), guard=guard) as server:
        askers = [socket.create_connection(server.address, timeout=5) for _ in range(2)]
        threads = [threading.Thread(target=ask, args=(p,), daemon=True) for p in askers]
        for t in threads:
            t.start()
        try:
            time.sleep(0.5)  # within the time-out: their places are theirs
            with pytest.raises(InputError, match="serves no more peers at once"):
                receive(*server.address, End(frames=10), timeout=5)
            time.sleep(2.5)
            assert len(receive(*server.address, End(frames=10), timeout=5).data) == 10
            first = f"127.0.0.1:{askers[0].getsockname()[1]}"
            assert _until(
                lambda: any(r.startswith(f"{first}: started no stream in ") for r in server.refused)
            )
        finally:
            stop.set()
            for t in threads:
                t.join(5)
            for p in askers:
                p.close()


def test_a_server_short_of_file_descriptors_says_so_and_serves_on(kundur_stream, monkeypatch):
    """An accept() failing with EMFILE (the open-file limit reached) ended the accept
    thread without a word: the server never served again.  It is said once, naming the
    limit, and the server serves once accept() works again."""
    import errno

    from stabctl.estimation import c37_tcp

    real, fails = c37_tcp._accept_conn, [0]

    def failing(sock):
        if fails[0] < 3:
            fails[0] += 1
            raise OSError(errno.EMFILE, "Too many open files")
        return real(sock)

    monkeypatch.setattr(c37_tcp, "_accept_conn", failing)
    _case, _pmus, cfg, cfg2, frames = kundur_stream
    with StreamServer(cfg2, _encoded(cfg, cfg2, frames[:5]), speed=float("inf")) as server:
        assert len(receive(*server.address, timeout=5).data) == 5
    said = [x for x in server.news if "cannot accept a peer" in x]
    assert len(said) == 1 and "open-file limit, ulimit -n, is" in said[0], server.news


def test_stop_pauses_start_resumes_and_config_requests_are_answered(kundur_stream):
    """'stop' closed the connection, so 'start' could not resume (C37.118.2-2011 Table 15:
    'turn off transmission' stops the data frames only), and a CFG-2 asked for mid-stream
    was ignored without a word.  Now 'stop' pauses, 'start' resumes where it stopped
    (every frame once), a CFG-2 request mid-stream is answered, a CFG-1 request is named
    with the session's verdict, and the session is whole."""
    from pyc37.frame import CommandFrame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    cfg1 = CommandFrame(1, "cfg1").convert2bytes()
    with StreamServer(cfg2, data, speed=2.0, guard=Guard(timeout=2)) as server:
        with socket.create_connection(server.address, timeout=5) as pdc:
            pdc.sendall(CommandFrame(1, "start").convert2bytes())
            got = _frames_until_close(pdc, 10)
            pdc.sendall(CommandFrame(1, "stop").convert2bytes())
            time.sleep(0.3)  # paused: what was in flight arrives
            pdc.settimeout(0.3)
            try:
                while True:
                    got += _frames_until_close(pdc, 1)
            except TimeoutError:
                pass
            pdc.settimeout(5)
            paused = len(got)
            assert paused < 30 and not server.sessions
            pdc.sendall(CommandFrame(1, "start").convert2bytes())
            pdc.sendall(CommandFrame(1, "cfg2").convert2bytes() + cfg1)
            got += _frames_until_close(pdc)
        assert _until(lambda: server.sessions)
    kinds = [c37.frame_kind(f) for f in got]
    assert [f for f in got if f[1] & 0x70 == 0] == data  # every frame, once, in order
    assert "CFG-2" in " ".join(kinds[paused:]), kinds
    [session] = server.sessions
    assert session.whole and session.sent == 61
    assert str(session).endswith(
        "whole; it asked for CFG-1 (command 4), which this server "
        "does not send (it sends its stream's CFG-2 only, command 5)"
    )


def test_a_pdc_that_has_its_cfg2_is_served_after_another_ended_whole(kundur_stream):
    """PDC B had asked for the CFG-2 and not yet said 'start' when PDC A got the stream
    whole: the server ended under B (0 frames, its connection closed).  A PDC past its
    first command now keeps the server until its own session ends; a silent peer does
    not."""
    from pyc37.frame import CommandFrame

    from stabctl.estimation.c37_tcp import _read_frame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    with StreamServer(cfg2, data, speed=float("inf"), guard=Guard(timeout=5)) as server:
        with (
            socket.create_connection(server.address, timeout=5) as b,
            socket.create_connection(server.address, timeout=5),  # silent: holds nothing
        ):
            b.sendall(CommandFrame(1, "cfg2").convert2bytes())
            assert "CFG-2" in c37.frame_kind(_read_frame(b))
            with socket.create_connection(server.address, timeout=5) as a:
                a.sendall(CommandFrame(1, "start").convert2bytes())
                assert len(_frames_until_close(a, len(data))) == len(data)
            assert _until(lambda: any(x.whole for x in server.sessions))
            time.sleep(0.3)
            assert not server.done()  # B is at work
            b.sendall(CommandFrame(1, "start").convert2bytes())
            assert len(_frames_until_close(b, len(data))) == len(data)
        assert _until(server.done)
    assert [x.whole for x in server.sessions] == [True, True]


def test_a_recording_that_starts_late_is_refused_as_one_cut_at_its_end(kundur_stream, tmp_path):
    """`estimate rmse --source` of a recording whose first frame is 0.5 s into the run
    (round 38: accepted, "0 missing", its errors over what came as over the whole run) is
    refused, naming when it starts; the whole recording is read."""
    from click.testing import CliRunner

    from stabctl.cli import main

    _, _, cfg, cfg2, frames = kundur_stream
    args = ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101", "--t-fault", "0.5"]
    args += ["--clear-cycles", "7", "--tf", "1", "--seed", "1", "--source"]
    for name, kept in (("late.c37", frames[30:]), ("whole.c37", frames)):
        (tmp_path / name).write_bytes(cfg2.convert2bytes() + b"".join(_encoded(cfg, cfg2, kept)))
    res = CliRunner().invoke(main, [*args, str(tmp_path / "late.c37")])
    assert res.exit_code == 2, res.output
    assert (
        f"error: --source {tmp_path / 'late.c37'} starts at t = 0.5000 s, 30 reporting "
        "instant(s) after the run's first (t = 0, the CFG-2's time stamp)"
    ) in res.stderr
    res = CliRunner().invoke(main, [*args, str(tmp_path / "whole.c37")])
    assert res.exit_code == 0, res.output
    # round 40: every data frame one instant before the CFG-2's stamp (a CFG-2 stamped
    # late) was called "short of the run's 1 s", its last frame 1/60 s before the end
    step = c37.TIME_BASE // RATE
    early = []
    for f in _encoded(cfg, cfg2, frames):
        at = int.from_bytes(f[6:10], "big") * c37.TIME_BASE + int.from_bytes(f[11:14], "big")
        early.append(_restamped(f, *divmod(at - step, c37.TIME_BASE)))
    (tmp_path / "early.c37").write_bytes(cfg2.convert2bytes() + b"".join(early))
    res = CliRunner().invoke(main, [*args, str(tmp_path / "early.c37")])
    assert res.exit_code == 2 and "short of" not in res.stderr, res.output
    assert "starts at t = -0.0167 s, 1 reporting instant(s) before the run's first" in res.stderr


def test_a_flood_of_silent_peers_leaves_the_plant_its_controller():
    """Round 40: 1 100 silent connections made `pmu plant` hold a thread and a descriptor
    each until its time-out and die with "Too many open files" before its controller
    came.  At most `Guard.max_peers` handshakes are held at once, a new peer taking the
    place of the one silent longest; the controller that comes after 200 silent peers
    takes the loop, the process's descriptors stay bounded, and the dropped peers are
    counted, the first `NAMED_PEERS` named."""
    import os

    from stabctl.estimation.c37_tcp import NAMED_PEERS

    case = stabctl.load_case("kundur")
    partial = stabctl.Simulator(case).run([fault_with_clearing(case, 3, 101, 1.0, 7)], t_end=0.1)
    ctrl, cfg, link = _plant(case, timeout=20)
    fds = len(os.listdir("/proc/self/fd"))
    with link:
        silent: list = []
        got: list = []
        ran = threading.Thread(target=lambda: got.append(link(0.05, partial)), daemon=True)
        ran.start()
        for _ in range(200):
            silent.append(socket.create_connection(link.address))
        time.sleep(0.5)  # each accepted, most given their place to a later one
        held = len(os.listdir("/proc/self/fd")) - fds - len(silent)
        threading.Thread(
            target=lambda: _served_quietly(ctrl, cfg, link.address), daemon=True
        ).start()
        ran.join(15)
        assert got and got[0].shape == (ctrl.mode.size,), link.refused[-3:]
        for s in silent:
            s.close()
    assert held <= Guard.max_peers + 4  # the plant's own: listening socket, a few in flight
    assert link.n_refused >= 200 - Guard.max_peers and len(link.refused) == NAMED_PEERS
    assert "sent no command in " in link.refused[0]
    assert link.refused[0].endswith(
        f"with {Guard.max_peers} peers connected: its place given to a new peer"
    )


def _served_quietly(ctrl, cfg, address):
    with contextlib.suppress(InputError, OSError):  # the plant closes after one frame
        c37_loop.serve_controller(ctrl, cfg, *address, timeout=5)


def test_a_command_frame_without_its_command_word_is_not_obeyed():
    """Round 40: a 16-byte frame marked a command, its CRC valid, has no CMD field (a
    command frame is 18 bytes at least); its CRC was read as the command word, and a
    CRC of 2 started a stream.  It is no command."""
    from stabctl.estimation.c37_tcp import command_word

    for frame, crc in (
        ("aa410010000100008b93000000000005", 5),
        ("aa41001000010000b480000000000002", 2),
    ):
        raw = bytes.fromhex(frame)
        assert int.from_bytes(raw[-2:], "big") == crc  # the CRC the server read as CMD
        assert command_word(raw) == 0 and command_word(raw, 1) == 0
    from pyc37.frame import CommandFrame

    assert command_word(CommandFrame(1, "start").convert2bytes(), 1) == 2  # a whole one


def test_a_stream_of_another_idcode_than_asked_is_refused(kundur_stream):
    """A server that answers commands addressed to IDCODE 1 with the stream IDCODE 7 (its
    CFG-2 and data frames valid) was tracked and recorded as the stream asked for, exit 0,
    no word (round 58 AZ15-16).  A command's IDCODE is its destination stream's
    (C37.118.2-2011 Table 2), as `pmu control` refuses a plant's CFG-2 of another: the
    receive refuses it naming both IDCODEs, before any data frame."""
    case, pmus, _cfg, _cfg2, frames = kundur_stream
    cfg = c37.stream_config(case, pmus, RATE, idcode=7)
    cfg2 = c37.config_frame(cfg)
    address = _cut_server(cfg2, _encoded(cfg, cfg2, frames), cut_last=False)
    with pytest.raises(InputError, match="its CFG-2 is of stream IDCODE 7, not the IDCODE 1"):
        receive(*address, End(frames=61), idcode=1, timeout=10)


def test_a_peer_that_never_starts_does_not_hold_the_server_open(kundur_stream):
    """After a PDC was sent the stream whole, a peer that asks for the header every 0.2 s
    and never says 'start' held `pmu serve` open for as long as it went on (round 58
    AZ08).  Like a peer it would evict (`Guard.max_peers`), it holds the server only
    within `Guard.timeout` s of connecting: a PDC that asks for its CFG-2 is still served
    that long."""
    from pyc37.frame import CommandFrame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    data = _encoded(cfg, cfg2, frames)
    stop = threading.Event()
    guard = Guard(timeout=3.0)
    with (
        StreamServer(cfg2, data, speed=float("inf"), guard=guard) as server,
        socket.create_connection(server.address, timeout=2) as stranger,
    ):

        def ask():
            while not stop.wait(0.2):
                with contextlib.suppress(OSError):
                    stranger.sendall(CommandFrame(1, "header").convert2bytes())

        threading.Thread(target=ask, daemon=True).start()
        time.sleep(0.3)
        assert len(receive(*server.address, timeout=10).data) == 61
        assert server.finished.wait(5)
        assert not server.done()  # within the stranger's first 3 s
        deadline = time.monotonic() + 10
        while not server.done() and time.monotonic() < deadline:
            time.sleep(0.05)
        held = server.done()
        stop.set()
    assert held


def test_a_plant_evicts_a_peer_of_bad_frames_before_one_of_valid_commands():
    """With `Guard.max_peers` handshakes open, a new peer takes the place of one without a
    valid command.  A peer that had its CFG-2 was evicted while seven strangers, whose
    only frame failed its CRC, kept theirs (round 58 AZ01: any frame counted as a
    command).  Now the first stranger gives its place, named as one that sent none."""
    from pyc37.frame import CommandFrame

    case = stabctl.load_case("kundur")
    partial = stabctl.Simulator(case).run([fault_with_clearing(case, 3, 101, 1.0, 7)], t_end=0.1)
    _ctrl, _cfg, link = _plant(case, timeout=3)
    bad = bytearray(CommandFrame(1, "header").convert2bytes())
    bad[-1] ^= 0xFF
    with link, contextlib.ExitStack() as peers:

        def wait_for_a_controller():  # none comes: 'no controller connected within 3 s'
            with contextlib.suppress(InputError):
                link(0.05, partial)

        thread = threading.Thread(target=wait_for_a_controller, daemon=True)
        thread.start()
        first = peers.enter_context(socket.create_connection(link.address, timeout=5))
        first.sendall(CommandFrame(1, "cfg2").convert2bytes())
        first.settimeout(5)
        assert first.recv(4)  # its CFG-2 is coming: a valid command was taken
        strangers = []
        for _ in range(7):
            strangers.append(peers.enter_context(socket.create_connection(link.address)))
            strangers[-1].sendall(bytes(bad))
        time.sleep(0.3)
        peers.enter_context(socket.create_connection(link.address))  # the ninth
        me = f"127.0.0.1:{strangers[0].getsockname()[1]}"
        said = f"{me}: sent no command in"
        assert _until(lambda: any(r.startswith(said) for r in link.refused)), link.refused
        mine = f"127.0.0.1:{first.getsockname()[1]}:"
        assert not any(r.startswith(mine) for r in link.refused)
        thread.join(10)


def test_a_peer_that_reads_no_answer_is_named_for_it(kundur_stream):
    """A peer that sends 'cfg2' again and again and reads none of the answers is dropped
    once an answer waits the time-out, named for what it did: it was named 'silent'
    (round 58 AZ07: 159 600 commands, 'silent for 5 s')."""
    from pyc37.frame import CommandFrame

    _case, _pmus, cfg, cfg2, frames = kundur_stream
    ask = CommandFrame(1, "cfg2").convert2bytes() * 100
    with (
        StreamServer(
            cfg2, _encoded(cfg, cfg2, frames), speed=float("inf"), guard=Guard(timeout=0.5)
        ) as server,
        socket.socket() as peer,
    ):
        peer.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        peer.connect(server.address)
        peer.settimeout(0.2)
        deadline = time.monotonic() + 20
        with contextlib.suppress(OSError):  # until the server no longer reads them
            while time.monotonic() < deadline:
                peer.sendall(ask)
        said = "command(s) and took no answer to its commands for 0.5 s"
        assert _until(lambda: any(said in r for r in server.refused)), server.refused
    assert not any("silent" in r for r in server.refused)
