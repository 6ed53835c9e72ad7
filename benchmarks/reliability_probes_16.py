#!/usr/bin/env python3
"""Sixteenth reliability round (round 39, part K): the work `place` and `estimate cct` keep
across an interrupt (stabctl.placement.memo, stabctl.locking.kept_path): interrupts at
every point and by every signal, settings changed between runs, planted, forged, cut and
foreign memo files, read-only, full and size-limited caches, two plans at once; the
interrupt lines of every long command; simulate --json's warnings, late recordings and
the C37 frequency bound.

    python benchmarks/reliability_probes_16.py [probe-id-prefix ...]

The package under test is this repository's (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's (`stabctl compile` first).  Needs root (it mounts small
tmpfs file systems for the full and read-only caches).  Prints `id ok|SHORT reason` per
probe, exits 1 if any is SHORT.  About 9 minutes on two cores.  The round found short:
the memo removed before place's output was written (a full disk there lost every
simulation), one memo file shared by every plan of a case (one plan's end removed
another's kept work), a read-only or full cache failing place and estimate cct, an edited
memo line crashing place, a line appended after a cut one lost, estimate cct's .damaged
file left, the interrupt lines' wording, None in estimate rmse's text; all fixed.
"""

# ruff: noqa: E501 - the child scripts in strings keep their long lines
from __future__ import annotations

import glob
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

K = Path(tempfile.mkdtemp(prefix="stabctl-probes-16."))
CLONE = Path(os.environ.get("CLONE", Path(__file__).resolve().parents[1]))
NB = Path(os.environ.get("NUMBA_CACHE_DIR") or K / "nb")
#: a detached start with default signal dispositions (a `&` job ignores SIGINT)
LAUNCHER = """
import os, signal, subprocess, sys
out, cwd, cmd = sys.argv[1], sys.argv[2], sys.argv[3:]
def pre():
    for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM, signal.SIGQUIT):
        signal.signal(s, signal.SIG_DFL)
f = open(out, "wb")
p = subprocess.Popen(cmd, cwd=cwd, stdout=f, stderr=subprocess.STDOUT,
                     stdin=subprocess.DEVNULL, start_new_session=True, preexec_fn=pre)
print(p.pid)
"""
WORK = Path(tempfile.mkdtemp(prefix="probes_k_", dir=str(K)))
RESULTS: list[tuple[str, bool, str]] = []
ONLY = sys.argv[1:]


def env(xdg: Path | None = None, **extra) -> dict:
    e = dict(os.environ)
    e.update(
        PYTHONPATH=str(CLONE),
        NUMBA_CACHE_DIR=str(NB),
        XDG_CACHE_HOME=str(xdg or (WORK / "xdg")),
        MPLBACKEND="Agg",
    )
    e.pop("PYTHONSTARTUP", None)
    e.update({k: str(v) for k, v in extra.items()})
    return e


