#!/usr/bin/env python
"""Twentieth reliability round (round 40, part O): network services, long work and
resources.  PMU services attacked at the protocol level (floods of silent peers, command
frames of a wrong size, strangers, IPv6, allow-lists), long commands interrupted and
resumed, hand-edited records, Dask scheduler addresses that are no scheduler, outputs
that cannot be written.

    python benchmarks/reliability_probes_20.py [PROBE_ID_PREFIX ...]

The package under test is this repository's (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's.  Prints per probe: id, ok/SHORT, one-line reason; exits
1 if any is SHORT.  About 6 minutes on two cores with a warm kernel cache.  The round
found short: 1 100 silent connections ended `pmu plant` before its controller came
("Too many open files"), and a 16-byte command frame had its CRC read as its command
word and obeyed; both fixed.
"""

# ruff: noqa: E501, B007, BLE001, SIM115, RUF021, RUF059 - a tester's script, kept as written
from __future__ import annotations

import json
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
CLONE = Path(os.environ.get("CLONE", HERE.parent))  # the package under test
ENV = dict(os.environ, PYTHONPATH=str(CLONE), PYTHONUNBUFFERED="1")
sys.path.insert(0, str(CLONE))
ROOT = Path(tempfile.mkdtemp(prefix="probes_o_"))
PROBES = []
STARTED: list[subprocess.Popen] = []
FAULT = ["--fault", "3", "--far-bus", "101"]


def probe(pid):
    def deco(fn):
        fn.pid = pid
        PROBES.append(fn)
        return fn

    return deco


def tb(s: str) -> bool:
    return "Traceback (most recent call last)" in s


def run(args, cwd, timeout=300, env=None, pre=None):
    """stabctl ARGS in cwd: (rc, stdout, stderr); rc None on timeout."""
    try:
        p = subprocess.run(
            ["stabctl", *args],
            cwd=cwd,
            env=env or ENV,
            capture_output=True,
            text=True,
            timeout=timeout,
            stdin=subprocess.DEVNULL,
            preexec_fn=pre,
        )
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired as exc:
        return (
            None,
            (exc.stdout or b"").decode(errors="replace")
            if isinstance(exc.stdout, bytes)
            else (exc.stdout or ""),
            (exc.stderr or b"").decode(errors="replace")
            if isinstance(exc.stderr, bytes)
            else (exc.stderr or ""),
        )


def _dfl():
    for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM, signal.SIGQUIT):
        signal.signal(s, signal.SIG_DFL)


def start(args, cwd, prefix=(), log="log.txt"):
    """stabctl ARGS in the background, new session, default signals; output to cwd/log."""
    f = open(Path(cwd) / log, "wb")
    p = subprocess.Popen(
        [*prefix, "stabctl", *args],
        cwd=cwd,
        env=ENV,
        stdout=f,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        start_new_session=True,
        preexec_fn=_dfl,
    )
    p.log = Path(cwd) / log
    STARTED.append(p)
    return p


def text(p) -> str:
    try:
        return p.log.read_text(errors="replace")
    except OSError:
        return ""


def wait_for(p, pattern, timeout):
    t0 = time.time()
    while time.time() - t0 < timeout:
        t = text(p)
        if re.search(pattern, t):
            return t
        if p.poll() is not None:
            t = text(p)
            return t if re.search(pattern, t) else None
        time.sleep(0.2)
    return None


def stop(p, sig=signal.SIGKILL):
    if p.poll() is None:
        try:
            os.killpg(p.pid, sig)
        except ProcessLookupError:
            pass
    try:
        p.wait(15)
    except subprocess.TimeoutExpired:
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.wait()


def wait_rc(p, timeout):
    try:
        return p.wait(timeout)
    except subprocess.TimeoutExpired:
        return None


# ------------------------------------------------------------------ C37.118.2 frames
def crc_ccitt(data: bytes) -> int:
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def cmd_frame(
    word: int,
    idcode: int = 1,
    extra: bytes = b"",
    size: int | None = None,
    soc: int = 0,
    frac: int = 0,
) -> bytes:
    n = 18 + len(extra) if size is None else size
    body = struct.pack(">BBHHIIH", 0xAA, 0x41, n, idcode, soc, frac, word) + extra
    return body + struct.pack(">H", crc_ccitt(body))


def read_frame(s: socket.socket):
    head = b""
    while len(head) < 4:
        c = s.recv(4 - len(head))
        if not c:
            return None
        head += c
    n = int.from_bytes(head[2:4], "big")
    body = b""
    while len(body) < n - 4:
        c = s.recv(n - 4 - len(body))
        if not c:
            return None
        body += c
    return head + body


def port_of(t: str) -> int:
    m = re.findall(r"(?:127\.0\.0\.1|\[::1\]):(\d+)", t)
    return int(m[0])


def plant(d, extra=(), prefix=(), log="plant.log"):
    speed = [] if "--speed" in extra else ["--speed", "0"]
    tf = [] if "--tf" in extra else ["--tf", "2"]
    args = ["pmu", "plant", "kundur", *FAULT, "--esd-pct", "5", *tf, "--port", "0", *speed, *extra]
    p = start(args, d, prefix=prefix, log=log)
    t = wait_for(p, r"(127\.0\.0\.1|\[::1\]):\d+", 240)
    if not t:
        stop(p)
        raise RuntimeError("plant did not listen: " + text(p)[-300:])
    return p, port_of(t)


class MyController:
    """A hand-made controller: handshake, then answer each data frame with modes."""

    def __init__(self, port, host="127.0.0.1", idcode=1):
        self.s = socket.create_connection((host, port), timeout=20)
        self.s.sendall(cmd_frame(5, idcode))
        self.cfg = read_frame(self.s)
        self.s.sendall(cmd_frame(2, idcode))

    def answer(self, data, modes=(0, 0, 0, 0), idcode=1):
        from stabctl.estimation.c37_loop import modes_frame

        soc = int.from_bytes(data[6:10], "big")
        cnt = int.from_bytes(data[11:14], "big")
        return modes_frame(idcode, soc, cnt, modes)


