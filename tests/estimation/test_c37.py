"""IEEE C37.118.2-2011 frames of the simulated PMUs (stabctl.estimation.c37): miniWECC's
34 PMUs through a recording and back (pyc37's parser), a data frame and the CFG-2 frame
decoded by hand from the standard's layout with a CRC-CCITT written here, and the errors
of broken recordings."""

import struct
import time

import numpy as np
import pytest

pytest.importorskip("pyc37")

from c37_check import crc_ccitt

import stabctl
from stabctl.errors import InputError
from stabctl.estimation import c37
from stabctl.estimation import pmu as pm
from stabctl.estimation.settings import PMUSettings
from stabctl.studies.cases import CASE2


@pytest.fixture(scope="module")
def wecc_stream():
    """miniWECC's Case 2 fault, 3 s; one PMU per generator terminal, 60 frames/s, 5 % of
    the frames lost."""
    case = stabctl.load_case("miniwecc")
    res = stabctl.Simulator(case).run(CASE2.fault.events(6 / case.freq_hz), t_end=3.0)
    pmus = pm.machine_pmus(case)
    stream = pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(drop_prob=0.05), seed=1)
    return case, c37.stream_config(case, pmus, 60), stream


def test_a_recording_gives_back_every_frame(wecc_stream, tmp_path):
    """34 PMUs, 181 frames: phasors back to float32 precision (the wire's), frequency to
    its 1 mHz and ROCOF to its 0.01 Hz/s (the 16-bit FREQ and DFREQ), time stamps to the
    microsecond, every lost PMU frame marked absent."""
    _case, cfg, stream = wecc_stream
    path = tmp_path / "wecc.c37"
    assert c37.record(path, cfg, stream) == len(stream) == 181
    back = c37.replay(path, cfg)
    assert len(back) == len(stream) and cfg.n == 34
    sent = list(stream)
    valid = np.array([f.valid for f in sent])
    assert 0 < (~valid).sum() and np.array_equal(np.array([b.valid for b in back]), valid)
    for b, f in zip(back, sent):
        ok = f.valid
        assert abs(b.t - f.t) <= 0.5e-6
        np.testing.assert_allclose(b.v[ok], f.v[ok], rtol=1.2e-7)
        np.testing.assert_allclose(b.i[ok], f.i[ok], rtol=1.2e-7)
        assert np.max(np.abs(b.freq[ok] - f.freq[ok])) <= 0.5e-3 + 1e-12
        assert np.max(np.abs(b.rocof[ok] - f.rocof[ok])) <= 0.005 + 1e-12
        assert np.all(np.isnan(b.v[~ok])) and np.all(np.isnan(b.freq[~ok]))


def test_a_data_frame_decoded_by_hand_from_the_standard(wecc_stream):
    """SYNC 0xAA01 (data frame, version 1), FRAMESIZE, IDCODE, SOC, FRACSEC (time quality
    byte, then the count of TIME_BASE), per PMU STAT, phasors (float re, im), FREQ (mHz
    deviation) and DFREQ (Hz/s x 100) as 16-bit integers, then CHK."""
    case, cfg, stream = wecc_stream
    k = 75  # 1.25 s: during the swing after clearing
    frame = stream.frame(k)
    data = c37.data_frame(cfg, c37.config_frame(cfg), frame)
    sync, size, idcode, soc, fracsec = struct.unpack(">HHHII", data[:14])
    assert (sync, size, idcode) == (0xAA01, len(data), cfg.idcode)
    assert soc == cfg.epoch + 1 and fracsec >> 24 == 0
    assert (fracsec & 0xFFFFFF) == round(0.25 * c37.TIME_BASE)
    assert struct.unpack(">H", data[-2:])[0] == crc_ccitt(data[:-2])
    at = 14
    for j in range(cfg.n):
        (stat,) = struct.unpack(">H", data[at : at + 2])
        at += 2
        re, im = struct.unpack(">ff", data[at : at + 8])
        at += 8 * cfg.phasors(j)
        freq, dfreq = struct.unpack(">hh", data[at : at + 4])
        at += 4
        if frame.valid[j]:
            assert stat == 0
            kv = case.buses.kv[case.bus_index(cfg.pmus[j].bus)]
            v = frame.v[j] * kv * 1e3 / np.sqrt(3)  # volts, phase to neutral
            assert (re, im) == pytest.approx((v.real, v.imag), rel=1e-7)
            assert freq == round((frame.freq[j] - 60.0) * 1000)
            assert dfreq == round(frame.rocof[j] * 100)
        else:
            assert stat == 0x8000  # bits 15-14 = 10: absent data inserted
    assert at == len(data) - 2


