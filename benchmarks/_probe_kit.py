"""The harness the reliability probe scripts (benchmarks/reliability_probes_*.py) share:
written once, so a fix to it reaches every round.

A script makes one `Kit` (its temporary-directory prefix and its options) and takes the
names its probe bodies call from it::

    from _probe_kit import Kit

    KIT = Kit("probes_w44.", line="{pid:<8} {state:<5} {why}")
    CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
    run, rec, probe = KIT.run, KIT.rec, KIT.probe
    ...
    if __name__ == "__main__":
        KIT.main()

The package under test is CLONE's (default: this repository), run as `python -m stabctl`
with PYTHONPATH=CLONE; every command has a timeout and runs in the work directory WD,
removed at the end unless KEEP=1 (`keep_any`: unless KEEP is set).  Besides: the small
readers (tail, records, ...), ports, and the C37.118.2 frame tools and fake server of
the PMU stream rounds.  The scripts are run as `python benchmarks/<script>.py`, so this
directory is on sys.path.
"""

import json
import os
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

INHERIT = object()  # stdin=INHERIT: the command reads the caller's stdin
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def tb(text):
    """Whether `text` holds a Python traceback."""
    return "Traceback (most recent call last)" in text


def tail(s, n=300):
    """The last n characters of s, on one line."""
    s = (s or "").strip()
    return s[-n:].replace("\n", " | ")


def lines_of(path):
    """The non-blank lines of a text file."""
    return [ln for ln in Path(path).read_text().splitlines() if ln.strip()]


def records(path):
    """The JSON records of a JSON-lines file, None for a line that is not one."""
    out = []
    for ln in lines_of(path):
        try:
            out.append(json.loads(ln))
        except ValueError:
            out.append(None)
    return out


def free_port():
    """A loopback TCP port free just now."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


def _until(ready, timeout, proc):
    """Poll ready() every 0.3 s until it is true (True), time runs out or proc ends (False)."""
    t = time.time()
    while time.time() - t < timeout:
        if proc is not None and proc.poll() is not None:
            return False
        if ready():
            return True
        time.sleep(0.3)
    return False


def wait_port(port, timeout=120, proc=None):
    """Wait until a loopback port accepts a connection (False if proc ends first)."""

    def ready():
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return True
        except OSError:
            return False

    return _until(ready, timeout, proc)


def wait_listen(port, timeout=120, proc=None):
    """Wait until port is listening without connecting (ss)."""

    def ready():
        r = subprocess.run(["ss", "-ltn"], capture_output=True, text=True)
        return f":{port} " in r.stdout

    return _until(ready, timeout, proc)


def group_alive(pgid):
    """The `ps` lines of processes still in process group pgid (zombies left out)."""
    r = subprocess.run(["ps", "-eo", "pid,pgid,stat,args"], capture_output=True, text=True)
    return [
        ln
        for ln in r.stdout.splitlines()[1:]
        if ln.split()[1] == str(pgid) and "Z" not in ln.split()[2]
    ]


def _text(b):
    """A TimeoutExpired's partial output as text (bytes even under text=True)."""
    if isinstance(b, bytes):
        return b.decode(errors="replace")
    return b or ""


def stabctl(args):
    """The command line of `python -m stabctl args`."""
    return [sys.executable, "-m", "stabctl", *map(str, args)]


# ---------------------------------------------------------------- C37.118.2 frames
def crc_ccitt(data: bytes) -> int:
    """CRC-CCITT of a frame's bytes (C37.118.2 CHK)."""
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def split_frames(blob: bytes):
    """The frames of a recording, by their FRAMESIZE."""
    out, i = [], 0
    while i + 4 <= len(blob):
        n = struct.unpack(">H", blob[i + 2 : i + 4])[0]
        out.append(blob[i : i + n])
        i += n
    return out


def fix_crc(fr: bytes) -> bytes:
    """The frame with its CHK recomputed."""
    body = fr[:-2]
    return body + struct.pack(">H", crc_ccitt(body))


