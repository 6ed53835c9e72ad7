#!/usr/bin/env python
"""Round 58 (AZ): variants of issue 54's findings on the C37.118.2 servers, the closed
ESD loop over TCP (`pmu plant` / `pmu control`) and their peers, that the earlier probe
scripts (reliability_probes*.py) do not try.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_53.py [AZ01,...]

Found (round 58, AZ; SHORT on main at 0eea4fee; all fixed since but AZ10, a limit of TCP
kept and documented in docs/estimation.md section 6):
  AZ01  pmu plant: a frame whose CRC fails counts as a valid command in the handshake
        (c37_loop.PlantLink._handshake sets `me.commanded` for any frame): a peer that
        asked for CFG-2 in a valid frame is evicted before seven strangers of garbage.
  AZ03-06  int() of more than 4300 digits escapes as ValueError with a traceback:
        --idcode (cli/pmu_options.stream_idcodes), a case file's machine_ids key
        (io/pst._machine_ids_field), a DYR record's bus field (io/dyr._integer).
  AZ07  pmu serve names a peer that sent 160 000 'cfg2' commands and read no answer
        "silent" (c37_tcp.StreamServer._session's TimeoutError from _answer's sendall).
  AZ08  pmu serve never ends after a whole session while a stranger asks for the header
        every 2 s (StreamServer.done: any commanded peer is "at work").
  AZ10  a peer that says 'start', reads nothing and half-closes (shutdown SHUT_WR) is
        counted whole and ends pmu serve with exit 0 (StreamServer._taken takes any FIN
        as the evidence of reading).
  AZ15-16  estimate track / pmu record --idcode 1 take a stream of IDCODE 7 without a
        word (c37_tcp.receive does not compare the CFG-2's IDCODE with the one asked
        for; sources.merge reads the expected IDCODE from the CFG-2 itself).
  AZ17  estimate track of 4 streams, one server closing before its CFG-2: the other 3
        streams are received whole (their servers end) and dropped, nothing kept
        (sources.read_frames raises the first error over the streams received).
  AZ20-21  Ctrl-C while `place` / `screen` spawn their workers: "Fatal Python error:
        init_import_site" and a traceback from the workers (parallel.process_pool: the
        spawned interpreter gets SIGINT before die_with_parent ignores it); screen 5-9 of
        25 moments, place intermittent (3 of 25 alone, then 0 of 25 and 0 of 40).
DOUBTFUL: AZ09 (plant --latency-ms 200 with control at 50: no word; the latency was
not on the wire: the plant's end-of-run header now says it, and pmu control warns).  ok: AZ02, AZ11-14, AZ18, AZ19 (controls and resume checks).

Each probe runs `stabctl` commands (fresh processes) against peers written here (raw
sockets speaking C37.118.2-2011 frames) and asserts what a source says: the issue's text
(item 3: "a stranger connecting first drives every ESD", "a silent or half-frame peer
blocks the server for everyone", "a start command with a bad CRC is obeyed"; item 7:
"`pmu control --rate 30` against a 60 fps plant accepted"), the servers' own docstrings
and --help (stabctl/estimation/c37_tcp.py, c37_loop.py, cli/pmu.py), and the developers'
guide's standard (a clear error naming what and where, non-zero exit, no traceback,
nothing changed or defaulted silently).
"""

# ruff: noqa
import json
import os
import signal
import socket
import struct
import threading
import time
from pathlib import Path

from _probe_kit import (
    FakeServer,
    Kit,
    crc_ccitt,
    fix_crc,
    free_port,
    read_frame,
    stamp_of,
    tail,
    tb,
    wait_listen,
)

KIT = Kit("probes_az56.", line="{pid:<6} {state:<5} {why}", timed=True)
CLONE, ENV, WD = KIT.clone, KIT.env, KIT.wd
run, rec, probe, start, finish = KIT.run, KIT.rec, KIT.probe, KIT.start, KIT.finish

FAULT = ["--fault", 3, "--far-bus", 101]


def cmdframe(word, idcode=1, extra=b"", soc=None, frac=0, bad_crc=False, size=None):
    """A C37.118.2-2011 command frame (Table 15): SYNC 0xAA41, FRAMESIZE, IDCODE, SOC,
    FRACSEC, CMD, extended data, CHK (bad_crc: its CHK inverted)."""
    n = 18 + len(extra) if size is None else size
    body = (
        struct.pack(
            ">HHHIIH",
            0xAA41,
            n,
            idcode,
            int(time.time()) if soc is None else soc,
            frac,
            word,
        )
        + extra
    )
    c = crc_ccitt(body) ^ (0xFFFF if bad_crc else 0)
    return body + struct.pack(">H", c)


def connect(port, timeout=30, host="127.0.0.1"):
    s = socket.create_connection((host, port), timeout=timeout)
    return s


def closed_by_peer(s, wait=1.5):
    """True if the server closed (or reset) s: recv gives b'' or an error within wait s."""
    s.settimeout(wait)
    try:
        while True:
            b = s.recv(65536)
            if not b:
                return True
    except TimeoutError:
        return False
    except OSError:
        return True


