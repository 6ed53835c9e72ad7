#!/usr/bin/env python
"""Thirty-third reliability round (round 47, part AC): issue 54's classes (no data loss, jobs
not run never recorded, interrupts keep finished work, no half-written output, long work
shows progress, reproducible outputs) tried with variants the earlier rounds did not:
`eig --report` and `estimate rmse --runs N` cut by SIGTERM / SIGHUP / SIGINT at start-up,
mid-run and while writing; `screen --plot` to /dev/full, under /proc, into a read-only
file system (/sys), under a file; `place CASE.json --out CASE.json` (an output equal to
an input); two `eig --report` into one directory at once; a reader polling `--plot` and
the report while another run rewrites them; `--json` stdout pure JSON beside the progress
of sweep-cct and estimate rmse; the same command twice giving the same bytes (screen
--plot .svg/.pdf, sweep-cct records, estimate rmse --json).

    python reliability_probes_33.py [ID ...]

CLONE (default: this repository) is the package under test; NUMBA_CACHE_DIR the caller's
(warm it first with `python -m stabctl compile`).  Prints per probe: id, ok/SHORT, reason;
exits 1 if any is SHORT.  Every command has a timeout; work in a temporary directory
(removed at the end unless KEEP=1).  About 6 minutes with a warm kernel cache.

The contract (docs/cli.md "The command line"; issue 54 "What to build"): Ctrl-C, SIGTERM,
SIGHUP end every command with 130 / 143 / 129 and one line `interrupted: <what was kept>;
resume with / run again with: <command>`; output files must be creatable in an existing
directory, refused before any work when they cannot be replaced or another option reads
them; a write that fails names the output; a figure is the same bytes every time.

The round found 4 of 18 short, all but one from one cause: `screen --plot` is the one output
not written through stabctl.parallel.atomic_write (stabctl/cli/stability.py screen ->
plotting.figures.screening_map -> save_figure -> fig.savefig(path) in place): a reader sees
an empty or partial figure (AC12), a SIGTERM as it writes leaves 0-124 bytes and loses the
old figure (AC14), a failed write (ulimit -f) leaves a truncated figure and says only
"error: File too large" (AC15); and `estimate rmse` shows no progress at all (AC09: 20 s of
silence on miniWECC at 30 runs, longer with more).  All four fixed: the map written through
atomic_write, and a bar of rmse's noise and ambient runs on stderr.
"""

# ruff: noqa: E501, BLE001, SIM115, RUF015, I001, RUF007, RUF059, RUF100 - a tester's script, kept as written

import glob
import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time

from _probe_kit import Kit

KIT = Kit("probes_ac47_", path=False, env={"COLUMNS": "120"})
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
rec, probe = KIT.rec, KIT.probe
TMP = os.path.join(WD, "tmpdir")
os.makedirs(TMP)
ENV["TMPDIR"] = TMP
ENV.pop("TQDM_DISABLE", None)
EXPECT = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGHUP: 129}
K_BUSES = "1,2,3,4,10,11,12,13"  # Kundur bus faults: a few seconds each


def W(name):
    d = os.path.join(WD, name)
    os.makedirs(d, exist_ok=True)
    return d


def _pre():
    for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM, signal.SIGQUIT):
        signal.signal(s, signal.SIG_DFL)


