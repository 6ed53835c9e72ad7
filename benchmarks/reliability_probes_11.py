"""Eleventh reliability round (round 35, part D): long work -- progress, interruption by
signals, resumption, reproducibility, concurrency -- across the long-running commands.

Progress bars on a terminal (a pseudo-terminal) and in a log file, eig's messages while it
linearises WECC 240; screen, sweep-cct, place, paper, simulate and import-psse interrupted
by SIGINT, SIGTERM, SIGHUP (alone, twice, several, to the process group), stopped by
Ctrl-Z and continued, killed by SIGKILL at chosen moments (a number of records written,
the output being written, paper's final moves) and resumed; a record line cut as by a kill;
--workers 1 and 2 and two runs compared record by record and byte by byte; two runs on one
output at once; the Dask local scheduler interrupted.

Contract: each probe runs `stabctl` commands detached in their own session with default
signal dispositions (the package of this repository first on PYTHONPATH, TMPDIR a directory
of the work directory, checked for leftovers), each under a timeout, its session killed at
the end, and states what a careful tool does: an interrupted command ends with 128 + the
signal's number, one line saying what it kept and how to resume, no traceback, no process
and no hidden or temporary file left; a resumed run gives the records and output of an
uninterrupted one; two runs on one output: one ends, the other is refused naming the
holder.  The round found paper's commit window (a signal between its first report moved
into OUT_DIR and its last record), paper's interrupt message (records said kept where none
were), the bar's frames in a log file and eig's silence short; they are fixed (an interrupt
during paper's final moves is delivered after them; "nothing is kept"; a bar on a stderr
that is no terminal redrawn every 30 s; "eig: still linearising ..." every 8 s) and the
probes are now their regression checks.  What SIGKILL leaves (simulate's hidden temporary
output, paper's staging directory, a sweep's marks in TMPDIR) was left by the next run
until 2026-11-30 (sigkill.leftovers); estimate cct's bar was named after its temporary
records file (progress.estimate_cct.label).  Both are fixed.

    python benchmarks/reliability_probes_11.py [-k SUBSTRING] [ID ...]

ID: a probe's name (``interrupt.place``) or its prefix before the first ``.`` (``paper``,
``interrupt``).  The probes needing a reference run (the 24-fault miniWECC screening,
paper --only table4) make it when first needed; paper.interrupt.resume also checks the
resume after sigkill.leftovers's SIGKILL when both run.  One line per probe (name, ok or
SHORT, why, its seconds), then the counts.  Needs Linux (/proc, pseudo-terminals) and WECC
240 of tests/data/wecc240.  NUMBA_CACHE_DIR is the caller's (numba's default when unset);
`stabctl compile` is run first (seconds with a warm cache, about a minute cold).  The work
directory is a new temporary directory, removed at the end unless KEEP is set.  About 8
minutes on two idle cores with a warm kernel cache (16 on busy ones).  Exit status 1 if any
probe is short.
"""

from __future__ import annotations

import argparse
import fcntl
import glob
import gzip
import json
import os
import pty
import select
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import termios
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]  # the package under test
STABCTL = [sys.executable, "-m", "stabctl"]
WECC240 = ROOT / "tests" / "data" / "wecc240"  # PSS/E's WECC 240 RAW and DYR, gzipped
WORK = tempfile.mkdtemp(prefix="stabctl-probes-11.")
TMP = os.path.join(WORK, "tmpdir")  # the commands' TMPDIR, checked for leftovers
os.makedirs(TMP)
ENV = dict(
    os.environ,
    PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]),
    TMPDIR=TMP,
    COLUMNS="120",
)
ENV.pop("PYTHONWARNINGS", None)
ENV.pop("TQDM_DISABLE", None)
RAW240 = os.path.join(WORK, "240busWECC_2018_PSS32_fixed_shunts.raw")
DYR240 = os.path.join(WORK, "240busWECC_2018_PSS.dyr")
B24 = ",".join(map(str, range(1, 25)))  # 24 miniWECC bus faults: ~25 s on 2 workers
SESSIONS: list[int] = []
RESULTS: list[tuple[str, bool, str]] = []
PROBES: list = []
EXPECT = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGHUP: 129}
REF: dict = {}


def W(name):
    """A directory of the work directory."""
    return os.path.join(WORK, name)


def wecc240():
    """WECC 240's RAW and DYR, unpacked into the work directory once."""
    for path in (RAW240, DYR240):
        if not os.path.exists(path):
            name = os.path.basename(path)
            with gzip.open(WECC240 / f"{name}.gz", "rb") as src, open(path, "wb") as dst:
                shutil.copyfileobj(src, dst)
    return RAW240, DYR240


# ---------------------------------------------------------------- processes


def _pre():
    for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM, signal.SIGQUIT, signal.SIGTSTP):
        signal.signal(s, signal.SIG_DFL)