def run(args, xdg=None, timeout=300, cwd=None, pre="", **extra):
    """Run `stabctl args` (or a shell line when pre is given) -> (rc, out, err)."""
    if pre:
        cmd = ["bash", "-c", pre + " exec stabctl " + " ".join(map(_q, args))]
    else:
        cmd = ["stabctl", *args]
    try:
        p = subprocess.run(
            cmd,
            env=env(xdg, **extra),
            cwd=cwd or WORK,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired as exc:
        return "timeout", exc.stdout or "", exc.stderr or ""


def _q(s):
    import shlex

    return shlex.quote(str(s))


def launch(args, out: Path, xdg=None, cwd=None, **extra) -> int:
    """Start `stabctl args` detached with default signal dispositions; its pid."""
    p = subprocess.run(
        [sys.executable, "-c", LAUNCHER, str(out), str(cwd or WORK), "stabctl", *args],
        env=env(xdg, **extra),
        capture_output=True,
        text=True,
        timeout=30,
    )
    return int(p.stdout.strip())


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie (launched by launch.py: reparented) counts as gone
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


def wait_gone(pid: int, timeout=120) -> bool:
    t0 = time.time()
    while time.time() - t0 < timeout:
        if not alive(pid):
            return True
        time.sleep(0.1)
    kill_group(pid)
    return False


def kill_group(pid: int):
    for s in (signal.SIGKILL,):
        try:
            os.killpg(pid, s)
        except (ProcessLookupError, PermissionError):
            pass


def interrupt_after(args, delay, sig, xdg=None, wait_file: str | None = None, **extra):
    """Launch, wait `delay` s (or until glob wait_file has >= delay lines if given), send
    `sig` to the process, wait for it; -> (output text, memo lines seen just before)."""
    out = WORK / f"bg_{time.time_ns()}.out"
    pid = launch(args, out, xdg=xdg, **extra)
    t0 = time.time()
    if wait_file:
        while time.time() - t0 < 120 and alive(pid):
            n = sum(_lines(f) for f in glob.glob(wait_file))
            if n >= delay:
                break
            time.sleep(0.05)
    else:
        time.sleep(delay)
    try:
        os.kill(pid, sig)
    except ProcessLookupError:
        pass
    ok = wait_gone(pid, 120)
    kill_group(pid)  # any worker left
    return out.read_text(errors="replace"), ok


def _lines(path) -> int:
    try:
        return sum(1 for ln in open(path, "rb").read().splitlines() if _whole(ln))
    except OSError:
        return 0


def _whole(line: bytes) -> bool:
    try:
        rec = json.loads(line)
        return isinstance(rec, dict) and "key" in rec and "result" in rec
    except ValueError:
        return False


def norm(js: str) -> dict:
    """A plan's JSON without its wall time."""
    d = json.loads(js)
    d.pop("wall_time_s", None)
    return d


VOLATILE = {
    "wall_time_s",
    "worker",
    "ran",
    "resumed",
    "reused",
    "skipped",
    "wall_s",
    "recorded",
    "from_records",
    "run_now",
    "elapsed_s",
}


def strip(v):
    if isinstance(v, dict):
        return {k: strip(w) for k, w in v.items() if k not in VOLATILE}
    if isinstance(v, list):
        return [strip(w) for w in v]
    return v


def diff(a, b, path="") -> str:
    if type(a) is not type(b):
        return f"{path}: {a!r} vs {b!r}"
    if isinstance(a, dict):
        for k in sorted(set(a) | set(b), key=str):
            if k not in a or k not in b:
                return f"{path}/{k}: only in one"
            d = diff(a[k], b[k], f"{path}/{k}")
            if d:
                return d
        return ""
    if isinstance(a, list):
        if len(a) != len(b):
            return f"{path}: len {len(a)} vs {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            d = diff(x, y, f"{path}[{i}]")
            if d:
                return d
        return ""
    return "" if a == b or (a != a and b != b) else f"{path}: {a!r} vs {b!r}"


def probe(pid):
    def deco(fn):
        if ONLY and not any(pid.startswith(o) for o in ONLY):
            return fn
        t0 = time.time()
        try:
            ok, why = fn()
        except Exception as exc:  # noqa: BLE001 - the probe itself broke
            ok, why = False, f"probe error: {exc!r} {traceback.format_exc(limit=2)[-300:]}"
        RESULTS.append((pid, ok, why))
        print(f"{pid} {'ok' if ok else 'SHORT'} {why} [{time.time() - t0:.0f}s]", flush=True)
        return fn

    return deco


def tb(err: str) -> bool:
    return "Traceback" in err


def memo_files(xdg: Path, kind="stabctl-place"):
    return sorted((xdg / kind).glob("*")) if (xdg / kind).exists() else []


def last_interrupted(text: str) -> str:
    lines = [ln for ln in text.splitlines() if ln.startswith("interrupted:")]
    return lines[-1] if lines else ""


def fresh(name: str) -> Path:
    p = WORK / name
    shutil.rmtree(p, ignore_errors=True)
    p.mkdir(parents=True)
    return p


PLACE = [
    "place",
    "kundur",
    "--faults",
    "DEFAULT",
    "--target-cct-gain",
    "10",
    "--workers",
    "1",
    "--json",
]
BASE: dict[str, dict] = {}


def baseline(args, key=None) -> dict:
    """The JSON of an uninterrupted run of args (fresh cache), cached by args."""
    key = key or " ".join(args)
    if key not in BASE:
        x = fresh(f"base{len(BASE)}")
        rc, out, err = run(args, xdg=x)
        if rc not in (0, 1):
            raise RuntimeError(f"baseline {key}: rc {rc} {err[-300:]}")
        BASE[key] = norm(out)
        left = memo_files(x) + memo_files(x, "stabctl-estimate")
        if left:
            raise RuntimeError(f"baseline {key} left {left}")
    return BASE[key]


# ---------------------------------------------------------------------------- place memo
print(f"stabctl of {CLONE}; kernel cache {NB}; work directory {K}", flush=True)
_rc, _, _err = run(["compile"], timeout=900)  # a warm cache loads in seconds
if _rc != 0:
    sys.exit(f"stabctl compile failed: {_err[-300:]}")


@probe("K01-place-deterministic")
def _():
    a = baseline(PLACE)
    x = fresh("k01")
    _rc, out, _err = run(PLACE, xdg=x)
    d = diff(a, norm(out))
    if d:
        return False, f"two uninterrupted runs differ: {d}"
    if memo_files(x):
        return False, f"memo left after a verified plan: {memo_files(x)}"
    return True, "two uninterrupted runs equal, memo removed, cache dir empty"


def _interrupt_resume(tag, sig, after_lines, extra_args=()):
    args = list(PLACE)
    if extra_args[:1] == ["--workers"]:
        args[args.index("--workers") + 1] = extra_args[1]
        extra_args = extra_args[2:]
    args += list(extra_args)
    x = fresh(tag)
    text, _gone = interrupt_after(
        args, after_lines, sig, xdg=x, wait_file=str(x / "stabctl-place" / "*.jsonl")
    )
    files = memo_files(x)
    n_file = sum(_lines(f) for f in files)
    line = last_interrupted(text)
    msgs = []
    if sig in (signal.SIGINT, signal.SIGTERM):
        m = re.match(r"interrupted: (\d+) finished simulation job\(s\) are kept in (\S+);", line)
        if not m and "no simulation had finished" not in line:
            if "verified" in text or '"verified"' in text:
                return None, "finished before the signal"
            msgs.append(f"interrupted line: {line!r}")
        elif m and int(m.group(1)) != n_file:
            msgs.append(f"says {m.group(1)} kept, file holds {n_file} whole lines")
        if tb(text):
            msgs.append("traceback on interrupt")
    rc, out, err = run(args, xdg=x)
    if rc not in (0, 1):
        return False, f"rerun rc {rc}: {err[-300:]}"
    d = diff(baseline(args), norm(out))
    if d:
        msgs.append(f"resumed JSON differs from uninterrupted: {d}")
    if memo_files(x):
        msgs.append(f"left behind: {memo_files(x)}")
    took = re.search(r"(\d+) simulation job\(s\) taken", err)
    return (not msgs), (
        "; ".join(msgs)
        or f"{signal.Signals(sig).name} after {n_file} jobs, resumed (took "
        f"{took.group(1) if took else 0}) = uninterrupted"
    )


for _i, (_sig, _n) in enumerate(
    [
        (signal.SIGINT, 1),
        (signal.SIGINT, 4),
        (signal.SIGTERM, 6),
        (signal.SIGHUP, 3),
        (signal.SIGKILL, 5),
        (signal.SIGINT, 9),
    ]
):

    def _mk(sig=_sig, n=_n, i=_i):
        def f():
            r = _interrupt_resume(f"k02_{i}", sig, n)
            if r[0] is None:
                return True, r[1]
            return r

        return f

    probe(f"K02-place-{signal.Signals(_sig).name}-after-{_n}")(_mk())


probe("K03-place-workers2-SIGINT")(
    lambda: (lambda r: (True, r[1]) if r[0] is None else r)(
        _interrupt_resume("k03", signal.SIGINT, 5, ["--workers", "2"])
    )
)


def full_memo(args, kind="stabctl-place") -> tuple[Path, list[bytes]]:
    """Run args uninterrupted, copying its memo as it grows: (memo name, its lines)."""
    x = fresh("full_" + str(abs(hash(" ".join(args)))))
    out = WORK / f"full_{time.time_ns()}.out"
    pid = launch(args, out, xdg=x)
    best, name = b"", None
    t0 = time.time()
    while alive(pid) and time.time() - t0 < 300:
        for f in memo_files(x, kind):
            if f.suffix == ".jsonl":
                try:
                    b = f.read_bytes()
                except OSError:
                    continue
                if len(b) > len(best):
                    best, name = b, f.name
        time.sleep(0.02)
    kill_group(pid)
    return name, [ln for ln in best.splitlines() if _whole(ln)]


FULL = {}


def planted_run(base_args, new_args, tag, kind="stabctl-place"):
    """Plant the whole memo of base_args, then run new_args: its JSON vs an uninterrupted
    run of new_args, and how many jobs it took from the memo."""
    key = " ".join(base_args)
    if key not in FULL:
        FULL[key] = full_memo(base_args, kind)
    name, lines = FULL[key]
    if not lines:
        raise RuntimeError("no memo captured")
    x = fresh(tag)
    (x / kind).mkdir(mode=0o700)
    (x / kind / name).write_bytes(b"\n".join(lines) + b"\n")
    rc, out, err = run(new_args, xdg=x)
    took = re.search(r"(\d+) simulation job\(s\) taken", err)
    return rc, out, err, (int(took.group(1)) if took else 0), len(lines)


SETTINGS = [
    ("gain20", ["--target-cct-gain", "20"]),
    ("coi-rest", ["--coi", "rest"]),
    ("step", ["--step", "0.004"]),
    ("load-levels", ["--load-levels", "0.95"]),
    ("cost-mwh", ["--cost-mwh", "0.3"]),
    ("tol", ["--tol-ms", "2"]),
    ("deadband", ["--deadband-hz", "0.05"]),
    ("no-q-limits", ["--no-q-limits"]),
    ("max-site-pct", ["--max-site-pct", "20"]),
    ("conventions", ["--conventions", "pstess"]),
]


def _stale(extra):
    def f():
        new = [a for a in PLACE if True]
        if extra[0] == "--target-cct-gain":
            new[new.index("--target-cct-gain") + 1] = extra[1]
        else:
            new += extra
        rc, out, err, took, n = planted_run(PLACE, new, "k04")
        if rc not in (0, 1, 2):
            return False, f"rc {rc}: {err[-200:]}"
        if tb(err):
            return False, f"traceback: {err[-300:]}"
        try:
            b = baseline(new)
        except RuntimeError as exc:
            if rc == 2:  # the setting refused alike
                return True, f"refused (rc 2) as without memo? {str(exc)[:120]}"
            raise
        d = diff(b, norm(out)) if rc in (0, 1) else "rc 2 with memo"
        if d:
            return False, f"with the memo of another setting (took {took} of {n}): {d}"
        return True, f"same as uninterrupted; took {took} of {n} planted jobs"

    return f


for _name, _extra in SETTINGS:
    probe(f"K04-place-stale-{_name}")(_stale(_extra))


@probe("K05-place-two-runs-one-case")
def _():
    """A (short) and B (longer, other settings) of one case at once; A ends and removes
    the memo file B is still keeping into; B interrupted: does its line tell the truth?"""
    x = fresh("k05")
    a_args = PLACE
    b_args = [a for a in PLACE] + [
        "--load-levels",
        "0.9,0.95,1.0,1.05",
        "--uniform-reference",
        "--alone",
    ]
    oa, ob = WORK / "k05a.out", WORK / "k05b.out"
    pb = launch(b_args, ob, xdg=x)
    time.sleep(1.0)
    pa = launch(a_args, oa, xdg=x)
    wait_gone(pa, 200)
    if not alive(pb):
        return True, "B ended before A: not tested"
    time.sleep(0.3)
    memo = sorted((x / "stabctl-place").glob("*.jsonl"))
    sum(_lines(f) for f in memo)
    os.kill(pb, signal.SIGINT)
    wait_gone(pb, 60)
    kill_group(pb)
    n_file2 = sum(_lines(f) for f in sorted((x / "stabctl-place").glob("*.jsonl")))
    line = last_interrupted(ob.read_text())
    m = re.match(r"interrupted: (\d+) finished", line)
    a_json = oa.read_text()
    a_ok = '"verified": true' in a_json
    msgs = []
    if not a_ok:
        msgs.append(f"A did not end verified: {a_json[-200:]}")
    if m and int(m.group(1)) != n_file2:
        msgs.append(
            f"B says {m.group(1)} jobs kept; its memo file holds {n_file2} "
            f"(A removed the shared file {memo[0].name if memo else ''} when it ended)"
        )
    rc, out, err = run(b_args, xdg=x)
    took = re.search(r"(\d+) simulation job\(s\) taken", err)
    d = diff(baseline(b_args), norm(out)) if rc in (0, 1) else f"rc {rc}"
    if d:
        msgs.append(f"B resumed differs: {d}")
    return not msgs, "; ".join(
        msgs
    ) or f"B line {line[:80]}.. file {n_file2}, rerun took {took.group(1) if took else 0}"


@probe("K06-place-memo-removed-exit1-kept-exit2")
def _():
    msgs = []
    x = fresh("k06a")
    args1 = [a for a in PLACE] + ["--max-iter", "1", "--max-rounds", "1"]
    rc, _out, err = run(args1, xdg=x)
    left = (
        [p.name for p in (x / "stabctl-place").iterdir()] if (x / "stabctl-place").exists() else []
    )
    if left:
        msgs.append(f"exit {rc}: left {left}")
    r1 = rc
    x = fresh("k06b")
    args2 = [a for a in PLACE]
    args2[args2.index("--target-cct-gain") + 1] = "400"
    rc, _out, err2 = run(args2, xdg=x)
    left = (
        [p.name for p in (x / "stabctl-place").iterdir()] if (x / "stabctl-place").exists() else []
    )
    # a refused plan (exit 2) keeps its memo since round 39's review (a scheduler down
    # when a plan is run again must not cost its kept work); old ones go after 30 days
    if rc == 2 and len(left) != 1:
        msgs.append(f"exit {rc}: kept {left}, not its one memo")
    if tb(err + err2):
        msgs.append("traceback")
    return not msgs, "; ".join(msgs) or (
        f"exit {r1}: nothing left; exit {rc} ({err2.strip().splitlines()[-1][:90]}): its memo kept"
    )


def _plant(kind, x, name):
    d = x / "stabctl-place"
    d.mkdir(mode=0o700, exist_ok=True)
    p = d / name
    if kind == "symlink":
        tgt = x / "target.jsonl"
        tgt.write_text("")
        p.symlink_to(tgt)
    elif kind == "mode666":
        p.write_text("")
        os.chmod(p, 0o666)
    elif kind == "other-owner":
        p.write_text("")
        os.chown(p, 1000, 1000)
    elif kind == "directory":
        p.mkdir()
    elif kind == "fifo":
        os.mkfifo(p)
    elif kind == "dir-777":
        os.chmod(d, 0o777)
    elif kind == "dir-other-owner":
        os.chown(d, 1000, 1000)
    elif kind == "dir-symlink":
        os.rmdir(d)
        real = x / "elsewhere"
        real.mkdir(mode=0o700)
        d.symlink_to(real)
    elif kind == "xdg-is-file":
        shutil.rmtree(d)
        shutil.rmtree(x)
        x.write_text("")


def _name_of_case():
    key = " ".join(PLACE)
    if key not in FULL:
        FULL[key] = full_memo(PLACE)
    return FULL[key][0]


for _kind in [
    "symlink",
    "mode666",
    "other-owner",
    "directory",
    "fifo",
    "dir-777",
    "dir-other-owner",
    "dir-symlink",
    "xdg-is-file",
]:

    def _mkp(kind=_kind):
        def f():
            x = fresh("k07_" + kind)
            tmp = fresh("k07tmp_" + kind)
            _plant(kind, x, _name_of_case())
            rc, out, err = run(PLACE, xdg=x, timeout=200, TMPDIR=tmp)
            msgs = []
            if rc != 0:
                msgs.append(f"rc {rc}: {err.strip()[-200:]}")
            elif diff(baseline(PLACE), norm(out)):
                msgs.append("result differs")
            if tb(err):
                msgs.append("traceback")
            warn = [ln for ln in err.splitlines() if ln.startswith("warning:")]
            if kind == "symlink" and (x / "target.jsonl").read_text():
                msgs.append("symlink target written")
            [str(p) for p in Path(tmp).rglob("*")] + [
                str(p) for p in (x / "stabctl-place").rglob("*") if (x / "stabctl-place").is_dir()
            ] if x.is_dir() else []
            return not msgs, "; ".join(msgs) or (
                f"rc 0 same plan; {warn[0][:150] if warn else 'no warning'}"
            )

        return f

    probe(f"K07-place-planted-{_kind}")(_mkp())


def _edited(edit):
    """Plant the whole memo with each result edited by edit(result) -> new result."""
    name, lines = (
        FULL.setdefault(" ".join(PLACE), full_memo(PLACE))
        if " ".join(PLACE) not in FULL
        else FULL[" ".join(PLACE)]
    )
    x = fresh("k08")
    (x / "stabctl-place").mkdir(mode=0o700)
    out = []
    for ln in lines:
        rec = json.loads(ln)
        rec["result"] = edit(rec["result"])
        out.append(json.dumps(rec))
    (x / "stabctl-place" / name).write_text("\n".join(out) + "\n")
    return run(PLACE, xdg=x, timeout=200)


def _first_number(r, f):
    """r with its first float (depth-first) replaced by f(value)."""
    done = [False]

    def walk(v):
        if done[0]:
            return v
        if isinstance(v, float) and v == v:
            done[0] = True
            return f(v)
        if isinstance(v, dict):
            return {k: walk(w) for k, w in v.items()}
        if isinstance(v, list):
            return [walk(w) for w in v]
        return v

    return walk(r)


EDITS = [
    ("string", lambda r: "garbage"),
    ("null", lambda r: None),
    ("empty-dict", lambda r: {}),
    ("list", lambda r: [1, 2]),
    ("nan", lambda r: _first_number(r, lambda v: float("nan"))),
    ("inf", lambda r: _first_number(r, lambda v: float("inf"))),
    ("forged-x2", lambda r: _first_number(r, lambda v: v * 2)),
]

for _n, _e in EDITS:

    def _mke(edit=_e, n=_n):
        def f():
            rc, out, err = _edited(edit)
            last = err.strip().splitlines()[-1] if err.strip() else ""
            if tb(err):
                x = WORK / "k08"
                _rc2, _, err2 = run(PLACE, xdg=x, timeout=200)
                sticky = "; the memo stays and the same command crashes again" if tb(err2) else ""
                return False, f"rc {rc}: traceback ending {last[:120]}{sticky}"
            if rc == 0 and diff(baseline(PLACE), norm(out)):
                return False, (
                    f"rc 0, a plan differing from the true one, no word that the kept "
                    f"results were hand-edited: {diff(baseline(PLACE), norm(out))[:150]}"
                )
            if rc == 0:
                return True, "rc 0, same plan"
            return True, f"rc {rc}: {last[:160]}"

        return f

    probe(f"K08-place-memo-edited-{_n}")(_mke())


@probe("K09-place-memo-giant-line")
def _():
    name = _name_of_case()
    x = fresh("k09")
    (x / "stabctl-place").mkdir(mode=0o700)
    with open(x / "stabctl-place" / name, "wb") as fh:
        fh.write(b'{"key": "' + b"a" * (60 << 20) + b'"\n')
        fh.write(b"[" * 200000 + b"\n")  # deep nesting
        fh.write(b'{"key": ' + b"[" * 200000 + b"\n")
    t0 = time.time()
    rc, out, err = run(PLACE, xdg=x, timeout=300)
    msgs = []
    if rc != 0 or tb(err):
        msgs.append(f"rc {rc} {err.strip()[-200:]}")
    elif diff(baseline(PLACE), norm(out)):
        msgs.append("plan differs")
    said = [ln for ln in err.splitlines() if "passed over" in ln or "damaged" in ln]
    return not msgs, "; ".join(
        msgs
    ) or f"rc 0 same plan in {time.time() - t0:.0f}s; said: {said[:1]}"


@probe("K10-place-ulimit-f")
def _():
    x = fresh("k10")
    (x / "stabctl-place").mkdir(parents=True, mode=0o700)
    name = _name_of_case()
    # a memo already 100 kB: the first append passes ulimit -f 100 (kB)
    (x / "stabctl-place" / name).write_text(("\n" * 1) + "x" * (100 * 1024) + "\n")
    rc, out, err = run(PLACE, xdg=x, pre="ulimit -f 100;", timeout=200)
    msgs = []
    last = err.strip().splitlines()[-1] if err.strip() else ""
    if tb(err):
        msgs.append(f"traceback: {last[:200]}")
    if rc == 0 and diff(baseline(PLACE), norm(out)):
        msgs.append("plan differs")
    if rc not in (0, 2):
        msgs.append(f"rc {rc}")
    return not msgs, "; ".join(msgs) or f"rc {rc}: {last[:200]}"


def _mounted(size_k: int, ro: bool, fill_k: int = 0) -> Path:
    m = K / "mnt"
    m.mkdir(exist_ok=True)
    subprocess.run(["umount", str(m)], capture_output=True)
    subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size_k}k,mode=755", "tmpfs", str(m)], check=True
    )
    (m / "stabctl-place").mkdir(mode=0o700)
    (m / "stabctl-estimate").mkdir(mode=0o700)
    if fill_k:
        with open(m / "filler", "wb") as fh:
            try:
                fh.write(b"x" * (fill_k * 1024))
            except OSError:
                pass
    if ro:
        subprocess.run(["mount", "-o", "remount,ro", str(m)], check=True)
    return m