def plant(port, *extra, tf=3, timeout=30):
    return start(
        [
            *"pmu plant kundur".split(),
            *FAULT,
            *"--tf".split(),
            tf,
            *"--esd-pct 5 --speed 0 --port".split(),
            port,
            *"--timeout".split(),
            timeout,
            *extra,
        ]
    )


def serve(port, *extra, tf=3, timeout=30, wait=10, speed=0):
    return start(
        [
            *"pmu serve kundur".split(),
            *FAULT,
            *"--tf".split(),
            tf,
            *"--speed".split(),
            speed,
            *"--port".split(),
            port,
            *"--timeout".split(),
            timeout,
            *"--wait".split(),
            wait,
            *extra,
        ]
    )


def close_all(socks):
    for s in socks:
        try:
            s.close()
        except OSError:
            pass


# ------------------------------------------------------------------ the plant's handshake
def _crowd(port):
    """Peer A asks for the CFG-2 in a valid frame, seven strangers send one frame whose CRC
    fails, a ninth peer connects: (A dropped?, each stranger dropped?), or why not run."""
    socks = []
    try:
        a = connect(port)
        socks.append(a)
        a.sendall(cmdframe(5))
        a.settimeout(10)
        if read_frame(a) is None:
            return "A got no CFG-2"
        for _ in range(7):
            s = connect(port)
            socks.append(s)
            time.sleep(0.2)
            s.sendall(cmdframe(2, bad_crc=True))
            time.sleep(0.2)
        time.sleep(0.5)
        socks.append(connect(port))  # the ninth
        time.sleep(1.0)
        return closed_by_peer(a), [closed_by_peer(s, 0.3) for s in socks[1:8]]
    finally:
        close_all(socks)


@probe("AZ01")
def plant_garbage_frames_outrank_a_commanded_peer():
    """`pmu plant`: peer A asks for CFG-2 in a valid command frame (a controller between
    its 'cfg2' and its 'start'); seven strangers then each send one frame whose CRC fails
    and stay; a ninth peer connects.  c37_loop.PlantLink's docstring: "with every place
    taken, a new peer takes that of the peer connected longest without a valid command,
    else of the one connected longest": the place is a stranger's (no valid command),
    and A keeps its connection."""
    port = free_port()
    p = plant(port, timeout=25)
    if not wait_listen(port, 300, p):
        finish(p, 5)
        return False, "plant did not listen"
    crowd = _crowd(port)
    if isinstance(crowd, str):
        return False, crowd
    a_gone, gone = crowd
    rc, o, e = finish(p, 60)
    bad = []
    if a_gone:
        bad.append(
            f"A (valid 'cfg2', first) was dropped for the ninth peer while {7 - sum(gone)} "
            f"of 7 strangers whose only frame failed its CRC kept their place"
        )
    if tb(e):
        bad.append("traceback: " + tail(e))
    return not bad, "; ".join(
        bad
    ) or f"a stranger gave its place ({sum(gone)} dropped); plant exit {rc}"


@probe("AZ02")
def serve_garbage_frames_do_not_outrank_a_commanded_peer():
    """The same against `pmu serve` (StreamServer._admit: the peer "that has waited
    longest without sending a valid command" gives its place): A, which asked for the
    CFG-2 in a valid frame, keeps its connection; a stranger gives its place."""
    port = free_port()
    p = serve(port, timeout=25, wait=3)
    if not wait_listen(port, 300, p):
        finish(p, 5)
        return False, "serve did not listen"
    crowd = _crowd(port)
    if isinstance(crowd, str):
        return False, crowd
    a_gone, gone = crowd
    with_pdc_waiting = p.poll() is None  # no PDC came: it waits for one (its --help)
    if with_pdc_waiting:
        os.killpg(p.pid, signal.SIGINT)
    rc, o, e = finish(p, 30)
    bad = []
    if a_gone:
        bad.append(f"A (valid 'cfg2') dropped for the ninth; {sum(gone)} stranger(s) dropped")
    if tb(e):
        bad.append("traceback: " + tail(e))
    return not bad, "; ".join(
        bad
    ) or f"a stranger gave its place ({sum(gone)} dropped); serve exit {rc}"


# ------------------------------------------------------------------ integers past int()'s limit
#: more digits than Python's int() converts (sys.get_int_max_str_digits(), 4300): the class
#: jsontext.parse_json and c37_tcp.port_number close ("Python refuses to convert a string
#: of more than 4300 digits"), tried where text reaches int() elsewhere
BIG = "9" * 5000


def refused_cleanly(rc, o, e, words=()):
    """(ok, why) of a run that must refuse its input: exit 2, one `error:` line naming
    what, no traceback."""
    bad = []
    if tb(o + e):
        last = [ln for ln in e.splitlines() if ln.strip()][-1:] or ["?"]
        bad.append(f"traceback, exit {rc}: {last[0][:150]}")
    elif rc != 2:
        bad.append(f"exit {rc}, not 2: {tail(e, 150)}")
    elif not any(ln.startswith("error:") for ln in e.splitlines()):
        bad.append(f"no error: line: {tail(e, 150)}")
    elif words and not any(w in e for w in words):
        bad.append(f"error names none of {words}: {tail(e, 150)}")
    return not bad, "; ".join(bad) or f"refused: {tail(e, 140)}"


