"""Sixth reliability round (round 32, part B): results that could be silently wrong, labels
and units, PSS/E and ANDES imports, the Python API.

The numerical settings (a search limit off the tolerance's lattice, steps that do not
divide the event times, clearings inside one step, a 300 s run, the CCT tolerances and
fault times), the labels a result carries (cycles at 50 Hz, per-unit bases in the CSV,
which end of a line is faulted, the PMU reporting rates of a 50 Hz case), RAW/DYR and
ANDES files changed one thing at a time (each change named or refused by file and line),
and the Python API (results through npz and pickle, threads, a Simulator reused after an
exception, NumPy scalars and arrays as inputs, a relabelled state-space model).

Contract: each probe runs `stabctl` commands (in fresh processes, the package of this
repository first on PYTHONPATH) or the Python API in this process and states what a
careful tool does: a refused input ends with exit status 2 and one ``error:`` line naming
what, no traceback; a legitimate run exits 0 with the result the physics or the
documentation gives.  A search limit that is not a multiple of the CCT tolerance is
refused (N1: the refusal is the pass); an imported case is named after its RAW file (L3,
by design: an informational check).

    python benchmarks/reliability_probes_6.py [-k SUBSTRING] [ID ...]

ID: a probe's name or its prefix before the first ``_`` (``N1``, ``I4``).  One line per
probe (id, ok or SHORT, why), then the counts.  NUMBA_CACHE_DIR is the caller's (numba's
default when unset): run `stabctl compile` first for a warm cache.  The work directory is
a new temporary directory, removed at the end unless KEEP is set.  About 3 minutes on two
cores with a warm kernel cache.  Exit status 1 if any probe is short.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import threading
import traceback
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the package under test, in this process too
STABCTL = [sys.executable, "-m", "stabctl"]
ENV = dict(
    os.environ,
    PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]),
)
ENV.pop("PYTHONWARNINGS", None)
PSSE = ROOT / "tests" / "data" / "psse_runs"  # PSS/E runs: ThreeBusMulti and the others
GENROU_RAW = PSSE / "GENROU" / "ThreeBusMulti.raw"
GENROU_DYR = PSSE / "GENROU" / "ThreeBus_GENROU.dyr"
WORK = Path(tempfile.mkdtemp(prefix="stabctl-probes-6."))
RESULTS: list[tuple[str, bool, str]] = []
PROBES: list = []


def probe(fn):
    PROBES.append(fn)
    return fn


def sh(*args, timeout=300, cwd=None):
    """Run `stabctl args` -> (rc, stdout, stderr)."""
    try:
        p = subprocess.run(
            [*STABCTL, *map(str, args)],
            capture_output=True,
            text=True,
            timeout=timeout,
            env=ENV,
            cwd=cwd or WORK,
            stdin=subprocess.DEVNULL,
        )
    except subprocess.TimeoutExpired:
        return -9, "", "TIMEOUT"
    return p.returncode, p.stdout, p.stderr


def sjson(*args, **kw):
    """`sh` with --json -> (rc, the parsed JSON or None, stderr [+ stdout if not JSON])."""
    rc, out, err = sh(*args, "--json", **kw)
    try:
        return rc, json.loads(out), err
    except json.JSONDecodeError:
        return rc, None, err + out


def report(pid, ok, why):
    RESULTS.append((pid, ok, why))
    print(f"{pid:<38} {'ok   ' if ok else 'SHORT'} {why}", flush=True)


def has_traceback(text):
    return "Traceback (most recent call last)" in text


def error_lines(text):
    return [line for line in text.splitlines() if line.startswith("error:")]


def read_json(path):
    with open(path) as f:
        return json.load(f)


def write_text(path, text):
    with open(path, "w") as f:
        f.write(text)


def case_at_50hz(name):
    """Kundur's case written as JSON with freq_hz 50 -> its path."""
    import stabctl
    from stabctl.io.pst import write_case_json

    path = WORK / name
    write_case_json(stabctl.load_case("kundur"), path)
    d = read_json(path)
    d["freq_hz"] = 50
    write_text(path, json.dumps(d))
    return path


# ---------------------------------------------------------------- 1. numerical settings


