#!/usr/bin/env python
"""Twenty-eighth reliability round (round 44, part W): variants of issue 54's items 1-5 (long work interrupted and resumed,
PMU streams from peers that misbehave, the compile cache, memory bounds of readers).

    python benchmarks/reliability_probes_28.py [ONLY_PREFIX ...]

The package under test is CLONE's (default: this repository), run as `python -m stabctl`;
NUMBA_CACHE_DIR is the caller's (warm it with `stabctl compile`).  Prints per probe: id,
ok/SHORT, reason; exits 1 if any is SHORT.  Every command has a timeout; all work in a
temporary directory (removed at the end unless KEEP=1).

The round found short: a records file of 223 MiB (under the 256 MiB cap of every input) read at 1.8 GiB, 9 million lines that are no records read with one warning each (1.9 GiB, 195 s), a 250 MiB case file parsed whole (1.4 GiB) before its refusal (W-M8, W-M8b, W-M9); fixed by the 64 MiB cap of JSON text read whole (`stabctl.jsontext.MAX_JSON_BYTES`). A whole run takes about 25 minutes (the cache probes recompile).
"""

# ruff: noqa: E501, BLE001, F841, RUF015, RUF059, UP031 - a tester's script, kept as written

import json
import os
import shutil
import signal
import socket
import struct
import time
from pathlib import Path

from _probe_kit import (
    FakeServer,
    Kit,
    crc_ccitt,
    free_port,
    group_alive,
    lines_of,
    read_frame,
    records,
    split_frames,
    stamp_of,
    tail,
    tb,
    wait_listen,
    with_stamp,
)

KIT = Kit("probes_w44.", line="{pid:<8} {state:<5} {why}", show_tb=True)
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
run, run_rss, start, finish = KIT.run, KIT.run_rss, KIT.start, KIT.finish
rec, probe = KIT.rec, KIT.probe
recording, track_tcp = KIT.recording, KIT.track_tcp
KUNDUR = Path(CLONE) / "stabctl/case/data/kundur.json"


# ---------------------------------------------------------------- 1. interrupted long work
SWEEP = ["sweep-cct", "kundur", "--faults", "DEFAULT", "--workers", 1, "--tol-ms", 5]


def keys_of(path):
    return [r.get("key") for r in records(path) if r]