@probe("AZ03")
def record_idcode_of_5000_digits():
    """`pmu record HOST:PORT --frames 1 -o x.c37 --idcode <5000 digits>`: refused as an
    IDCODE out of 1-65534 naming --idcode (pmu_options.stream_idcodes: "An item that is
    not a number in 1-65534 ... InputError"), no traceback, no file."""
    rc, o, e, _ = run(
        ["pmu", "record", "127.0.0.1:9", "--frames", 1, "-o", "x.c37", "--idcode", BIG], 120
    )
    ok, why = refused_cleanly(rc, o, e, ("--idcode",))
    if (WD / "x.c37").exists():
        ok, why = False, why + "; x.c37 written"
    return ok, why


@probe("AZ04")
def track_idcode_list_of_5000_digits():
    """`estimate track kundur --source tcp://127.0.0.1:9 --frames 5 --idcode 1,<5000
    digits>`: refused naming --idcode, no traceback."""
    rc, o, e, _ = run(
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            "tcp://127.0.0.1:9",
            "--frames",
            5,
            "--out",
            "t.csv",
            "--idcode",
            "1," + BIG,
        ],
        300,
    )
    return refused_cleanly(rc, o, e, ("--idcode",))


def five_bus_json():
    """tests/data/psse's five-bus RAW + DYR imported once: its case file's path."""
    out = WD / "five.json"
    if not out.exists():
        d = Path(CLONE) / "tests/data/psse"
        rc, o, e, _ = run(
            ["import-psse", d / "five_bus_v33.raw", d / "five_bus.dyr", "-o", out], 300
        )
        if rc != 0:
            raise RuntimeError(f"import-psse exit {rc}: {tail(e)}")
    return out


@probe("AZ05")
def case_machine_ids_key_of_5000_digits():
    """A case file whose "machine_ids" names machine <5000 digits> (pst._machine_ids_field:
    "{key!r} is no machine number", a CaseError): `simulate` refuses it naming the file
    and machine_ids, no traceback (jsontext: "an integer of more digits than Python
    converts ... is refused naming the file instead of escaping as Python's ValueError")."""
    d = json.loads(five_bus_json().read_text())
    d["machine_ids"][BIG] = "X"
    (WD / "ids.json").write_text(json.dumps(d))
    rc, o, e, _ = run(["simulate", "ids.json", "--tf", 1], 300)
    return refused_cleanly(rc, o, e, ("machine_ids", "ids.json"))


@probe("AZ06")
def dyr_bus_of_5000_digits():
    """A DYR record whose bus field is <5000 digits> (dyr._integer): `import-psse RAW DYR`
    refuses it naming the DYR file and line, no traceback, no case file written."""
    d = Path(CLONE) / "tests/data/psse"
    text = (d / "five_bus.dyr").read_text()
    first = text.splitlines()[0]
    bus = first.split()[0]
    (WD / "big.dyr").write_text(text.replace(first, first.replace(bus, BIG, 1), 1))
    rc, o, e, _ = run(["import-psse", d / "five_bus_v33.raw", "big.dyr", "-o", "big.json"], 300)
    ok, why = refused_cleanly(rc, o, e, ("big.dyr",))
    if (WD / "big.json").exists():
        ok, why = False, why + "; big.json written"
    return ok, why


# ------------------------------------------------------------------ the stream server's peers
@probe("AZ07")
def serve_unread_cfg2_answers_named_silent():
    """`pmu serve --timeout 5`: a peer sends thousands of valid 'cfg2' commands and reads
    none of the answers (its receive buffer small), so the server's sendall of a CFG-2
    times out.  The peer is dropped (bounded), and the reason must say what it did
    (C37.118.2 commands, answers not taken), not call it "silent" (c37_tcp.Guard: a peer
    "expected to send" that sends nothing; the developers' guide: a message naming what
    happened)."""
    port = free_port()
    p = serve(port, timeout=5, wait=3)
    if not wait_listen(port, 300, p):
        finish(p, 5)
        return False, "serve did not listen"
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect(("127.0.0.1", port))
    s.settimeout(1)
    sent, t0 = 0, time.time()
    try:
        while time.time() - t0 < 4:
            s.sendall(cmdframe(5) * 100)
            sent += 100
    except OSError:
        pass
    time.sleep(8)
    s.close()
    os.killpg(p.pid, signal.SIGINT)
    rc, o, e = finish(p, 30)
    drops = [ln for ln in e.splitlines() if ln.startswith("dropped")]
    bad = []
    if not drops:
        bad.append(f"the peer was not dropped: {tail(e, 200)}")
    elif any("silent" in ln for ln in drops):
        bad.append(f"a peer that sent {sent} 'cfg2' commands is named {drops[0]!r}")
    if tb(e):
        bad.append("traceback: " + tail(e))
    return not bad, "; ".join(bad) or f"{sent} commands sent; {drops[0]}"