@probe
def N1_cct_tmax_off_lattice_json():
    """--t-max not a multiple of the CCT tolerance (0.1545 s, tolerance 1 ms): the search
    clears on multiples of the tolerance, so it would test 0.154 s at most and call a fault
    stable there robust up to 0.1545 s (true CCT 0.1541 s).  The fixed behaviour: refused,
    exit 2, one error line naming "not a multiple of the CCT tolerance" (the pass)."""
    pid = "N1_cct_tmax_off_lattice_json"
    rc, out, err = sh("cct", "kundur", "--fault", 3, "--far-bus", 101, "--t-max", 0.1545, "--json")
    errs = error_lines(err)
    needle = "not a multiple of the CCT tolerance"
    ok = rc == 2 and len(errs) == 1 and needle in errs[0] and not has_traceback(err)
    if ok:
        why = f"refused: {errs[0][:120]}"
    else:
        why = f"want exit 2 naming {needle!r}; exit {rc}, {len(errs)} error line(s): "
        why += (errs[-1] if errs else (err + out).strip()[-150:])[:150]
    report(pid, ok, why)


@probe
def N2_screen_tmax_off_lattice_table():
    rc, o, _ = sh(
        "screen", "kundur", "--buses", 3, "--lines", "--t-max", 0.16, "--tol-ms", 50,
        "--workers", 1, "--out", WORK / "scr.jsonl", timeout=600,
    )  # fmt: skip
    row = [ln for ln in o.splitlines() if ln.startswith("bus 3 line to 101 ") and ">" in ln]
    bad = bool(row) and ">0.160" in row[0]
    report(
        "N2_screen_tmax_off_lattice_table",
        not bad,
        f"rc={rc}; row {row[0].strip() if row else None!r}: the table claims CCT > 0.160 s, "
        "only 0.150 s was run, true CCT 0.154 s",
    )


@probe
def N3_sweep_tmax_off_lattice_table():
    faults = WORK / "f.csv"
    write_text(faults, "bus,far_bus\n3,101\n")
    rc, o, _ = sh(
        "sweep-cct", "kundur", "--faults", faults, "--t-max", 0.1545, "--workers", 1,
        "--out", WORK / "sw.jsonl", timeout=600,
    )  # fmt: skip
    row = [ln for ln in o.splitlines() if ln.startswith("kundur/3-101")]
    bad = bool(row) and "t_max = 0.1545" in row[0]
    report(
        "N3_sweep_tmax_off_lattice_table",
        not bad,
        f"rc={rc}; row {row[0].strip() if row else None!r} "
        "(searched up to 0.154 s only; CCT 0.1541 s)",
    )


@probe
def N4_simulate_step_vs_half_step():
    """Every method at steps that do not divide the event times: a verdict that changes at
    h/2 must come with a warning."""
    silent = []
    n = 0
    for m in ("heun", "trapezoid"):
        for h in (0.0037, 0.0073, 0.01, 0.0123):
            for cc in (6, 9.0):
                base = [
                    "simulate", "kundur", "--fault", 3, "--far-bus", 101,
                    "--clear-cycles", cc, "--method", m,
                ]  # fmt: skip
                rc1, d1, e1 = sjson(*base, "--step", h)
                rc2, d2, e2 = sjson(*base, "--step", h / 2)
                n += 1
                if d1 is None or d2 is None:
                    silent.append(f"{m} h={h} cc={cc}: rc {rc1}/{rc2} {(e1 + e2)[-120:]}")
                    continue
                if d1["verdict"] != d2["verdict"] and "warning" not in e1:
                    silent.append(
                        f"{m} h={h} cc={cc}: {d1['verdict']} vs {d2['verdict']} at h/2, no warning"
                    )
    report(
        "N4_simulate_step_vs_half_step",
        not silent,
        f"{n} pairs; " + ("; ".join(silent) or "verdicts agree or warned"),
    )


@probe
def N5_cct_tolerances():
    got = {}
    for tol in (0.1, 1, 50):
        rc, d, _ = sjson("cct", "kundur", "--fault", 3, "--far-bus", 101, "--tol-ms", tol)
        got[tol] = (rc, d and d.get("t_stable_s"), d and d.get("t_unstable_s"))
    rc, _, e = sh("cct", "kundur", "--fault", 3, "--far-bus", 101, "--tol-ms", 1000)
    consistent = all(
        r[0] == 0 and r[1] is not None and r[1] <= 0.1542 <= r[2] + 1e-12 for r in got.values()
    )
    refused = rc == 2 and e.startswith("error:") and not has_traceback(e)
    report(
        "N5_cct_tolerances",
        consistent and refused,
        f"brackets {got}; tol 1000 ms rc={rc} {e.strip()[:80]}",
    )


@probe
def N6_cct_fault_time_off_grid():
    ccts = {}
    for tf in (1.0, 1.0037, 0, 3.3333):
        _, d, _ = sjson("cct", "kundur", "--fault", 3, "--far-bus", 101, "--t-fault", tf)
        ccts[tf] = d and d.get("cct_s")
    report("N6_cct_fault_time_off_grid", len(set(ccts.values())) == 1, f"CCT by fault time {ccts}")