@probe("W-R1")
def sweep_truncated_tail():
    """A sweep's records file whose last line was cut (a kill during its write, a full
    disk): the next run names the damaged line clearly, runs that job again and keeps the
    finished ones (issue 54 item 1: nothing finished is lost, nothing repeated; 'a
    corrupt/truncated last line handled with a clear message')."""
    out = WD / "r1.jsonl"
    rc, o, e, dt = run([*SWEEP, "--out", out], timeout=600)
    if rc != 0:
        return False, f"first sweep exit {rc}: {tail(e)}"
    full = lines_of(out)
    if len(full) != 2:
        return False, f"first sweep wrote {len(full)} lines, expected 2 (DEFAULT has 2 faults)"
    (WD / "r1_full.jsonl").write_text("\n".join(full) + "\n")
    out.write_text(full[0] + "\n" + full[1][: len(full[1]) // 2])  # cut, no newline
    rc2, o2, e2, dt2 = run([*SWEEP, "--out", out], timeout=600)
    bad = []
    if tb(e2):
        bad.append("traceback: " + tail(e2))
    if rc2 not in (0,):
        bad.append(f"resume exit {rc2}: {tail(e2)}")
    ks = keys_of(out)
    if sorted(set(ks)) != sorted(set(keys_of(WD / "r1_full.jsonl"))) or len(ks) != len(set(ks)):
        bad.append(f"records after resume: keys {ks}")
    said = (o2 + e2).lower()
    if not any(
        w in said
        for w in (
            "line 2",
            "damaged",
            "cut",
            "truncat",
            "incomplete",
            "not json",
            "unreadable",
            "set aside",
        )
    ):
        bad.append(f"no word of the cut line: {tail(o2 + e2, 200)}")
    return not bad, "; ".join(bad) or f"resume ran the cut job, said: {tail(e2, 160)}"


@probe("W-R2")
def sweep_other_case():
    """A records file written for another case (kundur's, with machine 1's H changed) is
    refused (or its jobs run again), never taken as this case's results (issue 54 item 1:
    'a records file from a different case/settings is refused rather than mixed')."""
    src = WD / "r1_full.jsonl"
    if not src.exists():
        return False, "needs W-R1's records"
    d = json.loads(KUNDUR.read_text())
    m = d["tables"]["machines"]
    hi = m["columns"].index("H")
    m["rows"][0][hi] = m["rows"][0][hi] * 0.5
    d["name"] = "kundur"
    case = WD / "kundur.json"  # same file name stem as the built-in
    case.write_text(json.dumps(d))
    out = WD / "r2.jsonl"
    shutil.copy(src, out)
    fl = WD / "faults.csv"
    fl.write_text("bus,far_bus\n3,101\n13,101\n")
    rc, o, e, dt = run(
        ["sweep-cct", case, "--faults", fl, "--workers", 1, "--tol-ms", 5, "--out", out, "--json"],
        timeout=600,
    )
    if tb(e):
        return False, "traceback: " + tail(e)
    if rc == 2 and out.read_text() == src.read_text():
        return True, f"refused: {tail(e, 200)}"
    recs = [r for r in records(out) if r]
    ran = len(recs) > 2
    if ran:
        return True, f"jobs run again for the changed case (exit {rc}), {len(recs)} lines"
    return (
        False,
        f"exit {rc}: the other case's CCTs taken as this case's ({dt:.0f} s, nothing run): {tail(o + e, 200)}",
    )


@probe("W-R3")
def sweep_other_settings():
    """The same case and faults with another --t-max (a different setting of the search):
    the recorded CCTs were searched under other settings; expected refused or run again,
    not skipped as 'already in' (issue 54 item 1)."""
    src = WD / "r1_full.jsonl"
    if not src.exists():
        return False, "needs W-R1's records"
    out = WD / "r3.jsonl"
    shutil.copy(src, out)
    rc, o, e, dt = run([*SWEEP, "--out", out, "--t-max", 0.5, "--tf", 5.5], timeout=600)
    if tb(e):
        return False, "traceback: " + tail(e)
    if rc == 2 and out.read_text() == src.read_text():
        return True, f"refused: {tail(e, 200)}"
    if len(lines_of(out)) > 2:
        return True, f"run again (exit {rc})"
    return False, f"exit {rc}: skipped as done: {tail(o + e, 200)}"


def sweep_killed(sig, pid_id, when_lines, jobs_pct="none,5"):
    out = WD / f"{pid_id}.jsonl"
    args = [
        "sweep-cct",
        "kundur",
        "--faults",
        "DEFAULT",
        "--esd-pct",
        jobs_pct,
        "--workers",
        2,
        "--tol-ms",
        5,
        "--out",
        out,
    ]
    p = start(args)
    t = time.time()
    while time.time() - t < 600 and p.poll() is None:
        n = len(lines_of(out)) if out.exists() else 0
        if n >= when_lines:
            break
        time.sleep(0.2)
    if p.poll() is not None:
        rc, o, e = finish(p)
        return None, f"sweep ended (exit {rc}) before the signal: {tail(e)}"
    os.kill(p.pid, sig) if sig != signal.SIGKILL else os.killpg(p.pid, signal.SIGKILL)
    rc, o, e = finish(p, 120)
    time.sleep(2)
    left = group_alive(p.pid)
    before = lines_of(out) if out.exists() else []
    rc2, o2, e2, dt2 = run(args, timeout=900)
    after = records(out)
    return (rc, e, left, before, rc2, o2, e2, after), ""


def check_killed(sig, pid_id, when_lines):
    r, why = sweep_killed(sig, pid_id, when_lines)
    if r is None:
        return False, why
    rc, e, left, before, rc2, o2, e2, after = r
    bad = []
    if tb(e) or tb(e2):
        bad.append("traceback: " + tail(e if tb(e) else e2))
    if left:
        bad.append(f"{len(left)} process(es) left after the kill: {left[:2]}")
    if any(x is None for x in after):
        bad.append("an unreadable line left in the records")
    keys = [x.get("key") for x in after if x]
    if len(keys) != len(set(keys)):
        bad.append(f"a job recorded twice: {keys}")
    if len(set(keys)) != 4:
        bad.append(f"{len(set(keys))} of 4 jobs recorded after the resume")
    failed = [x.get("key") for x in after if x and (x.get("failed") or x.get("status") == "failed")]
    if failed:
        bad.append(f"recorded as failed: {failed}")
    if rc2 != 0:
        bad.append(f"resume exit {rc2}: {tail(e2)}")
    if sig == signal.SIGTERM and rc not in (143, -15, 1, 2, 130):
        bad.append(f"SIGTERM exit status {rc}")
    return not bad, "; ".join(
        bad
    ) or f"killed at {len(before)} line(s) (exit {rc}), resumed to 4 jobs once each"


@probe("W-R4")
def sweep_sigkill_first_record():
    """SIGKILL of the whole process group as the first record lands, then the same
    command: every job recorded once, none as failed, no process left behind (issue 54
    items 1 and 4: 'a cold compile's child outlives a SIGKILLed parent')."""
    return check_killed(signal.SIGKILL, "r4", 1)


@probe("W-R5")
def sweep_sigterm_mid():
    """SIGTERM to the sweep (the parent only, as `kill PID` does) mid-way: its workers
    stop too, the finished jobs are kept, the resume finishes the rest once each."""
    return check_killed(signal.SIGTERM, "r5", 2)


@probe("W-R6")
def sweep_worker_killed():
    """A local worker process SIGKILLed mid-job (the OOM killer's way): the sweep must not
    record the job it was running, or the jobs never run, as 'failed' or as results; it
    runs them again or stops saying what is left; no job twice (issue 54 item 1)."""
    out = WD / "r6.jsonl"
    args = [
        "sweep-cct",
        "kundur",
        "--faults",
        "DEFAULT",
        "--esd-pct",
        "none,1,2,3,4,5,6,8,10,12",
        "--workers",
        2,
        "--tol-ms",
        1,
        "--out",
        out,
    ]
    p = start(args)
    import psutil

    t = time.time()
    victim = None
    while time.time() - t < 300 and p.poll() is None:
        busy = []
        try:
            for c in psutil.Process(p.pid).children(recursive=True):
                try:
                    if "resource_tracker" not in " ".join(c.cmdline()) and c.cpu_percent(0.1) > 20:
                        busy.append(c)
                except psutil.Error:
                    pass
        except psutil.Error:
            pass
        if busy and out.exists() and len(lines_of(out)) >= 1:
            victim = busy[0]
            break
    if victim is None:
        rc, o, e = finish(p)
        return False, f"no busy worker found (exit {rc}) {tail(e)}"
    victim.kill()
    rc, o, e = finish(p, 600)
    recs = records(out) if out.exists() else []
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    keys = [x.get("key") for x in recs if x]
    if len(keys) != len(set(keys)):
        bad.append(f"a job recorded twice {keys}")
    failed = [x for x in recs if x and "failed" in json.dumps(x).lower() and "cct" not in x]
    if failed:
        bad.append(f"recorded as failed: {[x.get('key') for x in failed]} ({str(failed[0])[:200]})")
    if rc == 0 and len(set(keys)) != 20:
        bad.append(f"exit 0 with {len(set(keys))} of 20 jobs")
    return not bad, "; ".join(bad) or f"exit {rc}, {len(set(keys))} jobs recorded; {tail(e, 160)}"


@probe("W-R7")
def sweep_dask_worker_killed():
    """`--scheduler local --workers 2` with one Dask worker process SIGKILLed mid-sweep,
    then the same command again: the never-run jobs are never recorded as failed or as
    results; after the resume every job is there once, none failed (issue 54 item 1:
    'a Dask scheduler killed mid-sweep: the sweep exits 0 and records the never-run jobs
    as failed')."""
    import psutil

    out = WD / "r7.jsonl"
    args = [
        "sweep-cct",
        "kundur",
        "--faults",
        "DEFAULT",
        "--esd-pct",
        "none,1,2,3,4,5,6,8,10,12",
        "--scheduler",
        "local",
        "--workers",
        2,
        "--tol-ms",
        1,
        "--out",
        out,
    ]
    p = start(args)
    t = time.time()
    victim = None
    while time.time() - t < 300 and p.poll() is None:
        busy = []
        try:
            for c in psutil.Process(p.pid).children(recursive=True):
                try:
                    if "resource_tracker" not in " ".join(c.cmdline()) and c.cpu_percent(0.1) > 30:
                        busy.append(c)
                except psutil.Error:
                    pass
        except psutil.Error:
            pass
        if busy and out.exists() and len(lines_of(out)) >= 1:
            victim = busy[0]
            break
    if victim is None:
        rc, o, e = finish(p)
        return False, f"no busy Dask worker found (exit {rc}): {tail(e)}"
    vdesc = " ".join(victim.cmdline())[:80]
    victim.kill()
    rc, o, e = finish(p, 600)
    first = records(out) if out.exists() else []
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    failed = [x.get("key") for x in first if x and x.get("status") == "failed"]
    if failed:
        bad.append(f"recorded as failed after a worker kill: {failed} (exit {rc})")
    keys1 = [x.get("key") for x in first if x]
    if rc == 0 and len(set(keys1)) != 20:
        bad.append(f"exit 0 with {len(set(keys1))} of 20 jobs")
    rc2, o2, e2, dt2 = run(args, timeout=600)
    after = records(out)
    keys = [x.get("key") for x in after if x]
    if len(keys) != len(set(keys)) and not failed:
        bad.append(f"a job twice: {keys}")
    if len(set(keys)) != 20 or rc2 != 0:
        bad.append(f"resume exit {rc2}, {len(set(keys))} of 20 jobs: {tail(e2, 150)}")
    if any(x and x.get("status") == "failed" for x in after):
        bad.append(
            "failed records remain after the resume: "
            + str([x.get("key") for x in after if x and x.get("status") == "failed"])
        )
    return not bad, "; ".join(
        bad
    ) or f"killed {vdesc!r}: exit {rc}, {len(set(keys1))} recorded, resume to 20: {tail(e, 140)}"


@probe("W-R8")
def screen_sigint_resume():
    """`screen kundur --buses 3,4,13,14 --out` interrupted by SIGINT after its first
    record, then the same command: the rows are the same as an uninterrupted screening's
    (same CCTs), each fault once (issue 54 item 1)."""
    out, ref = WD / "s8.jsonl", WD / "s8ref.jsonl"
    base = ["screen", "kundur", "--buses", "3,4,13,14", "--workers", 2, "--json"]
    rc0, o0, e0, _ = run([*base, "--out", ref], timeout=600)
    if rc0 not in (0, 1):
        return False, f"reference screening exit {rc0}: {tail(e0)}"
    p = start([*base, "--out", out])
    t = time.time()
    while time.time() - t < 300 and p.poll() is None:
        if out.exists() and len(lines_of(out)) >= 1:
            break
        time.sleep(0.1)
    if p.poll() is None:
        os.kill(p.pid, signal.SIGINT)
    rc, o, e = finish(p, 120)
    n_kept = len(lines_of(out)) if out.exists() else 0
    rc2, o2, e2, _ = run([*base, "--out", out], timeout=600)
    bad = []
    if tb(e) or tb(e2):
        bad.append("traceback: " + tail(e if tb(e) else e2))

    def ccts(path):
        d = {}
        for r in records(path):
            if r:
                res = r.get("result") or {}
                d[r["key"]] = (r.get("status"), res.get("cct_s", res.get("cct")))
        return d

    a, b = ccts(ref), ccts(out)
    keys = [r.get("key") for r in records(out) if r]
    if len(keys) != len(set(keys)):
        bad.append("a fault recorded twice")
    if a != b:
        diff = {k: (a.get(k), b.get(k)) for k in set(a) | set(b) if a.get(k) != b.get(k)}
        bad.append(f"resumed records differ from an uninterrupted run: {str(diff)[:200]}")
    if rc2 != rc0:
        bad.append(f"resume exit {rc2}, uninterrupted {rc0}")
    return not bad, "; ".join(
        bad
    ) or f"SIGINT at {n_kept} record(s) (exit {rc}), resume equals the uninterrupted run"


# ---------------------------------------------------------------- 2. PMU streams


def track_refused(pid, data, why_words, extra=("--frames", 180)):
    cfg, _ = recording()
    srv = FakeServer(cfg, data)
    rc, o, e, dt, out = track_tcp(srv, list(extra))
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    if rc == 0:
        bad.append(
            f"exit 0, {srv.sent} frames sent, a defective stream taken as whole: {tail(o + e, 200)}"
        )
    if rc == 0 and out.exists():
        bad.append(f"{out.name} written with {len(out.read_text().splitlines())} lines")
    if rc != 0 and not any(w in e.lower() for w in why_words):
        bad.append(f"exit {rc} without naming the defect ({why_words[0]}): {tail(e, 200)}")
    return not bad, "; ".join(bad) or f"exit {rc}: {tail(e, 180)}"


@probe("W-P1")
def track_duplicate_stamp():
    """A TCP stream whose data frame 61 repeats frame 60 (same time stamp, valid CRC):
    `estimate track` refuses the source (its --help: 'its time stamp against the one
    before ... a frame refused refuses the source, exit status 2'); issue 54 item 7."""
    _, d = recording()
    return track_refused(
        "W-P1", d[:60] + [d[59]] + d[60:], ("repeat", "time stamp", "duplicate", "same")
    )


@probe("W-P2")
def track_backward_stamp():
    """A TCP stream whose frame 61 is stamped as frame 30 (CRC recomputed): refused."""
    _, d = recording()
    s, c = stamp_of(d[29])
    return track_refused(
        "W-P2", d[:60] + [with_stamp(d[60], s, c)] + d[61:], ("back", "time stamp", "before")
    )


@probe("W-P3")
def track_bad_crc_mid():
    """A TCP stream whose frame 61 has a bad CRC: refused, never tracked as whole."""
    _, d = recording()
    b = bytearray(d[60])
    b[-1] ^= 0xFF
    return track_refused("W-P3", d[:60] + [bytes(b)] + d[61:], ("crc",))


@probe("W-P4")
def track_off_rate():
    """Frames stamped at 120 fps in a stream whose CFG-2 says 60 (every second instant off
    the grid): refused as the --help says ('off the reporting instants ... refuse the
    source')."""
    _, d = recording()
    s0, c0 = stamp_of(d[0])
    tb_ = 1_000_000
    fr = []
    for i, f in enumerate(d):
        tot = s0 * tb_ + c0 + round(i * tb_ / 120)
        fr.append(with_stamp(f, tot // tb_, tot % tb_))
    return track_refused("W-P4", fr, ("rate", "instant", "grid", "off"))


@probe("W-P5")
def track_half_frame_end():
    """After 100 of 180 frames the server sends half a frame and closes: exit 2 with the
    result named partial (issue 54 item 2: 'a frame cut in the middle then close: exit 0
    with a partial result presented as whole')."""
    cfg, d = recording()
    srv = FakeServer(cfg, d[:100], end="half")
    srv.data_last = d[100]
    rc, o, e, dt, out = track_tcp(srv, ["--frames", 180])
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    if rc == 0:
        bad.append("exit 0")
    if "partial" not in e.lower() and "100" not in e:
        bad.append(f"not named partial: {tail(e, 200)}")
    return not bad, "; ".join(bad) or f"exit {rc}: {tail(e, 180)}"


@probe("W-P6")
def track_until_beyond():
    """--until 10 on a stream of 3 s whose server closes in order after its last frame:
    exit 2, the track named partial (help: 'A stream that stops before --until or
    --frames is tracked as far as it came, written, and named an error')."""
    cfg, d = recording()
    srv = FakeServer(cfg, d)
    rc, o, e, dt, out = track_tcp(srv, ["--until", 10])
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    if rc != 2:
        bad.append(f"exit {rc}")
    return not bad, "; ".join(bad) or f"exit {rc}: {tail(e, 180)}"


@probe("W-P7")
def track_silent_after_cfg():
    """A server that sends CFG-2, takes 'start' and then 30 frames and stays connected and
    silent: `estimate track --frames 180` ends within its 30 s frame time-out (+margin),
    exit 2, partial named; it does not hang."""
    cfg, d = recording()
    srv = FakeServer(cfg, d[:30], end="silent")
    rc, o, e, dt, out = track_tcp(srv, ["--frames", 180], timeout=90)
    bad = []
    if rc == "timeout":
        bad.append("hung past 90 s")
    elif rc != 2:
        bad.append(f"exit {rc}")
    if tb(e):
        bad.append("traceback: " + tail(e))
    return not bad, "; ".join(bad) or f"exit {rc} after {dt:.0f} s: {tail(e, 160)}"


def endless(cfg, d):
    """frames with increasing stamps for ever (the recording's payloads cycled)."""
    s0, c0 = stamp_of(d[0])
    i = 0
    tb_ = 1_000_000
    while True:
        tot = s0 * tb_ + c0 + round(i * tb_ / 60)
        yield with_stamp(d[i % len(d)], tot // tb_, tot % tb_)
        i += 1


@probe("W-P8")
def track_endless_sigterm():
    """A stream that never ends, `estimate track --frames 2500000` (under its 256 MiB stream cap): SIGTERM after 20 s is
    honoured within 10 s (exit 143 or non-zero), memory stays bounded (< 800 MiB), and the
    frames received are said/kept (issue 54 item 5)."""
    cfg, d = recording()
    frames = list(endless(cfg, d[:60]) for _ in [0])[0]
    # pre-build to keep the fake server fast: 60 s worth cycled
    pre = [next(frames) for _ in range(3600)]

    def gen():
        while True:
            yield from pre  # stamps repeat every 60 s: fine for 20 s

    srv = FakeServer(cfg, pre + [next(frames) for _ in range(0)], end="silent")
    o = WD / "p8.csv"
    import psutil

    p = start(
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            f"tcp://127.0.0.1:{srv.port}",
            "--frames",
            2500000,
            "--out",
            o,
        ]
    )
    peak = 0
    t = time.time()
    while time.time() - t < 20 and p.poll() is None:
        try:
            peak = max(
                peak,
                sum(
                    x.memory_info().rss
                    for x in [psutil.Process(p.pid), *psutil.Process(p.pid).children(True)]
                ),
            )
        except psutil.Error:
            pass
        time.sleep(0.5)
    if p.poll() is not None:
        rc, out, e = finish(p)
        srv.close()
        return False, f"ended by itself (exit {rc}) with frames pending: {tail(e)}"
    os.kill(p.pid, signal.SIGTERM)
    t1 = time.time()
    rc, out, e = finish(p, 30)
    dt = time.time() - t1
    srv.close()
    bad = []
    if rc == "timeout":
        bad.append("SIGTERM not honoured in 30 s")
    elif rc == 0:
        bad.append("exit 0 after SIGTERM")
    if dt > 10:
        bad.append(f"took {dt:.0f} s after SIGTERM")
    if peak > 800 * 2**20:
        bad.append(f"RSS {peak / 2**20:.0f} MiB")
    if tb(e):
        bad.append("traceback: " + tail(e))
    return not bad, "; ".join(
        bad
    ) or f"exit {rc} {dt:.1f} s after SIGTERM, RSS {peak / 2**20:.0f} MiB: {tail(e, 160)}"


@probe("W-P9")
def record_duplicate():
    """`pmu record --frames 180` of a stream whose frame 61 repeats frame 60: exit 2, OUT
    not written as if whole, the partial beside it (its --help)."""
    cfg, d = recording()
    srv = FakeServer(cfg, d[:60] + [d[59]] + d[60:])
    out = WD / "p9.c37"
    rc, o, e, dt = run(
        ["pmu", "record", f"127.0.0.1:{srv.port}", "--frames", 180, "-o", out], timeout=90
    )
    srv.close()
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    if rc != 2:
        bad.append(f"exit {rc}")
    if out.exists() and len(split_frames(out.read_bytes())) > 61:
        bad.append(f"{out.name} holds the duplicate")
    return not bad, "; ".join(bad) or f"exit {rc}: {tail(e, 180)}"


@probe("W-P10")
def track_rate_mismatch():
    """`pmu serve kundur --rate 30` tracked with `estimate track --rate 60`: the stream's
    rate differs from the one the filters are tuned to; expected refused or warned
    (issue 54 item 7: '`pmu control --rate 30` against a 60 fps plant accepted')."""
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
            3,
            "--speed",
            0,
            "--port",
            port,
            "--rate",
            30,
            "--wait",
            5,
            "--timeout",
            20,
        ]
    )
    if not wait_listen(port, 300, srv):
        finish(srv, 5)
        return False, "serve did not listen"
    o = WD / "p10.csv"
    rc, out, e, dt = run(
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            f"tcp://127.0.0.1:{port}",
            "--frames",
            90,
            "--rate",
            60,
            "--out",
            o,
        ],
        timeout=120,
    )
    finish(srv, 30)
    if tb(e):
        return False, "traceback: " + tail(e)
    if rc != 0 or "rate" in e.lower():
        return True, f"exit {rc}: {tail(e, 180)}"
    return False, f"exit 0, no word of the rate: {tail(out + e, 200)}"


@probe("W-P11")
def serve_many_silent():
    """`pmu serve --timeout 5` with 12 peers connected and silent (more than its 8 places):
    a real PDC that comes after them still gets the stream whole, and the server exits 0
    (issue 54 item 3: 'a silent or half-frame peer blocks the server for everyone')."""
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
            3,
            "--speed",
            0,
            "--port",
            port,
            "--wait",
            10,
            "--timeout",
            5,
        ]
    )
    if not wait_listen(port, 300, srv):
        finish(srv, 5)
        return False, "serve did not listen"
    peers = []
    for i in range(12):
        s = socket.create_connection(("127.0.0.1", port), timeout=5)
        if i % 3 == 1:
            s.sendall(b"\xaa\x41\x00\x12")  # half a command frame
        peers.append(s)
    time.sleep(1)
    out = WD / "p11.c37"
    rc, o, e, dt = run(
        ["pmu", "record", f"127.0.0.1:{port}", "--frames", 181, "-o", out], timeout=120
    )
    for s in peers:
        s.close()
    rcs, os_, es = finish(srv, 60)
    bad = []
    if rc != 0:
        bad.append(f"record exit {rc}: {tail(e)}")
    if rcs != 0:
        bad.append(f"serve exit {rcs}: {tail(es)}")
    if tb(e) or tb(es):
        bad.append("traceback")
    return not bad, "; ".join(bad) or f"served whole after 12 silent peers in {dt:.0f} s"


