"""Seventh reliability round (round 32, part A): files and the operating system,
concurrency, Dask clusters, C37.118 streams.

Outputs that cannot be written (a full file system, RLIMIT_FSIZE, /dev/full, a read-only
mount), outputs that are inputs under another name (a symbolic or hard link, a ../ path),
odd file names (a newline, bytes that are not UTF-8, a path beyond PATH_MAX, a loop of
links, a leading '-'), TMPDIR, HOME and NUMBA_CACHE_DIR unusable or unsafe; two commands at
once on one file; a Dask scheduler that is not one, a worker killed, interrupted, older,
multi-threaded or with a cold kernel cache, the scheduler killed in mid-sweep; PMU servers
and clients that lie about frame sizes, time stamps and PMU counts, speak HTTP, read
slowly, or come in a hundred at once; ``--allow`` spellings and IPv4-mapped IPv6 peers.

Contract: each probe runs `stabctl` commands in fresh processes (the package of this
repository first on PYTHONPATH) and states what a careful tool does: a failed or refused
command ends with exit status 2 (130 / 143 on SIGINT / SIGTERM), one ``error:`` line naming
the file, option or peer, no traceback, and leaves no file or temporary behind and its
inputs unchanged; a legitimate run exits 0 with whole outputs (records once each).  An
output name that is not UTF-8 is refused (A10b: the refusal is the pass).

    python benchmarks/reliability_probes_7.py [-k SUBSTRING] [--skip-compile] [ID ...]

ID: a prefix of a probe's name (``A10``, ``C0``); -k: a substring of it.  One line per
probe (id, ok or SHORT, why), then the counts.  Needs root (tmpfs mounts for full and
read-only file systems, ``chown nobody``), the ``dask``/``distributed`` and ``pyc37``
packages.  NUMBA_CACHE_DIR is the caller's (numba's default when unset); `stabctl compile`
is run first (seconds with a warm cache).  B03 and C10 compile the kernels into caches of
their own (several CPU-minutes): --skip-compile skips them.  The work directory is a new
temporary directory, removed at the end unless KEEP is set.  About 10 minutes on two cores
with a warm kernel cache (20 with B03 and C10).  Exit status 1 if any probe is short.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import resource
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]  # the package under test
ENV = dict(
    os.environ,
    PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]),
)
ENV.pop("PYTHONWARNINGS", None)
NB = os.environ.get("NUMBA_CACHE_DIR")  # the caller's kernel cache (None: numba's default)
PY = sys.executable
S = [PY, "-m", "stabctl"]
RESULTS: list[tuple[str, bool, str]] = []
PROBES: list = []
STARTED: list[subprocess.Popen] = []
MOUNTS: list[Path] = []
WORK = Path(tempfile.mkdtemp(prefix="stabctl-probes-7."))
D_PSSE = ROOT / "tests" / "data" / "psse"
OPTS = argparse.Namespace(skip_compile=False)


def probe(fn):
    PROBES.append(fn)
    return fn


def _pre():
    for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM, signal.SIGQUIT):
        signal.signal(s, signal.SIG_DFL)


def run(
    args,
    cwd=None,
    env=None,
    timeout=300,
    stdin=subprocess.DEVNULL,
    stdout=subprocess.PIPE,
    fsize=None,
):
    """(rc, stdout, stderr) of a command; fsize: RLIMIT_FSIZE in bytes."""

    def pre():
        _pre()
        if fsize is not None:
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))

    p = subprocess.Popen(
        args,
        cwd=cwd or WORK,
        env=env or ENV,
        stdin=stdin,
        stdout=stdout,
        stderr=subprocess.PIPE,
        preexec_fn=pre,
        start_new_session=True,
    )
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
        err = (err or b"").decode(errors="replace") + "\n[TIMEOUT]"
        return 124, (out or b"").decode(errors="replace"), err
    except BaseException:  # the script ended by a signal (`_terminated`): the command too
        os.killpg(p.pid, signal.SIGKILL)
        raise
    return p.returncode, (out or b"").decode(errors="replace"), err.decode(errors="replace")


def launch(args, cwd=None, env=None, log=None):
    """A background process in its own session, default signal dispositions."""
    with open(log or os.devnull, "wb") as f:  # the child holds its own descriptor
        p = subprocess.Popen(
            args,
            cwd=cwd or WORK,
            env=env or ENV,
            stdin=subprocess.DEVNULL,
            stdout=f,
            stderr=subprocess.STDOUT,
            preexec_fn=_pre,
            start_new_session=True,
        )
    STARTED.append(p)
    return p


def spawn(args, cwd, env=None):
    """A process in its own session whose stdout and stderr are read at its end."""
    return subprocess.Popen(
        args,
        cwd=cwd,
        env=env or ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=_pre,
        start_new_session=True,
    )


def finish(p, timeout):
    """(stdout, stderr as text) of a `spawn`ed process, killed if it outlives timeout."""
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
    return out, err.decode(errors="replace")


def stop(p, sig=signal.SIGTERM, wait=10):
    if p.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, sig)
        try:
            p.wait(wait)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGKILL)
            p.wait()


def error_lines(err):
    return [line for line in err.splitlines() if line.startswith("error:")]


def one_error(rc, err, name=None, code=2):
    """'' if rc == code, exactly one error: line (naming `name`), no traceback; else why."""
    errs = error_lines(err)
    if "Traceback" in err:
        return "traceback: " + err.strip().splitlines()[-1][:160]
    if rc != code:
        return f"exit {rc} (want {code}); stderr: {err.strip()[-200:]!r}"
    if len(errs) != 1:
        return f"{len(errs)} error: lines: {err.strip()[-200:]!r}"
    if name and name not in errs[0]:
        return f"error line does not name {name!r}: {errs[0][:200]}"
    return ""


def leftovers(d: Path, keep=()):
    return sorted(p.name for p in Path(d).iterdir() if p.name not in keep)


def tmpfs(size="64k", inodes=None, ro=False) -> Path:
    d = Path(tempfile.mkdtemp(prefix="mnt-", dir=str(WORK)))
    opts = f"size={size}" + (f",nr_inodes={inodes}" if inodes else "")
    subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(d)], check=True)
    MOUNTS.append(d)
    if ro:
        subprocess.run(["mount", "-o", "remount,ro", str(d)], check=True)
    return d


def fill(d: Path, leave=2048):
    """Fill tmpfs d leaving about `leave` bytes."""
    free = shutil.disk_usage(d).free
    with open(d / "zz_fill", "wb") as f:
        f.write(b"\0" * max(0, free - leave))


def records(path):
    return [json.loads(line) for line in Path(path).read_text().splitlines()]


def result(pid, ok, why):
    RESULTS.append((pid, ok, why))
    print(f"{pid:10s} {'ok' if ok else 'SHORT'}  {why}", flush=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def workdir(name):
    d = WORK / name
    d.mkdir()
    return d


# ---------------------------------------------------------------- fixtures

FIX: dict = {}


def pmu_recording() -> Path:
    """A 181-frame recording of Kundur's fault 3-101 (pmu serve --speed 0 + pmu record)."""
    if "rec" in FIX:
        return FIX["rec"]
    d = WORK / "fix"
    d.mkdir(exist_ok=True)
    log = d / "serve.log"
    srv = launch(
        S + ["pmu", "serve", "kundur", "--fault", "3", "--far-bus", "101", "--speed", "0"]
        + ["--port", "0", "--tf", "3", "--wait", "5"],
        cwd=d,
        log=log,
    )  # fmt: skip
    addr = serve_addr(log, 60)
    if addr is None:
        stop(srv)
        raise RuntimeError(f"pmu serve did not start: {log.read_text()[-200:]!r}")
    rc, _, err = run(
        S + ["pmu", "record", addr, "--frames", "181", "-o", "rec.c37"], cwd=d, timeout=120
    )
    stop(srv)
    if rc != 0:
        raise RuntimeError(f"pmu record of the fixture: exit {rc}: {err[-200:]}")
    FIX["rec"] = d / "rec.c37"
    return FIX["rec"]


def crc16(data: bytes) -> int:
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def seal(body: bytes) -> bytes:
    """A frame from its bytes without CHK: FRAMESIZE set, CRC appended."""
    body = body[:2] + struct.pack(">H", len(body) + 2) + body[4:]
    return body + struct.pack(">H", crc16(body))


def split_frames(data: bytes):
    out, i = [], 0
    while i < len(data):
        n = struct.unpack(">H", data[i + 2 : i + 4])[0]
        out.append(data[i : i + n])
        i += n
    return out


def n_data_frames(path: Path) -> int:
    """The data frames of a recording (its frames but the CFG-2), -1 if there is none."""
    return len(split_frames(path.read_bytes())) - 1 if path.exists() else -1


class _Listener:
    """A TCP server at 127.0.0.1 on a free port: each connection accepted is handed to
    `_serve` (a subclass's) in a thread of its own; `close` ends it and its connections."""

    def __init__(self):
        self.sock = socket.socket()
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(50)
        self.port = self.sock.getsockname()[1]
        self.stopped = False
        self.conns = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self):
        while not self.stopped:
            try:
                c, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(c)
            threading.Thread(target=self._serve, args=(c,), daemon=True).start()

    def _serve(self, c):
        raise NotImplementedError

    def close(self):
        self.stopped = True
        with contextlib.suppress(OSError):
            self.sock.close()
        for c in self.conns:
            with contextlib.suppress(OSError):
                c.close()