@probe
def N7_clear_cycles_fraction_of_step():
    bad = []
    for cc in (0.01, 0.1, 0.3):
        a = [
            sjson(
                "simulate", "kundur", "--fault", 3, "--far-bus", 101,
                "--clear-cycles", cc, "--step", h,
            )[1]
            for h in (0.005, 0.0025)
        ]  # fmt: skip
        if None in a:
            bad.append(f"cc {cc}: no result")
            continue
        d = abs(a[0]["max_angle_from_coi_rad"] - a[1]["max_angle_from_coi_rad"])
        if d > 1e-4 or a[0]["verdict"] != a[1]["verdict"]:
            bad.append(f"cc {cc}: max angle differs by {d:.2e} at h/2")
    report(
        "N7_clear_cycles_fraction_of_step",
        not bad,
        "; ".join(bad) or "a clearing inside one step converges (grid lands on it)",
    )


@probe
def N8_long_run_300s():
    rc, d, _ = sjson("simulate", "kundur", "--fault", 3, "--far-bus", 101, "--tf", 300)
    ok = rc == 0 and d and d["t_end_s"] == 300.0 and d["verdict"] == "stable"
    report(
        "N8_long_run_300s",
        bool(ok),
        f"rc={rc} steps={d and d['n_steps']} end={d and d['end_state']}",
    )


@probe
def N9_cct_warning_advises_missing_option():
    _, _, e = sh("cct", "kundur", "--fault", 3, "--far-bus", 101, "--step", 0.013)
    rc2, _, e2 = sh(
        "cct", "kundur", "--fault", 3, "--far-bus", 101, "--step", 0.013, "--check-step"
    )
    bad = "(--check-step)" in e and rc2 == 2
    last = e2.strip().splitlines()[-1][:90] if e2.strip() else ""
    report(
        "N9_cct_warning_advises_missing_option",
        not bad,
        f"cct's step warning ends '(--check-step)', but cct {last}",
    )


@probe
def N10_eig_perturbation_check():
    import stabctl
    from stabctl.smallsignal.linearise import perturbation_error

    cases = ["kundur", "miniwecc"]
    for sub, raw, dyr in (
        ("IEEEST", "ThreeBusMulti.raw", "ThreeBus_IEEEST.dyr"),
        ("EXST1", "TVC_System_32.raw", "TVC_System.dyr"),
    ):
        out = WORK / f"{sub}.json"
        sh("import-psse", PSSE / sub / raw, PSSE / sub / dyr, "-o", out)
        cases.append(str(out))
    worst = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for c in cases:
            case = stabctl.load_case(c)
            for rs, fac in ((1e-4, 100), (1e-5, 10)):
                e = perturbation_error(case, rel_step=rs, factor=fac)
                worst[(os.path.basename(c), rs)] = max(e["eig"], e["freq_hz"], e["damping"])
    bad = {k: v for k, v in worst.items() if v > 1e-3}
    report(
        "N10_eig_perturbation_check",
        not bad,
        f"largest eig/freq/damping change {max(worst.values()):.1e} over {len(worst)} checks",
    )


# ---------------------------------------------------------------- 2. labels and units


@probe
def L1_cycles_at_50hz():
    p50 = case_at_50hz("k50.json")
    _, c, _ = sjson("cct", p50, "--fault", 3, "--far-bus", 101)
    _, s, _ = sjson("simulate", p50, "--fault", 3, "--far-bus", 101, "--clear-cycles", 6)
    ok = (
        c
        and abs(c["cct_cycles"] - 50 * c["cct_s"]) < 1e-9
        and s
        and "after 120.0 ms" in s["events"][0]
    )
    report(
        "L1_cycles_at_50hz",
        bool(ok),
        f"cct {c and (c['cct_s'], c['cct_cycles'])}; 6 cycles -> {s and s['events'][0][-50:]}",
    )


@probe
def L2_csv_bases():
    out = WORK / "flat.csv"
    sh("simulate", "kundur", "--tf", 0.1, "--out", out)
    with open(out, newline="") as f:
        r = csv.reader(f)
        h = next(r)
        row = dict(zip(h, map(float, next(r))))
    pe, pm = row["pelect_pu.G1"], row["pmech_pu_mbase.G1"]
    ok = abs(pe - pm * 9.0) < 1e-6  # G1 900 MVA on a 100 MVA system base
    report(
        "L2_csv_bases",
        ok,
        f"pelect_pu.G1 {pe:.5f} (system) vs pmech_pu_mbase.G1*9 {pm * 9:.5f}",
    )


