"""What a C37.118.2 peer sends is checked wherever it is read.  A receiver (`pmu record`,
`estimate track`) checks the CFG-2 and every data frame (CRC, IDCODE, type, size) as they
come, and keeps only the good frames before one it refuses; `pmu replay` checks a
recording whole before it listens; every frame, a server's commands and a plant's or a
controller's too, is due whole within the time-out, so that a peer sending it a byte at a
time is timed out as a silent one is; and the servers obey only commands addressed to their
stream's IDCODE, dropping a peer that addresses another and naming it."""

import binascii
import socket
import threading
import time

import pytest
from click.testing import CliRunner

pytest.importorskip("pyc37")

from pyc37.frame import CommandFrame

from stabctl.cli import main
from stabctl.errors import InputError
from stabctl.estimation import c37, c37_loop, c37_tcp
from stabctl.estimation.c37_tcp import End, Guard, StreamServer, receive


@pytest.fixture(scope="module")
def wire():
    """Kundur's 4-PMU stream for 1 s (61 frames): its config, CFG-2 (pyc37) and the CFG-2
    and data frames as bytes."""
    from pmu_streams import kundur_stream, on_the_wire

    _, _, cfg, frames = kundur_stream(t_end=1.0)
    head, body = on_the_wire(cfg, frames)
    return cfg, c37.config_frame(cfg), head, body


def _crc(frame: bytes) -> bytes:
    """frame with its CHK (CRC-CCITT) made valid again."""
    return frame[:-2] + binascii.crc_hqx(frame[:-2], 0xFFFF).to_bytes(2, "big")


def _bad_crc(frame: bytes) -> bytes:
    return frame[:-1] + bytes([frame[-1] ^ 0xFF])


def _idcode(frame: bytes, idcode: int) -> bytes:
    """frame addressed to (or sent as) another IDCODE, its CRC valid."""
    return _crc(frame[:4] + idcode.to_bytes(2, "big") + frame[6:])


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def one_error(res, *needles):
    assert res.exit_code == 2, (res.exit_code, res.output, res.exception)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    for n in needles:
        assert n in lines[0], (n, lines[0])


def _server(head, after_start, stop=None, drip=None, gap=0.1):
    """A fake PMU server: the CFG-2 `head` on 'cfg2' (dripped a byte per `gap` s if drip
    == 'cfg2'), then on 'start' the bytes `after_start`, then (drip: bytes) those a byte
    per `gap` s until `stop` is set."""
    from pmu_streams import fake_server

    stop = stop or threading.Event()

    def talk(conn):
        conn.recv(1000)
        if drip == "cfg2":
            for b in head:
                conn.sendall(bytes([b]))
                if stop.wait(gap):
                    return
            return
        conn.sendall(head)
        conn.recv(1000)
        conn.sendall(after_start)
        for b in drip or b"":
            conn.sendall(bytes([b]))
            if stop.wait(gap):
                return
        stop.wait(0.3)

    return fake_server(talk)


# -- the frames a receiver and a replay take --------------------------------------------