def _umount():
    subprocess.run(["umount", str(K / "mnt")], capture_output=True)


def _cache_fs_probe(ro, size_k, fill_k, args=None, tag=""):
    args = args or PLACE
    m = _mounted(size_k, ro, fill_k)
    try:
        rc, out, err = run(args, xdg=m, timeout=300, MPLCONFIGDIR=WORK / "mpl")
        left = [p.name for p in (m / "stabctl-place").iterdir()] + [
            p.name for p in (m / "stabctl-estimate").iterdir()
        ]
    finally:
        _umount()
    last = err.strip().splitlines()[-1] if err.strip() else ""
    msgs = []
    if tb(err):
        msgs.append(f"traceback: {last[:200]}")
    if rc != 0:
        msgs.append(
            f"rc {rc}: {last[:200]!r} (the kept work is only a cache; no file named)"
            if "/" not in last
            else f"rc {rc}: {last[:200]!r}"
        )
    elif diff(baseline(args), norm(out)):
        msgs.append("result differs")
    return not msgs, "; ".join(msgs) or f"rc 0 same result; left {left}; {last[:120]}"


@probe("K11-place-cache-read-only")
def _():
    return _cache_fs_probe(True, 256, 0)


@probe("K12-place-cache-full")
def _():
    return _cache_fs_probe(False, 64, 60)


