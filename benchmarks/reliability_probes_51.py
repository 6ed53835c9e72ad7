#!/usr/bin/env python
"""Round 56 (AV): long work as a log file shows it.  Each long command runs with stdout
and stderr on pipes (no terminal), every line (split at \\n and at tqdm's \\r frames)
timestamped as it arrives; from that log: the longest silence, the longest stretch whose
lines carry no new fraction done or time left (a bar counts, a repeated identical line
does not), fractions that go back, a time left repeated unchanged ("a clock that does
not move"), and, where asked, SIGINT in the middle and what is kept.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_51.py [AV01,...]

The developers' guide: "Long work shows progress (fraction done, time left) and can be
interrupted without losing finished results."  A probe is SHORT when a stretch over
LIMIT_S (60 s) shows no fraction or time left, or a line is stale/contradictory.
Minutes per probe on 2 cores with a warm kernel cache (`stabctl compile`); LOGS=<dir>
keeps the timestamped logs.

Found (round 56, AV, on one core): AV03 (paper placement, Pareto plans in threads
sharing one pool: "miniwecc 6 cycles: ... 111 evaluate job(s) running" for 88-96 s while
its jobs wait, then "1 of 111 done, about 11317 s left" for a batch that ended 105 s
later); AV12 (place: the heartbeat repeats "40 of 42 done (95%), about 2 s left"
unchanged for ~50 s; 62-78 s of "1 evaluate job(s) running" without a fraction);
AV08 (screen --workers 1: a bar silent 80 s on 0/171); AV09 (sweep-cct: tqdm's
"<00:04" left with 137 s to go, and two 100 % frames of one bar with different rates);
AV02 (a bar at 100 % then the same name from 0/5, three times); AV01 (compile on an
empty cache: 2 min of "still compiling (N s)", no fraction).  `--log LOG...` judges
logs already written (tsrun style: "t stream text").

Fixed (99c940b5): a plan's batch line worked out at each heartbeat (`stabctl.progress.
BatchClock`: the pace from the first job that ends, the time left going down between ends
and, once spent, how long the jobs left have run; shares rounded down; kept jobs told at
once); a bar in a log drawn again every 30 s while no job ends (mean rate, its full frame
once); a long compile names its kernel with its time left by the reference machine; the
rounds of more seeds named; simulate says it writes a long run's outputs.  Rerun on main:
AV08 ok (longest stretch 36 s: a 50-s search in this process holds the GIL from the
redrawing thread), AV12 ok but for the plan's exit status 1 (not verified: a verdict,
accepted for `place`), no stale line; AV03 (835 s) ok, longest stretch 46 s, no stale line
(a batch's end is the first line of its speaker with another batch's total or start:
"0 of 4 job(s) done" of the next was read as this one's); AV09 ok, longest stretch 34 s,
two times left off by more than 3x (OFF: said, not SHORT).
"""

# ruff: noqa
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from _probe_kit import Kit, stabctl

KIT = Kit("probes_av56.", line="{pid:<6} {state:<5} {why}", timed=True)
CLONE, ENV, WD = KIT.clone, KIT.env, KIT.wd
rec, probe = KIT.rec, KIT.probe
LIMIT_S = 60.0
#: a time left off by more than 3x: said, not SHORT (round 57: a sweep whose last three of
#: 63 jobs were 50-60 s searches said "about 22 s left" with 184 s to go; no pace of the
#: jobs done foresees that, and the line then says how long they have run past it); a
#: time left repeated unchanged, a share of 100 % with jobs left, a bar drawn twice at
#: 100 % or begun again under its name stay SHORT
OFF = "(time left off) "
LOGS = Path(os.environ.get("LOGS", WD / "logs"))
PSSE = Path("/work/shared/reference/psse/wecc240")

FRAC = re.compile(
    r"((?<![@\d.])\d+(\.\d+)?\s*%|(?<![\d.])\d+\s*/\s*\d+(?![\d.])|\bleft\b|remaining|<\d+:\d\d|\b\d+ of \d+\b)"
)
LEFT = re.compile(r"about (\d+) s left|<(\d+:\d\d)")