def test_a_cfg2_with_a_bad_crc_is_refused_and_nothing_recorded(wire, tmp_path):
    """`pmu record` wrote a recording whose CFG-2 fails its CRC (which `estimate track`
    refuses later): refused as it arrives, naming the server; no file."""
    _, _, head, body = wire
    srv, port = _server(_bad_crc(head), b"".join(body[:20]))
    with srv:
        res = run("pmu", "record", f"127.0.0.1:{port}", "--frames", 10, "-o", tmp_path / "r.c37")
    one_error(res, f"127.0.0.1:{port}: its CFG-2 is not a configuration frame: CRC failed")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "bad, needle",
    [
        (_bad_crc, "C37.118.2 data frame not readable: CRC failed"),
        (lambda f: _idcode(f, 999), "a data frame of IDCODE 999, not the stream's 1"),
    ],
)
def test_record_keeps_the_good_frames_before_a_refused_one(wire, tmp_path, bad, needle):
    """Data frames with a bad CRC, or of another IDCODE (CRC recomputed), were recorded
    with exit status 0.  The recording stops at the first refused frame: a new file holds
    the good frames before it and the command exits 2 naming the server, the frame and
    why; an existing file is left as it was, the good frames written beside it; a stream
    bad from its first frame writes
    nothing."""
    _, _, head, body = wire
    stream = b"".join([*body[:5], bad(body[5]), *body[6:20]])
    out = tmp_path / "r.c37"
    srv, port = _server(head, stream)
    with srv:
        res = run("pmu", "record", f"127.0.0.1:{port}", "--frames", 15, "-o", out)
    one_error(
        res,
        f"127.0.0.1:{port}: the server sent a data frame that is refused (data frame 6: {needle}",
        f"5 data frames before it, the last stamped 0.0667 s, before 15 frames; the 5 "
        f"received are in {out}",
    )
    assert out.read_bytes() == head + b"".join(body[:5])
    keep = tmp_path / "keep.c37"
    keep.write_bytes(head + b"".join(body))
    srv, port = _server(head, stream)
    with srv:
        res = run("pmu", "record", f"127.0.0.1:{port}", "--frames", 15, "-o", keep)
    beside = tmp_path / "keep.partial.c37"
    one_error(res, "data frame 6", f"the 5 received are in {beside} ({keep} is left as it was)")
    assert keep.read_bytes() == head + b"".join(body)
    assert beside.read_bytes() == head + b"".join(body[:5])
    srv, port = _server(head, b"".join(bad(f) for f in body[:20]))
    with srv:
        res = run("pmu", "record", f"127.0.0.1:{port}", "--frames", 15, "-o", tmp_path / "n.c37")
    one_error(res, f"127.0.0.1:{port}: ", f"(data frame 1: {needle}")
    assert not (tmp_path / "n.c37").exists()


@pytest.mark.parametrize(
    "at, value, said",
    [
        (2, b"\x00\x00", "\\xaa\\x01\\x00\\x00"),
        (2, b"\x00\x0f", "\\x00\\x0f"),
        (0, b"\xab", "\\xab"),
    ],
)
def test_record_keeps_the_good_frames_before_bytes_that_start_no_frame(
    wire, tmp_path, at, value, said
):
    """Round 46: data frame 6's header damaged so that it starts no frame (FRAMESIZE 0 or
    15, below a frame's 16 bytes; SYNC 0xAB) stopped `pmu record` with nothing written,
    the 5 good frames before it lost.  Such bytes after a data frame are now a frame
    refused: the good frames are kept, exit 2 naming them; before any data frame they
    still say the peer does not speak C37.118.2."""
    _, _, head, body = wire
    damaged = bytearray(body[5])
    damaged[at : at + len(value)] = value
    out = tmp_path / "r.c37"
    srv, port = _server(head, b"".join([*body[:5], bytes(damaged), *body[6:20]]))
    with srv:
        res = run("pmu", "record", f"127.0.0.1:{port}", "--frames", 15, "-o", out)
    one_error(
        res,
        f"127.0.0.1:{port}: the server sent bytes that start no frame (after data frame 5: b'",
        said,
        "', no frame start (SYNC 0xAA, FRAMESIZE of at least 16), or data frame 5's FRAMESIZE "
        "is off); the stream is cut there: 5 data frames before them, the last stamped "
        f"0.0667 s, before 15 frames; the 5 received are in {out}",
    )
    assert out.read_bytes() == head + b"".join(body[:5])
    srv, port = _server(head, b"".join([bytes(damaged), *body[6:20]]))
    with srv:
        res = run("pmu", "record", f"127.0.0.1:{port}", "--frames", 15, "-o", tmp_path / "n.c37")
    one_error(res, "after 0 data frames: the peer does not speak C37.118.2")
    assert not (tmp_path / "n.c37").exists()


