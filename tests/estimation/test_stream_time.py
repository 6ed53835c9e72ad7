"""Time stamps and time quality of a received stream: a frame whose FRACSEC time quality
says clock failure is not used, as one whose STAT says sync lost; frames off the reporting
instants of the CFG-2's DATA_RATE are refused by name; reporting instants no stream sent
are counted and said, a short gap filled with missing values and a long one restarting
the estimator, never predicted across."""

import binascii
import re
import struct

import numpy as np
import pytest
from click.testing import CliRunner

pytest.importorskip("pyc37")

from stabctl.cli import main
from stabctl.estimation import c37


@pytest.fixture(scope="module")
def wire():
    """Kundur's 4-PMU stream for 1.5 s (91 frames): its CFG-2 (pyc37) and the CFG-2 and
    data frames as bytes."""
    from pmu_streams import kundur_stream, on_the_wire

    _, _, cfg, frames = kundur_stream(t_end=1.5)
    head, body = on_the_wire(cfg, frames)
    return c37.config_frame(cfg), head, body


@pytest.fixture(scope="module")
def midnight_wire():
    """`wire` with t = 1 s at 00:00:00 UTC (SOC 1 700 006 400, a multiple of 86 400): a
    leap second is inserted only at the end of a UTC day (ITU-R TF.460)."""
    import dataclasses

    from pmu_streams import kundur_stream, on_the_wire

    _, _, cfg, frames = kundur_stream(t_end=1.5)
    cfg = dataclasses.replace(cfg, epoch=1_700_006_399)
    head, body = on_the_wire(cfg, frames)
    return c37.config_frame(cfg), head, body


def _crc(frame: bytes) -> bytes:
    return frame[:-2] + binascii.crc_hqx(frame[:-2], 0xFFFF).to_bytes(2, "big")


def _later(frame: bytes, us: int) -> bytes:
    """frame stamped `us` microseconds later, its CRC valid."""
    t = int.from_bytes(frame[6:10], "big") * 1_000_000 + int.from_bytes(frame[11:14], "big")
    t += us
    soc, count = divmod(t, 1_000_000)
    return _crc(
        frame[:6] + soc.to_bytes(4, "big") + frame[10:11] + count.to_bytes(3, "big") + frame[14:]
    )


def _quality(frame: bytes, byte: int) -> bytes:
    """frame with FRACSEC's time quality byte set, its CRC valid."""
    return _crc(frame[:10] + bytes([byte]) + frame[11:])


def _track(tmp_path, head, body):
    path = tmp_path / "r.c37"
    path.write_bytes(head + b"".join(body))
    args = ["estimate", "track", "kundur", "--source", str(path), "--out", str(tmp_path / "t.csv")]
    return CliRunner().invoke(main, args)


def _largest_mhz(res) -> float:
    return float(res.stdout.split("largest |f_i - f_COI| ")[1].split(" mHz")[0])


def test_a_clock_failure_makes_the_frame_s_values_unusable(wire, tmp_path):
    """FRACSEC time quality 0xF (C37.118.2-2011 clause 6.2.2: clock failure, time not
    reliable) was never read: such frames were tracked as good data.  Their values are now
    not used and counted by that reason, as a STAT's sync lost are; the leap-second bits
    leave them used."""
    cfg2, head, body = wire
    bad = _quality(body[50], 0x0F)
    assert c37.flags(cfg2, bad) == [c37.TIME_QUALITY_FAULT[2]] * 4
    assert c37.flags(cfg2, _quality(body[50], 0x30)) == [""] * 4
    res = _track(tmp_path, head, body[:45] + [_quality(f, 0x0F) for f in body[45:]])
    assert res.exit_code == 0, res.output
    assert (
        "184 PMU values not used by their STAT or time quality (184 clock failure (FRACSEC "
        "time quality 0xF))" in res.stdout
    )
    leap = _track(tmp_path, head, [_quality(f, 0x30) for f in body])
    assert leap.exit_code == 0 and "not used" not in leap.stdout, leap.output