class Run:
    """`python -m stabctl ARGS` detached (own session), stdout/stderr to TAG.out/TAG.err."""

    def __init__(self, args, cwd, tag, env=None):
        self.cwd, self.tag = cwd, tag
        self.fo = open(f"{cwd}/{tag}.out", "wb")  # noqa: SIM115
        self.fe = open(f"{cwd}/{tag}.err", "wb")  # noqa: SIM115
        self.p = subprocess.Popen(
            [sys.executable, "-m", "stabctl", *map(str, args)],
            cwd=cwd, stdout=self.fo, stderr=self.fe, stdin=subprocess.DEVNULL,
            start_new_session=True, preexec_fn=_pre, env=env or ENV,
        )  # fmt: skip
        self.t0 = time.monotonic()
        self.rc = None

    def signal(self, sig, group=False):
        try:
            (os.killpg if group else os.kill)(self.p.pid, sig)
        except ProcessLookupError:
            pass

    def wait(self, timeout=300):
        try:
            self.rc = self.p.wait(timeout)
        except subprocess.TimeoutExpired:
            try:
                os.killpg(self.p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.p.wait()
            self.rc = "TIMEOUT"
        self.fo.close()
        self.fe.close()
        self.wall = time.monotonic() - self.t0
        return self.rc

    @property
    def out(self):
        with open(f"{self.cwd}/{self.tag}.out", errors="replace") as f:
            return f.read()

    @property
    def err(self):
        with open(f"{self.cwd}/{self.tag}.err", errors="replace", newline="") as f:
            return f.read()

    def lines(self):
        t = self.err.replace("\r", "\n")
        return [ln for ln in t.splitlines() if ln.strip() and "%|" not in ln]

    def last(self):
        ls = self.lines()
        return ls[-1] if ls else ""


def run(args, cwd, tag, timeout=300, env=None):
    r = Run(args, cwd, tag, env)
    r.wait(timeout)
    return r


def wait_for(pred, timeout):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if pred():
            return True
        time.sleep(0.05)
    return False


def nlines(path):
    try:
        with open(path, "rb") as f:
            return sum(1 for ln in f if ln.strip())
    except FileNotFoundError:
        return 0


def keys(path):
    ks = []
    with open(path) as f:
        for ln in f:
            if ln.strip():
                ks.append(json.loads(ln).get("key"))
    return ks


def no_traceback(r):
    return "Traceback" not in r.err


def hidden_left(d):
    return [x for x in os.listdir(d) if x.startswith(".") or "~stabctl" in x or x.endswith(".tmp")]


# ================================================================== probes


# ---------------------------------------------------------------- outputs that cannot be


@probe("AC01")
def _():
    """screen --plot /dev/full: the figure is written after the searches; its failure (a full
    disk) must exit non-zero with one error line naming the output, no traceback, the
    finished records kept (docs/cli.md: 'a write that fails without naming its file (a full
    disk, ulimit -f) names the output in its error: line')."""
    d = W("ac01")
    os.symlink("/dev/full", f"{d}/full.png")
    bad, notes = [], []
    for k, plot in enumerate(("/dev/full", "full.png")):
        r = run(
            [
                "screen",
                "kundur",
                "--buses",
                "1,2",
                "--workers",
                "1",
                "--out",
                f"s{k}.jsonl",
                "--plot",
                plot,
            ],
            d,
            f"a{k}",
        )
        n = nlines(f"{d}/s{k}.jsonl")
        ok = (
            r.rc not in (0, "TIMEOUT")
            and plot in r.last()
            and no_traceback(r)
            and (n == 2 or r.rc == 2)
        )
        (notes if ok else bad).append(
            f"--plot {plot}: exit {r.rc}, records {n}, '{r.last()[:110]}'"
        )
    return not bad, "; ".join(bad or notes)


@probe("AC02")
def _():
    """screen --plot under /proc (a directory where no file can be made): refused before any
    work, exit 2, one error line naming it, no records file written ('writing nothing')."""
    d = W("ac02")
    r = run(
        [
            "screen",
            "kundur",
            "--buses",
            "1,2",
            "--workers",
            "1",
            "--out",
            "s.jsonl",
            "--plot",
            "/proc/stabctl_probe.png",
        ],
        d,
        "a",
        timeout=120,
    )
    made = os.path.exists(f"{d}/s.jsonl")
    ok = (
        r.rc == 2
        and "/proc/stabctl_probe.png" in r.last()
        and no_traceback(r)
        and not made
        and r.wall < 30
    )
    return ok, f"exit {r.rc} after {r.wall:.1f} s, records file made: {made}, '{r.last()[:150]}'"


@probe("AC03")
def _():
    """screen --out in a read-only file system (/sys, root cannot write it either), and
    sweep-cct --out there: refused before any work (exit 2, the path named), no traceback."""
    d = W("ac03")
    bad, notes = [], []
    for tag, args, path in (
        (
            "screen",
            [
                "screen",
                "kundur",
                "--buses",
                "1",
                "--workers",
                "1",
                "--out",
                "/sys/stabctl_probe.jsonl",
            ],
            "/sys/stabctl_probe.jsonl",
        ),
        (
            "sweep",
            [
                "sweep-cct",
                "kundur",
                "--faults",
                "DEFAULT",
                "--workers",
                "1",
                "--out",
                "/sys/kernel/stabctl_probe.jsonl",
            ],
            "/sys/kernel/stabctl_probe.jsonl",
        ),
        (
            "plot",
            [
                "screen",
                "kundur",
                "--buses",
                "1",
                "--workers",
                "1",
                "--out",
                "p.jsonl",
                "--plot",
                "/sys/stabctl_probe.svg",
            ],
            "/sys/stabctl_probe.svg",
        ),
    ):
        r = run(args, d, tag, timeout=120)
        notes.append(f"{tag}: {r.rc} {r.wall:.1f}s")
        if not (r.rc == 2 and path in r.last() and no_traceback(r) and r.wall < 30):
            bad.append(f"{tag}: exit {r.rc} after {r.wall:.1f} s '{r.last()[:140]}'")
    if os.path.exists(f"{d}/p.jsonl"):
        bad.append("plot refused but p.jsonl written")
    return not bad, "; ".join(bad) if bad else ", ".join(notes)


@probe("AC04")
def _():
    """An output whose parent is a file: screen --out F/x.jsonl, screen --plot F/x.png, eig
    --report --out-dir F/sub, place --out F/p.json: exit 2, one error line naming it, nothing
    written, no traceback."""
    d = W("ac04")
    with open(f"{d}/F", "w") as f:
        f.write("a file\n")
    bad, notes = [], []
    for tag, args in (
        (
            "screen-out",
            ["screen", "kundur", "--buses", "1", "--workers", "1", "--out", "F/x.jsonl"],
        ),
        (
            "screen-plot",
            [
                "screen",
                "kundur",
                "--buses",
                "1",
                "--workers",
                "1",
                "--out",
                "q.jsonl",
                "--plot",
                "F/x.png",
            ],
        ),
        ("eig", ["eig", "kundur", "--report", "--out-dir", "F/sub"]),
        (
            "place",
            [
                "place",
                "kundur",
                "--faults",
                "DEFAULT",
                "--target-cct-gain",
                "5",
                "--workers",
                "1",
                "--out",
                "F/p.json",
            ],
        ),
    ):
        r = run(args, d, tag, timeout=120)
        notes.append(f"{tag} {r.rc}")
        if not (r.rc == 2 and "F/" in r.last() and no_traceback(r) and r.wall < 30):
            bad.append(f"{tag}: exit {r.rc} after {r.wall:.1f} s '{r.last()[:140]}'")
    if open(f"{d}/F").read() != "a file\n" or os.path.exists(f"{d}/q.jsonl"):
        bad.append("F changed or q.jsonl written")
    return not bad, "; ".join(bad) if bad else ", ".join(notes)


@probe("AC05")
def _():
    """An output equal to an input: place k.json --out k.json (the case file read is the
    plan's output), and via a symlink to it: refused before any work (docs/cli.md: 'An
    output file that another option of the command reads ... is refused before any work'),
    k.json unchanged."""
    d = W("ac05")
    shutil.copy(os.path.join(CLONE, "stabctl/case/data/kundur.json"), f"{d}/k.json")
    os.symlink("k.json", f"{d}/link.json")
    with open(f"{d}/f.csv", "w") as f:
        f.write("bus,far_bus\n3,101\n")
    before = open(f"{d}/k.json", "rb").read()
    bad, notes = [], []
    for tag, out in (("same", "k.json"), ("link", "link.json"), ("abs", f"{d}/./k.json")):
        r = run(
            [
                "place",
                "k.json",
                "--faults",
                "f.csv",
                "--target-cct-gain",
                "5",
                "--workers",
                "1",
                "--out",
                out,
            ],
            d,
            tag,
            timeout=240,
        )
        notes.append(f"{tag}: {r.rc} {r.wall:.1f}s")
        if not (r.rc == 2 and no_traceback(r) and r.wall < 30):
            bad.append(f"--out {out}: exit {r.rc} after {r.wall:.1f} s '{r.last()[:140]}'")
        if open(f"{d}/k.json", "rb").read() != before:
            bad.append(f"--out {out}: the case file k.json was overwritten")
            shutil.copy(os.path.join(CLONE, "stabctl/case/data/kundur.json"), f"{d}/k.json")
    return not bad, "; ".join(bad) if bad else ", ".join(notes)


# ---------------------------------------------------------------- eig --report


def report_files(d):
    """{name: bytes} of a report directory (hidden files listed as such)."""
    out = {}
    if not os.path.isdir(d):
        return out
    for root, _, files in os.walk(d):
        for f in files:
            p = os.path.join(root, f)
            out[os.path.relpath(p, d)] = open(p, "rb").read()
    return out


def png_whole(b):
    return b.startswith(b"\x89PNG") and b.rstrip().endswith(b"IEND\xaeB`\x82")


def report_consistent(files, ref):
    """A report directory: every file whole and equal to the reference's (the same
    command), or absent as a set; no hidden file."""
    hidden = [k for k in files if os.path.basename(k).startswith(".") or "~stabctl" in k]
    if hidden:
        return False, f"hidden/temporary files left: {hidden}"
    diff = [k for k in files if k in ref and files[k] != ref[k]]
    extra = [k for k in files if k not in ref]
    if diff or extra:
        return False, f"files differing from a whole report: {diff} extra {extra}"
    md = [k for k in files if k.endswith(".md")]
    if md:  # a report present: every figure it names present
        missing = [k for k in ref if k not in files]
        if missing:
            return False, f"report present but its figures missing: {missing}"
    return True, f"{len(files)} files whole"


REF_EIG = {}


def eig_ref():
    if not REF_EIG:
        d = W("eigref")
        r = run(["eig", "kundur", "--report", "--out-dir", "R"], d, "ref")
        REF_EIG["rc"] = r.rc
        REF_EIG["files"] = report_files(f"{d}/R")
        REF_EIG["wall"] = r.wall
    return REF_EIG


@probe("AC06")
def _():
    """Two `eig kundur --report --out-dir R` at once (same report files): both end 0, or one
    is refused naming the holder; R then holds one whole report (the reference's bytes), no
    temporary file left."""
    ref = eig_ref()
    if ref["rc"] != 0:
        return False, f"reference eig --report exit {ref['rc']}"
    d = W("ac06")
    a = Run(["eig", "kundur", "--report", "--out-dir", "R"], d, "a")
    time.sleep(0.2)
    b = Run(["eig", "kundur", "--report", "--out-dir", "R"], d, "b")
    ra, rb = a.wait(300), b.wait(300)
    ok1 = (ra, rb) == (0, 0) or (
        sorted([ra, rb], key=str) == [0, 2] and any("another" in x.last() for x in (a, b))
    )
    ok2, why = report_consistent(report_files(f"{d}/R"), ref["files"])
    tb = not (no_traceback(a) and no_traceback(b))
    return (
        ok1 and ok2 and not tb,
        f"exits {ra}/{rb} ('{a.last()[:60]}' | '{b.last()[:60]}'); {why}; traceback: {tb}",
    )


@probe("AC07")
def _():
    """eig --report over an existing report, cut by SIGTERM / SIGHUP / SIGINT at start-up,
    mid-linearisation and around the write (a sweep of moments from 0.3 s to past the
    reference's wall time): each exit 143/129/130 with `interrupted: ...` (or 0 when it had
    ended), the report directory always the whole old report or the whole new one (here the
    same bytes), never a half-written .md or PNG, nothing hidden left."""
    ref = eig_ref()
    if ref["rc"] != 0:
        return False, f"reference eig --report exit {ref['rc']}"
    wall = ref["wall"]
    moments = [0.3, 1.0] + [wall * f for f in (0.5, 0.8, 0.9, 0.95, 1.0, 1.05)]
    sigs = [signal.SIGTERM, signal.SIGHUP, signal.SIGINT]
    bad, notes = [], []
    d = W("ac07")
    for i, at in enumerate(moments):
        sig = sigs[i % 3]
        R = f"{d}/R"
        shutil.rmtree(R, ignore_errors=True)
        shutil.copytree(f"{W('eigref')}/R", R)
        # an old report that differs: its md marked, so that old and new can be told apart
        md = [k for k in ref["files"] if k.endswith(".md")][0]
        with open(f"{R}/{md}", "ab") as f:
            f.write(b"\nOLD REPORT\n")
        r = Run(["eig", "kundur", "--report", "--out-dir", "R"], d, f"t{i}")
        time.sleep(at)
        r.signal(sig)
        rc = r.wait(120)
        files = report_files(R)
        old = files.get(md, b"").endswith(b"OLD REPORT\n")
        if old:
            files[md] = ref["files"][md]
        ok, why = report_consistent(files, ref["files"])
        notes.append(f"{at:.1f}s {signal.Signals(sig).name}->{rc} {'old' if old else 'new'}")
        if not ok:
            bad.append(f"{signal.Signals(sig).name} at {at:.2f} s: {why}")
        if rc == 0:
            if old:
                bad.append(f"at {at:.2f} s: exit 0 but the old report left")
        elif rc != EXPECT[sig] or not r.last().startswith("interrupted:") or not no_traceback(r):
            bad.append(f"{signal.Signals(sig).name} at {at:.2f} s: exit {rc} '{r.last()[:100]}'")
        elif not old:
            bad.append(
                f"{signal.Signals(sig).name} at {at:.2f} s: exit {rc} but the report replaced ('{r.last()[:80]}')"
            )
    return not bad, "; ".join(bad) if bad else "; ".join(notes)


# ---------------------------------------------------------------- estimate rmse --runs N

RMSE = [
    "estimate",
    "rmse",
    "kundur",
    "--fault",
    "3",
    "--far-bus",
    "101",
    "--ambient-s",
    "10",
    "--ambient-runs",
    "2",
]


@probe("AC08")
def _():
    """estimate rmse --runs 8 (it keeps nothing) cut by SIGHUP at start-up, SIGTERM
    mid-Monte-Carlo, SIGINT in the runs without fault: 129 / 143 / 130 with
    `interrupted: nothing is kept; run again with: <command>` naming this command, within
    a few seconds, no traceback, nothing printed on stdout as if it were the figures."""
    d = W("ac08")
    ref = run([*RMSE, "--runs", "8", "--json"], d, "ref", timeout=300)
    if ref.rc != 0:
        return False, f"uncut run exit {ref.rc}: {ref.last()[:120]}"
    bad, notes = [], []
    for sig, at in (
        (signal.SIGHUP, 0.6),
        (signal.SIGTERM, ref.wall * 0.4),
        (signal.SIGINT, ref.wall * 0.85),
    ):
        r = Run([*RMSE, "--runs", "8", "--json"], d, signal.Signals(sig).name)
        time.sleep(at)
        t0 = time.monotonic()
        r.signal(sig)
        rc = r.wait(120)
        lat = time.monotonic() - t0
        last = r.last()
        notes.append(f"{signal.Signals(sig).name}@{at:.1f}s->{rc} in {lat:.1f}s")
        if rc == 0:
            continue
        if (
            rc != EXPECT[sig]
            or not last.startswith("interrupted:")
            or "estimate rmse kundur" not in last
            or not no_traceback(r)
        ):
            bad.append(f"{signal.Signals(sig).name} at {at:.1f} s: exit {rc} '{last[:140]}'")
        if lat > 5:
            bad.append(f"{signal.Signals(sig).name}: ended {lat:.1f} s after the signal")
        if r.out.strip():
            bad.append(f"{signal.Signals(sig).name}: stdout '{r.out[:60]}' after an interrupt")
    return not bad, "; ".join(bad) if bad else f"uncut {ref.wall:.1f} s; " + ", ".join(
        notes
    ) + f"; line '{last[:110]}'"


def run_pty_err(args, cwd, timeout=300):
    """Run with stdout to a pipe and stderr to a terminal (a pty): (rc, stdout, stderr)."""
    import pty

    import fcntl
    import struct
    import termios

    m, s = pty.openpty()
    fcntl.ioctl(s, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))  # a terminal's size
    p = subprocess.Popen(
        [sys.executable, "-m", "stabctl", *map(str, args)], cwd=cwd, env=ENV,
        stdout=subprocess.PIPE, stderr=s, stdin=subprocess.DEVNULL, start_new_session=True,
    )  # fmt: skip
    os.close(s)
    buf = bytearray()
    stamps = [time.monotonic()]

    def reader():
        while True:
            try:
                b = os.read(m, 4096)
            except OSError:
                break
            if not b:
                break
            stamps.append(time.monotonic())
            buf.extend(b)

    t = threading.Thread(target=reader, daemon=True)
    t.start()
    try:
        out, _ = p.communicate(timeout=timeout)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        rc = "TIMEOUT"
    t.join(5)
    os.close(m)
    stamps.append(time.monotonic())
    global LAST_SILENCE
    LAST_SILENCE = max(b - a for a, b in zip(stamps, stamps[1:]))
    return rc, out.decode(errors="replace"), buf.decode(errors="replace")