def test_receive_keeps_the_frames_before_one_refused(wire):
    """The library's receiver: the stream cut at the refused frame, `refused` says why."""
    _, _, head, body = wire
    srv, port = _server(head, b"".join([*body[:3], _bad_crc(body[3]), *body[4:10]]))
    with srv:
        got = receive("127.0.0.1", port, End(frames=8), timeout=5)
    assert got.data == body[:3] and got.cfg2 == head
    assert got.refused.startswith("data frame 4: C37.118.2 data frame not readable: CRC")
    assert "the stream is cut there: 3 data frames before it" in got.short


def _header(text: str = "hello") -> bytes:
    from pyc37.frame import HeaderFrame

    return HeaderFrame(1, text).convert2bytes()


def _stamped(frame: bytes, soc: int) -> bytes:
    """frame with another SOC, its CRC valid."""
    return _crc(frame[:6] + soc.to_bytes(4, "big") + frame[10:])


def test_frames_other_than_data_frames_after_start_are_checked(wire):
    """Frames after 'start' that were not data frames were skipped unread: a header frame
    with a bad CRC passed, and a CFG-2 that changed the stream's configuration mid-stream
    (same size) was ignored, the data frames after it read by the old layout.  Every
    frame's CRC is checked and a CFG-2 must be the one in use (resent with a new time
    stamp it is): else the stream is cut there, the data frames before it kept and the
    field that changed named."""
    import dataclasses

    cfg, _, head, body = wire
    srv, port = _server(
        head,
        b"".join([*body[:3], _header(), _stamped(head, cfg.epoch + 7), *body[3:10]]),
    )
    with srv:
        got = receive("127.0.0.1", port, End(frames=8), timeout=5)
    assert got.data == body[:8] and not got.short and not got.refused
    changed = c37.config_frame(dataclasses.replace(cfg, rate=30)).convert2bytes()
    assert len(changed) == len(head)
    for odd, kind, needle in (
        (_bad_crc(_header()), "header frame", "C37.118.2 header frame not readable: CRC failed"),
        (changed, "CFG-2", "changes the stream's configuration (DATA_RATE 30 where the CFG-2 in "
         "use has 60)"),
    ):  # fmt: skip
        srv, port = _server(head, b"".join([*body[:3], odd, *body[3:10]]))
        with srv:
            got = receive("127.0.0.1", port, End(frames=8), timeout=5)
        assert got.data == body[:3]
        assert got.refused.startswith(f"{kind}: ") and needle in got.refused, got.refused
        assert got.short.startswith(f"the server sent a {kind} that is refused ({kind}: ")
        assert "the stream is cut there: 3 data frames before it" in got.short


def test_a_server_sending_only_header_frames_is_timed_out(wire, tmp_path, monkeypatch):
    """A server that answered 'start' with a header frame every 0.2 s and never a data
    frame kept `pmu record` waiting for ever: each header frame restarted the time-out.
    The time-out is the longest wait for a data frame, whatever comes meanwhile: the
    stream ends after it, with the data frames that came (exit 2, the server named)."""
    from pmu_streams import fake_server

    _, _, head, body = wire
    monkeypatch.setattr(c37_tcp, "RECEIVE_TIMEOUT_S", 1.0)
    for before in (0, 2):
        stop = threading.Event()

        def talk(conn, before=before, stop=stop):
            conn.recv(1000)
            conn.sendall(head)
            conn.recv(1000)
            conn.sendall(b"".join(body[:before]))
            while not stop.wait(0.2):
                conn.sendall(_header())

        srv, port = fake_server(talk)
        out = tmp_path / f"r{before}.c37"
        try:
            t0 = time.monotonic()
            res = run("pmu", "record", f"127.0.0.1:{port}", "--frames", 10, "-o", out)
        finally:
            stop.set()
            srv.close()
        assert time.monotonic() - t0 < 10
        one_error(
            res, f"127.0.0.1:{port}: the server sent no data frame for 1 s after {before} data"
        )
        assert out.exists() == bool(before)


