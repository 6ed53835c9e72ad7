#!/usr/bin/env python
"""Twenty-fourth reliability round (round 42, part S): silently wrong results (variants of
issue 54 items 6-9) from DYR and RAW data and options: negative governor time constants
(TGOV1, DEGOV, DEGOV1, IEESGO), a GENROU whose Xl lies between X''d and X'd, a RAW's area
interchange record and a generator dispatched above its PT, a machine out of service with
its DYR record; storage that can never act (`cct --v-gate 1.5`, `--deadband-hz 5`);
`cct` against `simulate` and `screen`; the same run by two routes; event timing; impossible
ESD1 values of ANDES's ieee14_esd1.  A probe of bad data is ok when the data is refused
(rc 2, `error:`) or named; accepted silently, the probe says whether the run differs from
the run with the value that has no effect.

    python benchmarks/reliability_probes_24.py [ID ...]

The package under test is this repository's (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's; XDG_CACHE_HOME a temporary directory.  Prints per probe:
id, ok/SHORT, one-line reason; exits 1 if any is SHORT.  About 3 minutes with a warm
kernel cache.  The round found short: negative governor leads and lags (TGOV1 T2, DEGOV
T4, DEGOV1 T3 and T4) run as given and IEESGO's T4 = -0.3 run as T4 = 0, a GENROU with
X''d < Xl < X'd, a RAW's area interchange record and a generator above its PT read without
a word, a CCT with storage whose devices never switched printed as the CCT with storage;
all fixed (refused, or kept and named; `cct` notes that no storage device switched).
"""

# ruff: noqa: E501, BLE001, F841, SIM115, RUF015, RUF059 - a tester's script, kept as written

import csv
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

CLONE = os.environ.get(
    "CLONE", os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
)  # the package under test
WORK = tempfile.mkdtemp(prefix="probes_s.")
ENV = dict(os.environ, PYTHONPATH=CLONE, XDG_CACHE_HOME=os.path.join(WORK, "xdg"))
RAW = open(os.path.join(CLONE, "tests/data/psse_runs/GENROU/ThreeBusMulti.raw")).read()
GR = "8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8"
DYR = f"    101 'GENCLS' 1 0.0 0.0 /\n    102 'GENROU' 1 {GR} /\n"
RESULTS = []
PROBES = []


