#!/usr/bin/env python
"""Thirty-first reliability round (round 46, part AA): variants of issue 54's items 1-5 and 7 not in the earlier
rounds: recordings whose CFG-2 is odd (DATA_RATE 0 or negative, TIME_BASE 0, a bad CRC), two
recordings concatenated, junk after the last frame, a FRAMESIZE of 0 or below the header, a
CFG-2 resent mid-stream with another PMU count, `estimate rmse --source` of a damaged
recording, odd ports and wildcard --host spellings, odd --allow spellings, two controllers
for one plant, records files whose last line lacks its newline or whose lines end in CRLF,
NUMBA_CACHE_DIR empty / below a file / relative.

    python benchmarks/reliability_probes_31.py [ONLY_PREFIX ...]

CLONE (default: this repository) is the package under test, run as `python -m stabctl`;
NUMBA_CACHE_DIR the caller's (warm it with `stabctl compile`).  Prints per probe: id,
ok/SHORT, reason; exits 1 if any is SHORT.  Every command has a timeout; all work in a
temporary directory (removed at the end unless KEEP=1).

The round found short: `pmu record` of a stream whose data frame starts no frame (FRAMESIZE 0 or
below 16, a damaged SYNC byte) after 30 good frames writes none of them (AA-T2, issue 54 item 2's
class), and `--allow ::1%lo` (an IPv6 zone) accepted without a word though it admits no peer
(AA-N3); both fixed (the good frames kept, exit 2 naming the bytes; the zone left out and
said).  About 6 minutes with a warm kernel cache.

The contract (issue 54's "What to build"): a stream source knows its end and says when it got
less; servers bind to loopback unless told otherwise with a warning and take a peer
allow-list; jobs not run are never recorded, finished ones never repeated; every reader
bounds its input; and the developers' standards: one error line naming what and where,
exit status 2, no traceback, no hang, no half-written output presented as whole.
"""

# ruff: noqa: E501, B007, RUF059, SIM115 - a tester's script, kept as written

import json
import os
import shutil
import signal
import struct
import subprocess
import time
from pathlib import Path

from _probe_kit import (
    FakeServer,
    Kit,
    fix_crc,
    free_port,
    group_alive,
    lines_of,
    records,
    stamp_of,
    tail,
    tb,
    wait_listen,
    wait_port,
    with_stamp,
)

KIT = Kit("probes_aa46.", line="{pid:<8} {state:<5} {why}", show_tb=True)
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
run, run_rss, start, finish = KIT.run, KIT.run_rss, KIT.start, KIT.finish
rec, probe = KIT.rec, KIT.probe
recording, track_tcp = KIT.recording, KIT.track_tcp


SWEEP = ["sweep-cct", "kundur", "--faults", "DEFAULT", "--workers", 1, "--tol-ms", 5]


# ---------------------------------------------------------------- recordings read from a file
def blob(cfg, data):
    return cfg + b"".join(data)


def cfg_with(cfg, *, rate=None, time_base=None):
    b = bytearray(cfg)
    if rate is not None:
        b[-4:-2] = struct.pack(">h", rate)
    if time_base is not None:
        b[15:18] = time_base.to_bytes(3, "big")
    return fix_crc(bytes(b))


def track_file(data: bytes, name, extra=(), sub="track", timeout=120):
    f = WD / name
    f.write_bytes(data)
    out = WD / (name + ".csv")
    if out.exists():
        out.unlink()
    args = ["estimate", sub, "kundur", "--source", f]
    if sub == "track":
        args += ["--out", out]
    else:
        args += ["--fault", 3, "--far-bus", 101]
    rc, o, e, dt = run([*args, *extra], timeout=timeout)
    return rc, o, e, dt, out


def refused_file(data, name, words, sub="track"):
    rc, o, e, dt, out = track_file(data, name, sub=sub)
    bad = []
    if rc == "timeout":
        return False, "timeout (a hang)"
    if tb(e):
        bad.append("traceback: " + tail(e, 250))
    if rc == 0:
        bad.append(f"exit 0, taken as whole: {tail(o + e, 200)}")
    elif rc != 2:
        bad.append(f"exit {rc}: {tail(e, 200)}")
    if rc != 0 and sub == "track" and out.exists():
        bad.append(f"{out.name} written beside the refusal")
    if rc != 0 and words and not any(w in e.lower() for w in words):
        bad.append(f"does not name the defect ({words[0]}): {tail(e, 200)}")
    return not bad, "; ".join(bad) or f"exit {rc}: {tail(e, 170)}"


@probe("AA-F1")
def file_rate_zero():
    """A recording whose CFG-2 says DATA_RATE 0 (CRC right): no reporting rate; refused
    naming DATA_RATE, not a ZeroDivisionError or a track at a made-up rate."""
    cfg, d = recording()
    return refused_file(blob(cfg_with(cfg, rate=0), d), "rate0.c37", ["data_rate", "rate"])