class Run:
    """`stabctl cmd` started detached (own session, default signals), its stdout and stderr
    to the files TAG.out and TAG.err of cwd."""

    def __init__(self, cmd, cwd, tag, env=None):
        os.makedirs(cwd, exist_ok=True)
        self.cwd, self.tag = cwd, tag
        self.out_path, self.err_path = f"{cwd}/{tag}.out", f"{cwd}/{tag}.err"
        self._fo, self._fe = open(self.out_path, "wb"), open(self.err_path, "wb")  # noqa: SIM115
        self.p = subprocess.Popen(
            [*STABCTL, *map(str, cmd)],
            cwd=cwd,
            stdout=self._fo,
            stderr=self._fe,
            stdin=subprocess.DEVNULL,
            start_new_session=True,
            preexec_fn=_pre,
            env=env or ENV,
        )
        self.pid = self.p.pid
        SESSIONS.append(self.pid)
        self.t0 = time.monotonic()
        self.rc: int | str | None = None
        self.wall = 0.0

    def signal(self, sig, group=False):
        try:
            (os.killpg if group else os.kill)(self.pid, sig)
        except ProcessLookupError:
            pass

    def wait(self, timeout=300):
        try:
            rc: int | str = self.p.wait(timeout)
        except subprocess.TimeoutExpired:
            kill_session(self.pid)
            self.p.wait()
            rc = "TIMEOUT"
        self._fo.close()
        self._fe.close()
        self.wall = time.monotonic() - self.t0
        return rc

    @property
    def out(self):
        with open(self.out_path, errors="replace") as f:
            return f.read()

    @property
    def err(self):  # newline="": the bars' carriage returns kept as written
        with open(self.err_path, errors="replace", newline="") as f:
            return f.read()

    def err_lines(self):
        """stderr's lines that are no progress-bar frame."""
        text = self.err.replace("\r", "\n")
        return [ln for ln in text.splitlines() if ln.strip() and "%|" not in ln]

    def last_line(self):
        lines = self.err_lines()
        return lines[-1] if lines else ""


def run(cmd, cwd, tag, timeout=300, env=None):
    r = Run(cmd, cwd, tag, env)
    r.rc = r.wait(timeout)
    return r


def session_procs(sid):
    """The processes (not zombies) of session sid: (pid, command line)."""
    out = []
    for d in glob.glob("/proc/[0-9]*"):
        try:
            with open(d + "/stat") as f:
                st = f.read()
            fields = st[st.rindex(")") + 2 :].split()
            if int(fields[3]) == sid and fields[0] != "Z":
                with open(d + "/cmdline", "rb") as f:
                    cmd = f.read().replace(b"\0", b" ").decode()[:120]
                out.append((int(d[6:]), cmd))
        except (OSError, ValueError):
            pass
    return out


def orphans(sid, grace=6.0):
    """The processes of session sid still there after `grace` s."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < grace:
        left = session_procs(sid)
        if not left:
            return []
        time.sleep(0.25)
    return session_procs(sid)


def kill_session(sid):
    for pid, _ in session_procs(sid):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def nlines(path):
    try:
        with open(path, "rb") as f:
            return sum(1 for ln in f if ln.endswith(b"\n"))
    except OSError:
        return 0


def wait_until(pred, timeout, r=None, step=0.02):
    """Poll pred() until true, `timeout` s, or Run r ended (then pred() once more)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if pred():
            return True
        if r is not None and r.p.poll() is not None:
            return pred()
        time.sleep(step)
    return False


def hidden(d):
    """The hidden or temporary entries of directory d."""
    try:
        return sorted(
            f for f in os.listdir(d) if f.startswith(".") or f.endswith((".tmp", ".part"))
        )
    except OSError:
        return []


def tmp_left():
    return sorted(os.listdir(TMP))


def clear_tmp():
    for f in os.listdir(TMP):
        p = os.path.join(TMP, f)
        if os.path.isdir(p):
            shutil.rmtree(p, ignore_errors=True)
        else:
            os.unlink(p)


RUN_DEP = ("wall_time_s", "worker", "traceback")


def records(path):
    """({key: record} without run-dependent fields, the number of lines)."""
    out, n = {}, 0
    with open(path) as f:
        for ln in f:
            n += 1
            r = json.loads(ln)
            for k in RUN_DEP:
                r.pop(k, None)
                if isinstance(r.get("result"), dict):
                    r["result"].pop(k, None)
            out[r["key"]] = r
    return out, n


def screen_rows(text):
    return [{k: v for k, v in r.items() if k != "run_now"} for r in json.loads(text)]