def _stat(cfg2, frame: bytes, bits: int) -> bytes:
    """frame with `bits` set in every PMU's STAT word, its CRC valid."""
    out, at = bytearray(frame), 14
    for b in c37.blocks(cfg2):
        stat = int.from_bytes(out[at : at + 2], "big") | bits
        out[at : at + 2] = stat.to_bytes(2, "big")
        at += b.size
    return _crc(bytes(out))


@pytest.mark.parametrize(
    "edit, reason",
    [
        ("q0B", "clock error up to 10 s (FRACSEC time quality 0xB)"),
        ("q06", "clock error up to 100 us (FRACSEC time quality 0x6)"),
        ("s0030", "clock unlocked for over 1000 s (STAT bits 5-4 = 11)"),
        ("s01C0", "PMU time error over 10 ms or unknown (STAT bits 8-6 = 111)"),
        ("s0100", "PMU time error up to 100 us (STAT bits 8-6 = 100)"),
    ],
)
def test_time_quality_beyond_10_us_is_named_and_not_used(wire, tmp_path, edit, reason):
    """FRACSEC time quality 0xB (clock unlocked, error up to 10 s), STAT bits 5-4 = 11
    (unlocked over 1000 s) or bits 8-6 = 111 (time error over 10 ms) were tracked as
    good data without a word.  A value is used only if its time is known to within 10 us
    (1 % TVE is 26.5 us at 60 Hz): the others are not used, counted and named; FRACSEC
    code 0x5 (10 us), STAT bits 8-6 = 011 and bits 5-4 = 10 leave the values used."""
    cfg2, head, body = wire
    value = int(edit[1:], 16)
    mark = (lambda f: _quality(f, value)) if edit[0] == "q" else (lambda f: _stat(cfg2, f, value))
    assert c37.flags(cfg2, mark(body[50])) == [reason] * 4
    res = _track(tmp_path, head, body[:45] + [mark(f) for f in body[45:]])
    assert res.exit_code == 0, res.output
    assert "184 PMU values not used by their " in res.stdout and f"(184 {reason})" in res.stdout
    for fine in (_quality(body[50], 0x05), _stat(cfg2, body[50], 0x00E0)):
        assert c37.flags(cfg2, fine) == [""] * 4


def test_frames_off_the_data_rate_s_instants_are_refused(wire, tmp_path):
    """Frames 1/50 s apart in a stream whose CFG-2 says 60 frames/s were tracked, exit 0:
    the second frame is refused by name, with the count of such frames."""
    _, head, body = wire
    off = [_later(f, k * 20_000 - round(k * 1e6 / 60)) for k, f in enumerate(body)]
    res = _track(tmp_path, head, off)
    assert res.exit_code == 2, res.output
    assert (
        "stream 1: data frame 2 is stamped 0.020000 s into its second, not a reporting "
        "instant of its CFG-2's DATA_RATE 60" in res.stderr
    )


def test_a_short_gap_is_filled_and_said(wire, tmp_path):
    """Frames 40 on stamped 0.5 s later (30 reporting instants missing) were tracked with
    no word: the gap is said (count, where) and filled with frames of missing values, and
    the count of what was tracked tells the 91 frames received from the 30 instants
    filled (it said "tracked 121 frames")."""
    _, head, body = wire
    res = _track(tmp_path, head, body[:40] + [_later(f, 500_000) for f in body[40:]])
    assert res.exit_code == 0, res.output
    assert res.stdout.startswith(
        "tracked 121 reporting instants (91 received, 30 of gaps filled with missing values)"
    )
    assert (
        "30 reporting instants missing (sent by no stream) in 1 gap(s): 30 after t = 0.6500 "
        "s, to 1.1667 s (filled with missing values)" in res.stdout
    )
    rows = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)
    assert rows.shape[0] == 121 and np.allclose(np.diff(rows[:, 0]), 1 / 60)
    # the filled rows say how old each machine's value is (round 44: `--estimator raw`
    # held values through the gap and wrote them as measured): k/60 s at the k-th filled
    # instant, 0 where measured
    ages = np.genfromtxt(tmp_path / "t.csv", delimiter=",", names=True)
    age = np.column_stack([ages[n] for n in ages.dtype.names if n.startswith("age_")])
    assert age.shape == (121, 4)
    want = np.zeros(121)
    want[40:70] = np.arange(1, 31) / 60
    np.testing.assert_allclose(age, np.repeat(want[:, None], 4, axis=1), atol=1e-9)


