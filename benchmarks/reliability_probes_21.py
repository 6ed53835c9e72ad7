#!/usr/bin/env python
"""Twenty-first reliability round (round 41, part P): impossible or inconsistent dynamic
and network data.  Each probe makes its input in a temporary directory, runs `stabctl
import-psse`, `import-andes` or `simulate`, and prints: id, ok/SHORT, one-line reason.  A
probe of bad data is ok when the data is refused (rc 2, `error:`) or named in the
output; when it is accepted silently, the probe runs the case with the value and with
the value that has no effect and says whether the two CSVs are byte-identical.

    python benchmarks/reliability_probes_21.py

The package under test is this repository's (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's; XDG_CACHE_HOME a temporary directory.  Exits 1 if any
is SHORT.  About 2 minutes with a warm kernel cache.  The round found short: governor
leads without their lags (IEEEG1, IEESGO), PST's stabiliser's second lead without its
lag, AC8B's VFEMAX and VEMIN (not modelled) read without a word, a stabiliser of gain 0,
ST2CUT's lead named in another table's words, a RAW bus's inverted voltage limits and a
branch of negative R read without a word; all fixed (refused, or kept and named).
"""

# ruff: noqa: E501, BLE001, SIM115, RUF015, RUF059 - a tester's script, kept as written

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

CLONE = os.environ.get(
    "CLONE", os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
)  # the package under test
WORK = tempfile.mkdtemp(prefix="probe_p.")
ENV = dict(os.environ, PYTHONPATH=CLONE, XDG_CACHE_HOME=os.path.join(WORK, "xdg"))
RAW = os.path.join(CLONE, "tests/data/psse_runs/GENROU/ThreeBusMulti.raw")
BASE_RAW = open(RAW).read()
KUNDUR = os.path.join(CLONE, "stabctl/case/data/kundur.json")
GR = "8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8"
HEAD = f"    101 'GENCLS' 1 0.0 0.0 /\n    102 'GENROU' 1 {GR} /\n"
SEXS = "    102 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n"
RESULTS = []