@probe
def L3_imported_case_name_is_raw_stem():
    """Two cases imported from one RAW file with different DYR files, written to
    variantA.json and variantB.json, are both named after the RAW file's stem ('case
    ThreeBusMulti' in the output of each).  By design (the case is the network of the RAW
    file; the output file's name is where it is written, not what it is called): an
    informational check, ok when both imports run and their names can be read."""
    a, b = WORK / "variantA.json", WORK / "variantB.json"
    sh("import-psse", GENROU_RAW, GENROU_DYR, "-o", a)
    nosat = PSSE / "GENROU_NO_SAT" / "ThreeBus_GENROU_NO_SAT.dyr"
    sh("import-psse", GENROU_RAW, nosat, "-o", b)
    la = sh("simulate", a, "--tf", 0.5)[1].splitlines()[:1]
    lb = sh("simulate", b, "--tf", 0.5)[1].splitlines()[:1]
    name_a = la[0].split(":")[0] if la else None
    name_b = lb[0].split(":")[0] if lb else None
    report(
        "L3_imported_case_name_is_raw_stem",
        bool(la and lb),
        f"by design: variantA.json -> {name_a!r}, variantB.json -> {name_b!r}",
    )


@probe
def L4_fault_ends_and_circuits():
    r1 = sjson("cct", "kundur", "--fault", 3, "--far-bus", 101)[1]
    r2 = sjson("cct", "kundur", "--fault", 101, "--far-bus", 3)[1]
    rc3, _, e3 = sh("cct", "kundur", "--fault", 3, "--far-bus", 13)
    rc4, _, e4 = sh("cct", "kundur", "--fault", 3, "--far-bus", 101, "--circuit", 3)
    ok = (
        r1
        and r2
        and r1["fault"]["bus"] == 3
        and r2["fault"]["bus"] == 101
        and r1["cct_s"] != r2["cct_s"]
        and rc3 == 2
        and rc4 == 2
        and not has_traceback(e3 + e4)
    )
    report(
        "L4_fault_ends_and_circuits",
        bool(ok),
        f"3->101 {r1 and r1['cct_s']} s, 101->3 {r2 and r2['cct_s']} s; "
        f"non-adjacent: {e3.strip()[:60]}; circuit 3: {e4.strip()[:60]}",
    )


@probe
def L5_pmu_rates_on_50hz_case():
    """A 50 Hz case: estimate rmse at --rate 50 and --rate 25 (C37.118.1's 50 Hz rates are
    10, 25, 50, 100 frames/s) and at the default rate all run."""
    p50 = case_at_50hz("k50e.json")
    args = (
        "estimate", "rmse", p50, "--fault", 3, "--far-bus", 101, "--runs", 1, "--ambient-s", 0,
    )  # fmt: skip
    rc50, _, e50 = sh(*args, "--rate", 50)
    rc25, _, _ = sh(*args, "--rate", 25)
    rc60, _, _ = sh(*args)
    ok = rc50 == 0 and rc25 == 0
    report(
        "L5_pmu_rates_on_50hz_case",
        ok,
        f"50 Hz case: --rate 50 rc={rc50} ({e50.strip()[:110]}); --rate 25 rc={rc25}; "
        f"default 60 frames/s rc={rc60}",
    )


# ---------------------------------------------------------------- 3. imports