@pytest.mark.parametrize("frame", [7, 1])
def test_replay_checks_every_frame_before_it_listens(wire, tmp_path, monkeypatch, frame):
    """`pmu replay` served a recording whose frame 7 fails its CRC (a reader refused it
    only once served): refused before listening, naming RECORDING and the frame; the
    library's `StreamServer.of_recording` too, and a frame of another IDCODE."""
    import stabctl.cli.pmu as cli_pmu

    _, _, head, body = wire
    frames = list(body)
    frames[frame - 1] = _bad_crc(frames[frame - 1])
    rec = tmp_path / "bad.c37"
    rec.write_bytes(head + b"".join(frames))

    def served(servers):
        raise AssertionError("served a recording with a bad frame")

    monkeypatch.setattr(cli_pmu, "_serve", served)
    res = run("pmu", "replay", rec, "--port", 0, "--speed", 0)
    one_error(
        res, f"RECORDING {rec}: data frame {frame}: C37.118.2 data frame not readable: CRC failed"
    )
    with pytest.raises(InputError, match=f"data frame {frame}: C37.118.2 data frame not"):
        StreamServer.of_recording(rec)
    frames[frame - 1] = _idcode(body[frame - 1], 999)
    rec.write_bytes(head + b"".join(frames))
    res = run("pmu", "replay", rec, "--port", 0, "--speed", 0)
    one_error(res, f"data frame {frame}: a data frame of IDCODE 999, not the stream's 1")


def _typed(frame: bytes, kind: int) -> bytes:
    """frame with another frame type in its SYNC word (bits 6-4), its CRC valid."""
    return _crc(frame[:1] + bytes([frame[1] & 0x8F | kind << 4]) + frame[2:])


@pytest.mark.parametrize("kind, name", [(2, "CFG-1"), (5, "CFG-3"), (7, "frame of type 7")])
def test_a_configuration_frame_of_another_type_is_refused_wherever_a_cfg2_is_read(
    wire, tmp_path, monkeypatch, kind, name
):
    """A recording whose first frame is a CFG-3, or a server or a plant answering 'cfg2'
    with one: pyc37's parser recursed without end (a RecursionError traceback); a CFG-1
    was read as the CFG-2 (`pmu replay` served it, `estimate track` tracked it, `pmu
    control` took a plant's).  Each is one error line naming the frame type."""
    import stabctl.cli.pmu as cli_pmu

    _, _, head, body = wire
    odd = _typed(head, kind)
    said = f"is a {name} (SYNC frame type {kind}), not the CFG-2 expected"
    rec, out = tmp_path / "odd.c37", tmp_path / "t.csv"
    rec.write_bytes(odd + b"".join(body))
    monkeypatch.setattr(cli_pmu, "_serve", lambda servers: pytest.fail("served"))
    one_error(run("pmu", "replay", rec, "--port", 0, "--speed", 0), f"first frame {said}")
    one_error(run("estimate", "track", "kundur", "--source", rec, "--out", out), said)
    res, port = _tracked_over_tcp(odd, b"".join(body), out)
    one_error(res, f"127.0.0.1:{port}: its CFG-2 {said}")
    assert not out.exists()
    srv, port = _server(odd, b"")
    with srv:
        res = run("pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", 5)
    one_error(res, f"127.0.0.1:{port}'s CFG-2 {said}")


def _tracked_over_tcp(head: bytes, body: bytes, out):
    """`estimate track` of 10 frames from a server sending `head` (its CFG-2) and `body`:
    (the CLI result, the server's port)."""
    srv, port = _server(head, body)
    with srv:
        res = run(
            "estimate", "track", "kundur", "--source", f"tcp://127.0.0.1:{port}",
            "--frames", 10, "--out", out,
        )  # fmt: skip
    return res, port