@probe("AA-F2")
def file_rate_negative():
    """A recording whose CFG-2 says DATA_RATE -1 (C37.118.2: one frame every second) while
    the frames come 60 a second: off the reporting instants, refused (as W-P4 at 120 vs 60)."""
    cfg, d = recording()
    return refused_file(
        blob(cfg_with(cfg, rate=-1), d), "rateneg.c37", ["data_rate", "rate", "instant"]
    )


@probe("AA-F3")
def file_time_base_zero():
    """A recording whose CFG-2 says TIME_BASE 0: refused naming TIME_BASE, no
    ZeroDivisionError (FRACSEC / TIME_BASE)."""
    cfg, d = recording()
    return refused_file(blob(cfg_with(cfg, time_base=0), d), "tb0.c37", ["time_base", "time base"])


@probe("AA-F4")
def file_cfg_bad_crc():
    """A recording whose CFG-2 has a bad CRC: refused naming the CFG-2 (or frame 0) and
    the CRC."""
    cfg, d = recording()
    bad = cfg[:-2] + bytes([cfg[-2] ^ 0xFF, cfg[-1]])
    return refused_file(blob(bad, d), "cfgcrc.c37", ["crc", "check"])


@probe("AA-F5")
def file_two_concatenated():
    """Two recordings concatenated (`cat a.c37 a.c37 > b.c37`, a second CFG-2 in the middle,
    the time going back 3 s): refused, never tracked as one 6 s stream."""
    cfg, d = recording()
    return refused_file(
        blob(cfg, d) + blob(cfg, d), "twice.c37", ["back", "repeat", "cfg", "time stamp"]
    )


@probe("AA-F6")
def file_trailing_junk():
    """A recording with a text line appended after its last frame (a file edited or
    appended to by mistake): refused, or at least a warning that bytes after the last
    frame are no frame; never tracked silently as whole."""
    cfg, d = recording()
    rc, o, e, dt, out = track_file(blob(cfg, d) + b"# recorded 2026-12-02 by hand\n", "junk.c37")
    if rc == "timeout" or tb(e):
        return False, f"{rc}: {tail(e)}"
    if rc == 0 and not any(
        w in e.lower() for w in ("warning", "byte", "junk", "trailing", "after")
    ):
        return (
            False,
            f"exit 0, {len(d)} frames tracked, the 30 bytes after the last frame passed without a word: {tail(o + e, 160)}",
        )
    return True, f"exit {rc}: {tail(e, 170)}"


@probe("AA-F7")
def file_framesize_zero():
    """Data frame 60 of a recording with FRAMESIZE 0 (and, a second file, 3: below the
    4 bytes of SYNC and FRAMESIZE): a reader stepping by FRAMESIZE must not loop for
    ever; refused naming the frame, within the timeout."""
    cfg, d = recording()
    bad = []
    for n in (0, 3):
        fr = bytearray(d[60])
        fr[2:4] = struct.pack(">H", n)
        ok, why = refused_file(blob(cfg, [*d[:60], bytes(fr), *d[61:]]), f"fs{n}.c37", ["frame"])
        if not ok:
            bad.append(f"FRAMESIZE {n}: {why}")
    return not bad, "; ".join(bad) or "both refused"


@probe("AA-F8")
def file_empty_and_cfg_only():
    """A recording of 0 bytes, and one of only its CFG-2 (no data frame): one error line
    each, exit 2; never 'tracked 0 frames' with exit 0."""
    cfg, d = recording()
    bad = []
    for name, data in (("empty.c37", b""), ("cfgonly.c37", cfg)):
        ok, why = refused_file(data, name, [])
        if not ok:
            bad.append(f"{name}: {why}")
    return not bad, "; ".join(bad) or "both refused"


@probe("AA-F9")
def rmse_damaged_recording():
    """`estimate rmse --source FILE` (not `track`) of a recording cut in the middle of its
    frame 120 of 180 (a recorder killed mid-write): not evaluated as whole; exit 2 (or a
    warning that the recording is cut)."""
    cfg, d = recording()
    data = blob(cfg, d[:120]) + d[120][:20]
    rc, o, e, dt, out = track_file(data, "cut.c37", sub="rmse", timeout=300)
    if rc == "timeout" or tb(e):
        return False, f"{rc}: {tail(e)}"
    if rc == 0 and not any(
        w in (o + e).lower() for w in ("cut", "partial", "truncat", "incomplete", "warning")
    ):
        return False, f"exit 0, an RMSE over the cut recording presented as whole: {tail(o, 160)}"
    return True, f"exit {rc}: {tail(e or o, 170)}"