@probe("W-P12")
def plant_stranger_bad_crc_start():
    """`pmu plant`: a stranger connects first and asks for CFG-2 and 'start' with a bad
    CRC, then stays connected; the real `pmu control` connects next and the run completes
    with it (issue 54 item 3: 'a start command with a bad CRC is obeyed')."""
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
            60,
        ]
    )
    if not wait_listen(port, 300, plant):
        finish(plant, 5)
        return False, "plant did not listen"
    s = socket.create_connection(("127.0.0.1", port))

    def cmdframe(word, badcrc):
        body = struct.pack(">HHHIIH", 0xAA41, 18, 1, int(time.time()), 0, word)
        c = crc_ccitt(body) ^ (0xFFFF if badcrc else 0)
        return body + struct.pack(">H", c)

    s.sendall(cmdframe(5, True))
    s.sendall(cmdframe(2, True))
    time.sleep(1)
    ctl = start(
        ["pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", 5, "--estimator", "raw"]
    )
    rcc, oc, ec = finish(ctl, 180)
    rcp, op, ep = finish(plant, 60)
    s.close()
    bad = []
    if rcp != 0 or rcc != 0:
        bad.append(f"plant exit {rcp}: {tail(ep, 150)}; control exit {rcc}: {tail(ec, 150)}")
    if tb(ep) or tb(ec):
        bad.append("traceback")
    return not bad, "; ".join(bad) or f"controller ran the loop; plant: {tail(ep, 120)}"