# =================================================================== PMU probes
@probe("O01-plant-fd-exhaustion-by-silent-strangers")
def _():
    """pmu plant under the usual 1024 open files; 1100 silent strangers connect and leave after 4
    s; then a real `pmu control`.  The plant must survive (or end with a one-line error),
    never a traceback; the controller must then get through."""
    d = ROOT / "o01"
    d.mkdir()
    p, port = plant(d, ["--timeout", "40"], prefix=("prlimit", "--nofile=1024:1024"))
    socks = []
    for _ in range(1100):
        try:
            socks.append(socket.create_connection(("127.0.0.1", port), timeout=2))
        except OSError:
            break
    time.sleep(4)
    for s in socks:
        s.close()
    time.sleep(1)
    alive = p.poll() is None
    rc, o, e = run(
        ["pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", "5", "--timeout", "30"],
        d,
        timeout=200,
    )
    prc = wait_rc(p, 60)
    stop(p)
    t = text(p)
    if tb(t):
        return False, f"plant traceback after {len(socks)} strangers: " + t.strip().splitlines()[
            -1
        ][:160]
    if not alive:
        return False, f"plant died (rc {prc}) of {len(socks)} silent strangers: " + " | ".join(
            t.strip().splitlines()[-2:]
        )[:200]
    if rc != 0 or prc != 0:
        return False, f"controller rc {rc}, plant rc {prc} after the flood: " + (
            e.strip().splitlines() or [""]
        )[-1][:150]
    return True, f"{len(socks)} strangers on 1024 fds: plant survived, controller then ran (rc 0)"


@probe("O02-plant-stranger-cannot-drive-during-run")
def _():
    """While `pmu control` drives the plant, a stranger connects, says cfg2/start and sends
    mode frames 'all +1' for every stamp of the run: the plant's ESD switchings must equal
    those of the same run without the stranger."""
    d = ROOT / "o02"
    d.mkdir()
    outs = []
    for stranger in (False, True):
        p, port = plant(
            d, ["--timeout", "30", "--json", "--speed", "1"], log=f"plant{int(stranger)}.log"
        )
        ctl = subprocess.Popen(
            [
                "stabctl",
                "pmu",
                "control",
                "kundur",
                f"127.0.0.1:{port}",
                "--esd-pct",
                "5",
                "--timeout",
                "30",
            ],
            cwd=d,
            env=ENV,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            preexec_fn=_dfl,
            start_new_session=True,
        )
        STARTED.append(ctl)
        got = ""
        if stranger:
            t0 = time.time()
            while time.time() - t0 < 120:  # the controller's connection established first
                ss = subprocess.run(
                    ["ss", "-tnH", "state", "established", f"( sport = :{port} )"],
                    capture_output=True,
                    text=True,
                ).stdout
                if ss.strip():
                    break
                time.sleep(0.05)
            time.sleep(0.3)
            try:
                s = socket.create_connection(("127.0.0.1", port), timeout=3)
                s.sendall(cmd_frame(5) + cmd_frame(2))
                from stabctl.estimation import c37
                from stabctl.estimation.c37_loop import modes_frame

                blob = b"".join(
                    modes_frame(
                        1, 0, int(round(k / 60 * c37.TIME_BASE)) % c37.TIME_BASE, [1, 1, 1, 1]
                    )
                    for k in range(1, 121)
                )
                s.settimeout(3)
                try:
                    s.sendall(blob)
                    got = "sent"
                except OSError as exc:
                    got = f"send failed {exc}"
            except OSError as exc:
                got = f"connect failed {exc}"
        try:
            co, ce = ctl.communicate(timeout=200)
        except subprocess.TimeoutExpired:
            stop(ctl)
            stop(p)
            return False, "controller did not end in 200 s"
        prc = wait_rc(p, 60)
        stop(p)
        if stranger:
            try:
                s.close()
            except Exception:
                pass
        t = text(p)
        if prc != 0 or ctl.returncode != 0 or tb(t):
            return (
                False,
                f"stranger={stranger}: plant rc {prc}, control rc {ctl.returncode}: {t.strip()[-200:]} {ce.strip()[-200:]}",
            )
        js = t[t.find("{") :]
        try:
            outs.append(json.loads(js))
        except ValueError:
            outs.append(js)
    a, b = outs
    for k in ("link",):
        if isinstance(a, dict):
            a.pop(k, None), b.pop(k, None)

    def strip(o):
        if isinstance(o, dict):
            return {
                k: strip(v)
                for k, v in o.items()
                if "round_trip" not in k and "ms" not in k and "time" not in k and k != "late"
            }
        if isinstance(o, list):
            return [strip(v) for v in o]
        if isinstance(o, str):
            return re.sub(r"round trip.*", "", o)
        return o

    if strip(a) != strip(b):
        diff = [k for k in (a if isinstance(a, dict) else {}) if strip(a.get(k)) != strip(b.get(k))]
        return False, f"stranger ({got}) changed the plant's result: keys {diff[:6]}"
    return True, f"stranger ({got}) changed nothing in the plant's result"


@probe("O03-plant-controller-leaves-another-arrives")
def _():
    """A hand-made controller answers 15 frames and closes; a real `pmu control` connects
    at once: the plant ends with one error line naming the first controller's loss (rc 2,
    no verdict as if whole); the second controller ends with an error within its time-out."""
    d = ROOT / "o03"
    d.mkdir()
    p, port = plant(d, ["--timeout", "15"])
    c = MyController(port)
    n = 0
    while n < 15:
        f = read_frame(c.s)
        if f is None:
            break
        if (f[1] >> 4) & 7 == 0:
            c.s.sendall(c.answer(f))
            n += 1
    c.s.close()
    rc, o, e = run(
        ["pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", "5", "--timeout", "10"],
        d,
        timeout=120,
    )
    prc = wait_rc(p, 60)
    stop(p)
    t = text(p)
    bad = []
    if tb(t) or tb(e):
        bad.append("traceback")
    if prc != 2 or "error:" not in t:
        bad.append(f"plant rc {prc}: {t.strip()[-200:]}")
    if rc is None:
        bad.append("second controller hung")
    elif rc == 0:
        bad.append(f"second controller rc 0: {o.strip()[-200:]}")
    elif "error:" not in e:
        bad.append(f"second controller rc {rc} without error: {e.strip()[-150:]}")
    if bad:
        return False, "; ".join(bad)
    return True, (
        f"plant rc 2 '{[l for l in t.splitlines() if 'error' in l][-1][:110]}'; second "
        f"controller rc {rc} '{e.strip().splitlines()[-1][:110]}'"
    )