def _raw_variants():
    """{name: (RAW text, DYR text, texts the import must print)}: ThreeBusMulti changed one
    thing at a time."""
    base = GENROU_RAW.read_text()
    dyr = GENROU_DYR.read_text()
    b4 = (
        "   104,'BUS 4', 138.0000,{ide},   1,   1,   1,1.00000,   0.0000,"
        "1.10000,0.90000,1.10000,0.90000\n"
    )
    load4 = (
        "   104,'1 ',1,   1,   1,   10.000,    3.000,     0.000,     0.000,     0.000,"
        "     0.000,   1,1,0\n"
    )
    br = (
        "   103,   104,'1 ', 0.00000E+0, {x},   0.00000,  250.00,  250.00,  250.00,  0.00000,"
        "  0.00000,  0.00000,  0.00000,1,1,   0.00,   1,1.0000\n"
    )
    genrou = " 0.03 0.4 0.05 {td} 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8 /\n"

    def add(s, sect, text):
        return s.replace(f" 0 /End of {sect}", text + f" 0 /End of {sect}", 1)

    g102 = next(ln for ln in base.splitlines() if ln.strip().startswith("102,'1 ',   100.000"))
    v = {}
    v["genoff"] = (
        base.replace(g102, g102.replace("1.00000,1,  100.0", "1.00000,0,  100.0")),
        dyr,
        [
            "generator at bus 102 '1': out of service",
            "GENROU (bus 102, id 1): its generator is out",
        ],
    )
    v["bus_ide4"] = (
        add(add(base, "Bus data", b4.format(ide=4)), "Load data", load4),
        dyr,
        ["bus 104: isolated (IDE 4)", "load at bus 104 '1'"],
    )
    z = add(
        add(add(base, "Bus data", b4.format(ide=1)), "Load data", load4),
        "Branch data",
        br.format(x="0.00000E+0"),
    )
    v["zero_impedance"] = (z, dyr, ["branch 103-104 '1': R + jX must not be 0"])
    parallel = br.replace("103,   104", "101,   102").replace("'1 '", "'9 '")
    v["parallel_ckt9"] = (
        add(base, "Branch data", parallel.format(x="1.20000E-1")),
        dyr,
        ["101-102 (in file order :1 is '1', :2 is '9')"],
    )
    v["quoted_comma"] = (base.replace("'BUS 2'", "'BUS, 2/x'"), dyr, [])
    v["area_record"] = (
        add(base, "Area interchange data", "   1,   101,    10.000,     5.000,'AREA, 1'\n"),
        dyr,
        [],
    )
    v["switched_shunt"] = (
        add(
            base,
            "Switched shunt data",
            "   103,1,0,1,1.05000,0.95000,     0,100.0,'            ',   50.00,   1,  50.00\n",
        ),
        dyr,
        ["switched shunt at bus 103: held at BINIT"],
    )
    v["dyr_no_machine"] = (
        base,
        dyr + "    103 'GENROU' 1 8.0" + genrou.format(td="6.175"),
        ["GENROU at bus 103 '1': matches no generator"],
    )
    v["dyr_two_models"] = (
        base,
        dyr + "    102 'GENROU' 1 5.0" + genrou.format(td="3.0"),
        ["second machine model for this generator"],
    )
    v["dyr_usrmdl"] = (
        base,
        dyr + "    102 'USRMDL' 1 'MYEXC' 4 0 2 3 0 0 1 2 1.0 2.0 3.0 /\n",
        ["USRMDL at bus 102 '1': model USRMDL is not mapped"],
    )
    v["dyr_unsupported"] = (
        base,
        dyr + "    102 'ESST6B' 1 0.1 10 100 0.1 0 4 /\n",
        ["ESST6B at bus 102 '1'"],
    )
    v["dyr_split_line"] = (
        base,
        dyr.replace("0.30000E-01  0.40000", "0.30000E-01\n  0.40000"),
        [],
    )
    v["dyr_unterminated"] = (
        base,
        dyr.rstrip().rstrip("/") + "\n",
        ["record not terminated by '/'"],
    )
    return v


@probe
def I1_psse_variants():
    bad = []
    variants = _raw_variants()
    for name, (raw, dyr, must) in variants.items():
        r, d, o = (WORK / f"{name}.{x}" for x in ("raw", "dyr", "json"))
        write_text(r, raw)
        write_text(d, dyr)
        rc, out, err = sh("import-psse", r, d, "-o", o)
        text = out + err
        if has_traceback(text) or rc not in (0, 2):
            bad.append(f"{name}: rc {rc} traceback")
        bad.extend(f"{name}: not named: {m!r}" for m in must if m not in text)
        if rc == 2 and o.exists():
            bad.append(f"{name}: refused but wrote {o}")
    report(
        "I1_psse_variants",
        not bad,
        "; ".join(bad)
        or f"{len(variants)} RAW/DYR variants: each change named or refused by file:line",
    )


@probe
def I2_psse_short_branch_unsolved_start():
    """A 0.001 pu branch to a new bus whose RAW voltage is still 1.0 pu at 0 deg: the power
    flow is started from the RAW voltages (magnitudes clipped to [0.5, 1.5]); the import
    must solve it, as it solves the same case started near the solution."""
    raw, dyr, _ = _raw_variants()["zero_impedance"]
    raw = raw.replace(
        "103,   104,'1 ', 0.00000E+0, 0.00000E+0", "103,   104,'1 ', 0.00000E+0, 1.00000E-3"
    )
    r, d = WORK / "short.raw", WORK / "short.dyr"
    write_text(r, raw)
    write_text(d, dyr)
    rc, _, err = sh("import-psse", r, d, "-o", WORK / "short.json")
    raw2 = raw.replace(
        "104,'BUS 4', 138.0000,1,   1,   1,   1,1.00000,   0.0000",
        "104,'BUS 4', 138.0000,1,   1,   1,   1,0.99341,  -8.7697",
    )
    r2 = WORK / "short2.raw"
    write_text(r2, raw2)
    rc2, _, _ = sh("import-psse", r2, d, "-o", WORK / "short2.json")
    report(
        "I2_psse_short_branch_unsolved_start",
        rc == 0,
        f"start 1.0/0 deg: rc={rc} {err.strip()[-110:]!r}; start near solution: rc={rc2}",
    )


