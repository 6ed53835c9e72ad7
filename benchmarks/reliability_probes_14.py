#!/usr/bin/env python3
"""Fourteenth reliability round (round 38, part J): variants of issue 54's items 6-9
(integration steps, PMU recordings, converter and DYR data, fault labels), its crash list
and the newcomer frictions.  Re-runnable: every input is made in a fresh temporary
directory, removed at the end.

    python benchmarks/reliability_probes_14.py            # all probes
    python benchmarks/reliability_probes_14.py J7 J6-0    # only ids starting with these

The package under test is this repository's (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's.  Prints per probe: id, ok/SHORT, one-line reason; exits
1 if any is SHORT.  About 5 minutes on two cores with a warm kernel cache.  The round found
short: an impossible FREQ sample (75 Hz on a 60 Hz case) driving every ESD, a recording
that starts late accepted by estimate rmse, simulate --json without its step warnings, a
failing trapezoid step not named, --check-step advising the trapezoid to a trapezoid run;
all fixed, the probes now their regression checks.
"""

import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

HERE = os.path.dirname(os.path.abspath(__file__))
CLONE = os.environ.get("CLONE", os.path.dirname(HERE))  # the package under test
ENV = dict(os.environ, PYTHONPATH=CLONE)
ENV.pop("PYTHONWARNINGS", None)
STABCTL = [sys.executable, "-m", "stabctl"]
WORK = tempfile.mkdtemp(prefix="probes_j_")
RESULTS = []
ONLY = sys.argv[1:]


def run(args, timeout=300, cwd=None, stdin=None):
    """(rc, stdout, stderr) of stabctl args."""
    try:
        p = subprocess.run(
            STABCTL + list(args),
            cwd=cwd or WORK,
            env=ENV,
            capture_output=True,
            text=True,
            timeout=timeout,
            stdin=subprocess.DEVNULL,
        )
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired as e:
        return -999, e.stdout or "", f"TIMEOUT after {timeout}s"