@pytest.mark.parametrize("seconds", [10, 3600])
def test_a_long_gap_restarts_the_estimator(wire, tmp_path, seconds):
    """A stream followed by itself an hour later was tracked with a relative speed of
    1.1 kHz (the filter predicted across the hour), exit 0, and a 10 s gap with no word:
    the gap is said, and the estimator starts again after it, so the relative speeds stay
    those of the stream."""
    _, head, body = wire
    whole = _track(tmp_path, head, body)
    res = _track(tmp_path, head, body + [_later(f, seconds * 1_000_000) for f in body])
    assert res.exit_code == 0, res.output
    missing = seconds * 60 - 91
    assert (
        f"{missing} reporting instants missing (sent by no stream) in 1 gap(s): {missing} "
        "after t = 1.5000 s" in res.stdout
    )
    assert "(the estimator restarts after it)" in res.stdout
    assert _largest_mhz(res) == pytest.approx(_largest_mhz(whole), rel=0.05)


def _config(head: bytes, time_base=None, rate=None) -> bytes:
    """The CFG-2 frame with TIME_BASE (bytes 14-17) or DATA_RATE (the int16 before its
    CHK) changed, its CRC valid."""
    out = bytearray(head)
    if time_base is not None:
        out[14:18] = time_base.to_bytes(4, "big")
    if rate is not None:
        out[-4:-2] = rate.to_bytes(2, "big", signed=True)
    return _crc(bytes(out))


def test_a_cfg2_inside_a_recording_is_named_not_read_as_a_data_frame(wire, tmp_path):
    """A second CFG-2 after data frame 60 was called "data frame 61 goes back from the
    time stamp of frame 60".  One that changes the configuration is refused naming the
    frame, the data frames before it and the field; the same CFG-2 resent is left out,
    as a receiver leaves it out of a stream."""
    _, head, body = wire
    res = _track(tmp_path, head, body[:60] + [_config(head, time_base=1000)] + body[60:])
    assert res.exit_code == 2, res.output
    assert (
        "frame 62, after data frame 60: a CFG-2 that changes the stream's configuration "
        "(TIME_BASE 1000 where the CFG-2 in use has 1000000)"
    ) in res.stderr, res.stderr
    res = _track(tmp_path, head, body[:60] + [head] + body[60:])
    assert res.exit_code == 0 and "tracked 91 frames" in res.stdout, res.output


