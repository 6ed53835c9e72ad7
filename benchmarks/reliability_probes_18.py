#!/usr/bin/env python
"""Eighteenth reliability round (round 40, part M): inputs, data and silently wrong
results.  Recordings given to `estimate rmse/track --source` (concatenated, CFG-2 stamped
late, frames shifted, other rate, other placement, swapped PMUs, other IDCODE, every value
flagged, an ESD run's truth, a leap second where none can be); case imports (import-psse
DYR and import-andes: time-constant order, lead without lag, negative PI gains of
converter controls, duplicated governors, a PSS's negative washout, plus regression
guards); CLI fault arguments (numbers, times, steps, percentages, labels).

    python benchmarks/reliability_probes_18.py

The package under test is this repository's (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's; XDG_CACHE_HOME a temporary directory.  Prints per
probe: id, ok/SHORT, one-line reason; exits 1 if any is SHORT.  About 6 minutes on two
cores with a warm kernel cache.  The round found short: GENROU T"do above T'do, an
exciter's lead without its lag, negative PI gains of converter controls (all read
without a word), a recording given twice read to the run's end by `estimate rmse`, a
leap second where none can be, a CFG-2 stamped late called "short", two TGOV1 of one
machine and a stabiliser's negative washout unclearly named; all fixed.
"""