LAST_SILENCE = 0.0


def shows_progress(err, total=None):
    """A bar with a fraction done and the time left (tqdm's 'n/N [elapsed<left')."""
    import re

    frac = re.search(r"(\d+)/(\d+)", err)
    left = re.search(r"<\s*\d+:\d\d|<\s*\d+(\.\d+)?s|\d+ s left| left\]|time left", err)
    return bool(frac and left), (frac.group(0) if frac else None)


@probe("AC09")
def _():
    """estimate rmse miniwecc --runs 30 --json (its defaults but the runs; about half a
    minute) with stderr a terminal, stdout a pipe: stdout is one pure JSON document; stderr
    shows the Monte Carlo's fraction done and time left (issue 54: long work shows
    progress; stabctl.progress: 'a long batch of runs is never silent', HEARTBEAT_S 8 s):
    ok when a fraction and time left is shown or no silence exceeds 10 s."""
    d = W("ac09")
    t0 = time.monotonic()
    rc, out, err = run_pty_err(
        [
            "estimate",
            "rmse",
            "miniwecc",
            "--fault",
            "83",
            "--far-bus",
            "33",
            "--runs",
            "30",
            "--json",
        ],
        d,
    )
    wall = time.monotonic() - t0
    try:
        json.loads(out)
        pure = True
    except ValueError as e:
        pure = f"not JSON: {e} '{out[:80]}'"
    prog, frac = shows_progress(err)
    ok = rc == 0 and pure is True and (prog or LAST_SILENCE <= 10)
    tail = err.replace("\r", "\n").strip().splitlines()
    return (
        ok,
        f"exit {rc} after {wall:.0f} s; longest silence on stderr {LAST_SILENCE:.1f} s; {len(err.strip())} bytes on stderr; stdout pure JSON: {pure}; progress with fraction and time left on stderr: {prog} ({frac}); stderr's last line '{(tail[-1] if tail else '')[:100]}'",
    )