def test_replay_refuses_a_negative_data_rate_its_frames_do_not_keep(wire, tmp_path):
    """`pmu replay` of a recording whose CFG-2 says DATA_RATE -1 (one frame a second)
    with frames 1/60 s apart listened and served it: the rate grid was not checked for a
    DATA_RATE <= 0.  Refused before listening, naming DATA_RATE; a stream of one frame a
    second is served."""
    _, head, body = wire
    path = tmp_path / "r.c37"
    path.write_bytes(_config(head, rate=-1) + b"".join(body))
    args = ["pmu", "replay", str(path), "--port", "0", "--wait", "1", "--timeout", "1"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2 and "serving" not in res.stderr, res.output
    assert (
        "data frame 2 is stamped 0.016667 s into its second, 0 s after the first, not a "
        "reporting instant of its CFG-2's DATA_RATE -1 (negative: one frame every 1 s"
    ) in res.stderr, res.stderr
    from stabctl.estimation.sources import check_order

    check_order(body[::60], c37.read_config(_config(head, rate=-1), "CFG-2"), "ok")


def test_a_leap_second_is_read_across_in_order(midnight_wire, wire, tmp_path):
    """A stream across a positive leap second (frames flagged leap pending, one second's
    SOC repeated, then flagged leap occurred) was refused as "goes back": the repeated
    second is the leap second, so the frames from it on are 1 s later than stamped.  The
    track is the one of the same frames stamped without the leap (row for row), and the
    recording passes the order check; a stream that goes back more than the second, or
    flags a deleted second, is still refused naming the leap-second flags, and so is a
    flagged stream whose frames repeat or go back within a second."""
    from stabctl.estimation.sources import check_order

    # round 40: flags and a repeated second at 22:13:21 UTC, where no leap second is ever
    # inserted, were read as one (a replayed second re-timed 1 s later, without a word)
    _, head, body = wire
    res = _track(tmp_path, head, _leaped(body))
    assert res.exit_code == 2, res.output
    assert "data frame 61 goes back from the time stamp of frame 60" in res.stderr
    _, head, body = midnight_wire
    pending = [_quality(f, 0x10) for f in body[:60]]
    again = [_later(_quality(f, 0x20), -1_000_000) for f in body[60:]]
    cfg2 = c37.read_config(head, "CFG-2")
    check_order(pending + again, cfg2, "leap")
    assert list(c37.leap_offsets(pending + again, cfg2)) == [0] * 60 + [1] * len(again)
    res = _track(tmp_path, head, pending + again)
    assert res.exit_code == 0, res.output
    leaped = (tmp_path / "t.csv").read_text()
    res = _track(tmp_path, head, body)
    assert res.exit_code == 0, res.output
    assert leaped == (tmp_path / "t.csv").read_text()
    for bad in (
        [_later(_quality(f, 0x20), -2_000_000) for f in body[60:]],  # back 2 s
        [_later(_quality(f, 0x60), -1_000_000) for f in body[60:]],  # a deleted second
    ):
        res = _track(tmp_path, head, [_quality(f, 0x50) for f in body[:60]] + bad)
        assert res.exit_code == 2, res.output
        assert "data frame 61 goes back from the time stamp of frame 60" in res.stderr
        assert "its FRACSEC flags a leap second (C37.118.2-2011 Table 3)" in res.stderr
    # flags set, but a frame repeated, two swapped, or ten sent again within a second:
    # not the second's SOC again from its rollover (they were read as a leap: every frame
    # after them 1 s late and a gap of 59 frames made up)
    flagged = [_quality(f, 0x10) for f in body]
    occurred = [_quality(f, 0x20) for f in body]
    for frames, k, how in (
        (flagged[:51] + flagged[50:], 51, "repeats"),
        (occurred[:30] + [occurred[31], occurred[30]] + occurred[32:], 31, "goes back from"),
        (flagged[:60] + flagged[50:], 60, "goes back from"),
    ):
        assert list(c37.leap_offsets(frames, cfg2)) == [0] * len(frames)
        res = _track(tmp_path, head, frames)
        assert res.exit_code == 2, res.output
        assert f"data frame {k + 1} {how} the time stamp of frame {k}" in res.stderr
        assert "a frame repeated or out of order" in res.stderr


def test_one_frame_tracked_is_said_in_the_singular(wire, tmp_path):
    """A recording of one data frame was "tracked 1 frames": one frame is said as one."""
    _, head, body = wire
    res = _track(tmp_path, head, body[:1])
    assert res.exit_code == 0, res.output
    assert res.stdout.startswith("tracked 1 frame from "), res.stdout
    assert len((tmp_path / "t.csv").read_text().splitlines()) == 2


def _stamped(frame: bytes, soc: int, count: int, quality: int | None = None) -> bytes:
    """frame stamped (soc, FRACSEC count), its time quality byte kept or set, CRC valid."""
    q = frame[10:11] if quality is None else bytes([quality])
    return _crc(frame[:6] + soc.to_bytes(4, "big") + q + count.to_bytes(3, "big") + frame[14:])


def _served(head: bytes, body: list):
    """A PMU server on 127.0.0.1 that answers 'cfg2' with `head` and 'start' with `body`,
    then waits for the client to close: (listening socket, port)."""
    from pmu_streams import fake_server

    def talk(conn):
        conn.recv(1000)  # 'cfg2'
        conn.sendall(head)
        conn.recv(1000)  # 'start'
        conn.sendall(b"".join(body))
        while conn.recv(1000):  # 'stop', until the client closes
            pass

    return fake_server(talk)


def _track_tcp(tmp_path, head, body, *end, out="tcp.csv"):
    srv, port = _served(head, body)
    with srv:
        src = f"tcp://127.0.0.1:{port}"
        args = ["estimate", "track", "kundur", "--source", src, "--out", str(tmp_path / out)]
        return CliRunner().invoke(main, [*args, *end])


def _leaped(body: list) -> list:
    """body across a positive leap second after its frame 59: frames 0-59 flag it pending,
    frames 60 on are stamped 1 s earlier (the repeated second) and flag it occurred."""
    return [_quality(f, 0x10) for f in body[:60]] + [
        _later(_quality(f, 0x20), -1_000_000) for f in body[60:]
    ]


def test_until_over_tcp_reads_the_time_elapsed_across_a_leap_second(midnight_wire, tmp_path):
    """`estimate track --until 1.25` of a stream across a leap second over TCP read the
    repeated second's stamps as 0 s again: it never reached 1.25 s, took the whole stream
    (91 frames) and called it short (exit 2), where the same frames from a recording
    ended at 1.25 s.  The TCP end reads the time elapsed as the recording does: 76 frames
    (t = 0 .. 1.25 s), exit 0, the same rows as the recording's track."""
    _, head, body = midnight_wire
    leaped = _leaped(body)
    res = _track(tmp_path, head, leaped)  # the recording whole, for the rows
    path = tmp_path / "r.c37"
    args = ["estimate", "track", "kundur", "--source", str(path), "--until", "1.25"]
    res = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "file.csv")])
    assert res.exit_code == 0 and res.stdout.startswith("tracked 76 frames"), res.output
    res = _track_tcp(tmp_path, head, leaped, "--until", "1.25")
    assert res.exit_code == 0, res.output
    assert res.stdout.startswith("tracked 76 frames from tcp://"), res.stdout
    assert (tmp_path / "tcp.csv").read_text() == (tmp_path / "file.csv").read_text()
    # cut short after the leap second: the last time stamp said is the time elapsed
    res = _track_tcp(tmp_path, head, leaped[:70], "--until", "1.25", out="short.csv")
    assert res.exit_code == 2, res.output
    assert "70 data frames, the last stamped 1.1500 s, before t = 1.25 s" in res.stderr


