"""Eighth reliability round (round 34, part A): whole workflows on grids the developers have
not studied.

A planning engineer brings hand-edited variants of ANDES's IEEE 14 RAW+DYR (bus 12 made
radial, the generator at bus 3 out of service with its DYR records kept, the machine at bus
8 at H = 0.005 s and 0.05 s, a second identical circuit 2-3, transformer 4-7 with WINDV2
0.9), ANDES's pjm5bus and PSS/E's WECC 240, and runs the whole workflow on them: import-psse
and import-andes, cases, simulate, cct, screen, eig (text, --json and --report), place,
estimate cct and sweep-cct, each result checked against another command's (a CCT against
simulate at the CCT and one step above it, screen and sweep-cct against cct, a VERIFIED
plan against cct --esd-pct, eig's report against its --json).

Contract: each probe runs `stabctl` commands in fresh processes (the package of this
repository first on PYTHONPATH) and states what a careful tool does: a refused input ends
with exit status 2 and an ``error:`` line naming what (the machine, the circuit), no
traceback; a legitimate run exits 0 with the result the other commands give, every record
left out or changed named by the import, every column and mode label what it says.  The
round found A09, A10, A12, A14, A15, A16, A17 and A19 short; they are fixed and the probes
are now their regression checks (a governor that cannot start named by machine and bus, and
by import-andes too; a fast rotor mode outside 0.1-2.5 Hz named; pjm5bus's swing modes not
called 'common'; the bus table's set-point voltage labelled V_data_pu; a worker's warning one
line; a bus fault's circuit null in cct --json as in screen --json; ANDES's reading of WINDV2
named).  A plan that `place` does not call VERIFIED is reported, not a shortfall (A06).

    python benchmarks/reliability_probes_8.py [-k SUBSTRING] [ID ...]

ID: a probe's name or its prefix before the first ``_`` (``A07``).  The probes that need
an earlier probe's files (the imported IEEE 14 case, the out-of-service variant, pjm5bus,
the fault list) make them when run alone.  One line per probe (name, ok or SHORT, why, its
seconds), then the counts.  Needs the ``andes`` package (its case files) and WECC 240 of
tests/data/wecc240.  NUMBA_CACHE_DIR is the caller's (numba's default when unset);
`stabctl compile` is run first (seconds with a warm cache, about a minute cold).  The work
directory is a new temporary directory, removed at the end unless KEEP is set.  About 4
minutes on two cores with a warm kernel cache.  Exit status 1 if any probe is short.
"""

from __future__ import annotations

import argparse
import cmath
import gzip
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]  # the package under test
STABCTL = [sys.executable, "-m", "stabctl"]
ENV = dict(
    os.environ,
    PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]),
)
ENV.pop("PYTHONWARNINGS", None)
WECC240 = ROOT / "tests" / "data" / "wecc240"  # PSS/E's WECC 240 RAW and DYR, gzipped
WORK = Path(tempfile.mkdtemp(prefix="stabctl-probes-8."))
RESULTS: list[tuple[str, bool, str]] = []
PROBES: list = []


def probe(fn):
    """A probe returns (ok, why)."""
    PROBES.append(fn)
    return fn


def sh(*args, timeout=300):
    """Run `stabctl args` in the work directory -> (rc, stdout, stderr)."""
    try:
        p = subprocess.run(
            [*STABCTL, *map(str, args)],
            capture_output=True,
            text=True,
            timeout=timeout,
            env=ENV,
            cwd=WORK,
            stdin=subprocess.DEVNULL,
        )
    except subprocess.TimeoutExpired:
        return -9, "", f"TIMEOUT after {timeout} s"
    return p.returncode, p.stdout, p.stderr


def js(*args, timeout=300):
    """`sh` of a command given --json -> (rc, the parsed JSON or None, stderr [+ stdout])."""
    rc, out, err = sh(*args, timeout=timeout)
    try:
        return rc, json.loads(out), err
    except json.JSONDecodeError:
        return rc, None, err + out


def report(pid, ok, why, seconds):
    RESULTS.append((pid, ok, why))
    print(f"{pid:<34} {'ok   ' if ok else 'SHORT'} {why}  [{seconds:.1f} s]", flush=True)