def py(code, timeout=300):
    try:
        p = subprocess.run(
            [sys.executable, "-c", code],
            cwd=WORK,
            env=ENV,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired as e:
        return -999, e.stdout or "", f"TIMEOUT after {timeout}s"


def probe(pid):
    def deco(fn):
        if ONLY and not any(pid.startswith(o) for o in ONLY):
            return fn
        t0 = time.time()
        try:
            ok, why = fn()
        except Exception as exc:  # noqa: BLE001 - a probe's own failure is a SHORT to look at
            ok, why = False, f"probe raised {type(exc).__name__}: {exc}"
        RESULTS.append((pid, ok, why))
        print(
            f"{pid:10s} {'ok   ' if ok else 'SHORT'} {why}  [{time.time() - t0:.0f}s]", flush=True
        )
        return fn

    return deco


def last(s, n=300):
    lines = [ln for ln in s.strip().splitlines() if ln.strip() and "%|" not in ln]
    return (lines[-1] if lines else "")[:n]


def refused(args, pattern=None, timeout=300):
    """Clean refusal: exit 2, an 'error:' line, no traceback (and pattern in stderr)."""
    rc, out, err = run(args, timeout)
    if "Traceback" in err or "Traceback" in out:
        return False, f"traceback (rc {rc}): {last(err)}"
    if rc != 2:
        return False, f"rc {rc}, expected 2: {last(out) or last(err)}"
    if not re.search(r"^error: ", err, re.M):
        return False, f"no 'error:' line: {last(err)}"
    if pattern and not re.search(pattern, err, re.S):
        return False, f"message lacks /{pattern}/: {last(err)}"
    return True, "refused: " + last(err, 200)


def runs_ok(args, pattern=None, where="both", timeout=300):
    rc, out, err = run(args, timeout)
    if "Traceback" in err or "Traceback" in out:
        return False, f"traceback (rc {rc}): {last(err)}"
    if rc != 0:
        return False, f"rc {rc}: {last(err)}"
    text = {"out": out, "err": err}.get(where, out + "\n" + err)
    if pattern and not re.search(pattern, text, re.S):
        return False, f"output lacks /{pattern}/: {last(out)}"
    return True, "exit 0: " + (last(out, 160) or last(err, 160))


def write(name, text):
    path = os.path.join(WORK, name)
    with open(path, "w") as fh:
        fh.write(textwrap.dedent(text) if text.startswith("\n") else text)
    return path


FAULT = ["--fault", "3", "--far-bus", "101"]

# ---------------------------------------------------------------- item 6: steps ----------


@probe("J6-01")
def _():
    """trapezoid at 0.2 s on a fault stable at the converged step: warned on stderr."""
    rc, out, err = run(
        [
            "simulate",
            "kundur",
            *FAULT,
            "--clear-cycles",
            "6",
            "--method",
            "trapezoid",
            "--step",
            "0.2",
        ]
    )
    if "trapezoid step 0.2 s is above" in err:
        return True, f"rc {rc}, '{last(out, 80)}' with the one-cycle warning on stderr"
    return False, f"rc {rc}: no step warning: {last(out)}"


@probe("J6-02")
def _():
    """--json of that run: the verdict it gives (unstable; stable at 5 ms) carries no mark
    of the step warning (a program reading the JSON sees a plain 'loss of synchronism')."""
    _rc, out, _err = run(
        [
            "simulate",
            "kundur",
            *FAULT,
            "--clear-cycles",
            "6",
            "--method",
            "trapezoid",
            "--step",
            "0.2",
            "--json",
        ]
    )
    d = json.loads(out)
    ref = json.loads(run(["simulate", "kundur", *FAULT, "--clear-cycles", "6", "--json"])[1])
    blob = json.dumps(d)
    marked = any(k in blob for k in ("trapezoid step", "warning", "step_warning", "untrusted"))
    if d["stable"] != ref["stable"] and not marked:
        return False, (
            f"JSON verdict {d['verdict']!r} at trapezoid 0.2 s vs {ref['verdict']!r} "
            "at 5 ms; no field marks the step warning (stderr only)"
        )
    return True, f"verdict {d['verdict']} (ref {ref['verdict']}), marked={marked}"


@probe("J6-03")
def _():
    """trapezoid at 0.5 s: the run fails; the error should say the step is the cause
    (and the one-cycle warning is not printed on this path)."""
    rc, _out, err = run(
        [
            "simulate",
            "kundur",
            *FAULT,
            "--clear-cycles",
            "6",
            "--method",
            "trapezoid",
            "--step",
            "0.5",
        ]
    )
    if rc == 2 and "Traceback" not in err and ("--step" in err or "too large" in err):
        return True, "refused naming the step: " + last(err, 160)
    return False, (
        f"rc {rc}: '{last(err, 160)}' - neither names the step nor prints the "
        f"trapezoid warning (warning printed: {'trapezoid step' in err})"
    )


@probe("J6-04")
def _():
    """--check-step on a trapezoid run must not advise '--method trapezoid'."""
    _rc, out, _err = run(
        [
            "simulate",
            "kundur",
            *FAULT,
            "--clear-cycles",
            "9.1",
            "--method",
            "trapezoid",
            "--step",
            "0.0166",
            "--check-step",
        ]
    )
    line = next((ln for ln in out.splitlines() if ln.startswith("step check")), "")
    if "--method trapezoid" in line:
        return False, (
            "--method trapezoid run's step check advises: " + line[line.rfind("(") :][:110]
        )
    return True, line[:160]


for _pid, _cmd in [
    ("J6-05", ["cct", "kundur", *FAULT, "--step", "0.25"]),
    ("J6-06", ["screen", "kundur", "--buses", "3", "--step", "0.25", "--out", "s6.jsonl"]),
    ("J6-07", ["estimate", "rmse", "kundur", *FAULT, "--runs", "1", "--step", "0.25"]),
    (
        "J6-08",
        ["sweep-cct", "kundur", "--faults", "DEFAULT", "--step", "0.25", "--out", "w8.jsonl"],
    ),
    (
        "J6-09",
        ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "10", "--step", "0.25"],
    ),
    (
        "J6-10",
        ["estimate", "cct", "kundur", *FAULT, "--esd-pct", "5", "--runs", "1", "--step", "0.25"],
    ),
    (
        "J6-11",
        ["pmu", "plant", "kundur", *FAULT, "--esd-pct", "5", "--port", "0", "--step", "0.25"],
    ),
    ("J6-12", ["estimate", "closed-loop", "kundur", *FAULT, "--esd-pct", "5", "--step", "0.25"]),
]:
    probe(_pid)(lambda c=_cmd: refused(c, r"step"))


@probe("J6-13")
def _():
    """steps in odd formats and values: each refused with one error line."""
    bad = [
        "0x10",
        "10ms",
        "1/100",
        "nan",
        "inf",
        "-0.01",
        "0",
        "-0",
        "1_0e-3",
        "\uff10.01",
        "1e-300",
        "1e-9",
        "",
    ]
    fails = []
    for s in bad:
        ok, why = refused(["simulate", "kundur", "--tf", "1", "--step", s], timeout=120)
        if not ok:
            fails.append(f"{s!r}: {why}")
    return (not fails), (f"all {len(bad)} refused") if not fails else "; ".join(fails)[:300]


@probe("J6-14")
def _():
    """Heun between T and 2T on cct: warned or refused, never a bare result."""
    rc, out, err = run(["cct", "kundur", *FAULT, "--step", "0.0185"])
    if "Traceback" in err:
        return False, "traceback"
    if rc == 2 or "above the fastest time constant" in err:
        return True, f"rc {rc}: {last(err, 160)}"
    return False, f"rc {rc} without warning: {last(out)}"


@probe("J6-15")
def _():
    """Python API: Simulator.run(h=0.2, method='trapezoid') warns (UserWarning)."""
    rc, out, err = py(
        textwrap.dedent("""
        import warnings, stabctl
        case = stabctl.load_case("kundur")
        sim = stabctl.Simulator(case)
        f = stabctl.fault_with_clearing(case, 3, 101, 1.0, 6)
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            r = sim.run([f], t_end=6.0, h=0.2, method="trapezoid")
        print("STABLE", r.stable, "WARN", any("trapezoid step" in str(x.message) for x in w))
    """)
    )
    m = re.search(r"STABLE (\w+) WARN (\w+)", out)
    if not m:
        return False, f"rc {rc}: {last(err)}"
    return m.group(2) == "True", f"stable={m.group(1)}, warned={m.group(2)}"