@probe("AA-F10")
def file_cfg_changed_mid():
    """A recording whose CFG-2 is repeated after frame 60 with NUM_PMU 3 instead of 4 (a
    PDC reconfigured; CRC right, the frames after it unchanged): refused, as the --help
    says a CFG-2 resent must be the one in use."""
    cfg, d = recording()
    b = bytearray(cfg)
    b[18:20] = struct.pack(">H", struct.unpack(">H", bytes(b[18:20]))[0] - 1)
    cfg2 = fix_crc(bytes(b))
    return refused_file(blob(cfg, [*d[:60], cfg2, *d[60:]]), "cfgmid.c37", ["cfg"])


@probe("AA-F11")
def rmse_backward_stamp():
    """`estimate rmse --source FILE` (not `track`, which X07 tried) of a recording whose
    frame 90 is stamped as frame 30 (CRC right): refused naming the frame, as track does."""
    cfg, d = recording()
    s30 = stamp_of(d[30])
    dd = [*d[:90], with_stamp(d[90], *s30), *d[91:]]
    return refused_file(
        blob(cfg, dd), "back_rmse.c37", ["back", "time stamp", "repeat"], sub="rmse"
    )


@probe("AA-F12")
def replay_refuses_before_listening():
    """`pmu replay` of a recording with a FRAMESIZE 0 frame, of two recordings concatenated,
    and of one with junk after its last frame: refused before it listens (its --help:
    'Every frame is checked before the server listens'), exit 2, within 30 s."""
    cfg, d = recording()
    fr = bytearray(d[60])
    fr[2:4] = b"\x00\x00"
    bad, said = [], ""
    for name, data in (
        ("rfs0.c37", blob(cfg, [*d[:60], bytes(fr), *d[61:]])),
        ("rtwice.c37", blob(cfg, d) * 2),
        ("rjunk.c37", blob(cfg, d) + b"junk\n"),
    ):
        (WD / name).write_bytes(data)
        rc, o, e, dt = run(
            ["pmu", "replay", WD / name, "--port", 0, "--wait", 2, "--timeout", 2], timeout=30
        )
        if rc != 2 or tb(e) or "serving" in e:
            bad.append(f"{name}: rc {rc}: {tail(e, 140)}")
        said = tail(e, 120)
    return not bad, "; ".join(bad) or f"each refused: {said}"


# ---------------------------------------------------------------- TCP sources
@probe("AA-T1")
def tcp_cfg_resent_other_pmu_count():
    """Over TCP: after 60 frames the server resends its CFG-2 with NUM_PMU one less (CRC
    right), then goes on: `estimate track --frames 180` refuses the source (its --help:
    'a CFG-2 resent must be the one in use ... refused refuses the source, exit status 2
    and nothing written')."""
    cfg, d = recording()
    b = bytearray(cfg)
    b[18:20] = struct.pack(">H", struct.unpack(">H", bytes(b[18:20]))[0] - 1)
    srv = FakeServer(cfg, [*d[:60], fix_crc(bytes(b)), *d[60:]])
    rc, o, e, dt, out = track_tcp(srv, ["--frames", 180])
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    if rc != 2:
        bad.append(f"exit {rc}: {tail(o + e, 200)}")
    if rc != 0 and out.exists():
        bad.append("CSV written")
    return not bad, "; ".join(bad) or f"exit {rc}: {tail(e, 170)}"


@probe("AA-T2")
def tcp_frame_start_damaged():
    """Over TCP: data frame 30 whose header starts no frame (FRAMESIZE 0; FRAMESIZE 15, below
    the 16 bytes of the smallest frame; SYNC 0xAB for 0xAA, a bit flip), CRC irrelevant:
    `pmu record --frames 180` keeps the 30 frames before it (its --help: 'A stream that
    stops before FRAMES (... or a frame is refused) is written as far as it came, up to the
    frame refused, and named an error (exit status 2)'; issue 54 item 2: `pmu record`
    discarded every frame received), within its time-outs, no traceback."""
    cfg, d = recording()
    bad, said = [], ""
    for name, at, val in (("fs0", 2, b"\x00\x00"), ("fs15", 2, b"\x00\x0f"), ("sync", 0, b"\xab")):
        fr = bytearray(d[30])
        fr[at : at + len(val)] = val
        srv = FakeServer(cfg, [*d[:30], bytes(fr), *d[31:]])
        out = WD / f"{name}rec.c37"
        rc, o, e, dt = run(
            ["pmu", "record", f"127.0.0.1:{srv.port}", "--frames", 180, "-o", out], timeout=90
        )
        srv.close()
        if rc == "timeout":
            bad.append(f"{name}: timeout (90 s)")
            continue
        if tb(e):
            bad.append(f"{name}: traceback " + tail(e, 100))
        kept = out.exists() or (WD / f"{name}rec.partial.c37").exists()
        if rc != 2 or not kept:
            bad.append(
                f"{name}: exit {rc}, the 30 frames received {'kept' if kept else 'not written'}: {tail(e, 170)}"
            )
        said = tail(e, 150)
    return not bad, "; ".join(bad) or f"each kept its 30 frames, exit 2: {said}"