@probe("O04-plant-answers-twice-or-ahead")
def _():
    """A controller that answers each frame twice: the plant must refuse at the second frame
    (the queued duplicate answers another frame), rc 2, one error line."""
    d = ROOT / "o04"
    d.mkdir()
    p, port = plant(d, ["--timeout", "15"])
    c = MyController(port)
    n = 0
    c.s.settimeout(20)
    try:
        while n < 30:
            f = read_frame(c.s)
            if f is None:
                break
            if (f[1] >> 4) & 7 == 0:
                a = c.answer(f)
                c.s.sendall(a + a)
                n += 1
    except OSError:
        pass
    prc = wait_rc(p, 60)
    stop(p)
    t = text(p)
    if tb(t) or prc != 2 or "error:" not in t:
        return False, f"plant rc {prc} after {n} frames answered twice: {t.strip()[-200:]}"
    return (
        True,
        f"plant rc 2 after {n} frame(s): {[l for l in t.splitlines() if 'error' in l][-1][:140]}",
    )


@probe("O05-serve-odd-commands-then-start-and-ipv6")
def _():
    """pmu serve --host ::1 --allow 0:0:0:0:0:0:0:1 (uncompressed): a PDC sends command
    words 0, 3 (cfg1), 6 (cfg3), 8 (extended, payload), 0xffff, a 'start' of FRAMESIZE 20
    with 2 extra bytes, then cfg2, start, reads every frame and closes: all 180 frames,
    server rc 0; a connection to 127.0.0.1 is refused (not listening)."""
    d = ROOT / "o05"
    d.mkdir()
    p = start(
        [
            "pmu",
            "serve",
            "kundur",
            *FAULT,
            "--tf",
            "3",
            "--host",
            "::1",
            "--allow",
            "0:0:0:0:0:0:0:1",
            "--port",
            "0",
            "--speed",
            "0",
            "--timeout",
            "10",
            "--wait",
            "5",
        ],
        d,
    )
    t = wait_for(p, r"\[::1\]:\d+", 240)
    if not t:
        stop(p)
        return False, "serve did not listen on [::1]: " + text(p)[-300:]
    port = port_of(t)
    v4 = "refused"
    try:
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
        v4 = "ACCEPTED"
    except OSError:
        pass
    s = socket.create_connection(("::1", port), timeout=10)
    for w, extra in ((0, b""), (3, b""), (6, b""), (8, b"abc"), (0xFFFF, b"")):
        s.sendall(cmd_frame(w, extra=extra))
    s.sendall(cmd_frame(5))
    cfg = read_frame(s)
    s.sendall(cmd_frame(2))
    frames = 0
    s.settimeout(10)
    try:
        while True:
            f = read_frame(s)
            if f is None:
                break
            if (f[1] >> 4) & 7 == 0:
                frames += 1
    except OSError as exc:
        frames = f"{frames} then {exc}"
    s.close()
    rc = wait_rc(p, 30)
    stop(p)
    t = text(p)
    if tb(t) or rc != 0 or v4 != "refused" or cfg is None:
        return False, f"serve rc {rc}, v4 {v4}, frames {frames}: {t.strip()[-250:]}"
    return True, f"::1 with uncompressed --allow: {frames} frames, rc 0, IPv4 {v4}"


@probe("O06-serve-connect-close-storm-during-record")
def _():
    """3000 connect/close (and 300 RST) from 127.0.0.1 while `pmu record` reads the stream:
    the recording is whole, the server rc 0, and its log stays short (< 60 lines)."""
    d = ROOT / "o06"
    d.mkdir()
    p = start(
        [
            "pmu",
            "serve",
            "kundur",
            *FAULT,
            "--tf",
            "4",
            "--port",
            "0",
            "--speed",
            "1",
            "--timeout",
            "10",
            "--wait",
            "5",
        ],
        d,
    )
    t = wait_for(p, r"127\.0\.0\.1:\d+", 240)
    if not t:
        stop(p)
        return False, "serve did not listen: " + text(p)[-300:]
    port = port_of(t)
    rec = subprocess.Popen(
        ["stabctl", "pmu", "record", f"127.0.0.1:{port}", "--frames", "241", "-o", "r.c37"],
        cwd=d,
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_dfl,
        start_new_session=True,
    )
    STARTED.append(rec)
    time.sleep(1.5)
    n = 0
    for i in range(3300):
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            if i % 11 == 0:
                s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
            s.close()
            n += 1
        except OSError:
            pass
    try:
        ro, re_ = rec.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        stop(rec)
        stop(p)
        return False, "record did not end in 120 s"
    rc = wait_rc(p, 40)
    stop(p)
    t = text(p)
    lines = len(t.splitlines())
    if tb(t) or tb(re_) or rec.returncode != 0 or rc != 0 or lines >= 60:
        return False, (
            f"record rc {rec.returncode} ({re_.strip()[-150:]}), serve rc {rc}, "
            f"{lines} log lines: {t.strip()[-150:]}"
        )
    return True, f"{n} connect/close: record rc 0, serve rc 0, {lines} log lines"


@probe("O07-record-out-dev-full-and-directory")
def _():
    """pmu record -o /dev/full and -o DIR/: one error line, rc 2, nothing written under
    /dev (no /dev/full.partial), the directory unchanged."""
    d = ROOT / "o07"
    d.mkdir()
    (d / "dir.c37").mkdir()
    res = []
    for out in ("/dev/full", "dir.c37"):
        before = set(os.listdir("/dev"))
        p = start(
            [
                "pmu",
                "serve",
                "kundur",
                *FAULT,
                "--tf",
                "2",
                "--port",
                "0",
                "--speed",
                "0",
                "--timeout",
                "5",
                "--wait",
                "3",
            ],
            d,
            log=f"s{len(res)}.log",
        )
        t = wait_for(p, r"127\.0\.0\.1:\d+", 240)
        if not t:
            stop(p)
            return False, "serve did not listen"
        port = port_of(t)
        rc, o, e = run(["pmu", "record", f"127.0.0.1:{port}", "--frames", "60", "-o", out], d, 120)
        stop(p)
        new = set(os.listdir("/dev")) - before
        for x in new:
            if x.startswith("full"):
                try:
                    os.remove("/dev/" + x)
                except OSError:
                    pass
        ok = (
            rc == 2
            and "error:" in e
            and not tb(e)
            and not new
            and not list((d / "dir.c37").iterdir())
        )
        res.append(
            (out, ok, rc, e.strip().splitlines()[-1][:120] if e.strip() else "", sorted(new))
        )
    bad = [r for r in res if not r[1]]
    if bad:
        return False, "; ".join(f"-o {o}: rc {rc} '{l}' new in /dev {n}" for o, _, rc, l, n in bad)
    return True, "; ".join(f"-o {o}: rc {rc} '{l[:70]}'" for o, _, rc, l, _n in res)