@probe("J6-16")
def _():
    """A step longer than the fault (1 cycle, step 9.9 ms) and not a divisor of its
    times: the clearing is still on the grid."""
    return runs_ok(
        [
            "simulate",
            "kundur",
            *FAULT,
            "--clear-cycles",
            "1",
            "--step",
            "0.0099",
            "--t-fault",
            "1.0037",
        ],
        r"after 16\.7 ms",
        "out",
    )


@probe("J6-17")
def _():
    """pstess conventions with a step above T_R: warned."""
    return runs_ok(
        ["simulate", "kundur", "--conventions", "pstess", "--step", "0.015", *FAULT],
        r"above the fastest time constant",
        "err",
    )


@probe("J6-18")
def _():
    """estimate rmse at --rate 120 with a 9.9 ms step (frames denser than steps): runs."""
    return runs_ok(
        [
            "estimate",
            "rmse",
            "kundur",
            *FAULT,
            "--runs",
            "1",
            "--rate",
            "120",
            "--step",
            "0.0099",
            "--ambient-s",
            "0",
        ],
        r"ekf",
    )


# ------------------------------------------------------------- item 7: recordings ---------

MKREC = r"""
import sys, numpy as np, stabctl
from stabctl.dynamics.events import fault_with_clearing
from stabctl.estimation import c37, pmu as pm
from stabctl.estimation.settings import PMUSettings
def make(casename, bus, far, cycles, tf, rate=60, seed=1):
    case = stabctl.load_case(casename)
    res = stabctl.Simulator(case).run([fault_with_clearing(case, bus, far, 1.0, cycles)], t_end=tf)
    pmus = pm.machine_pmus(case)
    drawn = pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(rate=rate), seed=seed)
    return c37.stream_config(case, pmus, rate), list(drawn)
cfg, fr = make("kundur", 3, 101, 6, 6.0)
c37.record("base.c37", cfg, fr)
c37.record("other_fault.c37", cfg, make("kundur", 13, 120, 6, 6.0)[1])
c37.record("other_clear.c37", cfg, make("kundur", 3, 101, 9, 6.0)[1])
g = list(fr); f = g[100]; v = f.v.copy(); v[1] = complex(np.nan, np.nan); g[100] = f._replace(v=v)
c37.record("nanphasor.c37", cfg, g)
m = np.array([1, 0, 1, 1], bool)
g = [f._replace(valid=f.valid & m, v=np.where(m, f.v, np.nan), i=np.where(m, f.i, np.nan),
     freq=np.where(m, f.freq, np.nan), rocof=np.where(m, f.rocof, np.nan)) for f in fr]
c37.record("one_absent.c37", cfg, g)
c37.record("gap.c37", cfg, fr[:120] + fr[150:])
c37.record("gap2.c37", cfg, fr[:120] + fr[240:])
g = list(fr); f = g[200]; q = f.freq.copy(); q[0] = 75.0; g[200] = f._replace(freq=q)
c37.record("freqhigh.c37", cfg, g)
c37.record("short.c37", cfg, fr[:180])
c37.record("late.c37", cfg, fr[90:])
c37.record("halfrate.c37", cfg, fr[::2])
c37.record("wecc.c37", *make("miniwecc", 83, 33, 6, 3.0))
print("RECORDED")
"""
REC_OK = None


def recordings():
    global REC_OK
    if REC_OK is None:
        _rc, out, err = py(MKREC, timeout=600)
        REC_OK = "RECORDED" in out
        if not REC_OK:
            print("recordings not made:", last(err), flush=True)
    return REC_OK


RMSE = ["estimate", "rmse", "kundur", *FAULT, "--clear-cycles", "6", "--tf", "6"]


def with_recs(fn):
    def inner():
        if not recordings():
            return False, "could not make the recordings (pyc37 missing?)"
        return fn()

    return inner


probe("J7-01")(with_recs(lambda: runs_ok([*RMSE, "--source", "base.c37"], r"ekf")))
probe("J7-02")(
    with_recs(lambda: refused([*RMSE, "--source", "other_fault.c37"], "do not measure this run"))
)
probe("J7-03")(
    with_recs(lambda: refused([*RMSE, "--source", "other_clear.c37"], "do not measure this run"))
)
probe("J7-04")(with_recs(lambda: refused([*RMSE, "--source", "wecc.c37"], "not a PMU of this run")))
probe("J7-05")(
    with_recs(
        lambda: refused(
            [
                "estimate",
                "track",
                "kundur",
                "--source",
                "base.c37",
                "--out",
                "t5.csv",
                "--rate",
                "30",
            ],
            "DATA_RATE 60",
        )
    )
)
probe("J7-06")(
    with_recs(lambda: refused([*RMSE, "--source", "base.c37", "--rate", "30"], "DATA_RATE 60"))
)
probe("J7-07")(
    with_recs(
        lambda: runs_ok(
            [*RMSE, "--source", "nanphasor.c37"], r"1 PMU values not used as marked absent"
        )
    )
)
probe("J7-08")(
    with_recs(lambda: refused([*RMSE, "--source", "one_absent.c37"], "B2:G2's values unusable"))
)
probe("J7-09")(with_recs(lambda: runs_ok([*RMSE, "--source", "gap.c37"], r"120 missing")))
probe("J7-10")(with_recs(lambda: refused([*RMSE, "--source", "gap2.c37"], "gap longer than")))
probe("J7-11")(with_recs(lambda: refused([*RMSE, "--source", "short.c37"], "short of the run")))
probe("J7-12")(with_recs(lambda: runs_ok([*RMSE, "--source", "halfrate.c37"], r"720 missing")))