class FakePMU(_Listener):
    """A TCP server answering a PDC: on any command frame with CMD 5 sends `cfg`, on CMD 2
    streams `frames` (bytes each, sent as given), then behaves per `after` ('hold': keep the
    connection open, 'close')."""

    def __init__(self, cfg: bytes, frames, after="hold", gap=0.0):
        self.cfg, self.frames, self.after, self.gap = cfg, frames, after, gap
        super().__init__()

    def _serve(self, c):
        try:
            buf = b""
            while not self.stopped:
                chunk = c.recv(4096)
                if not chunk:
                    return
                buf += chunk
                while len(buf) >= 4:
                    n = struct.unpack(">H", buf[2:4])[0]
                    if len(buf) < n:
                        break
                    fr, buf = buf[:n], buf[n:]
                    cmd = struct.unpack(">H", fr[14:16])[0]
                    if cmd == 5:
                        c.sendall(self.cfg)
                    elif cmd == 2:
                        for f in self.frames:
                            c.sendall(f)
                            if self.gap:
                                time.sleep(self.gap)
                        if self.after == "close":
                            c.close()
                            return
        except OSError:
            return


def wait_for(pred, timeout=60, step=0.1):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        v = pred()
        if v:
            return v
        time.sleep(step)
    return None


def serve_addr(log: Path, timeout=120):
    def f():
        t = log.read_text(errors="replace") if log.exists() else ""
        for line in t.splitlines():
            if line.startswith("serving") and " on " in line:
                return line.split(" on ")[1].split()[0]
        return None

    return wait_for(f, timeout)


# ================================================================ A. files and the OS


def _write_fail(pid, args, name, fsize=None, mnt=None, cwd=None, extra_ok=()):
    """A command that writes `name` fails: one error line naming it, exit 2, and no file or
    hidden temporary left in its directory (other than `extra_ok`)."""
    d = Path(cwd or WORK)
    before = set(os.listdir(mnt or d))
    rc, out, err = run(args, cwd=d, fsize=fsize, timeout=300)
    why = one_error(rc, err, name)
    new = set(os.listdir(mnt or d)) - before - set(extra_ok)
    if new:
        why = (why + "; " if why else "") + f"left behind: {sorted(new)}"
    result(pid, not why, why or f"exit 2, one error line naming {name}, nothing left")
    return rc, out, err


@probe
def A01():
    """simulate --out on a 64 KB tmpfs"""
    m = tmpfs("64k")
    _write_fail(
        "A01",
        S + ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--out", f"{m}/x.csv"],
        f"{m}/x.csv",
        mnt=m,
    )


@probe
def A02():
    """simulate --out x.npz past RLIMIT_FSIZE"""
    d = workdir("a02")
    _write_fail(
        "A02",
        S + ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--out", "x.npz"],
        "x.npz",
        fsize=8192,
        cwd=d,
    )


@probe
def A03():
    """simulate --json and cct --json to /dev/full"""
    for pid, args in (
        ("A03a", ["simulate", "kundur", "--tf", "1", "--json"]),
        ("A03b", ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--json"]),
    ):
        with open("/dev/full", "wb") as full:
            rc, _, err = run(S + args, stdout=full)
        why = one_error(rc, err, "standard output")
        result(pid, not why, why or "cannot write to standard output, exit 2")


@probe
def A04():
    """sweep-cct and screen records past RLIMIT_FSIZE in mid-run: whole lines only, the
    error names the file, and the same command afterwards finishes with every key once."""
    for pid, args, n in (
        (
            "A04a",
            ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5"]
            + ["--out", "r.jsonl"],
            4,
        ),
        ("A04b", ["screen", "kundur", "--buses", "3,101,13,4", "--out", "r.jsonl"], 4),
    ):
        d = workdir(pid.lower())
        rc, _, err = run(S + args, cwd=d, fsize=2500)
        why = one_error(rc, err, "r.jsonl")
        try:
            recs = records(d / "r.jsonl")
        except (OSError, ValueError) as exc:
            recs, why = [], why + f"; r.jsonl not whole JSON lines: {exc}"
        rc2, _, err2 = run(S + args, cwd=d)
        try:
            keys = [r["key"] for r in records(d / "r.jsonl")]
        except (OSError, ValueError, KeyError) as exc:
            keys = []
            why += f"; after resume not JSON lines: {exc}"
        if rc2 != 0:
            why += f"; resume exit {rc2}: {err2.strip()[-150:]}"
        if len(keys) != n or len(set(keys)) != n:
            why += f"; after resume {len(keys)} records, {len(set(keys))} keys (want {n})"
        extra = [p for p in leftovers(d) if p != "r.jsonl"]
        if extra:
            why += f"; left: {extra}"
        why = why.strip("; ")
        result(
            pid,
            not why,
            why
            or f"cut at {len(recs)} whole record(s), error names r.jsonl, "
            f"resume completes {n} keys once",
        )


@probe
def A05():
    """estimate track --out and pmu record -o on a full file system and past RLIMIT_FSIZE"""
    rec = pmu_recording()
    m = tmpfs("64k")
    fill(m, 4096)
    track = S + ["estimate", "track", "kundur", "--source", str(rec), "--out"]
    _write_fail("A05a", [*track, f"{m}/t.csv"], f"{m}/t.csv", mnt=m)
    d = workdir("a05")
    _write_fail("A05b", [*track, "t.csv"], "t.csv", fsize=4096, cwd=d)
    # pmu record to a full disk: replay serves the recording
    for pid, kw in (("A05c", {"mnt": m}), ("A05d", {"fsize": 4096})):
        log = WORK / f"{pid}.log"
        srv = launch(
            S + ["pmu", "replay", str(rec), "--speed", "0", "--port", "0", "--wait", "3"], log=log
        )
        addr = serve_addr(log)
        out = f"{m}/r.c37" if pid == "A05c" else "r.c37"
        dd = workdir(pid.lower())
        _write_fail(
            pid,
            S + ["pmu", "record", str(addr), "--frames", "181", "-o", out],
            out,
            cwd=dd,
            fsize=kw.get("fsize"),
            mnt=kw.get("mnt"),
        )
        stop(srv)


@probe
def A06():
    """eig --report and paper --out-dir on a full tmpfs: no half-written report directory"""
    m = tmpfs("160k")
    _write_fail(
        "A06a", S + ["eig", "kundur", "--report", "--out-dir", f"{m}/rep"], f"{m}/rep", mnt=m
    )
    m2 = tmpfs("64k")
    _write_fail(
        "A06b",
        S + ["paper", "--only", "analytic", "--out-dir", f"{m2}/rep"],
        f"{m2}/rep",
        mnt=m2,
    )


@probe
def A07():
    """import-psse / import-andes -o on a full disk"""
    m = tmpfs("64k")
    fill(m, 1024)
    raw = str(D_PSSE / "ieee14_v33.raw")
    for pid, cmd in (("A07a", "import-psse"), ("A07b", "import-andes")):
        _write_fail(pid, S + [cmd, raw, "--static", "-o", f"{m}/c.json"], f"{m}/c.json", mnt=m)


@probe
def A08():
    """read-only output directories (a read-only mount: root ignores mode bits)"""
    m = tmpfs("1m", ro=True)
    rec = pmu_recording()
    cases = [
        ("A08a", ["simulate", "kundur", "--tf", "1", "--out", f"{m}/x.csv"]),
        ("A08b", ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", f"{m}/r.jsonl"]),
        ("A08c", ["eig", "kundur", "--report", "--out-dir", f"{m}/rep"]),
        ("A08d", ["estimate", "track", "kundur", "--source", str(rec), "--out", f"{m}/t.csv"]),
        (
            "A08e",
            ["import-psse", str(D_PSSE / "ieee14_v33.raw"), "--static", "-o", f"{m}/c.json"],
        ),
        ("A08f", ["paper", "--only", "analytic", "--out-dir", str(m)]),
    ]
    for pid, args in cases:
        t0 = time.monotonic()
        rc, _, err = run(S + args)
        why = one_error(rc, err, str(m))
        dt = time.monotonic() - t0
        result(pid, not why, why or f"refused at once ({dt:.1f} s): {error_lines(err)[0][:110]}")


@probe
def A09():
    """an output that is an input under another name: a symbolic link, a ../ path, a hard
    link"""
    d = workdir("a09")
    (d / "sub").mkdir()
    (d / "f.csv").write_text("bus,far_bus\n3,101\n")
    os.symlink("f.csv", d / "r.jsonl")
    os.link(d / "f.csv", d / "h.jsonl")
    rec = pmu_recording()
    shutil.copy(rec, d / "rec.c37")
    os.symlink("rec.c37", d / "t.csv")
    os.link(d / "rec.c37", d / "th.csv")
    case = d / "k.json"
    rc, _, err = run(
        S + ["import-psse", str(D_PSSE / "smib_v33.raw"), str(D_PSSE / "smib.dyr")]
        + ["-o", str(case)]
    )  # fmt: skip
    if rc != 0:
        raise RuntimeError(f"import-psse of the SMIB case: exit {rc}: {err[-200:]}")
    os.link(case, d / "kh.json")
    snap = {p: (d / p).read_bytes() for p in ("f.csv", "rec.c37", "k.json")}
    place = ["place", "k.json", "--faults", "f.csv", "--required-clearing-cycles", "6", "--out"]
    track = ["estimate", "track", "kundur", "--source"]
    cases = [
        ("A09a", ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "r.jsonl"]),
        ("A09b", ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "h.jsonl"]),
        ("A09c", [*track, "rec.c37", "--out", "t.csv"]),
        ("A09d", [*track, "sub/../rec.c37", "--out", "th.csv"]),
        ("A09e", [*place, "sub/../k.json"]),
        ("A09f", [*place, "kh.json"]),
        ("A09g", ["import-andes", "k.json", "-o", "kh.json"]),
    ]
    for pid, args in cases:
        rc, _, err = run(S + args, cwd=d, timeout=200)
        changed = [p for p in snap if (d / p).read_bytes() != snap[p]]
        for p in changed:  # restore for the next case
            (d / p).write_bytes(snap[p])
        why = "" if rc == 2 and "Traceback" not in err else f"exit {rc}: {err.strip()[-160:]!r}"
        if changed:
            why = (why + "; " if why else "") + f"INPUT OVERWRITTEN: {changed}"
        result(pid, not why, why or f"refused: {(error_lines(err) or [''])[0][:120]}")