def read_json(name):
    with open(WORK / name) as f:
        return json.load(f)


def records(name):
    return [json.loads(line) for line in (WORK / name).read_text().splitlines() if line.strip()]


def andes_cases() -> Path:
    import andes  # only to find ANDES's case files

    return Path(andes.__file__).parent / "cases"


# ---------------------------------------------------------------- variants of IEEE 14


def base14():
    """ANDES's IEEE 14 RAW and DYR lines (the DYR without its two Toggle records)."""
    i14 = andes_cases() / "ieee14"
    raw = (i14 / "ieee14.raw").read_text().splitlines()
    dyr = [ln for ln in (i14 / "ieee14.dyr").read_text().splitlines() if "Toggle" not in ln]
    return raw, dyr


def write(name, raw, dyr):
    (WORK / f"{name}.raw").write_text("\n".join(raw) + "\n")
    (WORK / f"{name}.dyr").write_text("\n".join(dyr) + "\n")


def v_radial():
    """Branch 12-13 removed: bus 12 radial behind 6-12."""
    raw, dyr = base14()
    return [ln for ln in raw if not re.match(r"\s+12,\s+13,'1 '", ln)], dyr


def v_genout():
    """The generator at bus 3 out of service (STAT 0); its DYR records kept."""
    raw, dyr = base14()
    out = []
    for ln in raw:
        if re.match(r"\s+3,'1 ',\s+40\.000", ln):
            f = ln.split(",")
            f[14] = "0"
            ln = ",".join(f)
        out.append(ln)
    return out, dyr


def v_h(h):
    """The machine at bus 8: H 5.0 s -> h."""
    raw, dyr = base14()
    out, i8 = [], None
    for k, ln in enumerate(dyr):
        if re.match(r"\s+8 'GENROU'", ln):
            i8 = k
        if i8 is not None and k == i8 + 1:
            ln = ln.replace("5.0000", h, 1)
        out.append(ln)
    return raw, out


def v_parallel():
    """A second, identical circuit 2-3 (CKT '2')."""
    raw, dyr = base14()
    out = []
    for ln in raw:
        out.append(ln)
        if re.match(r"\s+2,\s+3,'1 '", ln):
            out.append(ln.replace("'1 '", "'2 '"))
    return out, dyr


def v_windv2():
    """Transformer 4-7: WINDV1 1.0, WINDV2 0.9 (ratio 1.111 on bus 4's side)."""
    raw, dyr = base14()
    out, hit = [], None
    for k, ln in enumerate(raw):
        if re.match(r"\s+4,\s+7,\s+0,'1 '", ln):
            hit = k
        if hit is not None and k == hit + 2:
            ln = "1.00000" + ln[len("0.99677") :]
        if hit is not None and k == hit + 3:
            ln = "0.90000,   0.000"
        out.append(ln)
    return out, dyr


def imp_psse(name, *extra):
    """import-psse of NAME.raw + NAME.dyr -> NAME.json."""
    return sh("import-psse", f"{name}.raw", f"{name}.dyr", "-o", f"{name}.json", *extra)


# ---------------------------------------------------------------- fixtures (made once)


def import_i14():
    """import-psse of ANDES's ieee14.raw + ieee14.dyr -> i14.json: (rc, stdout, stderr)."""
    i14 = andes_cases() / "ieee14"
    return sh(
        "import-psse", i14 / "ieee14.raw", i14 / "ieee14.dyr", "-o", "i14.json",
        "--skip-unsupported",
    )  # fmt: skip


def i14():
    """The imported IEEE 14 case (A01's), made if absent."""
    if not (WORK / "i14.json").exists():
        rc, _, err = import_i14()
        if rc != 0:
            raise RuntimeError(f"import-psse ieee14 exit {rc}: {err[-200:]}")
    return "i14.json"


def faults14():
    """The fault list of A06 and A21: lines 2-4, 1-2 and bus 4."""
    (WORK / "f14.csv").write_text("bus,far_bus\n2,4\n1,2\n4,\n")
    return "f14.csv"