def test_a_cfg2_pyc37_cannot_read_is_one_error(wire):
    """A CFG-2, its CRC valid, whose fields pyc37 cannot read (NUM_PMU 65535 in a frame of
    four PMUs, a frame cut after 60 bytes): an error naming it, not a traceback."""
    _, _, head, _ = wire
    for odd in (head[:18] + (65535).to_bytes(2, "big") + head[20:], head[:60]):
        odd = _crc(odd[:2] + len(odd).to_bytes(2, "big") + odd[4:])
        with pytest.raises(InputError, match=r"^its CFG-2 is not a configuration frame: "):
            c37.read_config(odd, "its CFG-2")


def test_pmus_of_another_nominal_frequency_are_refused(wire, tmp_path):
    """PMUs whose CFG-2 says FNOM 50 Hz on a 60 Hz case were read, their FREQ (a deviation
    from 50 Hz) taken as 10 Hz swings: `estimate track` said 7751 mHz where the swing was
    202 mHz and `pmu control` commanded 34 ESD starts instead of 4, each with exit status
    0.  A recording, a server and a plant are refused, naming FNOM, the PMUs and the
    case's frequency."""
    import dataclasses

    cfg, _, _, body = wire
    head = c37.config_frame(dataclasses.replace(cfg, f0=50.0)).convert2bytes()
    labels = ", ".join(p.label for p in cfg.pmus)
    said = f"its CFG-2 FNOM 50 Hz (PMU {labels}), not the case's nominal frequency 60 Hz"
    rec, out = tmp_path / "fifty.c37", tmp_path / "t.csv"
    rec.write_bytes(head + b"".join(body))
    one_error(run("estimate", "track", "kundur", "--source", rec, "--out", out), said)
    res, _ = _tracked_over_tcp(head, b"".join(body), out)
    one_error(res, said)
    assert not out.exists()
    srv, port = _server(head, b"")
    with srv:
        res = run(
            "pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", 5, "--estimator", "ekf"
        )
    one_error(res, f"the plant at 127.0.0.1:{port}: {said}")


# -- a whole frame within the time-out -------------------------------------------------------


def _ends_within(seconds, func):
    """func() in a thread: (its result or exception, True) if it ended within seconds."""
    out: list = []

    def call():
        try:
            out.append(func())
        except Exception as exc:  # noqa: BLE001 - handed to the test
            out.append(exc)

    thread = threading.Thread(target=call, daemon=True)
    thread.start()
    thread.join(seconds)
    return (out[0] if out else None), not thread.is_alive()


def test_a_receiver_times_out_a_frame_sent_a_byte_at_a_time(wire):
    """A server sending a byte every 0.1 s never tripped the time-out of each read, so
    `pmu record` and `estimate track` never ended.  The time-out is the whole frame's:
    the stream ends after it, with the frames that came and what cut it; a CFG-2 dripped
    so is an error naming the server."""
    _, _, head, body = wire
    stop = threading.Event()
    srv, port = _server(head, b"".join(body[:2]), stop, drip=body[2] * 10)
    try:
        got, ended = _ends_within(6, lambda: receive("127.0.0.1", port, End(frames=10), timeout=1))
    finally:
        stop.set()
        srv.close()
    assert ended, "the receiver waited on a dripping server"
    assert got.data == body[:2]
    assert got.short.startswith(
        "the server sent part of a frame and not the rest within 1 s after 2 data frames"
    )
    stop = threading.Event()
    srv, port = _server(head, b"", stop, drip="cfg2")
    try:
        got, ended = _ends_within(6, lambda: receive("127.0.0.1", port, End(frames=10), timeout=1))
    finally:
        stop.set()
        srv.close()
    assert ended and isinstance(got, InputError), got
    assert str(got) == (
        f"127.0.0.1:{port}: sent part of a frame and not the rest within 1 s, before any data frame"
    )