@probe
def A10():
    """odd input names: a newline, non-UTF-8 bytes, a 4096+ byte path, a leading '-',
    a loop of links; the text and JSON that name them.  A10b: an --out name of bytes that
    are not UTF-8 is refused (exit 2, one error line saying "not UTF-8", no output): the
    refusal is the pass (it reached --json's 'files' as a lone surrogate before)."""
    d = workdir("a10")
    run(
        S + ["import-psse", str(D_PSSE / "smib_v33.raw"), str(D_PSSE / "smib.dyr")]
        + ["-o", "s.json"],
        cwd=d,
    )  # fmt: skip
    src = (d / "s.json").read_bytes()
    # a) newline in the output name: the 'wrote' line
    (d / "n\nl.json").write_bytes(src)
    rc, out, _ = run(S + ["simulate", "n\nl.json", "--tf", "0.5", "--out", "o\nut.csv"], cwd=d)
    wrote = [line for line in out.splitlines() if line.startswith("wrote")]
    split = rc == 0 and wrote and wrote[-1] == "wrote o"
    result(
        "A10a",
        not split,
        "the 'wrote' line is cut in two by the newline of the file name "
        "('wrote o' / 'ut.csv'); error lines escape it"
        if split
        else f"exit {rc}: {wrote}",
    )
    # b) a non-UTF-8 output name: refused before the run
    with open(os.fsencode(d) + b"/\xff.json", "wb") as f:
        f.write(src)
    before = set(os.listdir(os.fsencode(d)))
    args = [b"simulate", b"\xff.json", b"--tf", b"0.5", b"--out", b"\xffo.csv", b"--json"]
    rc, _, err = run([os.fsencode(a) for a in S] + args, cwd=d)
    why = one_error(rc, err, "not UTF-8")
    new = set(os.listdir(os.fsencode(d))) - before
    if new:
        why = (why + "; " if why else "") + f"left behind: {sorted(new)}"
    result("A10b", not why, why or f"refused: {error_lines(err)[0][:120]}")
    # c) a path longer than PATH_MAX
    deep = d
    while len(str(deep)) < 4200:
        deep = deep / ("x" * 200)
    with contextlib.suppress(OSError):
        os.makedirs(deep)
    long_out = str(deep / "o.csv")
    rc, _, err = run(S + ["simulate", "kundur", "--tf", "0.5", "--out", long_out], cwd=d)
    why = one_error(rc, err)
    result(
        "A10c",
        not why,
        why or f"refused: {error_lines(err)[0][:60]}...{error_lines(err)[0][-60:]}",
    )
    # d) a symbolic link loop as the case
    os.symlink("l2.json", d / "l1.json")
    os.symlink("l1.json", d / "l2.json")
    rc, _, err = run(S + ["simulate", "l1.json"], cwd=d)
    why = one_error(rc, err, "l1.json")
    if not why and "not found" in err:
        why = (
            "a loop of links called 'not found' (the --faults option says 'Too many levels "
            f"of symbolic links'): {error_lines(err)[0]}"
        )
    result("A10d", not why, why or error_lines(err)[0])
    # e) leading '-' names: a case file '-k.json' after --
    (d / "-k.json").write_bytes(src)
    rc, _, err = run(S + ["simulate", "--tf", "0.5", "--", "-k.json"], cwd=d)
    result("A10e", rc == 0, f"'-- -k.json' read (exit {rc})" + ("" if rc == 0 else err[-150:]))


@probe
def A11():
    """TMPDIR unwritable (read-only mount) or a file, HOME unset: sweeps on local processes
    and a local Dask cluster still run, and leave no scratch"""
    ro = tmpfs("1m", ro=True)
    d = workdir("a11")
    (d / "afile").write_text("x")
    for pid, tmp, extra in (
        ("A11a", str(ro), ["--scheduler", "local", "--workers", "2"]),
        ("A11b", str(d / "afile"), ["--workers", "2"]),
    ):
        env = dict(ENV, TMPDIR=tmp)
        env.pop("HOME", None)
        args = ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", f"{pid}.jsonl", *extra]
        rc, _, err = run(S + args, cwd=d, env=env, timeout=300)
        why = "" if rc == 0 and "Traceback" not in err else f"exit {rc}: {err.strip()[-200:]!r}"
        result(pid, not why, why or "ran, 2 jobs")


@probe
def A12():
    """NUMBA_CACHE_DIR a file / world-writable / another user's: one error, or a warning and
    the kernels cached privately"""
    d = workdir("a12")
    (d / "f").write_text("x")
    sim = S + ["simulate", "kundur", "--tf", "0.2"]
    rc, _, err = run(sim, env=dict(ENV, NUMBA_CACHE_DIR=str(d / "f")))
    why = one_error(rc, err, "NUMBA_CACHE_DIR")
    result("A12a", not why, why or error_lines(err)[0][:120])
    for pid, how in (("A12b", "ww"), ("A12c", "nobody")):
        c = d / how
        if NB and Path(NB).is_dir():  # a copy of the caller's cache (it is not used)
            shutil.copytree(NB, c)
        else:
            c.mkdir()
        if how == "ww":
            os.chmod(c, 0o777)
        else:
            subprocess.run(["chown", "-R", "nobody", str(c)], check=True)
        rc, _, err = run(sim, env=dict(ENV, NUMBA_CACHE_DIR=str(c)), timeout=600)
        ok = rc == 0 and "warning: numba cache" in err and "Traceback" not in err
        said = [line for line in err.splitlines() if "numba cache" in line]
        result(
            pid,
            ok,
            ("warned, cached privately: " + said[0][:110]) if ok else f"exit {rc}: {err[-200:]!r}",
        )


@probe
def A13():
    """pmu record -o an existing file on a nearly full disk while the stream stops early:
    the partial recording cannot be written beside it: one error line saying both, the
    existing file untouched, no temporary left"""
    cfg, frames = rec_frames()
    m = tmpfs("64k")
    (m / "r.c37").write_bytes(b"old recording")
    fill(m, 600)
    srv = FakePMU(cfg, frames[:60], after="close")
    before = set(os.listdir(m))
    rc, _, err = run(
        S + ["pmu", "record", f"127.0.0.1:{srv.port}", "--frames", "181", "-o", str(m / "r.c37")],
        timeout=120,
    )
    srv.close()
    why = one_error(rc, err)
    new = set(os.listdir(m)) - before
    if new:
        why += f"; left {sorted(new)}"
    if (m / "r.c37").read_bytes() != b"old recording":
        why += "; the existing file changed"
    why = why.strip("; ")
    result("A13", not why, why or " / ".join(error_lines(err))[:200])
    # estimate track likewise
    srv = FakePMU(cfg, frames[:60], after="close")
    (m / "zz_fill").unlink()
    (m / "t.csv").write_text("old")
    fill(m, 600)
    before = set(os.listdir(m))
    rc, _, err = run(
        S + ["estimate", "track", "kundur", "--source", f"tcp://127.0.0.1:{srv.port}"]
        + ["--frames", "181", "--out", str(m / "t.csv")],
        timeout=120,
    )  # fmt: skip
    srv.close()
    why = one_error(rc, err)
    new = set(os.listdir(m)) - before
    if new:
        why += f"; left {sorted(new)}"
    if (m / "t.csv").read_text() != "old":
        why += "; the existing file changed"
    why = why.strip("; ")
    result("A13b", not why, why or " / ".join(error_lines(err))[:200])


@probe
def A14():
    """place --out past RLIMIT_FSIZE and on a full disk"""
    d = workdir("a14")
    (d / "f.csv").write_text("bus,far_bus\n3,101\n")
    base = S + ["place", "kundur", "--faults", "f.csv", "--required-clearing-cycles", "12"]
    base += ["--workers", "2"]
    _write_fail("A14a", [*base, "--out", "p.json"], "p.json", fsize=512, cwd=d)
    m = tmpfs("64k")
    fill(m, 300)
    _write_fail("A14b", [*base, "--out", f"{m}/p.json"], f"{m}/p.json", cwd=d, mnt=m)