def genout_files():
    """genout.raw and genout.dyr (the generator at bus 3 out of service)."""
    if not (WORK / "genout.raw").exists():
        write("genout", *v_genout())
    return "genout"


def genout_case():
    """genout.json as import-psse writes it (A08's), made if absent."""
    if not (WORK / "genout.json").exists():
        imp_psse(genout_files())
    return "genout.json"


def pjm():
    """ANDES's pjm5bus through import-andes -> pjm.json, made if absent: (rc, stderr)."""
    if (WORK / "pjm.json").exists():
        return 0, ""
    rc, _, err = sh("import-andes", andes_cases() / "5bus" / "pjm5bus.json", "-o", "pjm.json")
    return rc, err


# ---------------------------------------------------------------- probes


@probe
def A01_import_ieee14():
    rc, out, err = import_i14()
    if rc != 0 or "TOGGLE" not in out:
        return False, f"import-psse ieee14 rc={rc}: {err[-200:]}"
    return True, "import-psse ieee14.raw+dyr: exit 0, the two TOGGLE records named as left out"


@probe
def A02_cct_bus_vs_simulate():
    """The CCT of a bus fault: simulate --bus-fault stable at it, unstable one step above."""
    case = i14()
    rc, d, err = js("cct", case, "--fault", 4, "--json")
    if rc or not d or d.get("cct_s") is None:
        return False, f"cct bus 4 rc={rc} {err[-200:]}"
    ts, tu = d["t_stable_s"], d["t_unstable_s"]
    v = []
    for t in (ts, tu):
        _, s, _ = js("simulate", case, "--bus-fault", 4, 1, f"{1 + t:.6g}", "--tf", 6, "--json")
        v.append(s and s.get("stable"))
    if v != [True, False]:
        return False, f"cct bus 4 CCT {ts} s, simulate at {ts}/{tu} s gives stable={v}"
    return True, f"cct bus 4 = {ts} s; simulate --bus-fault stable at it, unstable at {tu} s"


@probe
def A03_cct_line_vs_simulate():
    case = i14()
    _, d, _ = js("cct", case, "--fault", 2, "--far-bus", 4, "--json")
    ts, tu = d["t_stable_s"], d["t_unstable_s"]
    v = []
    for t in (ts, tu):
        _, s, _ = js(
            "simulate", case, "--fault", 2, "--far-bus", 4, "--clear-cycles", f"{t * 60:.6g}",
            "--tf", 6, "--json",
        )  # fmt: skip
        v.append(s and s.get("stable"))
    if v != [True, False]:
        return False, f"cct 2-4 CCT {ts}, simulate gives {v}"
    return True, f"cct line 2-4 = {ts} s; simulate --fault/--clear-cycles agrees at {ts}/{tu} s"


@probe
def A04_screen_vs_cct():
    case = i14()
    rc, rows, err = js(
        "screen", case, "--buses", "2,4", "--lines", "--t-max", 1, "--workers", 1,
        "--out", "scr.jsonl", "--json", timeout=600,
    )  # fmt: skip
    if rc != 0 or not rows:
        return False, f"screen rc={rc} {err[-200:]}"
    bad = []
    for r in rows:
        if (r["bus"], r["far_bus"]) in ((2, 4), (4, None), (1, 2)):
            args = ["cct", case, "--fault", r["bus"], "--json"]
            if r["far_bus"] is not None:
                args += ["--far-bus", r["far_bus"]]
            _, d, _ = js(*args)
            if d["cct_s"] != r["cct_s"]:
                bad.append((r["bus"], r["far_bus"], r["cct_s"], d["cct_s"]))
    if bad:
        return False, f"screen CCT differs from cct: {bad}"
    return True, "screen --lines rows 2-4, bus 4, 1-2 equal cct's CCTs"