def logged(name, args, timeout=900, interrupt_at=None, env=None):
    """Run `stabctl args` in WD, stdout/stderr on pipes; the timestamped lines
    [(t, stream, text)], rc, and the log's path."""
    LOGS.mkdir(parents=True, exist_ok=True)
    t0 = time.time()
    rows, lock = [], threading.Lock()
    p = subprocess.Popen(
        ["timeout", str(timeout), "nice", *stabctl(args)],
        cwd=WD,
        env=env or ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
    )

    def pump(f, tag):
        buf, shown = b"", b""

        def w(text):
            if text.strip():
                with lock:
                    rows.append((time.time() - t0, tag, text.decode(errors="replace")))

        while ch := f.read1(4096):
            buf += ch
            while (
                i := min([j for j in (buf.find(b"\n"), buf.find(b"\r")) if j >= 0], default=-1)
            ) >= 0:
                line, buf = buf[:i], buf[i + 1 :]
                if line != shown:
                    w(line[len(shown) :] if shown and line.startswith(shown) else line)
                shown = b""
            if buf and buf != shown:  # tqdm: "\r" + frame + flush, shown now
                w(buf[len(shown) :] if shown and buf.startswith(shown) else buf)
                shown = buf
        if buf != shown:
            w(buf)

    th = [
        threading.Thread(target=pump, args=(p.stdout, "O")),
        threading.Thread(target=pump, args=(p.stderr, "E")),
    ]
    for t in th:
        t.start()
    if interrupt_at is not None:
        try:
            p.wait(interrupt_at)
        except subprocess.TimeoutExpired:
            rows.append((time.time() - t0, "#", "SIGINT"))
            os.kill(p.pid, signal.SIGINT)  # timeout passes it on to the command
    rc = p.wait()
    for t in th:
        t.join()
    end = time.time() - t0
    path = LOGS / f"{name}.log"
    path.write_text("".join(f"{t:9.2f} {s} {x}\n" for t, s, x in rows) + f"{end:9.2f} # rc={rc}\n")
    return rows, rc, end, path


def _stretch(body, end):
    """(longest stretch without a new fraction/time-left line, its start, its last line)."""
    prev, nof, seen, last = (body[0][0] if body else 0.0), (0.0, 0.0, ""), set(), ""
    for t, _, x in body + [(end, "", "<end>")]:
        if x == "<end>" or (FRAC.search(x) and x not in seen):
            nof = max(nof, (t - prev, prev, last[:100]))
            prev = t
            seen.add(x)
        last = x
    return nof