@probe("O08-track-tcp-ipv6-source")
def _():
    """estimate track --source tcp://[::1]:PORT against pmu serve --host ::1: runs (rc 0)."""
    d = ROOT / "o08"
    d.mkdir()
    p = start(
        [
            "pmu",
            "serve",
            "kundur",
            *FAULT,
            "--tf",
            "3",
            "--host",
            "::1",
            "--port",
            "0",
            "--speed",
            "0",
            "--timeout",
            "10",
            "--wait",
            "5",
        ],
        d,
    )
    t = wait_for(p, r"\[::1\]:\d+", 240)
    if not t:
        stop(p)
        return False, "serve did not listen"
    port = port_of(t)
    rc, o, e = run(
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            f"tcp://[::1]:{port}",
            "--frames",
            "181",
            "--out",
            "t.csv",
        ],
        d,
        200,
    )
    prc = wait_rc(p, 30)
    stop(p)
    if rc != 0 or tb(e):
        return False, f"track rc {rc}: {e.strip()[-200:]} (serve rc {prc})"
    return True, f"track over [::1] rc 0, serve rc {prc}"


@probe("O09-plant-signals-waiting-and-midrun")
def _():
    """pmu plant SIGINT while waiting for its controller: rc 130, no traceback; SIGTERM
    mid-run (--speed 1) with `pmu control` connected: plant rc 143, the controller rc 2
    naming the plant's early stop (no summary as if the run was whole)."""
    d = ROOT / "o09"
    d.mkdir()
    bad, notes = [], []
    p, port = plant(d, ["--timeout", "60"], log="a.log")
    time.sleep(1)
    os.killpg(p.pid, signal.SIGINT)
    rc = wait_rc(p, 30)
    stop(p)
    t = text(p)
    notes.append(f"waiting+SIGINT rc {rc}")
    if rc != 130 or tb(t):
        bad.append(f"waiting+SIGINT rc {rc}: {t.strip()[-150:]}")
    p, port = plant(d, ["--timeout", "60", "--speed", "1", "--tf", "6"], log="b.log")
    ctl = subprocess.Popen(
        [
            "stabctl",
            "pmu",
            "control",
            "kundur",
            f"127.0.0.1:{port}",
            "--esd-pct",
            "5",
            "--timeout",
            "20",
        ],
        cwd=d,
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_dfl,
        start_new_session=True,
    )
    STARTED.append(ctl)
    t0 = time.time()
    while time.time() - t0 < 120:
        ss = subprocess.run(
            ["ss", "-tnH", "state", "established", f"( sport = :{port} )"],
            capture_output=True,
            text=True,
        ).stdout
        if ss.strip():
            break
        time.sleep(0.05)
    time.sleep(2.0)
    os.killpg(p.pid, signal.SIGTERM)
    rc = wait_rc(p, 30)
    stop(p)
    try:
        co, ce = ctl.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        stop(ctl)
        co, ce = "", "HUNG"
    t = text(p)
    notes.append(f"midrun+SIGTERM plant rc {rc}, control rc {ctl.returncode}")
    if rc != 143 or tb(t):
        bad.append(f"midrun SIGTERM plant rc {rc}: {t.strip()[-150:]}")
    if ctl.returncode in (0, None) or tb(ce) or "error:" not in ce:
        bad.append(f"controller rc {ctl.returncode}: {ce.strip()[-200:]} {co.strip()[-100:]}")
    else:
        notes.append("'" + ce.strip().splitlines()[-1][:120] + "'")
    if bad:
        return False, "; ".join(bad)
    return True, "; ".join(notes)


@probe("O15-plant-controller-bad-modes")
def _():
    """A controller answering the first frame with (a) mode 2, (b) five modes for 4 ESDs,
    (c) its IDCODE 2, (d) a valid 'stop' command: each plant rc 2 with one error line,
    none takes the modes."""
    from stabctl.estimation.c37_loop import modes_frame

    d = ROOT / "o15"
    d.mkdir()
    bad, notes = [], []
    variants = {
        "mode2": lambda f: modes_frame(
            1, int.from_bytes(f[6:10], "big"), int.from_bytes(f[11:14], "big"), [2, 0, 0, 0]
        ),
        "five": lambda f: modes_frame(
            1, int.from_bytes(f[6:10], "big"), int.from_bytes(f[11:14], "big"), [1, 1, 1, 1, 1]
        ),
        "idcode2": lambda f: modes_frame(
            2, int.from_bytes(f[6:10], "big"), int.from_bytes(f[11:14], "big"), [1, 1, 1, 1]
        ),
        "stop": lambda f: cmd_frame(1),
    }
    for name, make in variants.items():
        p, port = plant(d, ["--timeout", "10"], log=f"{name}.log")
        try:
            c = MyController(port)
            while True:
                f = read_frame(c.s)
                if f is None or (f[1] >> 4) & 7 == 0:
                    break
            if f is not None:
                c.s.sendall(make(f))
            time.sleep(0.5)
            c.s.close()
        except OSError as exc:
            notes.append(f"{name}: {exc}")
        rc = wait_rc(p, 40)
        stop(p)
        t = text(p)
        last = [l for l in t.splitlines() if "error" in l]
        if rc != 2 or tb(t) or not last:
            bad.append(f"{name}: rc {rc} {t.strip()[-150:]}")
        else:
            notes.append(f"{name}: '{last[-1][40:140]}'")
    if bad:
        return False, "; ".join(bad)
    return True, "; ".join(notes)