@probe
def A05_eig_report_vs_json():
    case = i14()
    rc, d, _ = js("eig", case, "--json")
    rc2, _, _ = sh("eig", case, "--report", "--out-dir", "rep")
    if rc or rc2:
        return False, f"eig rc={rc}/{rc2}"
    md = (WORK / "rep" / "eig_i14.md").read_text()
    for m in d["modes"]:
        if m["kind"] in ("local", "inter-area", "common"):
            row = re.search(rf"\| {m['mode']} \| [^|]+\| ([\d.]+) \| ([\d.]+) \| (\S+) ", md)
            if (
                not row
                or abs(float(row.group(1)) - m["freq_hz"]) > 1e-3
                or abs(float(row.group(2)) - m["damping_ratio"]) > 1e-3
                or row.group(3) != m["kind"]
            ):
                return False, f"mode {m['mode']} differs between --json and --report"
    return True, "eig --report table (f, zeta, kind) = --json for every electromechanical mode"


@probe
def A06_place_plan_vs_cct():
    """A VERIFIED plan of a uniform fleet meets every contingency it says it meets when
    checked with cct --esd-pct (100 MVA machines: MW = %); a plan not VERIFIED is reported."""
    case, faults = i14(), faults14()
    rc, _, err = sh(
        "place", case, "--faults", faults, "--target-cct-gain", 5, "--set-aside-infeasible",
        "--workers", 1, "--out", "pl14.json", timeout=600,
    )  # fmt: skip
    if rc != 0:
        return False, f"place rc={rc} {err[-300:]}"
    p = read_json("pl14.json")
    if not p["verified"]:
        return True, "place: not VERIFIED (" + p["message"][:80] + ")"
    mws = {a["mw"] for a in p["allocation"]}
    checked = []
    for c in p["contingencies"]:
        if not c["met"]:
            continue
        m = re.match(r"fault at bus (\d+)(?: on line \d+-(\d+))?", c["fault"])
        args = ["cct", case, "--fault", m.group(1), "--json"]
        if m.group(2):
            args += ["--far-bus", m.group(2)]
        if len(mws) == 1:
            pct = next(iter(mws))  # 100 MVA machines: MW = %
            args += ["--esd-pct", f"{pct:g}"]
            _, d, _ = js(*args)
            if d["cct_s"] < c["required_s"] - 1e-9:
                return False, (
                    f"VERIFIED plan {pct} % gives cct {d['cct_s']} < required {c['required_s']}"
                )
            checked.append(c["fault"])
    if len(mws) != 1:
        return True, f"place VERIFIED plan, not a uniform fleet ({sorted(mws)} MW): not checked"
    return True, (
        f"place VERIFIED plan (uniform {next(iter(mws)):g} MW) re-checked with cct --esd-pct: "
        f"meets {'; '.join(checked) or 'no contingency it calls met'}"
    )


@probe
def A07_radial_bus_islanded():
    write("radial", *v_radial())
    imp_psse("radial")
    rc, out, _ = sh("cct", "radial.json", "--fault", 12, "--far-bus", 6)
    if rc != 0 or "islanded" not in out or "load shed 6.1 MW" not in out:
        return False, f"radial line fault: rc={rc} {out[-200:]}"
    return True, "radial bus 12: line fault 12-6 names bus 12 islanded, load shed 6.1 MW"


@probe
def A08_genout_import_psse():
    rc, out, err = imp_psse(genout_files())
    ok = rc == 0 and "initial power order" in err and "IEEEG1 (bus 3" in out
    return ok, (
        "import-psse: generator STAT 0 and its 4 DYR records named; swing governor "
        "outside [Tmin,Tmax] warned"
        if ok
        else f"rc={rc} {err[-300:]}"
    )


@probe
def A09_genout_run_error_names_machine():
    """The case import-psse wrote (A08) with the swing governor outside its limits: a run
    refuses it naming the machine and its bus (round 34: only 'tg_con row 1')."""
    rc, _, err = sh("simulate", genout_case(), "--bus-fault", 4, 1, 1.1)
    line = err.strip().splitlines()[-1] if err.strip() else ""
    if rc == 2 and "G1" in line and "bus 1" in line:
        return True, f"simulate's refusal names the machine: {line[:120]}"
    return False, (
        f"simulate refuses with rc={rc} `{line[:120]}`: not the machine/governor (G1, bus 1, "
        "TGOV1) the import named"
    )