def run_pty(cmd, cwd, key_at=None, key=b"\x03", timeout=120):
    """`stabctl cmd` on a pseudo-terminal of 120 x 40; `key` typed after key_at s:
    (exit status, output)."""
    pid, fd = pty.fork()
    if pid == 0:
        os.chdir(cwd)
        _pre()
        os.execve(sys.executable, [*STABCTL, *cmd], ENV)
    SESSIONS.append(pid)
    fcntl.ioctl(fd, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    out, t0, sent, status = b"", time.monotonic(), False, None
    while True:
        ready, _, _ = select.select([fd], [], [], 0.05)
        if ready:
            try:
                d = os.read(fd, 65536)
            except OSError:
                d = b""
            if not d:
                break
            out += d
        if not sent and key_at is not None and time.monotonic() - t0 > key_at:
            os.write(fd, key)
            sent = True
        w = os.waitpid(pid, os.WNOHANG)
        if w[0]:
            status = w[1]
            break
        if time.monotonic() - t0 > timeout:
            kill_session(pid)
    try:
        while select.select([fd], [], [], 0.1)[0]:
            d = os.read(fd, 65536)
            if not d:
                break
            out += d
    except OSError:
        pass
    if status is None:
        _, status = os.waitpid(pid, 0)
    os.close(fd)
    return os.waitstatus_to_exitcode(status), out.decode(errors="replace")


# ---------------------------------------------------------------- reporting


def probe(pid):
    """A probe named pid, returning (ok, why)."""

    def deco(f):
        f.pid = pid
        PROBES.append(f)
        return f

    return deco


def report(pid, ok, why, seconds):
    RESULTS.append((pid, ok, why))
    print(f"{pid:<30} {'ok   ' if ok else 'SHORT'} {why}  [{seconds:.0f} s]", flush=True)


def screen24(extra=()):
    return ["screen", "miniwecc", "--buses", B24, "--workers", "2", "--out", "s.jsonl",
            "--json", *extra]  # fmt: skip


def ref_screen():
    """The uninterrupted 24-fault miniWECC screening (its Run, records, --json rows), once."""
    if "screen" not in REF:
        r = run(screen24(), W("ref"), "ref")
        assert r.rc == 0, f"reference screen exit {r.rc}: {r.last_line()}"
        REF["screen"] = (r, records(f"{W('ref')}/s.jsonl")[0], screen_rows(r.out))
    return REF["screen"]


# ---------------------------------------------------------------- progress


@probe("progress.screen.tty")
def progress_screen_tty():
    cwd = W("tty")
    os.makedirs(cwd)
    rc, out = run_pty(
        ["screen", "miniwecc", "--buses", "1,2,3,4", "--workers", "2", "--out", "t.jsonl"], cwd
    )
    has = "%|" in out and "/4 [" in out and "<" in out
    return rc == 0 and has, f"exit {rc}; bar with fraction and time left on a terminal: {has}"


@probe("progress.simulate.tty")
def progress_simulate_tty():
    cwd = W("ttysim")
    os.makedirs(cwd)
    rc, out = run_pty(
        ["simulate", "miniwecc", "--fault", "83", "--far-bus", "33", "--tf", "300"], cwd
    )
    has = "simulated" in out and " left]" in out
    return (
        rc == 0 and has,
        f"exit {rc}; simulated-time bar with time left (a run of several s): {has}",
    )


@probe("progress.nontty.frames")
def progress_nontty_frames():
    """A bar on a stderr that is a file: a few frames (round 35: 2 a job, ~10 000 frames /
    0.8 MB on one 'line' for a 5 206-fault N-1 screening; now redrawn every 30 s)."""
    r, _, _ = ref_screen()
    err = r.err
    frames = err.count("\r")
    longest = max(len(ln) for ln in err.split("\n"))
    ok = frames <= 24 and longest < 4000
    return ok, (
        f"stderr to a file, 24 jobs in {r.wall:.0f} s: {frames} carriage-return frames of the "
        f"bar, the longest 'line' {longest} bytes"
    )


@probe("progress.eig.silent")
def progress_eig_silent():
    """eig of WECC 240: done before its first 8 s of linearising are over (10 s with the
    start) or saying something while it works (round 35: 9-17 s of silence, the testers'
    bound 5 s; now 'eig: still linearising ...' every 8 s)."""
    cwd = W("eig")
    raw, dyr = wecc240()
    r = run(["import-psse", raw, dyr, "-o", "w240.json"], cwd, "imp")
    if r.rc != 0:
        return False, f"import-psse wecc240 exit {r.rc}: {r.last_line()}"
    e = run(["eig", "w240.json", "--json"], cwd, "eig")
    said = [ln for ln in e.err.splitlines() if ln.strip()]
    ok = e.rc == 0 and (e.wall < 10 or bool(said))
    return ok, (
        f"eig of WECC-240 exit {e.rc}, {e.wall:.1f} s wall, {len(said)} line(s) on stderr"
        + (f": '{said[0][:70]}'" if said else "")
    )


@probe("progress.estimate_cct.label")
def progress_estimate_cct_label():
    """estimate cct twice: the same JSON; its bar not named after a file the user cannot
    see (open by the developers' choice: named after its temporary records file)."""
    cwd = W("estcct")
    args = ["estimate", "cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5",
            "--runs", "2", "--json"]  # fmt: skip
    r = run(args, cwd, "a")
    r2 = run(args, cwd, "b")
    same = r.rc == 0 and r2.rc == 0 and json.loads(r.out) == json.loads(r2.out)
    label = "cct.jsonl:" in r.err
    exists = os.path.exists(f"{cwd}/cct.jsonl")
    ok = same and not (label and not exists)
    return ok, (
        f"two runs identical JSON: {same}; its progress bar is labelled 'cct.jsonl' "
        f"({label}), a file that exists nowhere the user can see (a removed temporary file): "
        f"{not exists}"
    )


# ---------------------------------------------------------------- interruption, resumption


@probe("interrupt.screen.chain")
def interrupt_screen_chain():
    """The 24-fault screening cut by SIGINT, SIGTERM, SIGHUP and SIGKILL in turn, resumed:
    the uninterrupted run's records and --json."""
    _, ref_recs, ref_rows = ref_screen()
    cwd = W("chain")
    clear_tmp()
    notes, bad = [], []
    cuts = ((signal.SIGINT, 3), (signal.SIGTERM, 10), (signal.SIGHUP, 16), (signal.SIGKILL, 20))
    for i, (sig, k) in enumerate(cuts):
        r = Run(screen24(), cwd, f"i{i}")
        wait_until(lambda k=k: nlines(f"{cwd}/s.jsonl") >= k, 150, r)
        r.signal(sig)
        rc = r.wait()
        left = orphans(r.pid)
        line = r.last_line()
        n = nlines(f"{cwd}/s.jsonl")
        if sig != signal.SIGKILL and (
            rc != EXPECT[sig] or f"({n} recorded)" not in line or "resume with:" not in line
        ):
            bad.append(f"{sig.name}: exit {rc}, '{line[:90]}'")
        if left:
            bad.append(f"{sig.name}: processes left {left}")
        notes.append(f"{sig.name}@{k}->{rc}")
    hid = [h for h in hidden(cwd) if h != ".s.jsonl.lock"]
    if hid:
        bad.append(f"hidden files {hid}")
    f = run(screen24(), cwd, "final")
    recs, n = records(f"{cwd}/s.jsonl")
    if f.rc != 0 or recs != ref_recs or n != 24 or screen_rows(f.out) != ref_rows:
        bad.append(f"resume exit {f.rc}, {n} lines, records equal {recs == ref_recs}")
    ran = sum(r["run_now"] for r in json.loads(f.out)) if f.rc == 0 else None
    if hidden(cwd):
        bad.append(f"after the resume, hidden files {hidden(cwd)}")
    if bad:
        return False, "; ".join(bad)
    return True, (
        f"{', '.join(notes)}; resume ran {ran} of 24, records and --json equal the "
        f"uninterrupted run's"
    )


@probe("interrupt.screen.lines")
def interrupt_screen_lines():
    """screen kundur --lines cut in its stage 1 and stage 2, resumed: the same rows."""
    args = ["screen", "kundur", "--lines", "--workers", "1", "--out", "L.jsonl", "--json"]
    ref = run(args, W("lref"), "ref")
    cwd = W("lines")
    bad = []
    for i, (sig, k) in enumerate(((signal.SIGINT, 5), (signal.SIGTERM, 17))):
        r = Run(args, cwd, f"i{i}")
        wait_until(lambda k=k: nlines(f"{cwd}/L.jsonl") >= k, 120, r, 0.005)
        r.signal(sig)
        rc = r.wait()
        if rc != EXPECT[sig] or orphans(r.pid):
            bad.append(f"{sig.name}: exit {rc}")
    f = run(args, cwd, "final")
    same = (
        f.rc == 0
        and screen_rows(f.out) == screen_rows(ref.out)
        and records(f"{cwd}/L.jsonl") == records(f"{W('lref')}/L.jsonl")
    )
    if not same:
        bad.append(f"resumed result differs (exit {f.rc})")
    if bad:
        return False, "; ".join(bad)
    return True, "kundur --lines cut in stage 1 and stage 2, resumed: same rows and records"


@probe("interrupt.sweep.resume+workers")
def interrupt_sweep_resume_workers():
    """sweep-cct miniwecc, 8 jobs: the same records on 1 and 2 workers; cut by SIGTERM after
    3 and resumed on 1 worker: the same records."""
    args = ["sweep-cct", "miniwecc", "--faults", "DEFAULT", "--esd-pct", "none,5,10,15",
            "--out", "r.jsonl", "--json"]  # fmt: skip
    a = run([*args, "--workers", "1"], W("sw1"), "a")
    b = run([*args, "--workers", "2"], W("sw2"), "b")
    ra, rb = records(f"{W('sw1')}/r.jsonl")[0], records(f"{W('sw2')}/r.jsonl")[0]
    bad = [] if a.rc == b.rc == 0 and ra == rb else [f"workers 1 vs 2 differ (exit {a.rc}, {b.rc})"]
    cwd = W("swi")
    r = Run([*args, "--workers", "2"], cwd, "i")
    wait_until(lambda: nlines(f"{cwd}/r.jsonl") >= 3, 120, r)
    r.signal(signal.SIGTERM)
    rc = r.wait()
    line = r.last_line()
    if rc != 143 or "recorded" not in line or orphans(r.pid):
        bad.append(f"SIGTERM: exit {rc} '{line[:80]}'")
    f = run([*args, "--workers", "1"], cwd, "f")
    rf = records(f"{cwd}/r.jsonl")
    if f.rc != 0 or rf[0] != ra or rf[1] != 8:
        bad.append(f"resume exit {f.rc}, {rf[1]} lines, equal {rf[0] == ra}")
    ran = json.loads(f.out)["ran"] if f.rc == 0 else None
    if bad:
        return False, "; ".join(bad)
    return True, (
        f"8 jobs: --workers 1 and 2 give the same records; SIGTERM after 3, resumed on 1 "
        f"worker ({ran} run now): same records"
    )


@probe("repro.screen.workers")
def repro_screen_workers():
    """screen kundur on 1, 2 and 2 workers again: identical --json rows and records."""
    outs = []
    for tag, workers in (("a", "1"), ("b", "2"), ("c", "2")):
        args = ["screen", "kundur", "--workers", workers, "--out", f"{tag}.jsonl", "--json"]
        outs.append(run(args, W("rw"), tag))
    recs = [records(f"{W('rw')}/{x}.jsonl")[0] for x in "abc"]
    rows = [screen_rows(r.out) if r.rc == 0 else None for r in outs]
    ok = (
        all(r.rc == 0 for r in outs)
        and rows[0] == rows[1] == rows[2]
        and recs[0] == recs[1] == recs[2]
    )
    return (
        ok,
        "screen kundur --json and records: workers 1, 2, 2 again identical" if ok else "differ",
    )


@probe("interrupt.double+group+tstp")
def interrupt_double_group_tstp():
    """Two and three signals in a row, SIGINT and SIGHUP to the process group: the exit of
    one of them, no traceback, nothing left; Ctrl-Z for 15 s then continued: the result."""
    _, _, ref_rows = ref_screen()
    bad, notes = [], []
    sets = (
        ((signal.SIGINT, signal.SIGINT), False),
        ((signal.SIGINT, signal.SIGTERM, signal.SIGHUP), False),
        ((signal.SIGINT,), True),
        ((signal.SIGHUP,), True),
    )
    for i, (sigs, group) in enumerate(sets):
        cwd = W(f"dbl{i}")
        r = Run(screen24(), cwd, "x")
        wait_until(lambda cwd=cwd: nlines(f"{cwd}/s.jsonl") >= 2, 120, r)
        for s in sigs:
            r.signal(s, group)
            time.sleep(0.05)
        rc = r.wait()
        left = orphans(r.pid)
        tb = "Traceback" in r.err
        name = "+".join(s.name for s in sigs) + (" (group)" if group else "")
        if rc not in {EXPECT[s] for s in sigs} or left or tb or hidden(cwd):
            bad.append(f"{name}: exit {rc}, left {left}, traceback {tb}, hidden {hidden(cwd)}")
        notes.append(f"{'+'.join(s.name[3:] for s in sigs)}{'(pg)' if group else ''}->{rc}")
    cwd = W("tstp")
    r = Run(screen24(), cwd, "x")
    wait_until(lambda: nlines(f"{cwd}/s.jsonl") >= 3, 120, r)
    r.signal(signal.SIGTSTP, True)
    time.sleep(15)
    r.signal(signal.SIGCONT, True)
    rc = r.wait()
    same = rc == 0 and screen_rows(r.out) == ref_rows
    if rc != 0 or not same or "stopped" in r.err:
        bad.append(
            f"Ctrl-Z 15 s then continued: exit {rc}, same {same}, warning {'stopped' in r.err}"
        )
    notes.append("TSTP15s+CONT->0")
    if bad:
        return False, "; ".join(bad)
    return True, ", ".join(notes) + ": statuses, no traceback, no process or file left"


@probe("resume.cut_record")
def resume_cut_record():
    """A record line cut (as by a kill): set aside (.damaged, a warning), its job run again,
    the same result."""
    cwd = W("cut")
    args = ["screen", "kundur", "--workers", "1", "--out", "k.jsonl", "--json"]
    a = run(args, cwd, "a")
    ref = records(f"{cwd}/k.jsonl")[0]
    with open(f"{cwd}/k.jsonl", "rb") as f:
        d = f.read()
    i = d.rstrip(b"\n").rfind(b"\n")
    with open(f"{cwd}/k.jsonl", "wb") as f:
        f.write(d[: i + 1 + 300])
    b = run(args, cwd, "b")
    ok = (
        a.rc == b.rc == 0
        and records(f"{cwd}/k.jsonl")[0] == ref
        and "damaged" in b.err
        and screen_rows(a.out) == screen_rows(b.out)
    )
    if not ok:
        return False, f"exit {b.rc}: {b.last_line()[:120]}"
    return True, "a record line cut: set aside (.damaged, warning), its job run again, same result"


@probe("interrupt.simulate")
def interrupt_simulate():
    """simulate: SIGINT mid-run ends it within 1.5 s saying 'nothing is kept'; SIGTERM while
    its --out is written leaves the old file and no temporary."""
    cwd = W("sim")
    os.makedirs(cwd)
    with open(f"{cwd}/sim.csv", "w") as f:
        f.write("old\n")
    bad = []
    sim = ["simulate", "miniwecc", "--fault", "83", "--far-bus", "33", "--clear-cycles", "4"]
    r = Run([*sim, "--tf", "900"], cwd, "a")
    time.sleep(5)
    t = time.monotonic()
    r.signal(signal.SIGINT)
    rc = r.wait()
    lat = time.monotonic() - t
    if rc != 130 or lat > 1.5 or "nothing is kept" not in r.last_line():
        bad.append(f"SIGINT mid-run: exit {rc} after {lat:.2f} s: '{r.last_line()[:80]}'")
    # a signal while the output is written: the old file stays, nothing hidden left
    r = Run([*sim, "--tf", "100", "--out", "sim.csv"], cwd, "b")
    seen = wait_until(lambda: bool(hidden(cwd)), 120, r, 0.002)
    time.sleep(0.3)
    r.signal(signal.SIGTERM)
    rc = r.wait()
    with open(f"{cwd}/sim.csv") as f:
        kept = f.read() == "old\n"
    if not seen or rc != 143 or not kept or hidden(cwd):
        bad.append(f"SIGTERM during the write: seen {seen}, exit {rc}, hidden {hidden(cwd)}")
    if bad:
        return False, "; ".join(bad)
    return True, (
        f"SIGINT mid-run 130 within {lat:.2f} s; SIGTERM while writing --out: 143, old file "
        f"intact, no temporary left"
    )


@probe("interrupt.import_psse")
def interrupt_import_psse():
    """SIGINT around import-psse's final write of WECC 240: 130 and the old file kept, or 0
    and the new one; never a mix, nothing hidden left."""
    cwd = W("imp")
    os.makedirs(cwd)
    raw, dyr = wecc240()
    bad, outcomes = [], set()
    for d in (0.0, 0.01, 0.02, 0.05, 0.3):
        with open(f"{cwd}/o.json", "w") as f:
            f.write('{"old": 1}')
        r = Run(["import-psse", raw, dyr, "-o", "o.json"], cwd, "x")
        wait_until(lambda: bool(hidden(cwd)), 60, r, 0.001)
        time.sleep(d)
        r.signal(signal.SIGINT)
        rc = r.wait()
        with open(f"{cwd}/o.json") as f:
            old = f.read() == '{"old": 1}'
        outcomes.add((rc, old))
        line = r.last_line()
        said = "nothing is kept" in line or "written whole" in line
        if (rc == 0) == old or hidden(cwd) or (rc == 130 and not said):
            bad.append(f"delay {d}: exit {rc}, old file kept {old}, hidden {hidden(cwd)}")
    if bad:
        return False, "; ".join(bad)
    return True, (
        f"SIGINT around the final write of WECC-240: outcomes {sorted(outcomes, key=str)} "
        f"(130 & old kept, or 0 & new)"
    )


@probe("interrupt.place")
def interrupt_place():
    """place: the same plan on 1 and 2 workers; SIGINT / SIGHUP during a run: 130 / 129, no
    plan, no process left (by design place has no resume)."""
    args = ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "10",
            "--out", "plan.json"]  # fmt: skip
    bad = []
    a = run([*args, "--workers", "1"], W("pl1"), "a")
    b = run([*args, "--workers", "2"], W("pl2"), "b")
    plans = []
    for x in ("pl1", "pl2"):
        with open(f"{W(x)}/plan.json") as f:
            plan = json.load(f)
        plan.pop("wall_time_s", None)
        plans.append(plan)
    if not (a.rc == b.rc == 0 and plans[0] == plans[1]):
        bad.append("plans differ between --workers 1 and 2")
    cwd = W("pli")
    # at 30 % and 70 % of the uninterrupted run on 2 workers (the testers': 3 s and 7 s, on
    # busier cores: a run shorter than 7 s ended before its SIGHUP)
    for sig, at in ((signal.SIGINT, 0.3), (signal.SIGHUP, 0.7)):
        r = Run([*args, "--workers", "2"], cwd, sig.name)
        time.sleep(at * b.wall)
        r.signal(sig)
        rc = r.wait()
        plan = os.path.exists(f"{cwd}/plan.json")
        if rc != EXPECT[sig] or orphans(r.pid) or plan or hidden(cwd):
            bad.append(f"{sig.name}: exit {rc}, plan {plan}, hidden {hidden(cwd)}")
    if bad:
        return False, "; ".join(bad)
    return True, (
        "plan JSON the same on 1 and 2 workers (but wall_time_s); SIGINT/SIGHUP: 130/129, "
        "'nothing is kept' (by design: place has no resume), no plan, no process left"
    )