@probe("AA-T3")
def default_rate_against_other_stream_rate():
    """`pmu serve --rate 30` tracked by `estimate track` with no --rate (its default: 60 at
    60 Hz), and `pmu plant --rate 30` commanded by `pmu control` with no --rate: the filters
    are tuned to 60 frames/s and the stream is 30 (issue 54 item 7: '`pmu control --rate 30`
    against a 60 fps plant accepted'; the reverse, with the default): each refused naming
    the rate, or run at the stream's rate with a word; never run silently mistuned."""
    bad, said = [], []
    port = free_port()
    srv = start(
        [
            "pmu",
            "serve",
            "kundur",
            "--fault",
            3,
            "--far-bus",
            101,
            "--tf",
            2,
            "--rate",
            30,
            "--speed",
            0,
            "--port",
            port,
            "--wait",
            3,
            "--timeout",
            10,
        ]
    )
    if wait_listen(port, 300, srv):
        rc, o, e, dt = run(
            [
                "estimate",
                "track",
                "kundur",
                "--source",
                f"tcp://127.0.0.1:{port}",
                "--frames",
                30,
                "--out",
                WD / "r30.csv",
            ],
            timeout=120,
        )
        if tb(e) or (rc == 0 and "30" not in e):
            bad.append(f"track: rc {rc}, {tail(e, 150)}")
        said.append(f"track rc {rc}: {tail(e, 110)}")
    finish(srv, 20)
    port = free_port()
    plant = start(
        [
            "pmu",
            "plant",
            "kundur",
            "--fault",
            3,
            "--far-bus",
            101,
            "--tf",
            2,
            "--rate",
            30,
            "--esd-pct",
            5,
            "--speed",
            0,
            "--port",
            port,
            "--timeout",
            15,
        ]
    )
    if wait_listen(port, 300, plant):
        rc, o, e, dt = run(
            ["pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", 5, "--timeout", 15],
            timeout=120,
        )
        if tb(e) or (rc == 0 and "30" not in e + o):
            bad.append(f"control: rc {rc}, {tail(o + e, 150)}")
        said.append(f"control rc {rc}: {tail(e, 110)}")
    finish(plant, 30)
    return not bad, "; ".join(bad) or " / ".join(said)


BAD_PORTS = [
    ["pmu", "replay", "REC", "--port", "65536"],
    ["pmu", "replay", "REC", "--port", "-1"],
    ["pmu", "replay", "REC", "--port", "http"],
    ["pmu", "replay", "REC", "--port", "4712.0"],
    ["pmu", "record", "127.0.0.1:65536", "--frames", "5", "-o", "x.c37"],
    ["pmu", "record", "127.0.0.1:0", "--frames", "5", "-o", "x.c37"],
    ["pmu", "record", "127.0.0.1:", "--frames", "5", "-o", "x.c37"],
    ["pmu", "record", "127.0.0.1:+80", "--frames", "5", "-o", "x.c37"],
    ["pmu", "record", "127.0.0.1:٤٧١٢", "--frames", "5", "-o", "x.c37"],
    [
        "estimate",
        "track",
        "kundur",
        "--source",
        "tcp://127.0.0.1:0",
        "--frames",
        "5",
        "--out",
        "x.csv",
    ],
    [
        "estimate",
        "track",
        "kundur",
        "--source",
        "tcp://127.0.0.1:4712x",
        "--frames",
        "5",
        "--out",
        "x.csv",
    ],
    [
        "estimate",
        "track",
        "kundur",
        "--source",
        "tcp://127.0.0.1:99999",
        "--frames",
        "5",
        "--out",
        "x.csv",
    ],
    ["estimate", "track", "kundur", "--source", "tcp://[::1]", "--frames", "5", "--out", "x.csv"],
    ["pmu", "control", "kundur", "127.0.0.1:65536", "--esd-pct", "5"],
    ["pmu", "control", "kundur", "127.0.0.1:0", "--esd-pct", "5"],
]


@probe("AA-N1")
def odd_ports():
    """Ports 65536, -1, text, 4712.0, 0 (no server's), empty, +80, Arabic-Indic digits, a
    missing port: each refused at once, exit 2, one error line, no traceback, nothing written."""
    cfg, d = recording()
    (WD / "rec.c37").write_bytes(blob(cfg, d))
    bad = []
    for c in BAD_PORTS:
        c = [str(WD / "rec.c37") if x == "REC" else x for x in c]
        for f in ("x.c37", "x.csv"):
            (WD / f).unlink(missing_ok=True)
        rc, o, e, dt = run(c, timeout=60)
        if rc != 2 or tb(e) or dt > 40 or (WD / "x.c37").exists() or (WD / "x.csv").exists():
            bad.append(f"{' '.join(c[1:4])[:48]}: rc {rc} {dt:.0f}s {tail(e, 90)}")
    return not bad, "; ".join(bad) or f"{len(BAD_PORTS)} refused"