@probe
def A10_genout_import_andes():
    """import-andes of the same RAW+DYR names the controls of the out-of-service generator
    and warns that the swing governor cannot start (round 34: neither)."""
    name = genout_files()
    rc, d, err = js("import-andes", f"{name}.raw", f"{name}.dyr", "-o", "aa_genout.json", "--json")
    if rc != 0 or d is None:
        return False, f"import-andes rc={rc} {err[-200:]}"
    named = " ".join(
        d.get("out_of_service", []) + d.get("left_out", []) + [str(x) for x in d.get("changed", [])]
    )
    missing = [m for m in ("ESST3A", "IEEEST", "IEEEG1") if m not in named]
    rc2, _, err2 = sh("cct", "aa_genout.json", "--fault", 2, "--far-bus", 4)
    probs = []
    if missing and (d["exciters"], d["pss"], d["governors"]) == (4, 2, 4):
        probs.append(
            f"controls of the out-of-service generator ({', '.join(missing)} at bus 3) "
            "dropped without a name"
        )
    if "initial power order" not in err and rc2 == 2:
        probs.append(
            "no warning that the swing governor cannot start; exit 0, then every command "
            f"refuses the case: `{err2.strip()[:90]}`"
        )
    if probs:
        return False, "import-andes genout: " + "; ".join(probs)
    return True, "import-andes names the out-of-service generator's controls"


@probe
def A11_tiny_inertia_instability():
    write("h005", *v_h("0.00500"))
    imp_psse("h005")
    rc, _, err = sh("simulate", "h005.json", "--tf", 3)
    if (
        rc == 2
        and err.startswith("error:")
        and "numerical instability" in err
        and "Traceback" not in err
    ):
        return True, (
            "H = 0.005 s: flat run stops with `error: ... numerical instability ... "
            "use a smaller step`"
        )
    return False, f"rc={rc} {err[-200:]}"


@probe
def A12_small_inertia_mode_named():
    """G5 at H = 0.05 s swings at 13.3 Hz, outside the 0.1-2.5 Hz band: eig lists or flags
    it (round 34: kind 'other', in no summary, and a better-damped mode called the least
    damped electromechanical one)."""
    write("h05", *v_h("0.05000"))
    imp_psse("h05")
    _, d, _ = js("eig", "h05.json", "--json")
    _, out, _ = sh("eig", "h05.json")
    g5 = [
        m
        for m in d["modes"]
        if m["dominant_states"]
        and m["dominant_states"][0]["state"] in ("mac_omega_G5", "mac_delta_G5")
    ]
    em = d["damping_statistics"]["electromechanical"]
    if (
        g5
        and g5[0]["kind"] == "other"
        and g5[0]["damping_ratio"] < em["damping_ratio"]
        and f"{g5[0]['freq_hz']:.3f}" not in out
    ):
        m = g5[0]
        return False, (
            f"G5 (H 0.05 s) swings at {m['freq_hz']:.1f} Hz, zeta {m['damping_ratio']:.3f}, "
            "rotor angle/speed dominant, kind 'other'; the text lists no mode of G5 and calls "
            f"{em['freq_hz']:.3f} Hz (zeta {em['damping_ratio']:.3f}) the least-damped "
            "electromechanical mode"
        )
    if not g5:
        return True, "no mode dominated by G5's rotor states"
    m = g5[0]
    listed = "listed" if f"{m['freq_hz']:.3f}" in out else "not in the text"
    return True, (
        f"G5's swing mode {m['freq_hz']:.1f} Hz (zeta {m['damping_ratio']:.3f}): kind "
        f"{m['kind']!r}, {listed}"
    )


@probe
def A13_parallel_circuits():
    write("par", *v_parallel())
    imp_psse("par")
    _, d1, _ = js("cct", "par.json", "--fault", 2, "--far-bus", 3, "--json")
    _, d2, _ = js("cct", "par.json", "--fault", 2, "--far-bus", 3, "--circuit", 2, "--json")
    rc3, _, err3 = sh("cct", "par.json", "--fault", 2, "--far-bus", 3, "--circuit", 3)
    ok = bool(d1 and d2 and d1["cct_s"] == d2["cct_s"] and rc3 == 2 and "circuit 3" in err3)
    return ok, (
        "identical parallel circuits give one CCT; circuit 3 refused by name"
        if ok
        else f"{d1 and d1['cct_s']} {d2 and d2['cct_s']} rc3={rc3} {err3[-150:]}"
    )