def run(args, timeout=300):
    try:
        p = subprocess.run(
            ["stabctl", *map(str, args)],
            cwd=WORK,
            env=ENV,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        return -9, "", "TIMEOUT"


def sj(args, timeout=300):
    rc, o, e = run([*args, "--json"], timeout)
    try:
        return rc, json.loads(o), e
    except Exception:
        return rc, None, e + o


def last(t, n=180):
    ls = [l for l in t.strip().splitlines() if l.strip()]
    return ls[-1][:n] if ls else ""


def w(name, text):
    p = os.path.join(WORK, name)
    with open(p, "w") as f:
        f.write(text)
    return p


def probe(pid):
    def deco(fn):
        PROBES.append((pid, fn))
        return fn

    return deco


def tb(t):
    return "Traceback" in t


# ---------------------------------------------------------------- helpers
def read_csv(path):
    with open(path) as f:
        r = csv.reader(f)
        head = next(r)
        rows = [[float(x) for x in row] for row in r]
    return head, rows


def col(head, rows, name):
    i = head.index(name)
    return [r[i] for r in rows]


def imp(raw_text, dyr_text, name, extra=()):
    r = w(name + ".raw", raw_text)
    d = w(name + ".dyr", dyr_text) if dyr_text is not None else None
    out = os.path.join(WORK, name + ".json")
    args = ["import-psse", r] + ([d] if d else []) + ["-o", out, *extra]
    rc, o, e = run(args)
    return rc, o + e, out


# ================================================================ A: DYR sign checks
def dyr_effect(
    pid_dir, raw, ok_text, bad_text, pat_named, fault=("--bus-fault", "103", "1", "1.1")
):
    """import ok and bad; bad must be refused or named (pat); if accepted silently, say
    whether the run differs from the ok data's."""
    rc, out, js = imp(raw, bad_text, pid_dir + "_bad")
    if rc == 2 and "error:" in out and not tb(out):
        return True, "refused: " + last(out, 120)
    if tb(out):
        return False, "traceback: " + last(out)
    if re.search(pat_named, out):
        return True, "named: " + [l for l in out.splitlines() if re.search(pat_named, l)][0][:120]
    rc2, out2, js2 = imp(raw, ok_text, pid_dir + "_ok")
    a = os.path.join(WORK, pid_dir + "_bad.csv")
    b = os.path.join(WORK, pid_dir + "_ok.csv")
    ra, oa, ea = run(["simulate", js, *fault, "--out", a])
    rb, ob, eb = run(["simulate", js2, *fault, "--out", b])
    if ra != 0:
        if ra == 2 and "error:" in ea:
            return True, "import silent, simulate refuses: " + last(ea, 120)
        return False, f"import silent, simulate rc={ra}: {last(ea)}"
    same = open(a).read() == open(b).read()
    return False, (
        "accepted without a word; the run "
        + ("is identical to" if same else "differs from")
        + " the run with the sign flipped back; simulate: "
        + last(oa, 80)
    )


PSR = os.path.join(CLONE, "tests/data/psse_runs")


def _rd(p):
    return open(os.path.join(PSR, p)).read()


NEG_LEADS = [
    # (id, dir/raw, dir/dyr, old, new, param name)
    (
        "S-D01",
        "TGOV1/ThreeBusMulti.raw",
        "TGOV1/ThreeBus_TGOV1.dyr",
        "0.1  0.3  0.8",
        "0.1  -0.3  0.8",
        "T2",
    ),
    (
        "S-D02",
        "DEGOV/ThreeBusMulti.raw",
        "DEGOV/ThreeBus_DEGOV.dyr",
        "         12.000",
        "        -12.000",
        "T4",
    ),
    (
        "S-D03",
        "DEGOV1/ThreeBusMulti.raw",
        "DEGOV1/ThreeBus_DEGOV1_nodelay_flag0.dyr",
        "0.47600E-01  0.18000E-01",
        "0.47600E-01  -0.18000E-01",
        "T3",
    ),
    (
        "S-D04",
        "DEGOV1/ThreeBusMulti.raw",
        "DEGOV1/ThreeBus_DEGOV1_nodelay_flag0.dyr",
        "1.0000       5.1000",
        "1.0000       -5.1000",
        "T4",
    ),
]
for _pid, _raw, _dyr, _old, _new, _nm in NEG_LEADS:

    def _p(pid=_pid, raw=_raw, dyr=_dyr, old=_old, new=_new, nm=_nm):
        """A negative lead time constant of a governor (other models' leads, EXST1 TC,
        ESST1A TC, PSS2A T1/T3, STAB1, are refused): refused or named?"""
        ok = _rd(dyr)
        assert old in ok, (pid, old)
        bad = ok.replace(old, new, 1)
        return dyr_effect(pid, _rd(raw), ok, bad, rf"\b{nm}\b.*-|{new.split()[-1]}")

    probe(_pid)(_p)


@probe("S-D05")
def _():
    """IEESGO T4 (the steam-chest lag) = -0.3 s: refused or named; not run as T4 = 0."""
    rec = "    102 'IEESGO' 1 0.1 0 0.2 {} 5.0 0.5 20 0.5 0.5 1.2 0 /\n"
    rc, out, js = imp(RAW, DYR + rec.format("-0.3"), "sgo_neg")
    if rc == 2 and "error:" in out:
        return True, "refused: " + last(out, 120)
    if re.search(r"T4", out):
        return True, "named"
    rc0, out0, js0 = imp(RAW, DYR + rec.format("0"), "sgo_zero")
    a, b = os.path.join(WORK, "sgo_neg.csv"), os.path.join(WORK, "sgo_zero.csv")
    ra = run(["simulate", js, "--bus-fault", "103", "1", "1.1", "--out", a])
    rb = run(["simulate", js0, "--bus-fault", "103", "1", "1.1", "--out", b])
    if ra[0]:
        return ra[0] == 2, "simulate: " + last(ra[2])
    same = csv_same(a, b)
    return False, (
        "T4 = -0.3 accepted without a word; its run is "
        + ("byte-identical to T4 = 0 (lag silently bypassed)" if same else "different from T4 = 0")
    )


@probe("S-D06")
def _():
    """GENROU with X''d (0.25) < Xl (0.28) < X'd (0.3): PSS/E requires Xl < X''d (the flux
    split (X''d - Xl)/(X'd - Xl) turns negative). stabctl accepts it by design (case/system.py,
    ANDES's ieee39_full has such units); is the user told?"""
    d = "    101 'GENCLS' 1 0.0 0.0 /\n    102 'GENROU' 1 8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.28 0.1 0.8 /\n"
    rc, out, js = imp(RAW, d, "leak_case")
    if rc == 2 or re.search(r"(?i)\bxl\b|leakage", out):
        return True, "named/refused: " + last(out, 120)
    return (
        False,
        "import-psse rc=0, Xl = 0.28 > X''d = 0.25 not named (by design in case/system.py, no warning)",
    )


@probe("S-E04")
def _():
    """Events at one instant: the order of the options does not change the run."""
    a, b = os.path.join(WORK, "ord1.csv"), os.path.join(WORK, "ord2.csv")
    r1 = run(
        [
            "simulate",
            "kundur",
            "--trip-gen",
            "2",
            "1",
            "--load-step",
            "4",
            "1",
            "-3",
            "0",
            "--trip",
            "3",
            "101",
            "--t-trip",
            "1",
            "--out",
            a,
        ]
    )
    r2 = run(
        [
            "simulate",
            "kundur",
            "--trip",
            "3",
            "101",
            "--t-trip",
            "1",
            "--load-step",
            "4",
            "1",
            "-3",
            "0",
            "--trip-gen",
            "2",
            "1",
            "--out",
            b,
        ]
    )
    if r1[0] or r2[0]:
        return False, last(r1[2] + r2[2])
    return csv_same(a, b), "identical" if csv_same(a, b) else "differ with the order of the options"


# ================================================================ B: RAW records
@probe("S-R01")
def _():
    """An area interchange record (desired net interchange 80 MW) is not modelled by a
    dynamic import: named, or refused?"""
    bad = RAW.replace(
        " 0 /End of Area interchange data",
        "   1,   101,   80.000,    10.000,'AREA1'\n 0 /End of Area interchange data",
    )
    rc, out, js = imp(bad, DYR, "ai")
    if rc == 2 or re.search(r"(?i)\barea\b|interchange", out):
        return True, "named/refused: " + last(out, 120)
    return (
        False,
        "import-psse rc=0, the area interchange record (80 MW desired) is not named: "
        + last(out, 110),
    )


@probe("S-R02")
def _():
    """A generator dispatched above its PT (PG 153 MW, PT 50 MW): named?"""
    bad = RAW.replace(
        " 100.0,   318.000,     0.000,   1,1.0000\n 0 /End of Gen",
        " 100.0,   50.000,     0.000,   1,1.0000\n 0 /End of Gen",
    )
    assert bad != RAW
    rc, out, js = imp(bad, DYR, "pgmax")
    if rc == 2 or re.search(r"(?i)PT\b|pmax|above its", out):
        return True, "named/refused: " + last(out, 120)
    return False, "import-psse rc=0, PG 153.3 MW above PT 50 MW not named: " + last(out, 100)


@probe("S-R03")
def _():
    """A machine out of service (STAT 0) whose DYR record is present: both named."""
    g = "1.00000,1,  100.0,   318.000,     0.000,   1,1.0000\n 0 /End of Gen"
    bad = RAW.replace(g, "1.00000,0,  100.0,   318.000,     0.000,   1,1.0000\n 0 /End of Gen")
    assert bad != RAW
    rc, out, js = imp(bad, DYR, "oos")
    ok = rc == 0 and "STAT 0" in out and "GENROU (bus 102" in out
    return ok, last(out, 150)


# ================================================================ C: options with effect
def cct_of(args):
    rc, d, e = sj(["cct", "kundur", *args])
    return rc, d, e


@probe("S-O01")
def _():
    """cct with storage whose voltage gate (1.5 pu) is above every bus voltage: no device can
    act; the CCT 'with 5 % storage' equals the one without: does cct say no device acted
    (simulate does: '0 of 4 devices acted')?"""
    rc0, d0, _ = cct_of(["--fault", "3", "--far-bus", "101"])
    rc, o, e = run(
        ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5", "--v-gate", "1.5"]
    )
    rc1, d1, e1 = cct_of(["--fault", "3", "--far-bus", "101", "--esd-pct", "5", "--v-gate", "1.5"])
    if d0 is None or d1 is None:
        return False, f"rc {rc0}/{rc1}: {last(e1)}"
    # fixed (round 42): cct notes "no storage device switched in any of the search's runs
    # (their deadband or voltage gate kept them idle): this CCT is the one without storage"
    said = re.search(
        r"(?i)no device|no storage device switched|never|0 of \d+ devices|did not act|idle|gate",
        o + e + json.dumps(d1.get("warnings", "")),
    )
    if d1["cct_s"] == d0["cct_s"] and not said:
        return False, (
            f"CCT with storage {d1['cct_s']} s = without {d0['cct_s']} s; text says "
            f"'storage 5 % of machine MVA' and not that no device ever acted (v-gate 1.5 pu)"
        )
    return True, f"{d1['cct_s']} vs {d0['cct_s']}; said={bool(said)}"


@probe("S-O02")
def _():
    """As S-O01 with --deadband-hz 5 (accepted: [0, 10] Hz): relative speeds never reach it."""
    rc0, d0, _ = cct_of(["--fault", "3", "--far-bus", "101"])
    rc, o, e = run(
        [
            "cct",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--esd-pct",
            "5",
            "--deadband-hz",
            "5",
        ]
    )
    rc1, d1, e1 = cct_of(
        ["--fault", "3", "--far-bus", "101", "--esd-pct", "5", "--deadband-hz", "5"]
    )
    if d0 is None or d1 is None:
        return False, f"rc {rc0}/{rc1}: {last(e1)}"
    said = re.search(
        r"(?i)no device|no storage device switched|never|0 of \d+ devices|did not act|idle", o + e
    )
    if d1["cct_s"] == d0["cct_s"] and not said:
        return False, (
            f"CCT with storage {d1['cct_s']} s = without {d0['cct_s']} s, no word that no "
            "device acted (deadband 5 Hz)"
        )
    return True, f"{d1['cct_s']} vs {d0['cct_s']}"


@probe("S-O03")
def _():
    """cct's bracket agrees with simulate at CCT-2 ms (stable) and CCT+2 ms (separated),
    line fault 3-101 and bus fault 3."""
    msgs = []
    for extra in (["--far-bus", "101"], []):
        rc, d, e = cct_of(["--fault", "3", *extra])
        if d is None:
            return False, last(e)
        c = d["cct_s"]
        for dt, want in ((-0.002, True), (0.002, False)):
            cyc = (c + dt) * 60
            rc2, s, e2 = sj(
                ["simulate", "kundur", "--fault", "3", *extra, "--clear-cycles", f"{cyc:.6f}"]
            )
            if s is None or s["stable"] != want:
                return (
                    False,
                    f"{extra} CCT {c}: simulate at {c + dt:.3f} s stable={None if s is None else s['stable']}",
                )
        msgs.append(f"{c}")
    return True, "brackets hold: " + ", ".join(msgs)


@probe("S-O04")
def _():
    """screen --json's CCTs equal cct's (same tol and t_max) for line 3-101 and bus 3, 4."""
    out = os.path.join(WORK, "scr.jsonl")
    rc, o, e = run(
        ["screen", "kundur", "--buses", "3,4", "--lines", "--workers", "1", "--out", out, "--json"]
    )
    try:
        rows = json.loads(o)
    except Exception:
        return False, f"rc={rc} {last(e)}"
    bad = []
    for r in rows:
        if (r["bus"], r.get("far_bus")) not in ((3, 101), (3, None), (4, None)) or r.get(
            "circuit"
        ) == 2:
            continue
        args = ["--fault", str(r["bus"]), "--t-max", "0.5"] + (
            ["--far-bus", str(r["far_bus"])] if r.get("far_bus") else []
        )
        rc2, d, e2 = cct_of(args)
        if d is None or d["cct_s"] != r["cct_s"]:
            bad.append(
                f"{r['bus']}-{r.get('far_bus')}: screen {r['cct_s']} cct {None if d is None else d['cct_s']}"
            )
    return not bad, "; ".join(bad) or "screen = cct"


# ================================================================ D: same result two routes
def csv_same(a, b):
    return open(a).read() == open(b).read()


@probe("S-E01")
def _():
    """Two load steps at one bus and instant = one step of their sum (CSV identical)."""
    a, b = os.path.join(WORK, "ls1.csv"), os.path.join(WORK, "ls2.csv")
    r1 = run(
        [
            "simulate",
            "kundur",
            "--load-step",
            "4",
            "1",
            "0.5",
            "0.1",
            "--load-step",
            "4",
            "1",
            "0.5",
            "0.1",
            "--out",
            a,
        ]
    )
    r2 = run(["simulate", "kundur", "--load-step", "4", "1", "1.0", "0.2", "--out", b])
    if r1[0] or r2[0]:
        return False, last(r1[2] + r2[2])
    return csv_same(a, b), "identical" if csv_same(a, b) else "differ"


@probe("S-E02")
def _():
    """--fault BUS without --far-bus = --bus-fault BUS T T+clear (CSV identical)."""
    a, b = os.path.join(WORK, "bf1.csv"), os.path.join(WORK, "bf2.csv")
    r1 = run(["simulate", "kundur", "--fault", "3", "--clear-cycles", "6", "--out", a])
    r2 = run(["simulate", "kundur", "--bus-fault", "3", "1", "1.1", "--out", b])
    if r1[0] or r2[0]:
        return False, last(r1[2] + r2[2])
    return csv_same(a, b), "identical" if csv_same(a, b) else "differ"


@probe("S-E03")
def _():
    """ESD energies in simulate --json equal the integral of pesd_pu columns (5 %)."""
    p = os.path.join(WORK, "esd.csv")
    rc, d, e = sj(
        [
            "simulate",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--clear-cycles",
            "9",
            "--esd-pct",
            "5",
            "--out",
            p,
        ]
    )
    if d is None:
        return False, last(e)
    h, rows = read_csv(p)
    t = col(h, rows, "t")
    worst = 0.0
    for s in d["storage"]:
        pw = [x * 100.0 for x in col(h, rows, f"pesd_pu.D{s['device']}")]
        ab = sum(max(pw[i], 0) * (t[i + 1] - t[i]) for i in range(len(t) - 1))
        de = sum(max(-pw[i], 0) * (t[i + 1] - t[i]) for i in range(len(t) - 1))
        step_mj = 45.0 * 0.005 * s["switchings"]  # one step per switching of slack
        worst = max(
            worst,
            abs(ab - s["energy_absorbed_mj"]) - step_mj,
            abs(de - s["energy_delivered_mj"]) - step_mj,
        )
    return worst <= 0.05, f"largest mismatch beyond one step per switching: {worst:.3f} MJ"


# ================================================================ E: event timing
@probe("S-T01")
def _():
    """A bus fault far shorter than the step (0.1 us): named as below the step, or run exactly
    (its effect no larger than a 0.1 us fault's)."""
    a, b = os.path.join(WORK, "tiny.csv"), os.path.join(WORK, "flat.csv")
    rc, o, e = run(["simulate", "kundur", "--bus-fault", "3", "1", "1.0000001", "--out", a])
    run(["simulate", "kundur", "--tf", "6", "--out", b])
    if rc:
        return rc == 2 and "error:" in e, last(e)
    h, ra = read_csv(a)
    _, rb = read_csv(b)
    i = h.index("speed_pu.G1")
    d = max(abs(x[i] - y[i]) for x, y in zip(ra, rb))
    return d < 1e-6, f"largest speed difference from the flat run {d:.2e} pu"


@probe("S-T02")
def _():
    """A fault never cleared starting 0.1 s before --tf: the run ends with the fault on;
    'stable' must be qualified (the end note) or refused."""
    rc, o, e = run(["simulate", "kundur", "--bus-fault", "3", "4.9", "inf", "--tf", "5"])
    ok = rc == 2 or re.search(r"(?i)no normal operating point|fault .*still|never cleared", o + e)
    return bool(ok), last(o + e, 150)


@probe("S-T03")
def _():
    """--t-fault 0: the fault at the very start (no rest before it) is run and reported at 0 s."""
    rc, d, e = sj(["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--t-fault", "0"])
    if d is None:
        return rc == 2, last(e)
    return "at 0 s" in d["events"][0], d["events"][0][:120]


@probe("S-T04")
def _():
    """--trip and --close of one line at the same instant: refused (ambiguous)."""
    rc, o, e = run(
        ["simulate", "kundur", "--trip", "3", "101", "--t-trip", "1", "--close", "3", "101", "1"]
    )
    return rc == 2 and "error:" in e and not tb(e), last(e, 150)


@probe("S-T05")
def _():
    """trapezoid at 0.05 s (3 cycles): warned that the step is coarse."""
    rc, d, e = sj(
        [
            "simulate",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--clear-cycles",
            "9",
            "--method",
            "trapezoid",
            "--step",
            "0.05",
        ]
    )
    if d is None:
        return rc == 2, last(e)
    return bool(d["warnings"]) or "step" in e, (d["warnings"] or [e])[0][:140]


# ================================================================ F: ANDES converter data
ANDES_LOAD = None


def andes_json(name, edits):
    """ieee14_esd1.xlsx as an ANDES JSON with edits [(model, row, field, value)]."""
    global ANDES_LOAD
    import math

    if ANDES_LOAD is None:
        import andes
        import pandas as pd

        sheets = pd.read_excel(andes.get_case("ieee14/ieee14_esd1.xlsx"), sheet_name=None)
        ANDES_LOAD = {
            k: [
                {c: v for c, v in r.items() if not (isinstance(v, float) and math.isnan(v))}
                for r in df.dropna(axis=0, how="all").to_dict("records")
            ]
            for k, df in sheets.items()
        }
    d = json.loads(json.dumps(ANDES_LOAD, default=str))
    for m, row, f, v in edits:
        d[m][row][f] = v
    p = os.path.join(WORK, name + ".json")
    with open(p, "w") as fh:
        json.dump(d, fh)
    return p


ESD_EDITS = [
    ("S-A01", [("ESD1", 0, "SOCinit", 1.5)], r"SOCinit"),
    ("S-A02", [("ESD1", 0, "SOCinit", -0.2)], r"SOCinit"),
    ("S-A03", [("ESD1", 0, "SOCmin", 0.2), ("ESD1", 0, "SOCinit", 0.1)], r"SOCinit|SOCmin"),
    ("S-A04", [("ESD1", 0, "gammap", 2.0)], r"gammap"),
    ("S-A05", [("ESD1", 0, "gammap", -0.5)], r"gammap"),
    ("S-A06", [("ESD1", 0, "qmx", -0.5)], r"qmx|qmn"),
    ("S-A07", [("ESD1", 0, "v0", 1.2)], r"\bv0\b|\bv1\b"),
    ("S-A08", [("ESD1", 0, "vrflag", 1), ("ESD1", 0, "vt0", 0.95)], r"vt0|vt1"),
    ("S-A09", [("ESD1", 0, "frflag", 1), ("ESD1", 0, "ft0", 59.8)], r"ft0|ft1"),
    ("S-A10", [("ESD1", 0, "ddn", -5)], r"ddn"),
    ("S-A11", [("ESD1", 0, "tip", -0.02)], r"tip"),
    ("S-A12", [("ESD1", 0, "xc", -0.01)], r"xc"),
    ("S-A13", [("ESD1", 0, "Tf", -1)], r"Tf"),
    ("S-A14", [("ESD1", 0, "fn", 50)], r"fn"),
    ("S-A15", [("ESD1", 0, "pqflag", 2)], r"pqflag"),
    ("S-A16", [("ESD1", 0, "EtaC", 1.5)], r"EtaC"),
    ("S-A17", [("ESD1", 0, "EtaD", 0)], r"EtaD"),
    ("S-A18", [("ESD1", 0, "gammaq", 1.5)], r"gammaq"),
]
for _pid, _edits, _pat in ESD_EDITS:

    def _p(pid=_pid, edits=_edits, pat=_pat):
        """An impossible ESD1 value (ieee14_esd1): refused or named by import-andes."""
        src = andes_json(pid, edits)
        out = os.path.join(WORK, pid + ".case.json")
        rc, o, e = run(["import-andes", src, "-o", out])
        t = o + e
        if tb(t):
            return False, "traceback: " + last(t)
        if rc == 2 and "error:" in e:
            return True, "refused: " + last(e, 120)
        named = [l for l in t.splitlines() if re.search(pat, l)]
        if named:
            return True, "named: " + named[0][:120]
        # silent: does the value change a run?
        ok = andes_json(pid + "_ok", [])
        okc = os.path.join(WORK, "esd_ok.case.json")
        if not os.path.exists(okc):
            run(["import-andes", ok, "-o", okc])
        a, b = os.path.join(WORK, pid + ".csv"), os.path.join(WORK, "esd_ok.csv")
        ra = run(
            [
                "simulate",
                out,
                "--no-q-limits",
                "--fault",
                "4",
                "--clear-cycles",
                "4",
                "--tf",
                "3",
                "--out",
                a,
            ]
        )
        if not os.path.exists(b):
            run(
                [
                    "simulate",
                    okc,
                    "--no-q-limits",
                    "--fault",
                    "4",
                    "--clear-cycles",
                    "4",
                    "--tf",
                    "3",
                    "--out",
                    b,
                ]
            )
        if ra[0]:
            if ra[0] == 2 and "error:" in ra[2]:
                return True, "import silent, simulate refuses: " + last(ra[2], 120)
            return False, f"simulate rc={ra[0]} {last(ra[2])}"
        same = os.path.exists(b) and csv_same(a, b)
        return False, (
            "import-andes rc=0 without a word; the run is "
            + ("identical to" if same else "different from")
            + " the original's"
        )

    probe(_pid)(_p)


def main():
    want = set(sys.argv[1:])
    short = 0
    n = 0
    for pid, fn in PROBES:
        if want and pid not in want:
            continue
        n += 1
        try:
            ok, why = fn()
        except Exception as exc:
            ok, why = False, f"probe error {type(exc).__name__}: {exc}"
        short += not ok
        print(f"{pid} {'ok' if ok else 'SHORT'} {why}", flush=True)
    print(f"{n} probes, {n - short} ok, {short} short")
    shutil.rmtree(WORK, ignore_errors=True)
    return 1 if short else 0


if __name__ == "__main__":
    sys.exit(main())