@probe("AC10")
def _():
    """sweep-cct --json with stderr a terminal: stdout every line a JSON record (no bar
    frame, no message), stderr a bar with fraction and time left; then `screen --json` the
    same."""
    d = W("ac10")
    bad, notes = [], []
    for tag, args in (
        (
            "sweep",
            [
                "sweep-cct",
                "kundur",
                "--faults",
                "DEFAULT",
                "--esd-pct",
                "none,5",
                "--workers",
                "1",
                "--out",
                "s.jsonl",
                "--json",
            ],
        ),
        (
            "screen",
            [
                "screen",
                "kundur",
                "--buses",
                "1,2,3",
                "--workers",
                "1",
                "--out",
                "c.jsonl",
                "--json",
            ],
        ),
    ):
        rc, out, err = run_pty_err(args, d)
        lines = [ln for ln in out.splitlines() if ln.strip()]
        nonjson = []
        for ln in lines:
            try:
                json.loads(ln)
            except ValueError:
                nonjson.append(ln[:60])
        if not lines:  # one document?
            nonjson.append("(empty stdout)")
        if len(lines) > 1 and nonjson:
            try:
                json.loads(out)
                nonjson = []
            except ValueError:
                pass
        prog, frac = shows_progress(err)
        notes.append(f"{tag}: exit {rc}, {len(lines)} stdout lines, bar {frac}")
        if rc != 0 or nonjson or not prog:
            bad.append(f"{tag}: exit {rc}, non-JSON stdout {nonjson[:2]}, progress {prog}")
    return not bad, "; ".join(bad) if bad else "; ".join(notes)