# ---------------------------------------------------------------------------- estimate cct
ECCT = [
    "estimate",
    "cct",
    "kundur",
    "--fault",
    "3",
    "--far-bus",
    "101",
    "--esd-pct",
    "5",
    "--runs",
    "2",
    "--json",
]


def _ecct_resume(tag, sig, n_after, args=ECCT):
    x = fresh(tag)
    text, _gone = interrupt_after(
        args, n_after, sig, xdg=x, wait_file=str(x / "stabctl-estimate" / "*.jsonl")
    )
    files = [f for f in memo_files(x, "stabctl-estimate") if f.suffix == ".jsonl"]
    n_file = sum(_lines(f) for f in files)
    line = last_interrupted(text)
    msgs = []
    if '"cct_cycles"' in text:
        return True, "finished before the signal"
    if sig in (signal.SIGINT, signal.SIGTERM):
        m = re.match(r"interrupted: (\d+) finished CCT search\(es\) are kept in (\S+);", line)
        if not m and "no CCT search had finished" not in line:
            msgs.append(f"interrupted line: {line!r}")
        elif m and int(m.group(1)) != n_file:
            msgs.append(f"says {m.group(1)} kept, file holds {n_file}")
        if tb(text):
            msgs.append("traceback on interrupt")
    rc, out, err = run(args, xdg=x)
    if rc != 0:
        return False, f"rerun rc {rc}: {err[-300:]}"
    d = diff(baseline(args), norm(out))
    if d:
        msgs.append(f"resumed differs: {d}")
    left = memo_files(x, "stabctl-estimate")
    if left:
        msgs.append(f"left behind {[p.name for p in left]}")
    read = re.search(r"(\d+) finished CCT search\(es\) of an interrupted run", err)
    return not msgs, "; ".join(msgs) or (
        f"{signal.Signals(sig).name} after {n_file} records; rerun read "
        f"{read.group(1) if read else 0}; same JSON, nothing left"
    )