def with_stamp(fr: bytes, soc: int, counts: int) -> bytes:
    """The frame stamped SOC soc, FRACSEC counts (CHK recomputed)."""
    b = bytearray(fr)
    b[6:10] = struct.pack(">I", soc)
    b[11:14] = counts.to_bytes(3, "big")
    return fix_crc(bytes(b))


def stamp_of(fr):
    """(SOC, FRACSEC counts) of a frame."""
    return struct.unpack(">I", fr[6:10])[0], int.from_bytes(fr[11:14], "big")


def read_frame(conn):
    """One frame read from a socket (None at its end)."""
    head = b""
    while len(head) < 4:
        c = conn.recv(4 - len(head))
        if not c:
            return None
        head += c
    n = struct.unpack(">H", head[2:4])[0]
    body = head
    while len(body) < n:
        c = conn.recv(n - len(body))
        if not c:
            return None
        body += c
    return body


class FakeServer:
    """One-shot C37.118.2 server on 127.0.0.1: answers 'cfg2' with cfg, and after 'start'
    sends `data` (an iterable of bytes objects), then does `end` ('close', 'silent',
    'half')."""

    def __init__(self, cfg, data, end="close", gap=0.0):
        self.cfg, self.data, self.end, self.gap = cfg, data, end, gap
        self.sock = socket.socket()
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(4)
        self.port = self.sock.getsockname()[1]
        self.sent = 0
        self.stop = threading.Event()
        self.th = threading.Thread(target=self._run, daemon=True)
        self.th.start()

    def _run(self):
        try:
            self.sock.settimeout(120)
            conn, _ = self.sock.accept()
            conn.settimeout(120)
            started = False
            while not started:
                fr = read_frame(conn)
                if fr is None:
                    return
                cmdw = struct.unpack(">H", fr[14:16])[0]
                if cmdw == 5:  # send CFG-2
                    conn.sendall(self.cfg)
                elif cmdw == 2:  # start
                    started = True
            for fr in self.data:
                if self.stop.is_set():
                    break
                conn.sendall(fr)
                self.sent += 1
                if self.gap:
                    time.sleep(self.gap)
            if self.end == "half":
                conn.sendall(
                    self.data_last[: len(self.data_last) // 2]
                    if hasattr(self, "data_last")
                    else b"\xaa\x01\x00\x40\x00\x01"
                )
                time.sleep(0.5)
            elif self.end == "silent":
                self.stop.wait(300)
            conn.close()
        except OSError:
            pass
        finally:
            self.sock.close()

    def close(self):
        """Stop sending (and a silent end's wait)."""
        self.stop.set()


class Kit:
    """One script's harness: its work directory, environment, probes and results.

    prefix      the work directory's prefix (tempfile.mkdtemp)
    path        WD as a Path (else a str)
    xdg         XDG_CACHE_HOME in WD/xdg (a cold cache of the caller's own)
    env         more environment variables for the commands run
    only        the probe ids (or prefixes) to run; default the command line's arguments
    prefixes    `only` names id prefixes (else whole ids)
    line        how a result is printed (fields pid, state, why)
    timed       add the probe's wall time to its reason
    show_tb     print the traceback of a probe that raised
    """

    def __init__(
        self,
        prefix,
        *,
        path=True,
        xdg=True,
        env=None,
        only=None,
        prefixes=True,
        line="{pid:<6} {state:<5} {why}",
        timed=False,
        show_tb=False,
    ):
        self.clone = os.environ.get("CLONE", REPO)  # the package under test
        wd = tempfile.mkdtemp(prefix=prefix)
        self.wd = Path(wd) if path else wd
        self.env = dict(os.environ, PYTHONPATH=self.clone)
        if xdg:
            self.env["XDG_CACHE_HOME"] = os.path.join(wd, "xdg")
        self.env.update(env or {})
        self.only = list(sys.argv[1:] if only is None else only)
        self.prefixes = prefixes
        self.line, self.timed, self.show_tb = line, timed, show_tb
        self.results, self.probes = [], []
        self._recording = {}  # recording()'s, made once
        self.t0 = time.time()

    # ------------------------------------------------------------ commands
    def run(self, args, timeout=300, cwd=None, env=None, stdin=None, partial=True):
        """(rc, stdout, stderr, seconds) of `python -m stabctl args` in WD; rc "timeout"
        with what it wrote (partial=False: nothing) when it ran out of time.  stdin is
        /dev/null unless given (INHERIT: the caller's)."""
        return self.run_argv(stabctl(args), timeout, cwd, env, stdin, partial)

    def cli(self, args, timeout=300, cwd=None, env=None, stdin=None, partial=True):
        """(rc, stdout, stderr) of `python -m stabctl args`: `run` without the time."""
        return self.run(args, timeout, cwd, env, stdin, partial)[:3]

    def run_argv(self, full, timeout=300, cwd=None, env=None, stdin=None, partial=True):
        """`run` of any command line `full`."""
        t = time.time()
        if stdin is INHERIT:
            stdin = None
        elif stdin is None:
            stdin = subprocess.DEVNULL
        try:
            p = subprocess.run(
                full,
                capture_output=True,
                text=True,
                timeout=timeout,
                cwd=cwd or self.wd,
                env=env or self.env,
                stdin=stdin,
            )
            return p.returncode, p.stdout, p.stderr, time.time() - t
        except subprocess.TimeoutExpired as e:
            if not partial:
                return "timeout", "", "", time.time() - t
            return "timeout", _text(e.stdout), _text(e.stderr), time.time() - t

    def run_rss(self, args, timeout=300, env=None):
        """run under /usr/bin/time: (rc, out, err, dt, peak RSS MiB)."""
        t = time.time()
        full = ["/usr/bin/time", "-f", "MAXRSS=%M", *stabctl(args)]
        try:
            p = subprocess.run(
                full,
                capture_output=True,
                text=True,
                timeout=timeout,
                cwd=self.wd,
                env=env or self.env,
                stdin=subprocess.DEVNULL,
            )
        except subprocess.TimeoutExpired:
            return "timeout", "", "", time.time() - t, -1
        rss = -1
        for line in p.stderr.splitlines()[::-1]:
            if line.startswith("MAXRSS="):
                rss = int(line[7:]) / 1024
                break
        err = "\n".join(
            x
            for x in p.stderr.splitlines()
            if not x.startswith("MAXRSS=") and "Command exited with non-zero" not in x
        )
        return p.returncode, p.stdout, err, time.time() - t, rss

    def start(self, args, env=None, **kw):
        """`python -m stabctl args` in the background, in a session of its own."""
        return subprocess.Popen(
            stabctl(args),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=self.wd,
            env=env or self.env,
            start_new_session=True,
            stdin=subprocess.DEVNULL,
            **kw,
        )

    @staticmethod
    def finish(p, timeout=60):
        """(rc, out, err) of a started process; its group killed at the timeout."""
        try:
            out, err = p.communicate(timeout=timeout)
            return p.returncode, out, err
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            out, err = p.communicate()
            return "timeout", out, err

    # ------------------------------------------------------------ a recorded stream
    def recording(self):
        """(cfg2, [data frames]) of kundur 3-101, 3 s, 60 fps, from `pmu serve` + `pmu record`."""
        if self._recording:
            return self._recording["cfg"], self._recording["data"]
        port = free_port()
        srv = self.start(
            [
                "pmu",
                "serve",
                "kundur",
                "--fault",
                3,
                "--far-bus",
                101,
                "--tf",
                3,
                "--speed",
                0,
                "--port",
                port,
                "--wait",
                5,
                "--timeout",
                20,
            ]
        )
        if not wait_listen(port, 300, srv):
            self.finish(srv, 5)
            raise RuntimeError("pmu serve did not listen")
        rc, _o, e, _dt = self.run(
            ["pmu", "record", f"127.0.0.1:{port}", "--frames", 180, "-o", self.wd / "k.c37"],
            timeout=120,
        )
        self.finish(srv, 30)
        if rc != 0:
            raise RuntimeError(f"pmu record exit {rc}: {tail(e)}")
        frames = split_frames((self.wd / "k.c37").read_bytes())
        self._recording["cfg"], self._recording["data"] = frames[0], frames[1:]
        return frames[0], frames[1:]

    def track_tcp(self, server, extra, timeout=120, out="t.csv"):
        """`estimate track kundur` of a FakeServer's stream into WD/out: (*run's, its path)."""
        o = self.wd / out
        if o.exists():
            o.unlink()
        r = self.run(
            [
                "estimate",
                "track",
                "kundur",
                "--source",
                f"tcp://127.0.0.1:{server.port}",
                "--out",
                o,
                *extra,
            ],
            timeout=timeout,
        )
        server.close()
        return (*r, o)

    # ------------------------------------------------------------ probes
    def selected(self, pid):
        """Whether probe pid is among those asked for (all when none is)."""
        if not self.only:
            return True
        if self.prefixes:
            return any(pid.startswith(o) for o in self.only)
        return pid in self.only

    def rec(self, pid, ok, why):
        """Record and print one probe's result."""
        self.results.append((pid, ok, why))
        print(self.line.format(pid=pid, state="ok" if ok else "SHORT", why=why), flush=True)

    def probe(self, pid):
        """Decorator: f() -> (ok, why) becomes the probe pid, run by `main` when selected;
        an exception it raises is its SHORT reason."""

        def deco(f):
            def g(*a, **k):
                if not self.selected(pid):
                    return
                t0 = time.time()
                try:
                    ok, why = f(*a, **k)
                except Exception as e:  # noqa: BLE001 - a probe that raises is SHORT
                    if self.show_tb:
                        traceback.print_exc()
                    ok, why = False, f"probe raised {type(e).__name__}: {e}"
                if self.timed:
                    why = f"{why} [{time.time() - t0:.0f} s]"
                self.rec(pid, ok, why)

            g.pid = pid
            self.probes.append(g)
            return g

        return deco

    # ------------------------------------------------------------ the run
    def main(
        self,
        probes=None,
        *,
        banner=None,
        summary="\n{ok} ok, {short} SHORT",
        keep_any=False,
        kept="kept {wd}",
        chown=False,
    ):
        """Run the probes (default: every one registered, in order), remove WD, print
        the summary and exit 1 if any probe is SHORT.

        banner      printed first (fields wd, clone), e.g. "work dir {wd}"
        summary     the last line (fields n, ok, short, secs)
        keep_any    any non-empty KEEP keeps WD (else only KEEP=1)
        kept        printed when WD is kept (None: nothing)
        chown       give WD back to root before removing it (a probe ran as another user)
        """
        if banner:
            print(banner.format(wd=self.wd, clone=self.clone), flush=True)
        try:
            for p in self.probes if probes is None else probes:
                p()
        finally:
            self.cleanup(keep_any, kept, chown)
        self.report(summary)

    def report(self, summary="\n{ok} ok, {short} SHORT"):
        """Print the summary (fields n, ok, short, secs); exit 1 if any probe is SHORT."""
        n = len(self.results)
        short = sum(not ok for _, ok, _ in self.results)
        secs = time.time() - self.t0
        print(summary.format(n=n, ok=n - short, short=short, secs=secs), flush=True)
        sys.exit(1 if short else 0)

    def cleanup(self, keep_any=False, kept="kept {wd}", chown=False):
        """Remove WD unless KEEP says to keep it."""
        keep = os.environ.get("KEEP")
        if keep if keep_any else keep == "1":
            if kept:
                print(kept.format(wd=self.wd))
            return
        if chown:
            subprocess.run(["chown", "-R", "root:root", str(self.wd)], capture_output=True)
        shutil.rmtree(self.wd, ignore_errors=True)