@probe("AZ08")
def serve_ends_after_whole_stream_despite_header_poller():
    """`pmu serve --timeout 5`: a stranger asks for the header every 2 s (valid commands,
    never 'start'); `pmu record --frames 181` (the whole 3 s stream) is sent it whole.
    `pmu serve --help`: "Exits once a PDC has been sent the stream whole and none is
    streaming (exit status 0 ...)": the server ends within a few seconds of the record,
    the poller not streaming."""
    port = free_port()
    p = serve(port, timeout=5, wait=3)
    if not wait_listen(port, 300, p):
        finish(p, 5)
        return False, "serve did not listen"
    stop = threading.Event()
    polls = [0]

    def poller():
        try:
            s = connect(port)
            while not stop.is_set():
                s.sendall(cmdframe(3))
                polls[0] += 1
                s.settimeout(2)
                try:
                    if read_frame(s) is None:
                        return
                except OSError:
                    return
                stop.wait(2)
            s.close()
        except OSError:
            pass

    th = threading.Thread(target=poller, daemon=True)
    th.start()
    time.sleep(1)
    rc, o, e, _ = run(
        ["pmu", "record", f"127.0.0.1:{port}", "--frames", 181, "-o", "whole.c37"], 120
    )
    t_rec = time.time()
    try:
        p.wait(30)
        ended = time.time() - t_rec
    except Exception:
        ended = None
    stop.set()
    rcs, os_, es = finish(p, 30)
    bad = []
    if rc != 0:
        bad.append(f"record exit {rc}: {tail(e, 150)}")
    if ended is None:
        bad.append(
            f"serve still running 30 s after the whole stream was recorded, held by a peer "
            f"asking for the header ({polls[0]} asks); it ended with exit {rcs} once that peer left"
        )
    if tb(es):
        bad.append("traceback: " + tail(es))
    return not bad, "; ".join(bad) or f"serve ended {ended:.1f} s after the record, exit {rcs}"


# ------------------------------------------------------------------ the loop's two ends agree
@probe("AZ09")
def loop_latency_mismatch():
    """`pmu plant --latency-ms 200` (the modes take effect 200 ms after each time stamp)
    with `pmu control` at its default --latency-ms 50 (its estimator forecasts the speeds
    50 ms ahead): issue 54 item 7 names "`pmu control --rate 30` against a 60 fps plant
    accepted" a silently wrong result; the latency is the other setting both ends must
    share.  The loop must refuse the mismatch or say it (either end), not run silently."""
    port = free_port()
    p = plant(port, "--latency-ms", 200, timeout=60)
    if not wait_listen(port, 300, p):
        finish(p, 5)
        return False, "plant did not listen"
    rc, o, e, _ = run(["pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", 5], 300)
    rcp, op, ep = finish(p, 120)
    said = [
        ln
        for ln in (o + e + op + ep).splitlines()
        if "latency" in ln.lower() and ("50" in ln and "200" in ln)
    ]
    if tb(e + ep):
        return False, "traceback: " + tail(e + ep)
    if rc == 0 and rcp == 0 and not said:
        return False, (
            "plant --latency-ms 200 and control --latency-ms 50 ran the loop, both exit 0, "
            f"no word of the mismatch (control: {tail(o, 100)})"
        )
    return True, f"control exit {rc}, plant exit {rcp}: {(said or [tail(e + ep, 120)])[0][:160]}"


@probe("AZ10")
def serve_half_close_unread_counts_whole():
    """`pmu serve` (--speed 1, real time, its default): a peer asks for CFG-2 and 'start'
    (valid frames), reads nothing, waits 5 s (the 3-s stream, 181 frames, all in its
    kernel's buffer by then) and
    half-closes (shutdown SHUT_WR: a FIN, its receive side still open and unread).
    StreamServer's docstring: "the session is whole only once the PDC closes its side in
    turn, in order (FIN) ... an orderly close after the last frame is the evidence that
    the PDC read the stream to its end"; issue 54 item 3: a peer that connects and closes
    must not end `pmu serve`.  A peer that read none of the frames must not be counted
    whole and end the server with exit 0 before the real PDC comes."""
    port = free_port()
    p = serve(port, timeout=10, wait=5, speed=1)
    if not wait_listen(port, 300, p):
        finish(p, 5)
        return False, "serve did not listen"
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
    s.connect(("127.0.0.1", port))
    s.sendall(cmdframe(5) + cmdframe(2))
    time.sleep(5)
    s.shutdown(socket.SHUT_WR)
    try:
        rc, o, e = p.wait(15), None, None
    except Exception:
        rc = None
    s.close()
    rcs, os_, es = finish(p, 10)
    whole = [ln for ln in es.splitlines() if "whole" in ln]
    if rcs == 0 and whole:
        return False, (
            f"a peer that read 0 bytes and half-closed ended the server: exit 0, "
            f"{whole[0][:120]!r}; stdout {tail(os_, 60)!r}"
        )
    if tb(es):
        return False, "traceback: " + tail(es)
    return True, f"not counted whole (serve exit {rcs}): {tail(es, 150)}"