@probe("J7-13")
@with_recs
def _():
    """A recording that starts 1.5 s in (after the fault at 1 s and after the error
    window's start, 1.2 s): refused or at least named, as one that ends early is."""
    rc, out, err = run([*RMSE, "--source", "late.c37"])
    if rc == 2 and "error:" in err:
        return True, "refused: " + last(err, 160)
    win = re.search(r"errors in mHz from ([\d.]+) s", out)
    miss = re.search(r"(\d+) missing", out)
    return False, (
        f"rc {rc}: accepted; errors labelled 'from {win and win.group(1)} s' though "
        f"the first frame is at 1.5 s; '{miss and miss.group(0)}' (90 reporting "
        "instants before the first frame not counted)"
    )


@probe("J7-14")
@with_recs
def _():
    """One data frame (STAT ok, CRC ok) reading FREQ = 75 Hz at G1 on a 60 Hz case:
    estimate track --estimator raw --esd-pct 5 should not use it (c37.plausible bounds
    V, I and ROCOF, not FREQ) and must not command every ESD from it."""
    rc, _out, err = run(
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            "freqhigh.c37",
            "--out",
            "fh.csv",
            "--estimator",
            "raw",
            "--esd-pct",
            "5",
        ]
    )
    if rc != 0:
        return True, f"rc {rc}: {last(err)}"
    import csv

    rows = list(csv.DictReader(io.StringIO(Path(WORK, "fh.csv").read_text())))
    row = next(r for r in rows if abs(float(r["t_s"]) - 200 / 60) < 1e-6)
    modes = [v for k, v in row.items() if k.startswith("mode_")]
    if float(row["f_B1:G1_hz"]) > 70 and any(m != "0" for m in modes):
        return False, (
            f"exit 0; at t = 3.333 s f_G1 = {row['f_B1:G1_hz']} Hz, f_coi = "
            f"{row['f_coi_hz']} Hz, ESD modes {modes} (0 the frames before and "
            "after); stderr/stdout name nothing implausible"
        )
    return True, f"frame not used (f_G1 {row['f_B1:G1_hz']}, modes {modes})"


@probe("J7-15")
@with_recs
def _():
    """The same glitch in estimate rmse --source: named as an implausible value, not as
    'another case, fault or clearing'."""
    rc, out, err = run([*RMSE, "--source", "freqhigh.c37"])
    if rc == 2 and "another case, fault or clearing" in err:
        return False, "one bad FREQ sample refuses the recording as " + last(err, 170)
    return True, f"rc {rc}: {last(err) or last(out)}"


# ------------------------------------------------------------- item 8: imports -----------

TB_RAW = os.path.join(CLONE, "tests/data/psse_runs/GENROU/ThreeBusMulti.raw")
GEN = (
    "    101 'GENCLS' 1 0.0 0.0 /\n"
    "    102 'GENROU' 1 8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8 /\n"
)
DYR = {
    "J8-01": ("h0", GEN.replace("6.175 0.05 1.8", "0.0 0.05 1.8"), "H = 0"),
    "J8-02": ("nan", GEN.replace("0.2 0.1 0.8", "0.2 nan 0.8"), "not a finite number"),
    "J8-03": ("negT", GEN.replace("1 8.0 0.03", "1 -8.0 0.03"), r"T'do = -8"),
    "J8-04": ("short", GEN.replace(" 0.25 0.2 0.1 0.8 /", " /"), "parameters"),
    "J8-05": ("negD", GEN.replace("6.175 0.05", "6.175 -0.5"), "D = -0.5"),
    "J8-06": ("tdo0", GEN.replace("1 8.0 0.03", "1 0.0 0.03"), r"T'do"),
    "J8-07": ("sexs", GEN + "    102 'SEXS' 1 0.4 5.0 20.0 1.0 50.0 -50.0 /\n", "upper limit"),
    "J8-08": ("tgovR", GEN + "    102 'TGOV1' 1 0.0 0.2 1.2 0.1 0.3 0.8 0 /\n", "droop"),
    "J8-09": (
        "ieeest",
        GEN + "    102 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n"
        "    102 'IEEEST' 1 1 0 0 0 0 0 0 0.0 0 0 0 -0.02 1.65 1.65 100 0.1 -0.1 0 0 /\n",
        "T4",
    ),
    "J8-10": ("inf", GEN.replace("6.175", "inf"), "not a finite number"),
    "J8-11": ("dup", GEN + GEN.splitlines(True)[1], "second machine model"),
}
for _pid, (_name, _text, _pat) in DYR.items():

    def _p(name=_name, text=_text, pat=_pat):
        write(name + ".dyr", text)
        return refused(["import-psse", TB_RAW, name + ".dyr", "-o", name + ".json"], pat)

    probe(_pid)(_p)