@probe
def I3_psse_three_winding():
    base = GENROU_RAW.read_text()
    buses = "".join(
        f"   {n},'T3 {n}', {kv},1,   1,   1,   1,1.00000,   0.0000,"
        "1.10000,0.90000,1.10000,0.90000\n"
        for n, kv in ((104, "138.0000"), (105, " 69.0000"), (106, " 13.8000"))
    )
    load = (
        "   105,'1 ',1,   1,   1,   20.000,    5.000,     0.000,     0.000,     0.000,"
        "     0.000,   1,1,0\n"
    )
    branch = (
        "   103,   104,'1 ', 1.00000E-3, 1.00000E-2,   0.00000,  250.00,  250.00,  250.00,"
        "  0.00000,  0.00000,  0.00000,  0.00000,1,1,   0.00,   1,1.0000\n"
    )
    w = (
        "1.00000,   0.000,   0.000,  100.00,  100.00,  100.00, 0, 0, 1.10000, 0.90000,"
        " 1.10000, 0.90000,  33, 0, 0.00000, 0.00000,  0.000\n"
    )
    t3 = (
        "   104,   105,   106,'1 ',1,1,1, 0.00000E+0, 0.00000E+0,2,'T3W         ',1,   1,1.0000\n"
        " 0.00000E+0, 5.00000E-2,  100.00, 0.00000E+0, 8.00000E-2,  100.00,"
        " 0.00000E+0, 6.00000E-2,  100.00,1.00000,   0.0000\n" + w * 3
    )
    s = base
    for sect, text in (
        ("Bus data", buses),
        ("Load data", load),
        ("Branch data", branch),
        ("Transformer data", t3),
    ):
        s = s.replace(f" 0 /End of {sect}", text + f" 0 /End of {sect}", 1)
    r, o = WORK / "t3w.raw", WORK / "t3w.json"
    write_text(r, s)
    rc, _, _ = sh("import-psse", r, GENROU_DYR, "-o", o)
    x = {}
    if rc == 0:
        t = read_json(o)["tables"]["branches"]
        cols = t["columns"]
        for row in t["rows"]:
            rr = dict(zip(cols, row))
            x[(int(rr[cols[0]]), int(rr[cols[1]]))] = rr.get("x", rr.get(cols[3]))
    want = {(104, 107): 0.015, (105, 107): 0.035, (106, 107): 0.045}
    ok = rc == 0 and all(abs(x.get(k, -1) - v) < 1e-9 for k, v in want.items())
    report(
        "I3_psse_three_winding",
        ok,
        f"rc={rc}; star branch x (104, 105, 106 to star 107) = {[x.get(k) for k in want]}",
    )


@probe
def I4_andes_mutations():
    try:
        import andes
        import pandas as pd
    except ImportError as e:
        report("I4_andes_mutations", True, f"skipped: {e}")
        return
    src = andes.get_case("ieee14/ieee14_full.xlsx")
    sheets = pd.read_excel(src, sheet_name=None)

    def col(s, sheet, c, row, val):
        s[sheet][c] = s[sheet][c].astype(object)
        s[sheet].loc[row, c] = val

    def extra_column(s):
        s["PQ"]["foo"] = 1.0

    muts = {
        "nan_M": (lambda s: col(s, "GENROU", "M", 1, np.nan), "M missing"),
        "line_x_nan": (lambda s: col(s, "Line", "x", 3, np.nan), "x missing"),
        "pq_on_missing_bus": (lambda s: col(s, "PQ", "bus", 0, 99), "bus = 99"),
        "dup_pq_idx": (
            lambda s: col(s, "PQ", "idx", 1, s["PQ"]["idx"].iloc[0]),
            "both give idx",
        ),
        "str_param": (lambda s: col(s, "GENROU", "D", 1, "abc"), "not a number"),
        "extra_column": (extra_column, "column 'foo'"),
        "pq_u0": (lambda s: col(s, "PQ", "u", 0, 0), "PQ row 1 (idx PQ_1): out of service"),
    }
    bad = []
    for name, (f, must) in muts.items():
        s = {k: v.copy() for k, v in sheets.items()}
        f(s)
        x = WORK / f"{name}.xlsx"
        with pd.ExcelWriter(x) as w:
            for k, v in s.items():
                v.to_excel(w, sheet_name=k, index=False)
        rc, out, err = sh("import-andes", x, "-o", WORK / f"{name}.json", timeout=300)
        if has_traceback(out + err) or must not in out + err:
            bad.append(f"{name}: rc {rc}, {must!r} not named: {(out + err).strip()[-120:]}")
    report(
        "I4_andes_mutations",
        not bad,
        "; ".join(bad) or f"{len(muts)} ANDES xlsx mutations named",
    )