def test_the_configuration_frame_decoded_by_hand(wecc_stream):
    """CFG-2: SYNC 0xAA31, TIME_BASE, NUM_PMU, the first PMU's station name, IDCODE,
    FORMAT 0x0002 (rectangular float phasors, integer FREQ), PHNMR, FNOM (bit 0 = 0: 60
    Hz), and DATA_RATE last before CHK."""
    _case, cfg, _stream = wecc_stream
    data = c37.config_frame(cfg).convert2bytes()
    sync, size = struct.unpack(">HH", data[:4])
    assert (sync, size) == (0xAA31, len(data))
    time_base, num_pmu = struct.unpack(">IH", data[14:20])
    assert (time_base & 0xFFFFFF, num_pmu) == (c37.TIME_BASE, 34)
    name = data[20:36].decode().strip()
    idcode, fmt, phnmr, annmr, dgnmr = struct.unpack(">HHHHH", data[36:46])
    assert (name, idcode, fmt, phnmr, annmr, dgnmr) == (cfg.pmus[0].label, 2, 0x0002, 2, 0, 0)
    assert struct.unpack(">h", data[-4:-2])[0] == 60
    assert struct.unpack(">H", data[-2:])[0] == crc_ccitt(data[:-2])


def test_a_single_pmu_stream(wecc_stream, tmp_path):
    """One PMU per stream (a PMU server's own): pyc37's single-PMU layout."""
    case, _cfg, stream = wecc_stream
    one = c37.stream_config(case, stream.pmus[:1], 60)
    frames = [pm.Frame(f.t, f.valid[:1], f.v[:1], f.i[:1], f.freq[:1], f.rocof[:1]) for f in stream]
    c37.record(tmp_path / "one.c37", one, frames[:10])
    back = c37.replay(tmp_path / "one.c37", one)
    assert len(back) == 10
    np.testing.assert_allclose(back[3].v, frames[3].v, rtol=1.2e-7)


def test_broken_recordings_and_settings_are_named(wecc_stream, tmp_path):
    case, cfg, stream = wecc_stream
    path = tmp_path / "r.c37"
    c37.record(path, cfg, list(stream)[:5])
    data = path.read_bytes()
    (tmp_path / "cut.c37").write_bytes(data[:-7])
    with pytest.raises(InputError, match=r"frame at byte \d+ cut short"):
        c37.replay(tmp_path / "cut.c37", cfg)
    flipped = bytearray(data)
    flipped[-10] ^= 0xFF  # a bit error in the last data frame
    (tmp_path / "crc.c37").write_bytes(bytes(flipped))
    with pytest.raises(InputError, match=r"data frame not readable.*CRC"):
        c37.replay(tmp_path / "crc.c37", cfg)
    other = c37.stream_config(case, cfg.pmus, 30)
    with pytest.raises(InputError, match="its CFG-2 DATA_RATE 60, not the 30 expected"):
        c37.replay(path, other)
    with pytest.raises(InputError, match=r"data rate must be 1\.\.240"):
        c37.stream_config(case, cfg.pmus, 1000)
    with pytest.raises(InputError, match="no frame SYNC at byte 0"):
        (tmp_path / "junk.c37").write_bytes(b"\x00" * 40)
        c37.replay(tmp_path / "junk.c37", cfg)


def test_loopback_stream_reaches_pyc37_s_client_whole(wecc_stream):
    """miniWECC's 34 PMUs at 60 frames/s in real time over loopback TCP to pyc37's own PDC
    client: the header and CFG-2 on request, then after 'start' all 181 data frames, in
    order, each carrying what was sent (none lost).  Latency from each frame's due time
    to its arrival is printed (benchmarks/c37_loopback.py measures a minute)."""
    from stabctl.estimation.c37_tcp import StreamServer, pdc_client

    _case, cfg, stream = wecc_stream
    sent = list(stream)
    with StreamServer.of_frames(cfg, sent) as server:
        pdc = pdc_client(*server.address, idcode=server.idcode)
        assert "34" in pdc.get_header().get_header()
        cfg2 = pdc.get_config()
        assert (cfg2.get_num_pmu(), cfg2.get_data_rate()) == (34, 60)
        pdc.start()
        got, arrived = [], []
        for _ in sent:
            got.append(pdc.get())
            arrived.append(time.perf_counter())
        pdc.quit()
    late = np.array(arrived) - np.array(server.due_at)
    print(
        f"\nloopback 34 PMUs, 60 fps: latency median {1e3 * np.median(late):.2f} ms, "
        f"99th percentile {1e3 * np.percentile(late, 99):.2f} ms"
    )
    assert len(got) == len(sent)
    for g, f in zip(got, sent):
        b = c37.parse_frame(cfg, cfg2, _as_sent(g.convert2bytes(), cfg2))
        assert b.t == pytest.approx(f.t, abs=0.5e-6)
        np.testing.assert_allclose(b.v[f.valid], f.v[f.valid], rtol=1.2e-7)


def _as_sent(data: bytes, cfg2) -> bytes:
    """A data frame pyc37's client parsed, written back by pyc37, with each STAT's bit 13
    (PMU sync error) as it was sent: pyc37 1.0.2 reads a clear bit 13 as 'not in sync'
    and writes that back as the bit set, so every frame it re-encodes says sync lost."""
    out, at = bytearray(data), 14
    for block in c37.blocks(cfg2):
        out[at] ^= 0x20
        at += block.size
    return bytes(out[:-2]) + crc_ccitt(bytes(out[:-2])).to_bytes(2, "big")