@probe("AA-N4")
def each_pmu_ports_past_65535():
    """`pmu serve kundur --each-pmu --port 65533`: 4 PMUs need 65533-65536; refused at once
    naming the ports (issue 54: '--each-pmu --port 65534 (OverflowError)'), and --port
    65532 (the last that fits) listens on 65532-65535 or says which is taken."""
    rc, o, e, dt = run(
        [
            "pmu",
            "serve",
            "kundur",
            "--fault",
            3,
            "--far-bus",
            101,
            "--tf",
            2,
            "--each-pmu",
            "--port",
            65533,
            "--wait",
            1,
            "--timeout",
            2,
        ],
        timeout=120,
    )
    if rc != 2 or tb(e) or "serving" in e:
        return False, f"--port 65533: rc {rc}: {tail(e, 200)}"
    return True, f"rc 2: {tail(e, 160)}"


def listen_news(host, extra=(), secs=4):
    """Start `pmu replay` of the recording on host (port 0) and return (alive, stderr) after secs."""
    cfg, d = recording()
    (WD / "rec.c37").write_bytes(blob(cfg, d))
    p = start(
        [
            "pmu",
            "replay",
            WD / "rec.c37",
            "--host",
            host,
            "--port",
            0,
            "--wait",
            2,
            "--timeout",
            2,
            *extra,
        ]
    )
    time.sleep(secs)
    alive = p.poll() is None
    if alive:
        os.killpg(p.pid, signal.SIGTERM)
    rc, o, e = finish(p, 20)
    return alive, rc, e


@probe("AA-N2")
def wildcard_host_spellings():
    """--host spelled as every interface in other ways than 0.0.0.0 / :: ('0', '0.0',
    '000.000.000.000', '::0', '0:0:0:0:0:0:0:0', '[::]', '::ffff:0.0.0.0'): each listens
    with the warning that any host may connect, or is refused; never bound to every
    interface without a word (issue 54: 'bind to loopback unless told otherwise with a
    warning')."""
    bad = []
    for h in ("0", "0.0", "000.000.000.000", "::0", "0:0:0:0:0:0:0:0", "[::]", "::ffff:0.0.0.0"):
        alive, rc, e = listen_news(h)
        listening = "serving" in e
        warned = "any host" in e or "warning" in e.lower()
        if tb(e):
            bad.append(f"{h}: traceback {tail(e, 100)}")
        elif listening and not warned:
            bad.append(f"{h}: listening without a warning ({tail(e, 120)})")
        elif not listening and rc != 2:
            bad.append(f"{h}: rc {rc} {tail(e, 100)}")
    return not bad, "; ".join(bad) or "each warned or refused"


@probe("AA-N3")
def odd_allow_spellings():
    """--allow spelled oddly: a trailing comma, a blank item, leading zeros (127.000.000.001),
    the short form 127.1, a bracketed [::1], a CIDR 127.0.0.0/8, a zone ::1%lo, a name
    LOCALHOST, a port 127.0.0.1:4712, upper-case ::FFFF:7F00:1: each refused before the
    server listens (exit 2, one line), or accepted meaning that peer exactly (then a
    client from 127.0.0.1 is admitted: `estimate track --frames 5` exits 0)."""
    bad = []
    for a in (
        "127.0.0.1,",
        " ,127.0.0.1",
        "127.000.000.001",
        "127.1",
        "[::1]",
        "127.0.0.0/8",
        "::1%lo",
        "LOCALHOST",
        "127.0.0.1:4712",
        "::FFFF:7F00:1",
    ):
        cfg, d = recording()
        (WD / "rec.c37").write_bytes(blob(cfg, d))
        host = "::1" if a in ("[::1]", "::1%lo") else "127.0.0.1"
        p = start(
            [
                "pmu",
                "replay",
                WD / "rec.c37",
                "--host",
                host,
                "--port",
                0,
                "--allow",
                a,
                "--wait",
                2,
                "--timeout",
                5,
                "--speed",
                0,
            ]
        )
        port = None
        t = time.time()
        while time.time() - t < 20 and p.poll() is None and port is None:
            time.sleep(0.3)
            r = subprocess.run(["ss", "-ltnp"], capture_output=True, text=True).stdout
            for ln in r.splitlines():
                if f"pid={p.pid}," in ln:
                    port = int(ln.split()[3].rsplit(":", 1)[1])
        if port is None:
            rc, o, e = finish(p, 20)
            if rc != 2 or tb(e) or len(e.strip().splitlines()) > 2:
                bad.append(f"--allow {a!r}: rc {rc}: {tail(e, 100)}")
            continue
        src = f"tcp://[::1]:{port}" if host == "::1" else f"tcp://127.0.0.1:{port}"
        rc2, o2, e2, dt = run(
            ["estimate", "track", "kundur", "--source", src, "--frames", 5, "--out", WD / "al.csv"],
            timeout=60,
        )
        os.killpg(p.pid, signal.SIGTERM)
        rc, o, e = finish(p, 20)
        if rc2 != 0:
            said = [ln for ln in e.splitlines() if "dropped" in ln or "warning" in ln]
            bad.append(
                f"--allow {a!r} accepted without a word (listening) but the loopback client not admitted: track rc {rc2}; server: {' | '.join(said)[:140]}"
            )
    return not bad, "; ".join(bad) or "each refused or meaning the peer"