@probe("AZ11")
def serve_unread_streamer_does_not_stall_a_pdc():
    """`pmu serve --speed 1 --tf 20` (1201 frames): a stranger says 'start' with a tiny
    receive buffer and reads nothing (the server's sendall to it blocks); `pmu record
    --frames 60` of the same server meanwhile gets its 60 frames in about 1 s of stream
    time (issue 54 item 3: "a silent or half-frame peer blocks the server for everyone")."""
    port = free_port()
    p = serve(port, tf=20, timeout=30, wait=3, speed=1)
    if not wait_listen(port, 300, p):
        finish(p, 5)
        return False, "serve did not listen"
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1024)
    s.connect(("127.0.0.1", port))
    s.sendall(cmdframe(5) + cmdframe(2))
    time.sleep(3)
    rc, o, e, dt = run(["pmu", "record", f"127.0.0.1:{port}", "--frames", 60, "-o", "r60.c37"], 60)
    s.close()
    os.killpg(p.pid, signal.SIGINT)
    rcs, os_, es = finish(p, 30)
    bad = []
    if rc != 0:
        bad.append(f"record exit {rc}: {tail(e, 150)}")
    elif dt > 15:
        bad.append(f"record took {dt:.0f} s for 60 frames (1 s of stream)")
    if tb(es):
        bad.append("traceback: " + tail(es))
    return not bad, "; ".join(
        bad
    ) or f"record of 60 frames in {dt:.1f} s beside the unread streamer"


@probe("AZ12")
def plant_unknown_command_then_controller():
    """`pmu plant`: a stranger sends a command frame with a valid CRC and an unknown
    command word (0x0007) and stays; the real `pmu control` then connects and runs the
    loop: both exit 0, the stranger never in the loop (issue 54 item 3)."""
    port = free_port()
    p = plant(port, timeout=60)
    if not wait_listen(port, 300, p):
        finish(p, 5)
        return False, "plant did not listen"
    s = connect(port)
    s.sendall(cmdframe(7))
    time.sleep(0.5)
    rc, o, e, _ = run(
        ["pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", 5, "--estimator", "raw"], 300
    )
    rcp, op, ep = finish(p, 120)
    s.close()
    bad = []
    if rc != 0 or rcp != 0:
        bad.append(f"control exit {rc}: {tail(e, 120)}; plant exit {rcp}: {tail(ep, 120)}")
    if tb(e + ep):
        bad.append("traceback")
    return not bad, "; ".join(bad) or f"loop ran: {tail(o, 110)}"


# ------------------------------------------------------------------ interrupts at seeded random moments
def _strip(obj):
    if isinstance(obj, dict):
        return {
            k: _strip(v)
            for k, v in obj.items()
            if k
            not in {
                "wall_time_s",
                "worker",
                "traceback",
                "solve_time_s",
                "solve_times_s",
                "solve_wall_s",
            }
        }
    if isinstance(obj, list):
        return [_strip(v) for v in obj]
    return obj


def _last_by_key(path):
    out, bad = {}, 0
    if not Path(path).exists():
        return out, bad
    for ln in Path(path).read_text().splitlines():
        if not ln.strip():
            continue
        try:
            r = json.loads(ln)
        except ValueError:
            bad += 1
            continue
        out[r.get("key")] = r
    return out, bad


def interrupted_resume(pid, args, out, seed, n_cuts=6, span=(0.3, 6.0), timeout=600):
    """Run `args` (writing records `out`) uninterrupted into ref_<out>; then again into
    `out`, cut n_cuts times at seeded random moments (SIGINT to the process group as a
    terminal's Ctrl-C, SIGTERM to the process, alternately), each cut followed by a
    resume; the last resume runs to its end.  The developers' guide: "Long work ... can
    be interrupted without losing finished results"; issue 54 item 1: jobs not run are
    never recorded.  ok when every cut ends 130/143 (or 0 if it had finished) without a
    traceback, no line of `out` is damaged or a 'failed' record, and the final records
    equal the reference's (run-dependent fields aside)."""
    import random

    rnd = random.Random(seed)
    ref = f"ref_{out}"
    for f in (ref, out):
        (WD / f).unlink(missing_ok=True)
    rc, o, e, dt = run([*args, "--out", ref], timeout)
    if rc not in (0,):
        return False, f"reference run exit {rc}: {tail(e)}"
    want, _ = _last_by_key(WD / ref)
    bad, cuts = [], []
    for k in range(n_cuts):
        at = rnd.uniform(*span)
        p = start([*args, "--out", out])
        time.sleep(at)
        sig = signal.SIGINT if k % 2 == 0 else signal.SIGTERM
        try:
            if sig == signal.SIGINT:
                os.killpg(p.pid, sig)
            else:
                os.kill(p.pid, sig)
        except ProcessLookupError:
            pass
        rcc, oc, ec = finish(p, 120)
        cuts.append(f"{at:.2f}s:{rcc}")
        if tb(oc + ec):
            bad.append(f"cut {k} at {at:.2f} s ({sig.name}): traceback: {tail(ec, 160)}")
        if rcc not in (0, 130, 143, -2, -15):
            bad.append(f"cut {k} at {at:.2f} s ({sig.name}): exit {rcc}: {tail(ec, 160)}")
        got, damaged = _last_by_key(WD / out)
        if damaged:
            bad.append(f"cut {k}: {damaged} damaged line(s) in {out}")
        failed = [key for key, r in got.items() if r.get("status") == "failed"]
        if failed:
            bad.append(f"cut {k} at {at:.2f} s ({sig.name}): recorded failed: {failed[:2]}")
        if bad:
            break
    if not bad:
        rc, o, e, _ = run([*args, "--out", out], timeout)
        if rc != 0:
            bad.append(f"final resume exit {rc}: {tail(e, 160)}")
        got, damaged = _last_by_key(WD / out)
        if set(got) != set(want):
            bad.append(
                f"keys differ: missing {sorted(set(want) - set(got))[:3]}, extra {sorted(set(got) - set(want))[:3]}"
            )
        else:
            diff = [key for key in want if _strip(want[key]) != _strip(got[key])]
            if diff:
                a, b = _strip(want[diff[0]]), _strip(got[diff[0]])
                fields = [f for f in set(a) | set(b) if a.get(f) != b.get(f)]
                bad.append(
                    f"{len(diff)} record(s) differ from the uninterrupted run, e.g. {diff[0]} in {fields}"
                )
    return not bad, "; ".join(bad) or f"{len(want)} records equal after cuts {', '.join(cuts)}"