for _i, (_sig, _n) in enumerate(
    [
        (signal.SIGINT, 1),
        (signal.SIGTERM, 3),
        (signal.SIGKILL, 4),
        (signal.SIGHUP, 2),
        (signal.SIGINT, 6),
    ]
):

    def _mkc(sig=_sig, n=_n, i=_i):
        return lambda: _ecct_resume(f"k13_{i}", sig, n)

    probe(f"K13-ecct-{signal.Signals(_sig).name}-after-{_n}")(_mkc())


@probe("K14-ecct-cache-read-only")
def _():
    return _cache_fs_probe(True, 256, 0, ECCT)


@probe("K15-ecct-two-at-once")
def _():
    x = fresh("k15")
    oa = WORK / "k15a.out"
    pa = launch(ECCT, oa, xdg=x)
    t0 = time.time()
    while time.time() - t0 < 60 and not any(memo_files(x, "stabctl-estimate")):
        time.sleep(0.05)
    rc, out, err = run(ECCT, xdg=x)
    wait_gone(pa, 200)
    a = oa.read_text()
    msgs = []
    if tb(err) or tb(a):
        msgs.append("traceback")
    js_a = a[a.index("{") :] if "{" in a else ""
    if rc == 0 and diff(baseline(ECCT), norm(out)):
        msgs.append(f"second run differs: {diff(baseline(ECCT), norm(out))}")
    try:
        if diff(baseline(ECCT), norm(js_a)):
            msgs.append("first run differs")
    except ValueError:
        msgs.append(f"first run gave no JSON: {a[-200:]}")
    left = memo_files(x, "stabctl-estimate")
    if left:
        msgs.append(f"left {[p.name for p in left]}")
    return not msgs, "; ".join(
        msgs
    ) or f"second: rc {rc} {err.strip().splitlines()[-1][:140] if err.strip() else ''}"