@probe("interrupt.dask_local")
def interrupt_dask_local():
    """screen --scheduler local cut by SIGINT: 130, its cluster and scratch gone."""
    cwd = W("dask")
    clear_tmp()
    bad = []
    args = ["screen", "kundur", "--scheduler", "local", "--workers", "2", "--out", "d.jsonl"]
    r = Run(args, cwd, "a")
    wait_until(lambda: nlines(f"{cwd}/d.jsonl") >= 2, 180, r)
    r.signal(signal.SIGINT)
    rc = r.wait()
    left = orphans(r.pid, 10)
    if rc != 130 or left or tmp_left():
        bad.append(f"SIGINT: exit {rc}, left {left}, TMPDIR {tmp_left()}")
    kill_session(r.pid)
    if bad:
        return False, "; ".join(bad)
    return True, "--scheduler local: SIGINT 130, cluster and its stabctl-dask-* scratch gone"


@probe("sigkill.leftovers")
def sigkill_leftovers():
    """SIGKILL (the OOM killer, kill -9) cannot be handled; what it leaves should be cleaned
    by the next run of the same command, which owns the output (its lock)."""
    notes = []
    # simulate --out killed while writing: hidden temporary files beside the output
    cwd = W("k9sim")
    os.makedirs(cwd)
    sim = ["simulate", "miniwecc", "--fault", "83", "--far-bus", "33", "--clear-cycles", "4"]
    r = Run([*sim, "--tf", "100", "--out", "sim.csv"], cwd, "a")
    wait_until(lambda: bool(hidden(cwd)), 120, r, 0.002)
    time.sleep(0.5)
    r.signal(signal.SIGKILL)
    r.wait()
    run([*sim, "--tf", "3", "--out", "sim.csv"], cwd, "b")
    h = hidden(cwd)
    size = sum(os.path.getsize(f"{cwd}/{x}") for x in h)
    notes.append(
        f"simulate --out: {len(h)} hidden temporary file(s), {size / 1e6:.0f} MB, still there "
        f"after the next run"
    )
    # paper killed: its .paper-XXXX staging directory stays in OUT_DIR after a --resume
    cwd = W("k9paper")
    os.makedirs(cwd)
    r = Run(["paper", "--out-dir", "P", "--only", "table4"], cwd, "a")

    def staging():
        return any(
            os.listdir(d)
            for d in glob.glob(f"{cwd}/P/.paper-*")
            if not d.endswith(("work", ".lock"))
        )

    wait_until(staging, 200, r, 0.01)
    r.signal(signal.SIGKILL)
    r.wait()
    f = run(["paper", "--out-dir", "P", "--only", "table4", "--resume"], cwd, "b")
    stale = [
        x
        for x in hidden(f"{cwd}/P")
        if x.startswith(".paper-") and x not in (".paper-work", ".paper-work.lock")
    ]
    REF["paper_resumed_after_kill"] = (f.rc, f"{cwd}/P")
    notes.append(f"paper: {stale} (a half-written figure) still in OUT_DIR after --resume "
                 f"(exit {f.rc})")  # fmt: skip
    # a local sweep killed: its stabctl-running-* marks directory stays in TMPDIR
    clear_tmp()
    cwd = W("k9screen")
    r = Run(screen24(), cwd, "a")
    wait_until(lambda: nlines(f"{cwd}/s.jsonl") >= 2, 120, r)
    r.signal(signal.SIGKILL)
    r.wait()
    time.sleep(1)
    run(screen24(), cwd, "b")
    notes.append(f"screen: TMPDIR keeps {tmp_left()}")
    return not h and not stale and not tmp_left(), "; ".join(notes)