@probe("W-P13")
def plant_mode_out_of_range():
    """`pmu plant` whose controller (a script) answers the first frame with mode +2 for
    one ESD: refused, the plant ends non-zero naming it, no verdict presented as whole."""
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
            "--json",
        ]
    )
    if not wait_listen(port, 300, plant):
        finish(plant, 5)
        return False, "plant did not listen"
    s = socket.create_connection(("127.0.0.1", port), timeout=30)

    def cmdframe(word, extra=b"", soc=None, frac=0):
        n = 18 + len(extra)
        body = (
            struct.pack(
                ">HHHIIH", 0xAA41, n, 1, soc if soc is not None else int(time.time()), frac, word
            )
            + extra
        )
        return body + struct.pack(">H", crc_ccitt(body))

    s.sendall(cmdframe(5))
    cfg = read_frame(s)
    s.sendall(cmdframe(2))
    fr = read_frame(s)
    try:
        soc, counts = stamp_of(fr)
        s.sendall(cmdframe(8, bytes([2, 0, 0, 0]), soc, counts))
        time.sleep(2)
    except Exception:
        pass
    rcp, op, ep = finish(plant, 60)
    s.close()
    bad = []
    if rcp == 0:
        bad.append(f"plant exit 0 with a mode +2 answer: {tail(op + ep, 200)}")
    if tb(ep):
        bad.append("traceback: " + tail(ep))
    if rcp != 0 and "mode" not in ep.lower():
        bad.append(f"not named: {tail(ep, 200)}")
    return not bad, "; ".join(bad) or f"exit {rcp}: {tail(ep, 180)}"