@probe
def A15():
    """an unsafe kernel cache (NUMBA_CACHE_DIR=/tmp-like world-writable dir; or a
    group-writable package __pycache__, an install under umask 002) with a HOME whose
    ~/.cache cannot be made (read-only home, as in containers and batch jobs): stabctl
    moves the cache to ~/.cache/stabctl-numba; no command, --version and --help included,
    may die with a traceback"""
    ro = tmpfs("1m", ro=True)
    ww = workdir("a15ww")
    os.chmod(ww, 0o1777)
    d = workdir("a15")
    (d / "afile").write_text("x")
    for pid, env, args in (
        ("A15a", dict(ENV, HOME=str(ro), NUMBA_CACHE_DIR=str(ww)), ["--version"]),
        (
            "A15b",
            dict(ENV, HOME=str(ro), NUMBA_CACHE_DIR=str(ww)),
            ["simulate", "kundur", "--tf", "0.2"],
        ),
        ("A15c", dict(ENV, XDG_CACHE_HOME=str(d / "afile"), NUMBA_CACHE_DIR=str(ww)), ["cases"]),
    ):
        rc, _, err = run(S + args, env=env, cwd=d)
        bad = "Traceback" in err or rc not in (0, 2)
        said = error_lines(err) or [line for line in err.splitlines() if "warning" in line]
        result(
            pid,
            not bad,
            f"exit {rc}, traceback ending {err.strip().splitlines()[-1][:120]!r}"
            if bad
            else f"exit {rc}: {(said or [''])[0][:120]}",
        )
    # the same with NUMBA_CACHE_DIR unset and a group-writable __pycache__ of the package
    # (its mode put back at once)
    pc = ROOT / "stabctl" / "dynamics" / "__pycache__"
    if not pc.is_dir():
        result("A15d", True, f"skipped: no {pc}")
        return
    mode = pc.stat().st_mode
    os.chmod(pc, mode | 0o020)
    try:
        env = dict(ENV, HOME=str(ro))
        env.pop("NUMBA_CACHE_DIR", None)
        rc, _, err = run(S + ["--version"], env=env, cwd=d)
    finally:
        os.chmod(pc, mode)
    bad = "Traceback" in err or rc not in (0, 2)
    result(
        "A15d",
        not bad,
        (
            f"group-writable __pycache__: exit {rc}, traceback ending "
            f"{err.strip().splitlines()[-1][:100]!r}"
        )
        if bad
        else f"exit {rc}",
    )


@probe
def A16():
    """simulate --out x.csv --plot x.png where the CSV write fails (RLIMIT_FSIZE between the
    two files' sizes): exit 2, and the command leaves no output of the failed run"""
    d = workdir("a16")
    rc, _, err = run(
        S + ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--tf", "1.2"]
        + ["--out", "x.csv", "--plot", "x.png"],
        cwd=d,
        fsize=100 * 1024,
    )  # fmt: skip
    left = leftovers(d)
    why = one_error(rc, err, "x.csv")
    if left:
        why += ("; " if why else "") + (
            f"the failed run left {left} (written before the CSV failed; "
            "a script testing for the figure takes the run for done)"
        )
    result("A16", not why, why or "exit 2, nothing left")