# ---------------------------------------------------------------- the same bytes


@probe("AC11")
def _():
    """The same command twice gives the same bytes: screen --plot .svg and .pdf (docs/cli.md:
    'a figure (--plot PNG, PDF or SVG) is the same bytes every time it is written'),
    estimate rmse --json (seeded), sweep-cct's records (but the wall-time and worker fields)."""
    d = W("ac11")
    bad, notes = [], []
    for ext in ("svg", "pdf"):
        outs = []
        for k in (1, 2):
            r = run(
                [
                    "screen",
                    "kundur",
                    "--buses",
                    "1,2,3",
                    "--workers",
                    "1",
                    "--out",
                    f"s{k}{ext}.jsonl",
                    "--plot",
                    f"m{k}.{ext}",
                ],
                d,
                f"{ext}{k}",
            )
            outs.append(
                open(f"{d}/m{k}.{ext}", "rb").read() if os.path.exists(f"{d}/m{k}.{ext}") else None
            )
            if r.rc != 0:
                bad.append(f"{ext} run {k}: exit {r.rc} {r.last()[:80]}")
        if outs[0] is None or outs[0] != outs[1]:
            bad.append(
                f"--plot .{ext}: two runs differ ({len(outs[0] or b'')} / {len(outs[1] or b'')} bytes)"
            )
        else:
            notes.append(f".{ext} same {len(outs[0])} bytes")
    js = [run([*RMSE, "--runs", "3", "--json"], d, f"rm{k}").out for k in (1, 2)]
    if not js[0] or js[0] != js[1]:
        bad.append("estimate rmse --json twice: differs")
    else:
        notes.append("rmse --json same bytes")
    recs = []
    for k in (1, 2):
        run(
            [
                "sweep-cct",
                "kundur",
                "--faults",
                "DEFAULT",
                "--esd-pct",
                "none,5",
                "--workers",
                "2",
                "--out",
                f"w{k}.jsonl",
            ],
            d,
            f"sw{k}",
        )
        rows = []
        for ln in open(f"{d}/w{k}.jsonl"):
            o = json.loads(ln)

            def strip(x):
                if isinstance(x, dict):
                    return {a: strip(b) for a, b in x.items() if "wall" not in a and a != "worker"}
                return x

            rows.append(json.dumps(strip(o), sort_keys=True))
        recs.append(sorted(rows))
    if recs[0] != recs[1]:
        bad.append("sweep-cct twice: records differ beyond wall times")
    else:
        notes.append(f"sweep records same ({len(recs[0])})")
    return not bad, "; ".join(bad) if bad else "; ".join(notes)