# ---------------------------------------------------------------- paper


def paper_ref():
    """An uninterrupted paper --only table4 (its OUT_DIR), once."""
    if "paper" not in REF:
        r = run(["paper", "--out-dir", "P1", "--only", "table4"], W("paper"), "ref", 600)
        assert r.rc == 0, f"paper exit {r.rc}: {r.last_line()}"
        REF["paper"] = f"{W('paper')}/P1"
    return REF["paper"]


PAPER_FILES = (
    "paper.md",
    "table4_kundur.jsonl",
    "table4_miniwecc.jsonl",
    "table4_cct_vs_rating.png",
)


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def same_files(a, b):
    """PAPER_FILES of OUT_DIR b missing or not byte-identical to a's."""
    return [
        f
        for f in PAPER_FILES
        if not os.path.exists(f"{b}/{f}") or read_bytes(f"{a}/{f}") != read_bytes(f"{b}/{f}")
    ]


@probe("paper.interrupt.resume")
def paper_interrupt_resume():
    """paper --only table4 cut by SIGINT, SIGTERM and SIGHUP, each saying how to resume,
    then resumed: byte-identical to an uninterrupted run (and after sigkill.leftovers's
    SIGKILL, when it ran)."""
    ref = paper_ref()
    cwd = W("paper")
    bad, notes = [], []

    def work():
        return sum(nlines(f) for f in glob.glob(f"{cwd}/P2/.paper-work/*.jsonl"))

    for i, (sig, k) in enumerate(((signal.SIGINT, 3), (signal.SIGTERM, 9), (signal.SIGHUP, 14))):
        resume = ["--resume"] if i else []
        r = Run(["paper", "--out-dir", "P2", "--only", "table4", *resume], cwd, f"i{i}")
        wait_until(lambda k=k: work() >= k, 200, r, 0.01)
        r.signal(sig)
        rc = r.wait()
        notes.append(f"{sig.name}@{k}->{rc}")
        if rc != EXPECT[sig] or orphans(r.pid) or "--resume" not in r.last_line():
            bad.append(f"{sig.name}: exit {rc}: {r.last_line()[:100]}")
    f = run(["paper", "--out-dir", "P2", "--only", "table4", "--resume"], cwd, "f", 600)
    diff = same_files(ref, f"{cwd}/P2")
    if f.rc != 0 or diff or hidden(f"{cwd}/P2"):
        bad.append(f"resume exit {f.rc}, differing {diff}, hidden {hidden(f'{cwd}/P2')}")
    rk = REF.get("paper_resumed_after_kill")
    if rk and (rk[0] != 0 or same_files(ref, rk[1])):
        bad.append(f"resumed after SIGKILL: exit {rk[0]}, differing {same_files(ref, rk[1])}")
    if bad:
        return False, "; ".join(bad)
    return True, (
        f"{', '.join(notes)}, resumed: paper.md, records and figure byte-identical to an "
        f"uninterrupted run"
    )