@probe
def A14_pjm5bus_common_label():
    """pjm5bus (4 GENCLS; ANDES: swing modes 1.079, 1.458, 1.725 Hz): at most one swing
    mode above 0.5 Hz called 'common' (round 34: two, machines against each other)."""
    rc, err = pjm()
    if rc != 0:
        return False, f"import pjm5bus rc={rc} {err[-200:]}"
    _, d, _ = js("eig", "pjm.json", "--json")
    bad = []
    for m in d["modes"]:
        if m["kind"] != "common" or m["freq_hz"] < 0.5:
            continue
        v = {k: cmath.rect(a, math.radians(deg)) for k, (a, deg) in m["speed_shape"].items()}
        ref = v[max(v, key=lambda q: abs(v[q]))]
        anti = [k for k, z in v.items() if abs(z) > 0.1 and (z / ref).real < 0]
        bad.append(
            f"mode {m['mode']} {m['freq_hz']:.3f} Hz zeta {m['damping_ratio']:.4f} 'common' "
            f"(shape {', '.join(f'{k} {abs(z):.2f}' for k, z in v.items())}; "
            f"against: {anti or 'none'})"
        )
    if len(bad) >= 2:
        return False, (
            "eig calls 2 of pjm5bus's 3 swing modes 'common (every machine in phase: the "
            "system's frequency)': " + "; ".join(bad)
        )
    return True, f"pjm5bus: {len(bad)} swing mode above 0.5 Hz called common"


@probe
def A15_bus_table_voltage_label():
    """cases --bus-table of PV bus 6 (set point 1.03 pu, solved 0.9987 pu with G4 at its
    10 Mvar limit): a column V_pu holds the solved voltage, or the set point is labelled
    as the data's (round 34: V_pu 1.03 beside the RAW's solved angle)."""
    _, d, _ = js("cases", i14(), "--bus-table", "--json")
    b6 = next(b for b in d["buses"] if b["bus"] == 6)
    if "V_pu" in b6:
        ok = not (abs(b6["V_pu"] - 1.03) < 1e-6 and abs(b6["angle_deg"] - (-6.3024)) < 1e-3)
        return ok, (
            f"bus 6 V_pu {b6['V_pu']} is the solved voltage"
            if ok
            else (
                "cases --bus-table V_pu of PV bus 6 is 1.03 (the set point) beside the RAW's "
                "solved angle -6.30 deg, while the case solves to 0.9987 pu; the column is "
                "headed V_pu with no word that it is the data's set point"
            )
        )
    ok = "V_data_pu" in b6
    return ok, (
        f"bus 6's set point labelled V_data_pu = {b6['V_data_pu']}"
        if ok
        else f"bus 6 has no voltage column: {sorted(b6)}"
    )


@probe
def A16_estimate_cct_warning_one_line():
    """A pool worker's warning in estimate cct is one 'warning:' line, not Python's file,
    line and source line in the progress bar (round 34)."""
    rc, _, err = sh(
        "estimate", "cct", i14(), "--fault", 1, "--far-bus", 2, "--esd-pct", 20, "--runs", 2,
        timeout=600,
    )  # fmt: skip
    text = err.replace("\r", "\n")
    if rc == 0 and re.search(r"\.py:\d+: UserWarning", text):
        line = next(ln for ln in text.splitlines() if "UserWarning" in ln)
        return False, (
            "estimate cct prints a raw Python warning from a worker beside its own "
            f"'warning:' line: `{line[line.find('/') :][:110]}...`"
        )
    return rc == 0, f"estimate cct rc={rc}, warnings formatted"