# ruff: noqa: E501, BLE001, SIM115, RUF059 - a tester's script, kept as written
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
CLONE = os.environ.get("CLONE", os.path.dirname(HERE))  # the package under test
WORK = tempfile.mkdtemp(prefix="probe_m.")
ENV = dict(os.environ, PYTHONPATH=CLONE, XDG_CACHE_HOME=os.path.join(WORK, "xdg"))
RESULTS = []
MKREC = '# makes recordings for part M probes, in cwd\nimport sys, struct, numpy as np, stabctl\nfrom stabctl.dynamics.events import fault_with_clearing\nfrom stabctl.estimation import c37, pmu as pm\nfrom stabctl.estimation.settings import PMUSettings\n\ndef crc(b):\n    c = 0xFFFF\n    for x in b:\n        c ^= x << 8\n        for _ in range(8):\n            c = ((c << 1) ^ 0x1021) & 0xFFFF if c & 0x8000 else (c << 1) & 0xFFFF\n    return c\n\ndef fix(fr):\n    fr = bytearray(fr[:-2])\n    return bytes(fr) + struct.pack(">H", crc(fr))\n\ndef make(casename, bus, far, cycles, tf, rate=60, seed=1, at="terminal", esd=None):\n    case = stabctl.load_case(casename)\n    res = stabctl.Simulator(case).run([fault_with_clearing(case, bus, far, 1.0, cycles)], t_end=tf)\n    pmus = pm.machine_pmus(case, at)\n    drawn = pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(rate=rate), seed=seed)\n    return c37.stream_config(case, pmus, rate), list(drawn)\n\ndef rewrite(src, dst, fn_cfg=None, fn_data=None):\n    data = open(src, "rb").read()\n    frames = c37.split_frames(data)\n    out = []\n    for k, f in enumerate(frames):\n        if k == 0:\n            f = fn_cfg(f) if fn_cfg else f\n        else:\n            f = fn_data(k, f) if fn_data else f\n        out.append(fix(f) if (k == 0 and fn_cfg) or (k and fn_data) else f)\n    open(dst, "wb").write(b"".join(out))\n\ncfg, fr = make("kundur", 3, 101, 6, 6.0)\nc37.record("base.c37", cfg, fr)\nBLK = 22  # STAT 2 + 2 float phasors 16 + FREQ 2 + DFREQ 2\n\ndef set_stat(bits, pmus=(0, 1, 2, 3), when=lambda k: True):\n    def f(k, fr):\n        fr = bytearray(fr)\n        if when(k):\n            for p in pmus:\n                at = 14 + p * BLK\n                s = int.from_bytes(fr[at:at + 2], "big") | bits\n                fr[at:at + 2] = s.to_bytes(2, "big")\n        return bytes(fr)\n    return f\n\nrewrite("base.c37", "syncall.c37", fn_data=set_stat(0x2000))\nrewrite("base.c37", "sorted_g3.c37", fn_data=set_stat(0x1000, pmus=(2,)))\nrewrite("base.c37", "absentall.c37", fn_data=set_stat(0x8000))\ndef tq(k, fr):\n    fr = bytearray(fr); fr[10] = 0x0F; return bytes(fr)\nrewrite("base.c37", "clockfail.c37", fn_data=tq)\n# the CFG-2 stamped one reporting interval (1/60 s) and 0.5 s later than the run\'s start\ndef shift(us):\n    def f(fr):\n        fr = bytearray(fr)\n        soc = int.from_bytes(fr[6:10], "big"); cnt = int.from_bytes(fr[11:14], "big") + us\n        soc += cnt // 1_000_000; cnt %= 1_000_000\n        fr[6:10] = soc.to_bytes(4, "big"); fr[11:14] = cnt.to_bytes(3, "big")\n        return bytes(fr)\n    return f\nrewrite("base.c37", "cfgshift1.c37", fn_cfg=shift(16667))\nrewrite("base.c37", "cfgshift3.c37", fn_cfg=shift(50000))\nrewrite("base.c37", "cfgshift30.c37", fn_cfg=shift(500000))\n# the data frames all shifted by one reporting interval (CFG-2 unchanged)\ndef dshift(k, fr):\n    return shift(16667)(fr)\nrewrite("base.c37", "datashift1.c37", fn_data=dshift)\n# IDCODE of every data frame 7 (CFG-2 says 1)\ndef idc(k, fr):\n    fr = bytearray(fr); fr[4:6] = (7).to_bytes(2, "big"); return bytes(fr)\nrewrite("base.c37", "idcode7.c37", fn_data=idc)\n# two recordings one after the other\nopen("twice.c37", "wb").write(open("base.c37", "rb").read() * 2)\n# PMU G2 and G3 swapped in the data (station names kept): values of G3 under G2\'s name\ndef swap(k, fr):\n    fr = bytearray(fr)\n    a, b = 14 + 1 * BLK, 14 + 2 * BLK\n    x, y = fr[a:a + BLK], fr[b:b + BLK]\n    fr[a:a + BLK], fr[b:b + BLK] = y, x\n    return bytes(fr)\nrewrite("base.c37", "swapped.c37", fn_data=swap)\nc37.record("rate30.c37", *make("kundur", 3, 101, 6, 6.0, rate=30))\ntry:\n    c37.record("hv.c37", *make("kundur", 3, 101, 6, 6.0, at="hv"))\nexcept Exception as e:\n    print("hv not made", e)\nc37.record("g1freeze.c37", cfg, [f._replace(v=np.where(np.arange(4) == 0, fr[0].v, f.v), freq=np.where(np.arange(4)==0, fr[0].freq, f.freq), rocof=np.where(np.arange(4)==0, 0.0, f.rocof), i=np.where(np.arange(4)==0, fr[0].i, f.i)) for f in fr])\n# all frequencies constant 60 Hz, phasors frozen (a PMU stuck / a replay of one frame)\nc37.record("frozen.c37", cfg, [fr[0]._replace(t=f.t) for f in fr])\nprint("RECORDED")\n'
ANDES_VAR = 'import andes, json, math, sys, subprocess, os\nimport pandas as pd\ndef load(name):\n    p = andes.get_case(name)\n    if p.endswith(".json"):\n        return json.load(open(p))\n    sheets = pd.read_excel(p, sheet_name=None)\n    return {k: [{c: v for c, v in r.items() if not (isinstance(v, float) and math.isnan(v))}\n                for r in df.dropna(axis=0, how="all").to_dict("records")] for k, df in sheets.items()}\nBASE = {"wt3": "ieee14/ieee14_wt3.xlsx", "pvd1": "ieee14/ieee14_pvd1.json",\n        "esd1": "ieee14/ieee14_esd1.xlsx", "kundur": "kundur/kundur_full.json"}\nGONE = object()\ndef variant(src, edits, name):\n    d = load(BASE[src])\n    for model, row, field, value in edits:\n        if field is None:  # duplicate row\n            d[model].append(dict(d[model][row]))\n            continue\n        if value is GONE:\n            d[model][row].pop(field, None)\n        else:\n            d[model][row][field] = value\n    json.dump(d, open(name, "w"), default=str)\n    return name\n'
RAW = os.path.join(CLONE, "tests/data/psse_runs/GENROU/ThreeBusMulti.raw")
REN = os.path.join(CLONE, "tests/data/psse_runs/RENA_DEFAULT")
GR = "8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8"