def run(args, timeout=300):
    p = subprocess.run(
        ["stabctl", *map(str, args)],
        cwd=WORK,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return p.returncode, p.stdout, p.stderr


def last(text, n=170):
    lines = [l for l in text.strip().splitlines() if l.strip()]
    return lines[-1][:n] if lines else ""


def probe(pid, fn):
    try:
        ok, why = fn()
    except subprocess.TimeoutExpired as e:
        ok, why = False, f"timeout: {e.cmd[-4:]}"
    except Exception as e:
        ok, why = False, f"probe error {type(e).__name__}: {e}"
    RESULTS.append((pid, ok, why))
    print(f"{pid:6s} {'ok' if ok else 'SHORT':5s} {why}", flush=True)


def judge(rc, o, e, named=None):
    """('refused'|'named'|'silent'|'traceback', text)"""
    if "Traceback" in e:
        return "traceback", last(e)
    if rc == 2 and "error:" in e:
        return "refused", last(e)
    if rc == 0 and named and re.search(named, o + e):
        return "named", re.search(r"[^\n]*(" + named + r")[^\n]*", o + e).group(0)[:170]
    return ("silent" if rc == 0 else f"rc {rc}"), last(o + e)


# ---------------------------------------------------------------- inputs --------------
def dyr_case(name, body, raw_text=None):
    if raw_text is not None:
        open(os.path.join(WORK, name + ".raw"), "w").write(raw_text)
    open(os.path.join(WORK, name + ".dyr"), "w").write(HEAD + body)
    raw = name + ".raw" if raw_text is not None else RAW
    return run(["import-psse", raw, name + ".dyr", "-o", name + ".json"])


ANDES_VAR = r"""
import andes, json, math, sys
import pandas as pd
def load(name):
    p = andes.get_case(name)
    if p.endswith(".json"):
        return json.load(open(p))
    sheets = pd.read_excel(p, sheet_name=None)
    return {k: [{c: v for c, v in r.items() if not (isinstance(v, float) and math.isnan(v))}
                for r in df.dropna(axis=0, how="all").to_dict("records")] for k, df in sheets.items()}
src, edits, out = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3]
d = load(src)
for model, row, field, value in edits:
    d[model][row][field] = value
json.dump(d, open(out, "w"), default=str)
"""


def andes_case(name, src, edits):
    path = os.path.join(WORK, "andes_var.py")
    if not os.path.exists(path):
        open(path, "w").write(ANDES_VAR)
    p = subprocess.run(
        [sys.executable, "andes_var.py", src, json.dumps(edits), name + ".json"],
        cwd=WORK,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=300,
    )
    if p.returncode:
        raise RuntimeError("ANDES variant not made: " + last(p.stderr))
    return run(["import-andes", name + ".json", "-o", "o_" + name + ".json"])


def case_file(name, edits, src=KUNDUR):
    d = json.load(open(src))
    for table, row, col, val in edits:
        t = d["tables"][table]
        t["rows"][row][t["columns"].index(col)] = val
    json.dump(d, open(os.path.join(WORK, name + ".json"), "w"))
    return name + ".json"


def sim(case, fault, far, extra=()):
    out = os.path.splitext(os.path.basename(case))[0] + ".csv"
    rc, o, e = run(
        [
            "simulate",
            case,
            "--fault",
            fault,
            "--far-bus",
            far,
            "--clear-cycles",
            "6",
            "--tf",
            "5",
            "--out",
            out,
            *extra,
        ],
        timeout=600,
    )
    return open(os.path.join(WORK, out), "rb").read() if rc == 0 else None


def no_effect(bad, neutral, fault, far, extra=()):
    """' (simulate: byte-identical to <neutral>, the value without effect)' or ''."""
    a, b = sim(bad, fault, far, extra), sim(neutral, fault, far, extra)
    if a is None or b is None:
        return "; simulate failed"
    return (
        "; simulate byte-identical to the case without the value: it has no effect"
        if a == b
        else "; simulate differs"
    )


# ---------------------------------------------------------------- probes --------------
def lead_dyr(pid, what, rec_bad, rec_neutral, named):
    def f():
        rc, o, e = dyr_case(pid + "b", SEXS + rec_bad)
        kind, text = judge(rc, o, e, named)
        if kind in ("refused", "named"):
            return True, f"{kind}: {text}"
        if kind != "silent":
            return False, f"{kind}: {text}"
        dyr_case(pid + "n", SEXS + rec_neutral)
        return False, f"{what} accepted without a word" + no_effect(
            pid + "b.json", pid + "n.json", "102", "103"
        )

    return f


def lead_andes(pid, what, src, bad, neutral, named, fault, far):
    def f():
        rc, o, e = andes_case(pid + "b", src, bad)
        kind, text = judge(rc, o, e, named)
        if kind in ("refused", "named"):
            return True, f"{kind}: {text}"
        if kind != "silent":
            return False, f"{kind}: {text}"
        andes_case(pid + "n", src, neutral)
        return False, f"{what} accepted without a word" + no_effect(
            "o_" + pid + "b.json", "o_" + pid + "n.json", fault, far, ("--no-q-limits",)
        )

    return f


def refused(args_fn, pat):
    def f():
        rc, o, e = args_fn()
        kind, text = judge(rc, o, e)
        if kind == "refused" and re.search(pat, e):
            return True, "refused: " + text
        return False, f"{kind} (expected a refusal matching {pat!r}): {text}"

    return f


def main():
    t0 = time.time()
    IG1 = "    102 'IEEEG1' 1 0 0 20 {T1} {T2} 0.2 0.1 -0.1 1.2 0 0.3 0.3 0 7 0.4 0 0.6 0.3 0 0 0 0 /\n"
    IES = "    102 'IEESGO' 1 0.1 {T2} {T3} 0.3 5 0.5 20 0.3 0.5 1.2 0 /\n"
    # -- governors: a lead without its lag (round 40's class, not yet covered) ------------
    probe(
        "P01",
        lead_dyr(
            "P01",
            "DYR IEEEG1 T2 = 1 s with its lag T1 = 0",
            IG1.format(T1=0, T2=1.0),
            IG1.format(T1=0, T2=0),
            r"\bT2 = 1|\bT1 = 0\b|without (its )?lag",
        ),
    )
    probe(
        "P02",
        lead_dyr(
            "P02",
            "DYR IEESGO T2 = 1 s with its lag T3 = 0",
            IES.format(T2=1.0, T3=0),
            IES.format(T2=0, T3=0),
            r"\bT2 = 1|\bT3 = 0\b|without (its )?lag",
        ),
    )
    probe(
        "P03",
        lead_andes(
            "P03",
            "ANDES kundur_ieeeg1 IEEEG1 T2 = 2 s with T1 = 0",
            "kundur/kundur_ieeeg1.json",
            [["IEEEG1", 0, "T1", 0.0], ["IEEEG1", 0, "T2", 2.0]],
            [["IEEEG1", 0, "T1", 0.0], ["IEEEG1", 0, "T2", 0.0]],
            r"\bT2 = 2|\bT1 = 0\b|without (its )?lag",
            "7",
            "8",
        ),
    )
    probe(
        "P04",
        lead_andes(
            "P04",
            "ANDES ieee14_ieesgo IEESGO T2 = 1 s with T3 = 0",
            "ieee14/ieee14_ieesgo.xlsx",
            [["IEESGO", 0, "T3", 0.0], ["IEESGO", 0, "T2", 1.0]],
            [["IEESGO", 0, "T3", 0.0], ["IEESGO", 0, "T2", 0.0]],
            r"\bT2 = 1|\bT3 = 0\b|without (its )?lag",
            "4",
            "5",
        ),
    )

    # -- PST pss (case file): second lead-lag's lead T3 without its lag T4 ----------------
    def pst_pss():
        bad = case_file("P05b", [("pss", 0, "T4", 0.0)])  # T3 = 0.05 kept
        neu = case_file("P05n", [("pss", 0, "T4", 0.0), ("pss", 0, "T3", 0.0)])
        rc, o, e = run(
            ["simulate", bad, "--fault", "3", "--far-bus", "101", "--tf", "2", "--out", "x.csv"]
        )
        kind, text = judge(rc, o, e, r"\bT3\b.*(lag|T4)|T4 = 0")
        if kind in ("refused", "named"):
            return True, f"{kind}: {text}"
        return False, (
            "kundur case file, pss row 1 T4 = 0 with T3 = 0.05 (PST pss type 1) accepted without a word"
            + no_effect(bad, neu, "3", "101")
        )

    probe("P05", pst_pss)

    # -- AC8B's VFEMAX / VEMIN: given, not modelled, not named --------------------------
    probe(
        "P06",
        lead_andes(
            "P06",
            "ANDES ieee14_ac8b AC8B VFEMAX = 1.0, VEMIN = 0.5 (not modelled)",
            "ieee14/ieee14_ac8b.xlsx",
            [["AC8B", 0, "VFEMAX", 1.0], ["AC8B", 0, "VEMIN", 0.5]],
            [],
            r"VFEMAX = 1\b|VEMIN = 0\.5|VFEMAX.*not (modelled|read)",
            "4",
            "5",
        ),
    )

    # -- a stabiliser of gain 0: counted as '1 PSS', never acts --------------------------
    ST = "    102 'IEEEST' 1 1 0 0 0 0 0 0 0 0.1 0.02 0 0 1.5 1.5 {KS} 0.1 -0.1 0 0 /\n"

    def pss_gain0():
        rc, o, e = dyr_case("P07b", SEXS + ST.format(KS=0))
        kind, text = judge(rc, o, e, r"KS = 0\b")
        if kind in ("refused", "named"):
            return True, f"{kind}: {text}"
        dyr_case("P07n", SEXS)
        m = re.search(r"\d+ PSS", o)
        return False, (
            f"DYR IEEEST KS = 0 accepted ('{m and m.group(0)}', no word)"
            + no_effect("P07b.json", "P07n.json", "102", "103").replace(
                "without the value", "without the PSS"
            )
        )

    probe("P07", pss_gain0)

    # -- ST2CUT's missing lag named under another record's field names ------------------
    def st2cut_names():
        rc, o, e = dyr_case(
            "P08",
            SEXS
            + "    102 'ST2CUT' 1 1 0 0 0 10 0 0 0 1.5 1.5 0.1 0.02 0 0 0.5 0 0.1 -0.1 0 0 /\n",
        )
        if rc == 2 and re.search(r"T10 = 0, T9 = 0\.5: a lead without its lag", e):
            return True, "refused: " + last(e)
        return (
            False,
            f"rc {rc}: ST2CUT T9 = 0.5, T10 = 0 refused as {last(e, 120)!r} (ST2CUT's T5 is 0.1, with its lag T6: the lead is T9)",
        )

    probe("P08", st2cut_names)

    # -- RAW: inverted normal voltage limits, negative resistance ------------------------
    B3 = "   103,'BUS 3', 138.0000,1,   1,   1,   1,0.99341,  -8.7697,1.10000,0.90000,1.10000,0.90000"

    def raw_named(pid, old, new, named, what):
        def f():
            rc, o, e = dyr_case(pid, SEXS, BASE_RAW.replace(old, new, 1))
            kind, text = judge(rc, o, e, named)
            return kind in ("refused", "named"), (
                f"{kind}: {text}" if kind != "silent" else f"{what} accepted without a word: {text}"
            )

        return f

    probe(
        "P09",
        raw_named(
            "P09",
            B3,
            B3.replace("1.10000,0.90000,1.10000,0.90000", "0.90000,1.10000,0.90000,1.10000"),
            r"NVHI|NVLO|EVHI|EVLO",
            "bus 103 NVHI 0.9 < NVLO 1.1 (and EVHI < EVLO)",
        ),
    )
    L12 = "   101,   102,'1 ', 1.00000E-2,"
    probe(
        "P10",
        raw_named(
            "P10",
            L12,
            "   101,   102,'1 ', -1.00000E-2,",
            r"R = -0\.01|negative r|R -1",
            "branch 101-102 R = -0.01 pu (a line that generates power)",
        ),
    )

    # -- regression guards: refused, naming the field -------------------------------------
    for pid, body, pat in [
        ("P20", "    102 'TGOV1' 1 -0.05 0.2 1.2 0.1 0.3 0.8 0 /\n", r"R = -0\.05"),
        ("P21", "    102 'TGOV1' 1 0.05 0.2 1.2 0.1 0.3 0.8 -5 /\n", r"Dt = -5"),
        ("P22", IG1.format(T1=0.5, T2=0.1).replace("0.1 -0.1", "-0.1 0.1"), r"Uo = -0\.1"),
        (
            "P23",
            IES.format(T2=0, T3=0.1).replace("-1.2 0", "").replace("1.2 0 /", "0 1.2 /"),
            r"PMAX = 0, PMIN = 1\.2",
        ),
        (
            "P24",
            "    102 'ESAC1A' 1 0.01 0.1 0.0 200.0 0.05 7.0 -7.0 1.333 0.02 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 10.0 -10.0 /\n",
            r"TF = 0",
        ),
        (
            "P25",
            "    102 'ESAC1A' 1 0.01 0.1 0.0 200.0 0.05 7.0 -7.0 1.333 0.02 0.8 0.0 0.0 1.0 4.0 0.8 5.0 0.1 10.0 -10.0 /\n",
            r"saturation must grow",
        ),
        (
            "P26",
            SEXS
            + "    102 'IEEEST' 1 1 0 0 0 0 0 0 0 0.1 0.02 0 0 1.5 1.5 10 0.1 -0.1 0.5 1.2 /\n",
            r"VCU = 0\.5",
        ),
        ("P27", SEXS + "    102 'STAB1' 1 6 1.5 13.3 0.0447 13.3 0.0447 -0.2 /\n", r"HLIM = -0\.2"),
        ("P28", "    102 'SEXS' 1 0.4 5.0 20.0 1.0 50.0 -50.0 /\n", r"EMAX = -50"),
        ("P29", "    102 'SCRX' 1 0.4 5.0 20.0 1.0 -50.0 50.0 2 0.0 /\n", r"CSWITCH = 2"),
    ]:
        probe(
            pid,
            refused(
                lambda b=body, p=pid: dyr_case(
                    p, b if "SEXS" in b or "ESAC1A" in b or "SCRX" in b else SEXS + b
                ),
                pat,
            ),
        )
    LD = "   103,'1 ',1,   1,   1,   250.000,"
    L23 = [l for l in BASE_RAW.splitlines() if l.startswith("   102,   103,")][0]
    TX = (
        "   102,   103,     0,'1 ',1,1,1, 0.00000E+0, 0.00000E+0,2,'TX          ',1,   1,1.0000\n"
        " 1.00000E-2, 1.20000E-1,   100.00\n0.00000,   0.000,   0.000,   250.00,   250.00,   250.00, 0, 0, 1.1, 0.9,"
        " 1.10000, 0.90000,  33, 0, 0.00000, 0.00000,  0.000\n1.00000,   0.000"
    )
    SS = "   103,{m},0,1, {vh}, {vl},     0,100.0,'            ',{binit}, 2, 30.00"
    for pid, raw_text, pat in [
        ("P30", BASE_RAW.replace(L12, "   101,   101,'1 ', 1.00000E-2,", 1), r"to itself"),
        ("P31", BASE_RAW.replace(B3, B3 + "\n" + B3, 1), r"appears twice"),
        ("P32", BASE_RAW.replace(LD, "   103,'1 ',1,   1,   1,   nan,", 1), r"not a finite number"),
        (
            "P33",
            BASE_RAW.replace(L23 + "\n", "").replace(
                " 0 /End of Transformer data", TX + "\n 0 /End of Transformer data"
            ),
            r"WINDV1 0\.00000 must be > 0",
        ),
        (
            "P34",
            BASE_RAW.replace(
                " 0 /End of Switched shunt data",
                SS.format(m=0, vh="1.05", vl="0.95", binit="90.00")
                + "\n 0 /End of Switched shunt data",
            ),
            r"outside the 0 to 60 Mvar",
        ),
        (
            "P35",
            BASE_RAW.replace(
                " 0 /End of Switched shunt data",
                SS.format(m=1, vh="0.95", vl="1.05", binit="30.00")
                + "\n 0 /End of Switched shunt data",
            ),
            r"VSWHI must be >= VSWLO",
        ),
        (
            "P36",
            BASE_RAW.replace(
                "   102,'1 ',   100.000,    -3.247,   100.000,  -100.000,1.02000,     0,   100.000,",
                "   104,'1 ',   100.000,    -3.247,   100.000,  -100.000,1.02000,     0,   100.000,",
                1,
            ),
            r"bus 104 is not in the bus data",
        ),
    ]:
        probe(pid, refused(lambda t=raw_text, p=pid: dyr_case(p, SEXS, t), pat))
    for pid, ed, pat in [
        ("P40", [("branches", 0, "x", 0.0)], r"must not be 0"),
        ("P41", [("branches", 0, "tap", -1.0)], r"must be > 0"),
        ("P42", [("pss", 0, "T2", 0.0)], r"field .T2.: first lag"),
        ("P43", [("exciters", 0, "TC", 5.0)], r"field .TC.: must be 0 where TB = 0"),
    ]:
        probe(
            pid,
            refused(
                lambda e=ed, p=pid: run(
                    [
                        "simulate",
                        case_file(p, e),
                        "--fault",
                        "3",
                        "--far-bus",
                        "101",
                        "--tf",
                        "2",
                        "--out",
                        p + ".csv",
                    ]
                ),
                pat,
            ),
        )

    short = [r for r in RESULTS if not r[1]]
    print(
        f"\n{len(RESULTS)} probes, {len(RESULTS) - len(short)} ok, {len(short)} short; {time.time() - t0:.0f} s"
    )
    return 1 if short else 0


if __name__ == "__main__":
    try:
        rc = main()
    finally:
        shutil.rmtree(WORK, ignore_errors=True)
    sys.exit(rc)
