#!/usr/bin/env python
"""Thirty-sixth reliability round (round 48, part AF): the newcomer who trusts the docs.
README.md, docs/*.md and every `--help` "Example:" block are RUN literally (in a temporary
directory; `stabctl` as `python -m stabctl`), and the figures and words they quote (a CCT,
an eigenvalue, a count, a file written, an exit status) compared with what the command
prints now; the ```python blocks are run as written; a few cheap statements of behaviour
("exit status 2 and one error: line", "nothing is written") are checked.  Earlier rounds
(reliability_probes_32.py AB51/AB52) checked only that the options exist.

    CLONE=/path/to/clone python reliability_probes_36.py        # ONLY=AF01,AF05 to pick

CLONE (default: this repository) is the package under test; NUMBA_CACHE_DIR the caller's
(warm it first with `python -m stabctl compile`).  Prints per probe: id, ok/SHORT, reason;
exits 1 if any is SHORT.  Every command has a timeout; work in a temporary directory
(removed at the end unless KEEP=1).  About 15-20 minutes with a warm kernel cache on a
loaded 2-core machine (the PMU probes run in real time: 10 s and 60 s streams).

Skipped (said in the output): `stabctl paper` (6-8 min), the ACTIVSg2000 / WECC-240 /
placement.md npcc/wecc lines (long), `sweep-cct ... --scheduler tcp://10.0.0.5`
(a Dask cluster), `place miniwecc --faults faults.csv` (no faults.csv given; long).

The round found 5 of 32 short: REAL, docs/placement.md section 9's own commands fail:
`place --screening` refuses every `stabctl screen` output (a bus fault's record has
circuit null since b7f51558; placement/requirements.py:screening_brackets calls _whole on
it); SMALLER: the help examples of `pmu serve`/`pmu record` (--tf 60 = 3601 frames,
--frames 3600) leave the server exiting 2 after a 60-s wait, and `estimate track --until 60`
over that recording's replay exits 2; docs/placement.md's "`stabctl cct` reports 146 ms"
(now 0.110 s, the window no longer non-monotone); omib names its later durations
MORE_CYCLES, an argument the user never typed, where docs/cli.md says `--fault-cycles`.
All five fixed (a bus fault's null circuit read as 1; --frames 3601 in the examples; the
placement page's example said as it now is; the later durations named --fault-cycles).
"""

# ruff: noqa: E501, BLE001, RUF059, SIM905, RUF100 - a tester's script, kept as written

import os
import re
import shutil
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from _probe_kit import Kit

KIT = Kit(
    "probes_af48_",
    path=False,
    xdg=False,
    env={"COLUMNS": "200"},
    only=filter(None, os.environ.get("ONLY", "").split(",")),
    prefixes=False,
    line="{pid}  {state}  {why}",
    timed=True,
)
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
rec, probe = KIT.rec, KIT.probe
try:
    import andes  # noqa: F401

    ANDES_CASES = Path(andes.__file__).parent / "cases"
except Exception:
    ANDES_CASES = None


def cli(args, timeout=300, cwd=None):
    """(rc, stdout, stderr) of `python -m stabctl args` in WD; of a run out of time, what
    it wrote on stdout."""
    rc, o, e = KIT.cli(args, timeout, cwd=cwd)
    return rc, o, "" if rc == "timeout" else e