def test_unpaced_stream_ends_the_session_and_serves_the_next(wecc_stream):
    """speed = inf sends as fast as the socket takes the frames; a session ends once every
    frame is sent and the client has taken the last (`finished`), and the next client gets
    the whole stream again."""
    from stabctl.estimation.c37_tcp import StreamServer, pdc_client

    _case, cfg, stream = wecc_stream
    with StreamServer.of_frames(cfg, stream, speed=float("inf")) as server:
        for _ in range(2):
            pdc = pdc_client(*server.address, idcode=server.idcode)
            pdc.get_config()
            pdc.start()
            frames = [pdc.get() for _ in range(len(stream))]
            assert [f.get_soc() for f in frames[:2]] == [cfg.epoch, cfg.epoch]
            pdc.quit()  # the last frame taken: the session is whole
            assert server.finished.wait(10) and server.n_sent == len(stream)
            server.finished.clear()
    with pytest.raises(InputError, match="speed must be > 0"):
        StreamServer.of_frames(cfg, stream, speed=0)


def test_peers_of_another_protocol_are_named_or_dropped(wecc_stream):
    """A web client at the stream server is dropped and the next PDC still gets the whole
    stream; a web server where a C37.118.2 server should be is named as such, not waited
    on."""
    import socket
    import threading

    from stabctl.estimation.c37_tcp import StreamServer, receive

    _case, cfg, stream = wecc_stream
    with StreamServer.of_frames(cfg, stream, speed=float("inf")) as server:
        with socket.create_connection(server.address) as web:
            web.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
            try:
                assert web.recv(100) == b""  # closed by the server
            except ConnectionResetError:
                pass  # closed with the request unread
        got = receive(*server.address, timeout=10)
        assert len(got.data) == len(stream) and got.cfg2[0] == 0xAA and not got.short
        assert "does not speak C37.118.2" in server.refused[0]
    web_server = socket.create_server(("127.0.0.1", 0))

    def answer():
        conn, _ = web_server.accept()
        with conn:
            conn.recv(100)
            conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\nhi")

    threading.Thread(target=answer, daemon=True).start()
    with web_server, pytest.raises(InputError, match=r"does not speak C37\.118\.2"):
        receive(*web_server.getsockname()[:2], timeout=10)


def test_a_file_that_is_no_recording_is_named():
    """A CSV given as a recording: the message names the file, not only 'recording'."""
    with pytest.raises(InputError, match=r"^faults\.csv: no frame SYNC at byte 0"):
        c37.split_frames(b"bus,far_bus\n", "faults.csv")


def test_a_stream_of_another_rate_than_its_configuration_is_refused(wecc_stream, tmp_path):
    """A 50 Hz case's stream described as 60 frames/s was configured, recorded and read
    back whole (the CLI refused the file): stream_config takes only the case's rates,
    record only frames at its reporting instants (writing nothing), and replay refuses
    repeated or backward time stamps as the CLI's sources do."""
    case, cfg, stream = wecc_stream
    with pytest.raises(InputError, match=r"stream_config\(rate=50\): must be one of 10, 12"):
        c37.stream_config(case, cfg.pmus, 50)
    slow = c37.stream_config(case, cfg.pmus, 30)
    path = tmp_path / "slow.c37"
    with pytest.raises(InputError, match=r"frame 2 at t = 0.0166667 s is no reporting instant"):
        c37.record(path, slow, stream)
    assert not path.exists() and list(tmp_path.iterdir()) == []
    frames = list(stream)
    assert c37.record(path, slow, frames[::2]) == len(frames[::2])
    twice = [frames[0], frames[1], frames[1], frames[2]]
    c37.record(tmp_path / "twice.c37", cfg, twice)
    with pytest.raises(InputError, match=r"twice.c37: .*data frame 3 .*repeat"):
        c37.replay(tmp_path / "twice.c37", cfg)


def test_a_recording_not_starting_with_a_sync_is_refused_before_it_is_read_whole(
    tmp_path, monkeypatch
):
    """Round 42: 200 MB of NUL bytes given as a recording were read whole (about 400 MiB)
    before "no frame SYNC at byte 0"; its first byte decides (C37.118.2-2011 6.2: every
    frame starts with SYNC 0xAA), so the file is not read further."""
    from pathlib import Path

    junk = tmp_path / "zeros.c37"
    junk.write_bytes(b"\x00" * 4096)

    def whole(self):
        raise AssertionError(f"{self} read whole")

    monkeypatch.setattr(Path, "read_bytes", whole)
    with pytest.raises(InputError, match=r"zeros\.c37: no frame SYNC at byte 0 \(not a C37"):
        c37.recorded_frames(junk)