@probe
def A17_bus_fault_circuit_null():
    """A bus fault's circuit: null in cct --json as in screen --json (round 34: cct gave 1)."""
    case = i14()
    _, d, _ = js("cct", case, "--fault", 4, "--json")
    _, srows, _ = js(
        "screen", case, "--buses", "2,4", "--lines", "--t-max", 1, "--workers", 1,
        "--out", "scr.jsonl", "--json",
    )  # fmt: skip
    s4 = next(r for r in srows if r["bus"] == 4 and r["far_bus"] is None)
    bus4 = [
        r
        for r in records("scr.jsonl")
        if r["inputs"]["bus"] == 4 and r["inputs"]["far_bus"] is None
    ]
    if d["fault"]["circuit"] is not None and s4["circuit"] is None:
        return False, (
            f"a bus fault's circuit: cct --json fault.circuit = {d['fault']['circuit']} (and "
            f"the screen records' inputs.circuit = "
            f"{bus4[0]['inputs']['circuit'] if bus4 else '?'}) while screen --json gives "
            "circuit null (docs: a bus fault's circuit is empty)"
        )
    return True, (
        f"bus fault circuit consistent (cct {d['fault']['circuit']}, screen {s4['circuit']})"
    )


@probe
def A18_wecc240_workflow():
    """WECC 240: its CCT of line 1001-1201 confirmed by simulate; cct under 60 s, eig under
    120 s."""
    names = ("240busWECC_2018_PSS32_fixed_shunts.raw", "240busWECC_2018_PSS.dyr")
    for name in names:
        with gzip.open(WECC240 / f"{name}.gz", "rb") as src, open(WORK / name, "wb") as dst:
            shutil.copyfileobj(src, dst)
    rc, _, err = sh("import-psse", *names, "-o", "w240.json")
    if rc != 0:
        return False, f"import wecc240 rc={rc} {err[-200:]}"
    t0 = time.monotonic()
    _, d, _ = js("cct", "w240.json", "--fault", 1001, "--far-bus", 1201, "--json")
    tc = time.monotonic() - t0
    ts, tu = d["t_stable_s"], d["t_unstable_s"]
    v = []
    for t in (ts, tu):
        _, s, _ = js(
            "simulate", "w240.json", "--fault", 1001, "--far-bus", 1201,
            "--clear-cycles", f"{t * 60:.6g}", "--tf", 6, "--json",
        )  # fmt: skip
        v.append(s["stable"])
    t0 = time.monotonic()
    rc, _, _ = js("eig", "w240.json", "--json", timeout=600)
    te = time.monotonic() - t0
    ok = v == [True, False] and tc < 60 and te < 120 and rc == 0
    return ok, (
        f"WECC 240: cct 1001-1201 {ts} s ({tc:.0f} s) confirmed by simulate; eig {te:.0f} s"
        if ok
        else f"simulate {v}, cct {tc:.0f} s eig {te:.0f} s rc={rc}"
    )


@probe
def A19_andes_windv2_named():
    """One RAW, two importers: import-andes reads transformer 4-7 as import-psse does, or
    names it (ANDES's RAW reader drops WINDV2; round 34: named nowhere)."""
    write("wv2", *v_windv2())
    imp_psse("wv2")
    _, out, err = sh("import-andes", "wv2.raw", "wv2.dyr", "-o", "aa_wv2.json")
    tp = {}
    for c in ("wv2.json", "aa_wv2.json"):
        _, d, _ = js("cases", c, "--line-table", "--json")
        tp[c] = next(ln for ln in d["lines"] if {ln["from"], ln["to"]} == {4, 7})
    a, b = tp["wv2.json"], tp["aa_wv2.json"]
    if abs(a["tap"] - b["tap"]) > 1e-6 and "WINDV2" not in out + err and "4-7" not in out + err:
        return False, (
            f"one RAW, two cases - import-psse 4-7 tap {a['tap']:.4f} x {a['x_pu']:.4f}, "
            f"import-andes tap {b['tap']:.4f} x {b['x_pu']:.4f}; import-andes names no "
            "transformer"
        )
    if abs(a["tap"] - b["tap"]) <= 1e-6:
        return True, f"WINDV2 read alike (tap {a['tap']:.4f})"
    said = next((ln for ln in (out + err).splitlines() if "4-7" in ln or "WINDV2" in ln), "")
    return True, f"import-andes tap {b['tap']:.4f} vs {a['tap']:.4f}, named: {said.strip()[:100]}"