def test_record_and_track_end_a_dripping_stream_naming_server_and_frames(
    wire, tmp_path, monkeypatch
):
    """The command lines on a dripping server: exit status 2, one line naming the server
    and the frames that came (the time-out set to 1 s here: 30 s by default)."""
    _, _, head, body = wire
    monkeypatch.setattr(c37_tcp, "RECEIVE_TIMEOUT_S", 1.0)
    out = tmp_path / "r.c37"
    for args in (
        ("pmu", "record", "ADDRESS", "--frames", 10, "-o", out),
        ("estimate", "track", "kundur", "--source", "tcp://ADDRESS", "--frames", 10)
        + ("--out", tmp_path / "t.csv"),
    ):
        stop = threading.Event()  # the drip lasts 31 s: a receiver that waits it out fails
        srv, port = _server(head, b"".join(body[:2]), stop, drip=body[2] * 3)
        argv = [str(a).replace("ADDRESS", f"127.0.0.1:{port}") for a in args]
        try:
            t0 = time.monotonic()
            res = run(*argv)  # in this thread: a command sets signal handlers
        finally:
            stop.set()
            srv.close()
        assert time.monotonic() - t0 < 15
        one_error(
            res,
            f"127.0.0.1:{port}: the server sent part of a frame and not the rest within 1 s "
            "after 2 data frames",
        )
    assert out.read_bytes() == head + b"".join(body[:2])


def _eventually(cond, seconds=2.0) -> bool:
    """cond() once true within seconds (a server names a dropped peer just after closing
    its connection)."""
    deadline = time.monotonic() + seconds
    while not cond() and time.monotonic() < deadline:
        time.sleep(0.02)
    return cond()


def _drip(sock, data, gap, stop):
    def run():
        for b in data:
            if stop.wait(gap):
                return
            try:
                sock.sendall(bytes([b]))
            except OSError:
                return

    threading.Thread(target=run, daemon=True).start()


def _read_all(sock, seconds):
    """Everything the peer gets within seconds, until the server closes."""
    sock.settimeout(seconds)
    got = b""
    try:
        while chunk := sock.recv(4096):
            got += chunk
    except (TimeoutError, ConnectionError):
        pass
    return got


def test_a_server_drops_a_peer_that_drips_a_command(wire):
    """A peer sending 'cfg2' a byte every 0.1 s (1.8 s for the frame) was answered with
    the CFG-2, each byte restarting the time-out: it is dropped once the frame is not
    whole within the time-out (0.5 s), named; a PDC beside it gets the whole stream."""
    _, cfg2, _, body = wire
    stop = threading.Event()
    with StreamServer(cfg2, body, speed=float("inf"), guard=Guard(timeout=0.5)) as server:
        with socket.create_connection(server.address) as peer:
            _drip(peer, CommandFrame(1, "cfg2").convert2bytes(), 0.1, stop)
            got = _read_all(peer, 3)
            stop.set()
        assert got == b"", got[:4]
        assert _eventually(
            lambda: any(
                "part of a frame and not the rest within 0.5 s" in r for r in server.refused
            )
        )
        assert len(receive(*server.address, timeout=5).data) == len(body)


def test_a_command_dripped_mid_stream_ends_the_session_by_name(wire):
    """A PDC that, while paced frames come, sends a command a byte at a time: the session
    ends, cut (`StreamServer.cut`), the PDC named with what it did, instead of the
    frame's bytes being lost at the pacing's poll and the PDC dropped without the session
    ending."""
    _, cfg2, _, body = wire
    stop = threading.Event()
    with (
        StreamServer(cfg2, body, speed=0.2, guard=Guard(timeout=0.5)) as server,
        socket.create_connection(server.address) as pdc,
    ):
        pdc.sendall(CommandFrame(1, "start").convert2bytes())
        pdc.settimeout(5)
        assert pdc.recv(4)[:1] == b"\xaa"
        _drip(pdc, CommandFrame(1, "stop").convert2bytes(), 0.1, stop)
        assert _eventually(lambda: server.cut, 3), "the session did not end"
        stop.set()
    assert "sent part of a frame and not the rest within 0.5 s" in server.cut[0].ended