@pytest.mark.parametrize("count", [1_000_000, 1_016_667, 0xFFFFFF])
def test_a_fracsec_count_of_a_second_or_more_is_refused(wire, tmp_path, count):
    """A data frame stamped (SOC, 1 000 000) with TIME_BASE 1 000 000, the rollover to
    the next second written in the wrong second, or with a count beyond a second, was
    tracked without a word (exit 0): FRACSEC's count is a fraction of one second
    (C37.118.2-2011 6.2.2).  Such a frame is refused as malformed, naming the frame and
    its count, from a recording and over TCP alike, and by `pmu replay`; a CFG-2 so
    stamped is refused too."""
    _, head, body = wire
    soc = int.from_bytes(body[59][6:10], "big")  # frame 60 is stamped 1 s, frame 61 1 s later
    bad = body[:60] + [_stamped(body[60], soc, count)] + body[61:]
    said = (
        f"data frame 61: a data frame stamped with FRACSEC count {count}, not below its "
        "CFG-2's TIME_BASE 1000000: the count is a fraction of one second (C37.118.2-2011 "
        "6.2.2)"
    )
    res = _track(tmp_path, head, bad)
    assert res.exit_code == 2 and f"stream 1, {said}" in res.stderr, res.output
    assert not (tmp_path / "t.csv").exists()
    res = _track_tcp(tmp_path, head, bad, "--frames", "91")
    assert res.exit_code == 2 and f": {said}" in res.stderr, res.output
    assert not (tmp_path / "tcp.csv").exists()
    res = CliRunner().invoke(main, ["pmu", "replay", str(tmp_path / "r.c37"), "--port", "0"])
    assert res.exit_code == 2 and said in res.stderr, res.output
    cfg = _crc(head[:11] + count.to_bytes(3, "big") + head[14:])
    res = _track(tmp_path, cfg, body)
    assert res.exit_code == 2, res.output
    assert (
        f"first frame stamped with FRACSEC count {count}, not below its TIME_BASE 1000000"
        in res.stderr
    )