@probe("K16-ecct-damaged-records")
def _():
    """A kept records file with a forged/odd line: warned, redone, same result?"""
    x = fresh("k16")
    _text, _ = interrupt_after(
        ECCT, 3, signal.SIGINT, xdg=x, wait_file=str(x / "stabctl-estimate" / "*.jsonl")
    )
    files = [f for f in memo_files(x, "stabctl-estimate") if f.suffix == ".jsonl"]
    if not files:
        return False, "nothing kept"
    lines = files[0].read_text().splitlines()
    rec = json.loads(lines[0])
    rec["result"] = "garbage"
    files[0].write_text("\n".join([json.dumps(rec)] + lines[1:]) + "\n")
    rc, out, err = run(ECCT, xdg=x)
    last = err.strip().splitlines()[-1] if err.strip() else ""
    if tb(err):
        return False, f"traceback {last[:200]}"
    if rc == 0 and diff(baseline(ECCT), norm(out)):
        return False, f"rc 0 differs: {diff(baseline(ECCT), norm(out))}"
    left = memo_files(x, "stabctl-estimate")
    if left:
        return False, (
            f"rc {rc}; the damaged kept file stays in the cache after the command "
            f"ended: {[p.name for p in left]} ({last[:120]})"
        )
    return (rc == 0), f"rc {rc}: {last[:200]}"


# ---------------------------------------------------------------------------- C37 plausibility
C37_SETUP = r"""
import numpy as np, stabctl, json, sys
from stabctl.estimation import c37, pmu as pm, sources
from stabctl.estimation.settings import PMUSettings
from stabctl.dynamics.events import fault_with_clearing
case = stabctl.load_case("kundur")
res = stabctl.Simulator(case).run([fault_with_clearing(case, 3, 101, 0.5, 7)], t_end=1.0)
pmus = pm.machine_pmus(case)
frames = list(pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(), seed=1))
cfg = c37.stream_config(case, pmus, 60)
cfg2 = c37.config_frame(cfg)
def enc(fr):
    return cfg2.convert2bytes() + b"".join(c37.data_frame(cfg, cfg2, x) for x in fr)
def with_freq(fr, k, pmu, f):
    out = list(fr)
    out[k] = fr[k]._replace(freq=np.where(np.arange(len(pmus)) == pmu, f, fr[k].freq))
    return out
"""