def test_a_controller_times_out_a_dripping_plant_and_a_plant_a_dripping_answer(wire):
    """`pmu control` against a plant dripping a data frame, and a plant whose controller
    drips its answer: each ends after the time-out for a whole frame, naming what came."""
    cfg, _, head, body = wire
    stop = threading.Event()
    srv, port = _server(head, b"", stop, drip=body[0] * 5)
    try:
        got, ended = _ends_within(
            6, lambda: c37_loop.serve_controller(None, cfg, "127.0.0.1", port, timeout=1)
        )
    finally:
        stop.set()
        srv.close()
    assert ended and isinstance(got, InputError), got
    assert str(got).startswith(
        f"the plant at 127.0.0.1:{port}: sent part of a frame and not the rest within 1 s, "
        "after 0 frame(s) answered"
    )
    link = c37_loop.PlantLink(None, cfg, timeout=0.5)
    stop = threading.Event()
    with link, socket.create_connection(link.address) as ctrl:
        ctrl.sendall(CommandFrame(1, "start").convert2bytes())
        me = f"127.0.0.1:{ctrl.getsockname()[1]}"
        conn = link._connected()
        conn.sendall(body[0])
        ctrl.recv(1000)
        _drip(ctrl, c37_loop.modes_frame(1, 0, 0, [0, 0, 0, 0]), 0.1, stop)
        t0 = time.monotonic()
        with pytest.raises(InputError) as err:
            link._next(conn, 0.05)
        stop.set()
    assert time.monotonic() - t0 < 1.5
    assert str(err.value) == (
        f"the controller at {me}: sent part of a frame and not the rest within 0.5 s (the "
        "frame at t = 0.0500 s, after 0 frame(s) answered)"
    )


@pytest.mark.parametrize(
    "how,said",
    [
        ("reset", "Connection reset by peer"),
        ("closed", "closed the loop before its answer"),
    ],
)
def test_a_plant_whose_controller_goes_names_it_the_frame_and_the_answers(wire, how, said):
    """A controller killed mid-run (its connection reset) ended `pmu plant` with only
    ``error: Connection reset by peer``: the controller's address, the frame and the
    frames answered are named, as for a controller that closes the loop or times out."""
    import struct

    cfg, _, _, body = wire
    link = c37_loop.PlantLink(None, cfg, timeout=5)
    with link, socket.create_connection(link.address) as ctrl:
        ctrl.sendall(CommandFrame(1, "start").convert2bytes())
        me = f"127.0.0.1:{ctrl.getsockname()[1]}"
        conn = link._connected()
        conn.sendall(body[0])
        ctrl.recv(1000)
        if how == "reset":
            ctrl.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        ctrl.close()
        with pytest.raises(InputError) as err:
            link._next(conn, 0.05)
    assert str(err.value) == (
        f"the controller at {me}: {said} (the frame at t = 0.0500 s, after 0 frame(s) answered)"
    )


def test_a_controller_takes_no_damaged_end_of_run_header(wire):
    """The plant's end-of-run header was taken without its CRC checked: a damaged one
    ended `pmu control` as if the run had ended.  It is a frame refused, named."""
    cfg, _, head, _ = wire
    srv, port = _server(head, _bad_crc(c37_loop.end_of_run_frame(1, 1.0)))
    with srv, pytest.raises(InputError) as err:
        c37_loop.serve_controller(None, cfg, "127.0.0.1", port, timeout=5)
    assert str(err.value).startswith(
        f"the plant at 127.0.0.1:{port}: its frame 1 after 'start': C37.118.2 data frame not "
        "readable: CRC failed"
    )