# ---------------------------------------------------------------- plant with two controllers
@probe("AA-P1")
def two_controllers_at_once():
    """`pmu plant` and two `pmu control` started at the same moment (two operators, or a
    controller restarted twice by a supervisor): the plant completes with one of them
    (exit 0); the other ends non-zero with one line saying it was refused or not the
    controller; neither exits 0 as if it had controlled the run, neither hangs."""
    port = free_port()
    plant = start(
        [
            "pmu",
            "plant",
            "kundur",
            "--fault",
            3,
            "--far-bus",
            101,
            "--tf",
            3,
            "--esd-pct",
            5,
            "--speed",
            0,
            "--port",
            port,
            "--timeout",
            20,
        ]
    )
    if not wait_listen(port, 300, plant):
        rc, o, e = finish(plant, 5)
        return False, f"plant did not listen: rc {rc} {tail(e)}"
    ctl = [
        start(["pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", 5, "--timeout", 20])
        for _ in range(2)
    ]
    res = [finish(c, 180) for c in ctl]
    prc, po, pe = finish(plant, 120)
    bad = []
    if prc != 0:
        bad.append(f"plant rc {prc}: {tail(pe, 150)}")
    rcs = [r[0] for r in res]
    for k, (rc, o, e) in enumerate(res):
        if tb(e):
            bad.append(f"controller {k}: traceback {tail(e, 120)}")
        if rc == "timeout":
            bad.append(f"controller {k}: hang")
    if rcs.count(0) != 1:
        bad.append(
            f"controllers' exit statuses {rcs}: {' || '.join(tail(r[1] + r[2], 120) for r in res)}"
        )
    loser = [r for r in res if r[0] != 0]
    return (
        not bad,
        "; ".join(bad)
        or f"one controller ran; the other rc {loser[0][0] if loser else '?'}: {tail(loser[0][2] if loser else '', 150)}",
    )


# ---------------------------------------------------------------- records files
SWEEP = ["sweep-cct", "kundur", "--faults", "DEFAULT", "--workers", 1, "--tol-ms", 5]
FIRST = {}


def first_sweep():
    if "lines" not in FIRST:
        out = WD / "first.jsonl"
        rc, o, e, dt = run([*SWEEP, "--out", out], timeout=900)
        if rc != 0:
            raise RuntimeError(f"first sweep exit {rc}: {tail(e)}")
        FIRST["lines"] = lines_of(out)
        FIRST["dt"] = dt
    return FIRST["lines"]


def resume_with(name, text, newline=""):
    out = WD / name
    out.write_bytes(text.encode())
    rc, o, e, dt = run([*SWEEP, "--out", out], timeout=900)
    raw = out.read_bytes().decode(errors="replace")
    recs, broken = [], []
    for ln in raw.replace("\r\n", "\n").split("\n"):
        if not ln.strip():
            continue
        try:
            recs.append(json.loads(ln.lstrip("\ufeff")))
        except ValueError:
            broken.append(ln[:60])
    keys = [r.get("key") for r in recs if isinstance(r, dict)]
    return rc, o, e, dt, keys, broken


@probe("AA-R1")
def records_last_line_without_newline():
    """A finished sweep's records file whose last line is whole but lacks its newline (an
    editor that strips it, `head -c`): the resume runs nothing again (exit 0, both keys
    once) and writes no record onto the end of that line."""
    lines = first_sweep()
    keys0 = sorted(json.loads(x)["key"] for x in lines)
    rc, o, e, dt, keys, broken = resume_with("nonl.jsonl", "\n".join(lines))
    bad = []
    if tb(e) or rc != 0:
        bad.append(f"rc {rc}: {tail(e, 150)}")
    if broken:
        bad.append(f"lines not JSON after the resume: {broken}")
    if sorted(keys) != keys0:
        bad.append(f"keys after the resume {keys} (before {keys0})")
    return not bad, "; ".join(bad) or f"nothing rerun ({dt:.0f} s): {tail(e, 120)}"