def py(code, timeout=300):
    p = subprocess.run(
        [sys.executable, "-c", C37_SETUP + code],
        env=env(WORK / "xdg"),
        cwd=WORK,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return p.returncode, p.stdout, p.stderr


@probe("K17-c37-freq-bound")
def _():
    rc, out, err = py(r"""
r = {}
for f in (70.0, 70.001, 50.0, 49.999, 69.99):
    fr = with_freq(frames, 40, 0, f)
    got = sources.merge(case, pmus, 60, [(cfg2, [c37.data_frame(cfg, cfg2, x) for x in fr])])
    r[repr(f)] = bool(got.frames[40].valid[0])
print(json.dumps(r))
""")
    if rc != 0:
        return False, f"rc {rc}: {err[-300:]}"
    r = json.loads(out.strip().splitlines()[-1])
    want = {"70.0": True, "70.001": False, "50.0": True, "49.999": False, "69.99": True}
    bad = {k: v for k, v in r.items() if want[k] != v}
    return not bad, f"valid flags {r}" + (f"; unexpected {bad}" if bad else "")


@probe("K18-rmse-source-late-start-one-frame")
def _():
    rc, _out, err = py(r"""
open("late1.c37", "wb").write(enc(frames[1:]))
open("whole.c37", "wb").write(enc(frames))
open("pmu0bad.c37", "wb").write(enc([f._replace(freq=np.where(np.arange(len(pmus)) == 0, 75.0, f.freq)) for f in frames]))  # noqa: E501
""")
    if rc != 0:
        return False, f"setup rc {rc}: {err[-300:]}"
    base = [
        "estimate",
        "rmse",
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--t-fault",
        "0.5",
        "--clear-cycles",
        "7",
        "--tf",
        "1",
        "--seed",
        "1",
        "--source",
    ]
    msgs, said = [], []
    rc1, _o1, e1 = run(base + ["late1.c37"])
    if rc1 != 2 or "starts at t = 0.0167 s, 1 reporting" not in e1:
        msgs.append(f"late by one frame: rc {rc1} {e1.strip()[-200:]}")
    rc2, _o2, e2 = run(base + ["whole.c37"])
    if rc2 != 0:
        msgs.append(f"whole: rc {rc2} {e2.strip()[-200:]}")
    rc3, o3, e3 = run(base + ["pmu0bad.c37"])
    said.append(
        f"every frame of PMU 0 at 75 Hz: rc {rc3}: {(e3.strip() or o3.strip()).splitlines()[-1][:220]}"
    )
    if tb(e3):
        msgs.append("traceback on a PMU always implausible")
    rc4, o4, e4 = run(["estimate", "track", "kundur", "--source", "late1.c37", "--out", "t.csv"])
    said.append(
        f"track of the late one: rc {rc4} {(e4.strip() or o4.strip()).splitlines()[-1][:160]}"
    )
    if rc4 != 0 or tb(e4):
        msgs.append(f"track late: rc {rc4}")
    rc5, o5, e5 = run(["estimate", "track", "kundur", "--source", "pmu0bad.c37", "--out", "t2.csv"])
    said.append(f"track PMU0 bad: rc {rc5} {(e5.strip() or o5.strip()).splitlines()[-1][:200]}")
    if tb(e5):
        msgs.append("traceback track pmu0bad")
    return not msgs, "; ".join(msgs + said)


# ---------------------------------------------------------------------------- other interrupts
OTHER = [
    ("cct-miniwecc", ["cct", "miniwecc", "--fault", "83", "--far-bus", "33", "--json"], 1.5),
    (
        "screen-lines",
        ["screen", "kundur", "--lines", "--out", "scr.jsonl", "--workers", "1", "--json"],
        "scr.jsonl",
    ),
    (
        "sweep-cct",
        [
            "sweep-cct",
            "kundur",
            "--faults",
            "DEFAULT",
            "--esd-pct",
            "none,5,10,15",
            "--out",
            "sw.jsonl",
            "--workers",
            "1",
            "--json",
        ],
        "sw.jsonl",
    ),
    (
        "estimate-rmse",
        [
            "estimate",
            "rmse",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--runs",
            "20",
            "--json",
        ],
        4,
    ),
]

for _name, _args, _delay in OTHER:

    def _mko(args=_args, delay=_delay, name=_name):
        def f():
            x = fresh("k19_" + name)
            cwd = fresh("k19cwd_" + name)
            out = WORK / f"k19_{name}.out"
            pid = launch(args, out, xdg=x, cwd=cwd)
            if isinstance(delay, str):
                t0 = time.time()
                while time.time() - t0 < 60 and alive(pid) and _lines(cwd / delay) < 3:
                    time.sleep(0.02)
            else:
                time.sleep(delay)
            if not alive(pid):
                return True, f"ended within {delay}s: not interrupted ({out.read_text()[-100:]!r})"
            os.kill(pid, signal.SIGINT)
            wait_gone(pid, 60)
            kill_group(pid)
            text = out.read_text(errors="replace")
            lines = [ln for ln in text.splitlines() if ln.startswith("interrupted:")]
            msgs = []
            if len(lines) != 1:
                msgs.append(f"{len(lines)} interrupted: lines")
            if tb(text):
                msgs.append("traceback")
            line = lines[-1] if lines else text[-200:]
            rc, o, e = run(args, xdg=x, cwd=cwd, timeout=400)
            if rc not in (0, 1):
                msgs.append(f"rerun rc {rc} {e.strip()[-150:]}")
            else:
                cwd2 = fresh("k19cwd2_" + name)
                _rc2, o2, _e2 = run(args, xdg=fresh("k19x2_" + name), cwd=cwd2, timeout=400)
                try:
                    d = diff(strip(json.loads(o2)), strip(json.loads(o)))
                except ValueError:
                    d = "" if o == o2 else "text differs"
                if d:
                    msgs.append(f"resumed differs from uninterrupted: {d[:200]}")
            return not msgs, "; ".join(msgs) or f"{line[:230]}"

        return f

    probe(f"K19-interrupt-{_name}")(_mko())


@probe("K20-api-plan-memo")
def _():
    rc, out, err = py(
        r"""
import tempfile, os
from stabctl.parallel import worker_pool
from stabctl.placement.loop import Study
from stabctl.placement.memo import Memo
from stabctl.placement.plan import PlanOptions, plan
from stabctl.placement.requirements import Requirement
from stabctl.stability.cct import LineFault
from stabctl.errors import InputError
faults = [LineFault(3, 101), LineFault(13, 101)]
d = tempfile.mkdtemp(dir=".")
path = os.path.join(d, "m", "k.jsonl")
r = {}
with worker_pool(1) as run_map:
    m1 = Memo(path)
    a = plan("kundur", faults, Requirement(gain_pct=10), PlanOptions(memo=m1), Study(run_map=run_map)).to_dict()  # noqa: E501
    r["exists_after_api_plan"] = os.path.exists(path)
    m1.close()
    m2 = Memo(path)
    b = plan("kundur", faults, Requirement(gain_pct=10), PlanOptions(memo=m2), Study(run_map=run_map)).to_dict()  # noqa: E501
    r["n_written1"], r["n_read2"], r["n_reused2"], r["n_written2"] = m1.n_written, m2.n_read, m2.n_reused, m2.n_written  # noqa: E501
    # the same Memo object for another requirement: nothing wrong reused
    c = plan("kundur", faults, Requirement(gain_pct=20), PlanOptions(memo=m2), Study(run_map=run_map)).to_dict()  # noqa: E501
    c0 = plan("kundur", faults, Requirement(gain_pct=20), PlanOptions(), Study(run_map=run_map)).to_dict()  # noqa: E501
for x in (a, b, c, c0):
    x.pop("wall_time_s", None)
r["same"] = a == b
r["same_other_req"] = c == c0
try:
    PlanOptions(memo=path)
    r["str_memo"] = "accepted"
except InputError as e:
    r["str_memo"] = str(e)[:100]
print(json.dumps(r))
""",
        timeout=400,
    )
    if rc != 0:
        return False, f"rc {rc}: {err[-300:]}"
    r = json.loads(out.strip().splitlines()[-1])
    ok = r["same"] and r["same_other_req"] and r["n_written2"] == 0 and r["n_reused2"] > 0
    return ok, json.dumps(r)


@probe("K21-place-out-write-fails-after-plan")
def _():
    """--out on a full file system: the plan ends, the memo is removed, then the output
    cannot be written: are the plan's simulations lost?"""
    x = fresh("k21")
    m = _mounted(64, False, 62)
    try:
        args = [a for a in PLACE if a != "--json"] + ["--out", str(m / "plan.json")]
        rc, _out, err = run(args, xdg=x)
        kept = [p.name for p in memo_files(x) if p.suffix == ".jsonl"]
        outs = [p.name for p in m.iterdir()]
    finally:
        _umount()
    last = err.strip().splitlines()[-1] if err.strip() else ""
    if rc == 0:
        return True, f"rc 0?? {outs}"
    if not kept:
        return False, (
            f"rc {rc} {last[:150]!r}; the memo was removed before the output was "
            "written: every simulation is lost and the same command redoes them all"
        )
    return True, f"rc {rc} {last[:150]!r}; memo kept {kept}"


@probe("K22-place-interrupt-after-plan-ended")
def _():
    """Ctrl-C while the plan's JSON is being written to a slow reader (a pipe of 4 kB not
    read yet): the plan has ended and its memo is removed: does the interrupted line say
    so, or does it claim the removed file keeps N jobs?"""
    import fcntl

    x = fresh("k22")
    r, w = os.pipe()
    fcntl.fcntl(w, 1031, 4096)  # F_SETPIPE_SZ
    errf = open(WORK / "k22.err", "wb")  # noqa: SIM115 - the child's stderr, closed after it

    def pre():
        for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM):
            signal.signal(s, signal.SIG_DFL)

    big = PLACE + ["--load-levels", "0.9,0.95,1.0,1.05", "--uniform-reference", "--alone"]
    p = subprocess.Popen(
        ["stabctl", *big],
        stdout=w,
        stderr=errf,
        env=env(x),
        cwd=WORK,
        start_new_session=True,
        preexec_fn=pre,
    )
    os.close(w)
    t0 = time.time()
    seen = False
    while time.time() - t0 < 200 and p.poll() is None:
        files = [f for f in memo_files(x) if f.suffix == ".jsonl"]
        if files:
            seen = True
        elif seen:
            break  # removed: the plan has ended
        time.sleep(0.01)
    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    # drain so that it can end
    os.set_blocking(r, False)
    t1 = time.time()
    while p.poll() is None and time.time() - t1 < 30:
        try:
            os.read(r, 65536)
        except BlockingIOError:
            time.sleep(0.05)
    try:
        while os.read(r, 65536):
            pass
    except OSError:
        pass
    os.close(r)
    if p.poll() is None:
        p.kill()
    errf.close()
    err = (WORK / "k22.err").read_text()
    line = last_interrupted(err)
    files = [f for f in memo_files(x) if f.suffix == ".jsonl"]
    m = re.match(r"interrupted: (\d+) finished simulation job\(s\) are kept in (\S+);", line)
    if m and not files:
        return False, (
            f"rc {p.returncode}: {line[:160]!r} but that file was removed when the "
            "plan ended (nothing is kept)"
        )
    return True, f"rc {p.returncode}: {line[:160]!r}; files {files}"