def bg(args):
    """A background `python -m stabctl args` (a server)."""
    return subprocess.Popen(
        [sys.executable, "-m", "stabctl", *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=WD,
        env=ENV,
        stdin=subprocess.DEVNULL,
    )


def finish(p, timeout=120):
    try:
        o, e = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        o, e = p.communicate()
        return "timeout", o, e
    return p.returncode, o, e


def wait_port(port, t=180):
    t0 = time.time()
    while time.time() - t0 < t:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return True
        time.sleep(0.5)
    return False


def py(code, timeout=300):
    """(rc, stdout, stderr) of a snippet run as a script in WD."""
    f = Path(WD, f"snippet_{len(RESULTS)}.py")
    f.write_text(textwrap.dedent(code))
    try:
        p = subprocess.run(
            [sys.executable, str(f)],
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=WD,
            env=ENV,
        )
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        return "timeout", "", ""


def doc_block(path, after, lang="python"):
    """The ```lang block that follows the line containing `after` in a doc."""
    text = Path(CLONE, path).read_text()
    i = text.index(after)
    j = text.index("```" + lang, i)
    k = text.index("```", j + 3 + len(lang))
    return text[j + 3 + len(lang) : k]


def tail(s, n=160):
    return " ".join(s.strip().split())[-n:]


# ---------------------------------------------------------------- README "One-minute start"


@probe("AF01")
def _():
    """README: `stabctl simulate miniwecc --fault 83 --far-bus 33 --clear-cycles 6 --esd-pct 5`
    prints 34 machines, 122 buses, 1200 steps, the fault line, 34 ESDs and "stable: largest
    angle from the COI 1.8940 rad"."""
    rc, o, e = cli("simulate miniwecc --fault 83 --far-bus 33 --clear-cycles 6 --esd-pct 5".split())
    want = [
        "case miniwecc: 34 machines, 122 buses; 0-6 s, 1200 steps (h = 5 ms, heun, ieee conventions, PV Q limits held)",
        "3-phase fault at bus 83 at 1 s on line 83-33 (circuit 1), cleared at 1.1 s (after 100.0 ms), line tripped",
        "storage: 34 ESDs of 5 % of machine MVA at the generator HV buses, bang-bang COI (paper Table 3)",
        "stable: largest angle from the COI 1.8940 rad",
    ]
    miss = [w for w in want if w not in o]
    return (
        rc == 0 and not miss,
        f"rc {rc}; missing {miss}; got {tail(o, 300)}"
        if miss or rc
        else "all four quoted lines printed",
    )


@probe("AF02")
def _():
    """README: `stabctl cct kundur --fault 3 --far-bus 101` prints CCT 0.154 s = 9.24 cycles
    (stable at 0.154 s, unstable at 0.155 s = 9.30 cycles; tolerance 1 ms ...)."""
    rc, o, e = cli("cct kundur --fault 3 --far-bus 101".split())
    want = "CCT 0.154 s = 9.24 cycles (stable at 0.154 s, unstable at 0.155 s = 9.30 cycles; tolerance 1 ms,"
    return rc == 0 and want in o, "as quoted" if want in o else f"rc {rc}: {tail(o, 300)} {tail(e)}"


@probe("AF03")
def _():
    """README: `stabctl eig kundur` lists modes 36, 37, 38 with f, zeta, kind and machines as quoted."""
    rc, o, e = cli("eig kundur".split())
    want = [
        "   36   0.612   0.1319  inter-area G3 (bus 11) G4 (bus 12) vs G1 (bus 1) G2 (bus 2)  [areas 2 vs 1]",
        "   37   1.292   0.3637  local      G4 (bus 12) G2 (bus 2) vs G3 (bus 11) G1 (bus 1)",
        "   38   1.340   0.3560  local      G2 (bus 2) G3 (bus 11) vs G1 (bus 1) G4 (bus 12)",
    ]
    miss = [w.split()[0] for w in want if w not in o]
    return (
        rc == 0 and not miss,
        "three quoted rows printed" if not miss else f"rc {rc}; rows {miss} differ: {o[:600]}",
    )


@probe("AF04")
def _():
    """README: `stabctl cases kundur --bus-table --line-table` lists buses and lines (both tables),
    and `stabctl cases kundur` prints the book-to-PSTess bus map (docs/cli.md)."""
    rc, o, e = cli("cases kundur --bus-table --line-table".split())
    rc2, o2, e2 = cli("cases kundur".split())
    bad = []
    if rc != 0 or "101" not in o:
        bad.append(f"tables rc {rc} {tail(e)}")
    if not re.search(r"\bbus(es)?\b", o, re.I) or not re.search(r"\bline", o, re.I):
        bad.append("a table missing")
    if rc2 != 0 or not re.search(r"book|Kundur's", o2):
        bad.append(f"`cases kundur` has no book map: {tail(o2, 200)}")
    return not bad, "; ".join(bad) or "both tables; the map printed"


@probe("AF05")
def _():
    """README's ```python block runs as written and prints 0.154."""
    rc, o, e = py(doc_block("README.md", "In Python:"))
    return rc == 0 and o.strip() == "0.154", f"rc {rc}, printed {o.strip()!r} {tail(e)}"


# ---------------------------------------------------------------- docs/library.md, modal.md


@probe("AF06")
def _():
    """docs/library.md's first two ```python blocks (the second continues the first) run as
    written: 0.154, then 0.15 with SearchOptions(tol=5e-3), and screen(...) returns rows."""
    code = doc_block("docs/library.md", "The public entry points") + doc_block(
        "docs/library.md", "Settings come as objects"
    )
    code += "\nprint('ROWS', type(rows).__name__, len(rows))\nimport os; print('FILE', os.path.exists('screen.jsonl'))\n"
    rc, o, e = py(code, 400)
    lines = o.split()
    ok = rc == 0 and lines[:2] == ["0.154", "0.15"] and "FILE True" in o
    return ok, f"rc {rc}; printed {o.strip()!r}; {tail(e, 300) if rc else ''}"


@probe("AF07")
def _():
    """docs/library.md's Sections 2-4 block runs and prints `True 0.2437...`."""
    rc, o, e = py(doc_block("docs/library.md", "The paper's Sections 2-4"))
    return rc == 0 and re.match(
        r"True 0\.2437", o.strip()
    ) is not None, f"rc {rc}; printed {o.strip()!r} {tail(e)}"


@probe("AF08")
def _():
    """docs/modal.md's block runs as written (linearise(load_case('kundur')): a Case, not a Simulator)
    and its result has eigenvalues; mode_sensitivity exists with (sys, ma)."""
    code = (
        doc_block("docs/modal.md", "# Linearised models")
        + "\nprint('OK', type(sys).__name__, type(ma).__name__, type(sens).__name__)\n"
    )
    rc, o, e = py(code)
    return rc == 0 and "OK StateSpace" in o, f"rc {rc}; {o.strip()[-200:]} {tail(e, 300)}"


# ---------------------------------------------------------------- quoted figures in docs/*.md


@probe("AF09")
def _():
    """docs/cli.md: `stabctl simulate kundur --bus-fault 3:0:0.05 1 1.1 --trip 3 101 --t-trip 1.1
    --close 3 101 1.6 --vref-step 2 3 0.02 --pref-step 1 4 0.05 --tf 10` runs (exit 0) and its
    header names the events."""
    args = "simulate kundur --bus-fault 3:0:0.05 1 1.1 --trip 3 101 --t-trip 1.1 --close 3 101 1.6 --vref-step 2 3 0.02 --pref-step 1 4 0.05 --tf 10".split()
    rc, o, e = cli(args)
    return rc == 0 and "stable" in o, f"rc {rc}: {tail(o, 250)} {tail(e)}"


@probe("AF10")
def _():
    """docs/cli.md: `stabctl cct miniwecc --fault 83 --far-bus 33 --tol-ms 5` prints
    `machine(s) G14 (bus 32) lose synchronism when cleared at 0.080 s`."""
    rc, o, e = cli("cct miniwecc --fault 83 --far-bus 33 --tol-ms 5".split(), 400)
    want = "machine(s) G14 (bus 32) lose synchronism when cleared at 0.080 s"
    return rc == 0 and want in o, "as quoted" if want in o else f"rc {rc}: {tail(o, 400)}"


@probe("AF11")
def _():
    """docs/cli.md: `stabctl screen kundur --buses 3,101` prints the row
    `bus 3 ... 0.238 14.28 0  G1 (bus 1), G2 (bus 2)`."""
    rc, o, e = cli("screen kundur --buses 3,101 --workers 1".split(), 400)
    row = next((ln for ln in o.splitlines() if re.match(r"\s*bus\s+3\b", ln)), "")
    ok = rc == 0 and re.search(r"0\.238\s+14\.28\s+0\s+G1 \(bus 1\), G2 \(bus 2\)", row) is not None
    return (
        ok,
        f"row {row.strip()!r}" if ok else f"rc {rc}: row {row.strip()!r}; {tail(o, 300)} {tail(e)}",
    )


@probe("AF12")
def _():
    """docs/storage.md: `stabctl cct kundur --fault 3 --far-bus 101 --esd-pct 5 [--esd-model wecc]`:
    0.199 s with 5 % ideal devices, 0.195 s with WECC batteries (docs/cli.md: 11.9 cycles)."""
    rc, o, e = cli("cct kundur --fault 3 --far-bus 101 --esd-pct 5".split())
    rc2, o2, e2 = cli("cct kundur --fault 3 --far-bus 101 --esd-pct 5 --esd-model wecc".split())
    a = re.search(r"CCT (\S+) s = (\S+) cycles", o)
    b = re.search(r"CCT (\S+) s = (\S+) cycles", o2)
    got = (a and a.groups(), b and b.groups())
    ok = (
        rc == 0
        and rc2 == 0
        and a
        and b
        and a.group(1) == "0.199"
        and a.group(2).startswith("11.9")
        and b.group(1) == "0.195"
    )
    return bool(ok), f"ideal, wecc: {got} (rc {rc}, {rc2}) {tail(e2) if rc2 else ''}"


@probe("AF13")
def _():
    """docs/cli.md: `simulate --separation-limit` not above the largest pre-disturbance COI angle
    (Kundur: G1 (bus 1), 0.3632 rad) is refused: exit 2, one error: line naming it."""
    rc, o, e = cli("simulate kundur --fault 3 --far-bus 101 --tf 2 --separation-limit 0.3".split())
    ok = rc == 2 and "0.3632" in e and "G1 (bus 1)" in e and "Traceback" not in e
    return ok, f"rc {rc}: {tail(e, 250)}"


@probe("AF14")
def _():
    """--help of simulate: "Bad input (unknown case or bus ...) exit with status 2 and one `error:`
    line; no file is written then" -- an unknown bus with --out and --plot writes nothing."""
    rc, o, e = cli("simulate kundur --fault 999 --far-bus 101 --out bad.csv --plot bad.png".split())
    errs = [ln for ln in e.splitlines() if ln.startswith("error:")]
    written = [f for f in ("bad.csv", "bad.png") if Path(WD, f).exists()]
    return rc == 2 and len(
        errs
    ) == 1 and not written, f"rc {rc}, error lines {len(errs)}, written {written}: {tail(e)}"


@probe("AF15")
def _():
    """--help of eig: "Bad input (unknown case, --areas out of range, --out-dir a file) exits with
    status 2 and one `error:` line; nothing is written then"."""
    Path(WD, "afile").write_text("x")
    bad = []
    for args in (
        ["eig", "kundur", "--areas", "99", "--report", "--out-dir", "eigd"],
        ["eig", "kundur", "--report", "--out-dir", "afile"],
        ["eig", "nosuchcase"],
    ):
        rc, o, e = cli(args)
        errs = [ln for ln in e.splitlines() if ln.startswith("error:")]
        if (
            rc != 2
            or len(errs) != 1
            or Path(WD, "eigd").exists()
            or Path(WD, "afile").read_text() != "x"
        ):
            bad.append(f"{' '.join(args[1:])}: rc {rc}, {len(errs)} error lines {tail(e, 120)}")
    return not bad, "; ".join(bad) or "three refused, nothing written"


@probe("AF16")
def _():
    """--help of cct: "A fault still stable when cleared at --t-max is a verdict (exit 0,
    "cct_s": null, "above_t_max_s", "verdict": "above t_max" in --json)"."""
    import json

    rc, o, e = cli("cct kundur --fault 3 --far-bus 101 --t-max 0.1 --json".split())
    try:
        j = json.loads(o)
    except Exception:
        return False, f"rc {rc}: not JSON: {tail(o)} {tail(e)}"
    ok = (
        rc == 0
        and j.get("cct_s") is None
        and "above_t_max_s" in j
        and j.get("verdict") == "above t_max"
    )
    return (
        ok,
        f"rc {rc}: cct_s {j.get('cct_s')!r}, verdict {j.get('verdict')!r}, keys has above_t_max_s: {'above_t_max_s' in j}",
    )


# ---------------------------------------------------------------- every --help example, run


def help_examples():
    """(command words, example line) of every --help's Example(s) block, continuation lines joined."""
    rc, o, e = cli(["--help"])
    cmds = re.findall(r"^  ([a-z][a-z-]+)\s{2,}", o.split("Commands:")[1], re.M)
    out = []
    for c in cmds:
        rc, h, e = cli([c, "--help"])
        subs = [[c]]
        if "Commands:" in h:
            subs = [
                [c, s]
                for s in re.findall(r"^  ([a-z][a-z-]+)\s{2,}", h.split("Commands:")[1], re.M)
            ]
        for sub in subs:
            rc, h, e = cli([*sub, "--help"])
            m = re.search(r"Examples?[^\n]*:\n(.*?)(?:\n\s*\n|\nOptions:)", h, re.S)
            if not m:
                continue
            joined = m.group(1).replace("\\\n", " ")
            for ln in joined.splitlines():
                if ln.strip().startswith("stabctl "):
                    out.append((sub, " ".join(ln.split())))
    return out


# estimated costs (s) on a loaded 2-core machine; above 180 s: skipped, said in the output
SKIP = {
    "stabctl paper --out-dir reports/paper --only analytic": None,  # cheap: run
    "stabctl sweep-cct miniwecc --faults faults.csv --scheduler tcp://10.0.0.5:8786": "a Dask scheduler at 10.0.0.5 (a network) and a faults.csv the help does not give",
    "stabctl place miniwecc --faults faults.csv --required-clearing-cycles 5 --load-levels 0.9,1.0,1.1 --cost-mw 1 --cost-mwh 0.3 --uniform-reference": "a faults.csv the help does not give; miniWECC placement at three load levels, estimated > 10 min",
}
# files the docs say a --report / --out-dir example writes (docs/cli.md, docs/modal.md)
REPORTS = {
    "stabctl eig kundur --report": ["reports/eig_kundur.md"],
    "stabctl eig miniwecc --areas 3 --report": ["reports/eig_miniwecc_areas3.md"],
    "stabctl paper --out-dir reports/paper --only analytic": [
        "reports/paper/paper.md",
        "reports/paper/run_log.json",
    ],
}
# the examples that need a server or a file another example writes run in AF18-AF21
LATER = ("stabctl pmu ", "stabctl estimate track", "stabctl import-")


@probe("AF17")
def _():
    """Every --help example that needs neither a server, a network nor a file it does not make
    runs literally (in a temp dir) with exit 0, and writes the files it names (--out, --plot,
    -o, --report)."""
    bad, ran, skipped = [], 0, []
    d = Path(WD, "helpex")
    d.mkdir()
    for sub, line in help_examples():
        if sub[0] in ("pmu", "import-psse", "import-andes") or line.startswith(LATER):
            continue
        if SKIP.get(line):
            skipped.append(f"`{line[:50]}...`: {SKIP[line]}")
            continue
        words = line.split()[1:]
        t0 = time.time()
        rc, o, e = cli(words, 600, cwd=d)
        ran += 1
        dt = time.time() - t0
        named = []
        for i, w in enumerate(words[:-1]):
            if w in ("--out", "--plot", "-o"):
                named.append(words[i + 1])
        named += REPORTS.get(line, [])
        missing = [f for f in named if not Path(d, f).exists()]
        if rc != 0 or missing:
            bad.append(f"`{line}`: rc {rc}, missing {missing}: {tail(e, 200)}")
        print(f"    ran `{line}`: rc {rc}, {dt:.0f} s", flush=True)
    if skipped:
        print("    skipped: " + "; ".join(skipped), flush=True)
    return not bad, "; ".join(
        bad
    ) or f"{ran} examples ran, exit 0, files written; {len(skipped)} skipped (printed)"


@probe("AF18")
def _():
    """docs/estimation.md 6.1: `pmu serve kundur --fault 3 --far-bus 101 --clear-cycles 7 --tf 10
    --port 4712 &` then `estimate rmse ... --source tcp://127.0.0.1:4712`: the table's received
    over TCP column, raw 7.3887, kf 7.3594, ekf 1.1684 mHz."""
    srv = bg(
        "pmu serve kundur --fault 3 --far-bus 101 --clear-cycles 7 --tf 10 --port 4712".split()
    )
    if not wait_port(4712):
        srv.kill()
        return False, f"server never listened: {finish(srv, 10)[2][-200:]}"
    rc, o, e = cli(
        "estimate rmse kundur --fault 3 --far-bus 101 --clear-cycles 7 --tf 10 --source tcp://127.0.0.1:4712".split(),
        400,
    )
    src, so, se = finish(srv, 60)
    found = {k: (k in o) for k in ("7.3887", "7.3594", "1.1684")}
    ok = rc == 0 and src == 0 and all(found.values())
    return ok, f"rc {rc}, server rc {src}; figures found {found}" + (
        "" if ok else f": {o[-700:]} {tail(e)}"
    )


@probe("AF19")
def _():
    """--help examples of pmu serve and pmu record, as they read together (docs/estimation.md 6.1
    pairs them too): `pmu serve miniwecc --fault 83 --far-bus 33 --tf 60 --port 4712` and `pmu
    record 127.0.0.1:4712 --frames 3601 -o wecc.c37`: wecc.c37 written, both exit 0 (serve's
    help: "exit status 0 once the PDC has been sent every frame")."""
    srv = bg("pmu serve miniwecc --fault 83 --far-bus 33 --tf 60 --port 4712".split())
    if not wait_port(4712, 300):
        srv.kill()
        return False, f"serve never listened: {finish(srv, 10)[2][-200:]}"
    rc, o, e = cli("pmu record 127.0.0.1:4712 --frames 3601 -o wecc.c37".split(), 300)
    src, so, se = finish(srv, 120)
    shutil.copy(Path(WD, "wecc.c37"), Path(WD, "wecc_keep.c37")) if Path(
        WD, "wecc.c37"
    ).exists() else None
    ok = rc == 0 and src == 0 and Path(WD, "wecc.c37").exists()
    errl = [ln for ln in se.splitlines() if "error" in ln.lower()]
    return (
        ok,
        f"record rc {rc}, wrote wecc.c37 {Path(WD, 'wecc.c37').exists()}; serve rc {src}: {tail(' '.join(errl), 300)}",
    )


@probe("AF31")
def _():
    """--help examples of estimate track and pmu replay on that recording: `estimate track
    miniwecc --source wecc.c37 --out tracked.csv` (a row per frame), then `pmu replay wecc.c37
    --speed 0` read by `estimate track miniwecc --source tcp://127.0.0.1:4712 --until 60 --out
    t.csv`: each exit 0, files written."""
    if not Path(WD, "wecc_keep.c37").exists():
        return False, "no recording (AF19 first)"
    bad = []
    rc, o, e = cli("estimate track miniwecc --source wecc_keep.c37 --out tracked.csv".split(), 300)
    if rc != 0 or not Path(WD, "tracked.csv").exists():
        bad.append(f"track (file) rc {rc}: {tail(e)}")
    else:
        n = len(Path(WD, "tracked.csv").read_text().splitlines())
        if n < 3600:
            bad.append(f"tracked.csv {n} lines for 3600 frames")
    rp = bg("pmu replay wecc_keep.c37 --speed 0".split())
    if not wait_port(4712, 120):
        rp.kill()
        bad.append(f"replay never listened: {tail(finish(rp, 10)[2])}")
    else:
        rc, o, e = cli(
            "estimate track miniwecc --source tcp://127.0.0.1:4712 --until 60 --out t.csv".split(),
            300,
        )
        rrc, ro, re_ = finish(rp, 120)
        if rc != 0 or not Path(WD, "t.csv").exists():
            bad.append(
                f"track (tcp, --until 60) rc {rc}: {tail(e, 300)}; t.csv {Path(WD, 't.csv').exists()}"
            )
        if rrc != 0:
            bad.append(f"replay rc {rrc}: {tail(re_)}")
    return not bad, "; ".join(
        bad
    ) or "track (file) and replay -> track (tcp --until 60): exit 0, files written"


@probe("AF32")
def _():
    """The track example straight from the serve example (no recording between):
    `pmu serve miniwecc --fault 83 --far-bus 33 --tf 60 --port 4712` read by `estimate track
    miniwecc --source tcp://127.0.0.1:4712 --until 60 --out t2.csv`: both exit 0."""
    srv = bg("pmu serve miniwecc --fault 83 --far-bus 33 --tf 60 --port 4712".split())
    if not wait_port(4712, 300):
        srv.kill()
        return False, f"serve never listened: {finish(srv, 10)[2][-200:]}"
    rc, o, e = cli(
        "estimate track miniwecc --source tcp://127.0.0.1:4712 --until 60 --out t2.csv".split(), 300
    )
    src, so, se = finish(srv, 120)
    ok = rc == 0 and src == 0 and Path(WD, "t2.csv").exists()
    return (
        ok,
        f"track rc {rc} {tail(e, 200) if rc else ''}; serve rc {src} {tail(se, 200) if src else ''}",
    )


@probe("AF20")
def _():
    """docs/estimation.md 6.2 / pmu plant --help: `pmu plant miniwecc --fault 83 --far-bus 33
    --clear-cycles 6 --tf 10 --esd-pct 5 --port 4713 &` with `pmu control miniwecc 127.0.0.1:4713
    --esd-pct 5 --estimator ekf`: stable, 8 switchings (printed as "mode commands 8"), no false action,
    600 frames answered (as quoted)."""
    pl = bg(
        "pmu plant miniwecc --fault 83 --far-bus 33 --clear-cycles 6 --tf 10 --esd-pct 5 --port 4713".split()
    )
    if not wait_port(4713, 300):
        pl.kill()
        return False, f"plant never listened: {tail(finish(pl, 10)[2])}"
    rc, o, e = cli("pmu control miniwecc 127.0.0.1:4713 --esd-pct 5 --estimator ekf".split(), 300)
    prc, po, pe = finish(pl, 120)
    txt = po + o
    ok = (
        rc == 0
        and prc == 0
        and "stable" in txt
        and re.search(r"mode commands\s+8\b", txt)
        and re.search(r"false actions\s+0\b", txt)
        and re.search(r"\b600 frames\b", txt)
    )
    return (
        bool(ok),
        f"control rc {rc}, plant rc {prc}; plant said: {tail(po, 400)} | control: {tail(o, 200)} {tail(e + pe, 150) if not ok else ''}",
    )


@probe("AF21")
def _():
    """--help examples of import-psse and import-andes, on ANDES's shipped case files (the
    `andes` extra): `import-psse kundur.raw kundur_full.dyr --skip-unsupported -o kundur_psse.json`
    then `simulate kundur_psse.json --fault 7 --far-bus 8 --tf 5`; `import-andes
    ieee39_full.xlsx -o ieee39.json --skip-unsupported` then `simulate ieee39.json --fault 16
    --no-q-limits --tf 5`."""
    if ANDES_CASES is None:
        return True, "skipped: andes not installed"
    for f in ("kundur/kundur.raw", "kundur/kundur_full.dyr", "ieee39/ieee39_full.xlsx"):
        shutil.copy(ANDES_CASES / f, WD)
    bad = []
    for line in (
        "import-psse kundur.raw kundur_full.dyr --skip-unsupported -o kundur_psse.json",
        "simulate kundur_psse.json --fault 7 --far-bus 8 --tf 5",
        "import-andes ieee39_full.xlsx -o ieee39.json --skip-unsupported",
        "simulate ieee39.json --fault 16 --no-q-limits --tf 5",
    ):
        rc, o, e = cli(line.split(), 400)
        if rc != 0:
            bad.append(f"`{line}`: rc {rc}: {tail(e, 200)}")
    return not bad, "; ".join(bad) or "four commands exit 0"


# ---------------------------------------------------------------- more quoted figures and statements


@probe("AF22")
def _():
    """docs/placement.md section 8: ANDES's ieee39_full imported with `import-andes`, the fault at
    bus 26 with line 26-29 tripped: CCT 0.497 s without storage, 0.469 s with 5 %, 0.436 s with
    20 % (`stabctl cct ieee39_full.json --fault 26 --far-bus 29 --esd-pct 20`), --coi rest 0.442 s;
    machine 9 (bus 38) separates in every case."""
    if ANDES_CASES is None:
        return True, "skipped: andes not installed"
    shutil.copy(ANDES_CASES / "ieee39/ieee39_full.xlsx", WD)
    rc, o, e = cli("import-andes ieee39_full.xlsx -o ieee39_full.json".split(), 300)
    if rc != 0:
        return (
            False,
            f"`import-andes ieee39_full.xlsx -o ieee39_full.json` (as is) rc {rc}: {tail(e, 300)}",
        )
    got, bad = {}, []
    for extra, want in (
        ([], "0.497"),
        (["--esd-pct", "5"], "0.469"),
        (["--esd-pct", "20"], "0.436"),
        (["--esd-pct", "20", "--coi", "rest"], "0.442"),
    ):
        rc, o, e = cli(["cct", "ieee39_full.json", "--fault", "26", "--far-bus", "29", *extra], 400)
        m = re.search(r"CCT (\S+) s", o)
        got[" ".join(extra) or "none"] = m and m.group(1)
        if rc != 0 or not m or m.group(1) != want:
            bad.append(
                f"{' '.join(extra) or 'no storage'}: {m and m.group(1)} (doc {want}, rc {rc}) {tail(e) if rc else ''}"
            )
        if "G9 (bus 38)" not in o:
            bad.append(f"{' '.join(extra) or 'no storage'}: G9 (bus 38) not named: {tail(o, 200)}")
    return not bad, "; ".join(bad) or f"as quoted: {got}"


@probe("AF23")
def _():
    """docs/placement.md: miniWECC 83-33 with the uniform 5 % fleet: "`stabctl cct miniwecc
    --fault 83 --far-bus 33 --esd-pct 5` reports 0.110 s" (it said 146 ms, of an earlier
    version of the models, until round 48)."""
    rc, o, e = cli("cct miniwecc --fault 83 --far-bus 33 --esd-pct 5".split(), 400)
    m = re.search(r"CCT (\S+) s", o)
    return rc == 0 and m and m.group(
        1
    ) == "0.110", f"rc {rc}: CCT {m and m.group(1)} (doc 0.110) {tail(e) if rc else ''}"


@probe("AF24")
def _():
    """docs/modal.md / cli.md: `eig --report` writes DIR/eig_<CASE>[_nopss][_areasN].md (its header
    the command that made it) and `--json` gives real_per_s, imag_rad_per_s, freq_hz (= imag/2pi),
    damping_ratio (= -real/|lambda|)."""
    import json
    import math

    bad = []
    rc, o, e = cli("eig kundur --no-pss --areas 3 --report --out-dir rep".split())
    f = Path(WD, "rep", "eig_kundur_nopss_areas3.md")
    if rc != 0 or not f.exists():
        bad.append(
            f"report rc {rc}: wrote {sorted(os.listdir(Path(WD, 'rep'))) if Path(WD, 'rep').exists() else 'nothing'}"
        )
    elif "eig kundur --no-pss --areas 3 --report --out-dir rep" not in f.read_text()[:2000]:
        bad.append(f"report header lacks the command: {f.read_text()[:200]!r}")
    rc, o, e = cli("eig kundur --json".split())
    try:
        j = json.loads(o)
        modes = j["modes"] if isinstance(j, dict) else j
        for m in modes:
            re_, im = m["real_per_s"], m["imag_rad_per_s"]
            if abs(m["freq_hz"] - abs(im) / (2 * math.pi)) > 1e-6 * max(1, m["freq_hz"]):
                bad.append(f"freq_hz {m['freq_hz']} != |imag|/2pi {abs(im) / 2 / math.pi}")
                break
            if abs(m["damping_ratio"] - (-re_ / math.hypot(re_, im))) > 1e-6:
                bad.append(f"damping_ratio {m['damping_ratio']} != -re/|lambda|")
                break
    except Exception as ex:
        bad.append(f"--json: {type(ex).__name__} {ex}: {o[:200]}")
    return not bad, "; ".join(
        bad
    ) or "report named as said, header the command; JSON units consistent"


@probe("AF25")
def _():
    """docs/cli.md: `simulate --out FILE.csv` has units in the column names (`angle_rad.G<k>`,
    `speed_pu.G<k>`, `pelect_pu.G<k>`, `pmech_pu_mbase.G<k>`); `--out FILE.npz` has a `units` array
    giving each array's unit."""
    import numpy as np

    bad = []
    rc, o, e = cli("simulate kundur --fault 3 --far-bus 101 --tf 2 --out r.csv".split())
    hdr = Path(WD, "r.csv").read_text().splitlines()[0] if Path(WD, "r.csv").exists() else ""
    for col in ("angle_rad.G1", "speed_pu.G1", "pelect_pu.G1", "qelect_pu.G1", "pmech_pu_mbase.G1"):
        if col not in hdr.split(","):
            bad.append(f"CSV lacks {col}")
    rc, o, e = cli("simulate kundur --fault 3 --far-bus 101 --tf 2 --out r.npz".split())
    try:
        z = np.load(Path(WD, "r.npz"), allow_pickle=False)
        if "units" not in z.files:
            bad.append(f"npz has no units array: {z.files}")
    except Exception as ex:
        bad.append(f"npz: {type(ex).__name__} {ex} (rc {rc} {tail(e)})")
    return not bad, "; ".join(
        bad
    ) or f"CSV columns and npz units as said ({len(hdr.split(','))} columns)"


@probe("AF26")
def _():
    """docs/setup.md: `compile --check` says whether the cache is warm (exit status 1 if not),
    without compiling or making anything; an unknown case is one error: line, exit status 2."""
    bad = []
    rc, o, e = cli(["compile", "--check"])
    if rc != 0:
        bad.append(f"warm cache: rc {rc} {tail(o + e)}")
    cold = Path(WD, "coldcache")
    env_save = ENV.get("NUMBA_CACHE_DIR")
    ENV["NUMBA_CACHE_DIR"] = str(cold)
    try:
        rc, o, e = cli(["compile", "--check"])
        made = cold.exists() and any(cold.rglob("*"))
        if rc != 1 or made:
            bad.append(f"cold cache: rc {rc} (doc 1), made files {made}: {tail(o + e)}")
    finally:
        if env_save is None:
            ENV.pop("NUMBA_CACHE_DIR")
        else:
            ENV["NUMBA_CACHE_DIR"] = env_save
    rc, o, e = cli(["compile", "--check", "nosuchcase"])
    if rc != 2 or len([ln for ln in e.splitlines() if ln.startswith("error:")]) != 1:
        bad.append(f"unknown case: rc {rc}: {tail(e)}")
    return not bad, "; ".join(bad) or "warm 0, cold 1 (nothing made), unknown case 2"


@probe("AF27")
def _():
    """docs/cli.md: `omib` refuses a duration of 0 cycles and (at 60 Hz) 180 cycles or more, naming
    --fault-cycles; the table's rows are shortest first however given."""
    bad = []
    for v in ("0", "180"):
        rc, o, e = cli(["omib", "--fault-cycles", "6", v])
        if rc != 2 or "--fault-cycles" not in e:
            bad.append(f"--fault-cycles 6 {v}: rc {rc} {tail(e)}")
    rc, o, e = cli(["omib", "--fault-cycles", "15", "6", "12", "--json"])
    import json

    try:
        j = json.loads(o)
        rows = j.get("rows") or j.get("cases") or next(v for v in j.values() if isinstance(v, list))
        cyc = [r.get("fault_cycles", r.get("cycles")) for r in rows]
        if cyc != sorted(cyc):
            bad.append(f"rows not shortest first: {cyc}")
    except Exception as ex:
        bad.append(f"--json: {type(ex).__name__} {ex}: {o[:200]}")
    return not bad, "; ".join(bad) or "0 and 180 refused naming --fault-cycles; rows sorted"


@probe("AF28")
def _():
    """docs/cli.md (paper): "reports and records hold no timings (two runs on one machine give
    identical files)" -- `paper --only analytic` twice into two directories: the same bytes
    (run_log.json, which holds the seconds, excepted)."""
    import filecmp

    for d in ("p1", "p2"):
        rc, o, e = cli(["paper", "--out-dir", d, "--only", "analytic"], 400)
        if rc != 0:
            return False, f"paper --out-dir {d} --only analytic rc {rc}: {tail(e)}"
    files = sorted(
        str(p.relative_to(Path(WD, "p1"))) for p in Path(WD, "p1").rglob("*") if p.is_file()
    )
    diff = [
        f
        for f in files
        if f != "run_log.json"
        and (
            not Path(WD, "p2", f).exists()
            or not filecmp.cmp(Path(WD, "p1", f), Path(WD, "p2", f), shallow=False)
        )
    ]
    return (
        not diff,
        f"{len(files)} files; differ: {diff}"
        if diff
        else f"{len(files)} files, identical (run_log.json excepted)",
    )


@probe("AF29")
def _():
    """docs/placement.md section 9, the ```bash block for IEEE 39 (with --workers 1, one core):
    import-andes, `screen ieee39_full.json --lines --out ieee39_screen.jsonl`, then `place ...
    --faults examples/placement/ieee39_faults.csv --target-cct-gain 20 --set-aside-infeasible
    --screening ieee39_screen.jsonl`: exit 0, "NOTHING TO PLACE"; with --target-cct-gain 5:
    verified, 348.4 MW, 0.15 MWh (sites 22 / 6 and 39 / 10)."""
    if ANDES_CASES is None:
        return True, "skipped: andes not installed"
    if not Path(WD, "ieee39_full.json").exists():
        shutil.copy(ANDES_CASES / "ieee39/ieee39_full.xlsx", WD)
        rc, o, e = cli("import-andes ieee39_full.xlsx -o ieee39_full.json".split(), 300)
        if rc != 0:
            return False, f"import rc {rc}: {tail(e)}"
    bad = []
    rc, o, e = cli(
        "screen ieee39_full.json --lines --out ieee39_screen.jsonl --workers 1".split(), 900
    )
    if rc != 0 or not Path(WD, "ieee39_screen.jsonl").exists():
        return False, f"screen rc {rc}: {tail(e)}"
    faults = Path(CLONE, "examples/placement/ieee39_faults.csv")
    base = [
        "place",
        "ieee39_full.json",
        "--faults",
        str(faults),
        "--set-aside-infeasible",
        "--screening",
        "ieee39_screen.jsonl",
        "--workers",
        "1",
    ]
    rc, o, e = cli([*base, "--target-cct-gain", "20"], 900)
    if rc != 0 or "NOTHING TO PLACE" not in o:
        bad.append(f"+20 %: rc {rc}: {tail(o, 300)} {tail(e)}")
    rc, o, e = cli([*base, "--target-cct-gain", "5"], 900)
    if rc != 0 or "348.4 MW" not in o:
        m = re.findall(r"[\d.]+ MW[^\n]{0,60}", o)
        bad.append(
            f"+5 %: rc {rc}: doc 'verified, 348.4 MW, 0.15 MWh'; printed {m[:3]} {tail(e) if rc else ''}"
        )
    return not bad, "; ".join(bad) or "+20 %: NOTHING TO PLACE, exit 0; +5 %: 348.4 MW as quoted"


@probe("AF30")
def _():
    """docs/examples.md: the seven scripts each run as they are (`python examples/NAME.py`, in a
    temp dir), exit 0; case2_with_storage.py writes case2.png as it says."""
    bad, times = [], []
    d = Path(WD, "ex")
    d.mkdir(exist_ok=True)
    for f in sorted(Path(CLONE, "examples").glob("*.py")):
        t0 = time.time()
        try:
            p = subprocess.run(
                [sys.executable, str(f)],
                capture_output=True,
                text=True,
                timeout=400,
                cwd=d,
                env=ENV,
            )
            rc, o, e = p.returncode, p.stdout, p.stderr
        except subprocess.TimeoutExpired:
            rc, o, e = "timeout", "", ""
        times.append(f"{f.name} {time.time() - t0:.0f} s")
        if rc != 0:
            bad.append(f"{f.name}: rc {rc}: {tail(e, 200)}")
        if "wrote case2.png" in o and not Path(d, "case2.png").exists():
            bad.append("case2_with_storage.py says 'wrote case2.png', none written")
    return not bad and len(times) == 7, "; ".join(
        bad
    ) or f"{len(times)} scripts exit 0 ({', '.join(times)})"


def main():
    KIT.main(banner="work dir {wd}; clone {clone}", kept=None)


if __name__ == "__main__":
    main()