@probe("W-P14")
def replay_duplicate_file():
    """`pmu replay` of a recording whose frame 61 repeats frame 60: refused before it
    listens, naming the file and frame (its --help: 'Every frame is checked before the
    server listens')."""
    cfg, d = recording()
    p = WD / "p14.c37"
    p.write_bytes(cfg + b"".join(d[:60] + [d[59]] + d[60:]))
    rc, o, e, dt = run(
        ["pmu", "replay", p, "--port", free_port(), "--wait", 2, "--timeout", 2, "--speed", 0],
        timeout=60,
    )
    if tb(e) or rc in (0, "timeout"):
        return False, f"exit {rc}: {tail(e)}"
    return True, f"exit {rc}: {tail(e, 160)}"


@probe("W-P15")
def track_file_cut_tail():
    """`estimate track --source FILE` of a recording whose last frame is cut in half (a
    recorder killed mid-write): not tracked as whole without a word: exit non-zero, or a
    warning naming the cut frame."""
    cfg, d = recording()
    p = WD / "p15.c37"
    p.write_bytes(cfg + b"".join(d[:100]) + d[100][: len(d[100]) // 2])
    o = WD / "p15.csv"
    rc, out, e, dt = run(["estimate", "track", "kundur", "--source", p, "--out", o], timeout=120)
    if tb(e):
        return False, "traceback: " + tail(e)
    if rc != 0 or any(
        w in e.lower() for w in ("cut", "partial", "incomplete", "truncat", "half", "bytes")
    ):
        return True, f"exit {rc}: {tail(e, 160)}"
    return False, f"exit 0, no word of the cut last frame: {tail(out + e, 200)}"


@probe("W-P16")
def serve_any_interface_warned():
    """`pmu serve --host 0.0.0.0` (every interface, no --allow): accepted with a warning
    that any host may connect (issue 54 item 3: '--host 0.0.0.0 accepted without a
    word')."""
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
            "--speed",
            0,
            "--port",
            port,
            "--host",
            "0.0.0.0",
            "--wait",
            1,
            "--timeout",
            2,
        ]
    )
    ok = wait_listen(port, 300, srv)
    time.sleep(1)
    os.kill(srv.pid, signal.SIGINT)
    rc, o, e = finish(srv, 30)
    if not ok and rc not in (2,):
        return False, f"did not listen, exit {rc}: {tail(e)}"
    if tb(e):
        return False, "traceback: " + tail(e)
    if any(w in e.lower() for w in ("warning", "any host", "every interface", "--allow")):
        return True, f"warned: {tail(e, 160)}"
    return False, f"no warning: {tail(e, 200)}"