@probe("AZ13")
def sweep_random_cuts_resume():
    """sweep-cct kundur DEFAULT x none,2,5,10,20 (10 jobs), 2 workers, cut 6 times at seeded
    random moments then resumed (interrupted_resume)."""
    return interrupted_resume(
        "AZ13",
        [*"sweep-cct kundur --faults DEFAULT --esd-pct none,2,5,10,20 --workers 2".split()],
        "sw.jsonl",
        seed=53,
        span=(0.5, 5.0),
    )


@probe("AZ14")
def screen_random_cuts_resume():
    """screen kundur --lines, 2 workers, cut 6 times at seeded random moments then resumed
    (interrupted_resume)."""
    return interrupted_resume(
        "AZ14",
        ["screen", "kundur", "--lines", "--workers", 2],
        "sc.jsonl",
        seed=54,
        span=(0.5, 6.0),
    )


# ------------------------------------------------------------------ the stream asked for
def with_idcode(fr, code):
    b = bytearray(fr)
    b[4:6] = struct.pack(">H", code)
    return fix_crc(bytes(b))


@probe("AZ15")
def track_answer_of_another_idcode():
    """A server (written here) answers `estimate track --idcode 1`'s commands with the
    stream IDCODE 7 (its CFG-2 and data frames, CRCs valid).  --idcode's help: "IDCODE of
    the C37.118.2 stream to receive, which the commands address"; C37.118.2-2011 Table 2:
    a command's IDCODE is its destination stream's; `pmu control` refuses a plant's CFG-2
    of another IDCODE (c37.check_config: "its CFG-2 IDCODE ..., not the ... expected").
    The track must refuse (or at least name) a stream other than the one asked for."""
    cfg, data = KIT.recording()
    srv = FakeServer(with_idcode(cfg, 7), [with_idcode(d, 7) for d in data])
    rc, o, e, _, out = KIT.track_tcp(srv, ["--frames", 180, "--idcode", 1, "--estimator", "raw"])
    if tb(o + e):
        return False, "traceback: " + tail(e)
    if rc == 0 and "IDCODE" not in (o + e):
        return (
            False,
            f"stream IDCODE 7 tracked as the stream IDCODE 1 asked for, exit 0, no word: {tail(o, 120)}",
        )
    return True, f"exit {rc}: {tail(o + e, 160)}"


@probe("AZ16")
def record_answer_of_another_idcode():
    """The same against `pmu record HOST:PORT --frames 180 --idcode 1` (its help: the
    stream "which the commands address"): refused, or the other IDCODE named."""
    cfg, data = KIT.recording()
    srv = FakeServer(with_idcode(cfg, 7), [with_idcode(d, 7) for d in data])
    rc, o, e, _ = run(
        ["pmu", "record", f"127.0.0.1:{srv.port}", "--frames", 180, "-o", "id7.c37"], 120
    )
    srv.close()
    if tb(o + e):
        return False, "traceback: " + tail(e)
    if rc == 0 and "IDCODE" not in (o + e):
        return False, f"stream IDCODE 7 recorded as IDCODE 1, exit 0, no word: {tail(o, 120)}"
    return True, f"exit {rc}: {tail(o + e, 160)}"