def test_t_0_is_the_cfg2_s_whole_time_stamp(wire, tmp_path):
    """A CFG-2 stamped 0.5 s into its second, its data frames from there on: the first row
    was at t = 0.5 s and --until 0.5 took one frame, the CFG-2's FRACSEC left out.  t = 0
    is its whole time stamp, from a recording and over TCP: the first row at 0, --until
    0.5 to 31 frames.  A CFG-2 stamped between two reporting instants (0.01 s) puts the
    frames at k / 60 - 0.01 s, and a gap among them is counted and filled at those
    instants."""
    _, head, body = wire
    half = _crc(head[:11] + (500_000).to_bytes(3, "big") + head[14:])
    res = _track(tmp_path, half, body[30:])
    assert res.exit_code == 0, res.output
    rows = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)
    assert rows.shape[0] == 61 and rows[0, 0] == 0.0 and rows[-1, 0] == 1.0
    path = tmp_path / "r.c37"
    args = ["estimate", "track", "kundur", "--source", str(path), "--until", "0.5"]
    res = CliRunner().invoke(main, [*args, "--out", str(tmp_path / "file.csv")])
    assert res.exit_code == 0 and res.stdout.startswith("tracked 31 frames"), res.output
    res = _track_tcp(tmp_path, half, body[30:], "--until", "0.5")
    assert res.exit_code == 0 and res.stdout.startswith("tracked 31 frames"), res.output
    assert (tmp_path / "tcp.csv").read_text() == (tmp_path / "file.csv").read_text()
    between = _crc(head[:11] + (10_000).to_bytes(3, "big") + head[14:])
    res = _track(tmp_path, between, body[1:40] + body[45:])
    assert res.exit_code == 0, res.output
    assert (
        "5 reporting instants missing (sent by no stream) in 1 gap(s): 5 after t = 0.6400 s, "
        "to 0.7400 s (filled with missing values)" in res.stdout
    )
    rows = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)
    assert np.allclose(rows[:, 0], np.arange(1, 91) / 60 - 0.01, atol=1e-9)


class _OnlyEnds(list):
    """Frames received so far, refusing any read but the first and the last frame (a slice
    past them copies every frame received)."""

    def __getitem__(self, k):
        if isinstance(k, slice):
            start, stop, _ = k.indices(len(self))
            if stop - start > 1:
                raise AssertionError(f"read frames {start}-{stop - 1} of {len(self)}")
        return super().__getitem__(k)


def test_a_receiver_checks_each_frame_against_the_first_and_last_only(wire):
    """A receiver checks each data frame's stamp as it comes (`c37.next_frame_fault`),
    against the first frame (the DATA_RATE grid) and the last: reading nothing else, so
    the check's cost stays the same however long the stream has run (it copied every
    frame received, 17 ms a frame after a million frames, beyond a 60 fps stream's
    16.7 ms).  The verdicts are those of the whole stream's check (`c37.order_faults`)."""
    cfg2, _, body = wire
    assert all(
        c37.next_frame_fault(_OnlyEnds(body[:k]), body[k], cfg2) is None for k in range(len(body))
    )
    back = _later(body[40], -round(2e6 / 60))  # two reporting instants back
    why = c37.next_frame_fault(_OnlyEnds(body[:41]), back, cfg2)
    whole = c37.order_faults([*body[:41], back], cfg2, "")
    assert why is not None and "data frame 42" in why and whole and "data frame 42" in whole[0][1]