REN = os.path.join(CLONE, "tests/data/psse_runs/RENA_DEFAULT")
for _pid, (_name, _old, _new, _pat) in {
    "J8-12": (
        "tgneg",
        "0.20000E-01   10.000      0.90000",
        "-0.20000E-01   10.000      0.90000",
        "Tg",
    ),
    "J8-13": ("imax0", "1.1100         0.20000E-01", "0.0000         0.20000E-01", "Imax"),
    "J8-14": (
        "femax",
        "99.000         -99.000          1.2000",
        "-99.000         99.000          1.2000",
        "femax",
    ),
    "J8-15": ("iqr", "100.00      -100.00", "-100.00      100.00", "Iqrmax"),
}.items():

    def _p(name=_name, old=_old, new=_new, pat=_pat):
        base = Path(REN, "ThreeBus_REN_A_DEFAULT_FLAG.dyr").read_text()
        assert old in base
        write("ren_" + name + ".dyr", base.replace(old, new, 1))
        return refused(
            [
                "import-psse",
                os.path.join(REN, "ThreeBusRenewable.raw"),
                "ren_" + name + ".dyr",
                "-o",
                "ren_" + name + ".json",
            ],
            pat,
        )

    probe(_pid)(_p)

ANDES_SRC = None


def andes_variant(name, edit):
    global ANDES_SRC
    if ANDES_SRC is None:
        import importlib.util

        spec = importlib.util.find_spec("andes")
        ANDES_SRC = os.path.join(os.path.dirname(spec.origin), "cases/kundur/kundur_full.json")
    d = json.loads(Path(ANDES_SRC).read_text())
    edit(d)
    path = os.path.join(WORK, name + ".json")
    Path(path).write_text(json.dumps(d))
    return path


ANDES = {
    "J8-20": ("M0", lambda d: d["GENROU"][1].__setitem__("M", 0.0), r"M = 0"),
    "J8-21": ("Mnan", lambda d: d["GENROU"][1].__setitem__("M", float("nan")), r"M missing"),
    "J8-22": ("Mneg", lambda d: d["GENROU"][1].__setitem__("M", -13.0), r"M = -13"),
    "J8-23": ("Td20", lambda d: d["GENROU"][2].__setitem__("Td20", -0.03), r"Td20"),
    "J8-24": ("xd", lambda d: d["GENROU"][0].pop("xd"), r"xd missing"),
    "J8-25": ("R0", lambda d: d["TGOV1"][0].__setitem__("R", 0.0), r"R = 0"),
    "J8-26": ("T1", lambda d: d["TGOV1"][0].__setitem__("T1", -0.49), r"T1 = -0.49"),
    "J8-27": ("KEtext", lambda d: d["EXDC2"][0].__setitem__("KE", "abc"), r"not a number"),
    "J8-28": ("Sn0", lambda d: d["GENROU"][0].__setitem__("Sn", 0.0), r"must be > 0"),
    "J8-29": ("TE0", lambda d: d["EXDC2"][0].__setitem__("TE", 0.0), r"TE = 0"),
    "J8-30": ("VR", lambda d: d["EXDC2"][0].__setitem__("VRMAX", -5.0), r"upper limit"),
}
for _pid, (_name, _edit, _pat) in ANDES.items():

    def _p(name=_name, edit=_edit, pat=_pat):
        path = andes_variant("a_" + name, edit)
        return refused(["import-andes", path, "-o", "o_" + name + ".json"], pat)

    probe(_pid)(_p)


@probe("J8-31")
def _():
    """A NaN exciter gain (EXDC2 KA) is run at ANDES's default: named in the summary
    (documented: AndesImport.defaulted)."""
    path = andes_variant("a_KAnan", lambda d: d["EXDC2"][0].__setitem__("KA", float("nan")))
    return runs_ok(
        ["import-andes", path, "-o", "o_KAnan.json"],
        r"not given in the file, run at ANDES's: EXDC2 KA = 40",
    )


for _pid, _cmd in [
    ("J8-40", ["cct", "kundur", *FAULT, "--esd-model", "wecc"]),
    (
        "J8-41",
        ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-model", "wecc", "--out", "e41.jsonl"],
    ),
    ("J8-42", ["estimate", "rmse", "kundur", *FAULT, "--esd-model", "wecc", "--runs", "1"]),
    ("J8-43", ["simulate", "kundur", "--hysteresis-hz", "0.01"]),
    ("J8-44", ["cct", "kundur", *FAULT, "--coi", "rest"]),
    ("J8-45", ["estimate", "closed-loop", "kundur", *FAULT, "--esd-model", "wecc"]),
]:
    probe(_pid)(lambda c=_cmd: refused(c, r"without --esd-pct|--esd-pct"))

# ------------------------------------------------------------- item 9: faults ------------

for _pid, _cmd, _pat in [
    ("J9-01", ["cct", "kundur", "--fault", "3", "--far-bus", "13"], "no branch"),
    ("J9-02", ["cct", "kundur", *FAULT, "--circuit", "3"], "does not exist"),
    ("J9-03", ["cct", "kundur", "--fault", "3", "--far-bus", "3"], "no branch"),
    ("J9-04", ["simulate", "kundur", "--bus-fault", "3", "1", "0.9"], "T_ON <= T_OFF"),
    (
        "J9-05",
        ["simulate", "kundur", *FAULT, "--clear-cycles", "6", "--far-clear-cycles", "3"],
        "far end",
    ),
    ("J9-06", ["cct", "kundur", *FAULT, "--trip", "3", "101"], "faulted circuit"),
    (
        "J9-07",
        ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "13", "--runs", "1"],
        "no branch",
    ),
    ("J9-08", ["pmu", "serve", "kundur", "--fault", "3", "--far-bus", "101:2"], "far-bus|integer"),
    ("J9-09", ["simulate", "kundur", *FAULT, "--t-fault", "-1"], "t-fault|T_FAULT|>= 0|range"),
    ("J9-10", ["cct", "kundur", "--fault", "3", "--circuit", "2"], "circuit"),
]:
    probe(_pid)(lambda c=_cmd, p=_pat: refused(c, p))