@probe("AC12")
def _():
    """A reader of --plot at any moment sees the old file or the new whole one: an old
    map.png (another figure) replaced by a screen run (resumed from its records, so the
    figure is written at once); polled every 2 ms meanwhile."""
    d = W("ac12")
    r0 = run(
        [
            "screen",
            "kundur",
            "--buses",
            "1,2",
            "--workers",
            "1",
            "--out",
            "s.jsonl",
            "--plot",
            "old.png",
        ],
        d,
        "a",
    )
    if r0.rc != 0:
        return False, f"first screen exit {r0.rc}: {r0.last()[:100]}"
    old = open(f"{d}/old.png", "rb").read()
    seen, stop = set(), threading.Event()
    partial = []

    def poll():
        while not stop.is_set():
            try:
                b = open(f"{d}/map.png", "rb").read()
            except FileNotFoundError:
                b = None
            if b is not None and b != old:
                seen.add(b)
                if not png_whole(b):
                    partial.append(len(b))
            time.sleep(0.002)

    bads = []
    for k in range(3):
        shutil.copy(f"{d}/old.png", f"{d}/map.png")
        stop.clear()
        t = threading.Thread(target=poll)
        t.start()
        r = run(
            [
                "screen",
                "kundur",
                "--buses",
                "1,2,3" if k == 0 else "1,2",
                "--workers",
                "1",
                "--out",
                "s.jsonl",
                "--plot",
                "map.png",
            ],
            d,
            f"b{k}",
        )
        stop.set()
        t.join()
        if r.rc != 0:
            bads.append(f"run {k} exit {r.rc}")
    ok = not partial and not bads and len(seen) <= 2
    return (
        ok,
        f"{len(seen)} distinct new contents seen, {len(partial)} partial reads {partial[:3]}; {bads}",
    )


@probe("AC15")
def _():
    """screen --plot over an existing figure when the figure's write fails (the file size
    limit, RLIMIT_FSIZE 20 KB, below the map's ~30 KB; the records already complete so only
    the figure is written): exit non-zero with one error line naming --plot's file, the old
    figure left as it was (atomic_write: 'a failure leaves every one of them as it was'),
    no partial file, no hidden temporary file left."""
    import resource

    d = W("ac15")
    r0 = run(
        [
            "screen",
            "kundur",
            "--buses",
            "1,2",
            "--workers",
            "1",
            "--out",
            "s.jsonl",
            "--plot",
            "map.png",
        ],
        d,
        "a",
    )
    if r0.rc != 0:
        return False, f"first screen exit {r0.rc}"
    old = open(f"{d}/map.png", "rb").read()

    def lim():
        _pre()
        resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)

    p = subprocess.run(
        [sys.executable, "-m", "stabctl", "screen", "kundur", "--buses", "1,2,3", "--workers", "1", "--out", "s.jsonl", "--plot", "map.png"],
        cwd=d, env=ENV, capture_output=True, text=True, timeout=300, preexec_fn=lim,
    )  # fmt: skip
    new = open(f"{d}/map.png", "rb").read() if os.path.exists(f"{d}/map.png") else None
    last = [ln for ln in p.stderr.replace("\r", "\n").splitlines() if ln.strip() and "%|" not in ln]
    last = last[-1] if last else ""
    kept = new == old
    hid = hidden_left(d)
    ok = (
        p.returncode not in (0,)
        and "map.png" in last
        and "Traceback" not in p.stderr
        and kept
        and not hid
    )
    return ok, (
        f"exit {p.returncode} '{last[:120]}'; old figure kept: {kept} "
        f"(now {None if new is None else len(new)} bytes, was {len(old)}, whole PNG {png_whole(new or b'')}); hidden left {hid}"
    )


# ---------------------------------------------------------------- interrupt and resume


@probe("AC13")
def _():
    """sweep-cct kundur, 8 jobs on 2 workers, SIGHUP to the whole process group (a closed
    terminal) mid-run, then resumed on 1 worker: exit 129, its line says how many were kept
    and that number equals the records file's lines; the resumed run runs only the rest
    (no key twice) and the records equal an uncut run's (but wall times); nothing recorded
    for a job that had not ended (every record a verdict)."""
    d = W("ac13")
    base = ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5,10,20"]
    ref = run([*base, "--workers", "2", "--out", "ref.jsonl"], d, "ref")
    if ref.rc != 0:
        return False, f"uncut exit {ref.rc}"
    r = Run([*base, "--workers", "2", "--out", "cut.jsonl"], d, "cut")
    wait_for(lambda: nlines(f"{d}/cut.jsonl") >= 3, 200)
    r.signal(signal.SIGHUP, group=True)
    rc = r.wait(120)
    kept = nlines(f"{d}/cut.jsonl")
    line = r.last()
    import re

    m = re.search(r"(\d+)", line)
    said = int(m.group(1)) if m else None
    r2 = run([*base, "--workers", "1", "--out", "cut.jsonl"], d, "res")
    ks = keys(f"{d}/cut.jsonl")
    dup = len(ks) != len(set(ks))

    def norm(p):
        out = {}
        for ln in open(p):
            o = json.loads(ln)
            res = o.get("result", o)
            out[o.get("key")] = json.dumps(
                {
                    a: b
                    for a, b in (res.items() if isinstance(res, dict) else [])
                    if "wall" not in a
                },
                sort_keys=True,
            )
        return out

    same = norm(f"{d}/ref.jsonl") == norm(f"{d}/cut.jsonl")
    failed = [ln for ln in open(f"{d}/cut.jsonl") if '"failed"' in ln]
    ok = (
        rc == 129
        and said == kept
        and r2.rc == 0
        and not dup
        and same
        and not failed
        and line.startswith("interrupted:")
    )
    return ok, (
        f"SIGHUP to group: exit {rc} '{line[:120]}'; file had {kept}; resume exit {r2.rc} "
        f"'{r2.last()[:80]}'; duplicates {dup}; equal to uncut {same}; failed records {len(failed)}"
    )