@probe("paper.commit_window")
def paper_commit_window():
    """A SIGTERM the moment the first report is moved into OUT_DIR (round 35: in the ~10 ms
    before the last record, OUT_DIR was left half replaced; now the interrupt is delivered
    after the final moves): OUT_DIR the old run's or the new run's, whole."""
    cwd = W("paperw")
    a = run(["paper", "--out-dir", "P", "--only", "analytic"], cwd, "a")
    if a.rc != 0:
        return False, f"paper --only analytic exit {a.rc}"
    ino = os.stat(f"{cwd}/P/paper.md").st_ino
    with open(f"{cwd}/P/run_log.json") as f:
        old_log = f.read()
    r = Run(["paper", "--out-dir", "P", "--only", "table4"], cwd, "b")

    def moved():
        try:
            return os.stat(f"{cwd}/P/paper.md").st_ino != ino
        except OSError:
            return False

    wait_until(moved, 300, r, 0.0005)
    r.signal(signal.SIGTERM)
    rc = r.wait()
    with open(f"{cwd}/P/paper.md") as f:
        md_new = "Table 4" in f.read()
    recs = [
        f
        for f in ("table4_kundur.jsonl", "table4_miniwecc.jsonl")
        if os.path.exists(f"{cwd}/P/{f}")
    ]
    with open(f"{cwd}/P/run_log.json") as f:
        log_old = f.read() == old_log
    mixed = rc != 0 and md_new and (len(recs) < 2 or log_old)
    return not mixed, (
        f"exit {rc}, '{r.last_line()[:60]}...'; OUT_DIR then holds the new paper.md (Table 4) "
        f"{md_new}, records delivered {recs}, run_log.json still the previous run's {log_old}"
    )