def run(args, cwd=WORK, timeout=300):
    p = subprocess.run(
        ["stabctl", *map(str, args)],
        cwd=cwd,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return p.returncode, p.stdout, p.stderr


def last(text, n=200):
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
    print(f"{pid:8s} {'ok' if ok else 'SHORT':5s} {why}", flush=True)


def refused(args, pat, cwd=WORK, out=None):
    rc, o, e = run(args, cwd)
    if "Traceback" in e:
        return False, "traceback: " + last(e)
    if out and os.path.exists(os.path.join(cwd, out)):
        return False, f"rc {rc}: output {out} written"
    if rc == 2 and e.strip().splitlines()[-1].startswith("error:") and re.search(pat, e):
        return True, "refused: " + last(e, 170)
    return False, f"rc {rc} (expected a refusal matching {pat!r}): " + (
        last(e, 170) or last(o, 170)
    )


def accepted_silently(args, pat_named, cwd=WORK, what=""):
    """Bad data: ok only if refused (rc 2, error:) or named (pat_named in the output)."""
    rc, o, e = run(args, cwd)
    if "Traceback" in e:
        return False, "traceback: " + last(e)
    if rc == 2 and "error:" in e:
        return True, "refused: " + last(e, 170)
    if rc == 0 and re.search(pat_named, o + e):
        return True, "named: " + re.search(r"[^\n]*(" + pat_named + r")[^\n]*", o + e).group(0)[
            :170
        ]
    return False, f"rc {rc}: {what} accepted without a word: " + (last(o, 150))


def sub(dirname):
    d = os.path.join(WORK, dirname)
    os.makedirs(d, exist_ok=True)
    return d


# ------------------------------------------------------------------ recordings ----------
REC = sub("rec")
RMSE = ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101", "--clear-cycles", "6"]


def make_recordings():
    open(os.path.join(REC, "mkrec.py"), "w").write(MKREC)
    p = subprocess.run(
        [sys.executable, "mkrec.py"], cwd=REC, env=ENV, capture_output=True, text=True, timeout=900
    )
    if "RECORDED" not in p.stdout:
        raise RuntimeError("recordings not made: " + last(p.stderr))
    # a leap second inserted at SOC 1700000003 (22:13:23 UTC): frames from t = 3 s stamped
    # 1 s back, the second before flagging 'leap second pending' (FRACSEC bit 4)
    code = (
        MKREC.split("def make")[0]
        + """
data = open("base.c37", "rb").read(); fr = c37.split_frames(data); out = [fr[0]]
for k, f in enumerate(fr[1:]):
    f = bytearray(f); soc = int.from_bytes(f[6:10], "big")
    if k >= 180: f[6:10] = (soc - 1).to_bytes(4, "big")
    if 120 <= k < 180: f[10] |= 0x10
    out.append(fix(bytes(f)))
open("leap_midday.c37", "wb").write(b"".join(out))
print("LEAP")
"""
    )
    p = subprocess.run(
        [sys.executable, "-c", code], cwd=REC, env=ENV, capture_output=True, text=True, timeout=300
    )
    if "LEAP" not in p.stdout:
        raise RuntimeError("leap recording not made: " + last(p.stderr))


def rec_probes():
    try:
        make_recordings()
    except Exception as exc:
        probe("M-R00", lambda exc=exc: (False, str(exc)))
        return

    def base_ok():
        rc, o, e = run([*RMSE, "--tf", "6", "--source", "base.c37"], REC)
        return rc == 0 and "361 data frames" in o, f"rc {rc}: " + (
            last(e) if rc else "361 frames, ekf ran"
        )

    probe("M-R01", base_ok)

    def twice_rmse():
        """base.c37 written twice in one file (a second CFG-2, then time stamps going back
        6 s): track refuses it (M-R03); rmse --source reads to its run's end and says
        nothing about the 362 frames after it."""
        rc, o, e = run([*RMSE, "--tf", "6", "--source", "twice.c37"], REC)
        if rc == 2 and "back" in e:
            return True, "refused: " + last(e, 160)
        m = re.search(r"frames from twice\.c37: [^;\n]*", o)
        return False, (
            f"rc {rc}: used; '{m and m.group(0)}'; the rest of the file (CFG-2 again "
            "and 361 frames going back 6 s, which `estimate track` refuses) not read, not named"
        )

    probe("M-R02", twice_rmse)
    probe(
        "M-R03",
        lambda: refused(
            ["estimate", "track", "kundur", "--source", "twice.c37", "--out", "t3.csv"],
            r"goes back",
            REC,
            "t3.csv",
        ),
    )

    def cfg_late():
        """The CFG-2 stamped one frame (16.7 ms) after the first data frame: with --tf 5
        refused naming frames from -0.0167 s; with --tf 6 the error should say the same,
        not that the recording is short."""
        rc, o, e = run([*RMSE, "--tf", "6", "--source", "cfgshift1.c37"], REC)
        if rc != 2:
            return False, f"rc {rc}: accepted"
        if re.search(r"-0\.01|before the run|before its CFG|not a stream of this run", e):
            return True, last(e, 160)
        return (
            False,
            "refused, but as "
            + repr(last(e, 150))
            + " (the frames start 16.7 ms BEFORE the run; with --tf 5 the same file is 'frames from -0.0166667 s ... not a stream of this run')",
        )

    probe("M-R04", cfg_late)
    probe(
        "M-R05",
        lambda: refused(
            [*RMSE, "--tf", "5", "--source", "cfgshift1.c37"], r"not a stream of this run", REC
        ),
    )
    probe(
        "M-R06",
        lambda: refused(
            [*RMSE, "--tf", "6", "--source", "datashift1.c37"], r"starts at t = 0\.0167", REC
        ),
    )
    probe(
        "M-R07",
        lambda: refused([*RMSE, "--tf", "6", "--source", "rate30.c37"], r"DATA_RATE 30", REC),
    )
    probe("M-R08", lambda: refused([*RMSE, "--tf", "6", "--source", "hv.c37"], r"--pmu-at hv", REC))
    probe(
        "M-R09",
        lambda: refused(
            [*RMSE, "--tf", "6", "--source", "swapped.c37"], r"do not measure this run", REC
        ),
    )
    probe(
        "M-R10", lambda: refused([*RMSE, "--tf", "6", "--source", "idcode7.c37"], r"IDCODE 7", REC)
    )
    probe(
        "M-R11",
        lambda: refused(
            [*RMSE, "--tf", "6", "--source", "syncall.c37"], r"nothing was measured", REC
        ),
    )
    probe(
        "M-R12",
        lambda: refused(
            [*RMSE, "--tf", "6", "--source", "absentall.c37"], r"nothing was measured", REC
        ),
    )
    probe(
        "M-R13",
        lambda: refused([*RMSE, "--tf", "6", "--source", "clockfail.c37"], r"clock failure", REC),
    )
    probe(
        "M-R14",
        lambda: refused(
            ["estimate", "track", "kundur", "--source", "syncall.c37", "--out", "t14.csv"],
            r"nothing was measured",
            REC,
            "t14.csv",
        ),
    )
    probe(
        "M-R15",
        lambda: accepted_silently(
            ["estimate", "track", "kundur", "--source", "sorted_g3.c37", "--out", "t15.csv"],
            r"sorted by arrival",
            REC,
        ),
    )
    probe(
        "M-R16",
        lambda: refused(
            [*RMSE, "--tf", "6", "--source", "base.c37", "--esd-pct", "5"],
            r"do not measure this run",
            REC,
        ),
    )
    probe(
        "M-R17",
        lambda: refused(
            ["estimate", "track", "miniwecc", "--source", "base.c37", "--out", "t17.csv"],
            r"not a PMU of this run|station|stations",
            REC,
            "t17.csv",
        ),
    )

    def leap():
        """A 'leap second' at SOC 1700000003 (22:13:23 UTC): leap seconds are inserted only
        at the end of a UTC day (C37.118.2-2011 6.2.2, 23:59:60); frames from 3 s on stepped
        1 s back with the pending flag set the second before.  Should be refused as going
        back, or at least named."""
        bad = []
        for args in (
            [*RMSE, "--tf", "6", "--source", "leap_midday.c37"],
            ["estimate", "track", "kundur", "--source", "leap_midday.c37", "--out", "t18.csv"],
        ):
            rc, o, e = run(args, REC)
            if not (rc == 2 or re.search(r"leap second", o + e, re.I)):
                bad.append(f"{args[1]} rc {rc}, no word of a leap second")
        return (not bad), "; ".join(bad) or "refused or named"

    probe("M-R18", leap)


# ------------------------------------------------------------------ imports -------------
DYRD = sub("dyr")


def dyr(name, body, pat, expect_refusal=True, gr=GR):
    text = f"    101 'GENCLS' 1 0.0 0.0 /\n    102 'GENROU' 1 {gr} /\n{body}"
    open(os.path.join(DYRD, name + ".dyr"), "w").write(text)
    args = ["import-psse", RAW, name + ".dyr", "-o", name + ".json"]
    if expect_refusal:
        return refused(args, pat, DYRD, name + ".json")
    return accepted_silently(args, pat, DYRD, name)


def import_probes():
    g = GR.split()
    sw = list(g)
    sw[0], sw[1] = g[1], g[0]  # T'do 0.03 < T''do 8
    probe("M-I01", lambda: dyr("tdo", "", r"T'do|T\"do|T''do", False, " ".join(sw)))
    sq = list(g)
    sq[2], sq[3] = g[3], g[2]  # T'qo 0.05 < T''qo 0.4
    probe("M-I02", lambda: dyr("tqo", "", r"T'qo|T\"qo|T''qo", False, " ".join(sq)))

    def exst1_tb0():
        """EXST1 TC = 10 s with TB = 0 (a lead without its lag): the run is identical to
        TC = 0 (TC without effect); IEEEST's 'lead T1 without lag' is refused."""
        ok, why = dyr(
            "exst1_tb0",
            "    102 'EXST1' 1 0.01 5.0 -5.0 10 0 200.0 0.1 6.0 0.0 0.0 0.0 0.1 /\n",
            r"\bTC = 10|\bTB = 0\b|lead TC",
            False,
        )
        if ok:
            return ok, why
        dyr(
            "exst1_tb0_tc0",
            "    102 'EXST1' 1 0.01 5.0 -5.0 0 0 200.0 0.1 6.0 0.0 0.0 0.0 0.1 /\n",
            "",
            False,
        )
        outs = []
        for n in ("exst1_tb0", "exst1_tb0_tc0"):
            rc, o, e = run(
                [
                    "simulate",
                    n + ".json",
                    "--fault",
                    "102",
                    "--far-bus",
                    "103",
                    "--clear-cycles",
                    "4",
                    "--tf",
                    "3",
                    "--out",
                    n + ".csv",
                ],
                DYRD,
            )
            outs.append(open(os.path.join(DYRD, n + ".csv"), "rb").read() if rc == 0 else b"")
        same = outs[0] == outs[1] and outs[0]
        return False, why + (
            "; simulate of TC=10 byte-identical to TC=0 (TC silently without effect)"
            if same
            else ""
        )

    probe("M-I03", exst1_tb0)
    probe(
        "M-I04",
        lambda: dyr(
            "ieeest_lead",
            "    102 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n"
            "    102 'IEEEST' 1 1 0 0 0 0 0 0 0.0 5 0 0 0.02 1.65 1.65 100 0.1 -0.1 0 0 /\n",
            r"T2 = 0, T1 = 5: a lead without its lag",  # round 41: in the record's fields
        ),
    )

    def ren(name, old, new, pat):
        base = open(os.path.join(REN, "ThreeBus_REN_A_DEFAULT_FLAG.dyr")).read()
        assert old in base
        open(os.path.join(DYRD, name + ".dyr"), "w").write(base.replace(old, new, 1))
        return accepted_silently(
            [
                "import-psse",
                os.path.join(REN, "ThreeBusRenewable.raw"),
                name + ".dyr",
                "-o",
                name + ".json",
            ],
            pat,
            DYRD,
            name,
        )

    probe(
        "M-I05",
        lambda: ren(
            "repca1_kp",
            "0.20000E-01      18.000          5.0000",
            "0.20000E-01      -18.000          5.0000",
            r"Kp = -18",
        ),
    )
    probe(
        "M-I06",
        lambda: ren("repca1_ki", "18.000          5.0000", "18.000          -5.0000", r"Ki = -5"),
    )
    # regression guards (refused with the field named)
    for pid, name, body, gr, pat in [
        ("M-I10", "xpp", "", GR.replace("0.3 0.55 0.25", "0.3 0.55 0.35"), r"x'd must be >= x\"d"),
        ("M-I11", "sat", "", GR.replace("0.1 0.8", "0.8 0.1"), r"S\(1\.2\) must be >="),
        ("M-I12", "sexs_te", "    102 'SEXS' 1 0.4 5.0 20.0 -1.0 -50.0 50.0 /\n", GR, r"TE = -1"),
        (
            "M-I13",
            "tgov_v",
            "    102 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n    102 'TGOV1' 1 0.05 0.2 0.1 1.2 0.3 0.8 0 /\n",
            GR,
            r"upper limit",
        ),
        (
            "M-I14",
            "sexs2",
            "    102 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n" * 2,
            GR,
            r"second exciter",
        ),
        (
            "M-I15",
            "bus999",
            "    999 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n",
            GR,
            r"none at bus 999",
        ),
        (
            "M-I16",
            "id7",
            "    102 'SEXS' 7 0.4 5.0 20.0 1.0 -50.0 50.0 /\n",
            GR,
            r"bus 102's: id '1'",
        ),
        ("M-I17", "gast2a", "    102 'GAST2A' 1 1 2 3 /\n", GR, r"GAST2A is not mapped"),
        (
            "M-I18",
            "ieeest_ls",
            "    102 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n    102 'IEEEST' 1 1 0 0 0 0 0 0 0.0 0 0 0 0.02 1.65 1.65 100 -0.1 0.1 0 0 /\n",
            GR,
            r"LSMAX",
        ),
    ]:
        probe(pid, lambda n=name, b=body, g2=gr, p=pat: dyr(n, b, p, True, g2))

    AN = sub("andes")
    open(os.path.join(AN, "andes_var.py"), "w").write(ANDES_VAR)

    def andes(name, src, edits, pat, expect_refusal=True):
        code = (
            "import sys; sys.path.insert(0, '.'); from andes_var import *\n"
            f"variant({src!r}, {edits!r}, {name + '.json'!r})\n"
        )
        p = subprocess.run(
            [sys.executable, "-c", code],
            cwd=AN,
            env=ENV,
            capture_output=True,
            text=True,
            timeout=300,
        )
        if p.returncode:
            return False, "variant not made: " + last(p.stderr)
        args = ["import-andes", name + ".json", "-o", "o_" + name + ".json"]
        if expect_refusal:
            return refused(args, pat, AN, "o_" + name + ".json")
        return accepted_silently(args, pat, AN, name)

    probe(
        "M-I20",
        lambda: andes(
            "td",
            "kundur",
            [("GENROU", 0, "Td10", 0.03), ("GENROU", 0, "Td20", 8.0)],
            r"Td10|Td20",
            False,
        ),
    )
    probe(
        "M-I21",
        lambda: andes(
            "tq",
            "kundur",
            [("GENROU", 0, "Tq10", 0.05), ("GENROU", 0, "Tq20", 0.4)],
            r"Tq10|Tq20",
            False,
        ),
    )

    def exdc2_tb0():
        ok, why = andes(
            "exdc2_tb0_tc5",
            "kundur",
            [("EXDC2", 0, "TB", 0.0), ("EXDC2", 0, "TC", 5.0)],
            r"\bTC = 5|\bTB = 0\b",
            False,
        )
        if ok:
            return ok, why
        andes(
            "exdc2_tb0_tc0", "kundur", [("EXDC2", 0, "TB", 0.0), ("EXDC2", 0, "TC", 0.0)], "", False
        )
        outs = []
        for n in ("exdc2_tb0_tc5", "exdc2_tb0_tc0"):
            rc, o, e = run(
                [
                    "simulate",
                    "o_" + n + ".json",
                    "--no-q-limits",
                    "--fault",
                    "7",
                    "--far-bus",
                    "8",
                    "--clear-cycles",
                    "6",
                    "--tf",
                    "4",
                    "--out",
                    n + ".csv",
                ],
                AN,
            )
            outs.append(open(os.path.join(AN, n + ".csv"), "rb").read() if rc == 0 else b"")
        same = outs[0] == outs[1] and outs[0]
        return False, why + ("; simulate of TC=5 byte-identical to TC=0" if same else "")

    probe("M-I22", exdc2_tb0)

    def neg_gains():
        """Negative PI gains of converter controls: KA, Kqv, Khv < 0 are refused; these not."""
        took = []
        for model, field, value in [
            ("REPCA1", "Kp", -1),
            ("REPCA1", "Ki", -0.1),
            ("REPCA1", "Kpg", -1),
            ("REPCA1", "Kig", -0.1),
            ("REECA1", "Kqp", -1),
            ("REECA1", "Kvi", -0.1),
            ("WTTQA1", "Kip", -0.1),
            ("WTPTA1", "Kiw", -0.1),
        ]:
            ok, why = andes(
                f"neg_{model}_{field}",
                "wt3",
                [(model, 0, field, value)],
                rf"{field} = {value}",
                False,
            )
            if not ok:
                took.append(f"{model} {field} = {value}")
        return (not took), (
            "accepted without a word: " + ", ".join(took)
        ) if took else "all refused or named"

    probe("M-I23", neg_gains)

    probe(
        "M-I24",
        lambda: andes(
            "tgov2",
            "kundur",
            [("TGOV1", 1, "syn", 1)],
            r"TGOV1.*(second|twice|both)|second governor",
        ),
    )
    probe("M-I25", lambda: andes("ieeest_t6", "pvd1", [("IEEEST", 0, "T6", -4.2)], r"T6"))
    for pid, name, src, ed, pat in [
        ("M-I30", "dupidx", "kundur", [("GENROU", 0, None, None)], r"both give idx"),
        ("M-I31", "zerox", "wt3", [("REGCA1", 0, "Zerox", 0.9)], r"Brkpt > Zerox"),
        ("M-I32", "lvpnt", "wt3", [("REGCA1", 0, "Lvpnt0", 1.2)], r"Lvpnt1 > Lvpnt0"),
        ("M-I33", "vup", "wt3", [("REECA1", 0, "Vup", 0.7)], r"Vdip < Vup"),
        ("M-I34", "repline", "wt3", [("REPCA1", 0, "line", "Line_99")], r"Line_99"),
        ("M-I35", "wttp", "wt3", [("WTTQA1", 0, "p2", 0.1)], r"p1 < p2"),
        ("M-I36", "pvdfdbd", "pvd1", [("PVD1", 0, "fdbd", 0.017)], r"fdbd"),
        (
            "M-I37",
            "socreq",
            "esd1",
            [("ESD1", 0, "SOCmin", 0.5), ("ESD1", 0, "SOCmax", 0.5)],
            r"SOCmin < SOCmax",
        ),
        ("M-I38", "busf", "esd1", [("ESD1", 0, "busf", "BusFreq_99")], r"BusFreq_99"),
        ("M-I39", "wtdfreq", "wt3", [("WTDTA1", 0, "Freq1", 0)], r"Freq1"),
        ("M-I40", "rrpwr", "wt3", [("REGCA1", 0, "Rrpwr", -10)], r"Rrpwr"),
        ("M-I41", "dupexc", "kundur", [("EXDC2", 1, "syn", 1)], r"second exciter"),
    ]:
        probe(pid, lambda n=name, s=src, e=ed, p=pat: andes(n, s, e, p))


# ------------------------------------------------------------------ CLI fault args -------
def cli_probes():
    C = sub("cli")
    F = ["--fault", "3", "--far-bus", "101"]
    for pid, args, pat in [
        ("M-C01", ["cct", "kundur", "--fault", "\uff13", "--far-bus", "101"], r"ASCII digits"),
        ("M-C02", ["cct", "kundur", "--fault", "\u0663", "--far-bus", "101"], r"ASCII digits"),
        ("M-C03", ["cct", "kundur", "--fault", "3e0", "--far-bus", "101"], r"not a valid integer"),
        ("M-C04", ["cct", "kundur", *F, "--circuit", "1.0"], r"not a valid integer"),
        ("M-C05", ["cct", "kundur", "--fault", "9" * 23, "--far-bus", "101"], r"beyond any value"),
        (
            "M-C06",
            ["simulate", "kundur", *F, "--t-fault", "5", "--tf", "3"],
            r"after the end of the run",
        ),
        (
            "M-C07",
            ["simulate", "kundur", *F, "--t-fault", "2.95", "--tf", "3"],
            r"ends at or after the end",
        ),
        ("M-C08", ["simulate", "kundur", *F, "--clear-cycles", "nan"], r"finite"),
        ("M-C09", ["simulate", "kundur", *F, "--clear-cycles", "inf"], r"finite"),
        ("M-C10", ["simulate", "kundur", *F, "--step", "0"], r"--step 0"),
        ("M-C11", ["simulate", "kundur", *F, "--step", "nan"], r"finite"),
        ("M-C12", ["simulate", "kundur", *F, "--step", "20", "--tf", "3"], r"--step 20"),
        ("M-C13", ["simulate", "kundur", *F, "--tf", "nan"], r"--tf nan"),
        ("M-C14", ["cct", "kundur", *F, "--esd-pct", "150"], r"\(0, 100\]"),
        ("M-C15", ["cct", "kundur", *F, "--esd-pct", "nan"], r"finite"),
        ("M-C16", ["cct", "kundur", *F, "--t-max", "nan"], r"finite"),
        (
            "M-C17",
            ["estimate", "rmse", "kundur", *F, "--runs", "1", "--ambient-s", "0", "--drop", "1"],
            r"\[0, 1\)",
        ),
        (
            "M-C18",
            [
                "estimate",
                "rmse",
                "kundur",
                *F,
                "--runs",
                "1",
                "--ambient-s",
                "0",
                "--settle-ms",
                "nan",
            ],
            r"finite",
        ),
        (
            "M-C19",
            [
                "estimate",
                "rmse",
                "kundur",
                *F,
                "--runs",
                "1",
                "--ambient-s",
                "0",
                "--latency-ms",
                "-5",
            ],
            r"latency",
        ),
        ("M-C20", ["estimate", "rmse", "kundur", "--fault", "3", "--runs", "1"], r"--far-bus"),
    ]:
        probe(pid, lambda a=args, p=pat: refused(a, p, C))

    def reversed_ends():
        rc, o, e = run(["cct", "kundur", "--fault", "101", "--far-bus", "3"], C)
        return (rc == 0 and "fault at bus 101 on line 101-3" in o), f"rc {rc}: " + (
            o.splitlines() or [""]
        )[0][:150]

    probe("M-C21", reversed_ends)

    def bus_fault_same():
        open(os.path.join(C, "f.csv"), "w").write("bus,far_bus\n3,\n")
        rc, o, e = run(
            ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "sw.jsonl", "--workers", "1"], C
        )
        rc2, o2, e2 = run(["cct", "kundur", "--fault", "3", "--json"], C)
        rec = json.loads(open(os.path.join(C, "sw.jsonl")).readline())
        d = json.loads(o2)
        s = json.dumps(d)
        same = rec["result"]["cct_s"] == d.get("cct_s", d.get("result", {}).get("cct_s"))
        return (same and rec["result"]["fault"]["far_bus"] is None and '"far_bus": null' in s), (
            f"sweep {rec['result']['cct_s']} far_bus {rec['result']['fault']['far_bus']}; cct --json far_bus null: "
            + str('"far_bus": null' in s)
        )

    probe("M-C22", bus_fault_same)


def main():
    t0 = time.time()
    try:
        rec_probes()
        import_probes()
        cli_probes()
    finally:
        shutil.rmtree(WORK, ignore_errors=True)
    short = [r for r in RESULTS if not r[1]]
    print(
        f"\n{len(RESULTS)} probes, {len(RESULTS) - len(short)} ok, {len(short)} short; {time.time() - t0:.0f} s"
    )
    return 1 if short else 0


if __name__ == "__main__":
    sys.exit(main())