def stretches(rows, end):
    """(longest silence, its start), (longest stretch without a new fraction/time-left
    line: over the whole log, and per speaker, the text before a line's first ': ' (the
    paper's placement runs plans in threads, each line named by its plan)), [stale or
    contradictory lines]."""
    body = [r for r in rows if r[1] != "#"]
    prev, sil = 0.0, (0.0, 0.0)
    for t, _, _ in body + [(end, "", "")]:
        sil = max(sil, (t - prev, prev))
        prev = t
    nof = _stretch(body, end)
    # per speaker (the text before "... ", e.g. "miniwecc 6 cycles: "; the paper's
    # placement runs plans in threads): from its first heartbeat line without a fraction
    # ("... 111 evaluate job(s) running") to its next line of another text
    hb = (0.0, 0.0, "")
    for i, (t, _, x) in enumerate(body):
        k = x.find("... ")
        if k < 0 or FRAC.search(x[k:]) or (i and body[i - 1][2] == x):
            continue
        who = x[:k]
        prior = [y for _, _, y in body[:i] if y.startswith(who) and y.find("... ") == k]
        if prior and prior[-1] == x:
            continue  # not the first of its run
        nxt = [t2 for t2, _, y in body[i + 1 :] if y.startswith(who) and y != x]
        hb = max(hb, ((nxt[0] if nxt else end) - t, t, x[:100]))
    if hb[0] > nof[0]:
        nof = hb
    stale, last = [], {}
    for i, (t, _, x) in enumerate(body):
        m = LEFT.search(x)
        if m and x in last and t - last[x] > 15:  # a time left said again unchanged
            stale.append(f"{t:.0f} s: '{x[:90]}' unchanged since {last[x]:.0f} s")
        if m and x not in last:
            last[x] = t
        k = re.search(r"(\d+) of (\d+) job\(s\) done \(100%\)", x)
        if k and k.group(1) != k.group(2):  # "334 of 335 ... (100%)"
            stale.append(f"{t:.0f} s: '{x[:70]}' says 100 % with jobs left")
        s = re.search(r"about (\d+) s left", x)
        if s and int(s.group(1)) > 20:  # the real remainder: until its batch's last line
            name = x.split(": ...")[0]
            # its batch: the total and when it was handed in ("0 of 4 job(s) done" of the
            # next batch, same speaker, is not this one's)
            ident = lambda y: re.findall(r"of (\d+) job\(s\) done|handed in (\d\d:\d\d)", y)
            fin = [
                t2 for t2, _, x2 in body[i + 1 :] if x2.startswith(name) and ident(x2) != ident(x)
            ]
            if fin and not (fin[0] - t) / 3 <= int(s.group(1)) <= 3 * (fin[0] - t) + 20:
                stale.append(
                    f"{OFF}{t:.0f} s: '{x[:80]}' but the batch ended {fin[0] - t:.0f} s later"
                )
        # tqdm's "[elapsed<mm:ss," or stabctl's "[elapsed, about N s left," (since 559f9697)
        q = re.match(r"(.+?):\s+(\d+)%\|.*\[[\d:]+(?:<(\d+):(\d\d)|, about ()(\d+) s left),", x)
        if q and int(q.group(2)) < 100:  # a bar's time left against its own 100 % frame
            fin = [
                t2
                for t2, _, x2 in body[i + 1 :]
                if re.match(re.escape(q.group(1)) + r":\s+100%\|", x2)
            ]
            said = int(q.group(3) or 0) * 60 + int(q.group(4) or q.group(6))
            real = fin[0] - t if fin else None
            if real is not None and real > 20 and not real / 3 <= said <= 3 * real:
                stale.append(f"{OFF}{t:.0f} s: '{x[:80]}' but it reached 100 % {real:.0f} s later")
        if (
            i
            and re.match(r".+?:\s+100%\|", x)
            and re.match(r".+?:\s+100%\|", body[i - 1][2])
            and x.split(":")[0] == body[i - 1][2].split(":")[0]
            and x != body[i - 1][2]
        ):
            stale.append(f"{t:.0f} s: bar '{x.split(':')[0]}' at 100 % printed twice, rates differ")
        b = re.match(r"(.+?):\s+100%\|", x)
        if b and any(re.match(re.escape(b.group(1)) + r":\s+0%\|", y) for _, _, y in body[i + 1 :]):
            stale.append(f"{t:.0f} s: bar '{b.group(1)}' at 100 %, then the same bar from 0 %")
    return sil, nof, sorted(set(stale))


def judged(pid, args, timeout=900, interrupt_at=None, env=None):
    """Run and judge; a plan not verified (`place`'s exit status 1) is a verdict."""
    rows, rc, end, path = logged(pid, args, timeout, interrupt_at, env)
    sil, nof, stale = stretches(rows, end)
    why = (
        f"{' '.join(args)[:70]}: rc {rc}, {end:.0f} s; silence {sil[0]:.0f} s at {sil[1]:.0f} s; "
        f"no fraction {nof[0]:.0f} s from {nof[1]:.0f} s (until '{nof[2][:60]}')"
    )
    if stale:
        why += f"; {len(stale)} stale time-left line(s), first {stale[0]}"
    verdicts = (0, 1, 130) if args[0] == "place" else (0, 130)
    hard = [x for x in stale if not x.startswith(OFF)]
    return rc in verdicts and nof[0] <= LIMIT_S and not hard, why + f" [{path}]"