@probe("W-P17")
def allow_hostname():
    """`pmu serve --allow localhost,999.1.1.1` (a name and a bad address): refused with a
    clear message before any simulation, or the name resolved; never a traceback."""
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
            "--port",
            0,
            "--allow",
            "localhost,999.1.1.1",
            "--wait",
            1,
        ],
        timeout=120,
    )
    if tb(e) or rc in (0, "timeout"):
        return False, f"exit {rc}: {tail(e)}"
    return True, f"exit {rc}: {tail(e, 160)}"


# ---------------------------------------------------------------- 3. compile cache
SIM = ["simulate", "kundur", "--fault", 3, "--far-bus", 101, "--tf", 2, "--json"]


def nc_copy(name):
    src = Path(os.environ.get("NUMBA_CACHE_DIR", ""))
    dst = WD / name
    shutil.copytree(src, dst, symlinks=True)
    return dst


def sim_ok(env, timeout=900):
    rc, o, e, dt = run(SIM, timeout=timeout, env=env)
    return rc, o, e, dt


@probe("W-C1")
def cache_dir_is_file():
    """NUMBA_CACHE_DIR names a regular file: simulate runs (compiling, warned) or refuses
    clearly; never a traceback (issue 54 item 4)."""
    f = WD / "ncfile"
    f.write_text("not a dir")
    env = dict(ENV, NUMBA_CACHE_DIR=str(f))
    rc, o, e, dt = sim_ok(env)
    if tb(e) or rc not in (0, 2):
        return False, f"exit {rc}: {tail(e)}"
    return True, f"exit {rc} in {dt:.0f} s: {tail(e, 150)}"


@probe("W-C2")
def cache_garbage_every_index():
    """Every *.nbi and *.nbc of a warm cache copy overwritten with garbage of the same
    size: simulate recompiles (exit 0), no UnpicklingError."""
    d = nc_copy("nc_garbage")
    n = 0
    for p in list(d.rglob("*.nbi")) + list(d.rglob("*.nbc")):
        sz = p.stat().st_size
        p.write_bytes(os.urandom(max(sz, 8)))
        n += 1
    env = dict(ENV, NUMBA_CACHE_DIR=str(d))
    rc, o, e, dt = sim_ok(env)
    if tb(e) or rc != 0:
        return False, f"exit {rc}: {tail(e)}"
    return True, f"{n} files garbage, recompiled in {dt:.0f} s"