@probe
def A17():
    """a records file with a cut last line, repaired on a resume whose rewrite fails
    (RLIMIT_FSIZE): the cut line is in <out>.damaged and still in <out>; the next resume
    appends it to <out>.damaged again"""
    d = workdir("a17")
    args = ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5,10"]
    args += ["--out", "r.jsonl", "--workers", "1"]
    run(S + args, cwd=d)
    data = (d / "r.jsonl").read_bytes()
    lines = data.splitlines(keepends=True)
    cut = b"".join(lines[:2]) + lines[2][: len(lines[2]) // 2]
    (d / "r.jsonl").write_bytes(cut)
    rc1, _, err1 = run(S + args, cwd=d, fsize=len(cut) - 200)
    rc2, _, _ = run(S + args, cwd=d)
    damaged = d / "r.jsonl.damaged"
    dam = damaged.read_bytes().splitlines() if damaged.exists() else []
    why = ""
    if len(dam) != 1:
        why = (
            f"<out>.damaged holds the one cut line {len(dam)} times after a failed repair and "
            f"a resume (exit {rc1}: {(error_lines(err1) or [''])[0][:60]}; then exit {rc2})"
        )
    result("A17", not why, why or f"one line aside; exits {rc1}, {rc2}")


# ================================================================ B. concurrency


@probe
def B01():
    """two sweeps at once on one records file, under two names (a hard link), and a screen
    beside a sweep-cct on the same file: one runs, the other is refused at once; no
    duplicate"""
    d = workdir("b01")
    run(
        S + ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", "a.jsonl", "--workers", "1"],
        cwd=d,
    )
    os.link(d / "a.jsonl", d / "b.jsonl")
    args = ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5,10"]
    args += ["--workers", "1"]
    p1 = launch(S + [*args, "--out", "a.jsonl"], cwd=d, log=d / "l1")
    p2 = launch(
        S + ["screen", "kundur", "--buses", "3,4", "--out", "b.jsonl", "--workers", "1"],
        cwd=d,
        log=d / "l2",
    )
    p1.wait(300)
    p2.wait(300)
    keys = [r["key"] for r in records(d / "a.jsonl")]
    t2 = (d / "l2").read_text()
    why = ""
    if len(keys) != len(set(keys)):
        why += f"duplicate keys {len(keys)} lines / {len(set(keys))} keys; "
    exits = [p1.returncode, p2.returncode]
    if sorted(exits) != [0, 2] and exits != [0, 0]:
        why += f"exits {p1.returncode}, {p2.returncode}; "
    said = [line for line in t2.splitlines() if line.startswith("error")][:1]
    result(
        "B01",
        not why,
        why or f"exits {p1.returncode}, {p2.returncode}; {len(keys)} unique records; {said}",
    )


@probe
def B02():
    """simulate --out x.csv twice at once: both end 0, x.csv one whole run, no temporary
    left"""
    d = workdir("b02")
    ps = [
        launch(
            S + ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--tf", str(tf)]
            + ["--out", "x.csv"],
            cwd=d,
            log=d / f"l{i}",
        )
        for i, tf in enumerate((3, 4))
    ]  # fmt: skip
    for p in ps:
        p.wait(300)
    rows = (d / "x.csv").read_text().splitlines()
    rest = leftovers(d, keep=("x.csv", "l0", "l1"))
    last_t = float(rows[-1].split(",")[0])
    ok = [p.returncode for p in ps] == [0, 0] and not rest and last_t in (3.0, 4.0)
    result("B02", ok, f"exits {[p.returncode for p in ps]}, x.csv ends at t={last_t}, left {rest}")


@probe
def B03():
    """two `stabctl compile` at once on one empty NUMBA_CACHE_DIR (slow: ~3 CPU-min each)"""
    if OPTS.skip_compile:
        result("B03", True, "skipped (--skip-compile)")
        return
    d = workdir("b03")
    c = d / "nb"
    c.mkdir(mode=0o700)
    env = dict(ENV, NUMBA_CACHE_DIR=str(c))
    ps = [launch(S + ["compile"], cwd=d, env=env, log=d / f"l{i}") for i in range(2)]
    for p in ps:
        try:
            p.wait(900)
        except subprocess.TimeoutExpired:
            stop(p)
    logs = [(d / f"l{i}").read_text() for i in range(2)]
    rc, _, err = run(S + ["simulate", "kundur", "--tf", "0.2"], cwd=d, env=env, timeout=120)
    why = ""
    if [p.returncode for p in ps] != [0, 0]:
        why += f"exits {[p.returncode for p in ps]}: {[x[-200:] for x in logs]}; "
    if any("Traceback" in x for x in logs):
        why += "traceback in a compile's output; "
    if rc != 0 or "compiling" in err:
        why += f"a later run did not load the cache (exit {rc}, {err[-120:]!r}); "
    result("B03", not why, why or "both compiles exit 0, a later run loads the cache")


@probe
def B04():
    """a hard link made to a records file while its sweep runs (the file new at its start),
    a second sweep on the link: refused, or no job recorded twice"""
    d = workdir("b04")
    args = ["sweep-cct", "miniwecc", "--faults", "DEFAULT", "--esd-pct", "none,5,10"]
    args += ["--workers", "1"]
    p1 = launch(S + [*args, "--out", "a.jsonl"], cwd=d, log=d / "l1")
    wait_for(lambda: (d / "a.jsonl").exists(), 300, 0.05)
    os.link(d / "a.jsonl", d / "b.jsonl")
    p2 = launch(S + [*args, "--out", "b.jsonl"], cwd=d, log=d / "l2")
    p1.wait(600)
    p2.wait(600)
    keys = [r["key"] for r in records(d / "a.jsonl")]
    dup = len(keys) - len(set(keys))
    why = ""
    if dup:
        why = (
            f"both ran (exits {p1.returncode}, {p2.returncode}) and appended to one file: "
            f"{len(keys)} records, {dup} job(s) recorded twice; the lock of the file itself "
            "is taken only when it exists at the start"
        )
    result(
        "B04",
        not why,
        why or f"exits {p1.returncode}, {p2.returncode}; {len(keys)} records, none twice",
    )


# ================================================================ C. Dask


class FakeServer(_Listener):
    """A TCP server at 127.0.0.1:port: 'http' answers an HTTP 400-ish line, 'echo' echoes,
    'hangup' accepts and closes at once, 'silent' accepts and says nothing."""

    def __init__(self, kind):
        self.kind = kind
        super().__init__()

    def _serve(self, c):
        if self.kind == "hangup":
            c.close()
            return
        try:
            while True:
                b = c.recv(65536)
                if not b:
                    return
                if self.kind == "echo":
                    c.sendall(b)
                elif self.kind == "http":
                    c.sendall(b"HTTP/1.0 400 Bad Request\r\nContent-Length: 0\r\n\r\n")
                    c.close()
                    return
        except OSError:
            return


def _can_connect(port):
    try:
        socket.create_connection(("127.0.0.1", port), 1).close()
    except OSError:
        return False
    return True


def dask_cluster(d: Path, n_workers=2, worker_env=None, sched_env=None):
    """A `dask scheduler` and n `dask worker`s (separate processes of this Python)."""
    port = free_port()
    sched = launch(
        [PY, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", str(port)]
        + ["--dashboard-address", ":0"],
        cwd=d,
        env=sched_env or ENV,
        log=d / "sched.log",
    )  # fmt: skip
    wait_for(lambda: _can_connect(port), 60)
    addr = f"tcp://127.0.0.1:{port}"
    workers = []
    for i in range(n_workers):
        env = worker_env[i] if worker_env else ENV
        w = launch(
            [PY, "-m", "distributed.cli.dask_worker", addr, "--nthreads", "1", "--nworkers", "1"]
            + ["--no-nanny", "--name", f"w{i}"],
            cwd=d,
            env=env,
            log=d / f"worker{i}.log",
        )  # fmt: skip
        workers.append(w)
    wait_for(
        lambda: all(
            "Registered to" in (d / f"worker{i}.log").read_text(errors="replace")
            for i in range(n_workers)
        ),
        120,
    )
    return addr, sched, workers


def check_records(path, n):
    recs = records(path)
    keys = [r["key"] for r in recs]
    why = ""
    if len(keys) != len(set(keys)):
        why += f"{len(keys) - len(set(keys))} duplicate record(s); "
    if len(set(keys)) != n:
        why += f"{len(set(keys))} keys, want {n}; "
    failed = [r["key"] for r in recs if r.get("status") == "failed"]
    if failed:
        why += f"failed: {failed}; "
    return why, recs


@probe
def C01():
    """--scheduler at an HTTP server (python -m http.server), an echo server, one that
    accepts and hangs up, one that accepts and is silent: one error line within ~15 s"""
    d = workdir("c01")
    port = free_port()
    http = launch(
        [PY, "-m", "http.server", str(port), "--bind", "127.0.0.1"], cwd=d, log=d / "http.log"
    )
    wait_for(lambda: _can_connect(port), 20)
    servers = [("C01a", None, port)] + [
        (f"C01{x}", FakeServer(k), None)
        for x, k in (("b", "echo"), ("c", "hangup"), ("d", "silent"))
    ]
    for pid, srv, p0 in servers:
        p = p0 or srv.port
        t0 = time.monotonic()
        rc, _, err = run(
            S + ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", f"{pid}.jsonl"]
            + ["--scheduler", f"tcp://127.0.0.1:{p}"],
            cwd=d,
            timeout=120,
        )  # fmt: skip
        dt = time.monotonic() - t0
        why = one_error(rc, err, f"127.0.0.1:{p}")
        if not why and dt > 25:
            why = f"took {dt:.0f} s"
        if (d / f"{pid}.jsonl").exists():
            why += "; a records file was made"
        result(pid, not why, why or f"{dt:.0f} s: {error_lines(err)[0][:120]}")
        if srv:
            srv.close()
    stop(http)


@probe
def C02():
    """a Dask worker killed with SIGKILL in mid-job (scheduler and workers started apart):
    the job runs again elsewhere, recorded once, every record there"""
    d = workdir("c02")
    addr, sched, workers = dask_cluster(d, 2)
    buses = "83,40,33,44,10,20,30,50"
    args = S + ["screen", "miniwecc", "--buses", buses, "--out", "r.jsonl", "--scheduler", addr]
    p = launch(args, cwd=d, log=d / "sweep.log")
    # kill worker 0 once the first record is in: it is then in the middle of its next job
    wait_for(
        lambda: (d / "r.jsonl").exists() and (d / "r.jsonl").read_text().count("\n") >= 1,
        300,
        0.05,
    )
    time.sleep(0.3)
    busy = p.poll() is None
    os.kill(workers[0].pid, signal.SIGKILL)
    # a replacement worker joins
    w = launch(
        [PY, "-m", "distributed.cli.dask_worker", addr, "--nthreads", "1", "--no-nanny"]
        + ["--name", "w9"],
        cwd=d,
        log=d / "worker9.log",
    )  # fmt: skip
    try:
        p.wait(600)
    except subprocess.TimeoutExpired:
        stop(p)
    log = (d / "sweep.log").read_text(errors="replace")
    why = "" if p.returncode == 0 else f"exit {p.returncode}: {log.strip()[-200:]!r}; "
    if "Traceback" in log:
        why += "traceback; "
    if (d / "r.jsonl").exists():
        why += check_records(d / "r.jsonl", 8)[0]
    else:
        why += "no records; "
    if not busy:
        why += "(the sweep had ended before the kill: probe void); "
    for x in [w, *workers, sched]:
        stop(x)
    result(
        "C02", not why, why or "exit 0, 8 records once each after a worker's SIGKILL in mid-sweep"
    )


@probe
def C03():
    """SIGINT to a Dask sweep in mid-run, then the same command: no repeats, no loss, the
    counts of its last line right"""
    d = workdir("c03")
    addr, sched, workers = dask_cluster(d, 2)
    args = S + ["sweep-cct", "miniwecc", "--faults", "DEFAULT", "--esd-pct", "none,5,10"]
    args += ["--out", "r.jsonl", "--scheduler", addr]
    p = launch(args, cwd=d, log=d / "s1.log")
    wait_for(
        lambda: (d / "r.jsonl").exists() and len((d / "r.jsonl").read_text().splitlines()) >= 1,
        400,
        0.2,
    )
    os.killpg(p.pid, signal.SIGINT)
    try:
        p.wait(120)
    except subprocess.TimeoutExpired:
        stop(p)
    log1 = (d / "s1.log").read_text(errors="replace")
    n1 = len(records(d / "r.jsonl")) if (d / "r.jsonl").exists() else 0
    rc, out, err = run(args, cwd=d, timeout=600)
    why = ""
    if p.returncode != 130:
        why += f"first exit {p.returncode}; "
    if "Traceback" in log1 + err:
        why += "traceback; "
    if rc != 0:
        why += f"resume exit {rc}: {err[-150:]!r}; "
    why += check_records(d / "r.jsonl", 6)[0]
    last = [line for line in out.splitlines() if "job(s):" in line]
    want = f"{6 - n1} run now, {n1} already in"
    if not last or want not in last[-1]:
        why += f"last line {last[-1:]} (want '{want}'); "
    for x in [*workers, sched]:
        stop(x)
    result(
        "C03",
        not why,
        why or f"interrupted at {n1} record(s) (exit 130), resume: {last[-1][:90]}",
    )


@probe
def C04():
    """a worker that runs an older stabctl (the tree of HEAD~30, exported with git
    archive): the command stops naming the worker and both digests; no records of the
    older version"""
    d = workdir("c04")
    old = workdir("old")
    with subprocess.Popen(
        ["git", "-C", str(ROOT), "archive", "--format=tar", "HEAD~30"], stdout=subprocess.PIPE
    ) as git:
        subprocess.run(["tar", "-x", "-C", str(old)], stdin=git.stdout, check=True)
    if git.returncode != 0:
        raise RuntimeError(f"git archive HEAD~30 exit {git.returncode}")
    envs = [ENV, dict(ENV, PYTHONPATH=str(old))]
    addr, sched, workers = dask_cluster(d, 2, worker_env=envs)
    # only the old worker first: the other stopped
    stop(workers[0])
    rc, _, err = run(
        S + ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", "r.jsonl"]
        + ["--scheduler", addr],
        cwd=d,
        timeout=300,
    )  # fmt: skip
    why = one_error(rc, err)
    if not why and "digest" not in err and "stabctl" not in error_lines(err)[0]:
        why = "error does not name the version: " + error_lines(err)[0]
    if (d / "r.jsonl").exists():
        why += f"; records written: {len(records(d / 'r.jsonl'))}"
    for x in [*workers, sched]:
        stop(x)
    result("C04", not why, why or error_lines(err)[0][:160])


@probe
def C05():
    """two Dask workers with different NUMBA_CACHE_DIRs (one a file, one fine): the sweep
    runs or names the worker's problem; no job recorded failed for it silently"""
    d = workdir("c05")
    (d / "afile").write_text("x")
    envs = [ENV, dict(ENV, NUMBA_CACHE_DIR=str(d / "afile"))]
    addr, sched, workers = dask_cluster(d, 2, worker_env=envs)
    rc, _, err = run(
        S + ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5"]
        + ["--out", "r.jsonl", "--scheduler", addr],
        cwd=d,
        timeout=400,
    )  # fmt: skip
    why = ""
    if "Traceback" in err:
        why += "traceback; "
    if rc == 0:
        why += check_records(d / "r.jsonl", 4)[0]
        msg = "exit 0, 4 records"
    else:
        e = error_lines(err)
        msg = f"exit {rc}: {e[:1]}"
        if rc != 2 or len(e) != 1:
            why += msg
    for x in [*workers, sched]:
        stop(x)
    result("C05", not why, why or msg)


@probe
def C06():
    """Ctrl-C (SIGINT) and SIGTERM while the command waits for a silent 'scheduler' (a peer
    that accepts and says nothing): exit 130 / 143 within 3 s, one 'interrupted:' line"""
    d = workdir("c06")
    srv = FakeServer("silent")
    for pid, sig, want in (("C06a", signal.SIGINT, 130), ("C06b", signal.SIGTERM, 143)):
        p = spawn(
            S + ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", f"{pid}.jsonl"]
            + ["--scheduler", f"tcp://127.0.0.1:{srv.port}"],
            cwd=d,
        )  # fmt: skip
        time.sleep(4)
        t0 = time.monotonic()
        os.killpg(p.pid, sig)
        _, err = finish(p, 30)
        dt = time.monotonic() - t0
        lines = [line for line in err.splitlines() if line.startswith("interrupted")]
        why = ""
        if p.returncode != want:
            why += f"exit {p.returncode} (want {want}); "
        if dt > 3:
            why += f"took {dt:.1f} s; "
        if "Traceback" in err:
            why += "traceback; "
        if len(lines) != 1:
            why += f"{len(lines)} interrupted lines: {err.strip()[-200:]!r}"
        result(pid, not why, why or f"{dt:.1f} s: {lines[0][:120]}")
    srv.close()


def _ccts(path):
    out = {}
    for r in records(path):
        res = r.get("result") or {}
        out[r["key"]] = (
            r.get("status"),
            res.get("cct_s"),
            res.get("bracket_s") or res.get("bracket"),
            res.get("numerical_error_s"),
            r.get("verdict") or res.get("verdict"),
        )
    return out


@probe
def C07():
    """a Dask worker started without --nthreads 1 (two threads: two jobs at once in one
    process): the results equal those of local processes, or the worker is refused"""
    d = workdir("c07")
    buses = "83,40,33,44,10,20,30,50,118,2"
    screen = S + ["screen", "miniwecc", "--buses", buses, "--out"]
    rc, _, _ = run([*screen, "ref.jsonl", "--workers", "2"], cwd=d, timeout=600)
    port = free_port()
    sched = launch(
        [PY, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", str(port)]
        + ["--dashboard-address", ":0"],
        cwd=d,
        log=d / "sched.log",
    )  # fmt: skip
    wait_for(lambda: _can_connect(port), 60)
    w = launch(
        [PY, "-m", "distributed.cli.dask_worker", f"tcp://127.0.0.1:{port}"]
        + ["--nthreads", "2", "--no-nanny"],
        cwd=d,
        log=d / "worker.log",
    )  # fmt: skip
    wait_for(lambda: "Registered to" in (d / "worker.log").read_text(errors="replace"), 120)
    rc2, _, err2 = run(
        [*screen, "thr.jsonl", "--scheduler", f"tcp://127.0.0.1:{port}"], cwd=d, timeout=600
    )
    stop(w)
    stop(sched)
    if rc2 == 2 and len(error_lines(err2)) == 1:
        result("C07", True, "refused: " + error_lines(err2)[0][:120])
        return
    a, b = _ccts(d / "ref.jsonl"), _ccts(d / "thr.jsonl")
    diff = [k for k in a if a[k] != b.get(k)]
    why = ""
    if rc2 != rc:
        why += f"exit {rc2} (local {rc}): {err2.strip()[-150:]!r}; "
    if diff:
        why += f"{len(diff)} of {len(a)} results differ, e.g. {diff[0]}: {a[diff[0]]} vs "
        why += f"{b.get(diff[0])}"
    result("C07", not why, why or f"{len(a)} results equal to local processes'")


@probe
def C08():
    """the Dask scheduler killed (SIGKILL) in mid-sweep, at several moments: each time exit 2
    and the sweep's own message (jobs not run, records kept, the same command runs the rest),
    the finished records whole; the same command on a new cluster completes, none twice"""
    raw = []
    delays = (0.0, 1.0, 0.8, 1.2, 0.6, 1.4, 0.9, 1.1, 0.7, 1.3, 0.5, 2.0)
    tried = 0
    for i, delay in enumerate(delays):
        if raw and i > 0:
            break
        tried += 1
        d = workdir(f"c08-{i}")
        addr, sched, workers = dask_cluster(d, 2)
        buses = "83,40,33,44,10,20,30,50,118,2,3,4"
        base = S + ["screen", "miniwecc", "--buses", buses, "--out", "r.jsonl", "--scheduler"]
        p = spawn([*base, addr], cwd=d)
        wait_for(lambda d=d: (d / "r.jsonl").exists(), 300, 0.05)
        time.sleep(delay)
        os.kill(sched.pid, signal.SIGKILL)
        _, err = finish(p, 200)
        for w in workers:
            stop(w)
        e = error_lines(err)
        if p.returncode == 2 and len(e) == 1 and "jobs not run" not in e[0]:
            raw.append(f"kill {delay} s after the first record: {e[0][:150]}")
        elif one_error(p.returncode, err) and p.returncode != 0:
            raw.append(f"kill at {delay} s: {one_error(p.returncode, err)}")
        if i == 0:
            addr2, sched2, workers2 = dask_cluster(d, 2)
            rc, _, _ = run([*base, addr2], cwd=d, timeout=600)
            for x in [*workers2, sched2]:
                stop(x)
            w2, _ = check_records(d / "r.jsonl", 12)
            if w2 or rc != 0:
                raw.append(f"resume: exit {rc}, {w2}")
    why = "; ".join(raw)
    if why:
        why = (
            f"{len(raw)} of {tried} kills: {why} (not the sweep's 'N of M jobs not run ... the "
            "same command runs the rest'; stabctl/parallel.py _DaskWorkers.ask catches "
            "TimeoutError only)"
        )
    result(
        "C08",
        not why,
        why
        or f"{tried} kills: each 'N of 12 jobs not run ... runs the rest', exit 2; "
        "resume completed 12 once",
    )


@probe
def C09():
    """SIGINT to a `--scheduler local` sweep in mid-run: exit 130, and no stabctl-dask-*
    scratch left in TMPDIR, no worker process left"""
    d = workdir("c09")
    tmp = d / "tmp"
    tmp.mkdir()
    p = spawn(
        S + ["screen", "miniwecc", "--buses", "83,40,33,44,10,20,30,50", "--out", "r.jsonl"]
        + ["--scheduler", "local", "--workers", "2"],
        cwd=d,
        env=dict(ENV, TMPDIR=str(tmp)),
    )  # fmt: skip
    wait_for(lambda: (d / "r.jsonl").exists(), 300, 0.05)
    os.killpg(p.pid, signal.SIGINT)
    _, err = finish(p, 60)
    time.sleep(2)
    left = list(tmp.iterdir())
    procs = subprocess.run(
        ["pgrep", "-s", str(p.pid)], capture_output=True, text=True, check=False
    ).stdout.split()
    why = ""
    if p.returncode != 130:
        why += f"exit {p.returncode}; "
    if "Traceback" in err:
        why += "traceback; "
    if left:
        why += f"left in TMPDIR: {[x.name for x in left]}; "
    if procs:
        why += f"processes left in its session: {procs}; "
        for pid in procs:  # the session of the command this probe started
            with contextlib.suppress(ProcessLookupError):
                os.kill(int(pid), signal.SIGKILL)
    result("C09", not why, why or "exit 130, TMPDIR empty, no process left")


@probe
def C10():
    """a Dask worker with an empty NUMBA_CACHE_DIR beside one with a warm cache (slow: the
    cold worker compiles for minutes inside its first job): the sweep completes, every job
    once, no false 'silent worker' or lost job"""
    if OPTS.skip_compile:
        result("C10", True, "skipped (--skip-compile)")
        return
    d = workdir("c10")
    cold = d / "nb"
    cold.mkdir(mode=0o700)
    addr, sched, workers = dask_cluster(
        d, 2, worker_env=[ENV, dict(ENV, NUMBA_CACHE_DIR=str(cold))]
    )
    t0 = time.monotonic()
    rc, _, err = run(
        S + ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5,10"]
        + ["--out", "r.jsonl", "--scheduler", addr],
        cwd=d,
        timeout=900,
    )  # fmt: skip
    dt = time.monotonic() - t0
    for x in [*workers, sched]:
        stop(x)
    why = "" if rc == 0 else f"exit {rc}: {err.strip()[-200:]!r}; "
    w2, recs = check_records(d / "r.jsonl", 6)
    why += w2
    warns = [line for line in err.splitlines() if line.startswith("warning")]
    by = sorted({r["worker"] for r in recs})
    result(
        "C10",
        not why,
        why or f"{dt:.0f} s, 6 records once, by {len(by)} worker(s); warnings: {warns[:2]}",
    )


# ================================================================ D. PMU streams


def rec_frames():
    data = pmu_recording().read_bytes()
    fr = split_frames(data)
    return fr[0], fr[1:]


def with_fracsec(frame: bytes, frac: int) -> bytes:
    body = frame[:-2]
    body = body[:10] + bytes([body[10]]) + frac.to_bytes(3, "big") + body[14:]
    return seal(body)


def time_base(cfg: bytes) -> int:
    return int.from_bytes(cfg[15:18], "big")


def cfg_with_pmus(cfg: bytes, n: int, claim: int | None = None) -> bytes:
    """A CFG-2 of n PMUs of no channels (frequency only, 16-bit), NUM_PMU = claim or n."""
    head = cfg[:14] + cfg[14:18]  # through TIME_BASE
    block = b""
    for k in range(n):
        block += f"PMU{k}".ljust(16).encode()
        block += struct.pack(">HHHHH", k + 10, 0, 0, 0, 0) + struct.pack(">HH", 0, 1)
    rate = cfg[-4:-2]
    body = head + struct.pack(">H", claim if claim is not None else n) + block + rate
    return seal(body)


def data_of_pmus(frame: bytes, n: int) -> bytes:
    """A data frame of n PMUs (STAT, FREQ, DFREQ 16-bit) with frame's time stamp."""
    body = frame[:14] + (struct.pack(">Hhh", 0, 0, 0) * n)
    return seal(body)


def _record(d, port, frames, timeout=120, out="r.c37"):
    return run(
        S + ["pmu", "record", f"127.0.0.1:{port}", "--frames", str(frames), "-o", out],
        cwd=d,
        timeout=timeout,
    )


def _serve(d, extra=(), tf="3", name="serve.log"):
    log = d / name
    srv = launch(
        S + ["pmu", "serve", "kundur", "--fault", "3", "--far-bus", "101", "--speed", "0"]
        + ["--port", "0", "--tf", tf, *extra],
        cwd=d,
        log=log,
    )  # fmt: skip
    addr = serve_addr(log)
    return srv, addr, log


@probe
def D01():
    """a server that sends a valid CFG-2, 5 data frames, then a data frame with a huge
    FRAMESIZE (65535) and holds: record keeps the 5, exit 2 within ~35 s, no traceback;
    estimate track over TCP likewise refuses"""
    d = workdir("d01")
    cfg, frames = rec_frames()
    big = bytearray(frames[5])
    big[2:4] = struct.pack(">H", 65535)
    srv = FakePMU(cfg, [*frames[:5], bytes(big)], after="hold")
    t0 = time.monotonic()
    rc, _, err = _record(d, srv.port, 181)
    dt = time.monotonic() - t0
    why = one_error(rc, err, f"127.0.0.1:{srv.port}")
    n = n_data_frames(d / "r.c37")
    if n != 5:
        why += f"; recording holds {n} data frames (want 5)"
    if dt > 45:
        why += f"; took {dt:.0f} s"
    why = why.strip("; ")
    result("D01a", not why, why or f"{dt:.0f} s, 5 frames kept: {error_lines(err)[0][:110]}")
    t0 = time.monotonic()
    rc, _, err = run(
        S + ["estimate", "track", "kundur", "--source", f"tcp://127.0.0.1:{srv.port}"]
        + ["--frames", "100", "--out", "t.csv"],
        cwd=d,
        timeout=120,
    )  # fmt: skip
    dt = time.monotonic() - t0
    why = one_error(rc, err)
    result("D01b", not why and dt < 45, why or f"{dt:.0f} s: {error_lines(err)[0][:120]}")
    srv.close()


@probe
def D02():
    """a data frame whose FRACSEC is beyond TIME_BASE (CRC right): refused and named,
    the frames before it kept"""
    d = workdir("d02")
    cfg, frames = rec_frames()
    tb = time_base(cfg)
    bad = with_fracsec(frames[3], tb + 5)
    srv = FakePMU(cfg, [*frames[:3], bad, *frames[4:10]], after="close")
    rc, _, err = _record(d, srv.port, 9)
    why = one_error(rc, err)
    if not why and not any(w in err for w in ("FRACSEC", "TIME_BASE", "fraction")):
        why = "error does not say FRACSEC/TIME_BASE: " + error_lines(err)[0]
    n = n_data_frames(d / "r.c37")
    if n != 3:
        why += f"; recording holds {n} data frames (want 3)"
    why = why.strip("; ")
    result("D02", not why, why or error_lines(err)[0][:140])
    srv.close()


@probe
def D03():
    """a CFG-2 of 0 PMUs (valid frames of no PMU data): record and track say so in one
    line"""
    d = workdir("d03")
    cfg, frames = rec_frames()
    c0 = cfg_with_pmus(cfg, 0)
    f0 = [data_of_pmus(f, 0) for f in frames[:20]]
    srv = FakePMU(c0, f0, after="close")
    rc, out, err = _record(d, srv.port, 20)
    rec_msg = (error_lines(err) or out.strip().splitlines() or [""])[-1][:120]
    why = "" if "Traceback" not in err and rc in (0, 2) else f"record exit {rc}: {err[-200:]!r}"
    track = S + ["estimate", "track", "kundur", "--source"]
    if rc == 0:
        rc2, _, err2 = run([*track, "r.c37", "--out", "t.csv"], cwd=d)
        w2 = one_error(rc2, err2)
        why += w2 and f"track of the 0-PMU recording: {w2}"
        rec_msg += " | track: " + (error_lines(err2) or [""])[0][:100]
    rc3, _, err3 = run(
        [*track, f"tcp://127.0.0.1:{srv.port}", "--frames", "10", "--out", "t2.csv"], cwd=d
    )
    w3 = one_error(rc3, err3)
    why += w3 and f"; track over TCP: {w3}"
    why = why.strip("; ")
    result(
        "D03",
        not why,
        why or f"record: {rec_msg} | tcp: {(error_lines(err3) or [''])[0][:100]}",
    )
    srv.close()


@probe
def D04():
    """a CFG-2 that declares 10 000 PMUs in a frame of 2 (a lie), and one of 2000 PMUs of
    no channels (60 KB, a legal frame): one error line, no traceback"""
    d = workdir("d04")
    cfg, frames = rec_frames()
    for pid, c, f in (
        ("D04a", cfg_with_pmus(cfg, 2, claim=10000), [data_of_pmus(x, 2) for x in frames[:5]]),
        ("D04b", cfg_with_pmus(cfg, 2000), [data_of_pmus(x, 2000) for x in frames[:5]]),
    ):
        srv = FakePMU(c, f, after="close")
        t0 = time.monotonic()
        rc, out, err = _record(d, srv.port, 5, out=f"{pid}.c37")
        dt = time.monotonic() - t0
        why = "" if "Traceback" not in err and rc in (0, 2) else f"exit {rc}: {err[-200:]!r}"
        msg = (error_lines(err) or out.strip().splitlines()[-1:] or [""])[0][:120]
        if pid == "D04a" and rc == 0:
            why += "a CFG-2 declaring 10000 PMUs in a 2-PMU frame was recorded"
        if rc == 0 and pid == "D04b":
            rc2, _, err2 = run(
                S + ["estimate", "track", "kundur", "--source", f"{pid}.c37", "--out", "t.csv"],
                cwd=d,
                timeout=120,
            )
            w2 = one_error(rc2, err2)
            why += w2 and f"track of it: {w2}"
            msg += " | track: " + (error_lines(err2) or [""])[0][:100]
        result(pid, not why, why or f"{dt:.1f} s: {msg}")
        srv.close()


@probe
def D05():
    """a peer speaking HTTP to `pmu serve`, then 100 connections at once that say nothing,
    then a real PDC: the server names the HTTP peer, survives, and sends the PDC its
    stream"""
    d = workdir("d05")
    srv, addr, log = _serve(d, ("--wait", "10", "--timeout", "10"))
    host, port = addr.rsplit(":", 1)
    with socket.create_connection((host, int(port)), 5) as h:
        h.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
        h.settimeout(10)
        try:
            got = h.recv(100)
        except OSError as exc:
            got = repr(exc).encode()
    many = []
    for _ in range(100):
        try:
            many.append(socket.create_connection((host, int(port)), 5))
        except OSError:
            break
    t0 = time.monotonic()
    rc, _, err = run(
        S + ["pmu", "record", addr, "--frames", "181", "-o", "r.c37"], cwd=d, timeout=120
    )
    dt = time.monotonic() - t0
    for s in many:
        s.close()
    try:
        srv.wait(60)
    except subprocess.TimeoutExpired:
        stop(srv)
    text = log.read_text(errors="replace")
    why = ""
    if rc != 0:
        why += f"the real PDC: exit {rc} after {dt:.0f} s: {err[-160:]!r}; "
    if "Traceback" in text:
        why += "server traceback; "
    if srv.returncode != 0:
        why += f"server exit {srv.returncode}: {text.strip()[-160:]!r}; "
    http_named = [
        line for line in text.splitlines() if "HTTP" in line or ("C37" in line and "not" in line)
    ]
    result(
        "D05",
        not why,
        why
        or f"{len(many)} idle peers held; PDC served in {dt:.1f} s; HTTP peer got {got[:30]!r}; "
        f"server said: {(http_named or [''])[0][:80]}",
    )


@probe
def D06():
    """a slow reader (a receive buffer of 4 KB, reads nothing after 'start') while the server
    streams a long run; a real PDC at the same time is served whole; the slow one is cut
    after --timeout and named"""
    from pyc37.frame import CommandFrame

    d = workdir("d06")
    srv, addr, log = _serve(d, ("--wait", "5", "--timeout", "5"), tf="20")
    host, port = addr.rsplit(":", 1)
    with socket.socket() as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        s.connect((host, int(port)))
        s.sendall(CommandFrame(1, "cfg2").convert2bytes())
        time.sleep(0.5)
        s.recv(65536)
        s.sendall(CommandFrame(1, "start").convert2bytes())
        t0 = time.monotonic()
        rc, _, err = run(
            S + ["pmu", "record", addr, "--frames", "1201", "-o", "r.c37"], cwd=d, timeout=120
        )
        dt = time.monotonic() - t0
        try:
            srv.wait(90)
        except subprocess.TimeoutExpired:
            stop(srv)
    text = log.read_text(errors="replace")
    why = ""
    if rc != 0:
        why += f"the real PDC beside the slow one: exit {rc} after {dt:.0f} s: {err[-160:]!r}; "
    if "Traceback" in text:
        why += "server traceback; "
    if srv.returncode is None:
        why += "server still running; "
    cut = [
        line
        for line in text.splitlines()
        if "took no frame" in line or "cut" in line or "unacknowledged" in line
    ]
    result(
        "D06",
        not why,
        why
        or f"PDC served whole in {dt:.1f} s beside the slow reader; server exit "
        f"{srv.returncode}; {(cut or ['slow reader not named'])[0][:100]}",
    )


@probe
def D07():
    """--allow with a host name, a CIDR, garbage, a port, an IPv6 zone: one error line each,
    before the server listens (no simulation run)"""
    d = workdir("d07")
    for pid, val in (
        ("D07a", "localhost"),
        ("D07b", "127.0.0.0/8"),
        ("D07c", "12x.0.0.1"),
        ("D07d", "127.0.0.1:4712"),
        ("D07f", "127.1"),
        ("D07g", ""),
    ):
        t0 = time.monotonic()
        rc, _, err = run(
            S + ["pmu", "serve", "kundur", "--fault", "3", "--far-bus", "101", "--port", "0"]
            + ["--allow", val, "--wait", "1", "--speed", "0", "--tf", "2"],
            cwd=d,
            timeout=60,
        )  # fmt: skip
        dt = time.monotonic() - t0
        why = one_error(rc, err, "--allow")
        result(pid, not why, why or f"{val!r}: {error_lines(err)[0][:120]} ({dt:.1f} s)")


@probe
def D08():
    """IPv4-mapped IPv6 peers: a server on :: that allows 127.0.0.1 admits an IPv4 client
    (seen as ::ffff:127.0.0.1); one allowing ::ffff:127.0.0.1 on 127.0.0.1 too; a server on
    :: allowing ::1 refuses the IPv4 client"""
    d = workdir("d08")
    for pid, host, allow, peer, want in (
        ("D08a", "::", "127.0.0.1", "127.0.0.1", 0),
        ("D08b", "127.0.0.1", "::ffff:127.0.0.1", "127.0.0.1", 0),
        ("D08c", "::", "::1", "127.0.0.1", 2),
        ("D08d", "::", "::ffff:127.0.0.1", "[::ffff:127.0.0.1]", 0),
    ):
        srv, addr, log = _serve(
            d,
            ("--host", host, "--allow", allow, "--wait", "3", "--timeout", "5"),
            name=f"{pid}.log",
        )
        if addr is None:
            stop(srv)
            result(pid, False, f"server did not start: {log.read_text()[-200:]!r}")
            continue
        port = addr.rsplit(":", 1)[1]
        rc, _, err = run(
            S + ["pmu", "record", f"{peer}:{port}", "--frames", "181", "-o", f"{pid}.c37"],
            cwd=d,
            timeout=60,
        )
        stop(srv)
        text = log.read_text(errors="replace")
        why = ""
        if rc != want or "Traceback" in err + text:
            said = (error_lines(err) or [err[-100:]])[0][:120]
            why = f"record exit {rc} (want {want}): {said}"
        refused = [
            line
            for line in text.splitlines()
            if "refus" in line or "not allowed" in line or "allow" in line
        ]
        result(
            pid, not why, why or f"exit {rc}" + (f"; server: {refused[0][:100]}" if refused else "")
        )


@probe
def D09():
    """100 PDCs at once that each ask for the CFG-2, say 'start' and read every frame: the
    server streams to all, names them, ends 0; its memory and threads bounded"""
    from pyc37.frame import CommandFrame

    d = workdir("d09")
    srv, addr, log = _serve(d, ("--wait", "5", "--timeout", "20"), tf="3")
    host, port = addr.rsplit(":", 1)
    got = [0] * 100

    def client(i):
        try:
            with socket.create_connection((host, int(port)), 30) as s:
                s.settimeout(60)
                s.sendall(CommandFrame(1, "cfg2").convert2bytes())
                s.sendall(CommandFrame(1, "start").convert2bytes())
                buf = b""
                while True:
                    b = s.recv(65536)
                    if not b:
                        break
                    buf += b
                    if len(buf) >= 19128 - 4:  # cfg + 181 frames of rec.c37 size
                        break
                got[i] = len(buf)
        except OSError:
            got[i] = -1

    ts = [threading.Thread(target=client, args=(i,)) for i in range(100)]
    for t in ts:
        t.start()
    for t in ts:
        t.join(120)
    try:
        srv.wait(90)
    except subprocess.TimeoutExpired:
        stop(srv)
    text = log.read_text(errors="replace")
    full = sum(1 for g in got if g >= 19000)
    why = ""
    if "Traceback" in text:
        why += "server traceback; "
    lines = text.splitlines()
    dropped = sum(1 for x in lines if x.startswith("dropped") and "more time" not in x)
    dropped += sum(int(x) for x in re.findall(r"(\d+) more time\(s\)", text))
    if full + dropped < 100:
        why += (
            f"{full} of 100 clients got the whole stream, {dropped} dropped and named "
            f"({sorted(set(got))[:5]}); "
        )
    if srv.returncode != 0:
        why += f"server exit {srv.returncode}: {text.strip()[-200:]!r}"
    result(
        "D09",
        not why,
        why
        or f"{full} clients got the stream, {dropped} dropped and named (8 peers at once, by "
        f"design); exit {srv.returncode}",
    )


# ================================================================ main

# the order of the original round (files, concurrency, Dask, PMU streams, then the probes
# added in its course)
ORDER = [
    "A01", "A02", "A03", "A04", "A05", "A06", "A07", "A08", "A09", "A10", "A11", "A12", "B01",
    "B02", "B03", "C01", "C02", "C03", "C04", "C05", "D01", "D02", "D03", "D04", "D05", "D06",
    "D07", "D08", "A13", "B04", "A14", "C06", "D09", "A15", "C07", "C08", "C09", "C10", "A16",
    "A17",
]  # fmt: skip


def _terminated(signum, _frame):
    raise SystemExit(128 + signum)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ids", nargs="*", help="prefixes of probe names (A10, C0)")
    ap.add_argument("-k", default="", help="run the probes whose name holds this")
    ap.add_argument(
        "--skip-compile", action="store_true", help="skip B03 and C10 (kernels compiled anew)"
    )
    ap.parse_args(argv, namespace=OPTS)
    # a timeout's SIGTERM (or a closed terminal's SIGHUP) ends the run through the finally
    # below, which stops the Dask servers started and unmounts the tmpfs mounts
    for s in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, _terminated)
    by_name = {f.__name__: f for f in PROBES}
    selected = [
        by_name[n]
        for n in ORDER
        if (not OPTS.ids or any(n.startswith(x) for x in OPTS.ids)) and OPTS.k in n
    ]
    t_start = time.monotonic()
    print(f"stabctl of {ROOT}; work directory {WORK}", flush=True)
    rc, _, err = run(S + ["compile"], timeout=900)  # a warm cache loads in seconds
    if rc != 0:
        print("stabctl compile failed:", err[-300:])
        return 2
    try:
        for f in selected:
            try:
                f()
            except Exception as exc:  # noqa: BLE001 - a probe that fails itself is reported short
                traceback.print_exc()
                result(f.__name__, False, f"PROBE ERROR (the probe itself failed): {exc!r}"[:200])
    finally:
        for p in STARTED:
            stop(p)
        for d in reversed(MOUNTS):
            subprocess.run(["umount", "-l", str(d)], check=False)
        keep = bool(os.environ.get("KEEP"))
        if not keep:
            shutil.rmtree(WORK, ignore_errors=True)
    short = [r for r in RESULTS if not r[1]]
    print(
        f"\n{len(RESULTS)} probes, {len(RESULTS) - len(short)} ok, {len(short)} SHORT; "
        f"{time.monotonic() - t_start:.0f} s; work dir {WORK} ({'kept' if keep else 'removed'})"
    )
    return 1 if short else 0


if __name__ == "__main__":
    sys.exit(main())