# ---------------------------------------------------------------- 4. Python API


@probe
def P1_result_roundtrips():
    import stabctl
    from stabctl import GeneratorTrip, LineTrip

    c = stabctl.load_case("kundur")
    sim = stabctl.Simulator(c)
    runs = {
        "unstable": [stabctl.fault_with_clearing(c, 3, 101, 1.0, 12.0)],
        "de-energised": [GeneratorTrip(k, 1.0) for k in (1, 2, 3, 4)],
        "split": [LineTrip(3, 101, 1.0, circuit=1), LineTrip(3, 101, 1.0, circuit=2)],
    }
    attrs = (
        "verdict", "stable", "t_separation", "separated", "de_energised_s", "max_angle_from_coi",
    )  # fmt: skip
    bad = []
    for name, ev in runs.items():
        r = sim.run(ev, t_end=5.0)
        f = WORK / f"{name}.npz"
        r.to_npz(f)
        loaded = (
            ("npz", stabctl.SimulationResult.from_npz(f)),
            ("pickle", pickle.loads(pickle.dumps(r))),
        )
        for how, q in loaded:
            for a in attrs:
                if getattr(q, a) != getattr(r, a):
                    bad.append(f"{name} {how} {a}: {getattr(q, a)!r} != {getattr(r, a)!r}")
                try:  # the run's own fields are plain Python values; a loaded one's should be too
                    json.dumps(getattr(q, a))
                except TypeError as ex:
                    bad.append(
                        f"{name} {how} {a} = {getattr(q, a)!r}: json.dumps fails ({ex}), "
                        f"the run's own is {getattr(r, a)!r}"
                    )
            if not np.array_equal(q.judged, r.judged):
                bad.append(f"{name} {how} judged")
        json.dumps(r.summary())
    report(
        "P1_result_roundtrips",
        not bad,
        "; ".join(bad) or "npz, pickle and summary JSON keep verdicts",
    )