@probe("W-C3")
def cache_foreign_index_not_unpickled():
    """A copy of the cache owned by this user, mode 0700, whose kernel index files are
    replaced by a pickle that runs `touch MARK` and chown'ed to user nobody (65534):
    never unpickled (the marker never appears), simulate still works."""
    d = nc_copy("nc_foreign")
    mark = WD / "PWNED"
    import pickle

    class P:
        def __reduce__(self):
            return (os.system, (f"touch {mark}",))

    payload = pickle.dumps(P())
    n = 0
    for p in d.rglob("*.nbi"):
        p.write_bytes(payload)
        os.chown(p, 65534, 65534)
        os.chmod(p, 0o644)
        n += 1
    env = dict(ENV, NUMBA_CACHE_DIR=str(d))
    rc, o, e, dt = sim_ok(env)
    if mark.exists():
        return False, f"planted pickle ran (marker made), exit {rc}"
    if tb(e) or rc != 0:
        return False, f"exit {rc}: {tail(e)}"
    return True, f"{n} foreign indexes refused, exit 0 in {dt:.0f} s"


@probe("W-C4")
def cache_link_to_foreign():
    """NUMBA_CACHE_DIR is a symbolic link (this user's) to a warm cache copy owned by user
    nobody (65534), whose indexes are a planted pickle (owned by nobody too): the link is
    followed and the directory refused (its owner), nothing unpickled, simulate works."""
    d = nc_copy("nc_link_target")
    mark = WD / "PWNED4"
    import pickle

    class P:
        def __reduce__(self):
            return (os.system, (f"touch {mark}",))

    payload = pickle.dumps(P())
    for p in d.rglob("*"):
        if p.is_file() and p.suffix == ".nbi":
            p.write_bytes(payload)
        os.lchown(p, 65534, 65534)
    os.chown(d, 65534, 65534)
    link = WD / "nc_link"
    link.symlink_to(d)
    env = dict(ENV, NUMBA_CACHE_DIR=str(link))
    rc, o, e, dt = sim_ok(env)
    if mark.exists():
        return False, f"planted pickle ran through a link, exit {rc}"
    if tb(e) or rc != 0:
        return False, f"exit {rc}: {tail(e)}"
    return True, f"refused, exit 0: {tail(e, 140)}"


@probe("W-C5")
def cache_index_fifo():
    """Kernel index files replaced by FIFOs: simulate does not hang (recompiles)."""
    d = nc_copy("nc_fifo")
    n = 0
    for p in list(d.rglob("*.nbi"))[:50]:
        p.unlink()
        os.mkfifo(p)
        n += 1
    env = dict(ENV, NUMBA_CACHE_DIR=str(d))
    rc, o, e, dt = sim_ok(env, timeout=900)
    if rc == "timeout":
        return False, "hung on a FIFO index"
    if tb(e) or rc != 0:
        return False, f"exit {rc}: {tail(e)}"
    return True, f"{n} FIFOs, exit 0 in {dt:.0f} s"


# ---------------------------------------------------------------- 4. memory bounds
def sparse(name, size, head=b""):
    p = WD / name
    with open(p, "wb") as f:
        f.write(head)
        f.truncate(size)
    return p


def bounded(pid, args, limit_mib=800, timeout=180):
    rc, o, e, dt, rss = run_rss(args, timeout=timeout)
    bad = []
    if rc == "timeout":
        bad.append(f"no end in {timeout} s")
    elif rc == 0:
        bad.append("exit 0 on a huge input")
    if tb(e):
        bad.append("traceback: " + tail(e))
    if rss > limit_mib:
        bad.append(f"peak RSS {rss:.0f} MiB")
    return not bad, "; ".join(bad) or f"exit {rc} in {dt:.1f} s, RSS {rss:.0f} MiB: {tail(e, 150)}"


@probe("W-M1")
def faults_csv_huge():
    """--faults a 3 GB CSV (header, then one line of 3 GB of digits, no newline): refused
    with bounded memory (issue 54: 'every reader bounds its input')."""
    p = WD / "faults_long.csv"
    with open(p, "wb") as f:
        f.write(b"bus,far_bus\n3,")
        f.truncate(3 * 2**30)  # NULs after: a never-ending number
    return bounded("W-M1", ["sweep-cct", "kundur", "--faults", p, "--out", WD / "m1.jsonl"])


@probe("W-M1b")
def faults_csv_many_rows():
    """--faults with 4 million rows of one valid fault (60 MB): refused or bounded (each
    row is a job: 4 M jobs' records)."""
    p = WD / "faults_many.csv"
    with open(p, "w") as f:
        f.write("bus,far_bus\n")
        f.write("3,101\n" * 4_000_000)
    rc, o, e, dt, rss = run_rss(
        ["sweep-cct", "kundur", "--faults", p, "--out", WD / "m1b.jsonl", "--workers", 1],
        timeout=120,
    )
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    if rss > 800:
        bad.append(f"peak RSS {rss:.0f} MiB")
    if rc == "timeout":
        bad.append("still running after 120 s (4 M duplicate jobs not refused)")
    return not bad, "; ".join(bad) or f"exit {rc} in {dt:.1f} s, RSS {rss:.0f} MiB: {tail(e, 150)}"


@probe("W-M2")
def records_huge_sparse():
    """--out a 3 GB records file of NULs (sparse): refused clearly, bounded memory."""
    p = sparse("m2.jsonl", 3 * 2**30)
    return bounded(
        "W-M2", ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", p, "--workers", 1]
    )


@probe("W-M2b")
def records_many_lines():
    """--out a records file of 1.2 GB made of 15 MiB lines (each under the 16 MiB line
    cap) of a JSON string: refused or read with bounded memory."""
    p = WD / "m2b.jsonl"
    line = b'{"key": "' + b"x" * (15 * 2**20) + b'"}\n'
    with open(p, "wb") as f:
        for _ in range(80):
            f.write(line)
    return bounded(
        "W-M2b", ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", p, "--workers", 1]
    )