#: 21 miniwecc line faults of CCT 0.05-0.4 s (a `place` of 4-9 minutes on one core)
FAULTS21 = (
    "84,28 33,83 33,85 83,85 20,24 84,20 49,113 72,69 115,46 6,79 6,28 83,84 63,96 "
    "6,106 63,66 63,97 83,103 24,86 7,10 24,15 68,69"
)
# commands as their words (one string each: a list of words, one a line, hid them)
PLACE21 = "place miniwecc --faults f21.csv --target-cct-gain 10 --load-levels 0.95,1.0 --workers 1".split()
PLACE_DEFAULT = "place miniwecc --faults DEFAULT --target-cct-gain 10 --load-levels 0.95,1.0 --workers 1".split()
CASES = [
    ("AV02", "paper --only estimation --out-dir p_est".split()),
    ("AV03", "paper --only placement --out-dir p_pl".split()),  # 11-17 min
    ("AV04", "paper --only table4 --out-dir p_t4".split()),
    (
        "AV05",
        "paper --only wecc --only convergence --only cases --only analytic --out-dir p_rest".split(),
    ),
    ("AV06", PLACE_DEFAULT),
    ("AV07", PLACE_DEFAULT + ["--set-aside-infeasible"]),
    ("AV08", "screen miniwecc --lines --workers 1 --out scr.jsonl".split()),
    (
        "AV09",
        "sweep-cct miniwecc --faults f21.csv --esd-pct none,5,10 --out s.jsonl --workers 1".split(),
    ),
    ("AV10", "estimate cct kundur --fault 3 --far-bus 101 --esd-pct 5 --runs 20".split()),
    ("AV11", "eig miniwecc --report --out-dir eig".split()),
    ("AV12", PLACE21 + ["--set-aside-infeasible"]),
]


def _f21():
    (WD / "f21.csv").write_text(
        "bus,far_bus,t_fault\n" + "".join(f"{f},1\n" for f in FAULTS21.split())
    )


@probe("AV01")
def av01():
    """`stabctl compile` on an empty kernel cache of its own: its parts named as they end."""
    env = dict(ENV, NUMBA_CACHE_DIR=str(WD / "numba_cold"))
    return judged("AV01", ["compile", "kundur"], timeout=900, env=env)


for _pid, _args in CASES:
    probe(_pid)(lambda a=_args, p=_pid: (_f21(), judged(p, a))[1])


@probe("AV13")
def av13():
    """place: SIGINT while its first batch runs keeps the finished jobs, and the same
    command reads them back (the brief: interrupted without losing finished results)."""
    _f21()
    rows, rc, end, path = logged("AV13a", PLACE21, interrupt_at=60)
    kept = [x for _, _, x in rows if "finished simulation job(s) are kept" in x]
    rows2, rc2, _, _ = logged("AV13b", PLACE21, interrupt_at=20)
    read = [x for _, _, x in rows2 if "read from" in x]
    return rc == 130 and kept and read, f"rc {rc}: {kept[:1]}; rerun: {read[:1]} [{path}]"


def judge_log(path):
    """Judge a log written by `logged` (or tsrun-style: "t stream text") without running."""
    rows, end = [], 0.0
    for ln in Path(path).read_text().splitlines():
        t, rest = float(ln[:9]), ln[10:]
        end = t
        if not rest.startswith("#"):
            rows.append(
                (t, rest[:1], rest[3:] if rest[1:2] in "rpe " and rest[2:3] == " " else rest[2:])
            )
    sil, nof, stale = stretches(rows, end)
    print(
        f"{path}: silence {sil[0]:.0f} s at {sil[1]:.0f} s; no fraction {nof[0]:.0f} s from {nof[1]:.0f} s ('{nof[2][:90]}')"
    )
    for x in stale:
        print("  " + x)


if __name__ == "__main__" and sys.argv[1:2] == ["--log"]:
    for a in sys.argv[2:]:
        judge_log(a)
    sys.exit(0)
if __name__ == "__main__":
    KIT.main(banner="work dir {wd}, package {clone}", keep_any=True)