CSVS = {
    "J9-20": ("bus,far_bus,extra\n3,101,1\n", "unknown"),
    "J9-21": ("bus\n3\n", "missing"),
    "J9-22": ("bus,far_bus\n3.0,101\n", "not an integer"),
    "J9-23": ("bus,far_bus\n3,101,\n", "field"),
    "J9-24": ("bus,far_bus,t_fault\n3,101,-1\n", "outside"),
    "J9-25": ("bus,far_bus,t_fault\n3,101,nan\n", "outside|finite"),
    "J9-26": ("bus,far_bus\n3,101\n3,101\n", "twice"),
    "J9-27": ("bus,far_bus,circuit\n3,,2\n", "circuit"),
    "J9-28": ("bus,far_bus\n3,13\n", "no branch"),
    "J9-29": ("bus,far_bus,circuit\n3,101,3\n", "does not exist"),
}
for _pid, (_text, _pat) in CSVS.items():

    def _p(pid=_pid, text=_text, pat=_pat):
        write(pid + ".csv", text)
        return refused(
            [
                "sweep-cct",
                "kundur",
                "--faults",
                pid + ".csv",
                "--out",
                pid + ".jsonl",
                "--workers",
                "1",
            ],
            pat,
        )

    probe(_pid)(_p)


@probe("J9-30")
def _():
    """place with the same bad list (far bus not adjacent) refused naming file:line."""
    write("p30.csv", "bus,far_bus\n3,13\n")
    return refused(
        ["place", "kundur", "--faults", "p30.csv", "--target-cct-gain", "10"], r"p30\.csv:2"
    )


@probe("J9-31")
def _():
    """cct --fault 1 (a generator terminal, no far bus): labelled a bus fault."""
    return runs_ok(
        ["cct", "kundur", "--fault", "1"],
        r"fault at bus 1 at 1 s, cleared without loss of a line",
        "out",
    )


@probe("J9-32")
def _():
    """A step-up transformer fault (1-10) labels the islanded machine."""
    return runs_ok(
        ["cct", "kundur", "--fault", "1", "--far-bus", "10"],
        r"islanded with machine\(s\) G1",
        "out",
    )


@probe("J9-33")
def _():
    """circuit 2 of the parallel pair is labelled as circuit 2."""
    return runs_ok(["cct", "kundur", *FAULT, "--circuit", "2"], r"line 3-101 \(circuit 2\)", "out")


@probe("J9-34")
def _():
    """--json of a bus fault CCT says it is a bus fault (far_bus null)."""
    rc, out, err = run(["cct", "kundur", "--fault", "3", "--json"])
    if rc != 0:
        return False, f"rc {rc}: {last(err)}"
    blob = json.loads(out)
    s = json.dumps(blob)
    return ('"far_bus": null' in s or "bus fault" in s), s[:160]


# ------------------------------------------------------------- crash variants ------------

for _pid, _cmd, _pat in [
    (
        "JC-01",
        ["estimate", "track", "kundur", "--source", "tcp://127.0.0.1:5-1", "--out", "t.csv"],
        "empty",
    ),
    (
        "JC-02",
        ["estimate", "track", "kundur", "--source", "tcp://127.0.0.1:0-3", "--out", "t.csv"],
        "out of range",
    ),
    (
        "JC-03",
        ["estimate", "track", "kundur", "--source", "tcp://[::1]:1-70000", "--out", "t.csv"],
        "out of range",
    ),
    (
        "JC-04",
        ["estimate", "track", "kundur", "--source", "tcp://:4712", "--out", "t.csv"],
        "HOST:PORT",
    ),
    (
        "JC-05",
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            "tcp://127.0.0.1:1-" + "9" * 30,
            "--out",
            "t.csv",
        ],
        "out of range",
    ),
    (
        "JC-06",
        ["estimate", "rmse", "kundur", *FAULT, "--source", "tcp://127.0.0.1:65535-65536"],
        "out of range",
    ),
    ("JC-07", ["pmu", "serve", "kundur", *FAULT, "--each-pmu", "--port", "65533"], "beyond 65535"),
    ("JC-08", ["pmu", "plant", "kundur", *FAULT, "--esd-pct", "5", "--port", "65536"], "range"),
    ("JC-09", ["import-psse", "/dev/urandom", "-o", "x.json"], "not a regular file"),
    ("JC-10", ["import-andes", "/dev/zero", "-o", "x.json"], "not a regular file"),
    ("JC-11", ["import-psse", TB_RAW, "/dev/zero", "-o", "x.json"], "not a regular file"),
    (
        "JC-12",
        ["estimate", "track", "kundur", "--source", "/dev/zero", "--out", "t.csv"],
        "not a regular file",
    ),
    ("JC-13", ["pmu", "replay", "/dev/zero"], "not a regular file"),
    ("JC-14", ["simulate", "kundur", "--trip", "3", "101.0", "--t-trip", "1"], "integers"),
    ("JC-15", ["simulate", "kundur", "--bus-fault", "3.0:0:0.05", "1", "1.1"], "bus number"),
    ("JC-16", ["screen", "kundur", "--buses", "3.0", "--out", "c16.jsonl"], "not a bus number"),
    ("JC-17", ["simulate", "kundur", "--load-step", "4.0", "1", "0.1", "0"], "integer"),
    ("JC-18", ["simulate", "kundur", "--vref-step", "1.0", "1", "0.01"], "integer"),
    ("JC-19", ["estimate", "rmse", "kundur", *FAULT, "--ambient-runs", "1", "--drop", "1"], "drop"),
    (
        "JC-20",
        ["estimate", "closed-loop", "kundur", *FAULT, "--esd-pct", "5", "--drop", "1"],
        "drop",
    ),
]:
    probe(_pid)(lambda c=_cmd, p=_pat: refused(c, p))