def test_data_stamped_long_before_its_cfg2_is_refused(wire, tmp_path):
    """A recording whose data frames are stamped 100 s before its CFG-2 (or a CFG-2 of
    SOC 0xFFFFFFFF, year 2106) was tracked at t = -98.9 s (or -2.6e9 s), exit 0: t = 0 is
    the CFG-2's stamp, and a configuration frame comes before the data it describes.
    Refused beyond BEFORE_CFG2_S; a frame stamped within it (a PMU's latency) is kept."""
    from stabctl.estimation.sources import BEFORE_CFG2_S

    _, head, body = wire
    soc = int.from_bytes(head[6:10], "big")
    for later, bad in ((100, True), (2**32 - 1 - soc, True), (0, False)):
        moved = _crc(head[:6] + (soc + later).to_bytes(4, "big") + head[10:])
        res = _track(tmp_path, moved, body)
        if bad:
            assert res.exit_code == 2, res.output
            assert "stream 1, data frame 1: stamped " in res.stderr
            assert "s before the CFG-2 (t = 0 the earliest CFG-2's time stamp)" in res.stderr
        else:
            assert res.exit_code == 0, res.output
    early = [_later(f, -round(0.5e6)) for f in body]  # 0.5 s before: a latency, kept
    assert BEFORE_CFG2_S > 0.5 and _track(tmp_path, head, early).exit_code == 0


def test_until_takes_the_frames_up_to_it_not_one_past_a_gap(wire, tmp_path):
    """A recording whose CFG-2 is stamped 1000 s before its data, tracked --until 1:
    one frame at t = 1000 s was tracked as if it were the end (the first frame at or
    after --until is the end's).  A frame more than one reporting interval past --until
    (after a gap) is not taken: here none is left, refused by name; --until 0.5 takes
    the frames to 0.5 s (31), --until 0.51 the one reaching it too (32)."""
    _, head, body = wire
    soc = int.from_bytes(head[6:10], "big")
    early = _crc(head[:6] + (soc - 1000).to_bytes(4, "big") + head[10:])
    path = tmp_path / "r.c37"
    path.write_bytes(early + b"".join(body))
    out = tmp_path / "t.csv"
    args = ["estimate", "track", "kundur", "--source", str(path), "--out", str(out)]
    res = CliRunner().invoke(main, [*args, "--until", "1"])
    assert res.exit_code == 2 and not out.exists()
    assert "its first data frame is stamped 1000.0000 s (t = 0 its CFG-2's time stamp), " in (
        res.stderr
    )
    path.write_bytes(head + b"".join(body))
    for until, n in (("0.5", 31), ("0.51", 32)):
        res = CliRunner().invoke(main, [*args, "--until", until])
        assert res.exit_code == 0 and res.stdout.startswith(f"tracked {n} frames"), res.output


def test_a_machine_never_measured_leaves_no_relative_speed_not_zero(wire, tmp_path):
    """A recording whose first PMU says in every frame that its data are absent (STAT
    bits 15-14 = 10): a COI needs every machine's speed, so no relative speed can be
    formed.  The track said "largest |f_i - f_COI| 0.0 mHz" and wrote 0 in every
    relative speed; it now writes none (nan, as the COI) beside the other machines'
    speeds, and says why, naming the machine."""
    _, head, body = wire
    absent = [
        _crc(f[:14] + (int.from_bytes(f[14:16], "big") | 0x8000).to_bytes(2, "big") + f[16:])
        for f in body
    ]
    res = _track(tmp_path, head, absent)
    assert res.exit_code == 0, res.output
    assert "largest" not in res.stdout
    assert (
        f"no relative speed in {len(body)} of {len(body)} frames (a COI needs an estimate "
        "of every machine; no estimate ever of G1 (bus 1; PMU B1:G1)): the devices idle "
        "there" in res.stdout  # machines named as every output names them (round 45)
    )
    rows = np.genfromtxt(tmp_path / "t.csv", delimiter=",", names=True)
    assert np.isnan(rows["f_B1G1_hz"]).all() and np.isfinite(rows["f_B2G2_hz"]).all()
    assert np.isnan(rows["f_coi_hz"]).all() and np.isnan(rows["rel_B2G2_mhz"]).all()
    whole = _track(tmp_path, head, body)
    assert "no relative speed" not in whole.stdout and _largest_mhz(whole) > 100
    assert re.search(r" mHz \(G(\d) \(bus \1; PMU B\1:G\1\) at \d+\.\d{3} s\)", whole.stdout)