@probe("AC14")
def _():
    """screen --lines --plot cut by SIGTERM the moment its last record is written (while the
    figure is drawn and written): exit 143 with every record kept (or 0, finished), the
    figure absent or whole, no hidden temporary file; the resumed run runs nothing again
    and writes the figure.  Then the SIGTERM the moment the write of the figure over an
    old one begins: the old figure or the new whole one, never a partial one."""
    d = W("ac14")
    args = [
        "screen",
        "kundur",
        "--buses",
        "1,2",
        "--lines",
        "--workers",
        "1",
        "--out",
        "s.jsonl",
        "--plot",
        "m.png",
    ]
    ref = run([*args[:-4], "--out", "ref.jsonl", "--plot", "ref.png"], d, "ref")
    total = nlines(f"{d}/ref.jsonl")
    if ref.rc not in (0, 1) or total == 0:
        return False, f"uncut exit {ref.rc}, {total} records"
    bad, notes = [], []
    for i, delay in enumerate((0.0, 0.4, 0.8, 1.2, 1.5, 1.8, 2.1, 2.5, 3.0)):
        for f in glob.glob(f"{d}/s.jsonl*") + glob.glob(f"{d}/m.png"):
            os.remove(f)
        r = Run(args, d, f"c{i}")
        wait_for(lambda: nlines(f"{d}/s.jsonl") >= total, 300)
        time.sleep(delay)
        r.signal(signal.SIGTERM)
        rc = r.wait(120)
        kept = nlines(f"{d}/s.jsonl")
        png = open(f"{d}/m.png", "rb").read() if os.path.exists(f"{d}/m.png") else None
        hid = hidden_left(d)
        notes.append(
            f"+{delay}s->{rc} kept {kept}/{total} png {'whole' if png and png_whole(png) else ('none' if png is None else 'PARTIAL')}"
        )
        if (
            rc not in (0, 1, 143)
            or kept != total
            or (png is not None and not png_whole(png))
            or hid
            or not no_traceback(r)
        ):
            bad.append(f"+{delay}s: exit {rc} kept {kept}/{total} hidden {hid} '{r.last()[:80]}'")
        if rc == 143 and png is not None:
            bad.append(f"+{delay}s: exit 143 (interrupted) yet the figure was written")
        if rc in (0, 1) and png is None:
            bad.append(f"+{delay}s: exit {rc} without the figure")
        r2 = run(args, d, f"r{i}")
        if r2.rc != ref.rc or not os.path.exists(f"{d}/m.png") or nlines(f"{d}/s.jsonl") != total:
            bad.append(
                f"+{delay}s resume: exit {r2.rc}, figure {os.path.exists(f'{d}/m.png')}, {nlines(f'{d}/s.jsonl')} records"
            )
        elif open(f"{d}/m.png", "rb").read() != open(f"{d}/ref.png", "rb").read():
            bad.append(f"+{delay}s resume: figure differs from the uncut run's")
    # the signal the moment the figure's write begins (an old figure there, its size seen to change)
    refpng = open(f"{d}/ref.png", "rb").read()
    for i in range(3):
        for f in glob.glob(f"{d}/s.jsonl*"):
            os.remove(f)
        with open(f"{d}/m.png", "wb") as f:
            f.write(refpng + b"OLD")  # an old figure, told apart by its tail
        r = Run(args, d, f"w{i}")
        size0 = len(refpng) + 3
        hit = wait_for(
            lambda: os.path.exists(f"{d}/m.png") and os.stat(f"{d}/m.png").st_size != size0, 300
        )
        r.signal(signal.SIGTERM)
        rc = r.wait(120)
        png = open(f"{d}/m.png", "rb").read() if os.path.exists(f"{d}/m.png") else None
        state = (
            "absent"
            if png is None
            else (
                "old"
                if png == refpng + b"OLD"
                else ("new" if png == refpng else f"PARTIAL {len(png)} bytes")
            )
        )
        notes.append(f"at the write ({hit}): {rc}, figure {state}")
        if state.startswith("PARTIAL") or state == "absent":
            bad.append(
                f"SIGTERM as the figure's write began: exit {rc}, the figure {state} (old one lost), '{r.last()[:80]}'"
            )
        elif rc == 143 and state == "new":
            bad.append("SIGTERM at the write: exit 143 'interrupted' yet the new figure written")
    return not bad, "; ".join(bad) if bad else "; ".join(notes)


PLACE = ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "5", "--workers", "2"]


def plan_core(path):
    """A plan's JSON without its wall times."""

    def strip(x):
        if isinstance(x, dict):
            return {a: strip(b) for a, b in x.items() if "wall" not in a and "time_s" not in a}
        if isinstance(x, list):
            return [strip(v) for v in x]
        return x

    return json.dumps(strip(json.load(open(path))), sort_keys=True)