@probe("JC-21")
def _():
    """estimate rmse with --drop 0.999 and ambient runs of 1: no traceback."""
    rc, out, err = run(
        [
            "estimate",
            "rmse",
            "kundur",
            *FAULT,
            "--ambient-runs",
            "1",
            "--drop",
            "0.999",
            "--runs",
            "1",
            "--ambient-s",
            "10",
        ],
        timeout=400,
    )
    if "Traceback" in err:
        return False, "traceback: " + last(err)
    return rc in (0, 2), f"rc {rc}: {last(err) if rc else last(out)}"


@probe("JC-22")
def _():
    """estimate closed-loop with --drop 0.999: no traceback, says the frames were lost."""
    rc, out, err = run(
        ["estimate", "closed-loop", "kundur", *FAULT, "--esd-pct", "5", "--drop", "0.999"],
        timeout=400,
    )
    if "Traceback" in err:
        return False, "traceback: " + last(err)
    return rc in (0, 2), f"rc {rc}: {last(err) if rc else last(out, 120)}"


@probe("JC-23")
def _():
    """deeply nested JSON: a case, its events, a --screening line, a sweep --out line."""
    json.loads(run(["cases", "kundur", "--json"])[1]) if False else None
    write("deep.json", '{"tables":' + "[" * 100000 + "]" * 100000 + "}")
    write("deep_sc.jsonl", '{"key":' + "[" * 60000 + "]" * 60000 + "}\n")
    shutil.copy(os.path.join(WORK, "deep_sc.jsonl"), os.path.join(WORK, "deep_out.jsonl"))
    res = [
        refused(["simulate", "deep.json", "--tf", "1"], "nested"),
        refused(
            [
                "place",
                "kundur",
                "--faults",
                "DEFAULT",
                "--target-cct-gain",
                "10",
                "--screening",
                "deep_sc.jsonl",
            ],
            "deep_sc.jsonl",
        ),
    ]
    rc, _out, err = run(
        ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", "deep_out.jsonl", "--workers", "1"]
    )
    res.append(
        (
            "Traceback" not in err and rc == 0 and "damaged" in err,
            f"sweep --out: rc {rc} {last(err, 100)}",
        )
    )
    bad = [w for ok, w in res if not ok]
    return (not bad), "all clean" if not bad else "; ".join(bad)


@probe("JC-24")
def _():
    """--esd-model wecc with --json, --check-step, --out npz and --plot at once."""
    return runs_ok(
        [
            "simulate",
            "kundur",
            *FAULT,
            "--esd-pct",
            "5",
            "--esd-model",
            "wecc",
            "--check-step",
            "--json",
            "--out",
            "w.npz",
            "--plot",
            "w.png",
        ],
        r'"step_check"',
        "out",
    )


@probe("JC-25")
def _():
    """a converter case (ANDES ieee14_pvd1): eig --report --json, cct --json, estimate
    rmse --json."""
    import importlib.util

    src = os.path.join(
        os.path.dirname(importlib.util.find_spec("andes").origin), "cases/ieee14/ieee14_pvd1.json"
    )
    ok, why = runs_ok(["import-andes", src, "-o", "pvd1.json"])
    if not ok:
        return ok, "import: " + why
    bad = []
    for c in (
        ["eig", "pvd1.json", "--no-q-limits", "--report", "--json", "--out-dir", "rep"],
        [
            "cct",
            "pvd1.json",
            "--no-q-limits",
            "--fault",
            "4",
            "--far-bus",
            "5",
            "--esd-pct",
            "5",
            "--json",
        ],
        [
            "estimate",
            "rmse",
            "pvd1.json",
            "--no-q-limits",
            "--fault",
            "4",
            "--far-bus",
            "5",
            "--runs",
            "1",
            "--ambient-s",
            "0",
            "--json",
        ],
        [
            "simulate",
            "pvd1.json",
            "--no-q-limits",
            "--fault",
            "4",
            "--far-bus",
            "5",
            "--esd-pct",
            "5",
            "--esd-model",
            "wecc",
            "--json",
        ],
    ):
        ok, why = runs_ok(c)
        if not ok:
            bad.append(f"{c[0]}: {why}")
    return (not bad), "all four ran" if not bad else "; ".join(bad)