@probe("AZ17")
def track_many_streams_one_dead_loses_the_rest():
    """`pmu serve kundur --each-pmu` on P..P+3; `estimate track --source
    tcp://127.0.0.1:P-P+2,127.0.0.1:Q --until 3` where Q accepts and closes before its
    CFG-2.  The three live streams are received whole (their servers say so and end: a
    live stream cannot be fetched again), then the source is refused.  Issue 54's class
    "no data loss" and track's own interrupt (it "writes each stream's frames received
    beside OUT as a partial recording, STEM.received.c37"): the frames received must be
    kept (or the others not taken whole before the refusal), and the message must say
    what came; not 543 frames dropped without a word."""
    for _ in range(5):
        P = free_port()
        if all(_port_free(P + k) for k in range(1, 4)):
            break
    p = start(
        [
            *"pmu serve kundur".split(),
            *FAULT,
            *"--tf 3 --speed 1 --port".split(),
            P,
            *"--each-pmu --timeout 10 --wait 3".split(),
        ]
    )
    if not all(wait_listen(P + k, 300, p) for k in range(4)):
        finish(p, 5)
        return False, "serve --each-pmu did not listen"
    dead = socket.socket()
    dead.bind(("127.0.0.1", 0))
    dead.listen(1)
    Q = dead.getsockname()[1]

    def closer():
        try:
            c, _ = dead.accept()
            time.sleep(0.2)
            c.close()
        except OSError:
            pass

    threading.Thread(target=closer, daemon=True).start()
    rc, o, e, dt = run(
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            f"tcp://127.0.0.1:{P}-{P + 2},127.0.0.1:{Q}",
            "--until",
            3,
            "--out",
            "t4.csv",
            "--estimator",
            "raw",
        ],
        200,
    )
    dead.close()
    os.killpg(p.pid, signal.SIGINT)
    rcs, os_, es = finish(p, 30)
    whole = sum("whole" in ln for ln in es.splitlines())
    kept = sorted(f.name for f in WD.glob("t4*"))
    bad = []
    if tb(o + e):
        bad.append("traceback: " + tail(e))
    if rc == 0:
        bad.append(f"exit 0 with a PMU's stream missing: {tail(o, 120)}")
    elif whole and not kept and "received" not in e:
        bad.append(
            f"{whole} of the streams were received whole ({whole} x 181 frames; their servers "
            f"ended), then dropped: exit {rc}, nothing kept ({tail(e, 110)})"
        )
    return not bad, "; ".join(bad) or f"exit {rc}, kept {kept}: {tail(e, 120)}"


def _port_free(port):
    s = socket.socket()
    try:
        s.bind(("127.0.0.1", port))
        return True
    except OSError:
        return False
    finally:
        s.close()


@probe("AZ18")
def loop_over_ipv6_loopback():
    """`pmu plant --host ::1` and `pmu control kundur [::1]:PORT` (an IPv6 host in
    brackets, as the servers print it): the loop runs, both exit 0."""
    if not socket.has_ipv6:
        return True, "no IPv6 here (skipped)"
    port = free_port()
    p = plant(port, "--host", "::1", timeout=60)
    t0 = time.time()
    up = False
    while time.time() - t0 < 300 and p.poll() is None:
        r = os.popen("ss -ltn").read()
        if f"[::1]:{port} " in r:
            up = True
            break
        time.sleep(0.3)
    if not up:
        rc, o, e = finish(p, 5)
        return False, f"plant did not listen on [::1]: {tail(e)}"
    rc, o, e, _ = run(
        ["pmu", "control", "kundur", f"[::1]:{port}", "--esd-pct", 5, "--estimator", "raw"], 300
    )
    rcp, op, ep = finish(p, 120)
    bad = []
    if rc != 0 or rcp != 0:
        bad.append(f"control exit {rc}: {tail(e, 120)}; plant exit {rcp}: {tail(ep, 120)}")
    if tb(e + ep):
        bad.append("traceback")
    return not bad, "; ".join(bad) or f"loop over [::1]: {tail(o, 100)}"


def _strip_json(obj, drop=("wall_time_s", "n_simulations", "wall_s", "kept", "resumed")):
    if isinstance(obj, dict):
        return {k: _strip_json(v, drop) for k, v in obj.items() if k not in drop}
    if isinstance(obj, list):
        return [_strip_json(v, drop) for v in obj]
    return obj