@probe("paper.message.nothing_kept")
def paper_message_nothing_kept():
    """paper --only analytic interrupted: it does not say records are kept where none are
    (round 35: named a directory that did not exist; now 'nothing is kept')."""
    cwd = W("papera")
    r = Run(["paper", "--out-dir", "PA", "--only", "analytic"], cwd, "a")
    time.sleep(2.5)
    r.signal(signal.SIGINT)
    rc = r.wait()
    line = r.last_line()
    exists = os.path.exists(f"{cwd}/PA")
    claims = "records" in line and "kept" in line
    return not (claims and not exists), f"exit {rc}: '{line[:110]}' -- OUT_DIR PA exists: {exists}"


@probe("concurrency.same_output")
def concurrency_same_output():
    """Two runs on one output at once (screen twice, sweep-cct beside screen, paper twice):
    one ends, the other is refused naming the holder; the paper run's result whole."""
    bad, notes = [], []
    for name, args in (
        ("screen", ["screen", "kundur", "--workers", "1", "--out", "s.jsonl", "--json"]),
        ("sweep+screen", None),
        ("paper", ["paper", "--out-dir", "PC", "--only", "table4"]),
    ):
        cwd = W(f"conc_{name}")
        if args is None:
            a = Run(
                ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5,10,15,20",
                 "--workers", "1", "--out", "s.jsonl"],
                cwd,
                "a",
            )  # fmt: skip
            time.sleep(0.3)
            b = Run(["screen", "kundur", "--workers", "1", "--out", "s.jsonl"], cwd, "b")
        else:
            a = Run(args, cwd, "a")
            time.sleep(0.3)
            b = Run(args, cwd, "b")
        ra, rb = a.wait(600), b.wait(600)
        refused = [x for x in (a, b) if "another stabctl process" in x.last_line()]
        if sorted([ra, rb], key=str) != [0, 2] or len(refused) != 1:
            bad.append(f"{name}: exits {ra}, {rb}: {a.last_line()[:60]} | {b.last_line()[:60]}")
        notes.append(f"{name}: {ra}/{rb}")
    # the paper run left its result whole
    if not bad and same_files(paper_ref(), f"{W('conc_paper')}/PC"):
        bad.append("paper run beside a refused one differs from the reference")
    if bad:
        return False, "; ".join(bad)
    return True, (
        f"two at once on one output: one ends, the other refused naming the holder "
        f"({', '.join(notes)})"
    )