@probe("AA-R2")
def records_crlf():
    """The same records file with CRLF line ends (copied through a Windows editor or
    `unix2dos`): the resume runs nothing again, or refuses naming the file; never reruns
    the finished jobs and appends them a second time."""
    lines = first_sweep()
    keys0 = sorted(json.loads(x)["key"] for x in lines)
    rc, o, e, dt, keys, broken = resume_with("crlf.jsonl", "\r\n".join(lines) + "\r\n")
    bad = []
    if tb(e):
        bad.append(f"traceback: {tail(e, 150)}")
    if rc == 0 and sorted(keys) != keys0:
        bad.append(
            f"rc 0 and keys after the resume {keys} (before {keys0}): finished jobs repeated"
        )
    if rc not in (0, 2):
        bad.append(f"rc {rc}: {tail(e, 150)}")
    return not bad, "; ".join(bad) or f"rc {rc} ({dt:.0f} s): {tail(e, 120)}"


@probe("AA-R3")
def records_bom():
    """The same records file with a UTF-8 byte-order mark before its first line (saved by
    Notepad): the first job is not run again silently (resume exit 0 with both keys once,
    or a refusal naming the file)."""
    lines = first_sweep()
    keys0 = sorted(json.loads(x)["key"] for x in lines)
    rc, o, e, dt, keys, broken = resume_with("bom.jsonl", "\ufeff" + "\n".join(lines) + "\n")
    bad = []
    if tb(e):
        bad.append(f"traceback: {tail(e, 150)}")
    if rc == 0 and sorted(keys) != keys0:
        bad.append(
            f"rc 0 and keys after the resume {keys} (before {keys0}): a finished job repeated"
        )
    if rc not in (0, 2):
        bad.append(f"rc {rc}: {tail(e, 150)}")
    return not bad, "; ".join(bad) or f"rc {rc} ({dt:.0f} s): {tail(e, 120)}"


# ---------------------------------------------------------------- kernel cache location
@probe("AA-C1")
def cache_dir_odd_values():
    """NUMBA_CACHE_DIR empty (`compile --check` only: numba's unset, the package's
    __pycache__), below a regular file (FILE/sub), and a relative path: `compile --check`
    and `simulate` (30 s) each either run (loading or compiling, with a word
    where the cache is not usable) or refuse with one error line; no traceback."""
    f = WD / "afile"
    f.write_text("x")
    bad, said = [], []
    for v in ("", f"{f}/sub", "nc_relative"):
        env = dict(ENV, NUMBA_CACHE_DIR=v)
        rc, o, e, dt = run(["compile", "--check"], timeout=120, env=env)
        if tb(e) or rc not in (0, 1, 2):
            bad.append(f"{v!r} compile --check: rc {rc} {tail(e, 120)}")
        if not v:  # '' is numba's unset: the package's __pycache__, not compiled into here
            said.append(f"'': compile --check rc {rc}")
            continue
        p = start(["simulate", "kundur", "--fault", 3, "--far-bus", 101, "--tf", 1.5], env=env)
        try:
            o2, e2 = p.communicate(timeout=30)
            rc2 = p.returncode
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            o2, e2 = p.communicate()
            rc2 = "compiling"
        if tb(e2) or rc2 not in (0, 2, "compiling"):
            bad.append(f"{v!r} simulate: rc {rc2} {tail(e2, 120)}")
        said.append(f"{v!r}: rc {rc2} {tail(e2, 60)}")
    return not bad, "; ".join(bad) or " / ".join(said)


@probe("AA-C3")
def cache_world_writable_entries_not_unpickled():
    """A warm cache copy (this user's, directories 0700) whose every kernel index (*.nbi)
    is a pickle that runs `touch MARK`, the files owned by this user but mode 0666 (writable
    by anyone: W-C3 tried files of another owner): never unpickled; `simulate` warns and
    compiles (40 s allowed; the marker checked after it)."""
    import pickle

    src = Path(os.environ.get("NUMBA_CACHE_DIR", ""))
    if not src.is_dir():
        return True, "no NUMBA_CACHE_DIR to copy: not tried"
    d = WD / "nc_ww"
    shutil.copytree(src, d, symlinks=True)
    mark = WD / "PWNED_AA"

    class P:
        def __reduce__(self):
            return (os.system, (f"touch {mark}",))

    payload = pickle.dumps(P())
    n = 0
    for f in d.rglob("*.nbi"):
        f.write_bytes(payload)
        os.chmod(f, 0o666)
        n += 1
    env = dict(ENV, NUMBA_CACHE_DIR=str(d))
    p = start(["simulate", "kundur", "--fault", 3, "--far-bus", 101, "--tf", 1.5], env=env)
    try:
        o, e = p.communicate(timeout=40)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        o, e = p.communicate()
        rc = "compiling (stopped at 40 s)"
    if mark.exists():
        return False, f"a world-writable planted index was unpickled (marker made); simulate {rc}"
    if tb(e):
        return False, f"traceback: {tail(e, 200)}"
    return True, f"{n} planted indexes not unpickled; simulate {rc}: {tail(e, 120)}"