@probe("W-M3")
def recording_huge_track():
    """`estimate track --source` a 3 GB recording (a real CFG-2, then NULs): refused with
    bounded memory (issue 54 item 5: 'a 2 GB recording is read whole')."""
    cfg, d = recording()
    p = sparse("m3.c37", 3 * 2**30, cfg + b"".join(d[:10]))
    return bounded("W-M3", ["estimate", "track", "kundur", "--source", p, "--out", WD / "m3.csv"])


@probe("W-M3b")
def recording_huge_replay():
    """`pmu replay` of the same 3 GB file: refused before listening, bounded memory."""
    cfg, d = recording()
    p = WD / "m3.c37"
    if not p.exists():
        p = sparse("m3.c37", 3 * 2**30, cfg + b"".join(d[:10]))
    return bounded(
        "W-M3b", ["pmu", "replay", p, "--port", free_port(), "--wait", 1, "--timeout", 1]
    )


@probe("W-M4")
def case_json_huge():
    """simulate a case file of 3 GB ('{' then spaces, sparse NULs): refused, bounded."""
    p = sparse("m4.json", 3 * 2**30, b'{"format": "')
    return bounded("W-M4", ["simulate", p, "--fault", 3, "--far-bus", 101])


@probe("W-M5")
def case_fifo():
    """simulate with the case file a FIFO no one writes: refused at once, no hang."""
    p = WD / "m5.json"
    os.mkfifo(p)
    r = bounded("W-M5", ["simulate", p, "--fault", 3, "--far-bus", 101], timeout=60)
    return r


@probe("W-M6")
def faults_dev_urandom():
    """--faults /dev/urandom (never ends): refused at once, bounded."""
    return bounded(
        "W-M6",
        ["sweep-cct", "kundur", "--faults", "/dev/urandom", "--out", WD / "m6.jsonl"],
        timeout=60,
    )


@probe("W-M7")
def screening_huge():
    """place --screening a 3 GB file of NULs: refused, bounded."""
    p = sparse("m7.jsonl", 3 * 2**30)
    return bounded(
        "W-M7",
        [
            "place",
            "kundur",
            "--faults",
            "DEFAULT",
            "--required-clearing-cycles",
            6,
            "--screening",
            p,
        ],
        timeout=120,
    )


@probe("W-M8")
def records_many_small():
    """--out a 250 MB records file (under the 256 MiB input cap) of 9 million short valid
    JSON records, each a key of its own: read with bounded memory (< 800 MiB) or refused
    (issue 54: 'every reader bounds its input', 'readers given huge inputs ... bound
    memory')."""
    p = WD / "m8.jsonl"
    with open(p, "w") as f:
        for i in range(9_000_000):
            f.write('{"key":"k%08d","a":1}\n' % i)
            if f.tell() > 250 * 2**20:
                break
    return bounded(
        "W-M8",
        ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", p, "--workers", 1, "--json"],
        timeout=300,
    )


@probe("W-M8b")
def records_many_genuine():
    """--out a 250 MB records file (under the 256 MiB cap) of 190 000 genuine-looking
    kundur records (a real record's line, its key's fault time varied): read within
    800 MiB or refused; the sweep's own two jobs then run or are refused clearly."""
    srcf = (
        WD / "r1_full.jsonl"
        if (WD / "r1_full.jsonl").exists()
        else Path("/tmp/s44p/W/sample_r1.jsonl")
    )
    if not srcf.exists():
        return False, "needs W-R1's records (run W-R1 first)"
    src = json.loads(srcf.read_text().splitlines()[0])
    p = WD / "m8b.jsonl"
    with open(p, "w") as f:
        for i in range(190_000):
            src["key"] = f"kundur/3-101/t{2 + i}/esd-none"
            src["inputs"]["t_fault"] = 2.0 + i
            f.write(json.dumps(src) + "\n")
    rc, o, e, dt, rss = run_rss(
        ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", p, "--workers", 1, "--tol-ms", 5],
        timeout=600,
    )
    bad = []
    if tb(e):
        bad.append("traceback: " + tail(e))
    if rss > 800:
        bad.append(
            f"peak RSS {rss:.0f} MiB for a {p.stat().st_size / 2**20:.0f} MiB records file (exit {rc}, {dt:.0f} s)"
        )
    return not bad, "; ".join(bad) or f"exit {rc} in {dt:.1f} s, RSS {rss:.0f} MiB: {tail(e, 150)}"


@probe("W-M9")
def case_json_big_array():
    """simulate a 250 MB case file (under the cap): kundur's JSON with an "extra" array of
    120 million zeros: refused or read within 800 MiB."""
    p = WD / "m9.json"
    d = json.loads(KUNDUR.read_text())
    text = json.dumps(d)
    assert text.endswith("}")
    with open(p, "w") as f:
        f.write(text[:-1] + ', "zz": [0')
        chunk = ",0" * (2**20)
        while f.tell() < 250 * 2**20:
            f.write(chunk)
        f.write("]}")
    return bounded(
        "W-M9", ["simulate", p, "--fault", 3, "--far-bus", 101, "--tf", 1.5], timeout=300
    )


@probe("W-M10")
def screening_many_small():
    """place --screening a 250 MB file of 9 M short records: bounded or refused."""
    p = WD / "m8.jsonl"
    if not p.exists():
        return False, "needs W-M8"
    return bounded(
        "W-M10",
        [
            "place",
            "kundur",
            "--faults",
            "DEFAULT",
            "--required-clearing-cycles",
            6,
            "--screening",
            p,
        ],
        timeout=300,
    )


def main():
    KIT.main(
        summary="\n{n} probes, {ok} ok, {short} SHORT; {secs:.0f} s", keep_any=True, chown=True
    )


if __name__ == "__main__":
    main()