@probe
def P2_threads():
    import stabctl

    c = stabctl.load_case("kundur")
    sim = stabctl.Simulator(c)
    evs = [
        [stabctl.fault_with_clearing(c, b, f, 1.0, cc)]
        for b, f, cc in ((3, 101, 9.0), (13, 101, 20.0), (3, None, 14.0))
    ]
    seq = [sim.run(e, t_end=5.0) for e in evs]
    out = {}

    def work(i):
        try:
            for k in range(3):
                out[(i, k)] = sim.run(evs[i], t_end=5.0)
        except Exception as ex:  # noqa: BLE001 - any error of a threaded run is the finding
            out[(i, "err")] = ex

    threads = [threading.Thread(target=work, args=(i,)) for i in range(len(evs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    bad = [
        k
        for k, v in out.items()
        if isinstance(v, Exception) or not np.array_equal(v.angle, seq[k[0]].angle)
    ]
    report("P2_threads", not bad, f"{len(out)} threaded runs, {len(bad)} differ from sequential")


@probe
def P3_reuse_after_exception():
    import stabctl
    from stabctl import LoadStep

    c = stabctl.load_case("kundur")
    ev = [stabctl.fault_with_clearing(c, 3, 101, 1.0, 9.0)]
    ref = stabctl.Simulator(c).run(ev, t_end=5.0)
    bad = []

    def monitor(p):
        if p.t[-1] > 1.5:
            raise ZeroDivisionError("the monitor raises")

    kinds = {
        "monitor raises": {"events": ev, "t_end": 5.0, "monitor": monitor},
        "numerical instability": {"events": ev, "t_end": 5.0, "h": 0.0199},
        "bad event": {"events": [*ev, "x"], "t_end": 5.0},
        "trapezoid load step": {
            "events": [LoadStep(3, 1.0, 30.0, 10.0)],
            "t_end": 5.0,
            "method": "trapezoid",
        },
    }
    for k, kw in kinds.items():
        sim = stabctl.Simulator(c)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sim.run(**kw)
        except Exception:  # noqa: BLE001 - whatever the run raised, the Simulator is reused
            pass
        r = sim.run(ev, t_end=5.0)
        if not np.array_equal(r.angle, ref.angle):
            bad.append(k)
    report(
        "P3_reuse_after_exception",
        not bad,
        f"differs after: {bad}"
        if bad
        else "a Simulator reused after each exception runs as a fresh one",
    )


@probe
def P4_numpy_inputs():
    import stabctl
    from stabctl.stability.cct import SearchOptions

    c = stabctl.load_case("kundur")
    sim = stabctl.Simulator(c)
    ref = sim.run([stabctl.fault_with_clearing(c, 3, 101, 1.0, 9.0)], t_end=5.0)
    bad = []
    fault = stabctl.fault_with_clearing(
        c, np.int64(3), np.int32(101), np.float32(1.0), np.float32(9.0)
    )
    r = sim.run([fault], t_end=np.int64(5))
    if not np.array_equal(r.angle, ref.angle):
        bad.append("numpy fault args change the run")
    cct = stabctl.critical_clearing_time(
        sim, stabctl.LineFault(3, 101, 1.0), SearchOptions(tol=np.float32(0.001))
    )
    if abs(cct.t_stable - 0.154) > 1e-6:
        bad.append(f"float32 tol CCT {cct.t_stable}")
    sp = ref.speed
    b = stabctl.coi_speed(sp, ref.inertia)
    for lab, s, h in (
        ("fortran", np.asfortranarray(sp), ref.inertia),
        ("float32", sp.astype(np.float32), ref.inertia),
        ("int inertia", sp, ref.inertia.astype(int)),
    ):
        if np.abs(stabctl.coi_speed(s, h) - b).max() > 1e-6:
            bad.append(f"coi_speed {lab}")
    report(
        "P4_numpy_inputs",
        not bad,
        "; ".join(bad) or "numpy ints/float32/Fortran arrays accepted with the same results",
    )


@probe
def P5_modal_analysis_relabelled_model():
    """A state-space model rebuilt with python-control from stabctl's matrices and state
    names (so without the output omega_coi): analysed, or a stabctl error (the documented
    InputError/TypeError), not a stray exception from inside."""
    import control

    import stabctl

    pid = "P5_modal_analysis_relabelled_model"
    sim = stabctl.Simulator(stabctl.load_case("kundur"))
    lin = stabctl.linearise(sim)
    a, b, c, d = (np.asarray(getattr(lin, k)) for k in "ABCD")
    sys2 = control.ss(a, b, c, d, states=lin.state_labels)  # a model rebuilt with its states
    try:
        stabctl.modal_analysis(sys2)
    except Exception as ex:  # noqa: BLE001 - which exception it is, is what the probe checks
        tb = traceback.extract_tb(ex.__traceback__)[-1]
        clear = type(ex).__module__.startswith("stabctl")
        report(
            pid,
            clear,
            f"{type(ex).__name__}: {ex} (at {os.path.basename(tb.filename)}:{tb.lineno} "
            f"{tb.name}; docs promise InputError/TypeError)",
        )
        return
    report(pid, True, "analysed")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ids", nargs="*", help="probe names or their prefixes (N1, I4)")
    ap.add_argument("-k", default="", help="run the probes whose name holds this")
    opts = ap.parse_args(argv)
    selected = [
        fn
        for fn in PROBES
        if (not opts.ids or fn.__name__ in opts.ids or fn.__name__.split("_")[0] in opts.ids)
        and opts.k in fn.__name__
    ]
    print(f"stabctl of {ROOT}; work directory {WORK}", flush=True)
    try:
        for fn in selected:
            try:
                fn()
            except Exception as ex:  # noqa: BLE001 - a probe that crashes is reported short
                report(fn.__name__, False, f"probe crashed: {type(ex).__name__}: {str(ex)[:200]}")
    finally:
        if os.environ.get("KEEP"):
            print(f"work directory kept: {WORK}")
        else:
            shutil.rmtree(WORK, ignore_errors=True)
    n_short = sum(not ok for _, ok, _ in RESULTS)
    print(f"\n{len(RESULTS)} probes, {len(RESULTS) - n_short} ok, {n_short} SHORT")
    return 1 if n_short else 0


if __name__ == "__main__":
    sys.exit(main())