@probe("JC-26")
def _():
    """a 3 GiB sparse case file is refused by size, not read."""
    path = os.path.join(WORK, "big.json")
    with open(path, "wb") as fh:
        fh.truncate(3 << 30)
    try:
        return refused(["simulate", "big.json", "--tf", "1"], "256 MiB")
    finally:
        os.remove(path)


# ------------------------------------------------------------- newcomer frictions --------


@probe("JN-01")
def _():
    """--scheduler local twice in one process through the API (main-guarded script)."""
    write(
        "twice.py",
        textwrap.dedent("""
        import os, stabctl
        from stabctl.parallel import run_sweep
        from stabctl.stability.cct import cct_jobs, SearchOptions
        def main():
            for k in range(2):
                jobs = cct_jobs("kundur", [stabctl.LineFault(3, 101, 1.0)],
                                search=SearchOptions(tol=0.005, t_max=0.5))
                run_sweep(jobs, f"twice_{k}.jsonl", workers=1, scheduler="local", progress=False)
                print("pass", k, flush=True)
        if __name__ == "__main__":
            main()
    """),
    )
    try:
        p = subprocess.run(
            [sys.executable, "twice.py"],
            cwd=WORK,
            env=ENV,
            capture_output=True,
            text=True,
            timeout=240,
        )
    except subprocess.TimeoutExpired:
        return False, "hung (240 s)"
    return ("pass 1" in p.stdout), f"rc {p.returncode}: {last(p.stdout)} {last(p.stderr, 120)}"


@probe("JN-02")
def _():
    """ANDES case importing and then simulate refusing it (Q limits): the message says
    what to give."""
    if not os.path.exists(os.path.join(WORK, "pvd1.json")):
        return False, "needs JC-25's import"
    return refused(["simulate", "pvd1.json", "--tf", "1"], r"--no-q-limits|Q limits")


@probe("JN-03")
def _():
    """`stabctl cases kundur --bus-table --line-table | head -1`: no traceback, status 0 or 141."""
    p = subprocess.run(
        "python -m stabctl cases kundur --bus-table --line-table | head -1; "
        "echo rc=${PIPESTATUS[0]}",
        shell=True,
        executable="/bin/bash",
        cwd=WORK,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=120,
    )
    rc = re.search(r"rc=(\d+)", p.stdout)
    ok = "Traceback" not in p.stderr and rc and rc.group(1) in ("0", "141") and not p.stderr.strip()
    return bool(ok), f"status {rc and rc.group(1)}, stderr {p.stderr.strip()[:80]!r}"


@probe("JN-04")
def _():
    """ModalAnalysis has a table view; simulate --out CSV columns carry units; machines
    named by bus."""
    _rc, out, _err = py(
        textwrap.dedent("""
        import stabctl
        sim = stabctl.Simulator(stabctl.load_case("kundur"))
        m = stabctl.modal_analysis(stabctl.linearise(sim))
        t = m.table() if callable(getattr(m, "table", None)) else None
        print("TABLE", type(t).__name__, str(t)[:80].replace("\\n", " | "))
    """)
    )
    ok1 = "TABLE" in out and "NoneType" not in out
    rc2, _out2, _err2 = run(["simulate", "kundur", "--tf", "0.1", "--out", "u.csv"])
    head = Path(WORK, "u.csv").read_text().split("\n", 1)[0] if rc2 == 0 else ""
    ok2 = "angle_rad.G1" in head and "speed_pu.G1" in head
    _rc3, out3, _err3 = run(["eig", "kundur"])
    ok3 = "G1 (bus 1)" in out3
    return ok1 and ok2 and ok3, f"table={ok1} ({last(out, 60)}), csv units={ok2}, eig names={ok3}"


@probe("JN-05")
def _():
    """Docs: en dashes in the CLI reference (smartquotes off), Kundur's book numbers in `cases`."""
    conf = Path(CLONE, "docs/conf.py").read_text()
    ok1 = re.search(r"^smartquotes\s*=\s*False", conf, re.M) is not None
    _rc, out, _err = run(["cases", "kundur"])
    ok2 = "Kundur's book" in out
    return ok1 and ok2, f"smartquotes off={ok1}, book map in cases={ok2}"


@probe("JN-06")
def _():
    """--help examples on their own lines (not run together)."""
    bad = []
    for c in (
        ["simulate"],
        ["cct"],
        ["place"],
        ["import-andes"],
        ["estimate", "rmse"],
        ["pmu", "serve"],
    ):
        _rc, out, _err = run([*c, "--help"], timeout=60)
        m = re.search(r"Examples?:\n(.*?)\n\n", out, re.S)
        if not m or any(ln.count("stabctl ") > 1 for ln in m.group(1).splitlines()):
            bad.append(" ".join(c))
    return (not bad), "examples one per line" if not bad else "run together: " + ", ".join(bad)


if __name__ == "__main__":
    try:
        n = len(RESULTS)
        short = [r for r in RESULTS if not r[1]]
        print(f"\n{n} probes, {n - len(short)} ok, {len(short)} SHORT")
        for pid, _ok, why in short:
            print(f"  SHORT {pid}: {why}")
    finally:
        shutil.rmtree(WORK, ignore_errors=True)
    sys.exit(1 if short else 0)