@probe("AZ19")
def place_random_cuts_resume():
    """place kundur DEFAULT --required-clearing-cycles 12 --out pl.json (about 13 s on 2
    workers): an uninterrupted run, then (its kept work, $XDG_CACHE_HOME/stabctl-place,
    removed) runs cut at 5 seeded random moments (SIGINT to the group, SIGTERM to the
    process, alternately), each resumed, the last to its end.  The developers' guide:
    long work "can be interrupted without losing finished results"; the plan must equal
    the uninterrupted one (wall times and simulation counts aside), and no cut may leave
    a traceback or a half-written pl.json."""
    import random, shutil

    rnd = random.Random(55)
    args = [*"place kundur --faults DEFAULT --required-clearing-cycles 12 --workers 2".split()]
    rc, o, e, _ = run([*args, "--out", "ref_pl.json"], 600)
    if rc != 0:
        return False, f"reference exit {rc}: {tail(e)}"
    want = json.loads((WD / "ref_pl.json").read_text())
    shutil.rmtree(WD / "xdg" / "stabctl-place", ignore_errors=True)
    bad, cuts = [], []
    for k in range(5):
        at = rnd.uniform(1.0, 11.0)
        p = start([*args, "--out", "pl.json"])
        time.sleep(at)
        sig = signal.SIGINT if k % 2 == 0 else signal.SIGTERM
        try:
            os.killpg(p.pid, sig) if sig == signal.SIGINT else os.kill(p.pid, sig)
        except ProcessLookupError:
            pass
        rcc, oc, ec = finish(p, 120)
        cuts.append(f"{at:.1f}s:{rcc}")
        if tb(oc + ec):
            (WD / f"cut{k}.err").write_text(ec)
            line = [ln for ln in ec.splitlines() if ln.strip() and not ln.startswith(" ")]
            bad.append(
                f"cut {k} at {at:.1f} s ({sig.name}): traceback: {' | '.join(line[-4:])[:400]}"
            )
        if rcc not in (0, 1, 130, 143):
            bad.append(f"cut {k} at {at:.1f} s: exit {rcc}: {tail(ec, 150)}")
        if (WD / "pl.json").exists():
            try:
                json.loads((WD / "pl.json").read_text())
            except ValueError:
                bad.append(f"cut {k}: pl.json half-written")
            if rcc in (130, 143):
                bad.append(f"cut {k} at {at:.1f} s ({sig.name}) exit {rcc} but pl.json written")
            (WD / "pl.json").unlink()
        if bad:
            break
    if not bad:
        rc, o, e, _ = run([*args, "--out", "pl.json"], 600)
        if rc != 0:
            bad.append(f"final resume exit {rc}: {tail(e, 150)}")
        else:
            got = json.loads((WD / "pl.json").read_text())
            a, b = _strip_json(want), _strip_json(got)
            if a != b:
                diff = [k for k in set(a) | set(b) if a.get(k) != b.get(k)]
                bad.append(f"plan differs from the uninterrupted run in {sorted(diff)[:6]}")
    return not bad, "; ".join(bad) or f"plan equal after cuts {', '.join(cuts)}"


def _ctrl_c_series(args, out, moments):
    """Ctrl-C to the group of `stabctl args` at each of `moments` (s) in, `out` removed
    before each: (ok, why), SHORT when any run printed a traceback or a worker's "Fatal
    Python error"."""
    hits, codes = [], []
    for k, at in enumerate(moments):
        (WD / out).unlink(missing_ok=True)
        p = start(args)
        time.sleep(at)
        try:
            os.killpg(p.pid, signal.SIGINT)
        except ProcessLookupError:
            pass
        rcc, oc, ec = finish(p, 120)
        codes.append(rcc)
        if tb(ec) or "Fatal Python error" in ec:
            (WD / f"ctrlc-{out}-{k}.err").write_text(ec)
            first = next(
                (ln for ln in ec.splitlines() if "Fatal Python" in ln or "Traceback" in ln), ""
            )
            hits.append(f"{at:.2f} s (exit {rcc}: {first[:60]})")
    n = len(moments)
    if hits:
        return False, (
            f"{len(hits)} of {n} Ctrl-C's printed a worker's start-up traceback (\"Fatal "
            f'Python error: init_import_site"), at {", ".join(hits[:4])}'
        )
    return True, f"{n} Ctrl-C's clean (exits {sorted(set(map(str, codes)))})"


@probe("AZ20")
def place_ctrl_c_while_workers_start():
    """Ctrl-C (SIGINT to the process group, as a terminal sends it) during `place kundur
    DEFAULT --required-clearing-cycles 12 --workers 2` (its kept work warm), at 40 moments
    1.6-3.2 s in (timing-dependent: 3 of 25 hit alone, 0 of 25 once in a full run): each must end with the one `interrupted:` line and exit 130, no
    traceback (docs/cli.md: Ctrl-C ends a command with "one interrupted: line"; workers
    "ignore" the group's signals, stabctl/parallel.die_with_parent).  The docs leave to
    Python only "a signal in the first tenth of a second or so, while the interpreter
    itself starts" - the command's, not a worker's spawned seconds into it."""
    args = [
        *"place kundur --faults DEFAULT --required-clearing-cycles 12 --workers 2 --out pc.json".split()
    ]
    rc, o, e, _ = run(args, 600)
    if rc != 0:
        return False, f"warm-up exit {rc}: {tail(e)}"
    return _ctrl_c_series(args, "pc.json", [1.6 + 0.04 * k for k in range(40)])


@probe("AZ21")
def screen_ctrl_c_while_workers_start():
    """The same as AZ20 for `screen kundur --lines --workers 2 --out s.jsonl` (its workers
    spawn about 1.3-1.5 s in here): Ctrl-C at 25 moments 1.0-2.2 s in, each a fresh
    records file: one `interrupted:` line, exit 130, no traceback."""
    args = ["screen", "kundur", "--lines", "--workers", 2, "--out", "scc.jsonl"]
    return _ctrl_c_series(args, "scc.jsonl", [1.0 + 0.05 * k for k in range(25)])


if __name__ == "__main__":
    KIT.main()