@probe("repro.eig_report")
def repro_eig_report():
    """eig --report twice: identical files but the command line they name."""
    cwd = W("eigr")
    a = run(["eig", "miniwecc", "--report", "--out-dir", "R1"], cwd, "a")
    b = run(["eig", "miniwecc", "--report", "--out-dir", "R2"], cwd, "b")
    diff = []
    for f in sorted(os.listdir(f"{cwd}/R1")):
        x = read_bytes(f"{cwd}/R1/{f}").replace(b"--out-dir R1", b"--out-dir R2")
        if x != read_bytes(f"{cwd}/R2/{f}"):
            diff.append(f)
    ok = a.rc == b.rc == 0 and not diff
    return (
        ok,
        "eig --report twice: identical files (but the command line it names)"
        if ok
        else f"differ: {diff}",
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ids", nargs="*", help="probe names or their prefixes (paper, interrupt)")
    ap.add_argument("-k", default="", help="run the probes whose name holds this")
    opts = ap.parse_args(argv)
    selected = [
        fn
        for fn in PROBES
        if (not opts.ids or fn.pid in opts.ids or fn.pid.split(".")[0] in opts.ids)
        and opts.k in fn.pid
    ]
    t_start = time.monotonic()
    print(f"stabctl of {ROOT}; work directory {WORK}", flush=True)
    c = run(["compile"], WORK, "compile", timeout=900)  # a warm cache loads in seconds
    if c.rc != 0:
        print("stabctl compile failed:", c.err[-300:])
        shutil.rmtree(WORK, ignore_errors=True)
        return 2
    try:
        for fn in selected:
            t0 = time.monotonic()
            try:
                ok, why = fn()
            except Exception as ex:  # noqa: BLE001 - a probe that crashes is reported short
                where = traceback.format_exc().splitlines()[-3].strip()
                ok, why = False, f"probe crashed: {type(ex).__name__}: {str(ex)[:200]} | {where}"
            report(fn.pid, bool(ok), why, time.monotonic() - t0)
    finally:
        for sid in SESSIONS:
            kill_session(sid)
        keep = bool(os.environ.get("KEEP"))
        if not keep:
            shutil.rmtree(WORK, ignore_errors=True)
    n_short = sum(not ok for _, ok, _ in RESULTS)
    print(
        f"\n{len(RESULTS)} probes, {len(RESULTS) - n_short} ok, {n_short} SHORT; "
        f"{time.monotonic() - t_start:.0f} s; work directory {WORK} "
        f"({'kept' if keep else 'removed'})"
    )
    return 1 if n_short else 0


if __name__ == "__main__":
    sys.exit(main())