def _first_pmu_field(cfg2, frame: bytes, field: str, raw: bytes) -> bytes:
    """frame with the first PMU's `field` (``freq``, ``dfreq`` or ``phasor``: its first
    phasor's second word) written `raw`, its CRC valid."""
    b = c37.blocks(cfg2)[0]
    at = 16 + len(b.units) * (8 if b.ph_float else 4)
    at = {"freq": at, "dfreq": at + len(raw), "phasor": 16 + len(raw)}[field]
    return _crc(frame[:at] + raw + frame[at + len(raw) :])


@pytest.mark.parametrize(
    "field, raw",
    [
        ("freq", b"\x80\x00"),  # the absent-data value: FNOM - 32.768 Hz as a number
        ("freq", b"\x7f\xff"),  # saturated: FNOM + 32.767 Hz
        ("dfreq", b"\x80\x00"),
        ("phasor", struct.pack(">f", float("nan"))),  # a floating-point phasor's NaN
        ("phasor", struct.pack(">f", float("inf"))),  # set aside, but neither counted nor said
    ],
)
def test_an_absent_data_value_in_a_field_is_not_a_measurement(wire, tmp_path, field, raw):
    """C37.118.2's absent-data value (0x8000) in G1's FREQ on six frames, its STAT good:
    the raw estimator read it as FNOM - 32.768 Hz, "largest |f_i - f_COI| 24988.7 mHz";
    a saturated FREQ (0x7FFF), 0x8000 in DFREQ and a NaN in a floating-point phasor
    likewise (a NaN was not counted).  Such values are not used, as a STAT saying
    absent makes them, and counted under their own reason: the track equals that of the
    same frames with G1's STAT flagged absent."""
    cfg2, head, body = wire
    assert not c37.blocks(cfg2)[0].fr_float and c37.blocks(cfg2)[0].ph_float
    hit = range(60, 66)
    marked = [_first_pmu_field(cfg2, f, field, raw) if k in hit else f for k, f in enumerate(body)]
    assert c37.flags(cfg2, marked[60]) == [c37.MARKED, "", "", ""]
    flagged = [_stat_first(cfg2, f) if k in hit else f for k, f in enumerate(body)]
    args = ["--estimator", "raw"]
    res = CliRunner().invoke(main, [*_track_args(tmp_path, head, marked, "m"), *args])
    same = CliRunner().invoke(main, [*_track_args(tmp_path, head, flagged, "s"), *args])
    assert res.exit_code == 0 and same.exit_code == 0, (res.output, same.output)
    assert "6 PMU values not used as marked absent in their fields (6 absent-data value " in (
        res.stdout
    )
    assert _largest_mhz(res) == _largest_mhz(same) < 1000
    assert (tmp_path / "m.csv").read_text() == (tmp_path / "s.csv").read_text()


def _stat_first(cfg2, frame: bytes) -> bytes:
    """frame with the first PMU's STAT saying absent data (bits 15-14 = 10), CRC valid."""
    stat = int.from_bytes(frame[14:16], "big") | 0x8000
    return _crc(frame[:14] + stat.to_bytes(2, "big") + frame[16:])


def _track_args(tmp_path, head, body, name):
    path = tmp_path / f"{name}.c37"
    path.write_bytes(head + b"".join(body))
    out = str(tmp_path / f"{name}.csv")
    return ["estimate", "track", "kundur", "--source", str(path), "--out", out]