def test_a_controller_takes_no_run_of_no_frame(wire):
    """A plant that answered 'start' with its end of run at t = 0 and closed: `pmu
    control` printed "answered 0 frames ..., 0 ESD starts", exit 0.  A stabctl plant's
    run always has frames (it refuses an end before its first frame arrives), so a run
    of none is refused, naming the plant."""
    cfg, _, head, _ = wire
    srv, port = _server(head, c37_loop.end_of_run_frame(1, 0.0))
    with srv, pytest.raises(InputError) as err:
        c37_loop.serve_controller(None, cfg, "127.0.0.1", port, timeout=5)
    assert str(err.value) == (
        f"the plant at 127.0.0.1:{port} announced the end of its run at t = 0.0000 s "
        "before any frame was answered: no run was controlled"
    )


# -- commands addressed to another IDCODE ---------------------------------------------------


def test_a_server_drops_a_peer_whose_commands_address_another_idcode(wire):
    """A valid command for IDCODE 999 was obeyed by a server of stream 1: the peer is
    dropped unanswered and named with the IDCODE; a PDC addressing 1 gets the stream."""
    _, cfg2, _, body = wire
    with StreamServer(cfg2, body, speed=float("inf"), guard=Guard(timeout=2)) as server:
        with socket.create_connection(server.address) as peer:
            peer.sendall(CommandFrame(999, "cfg2").convert2bytes())
            me = f"127.0.0.1:{peer.getsockname()[1]}"
            assert _read_all(peer, 1.5) == b""
        assert _eventually(
            lambda: f"{me}: a command for IDCODE 999, not this stream's 1" in server.refused
        )
        assert len(receive(*server.address, timeout=5).data) == len(body)


def test_a_receiver_addresses_the_stream_it_names(wire, tmp_path):
    """A recording of stream IDCODE 5 served again: a receiver addressing 1 is dropped
    and says why; addressing 5 gets it whole."""
    from pmu_streams import kundur_stream

    case, pmus, _, frames = kundur_stream(t_end=0.5)
    cfg5 = c37.stream_config(case, pmus, 60, idcode=5)
    rec = tmp_path / "five.c37"
    c37.record(rec, cfg5, frames)
    with StreamServer.of_recording(rec, speed=float("inf")) as server:
        assert server.idcode == 5
        why = r"before sending its CFG-2: .* serves another stream than IDCODE 1, which these"
        with pytest.raises(InputError, match=why):
            receive(*server.address, timeout=5)
        assert len(receive(*server.address, idcode=5, timeout=5).data) == len(frames)


def test_a_plant_drops_a_peer_whose_commands_address_another_idcode(wire):
    """`pmu plant` answered 'cfg2' for IDCODE 999 with its stream's CFG-2: the peer is
    dropped unanswered, named with the IDCODE; an answer addressed to another IDCODE is
    refused."""
    cfg = wire[0]
    link = c37_loop.PlantLink(None, cfg, timeout=1)
    with link, socket.create_connection(link.address) as peer:
        peer.sendall(CommandFrame(999, "cfg2").convert2bytes())
        with pytest.raises(InputError) as err:
            link._connected()
        assert _read_all(peer, 0.5) == b""
    assert "a command for IDCODE 999, not this stream's 1)" in str(err.value)
    answer = c37_loop.modes_frame(999, 0, 0, [0, 0, 0, 0])
    with pytest.raises(InputError, match="addressed to IDCODE 999, not this stream's 1"):
        c37_loop.read_modes(answer, 4, idcode=1)


def test_each_pmu_streams_share_the_idcode_a_client_addresses(wire):
    """`pmu serve --each-pmu` streams were IDCODE 1, 3, 5, ...: a client of the port range
    addressing one IDCODE would get only the first.  Every stream is IDCODE 1, its PMU's
    block 2 + k as in the one stream."""
    import stabctl

    cfg = wire[0]
    case = stabctl.load_case("kundur")
    one = c37.config_frame(cfg)
    for k, pmu in enumerate(cfg.pmus):
        sub = c37.config_frame(c37.stream_config(case, [pmu], 60, 1, pmu_idcode=2 + k))
        assert sub.get_id_code() == 1
        assert sub.get_stream_id_code() == one.get_stream_id_code()[k] == 2 + k