@probe("AC16")
def _():
    """place kundur --out p.json over an old plan, cut by SIGTERM at start-up, early and
    late in its runs: 143, `interrupted: ...` saying what was kept, p.json the old plan
    byte for byte, no hidden file beside it; the same command again gives the uncut run's
    plan (but wall times) and leaves no memo in the cache (docs/cli.md: 'the file removed
    once the command has ended with its output written')."""
    d = W("ac16")
    ref = run([*PLACE, "--out", "ref.json"], d, "ref", timeout=300)
    if ref.rc != 0:
        return False, f"uncut place exit {ref.rc}: {ref.last()[:100]}"
    old = b'{"old": "plan"}\n'
    bad, notes = [], []
    for i, (sig, at) in enumerate(
        ((signal.SIGTERM, 0.5), (signal.SIGTERM, ref.wall * 0.4), (signal.SIGHUP, ref.wall * 0.75))
    ):
        with open(f"{d}/p.json", "wb") as f:
            f.write(old)
        r = Run([*PLACE, "--out", "p.json"], d, f"c{i}")
        time.sleep(at)
        r.signal(sig)
        rc = r.wait(120)
        now = open(f"{d}/p.json", "rb").read()
        notes.append(f"{signal.Signals(sig).name}@{at:.1f}s->{rc} '{r.last()[:70]}'")
        if rc == 0:
            continue
        if rc != EXPECT[sig] or not r.last().startswith("interrupted:") or not no_traceback(r):
            bad.append(f"{signal.Signals(sig).name} at {at:.1f} s: exit {rc} '{r.last()[:100]}'")
        if now != old:
            bad.append(
                f"{signal.Signals(sig).name} at {at:.1f} s: p.json changed ({len(now)} bytes)"
            )
        if hidden_left(d):
            bad.append(f"hidden files left: {hidden_left(d)}")
    r2 = run([*PLACE, "--out", "p.json"], d, "resume", timeout=300)
    if r2.rc != 0 or plan_core(f"{d}/p.json") != plan_core(f"{d}/ref.json"):
        bad.append(
            f"resumed: exit {r2.rc}, plan equal to the uncut one: {r2.rc == 0 and plan_core(f'{d}/p.json') == plan_core(f'{d}/ref.json')}"
        )
    memo = [m for m in glob.glob(f"{WD}/xdg/stabctl-place/*") if os.path.isfile(m)]
    if memo:
        bad.append(
            f"memo files left after the plan was written: {[os.path.basename(m) for m in memo]}"
        )
    return not bad, "; ".join(bad) if bad else "; ".join(notes)


def children(pid):
    try:
        out = subprocess.run(
            ["ps", "-o", "pid=,args=", "--ppid", str(pid)],
            capture_output=True,
            text=True,
            timeout=10,
        ).stdout
    except Exception:
        return []
    return [
        int(ln.split()[0]) for ln in out.splitlines() if ln.strip() and "resource_tracker" not in ln
    ]


@probe("AC17")
def _():
    """screen kundur --lines --workers 2 with one worker process SIGKILLed mid-job (the OOM
    killer's way): no job recorded as failed because its worker died (issue 54: jobs not
    run are never recorded as results), the screening ends with the uncut run's verdicts
    (run again, or the run says the job was lost and exits non-zero without recording it)."""
    d = W("ac17")
    args = ["screen", "kundur", "--buses", "1,2,3", "--lines", "--workers", "2"]
    ref = run([*args, "--out", "ref.jsonl"], d, "ref")
    if ref.rc not in (0, 1):
        return False, f"uncut exit {ref.rc}"
    r = Run([*args, "--out", "k.jsonl"], d, "k")
    wait_for(lambda: nlines(f"{d}/k.jsonl") >= 4, 200)
    kids = children(r.p.pid)
    if kids:
        os.kill(kids[0], signal.SIGKILL)
    rc = r.wait(300)
    recs = [json.loads(ln) for ln in open(f"{d}/k.jsonl")]
    failed = [x for x in recs if x.get("status") == "failed"]
    dup = len({x["key"] for x in recs}) != len(recs)
    r2 = run([*args, "--out", "k.jsonl"], d, "k2")

    def verdicts(p):
        return {
            json.loads(ln)["key"]: json.loads(ln).get("result", {}).get("cct_s") for ln in open(p)
        }

    same = verdicts(f"{d}/k.jsonl") == verdicts(f"{d}/ref.jsonl")
    ok = kids and not failed and not dup and same and "Traceback" not in r.err
    return ok, (
        f"killed worker {kids[:1]}: exit {rc} '{r.last()[:110]}'; {len(recs)} records, failed {[x.get('reason', x.get('error', ''))[:80] for x in failed][:1]}, "
        f"duplicates {dup}; after a rerun (exit {r2.rc}) the same CCTs as uncut: {same}"
    )


@probe("AC18")
def _():
    """place miniwecc --faults DEFAULT --required-clearing-cycles 5 --load-levels 0.9,1.0 (a minute or more) with stderr a terminal: its
    long stretches (the screening's CCTs, each round's verifying runs) show a fraction done
    and the time left (issue 54, a newcomer's friction: 'placement's stretches show no
    fraction or time left'; docs/placement.md: one line per step, a batch's status with its
    fraction and time left repeated every 8 s of silence): ok when a fraction and time left
    is shown or no silence exceeds 10 s."""
    d = W("ac18")
    import re

    t0 = time.monotonic()
    rc, out, err = run_pty_err(
        [
            "place",
            "miniwecc",
            "--faults",
            "DEFAULT",
            "--required-clearing-cycles",
            "5",
            "--load-levels",
            "0.9,1.0",
            "--workers",
            "2",
            "--out",
            "p.json",
        ],
        d,
        timeout=600,
    )
    wall = time.monotonic() - t0
    frames = [f for f in re.split(r"[\r\n]+", err) if f.strip()]
    bars = [f for f in frames if re.search(r"\d+/\d+", f) and re.search(r"<\s*\d|left", f)]
    ok = rc == 0 and (bool(bars) or LAST_SILENCE <= 10)
    return ok, (
        f"exit {rc} after {wall:.0f} s; longest silence on stderr {LAST_SILENCE:.1f} s; {len(frames)} stderr lines/frames, {len(bars)} with a fraction and time left"
        + (
            f", e.g. '{bars[-1][:90]}'"
            if bars
            else f"; lines like '{frames[len(frames) // 2][:90] if frames else ''}'"
        )
    )


def main():
    KIT.main(summary="\n{ok} ok, {short} SHORT of {n}", keep_any=True, kept="work dir kept: {wd}")


if __name__ == "__main__":
    main()