def short_cmd(word: int) -> bytes:
    """A 16-byte 'command frame' (FRAMESIZE 16: no CMD field, C37.118.2 needs 18) whose
    CRC, found by trying SOC values, equals `word`: a server that reads the command word
    at bytes 14-15 without checking the size reads the CRC as the command."""
    for soc in range(1, 5_000_000):
        b = struct.pack(">BBHHII", 0xAA, 0x41, 16, 1, soc, 0)
        if crc_ccitt(b) == word:
            return b + struct.pack(">H", word)
    raise RuntimeError("no SOC found")


@probe("O16-serve-obeys-16-byte-command-frame")
def _():
    """A command frame whose FRAMESIZE says 16 (below the 18 bytes of SYNC..CMD..CHK), its
    CRC valid over those 16 bytes: it carries no command word, so the server must ignore it
    (or drop the peer), never read its CRC as 'cfg2' / 'start' and stream."""
    d = ROOT / "o16"
    d.mkdir()
    p = start(
        [
            "pmu",
            "serve",
            "kundur",
            *FAULT,
            "--tf",
            "2",
            "--port",
            "0",
            "--speed",
            "0",
            "--timeout",
            "5",
            "--wait",
            "3",
        ],
        d,
    )
    t = wait_for(p, r"127\.0\.0\.1:\d+", 240)
    if not t:
        stop(p)
        return False, "serve did not listen"
    port = port_of(t)
    s = socket.create_connection(("127.0.0.1", port), timeout=4)
    s.sendall(short_cmd(5))
    got = []
    try:
        f = read_frame(s)
        got.append("CFG-2" if f is not None and (f[1] >> 4) & 7 == 3 else repr(f)[:30])
    except OSError:
        got.append("nothing")
    s.sendall(short_cmd(2))
    n = 0
    try:
        while (f := read_frame(s)) is not None:
            n += (f[1] >> 4) & 7 == 0
    except OSError:
        pass
    s.close()
    rc = wait_rc(p, 30)
    stop(p)
    if got[0] == "CFG-2" or n:
        return False, (
            f"16-byte frames obeyed: 'cfg2' answered with {got[0]}, 'start' streamed {n} "
            f"data frames (serve rc {rc}: {text(p).strip().splitlines()[-1][:80]})"
        )
    return True, f"16-byte frames ignored ({got[0]}, {n} frames)"


# ========================================================== long work, records, resources
SWEEP = [
    "sweep-cct",
    "kundur",
    "--faults",
    "DEFAULT",
    "--esd-pct",
    "none,5",
    "--tol-ms",
    "20",
    "--workers",
    "1",
]


def records(path: Path) -> dict:
    out = {}
    for line in path.read_text().splitlines():
        try:
            r = json.loads(line)
        except ValueError:
            continue
        out[r["key"]] = r
    return out


def essence(recs: dict) -> dict:
    from stabctl.parallel import strip_run_dependent

    return {k: strip_run_dependent(r) for k, r in recs.items()}


REF: dict = {}


def reference(d: Path) -> dict:
    """The uninterrupted sweep's records (run once)."""
    if "sweep" not in REF:
        rc, o, e = run([*SWEEP, "--out", "ref.jsonl"], d, 600)
        if rc != 0:
            raise RuntimeError(f"reference sweep rc {rc}: {e.strip()[-300:]}")
        REF["sweep"] = records(d / "ref.jsonl")
        REF["path"] = d / "ref.jsonl"
    return REF["sweep"]