@probe
def A20_pjm5bus_screen_vs_cct():
    rc, err = pjm()
    if rc != 0:
        return False, f"import pjm5bus rc={rc} {err[-200:]}"
    rc, rows, err = js(
        "screen", "pjm.json", "--lines", "--workers", 1, "--out", "scrp.jsonl", "--json",
        timeout=600,
    )  # fmt: skip
    if rc != 0:
        return False, f"screen pjm rc={rc} {err[-200:]}"
    bad = []
    for r in rows[:6]:
        args = ["cct", "pjm.json", "--fault", r["bus"], "--t-max", 0.5, "--json"]
        if r["far_bus"] is not None:
            args += ["--far-bus", r["far_bus"], "--circuit", r["circuit"]]
        _, d, _ = js(*args)
        if d["cct_s"] != r["cct_s"]:
            bad.append((r["bus"], r["far_bus"], r["cct_s"], d["cct_s"]))
    return not bad, ("pjm5bus screen = cct on 6 faults" if not bad else f"differ: {bad}")


@probe
def A21_sweep_vs_cct():
    case, faults = i14(), faults14()
    rc, _, _ = sh(
        "sweep-cct", case, "--faults", faults, "--esd-pct", 5, "--workers", 1,
        "--out", "sw.jsonl", timeout=600,
    )  # fmt: skip
    r = next(
        x for x in records("sw.jsonl") if x["inputs"]["bus"] == 2 and x["inputs"]["far_bus"] == 4
    )
    _, d, _ = js("cct", case, "--fault", 2, "--far-bus", 4, "--esd-pct", 5, "--json")
    got = r["result"]["cct_s"]
    ok = rc == 0 and abs(got - d["cct_s"]) < 1e-9
    return ok, (
        f"sweep-cct 2-4 esd5 = cct ({d['cct_s']} s)" if ok else f"sweep {got} cct {d['cct_s']}"
    )


@probe
def A22_esd_wecc_simulate():
    rc, d, err = js(
        "simulate", i14(), "--fault", 2, "--far-bus", 4, "--clear-cycles", 6, "--esd-pct", 5,
        "--esd-model", "wecc", "--json",
    )  # fmt: skip
    ok = bool(rc == 0 and d["stable"] and len(d["storage"]) == 5)
    return ok, (
        "simulate --esd-model wecc on the import: 5 batteries, stable at 6 cycles"
        if ok
        else f"rc={rc} {err[-200:]}"
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ids", nargs="*", help="probe names or their prefixes (A07)")
    ap.add_argument("-k", default="", help="run the probes whose name holds this")
    opts = ap.parse_args(argv)
    selected = [
        fn
        for fn in PROBES
        if (not opts.ids or fn.__name__ in opts.ids or fn.__name__.split("_")[0] in opts.ids)
        and opts.k in fn.__name__
    ]
    t_start = time.monotonic()
    print(f"stabctl of {ROOT}; work directory {WORK}", flush=True)
    rc, _, err = sh("compile", timeout=900)  # a warm cache loads in seconds
    if rc != 0:
        print("stabctl compile failed:", err[-300:])
        shutil.rmtree(WORK, ignore_errors=True)
        return 2
    try:
        for fn in selected:
            t0 = time.monotonic()
            try:
                ok, why = fn()
            except Exception as ex:  # noqa: BLE001 - a probe that crashes is reported short
                ok, why = False, f"probe crashed: {type(ex).__name__}: {str(ex)[:200]}"
            report(fn.__name__, bool(ok), why, time.monotonic() - t0)
    finally:
        keep = bool(os.environ.get("KEEP"))
        if not keep:
            shutil.rmtree(WORK, ignore_errors=True)
    n_short = sum(not ok for _, ok, _ in RESULTS)
    print(
        f"\n{len(RESULTS)} probes, {len(RESULTS) - n_short} ok, {n_short} SHORT; "
        f"{time.monotonic() - t_start:.0f} s; work directory {WORK} "
        f"({'kept' if keep else 'removed'})"
    )
    return 1 if n_short else 0


if __name__ == "__main__":
    sys.exit(main())