@probe("K23-memo-line-after-a-cut-line")
def _():
    rc, out, err = py(r"""
import tempfile, os
from stabctl.placement.memo import Memo
d = tempfile.mkdtemp(dir=".")
p = os.path.join(d, "c.jsonl")
m = Memo(p); m.add("k1", {"cct_s": 0.1}); m.close()
open(p, "a").write('{"key": "k2", "result": {"cc')   # SIGKILL mid-write (or a full disk)
m2 = Memo(p); m2.add("k3", {"cct_s": 0.3}); said = m2.kept(); m2.close()
print(json.dumps({"said_kept": said, "reread": sorted(Memo(p).results)}))
""")
    if rc != 0:
        return False, f"rc {rc} {err[-200:]}"
    r = json.loads(out.strip().splitlines()[-1])
    if "k3" not in r["reread"]:
        return False, (
            f"a result appended after a cut line is lost on reading (glued to it): "
            f"kept() says {r['said_kept'][:40]!r}, file gives {r['reread']}"
        )
    return True, json.dumps(r)[:200]


@probe("K24-simulate-json-warnings")
def _():
    args = [
        "simulate",
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--method",
        "trapezoid",
        "--step",
        "0.05",
        "--json",
    ]
    rc, out, err = run(args, timeout=200)
    if rc != 0:
        return False, f"rc {rc} {err.strip()[-200:]}"
    js = json.loads(out)
    stderr_w = [ln[len("warning: ") :] for ln in err.splitlines() if ln.startswith("warning: ")]
    if js.get("warnings") != stderr_w:
        return False, f"JSON warnings {js.get('warnings')} vs stderr {stderr_w}"
    return True, f"{len(stderr_w)} warning(s) equal in JSON and stderr: {stderr_w[:1]}"[:230]


@probe("K25-ecct-cache-full")
def _():
    return _cache_fs_probe(False, 64, 62, ECCT)


# ---------------------------------------------------------------------------- summary
_umount()
n_short = sum(1 for _, ok, _ in RESULTS if not ok)
print(f"\n{len(RESULTS)} probes, {len(RESULTS) - n_short} ok, {n_short} SHORT (work dir {WORK})")
if os.environ.get("KEEP") != "1":
    shutil.rmtree(K, ignore_errors=True)
sys.exit(1 if n_short else 0)