@probe("O10-sweep-records-hand-edited")
def _():
    """Records of a finished sweep edited by hand and given back to --out: (a) one line
    duplicated with its result changed, (b) a line of the same key run with --tol-ms 5,
    (c) a cut line in the middle of the file: none silently taken as this run's (each
    refused with a one-line error, or run again), never a result changed without a word."""
    d = ROOT / "o10"
    d.mkdir()
    ref = reference(d)
    lines = REF["path"].read_text().splitlines()
    notes, bad = [], []
    # (a) a duplicate with another CCT appended: the last line of a key wins?
    rec = json.loads(lines[0])
    fake = dict(rec, result=dict(rec["result"], cct_s=rec["result"]["cct_s"] + 0.02))
    changed = "cct_s"
    (d / "a.jsonl").write_text("\n".join(lines + [json.dumps(fake)]) + "\n")
    rc, o, e = run([*SWEEP, "--out", "a.jsonl"], d, 300)
    notes.append(
        f"(a) dup+changed {changed}: rc {rc} '{(e.strip().splitlines() or [''])[-1][:90]}'"
    )
    if tb(e):
        bad.append("(a) traceback")
    # (b) another settings' line for a key
    other = dict(rec)
    if isinstance(other.get("inputs"), dict):
        other["inputs"] = dict(other["inputs"])
        other["inputs"]["tol"] = 0.04
        other["result"] = dict(other["result"], tol_s=0.04)
    (d / "b.jsonl").write_text("\n".join(lines[1:] + [json.dumps(other)]) + "\n")
    rc2, o2, e2 = run([*SWEEP, "--out", "b.jsonl"], d, 300)
    notes.append(f"(b) other tol: rc {rc2} '{(e2.strip().splitlines() or [''])[-1][:110]}'")
    if rc2 == 0 and "warning" not in e2.lower():
        bad.append("(b) a record with other settings taken silently")
    if tb(e2):
        bad.append("(b) traceback")
    # (c) a cut line in the middle
    cut = lines[:1] + [lines[1][: len(lines[1]) // 2]] + lines[2:]
    (d / "c.jsonl").write_text("\n".join(cut) + "\n")
    rc3, o3, e3 = run([*SWEEP, "--out", "c.jsonl"], d, 400)
    notes.append(f"(c) cut middle line: rc {rc3} '{(e3.strip().splitlines() or [''])[-1][:110]}'")
    if tb(e3):
        bad.append("(c) traceback")
    if rc3 == 0 and essence(records(d / "c.jsonl")) != essence(ref):
        bad.append("(c) resumed records differ from the uninterrupted run")
    if rc3 == 0 and "line 2" not in e3 and "warning" not in e3.lower():
        bad.append("(c) the cut line was not named")
    if bad:
        return False, "; ".join(bad) + " | " + " ".join(notes)
    return True, " ".join(notes)


def _interrupt_then_resume(
    d: Path, sig, after_lines: int | None, after_s: float | None, out="o.jsonl"
):
    p = start([*SWEEP, "--out", out], d, log=f"int_{sig}.log")
    t0 = time.time()
    while time.time() - t0 < 400 and p.poll() is None:
        n = len((d / out).read_text().splitlines()) if (d / out).exists() else 0
        if after_lines is not None and n >= after_lines:
            break
        if after_s is not None and time.time() - t0 >= after_s:
            break
        time.sleep(0.05)
    os.killpg(p.pid, sig)
    rc1 = wait_rc(p, 120)
    stop(p)
    t1 = text(p)
    kept = records(d / out) if (d / out).exists() else {}
    raw = (d / out).read_text() if (d / out).exists() else ""
    rc2, o2, e2 = run([*SWEEP, "--out", out], d, 600)
    return rc1, t1, kept, raw, rc2, e2


@probe("O11-sweep-sighup-startup-and-midrun-then-resume")
def _():
    """sweep-cct cut by SIGHUP 1.5 s after start (start-up) and by SIGTERM after its first
    record: each exits, keeps only whole records of jobs run, and the rerun finishes with
    records equal to an uninterrupted run's."""
    d = ROOT / "o11"
    d.mkdir()
    ref = reference(d)
    bad, notes = [], []
    for sig, lines, secs in (
        (signal.SIGHUP, None, 1.5),
        (signal.SIGTERM, 1, None),
        (signal.SIGINT, 3, None),
    ):
        out = f"o_{int(sig)}.jsonl"
        rc1, t1, kept, raw, rc2, e2 = _interrupt_then_resume(d, sig, lines, secs, out)
        if tb(t1) or tb(e2):
            bad.append(f"{sig.name}: traceback")
        if raw and not raw.endswith("\n"):
            bad.append(f"{sig.name}: half-written line kept")
        if rc1 == 0 and len(kept) < len(ref):
            bad.append(f"{sig.name}: rc 0 with {len(kept)} of {len(ref)} records")
        for k, r in kept.items():
            if k not in ref:
                bad.append(f"{sig.name}: record of a job not run {k}")
        if rc2 != 0 or essence(records(d / out)) != essence(ref):
            bad.append(
                f"{sig.name}: resume rc {rc2}, records differ from an uninterrupted run: {e2.strip()[-150:]}"
            )
        notes.append(f"{sig.name}: rc {rc1}, kept {len(kept)}, resume rc {rc2}")
    if bad:
        return False, "; ".join(bad)
    return True, "; ".join(notes)


@probe("O12-sweep-out-unwritable")
def _():
    """sweep-cct --out /dev/full, --out DIR, --out in a missing directory, --out a symlink to
    /dev/full: each one error line rc 2 before any work, no traceback."""
    d = ROOT / "o12"
    d.mkdir()
    (d / "dir.jsonl").mkdir()
    os.symlink("/dev/full", d / "link.jsonl")
    bad, notes = [], []
    for out in ("/dev/full", "dir.jsonl", "missing/o.jsonl", "link.jsonl"):
        t0 = time.time()
        rc, o, e = run([*SWEEP, "--out", out], d, 300)
        last = (e.strip().splitlines() or [""])[-1][:90]
        notes.append(f"{out}: rc {rc} {time.time() - t0:.0f}s '{last}'")
        if rc != 2 or tb(e) or "error:" not in e:
            bad.append(f"{out}: rc {rc} '{last}'")
    if bad:
        return False, "; ".join(bad)
    return True, "; ".join(notes)


@probe("O13-sweep-disk-full-mid-run")
def _():
    """sweep-cct whose --out lives on a 64 KiB tmpfs filled to the last bytes after the
    first record (RLIMIT_FSIZE variant: ulimit -f of the file's size + 200 bytes): exits
    with one error line (not rc 0), no half line, finished records kept, a rerun with room
    finishes equal to an uninterrupted run."""
    d = ROOT / "o13"
    d.mkdir()
    ref = reference(d)
    first = REF["path"].read_text().splitlines()[0] + "\n"
    (d / "o.jsonl").write_text(first)
    size = len(first.encode()) + 200
    import resource

    def lim():
        _dfl()
        blocks = size  # RLIMIT_FSIZE in bytes
        resource.setrlimit(resource.RLIMIT_FSIZE, (blocks, blocks))

    rc, o, e = run([*SWEEP, "--out", "o.jsonl"], d, 600, pre=lim)
    raw = (d / "o.jsonl").read_text()
    bad = []
    if tb(e):
        bad.append("traceback: " + e.strip().splitlines()[-1][:150])
    if rc == 0:
        bad.append("rc 0 with the file limit hit")
    if raw and not raw.endswith("\n"):
        bad.append("half line left")
    if not raw.startswith(first):
        bad.append("the finished first record lost")
    rc2, o2, e2 = run([*SWEEP, "--out", "o.jsonl"], d, 600)
    if rc2 != 0 or essence(records(d / "o.jsonl")) != essence(ref):
        bad.append(f"rerun rc {rc2} records differ: {e2.strip()[-150:]}")
    if bad:
        return False, "; ".join(
            bad
        ) + f" | first run rc {rc}: '{(e.strip().splitlines() or [''])[-1][:120]}'"
    return True, f"rc {rc} '{(e.strip().splitlines() or [''])[-1][:120]}', rerun equal"


# ================================================================== Dask
DONE = False


@probe("O20-scheduler-odd-addresses")
def _():
    """--scheduler given odd addresses: no port, tls://, inproc://, [::1] closed port,
    'LOCAL', a silent TCP listener (accepts and never speaks), a listener that sends
    garbage: each one error line rc 2 within 90 s, no traceback, no record written."""
    d = ROOT / "o20"
    d.mkdir()
    silent = socket.create_server(("127.0.0.1", 0))
    garb = socket.create_server(("127.0.0.1", 0))
    held = []
    global DONE
    DONE = False

    def acc(srv, payload):
        srv.settimeout(0.5)
        while not DONE:
            try:
                c, _ = srv.accept()
            except OSError:
                continue
            held.append(c)
            if payload:
                try:
                    c.sendall(payload)
                except OSError:
                    pass

    for srv, pay in ((silent, b""), (garb, b"\x00\xff" * 5000)):
        threading.Thread(target=acc, args=(srv, pay), daemon=True).start()
    addrs = [
        "tcp://127.0.0.1",
        "tls://127.0.0.1:1",
        "inproc://nothing",
        "tcp://[::1]:1",
        "LOCAL",
        f"tcp://127.0.0.1:{silent.getsockname()[1]}",
        f"tcp://127.0.0.1:{garb.getsockname()[1]}",
        "tcp://127.0.0.1:8786/extra",
        "ws://127.0.0.1:1",
    ]
    bad, notes = [], []
    for a in addrs:
        out = f"s{len(notes)}.jsonl"
        t0 = time.time()
        args = [x for x in SWEEP if x not in ("--workers", "1")]
        rc, o, e = run([*args, "--out", out, "--scheduler", a], d, 150)
        dt = time.time() - t0
        last = (e.strip().splitlines() or [""])[-1][:100]
        notes.append(f"{a}: rc {rc} {dt:.0f}s '{last[:60]}'")
        if (
            rc != 2
            or tb(e)
            or "error:" not in e
            or dt > 90
            or (d / out).exists()
            and (d / out).read_text().strip()
        ):
            bad.append(f"{a}: rc {rc} {dt:.0f}s '{last}'")
    DONE = True
    for c in held:
        c.close()
    silent.close()
    garb.close()
    if bad:
        return False, "; ".join(bad)
    return True, "; ".join(notes)


def _dask_cluster(d: Path, worker_cwd: Path):
    """A `dask scheduler` on loopback and one `dask worker --nthreads 1` started in
    worker_cwd; (scheduler proc, worker proc, address)."""
    f = open(d / "sched.log", "wb")
    sch = subprocess.Popen(
        ["dask", "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard"],
        cwd=d,
        env=ENV,
        stdout=f,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        start_new_session=True,
        preexec_fn=_dfl,
    )
    sch.log = d / "sched.log"
    STARTED.append(sch)
    t = wait_for(sch, r"Scheduler at:\s+tcp://127\.0\.0\.1:\d+", 90)
    if not t:
        raise RuntimeError("dask scheduler did not start: " + text(sch)[-300:])
    addr = re.search(r"Scheduler at:\s+(tcp://127\.0\.0\.1:\d+)", t).group(1)
    g = open(d / "worker.log", "wb")
    wk = subprocess.Popen(
        [
            "dask",
            "worker",
            addr,
            "--nthreads",
            "1",
            "--nworkers",
            "1",
            "--no-dashboard",
            "--host",
            "127.0.0.1",
        ],
        cwd=worker_cwd,
        env=ENV,
        stdout=g,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        start_new_session=True,
        preexec_fn=_dfl,
    )
    wk.log = d / "worker.log"
    STARTED.append(wk)
    if not wait_for(wk, r"Registered to|Starting established connection", 90):
        raise RuntimeError("dask worker did not register: " + text(wk)[-300:])
    return sch, wk, addr


@probe("O21-dask-worker-cwd-holds-another-case-file")
def _():
    """sweep-cct case.json (a relative path) on a separately started Dask scheduler whose
    worker runs in another directory holding another case.json (machine H halved): the
    records must be those of the client's case.json (as a local run's), or refused with a
    one-line error; never the worker's file's CCTs."""
    d = ROOT / "o21"
    w = ROOT / "o21w"
    d.mkdir()
    w.mkdir()
    src = json.loads((CLONE / "stabctl/case/data/kundur.json").read_text())
    (d / "case.json").write_text(json.dumps(src))
    other = json.loads(json.dumps(src))
    cols = other["tables"]["machines"]["columns"]
    h = cols.index("H")
    for row in other["tables"]["machines"]["rows"]:
        row[h] = row[h] / 2
    (w / "case.json").write_text(json.dumps(other))
    args = ["sweep-cct", "case.json", "--faults", "DEFAULT", "--tol-ms", "20"]
    # DEFAULT is built-in for kundur only: give the faults as a CSV
    (d / "f.csv").write_text("bus,far_bus\n3,101\n13,101\n")
    args = ["sweep-cct", "case.json", "--faults", "f.csv", "--tol-ms", "20"]
    rc0, o0, e0 = run([*args, "--workers", "1", "--out", "local.jsonl"], d, 300)
    if rc0 != 0:
        return False, f"local run rc {rc0}: {e0.strip()[-200:]}"
    sch, wk, addr = _dask_cluster(d, w)
    try:
        rc, o, e = run([*args, "--scheduler", addr, "--out", "dask.jsonl"], d, 300)
    finally:
        stop(wk, signal.SIGTERM)
        stop(sch, signal.SIGTERM)
    if tb(e):
        return False, "traceback: " + e.strip().splitlines()[-1][:150]
    if rc == 0:
        a, b = essence(records(d / "local.jsonl")), essence(records(d / "dask.jsonl"))
        if a != b:
            ca = {k: r["result"].get("cct_s") for k, r in a.items()}
            cb = {k: r["result"].get("cct_s") for k, r in b.items()}
            return False, f"rc 0, the worker's case.json computed: CCT local {ca} dask {cb}"
        return True, "rc 0, records equal to the local run's (the client's case.json)"
    if rc == 2 and "error:" in e:
        return True, f"refused: {e.strip().splitlines()[-1][:150]}"
    return False, f"rc {rc}: {e.strip()[-200:]}"


def png_whole(p: Path) -> bool:
    b = p.read_bytes()
    return b.startswith(b"\x89PNG") and b.rstrip(b"\x00").endswith(b"IEND\xaeB`\x82")


@probe("O14-screen-sigterm-while-writing-plot-and-records")
def _():
    """screen kundur --plot m.png with one search left, SIGTERM (and SIGHUP) at several
    moments after its last record is written (while it sorts, prints and draws): no
    half-written PNG, no stray temporary file, records whole; a rerun makes the figure and
    the records equal an uninterrupted run's."""
    d = ROOT / "o14"
    d.mkdir()
    args = [
        "screen",
        "kundur",
        "--tol-ms",
        "20",
        "--workers",
        "1",
        "--out",
        "s.jsonl",
        "--plot",
        "m.png",
    ]
    rc, o, e = run(args, d, 300)
    if rc != 0:
        return False, f"reference screen rc {rc}: {e.strip()[-200:]}"
    ref = essence(records(d / "s.jsonl"))
    lines = (d / "s.jsonl").read_text().splitlines()
    bad, notes = [], []
    for i, (sig, off) in enumerate(
        [
            (signal.SIGTERM, 0.0),
            (signal.SIGTERM, 0.2),
            (signal.SIGHUP, 0.5),
            (signal.SIGTERM, 0.9),
            (signal.SIGINT, 1.4),
            (signal.SIGTERM, 2.0),
        ]
    ):
        w = d / f"k{i}"
        w.mkdir()
        (w / "s.jsonl").write_text("\n".join(lines[:-1]) + "\n")
        p = start(args, w, log="k.log")
        t0 = time.time()
        while p.poll() is None and time.time() - t0 < 120:
            if len((w / "s.jsonl").read_text().splitlines()) >= len(lines):
                break
            time.sleep(0.01)
        time.sleep(off)
        if p.poll() is None:
            os.killpg(p.pid, sig)
        rc1 = wait_rc(p, 60)
        stop(p)
        t = text(p)
        stray = sorted(x for x in os.listdir(w) if x not in ("s.jsonl", "m.png", "k.log"))
        png = w / "m.png"
        if tb(t):
            bad.append(f"{sig.name}+{off}: traceback {t.strip().splitlines()[-1][:100]}")
        if png.exists() and not png_whole(png):
            bad.append(f"{sig.name}+{off}: half-written m.png ({png.stat().st_size} B), rc {rc1}")
        if rc1 == 0 and not png.exists():
            bad.append(f"{sig.name}+{off}: rc 0 without the figure")
        if stray:
            bad.append(f"{sig.name}+{off}: stray files {stray}")
        had = "whole" if png.exists() else "none"
        raw = (w / "s.jsonl").read_text()
        if not raw.endswith("\n"):
            bad.append(f"{sig.name}+{off}: half record line")
        rc2, o2, e2 = run(args, w, 300)
        if rc2 != 0 or essence(records(w / "s.jsonl")) != ref or not png_whole(png):
            bad.append(
                f"{sig.name}+{off}: rerun rc {rc2}, records equal {essence(records(w / 's.jsonl')) == ref}: {e2.strip()[-120:]}"
            )
        notes.append(f"{sig.name}+{off}s rc {rc1} png {had}")
    if bad:
        return False, "; ".join(bad)
    return True, "; ".join(notes)


@probe("O22-sweep-dask-local-sighup-then-resume")
def _():
    """sweep-cct --scheduler local --workers 2 cut by SIGHUP after its first record: exits
    (rc 129) with no process of its session left, no Dask scratch left in its TMPDIR,
    whole records only; the rerun's records equal an uninterrupted local run's."""
    d = ROOT / "o22"
    d.mkdir()
    tmp = d / "tmp"
    tmp.mkdir()
    base = [
        "sweep-cct",
        "kundur",
        "--faults",
        "DEFAULT",
        "--esd-pct",
        "none,5,10",
        "--tol-ms",
        "20",
    ]
    rc0, o0, e0 = run([*base, "--workers", "1", "--out", "ref.jsonl"], d, 600)
    if rc0 != 0:
        return False, f"reference rc {rc0}"
    ref = essence(records(d / "ref.jsonl"))
    env = dict(ENV, TMPDIR=str(tmp))
    f = open(d / "h.log", "wb")
    p = subprocess.Popen(
        ["stabctl", *base, "--scheduler", "local", "--workers", "2", "--out", "o.jsonl"],
        cwd=d,
        env=env,
        stdout=f,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        start_new_session=True,
        preexec_fn=_dfl,
    )
    p.log = d / "h.log"
    STARTED.append(p)
    t0 = time.time()
    while p.poll() is None and time.time() - t0 < 300:
        if (d / "o.jsonl").exists() and (d / "o.jsonl").read_text().count("\n") >= 1:
            break
        time.sleep(0.05)
    sid = p.pid
    os.kill(p.pid, signal.SIGHUP)  # the main process only, as a closed terminal's shell would
    rc1 = wait_rc(p, 90)
    time.sleep(3)
    left = subprocess.run(
        ["ps", "-o", "pid=,args=", "--sid", str(sid)], capture_output=True, text=True
    ).stdout.strip()
    scratch = sorted(os.listdir(tmp))
    t = text(p)
    stop(p)
    kept = records(d / "o.jsonl") if (d / "o.jsonl").exists() else {}
    raw = (d / "o.jsonl").read_text() if (d / "o.jsonl").exists() else ""
    rc2, o2, e2 = run(
        [*base, "--scheduler", "local", "--workers", "2", "--out", "o.jsonl"], d, 600, env=env
    )
    bad = []
    if tb(t) or tb(e2):
        bad.append("traceback")
    if rc1 not in (129,):
        bad.append(f"SIGHUP rc {rc1}")
    if left:
        bad.append(f"left running: {left[:200]}")
    if scratch:
        bad.append(f"scratch left in TMPDIR: {scratch[:4]}")
    if raw and not raw.endswith("\n"):
        bad.append("half line")
    if rc2 != 0 or essence(records(d / "o.jsonl")) != ref:
        bad.append(f"resume rc {rc2}, records equal {essence(records(d / 'o.jsonl')) == ref}")
    if bad:
        return False, "; ".join(bad) + f" | {t.strip()[-200:]}"
    return True, f"SIGHUP rc {rc1}, kept {len(kept)}, nothing left, resume equal"


def main(argv):
    only = argv[1:]
    shorts = 0
    try:
        for fn in PROBES:
            if only and not any(fn.pid.startswith(x) for x in only):
                continue
            t0 = time.time()
            try:
                ok, why = fn()
            except Exception as exc:  # a probe that could not run is SHORT
                ok, why = False, f"probe error: {type(exc).__name__}: {exc}"
            shorts += not ok
            print(
                f"{fn.pid}: {'ok' if ok else 'SHORT'} ({time.time() - t0:.0f}s) {why}", flush=True
            )
    finally:
        for p in STARTED:
            stop(p)
        if not os.environ.get("KEEP"):
            shutil.rmtree(ROOT, ignore_errors=True)
        else:
            print("kept", ROOT)
    return 1 if shorts else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