@probe("AA-C2")
def compile_killed_then_check_leaves_nothing():
    """`stabctl compile` on an empty cache SIGKILLed (the process only, as the OOM killer
    does) 20 s in: no process of it left after 10 s (its child compiling the integrator
    outlived a SIGKILLed parent, issue 54 item 4), and `compile --check` after it reports
    (exit 1, no traceback) rather than taking half-written files for kernels."""
    nc = WD / "nc_cold"
    env = dict(ENV, NUMBA_CACHE_DIR=str(nc))
    p = start(["compile", "kundur"], env=env)
    time.sleep(20)
    os.kill(p.pid, signal.SIGKILL)
    p.wait(10)
    time.sleep(10)
    left = group_alive(p.pid)
    for ln in left:
        try:
            os.kill(int(ln.split()[0]), signal.SIGKILL)
        except OSError:
            pass
    rc, o, e, dt = run(["compile", "--check"], timeout=120, env=env)
    bad = []
    if left:
        bad.append(
            f"{len(left)} process(es) of the killed compile still running 10 s later: {left[0][:120]}"
        )
    if tb(e) or rc not in (0, 1):
        bad.append(f"compile --check rc {rc}: {tail(e, 150)}")
    return not bad, "; ".join(bad) or f"nothing left; compile --check rc {rc}: {tail(o + e, 120)}"


# ---------------------------------------------------------------- Dask: a worker leaving in order
def dask_proc(args, logname):
    log = open(WD / logname, "w")
    return subprocess.Popen(
        ["dask", *args],
        stdout=log,
        stderr=subprocess.STDOUT,
        cwd=WD,
        env=ENV,
        start_new_session=True,
        stdin=subprocess.DEVNULL,
    )


def stop_group(p, sig=signal.SIGKILL):
    try:
        os.killpg(p.pid, sig)
    except OSError:
        pass
    try:
        p.wait(20)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)


@probe("AA-D1")
def dask_worker_sigterm_then_new_worker():
    """`sweep-cct kundur --esd-pct none,5` (4 jobs) on a separately started `dask scheduler`
    with one `dask worker --nthreads 1`; the worker stopped in order (SIGTERM, as a batch
    system or `systemctl stop` does) after the first record, a new worker started 5 s
    later: the sweep finishes on it, exit 0, every key once, none recorded 'failed' (issue
    54 item 1: jobs not run are never recorded as results)."""
    if not shutil.which("dask"):
        return True, "no dask CLI: not tried"
    port = free_port()
    sch = dask_proc(
        ["scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"], "sch.log"
    )
    workers = []
    try:
        if not wait_port(port, 60, sch):
            return False, "dask scheduler did not start"
        addr = f"tcp://127.0.0.1:{port}"
        workers.append(
            dask_proc(
                ["worker", addr, "--nthreads", "1", "--nworkers", "1", "--no-dashboard"], "w1.log"
            )
        )
        out = WD / "d1.jsonl"
        sw = start(
            [
                "sweep-cct",
                "kundur",
                "--faults",
                "DEFAULT",
                "--esd-pct",
                "none,5",
                "--tol-ms",
                5,
                "--scheduler",
                addr,
                "--out",
                out,
            ]
        )
        t = time.time()
        while time.time() - t < 600 and sw.poll() is None:
            if out.exists() and lines_of(out):
                break
            time.sleep(0.5)
        n_first = len(lines_of(out)) if out.exists() else 0
        stop_group(workers[0], signal.SIGTERM)
        time.sleep(5)
        workers.append(
            dask_proc(
                ["worker", addr, "--nthreads", "1", "--nworkers", "1", "--no-dashboard"], "w2.log"
            )
        )
        rc, o, e = finish(sw, 900)
        recs = [r for r in records(out) if r]
        keys = [r.get("key") for r in recs]
        failed = [r.get("key") for r in recs if r.get("status") != "ok"]
        bad = []
        if tb(e):
            bad.append("traceback: " + tail(e, 150))
        if rc != 0:
            bad.append(f"rc {rc}: {tail(o + e, 200)}")
        if len(keys) != 4 or len(set(keys)) != 4:
            bad.append(f"{len(keys)} records, keys {sorted(map(str, keys))}")
        if failed:
            bad.append(f"recorded as failed: {failed}")
        return not bad, "; ".join(
            bad
        ) or f"{n_first} record(s) before the SIGTERM, then 4 keys once, rc 0: {tail(e, 100)}"
    finally:
        for w in workers:
            stop_group(w)
        stop_group(sch)


def main():
    KIT.main(summary="\n{n} probes, {ok} ok, {short} SHORT; {secs:.0f} s", keep_any=True)


if __name__ == "__main__":
    main()
