#!/usr/bin/env python
"""Twenty-ninth reliability round (round 45, part Y): consistency of what stabctl's study commands report across their text,
--json, records files (--out) and figures on the built-in kundur and miniwecc cases
(`cct`, `sweep-cct`, `screen`, `place`, `eig`, `estimate track/rmse`), each checked against
an independent computation (`simulate` at the CCT and just above it, numpy eigenvalues of
the linearised A matrix), and the examples/ scripts and the docs' command examples run as
written from a clean temporary directory.

    python benchmarks/reliability_probes_29.py [--quick]

CLONE (default: this repository) is the package under test, run as `python -m stabctl`;
NUMBA_CACHE_DIR the caller's.  Prints per probe: id, ok/SHORT, reason; exits 1 if any is
SHORT.  Every command has a timeout; all work in a temporary directory (removed at the end
unless KEEP=1).

The round found short: `cct --coi critical` saying its group separates where the run fails first (CCT-5), `separated_machines` naming a machine that did not separate (CCT-2), `screen` without the failing end and the not-monotone caveat (SCREEN-3, SCREEN-1), `sweep-cct` without the end-of-run note and counting jobs as machines (SWEEP-2, SWEEP-1); all fixed (the probes' expectations may predate the fixed wording).
"""

# ruff: noqa: E501, RUF007, RUF021, RUF059, SIM115 - a tester's script, kept as written

import csv
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

from _probe_kit import INHERIT, Kit, stabctl

QUICK = "--quick" in sys.argv
KIT = Kit(
    "probes_y45_",
    only=[a for a in sys.argv[1:] if not a.startswith("--")],
    line="{pid:<10} {state:<5} {why}",
)
CLONE, ENV, WD, RESULTS = KIT.clone, KIT.env, KIT.wd, KIT.results
ENV.setdefault("NUMBA_CACHE_DIR", "/tmp/s45p/Y/nc")
rec, probe = KIT.rec, KIT.probe


def run(args, timeout=300, cwd=None, py=False):
    """(rc, stdout, stderr, seconds) of `python -m stabctl args` (py: `python args`); the
    caller's stdin."""
    full = [sys.executable, *map(str, args)] if py else stabctl(args)
    return KIT.run_argv(full, timeout, cwd, stdin=INHERIT)


def fnum(pattern, text, group=1):
    m = re.search(pattern, text)
    return float(m.group(group)) if m else None


def sim_verdict(args):
    """`simulate --json` of kundur/miniwecc: (stable?, json or None, rc, stderr)."""
    rc, out, err, _ = run(["simulate", *args, "--json"])
    if rc != 0:
        return None, None, rc, err
    d = json.loads(out)
    return d.get("stable"), d, rc, err


# ---------------------------------------------------------------- cct
@probe("CCT-1")
def cct_text_json_sim():
    """`cct kundur --fault 3 --far-bus 101`: the text's CCT (s and cycles), its unstable end,
    separated machines and simulation count equal --json's (docs/cli.md: 'CCT in s and
    cycles, the stable/unstable bracket, machines that separate ..., number of
    simulations'); cycles = s x 60; `simulate` cleared at the CCT is stable and at the
    unstable end is not (the CCT's definition)."""
    args = ["cct", "kundur", "--fault", "3", "--far-bus", "101"]
    rc, out, err, _ = run(args)
    rcj, outj, errj, _ = run([*args, "--json"])
    if rc != 0 or rcj != 0:
        return False, f"exit {rc}/{rcj}: {err[-200:]}{errj[-200:]}"
    d = json.loads(outj)
    bad = []
    m = re.search(
        r"CCT ([\d.]+) s = ([\d.]+) cycles \(stable at ([\d.]+) s, unstable at ([\d.]+) s = ([\d.]+) cycles",
        out,
    )
    if not m:
        return False, f"no CCT line: {out[:200]}"
    cct, cyc, st, un, uncyc = map(float, m.groups())
    for name, a, b in [
        ("cct_s", cct, d["cct_s"]),
        ("cct_cycles", cyc, d["cct_cycles"]),
        ("t_stable_s", st, d["t_stable_s"]),
        ("t_unstable_s", un, d["t_unstable_s"]),
        ("t_unstable_cycles", uncyc, d["t_unstable_cycles"]),
    ]:
        if abs(a - b) > 1e-9:
            bad.append(f"{name} text {a} json {b}")
    if abs(d["cct_cycles"] - 60 * d["cct_s"]) > 1e-6:
        bad.append(f"cycles {d['cct_cycles']} != 60 x {d['cct_s']}")
    nsim = fnum(r"(\d+) simulations \((\d+) at half", out)
    if nsim != d["n_simulations"]:
        bad.append(f"text {nsim} simulations, json {d['n_simulations']}")
    if d["n_simulations"] != len(d["probes"]) + len(d["half_step_probes"]):
        bad.append(
            f"n_simulations {d['n_simulations']} != probes {len(d['probes'])}+{len(d['half_step_probes'])}"
        )
    if "G1 (bus 1), G2 (bus 2) lose synchronism" not in out or d["separated_machines"] != [1, 2]:
        bad.append("separated machines differ")
    s1, _, rc1, e1 = sim_verdict(
        ["kundur", "--fault", 3, "--far-bus", 101, "--clear-cycles", f"{60 * d['cct_s']:.6g}"]
    )
    s2, _, rc2, e2 = sim_verdict(
        [
            "kundur",
            "--fault",
            3,
            "--far-bus",
            101,
            "--clear-cycles",
            f"{60 * d['t_unstable_s']:.6g}",
        ]
    )
    if s1 is not True:
        bad.append(f"simulate at the CCT: stable={s1} rc={rc1} {e1[-150:]}")
    if s2 is not False:
        bad.append(f"simulate at the unstable end: stable={s2} rc={rc2} {e2[-150:]}")
    return not bad, "; ".join(bad) or f"CCT {cct} s = {cyc} cycles in text, JSON and simulate"


@probe("CCT-2")
def cct_unstable_end_failure():
    """`cct kundur --fault 3 --far-bus 101 --trip 13 120` (new this week): text and --json
    both name the unstable end's failure; `simulate` cleared at the unstable end with the
    same trip fails (or is unstable) and cleared at the CCT is stable; the JSON's
    `separated_machines` ('machines that separate', docs/cli.md) does not list a machine
    that did not separate (the text calls it 'leading its swing')."""
    args = ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--trip", "13", "120"]
    rc, out, err, _ = run(args)
    rcj, outj, errj, _ = run([*args, "--json"])
    if rc != 0 or rcj != 0:
        return False, f"exit {rc}/{rcj}"
    d = json.loads(outj)
    bad = []
    uef = d.get("unstable_end_failure")
    if not uef or uef not in out:
        bad.append(f"failure text/JSON differ: json {uef!r}")
    if "lose synchronism" in out:
        bad.append("text says 'lose synchronism'")
    base = ["kundur", "--fault", 3, "--far-bus", 101, "--trip", 13, 120]
    s1, _, rc1, e1 = sim_verdict(
        [*base, "--clear-cycles", f"{60 * d['cct_s']:.6g}", "--t-trip", 1 + d["cct_s"]]
    )
    s2, j2, rc2, e2 = sim_verdict(
        [
            *base,
            "--clear-cycles",
            f"{60 * d['t_unstable_s']:.6g}",
            "--t-trip",
            1 + d["t_unstable_s"],
        ]
    )
    if s1 is not True:
        bad.append(f"simulate at the CCT stable={s1} rc={rc1} {e1.strip()[-200:]}")
    if s2 is True:
        bad.append("simulate at the unstable end is stable")
    if d.get("separated_machines"):
        bad.append(
            f"JSON separated_machines {d['separated_machines']} / separated_buses {d.get('separated_buses')} though the text says no machine separated ('leading its swing'); no JSON key says 'leading'"
        )
    return not bad, "; ".join(bad) or "failure named in both; simulate agrees"


@probe("CCT-3")
def cct_doc_miniwecc():
    """docs/cli.md: `stabctl cct miniwecc --fault 83 --far-bus 33 --tol-ms 5` prints
    `machine(s) G14 (bus 32) lose synchronism when cleared at 0.080 s`; its --json equals."""
    args = ["cct", "miniwecc", "--fault", "83", "--far-bus", "33", "--tol-ms", "5"]
    rc, out, err, _ = run(args)
    rcj, outj, _, _ = run([*args, "--json"])
    if rc != 0 or rcj != 0:
        return False, f"exit {rc}/{rcj}: {err[-200:]}"
    d = json.loads(outj)
    bad = []
    if "machine(s) G14 (bus 32) lose synchronism when cleared at 0.080 s" not in out:
        bad.append(
            "doc line not printed: "
            + " | ".join(ln for ln in out.splitlines() if "synchronism" in ln or "CCT" in ln)
        )
    cct = fnum(r"CCT ([\d.]+) s", out)
    if cct != d["cct_s"]:
        bad.append(f"text CCT {cct} json {d['cct_s']}")
    if d["separated_machines"] != [14] or d.get("separated_buses") != [32]:
        bad.append(f"json separated {d['separated_machines']} {d.get('separated_buses')}")
    return not bad, "; ".join(bad) or f"CCT {cct} s, G14 (bus 32) in text and JSON"


@probe("CCT-4")
def cct_bus_fault_vs_screen():
    """`cct kundur --fault 3` (a bus fault, no line lost) equals `screen kundur --buses 3`'s
    row and docs/cli.md's `bus 3 ... 0.238 14.28 0  G1 (bus 1), G2 (bus 2)`; the text
    does not call it a line fault."""
    rc, out, err, _ = run(["cct", "kundur", "--fault", "3", "--json"])
    rc2, out2, err2, _ = run(
        ["screen", "kundur", "--buses", "3,101", "--workers", "1", "--out", WD / "s3.jsonl"]
    )
    rc3, out3, _, _ = run(["cct", "kundur", "--fault", "3"])
    if rc != 0 or rc2 != 0:
        return False, f"exit {rc}/{rc2}: {err[-200:]} {err2[-200:]}"
    d = json.loads(out)
    bad = []
    row = next((ln for ln in out2.splitlines() if ln.startswith("bus 3 ")), "")
    if not re.search(r"bus 3\s+0\.238\s+14\.28\s+0\s+G1 \(bus 1\), G2 \(bus 2\)", row):
        bad.append(f"screen row {row!r}")
    if d["cct_s"] != 0.238:
        bad.append(f"cct {d['cct_s']}")
    if "line tripped" in out3 or "line 3-None" in out3:
        bad.append("bus fault text names a line")
    return not bad, "; ".join(bad) or "0.238 s in cct, screen and the docs"


@probe("CCT-5")
def cct_critical_group_of_failed_end():
    """`cct kundur --fault 3 --far-bus 101 --trip 13 120 --esd-pct 5 --coi critical`: the
    critical group is 'the machines that separate without storage, found by a first search'
    (docs/cli.md, cct row); the no-storage search's unstable end fails (voltage collapse)
    before any machine separates (CCT-2: 'machine(s) leading its swing'), so the output must
    not say 'machines G1 (bus 1) separate without storage' (nor arm the law on a group no
    separation found without saying so)."""
    args = [
        "cct",
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--trip",
        "13",
        "120",
        "--esd-pct",
        "5",
        "--coi",
        "critical",
    ]
    rc, out, err, _ = run(args)
    rcj, outj, _, _ = run([*args, "--json"])
    if rc != 0:
        return False, f"exit {rc}: {err[-200:]}"
    line = next((ln for ln in out.splitlines() if "separate without storage" in ln), "")
    d = json.loads(outj) if rcj == 0 else {}
    if line:
        return (
            False,
            f"text: '{line[:110]}...' though the no-storage search's unstable end failed before any separation; JSON critical_group {d.get('critical_group')}",
        )
    return True, "no separation claimed"


# ---------------------------------------------------------------- sweep-cct
@probe("SWEEP-1")
def sweep_text_json_records():
    """`sweep-cct kundur` over four faults x {none, 5 %}: every row's CCT, cycles, error (ms)
    and simulation count in the text equal the records file and --json; the summary's
    counts equal the rows; a non-monotone N-1 insecure job says so in text and records."""
    (WD / "f.csv").write_text("bus,far_bus\n3,101\n2,20\n10,20\n3,\n")
    out_f = WD / "sw.jsonl"
    args = [
        "sweep-cct",
        "kundur",
        "--faults",
        WD / "f.csv",
        "--esd-pct",
        "none,5",
        "--workers",
        "1",
        "--out",
        out_f,
    ]
    rc, out, err, _ = run(args, timeout=600)
    if rc != 0:
        return False, f"exit {rc}: {err[-300:]}"
    recs = {
        json.loads(ln)["key"]: json.loads(ln) for ln in out_f.read_text().splitlines() if ln.strip()
    }
    rcj, outj, _, _ = run([*args, "--json"])
    dj = json.loads(outj)
    jrecs = {r["key"]: r for r in dj["records"]}
    bad = []
    if set(jrecs) != set(recs):
        bad.append("json records keys != file keys")
    ncct = nins = 0
    for ln in out.splitlines():
        m = re.match(r"(kundur/\S+)\s+([\d.]+)\s+([\d.]+)\s+(\d+)\s+(\d+)\s+[\d.]+$", ln)
        if m:
            k = m.group(1)
            r = recs[k]["result"]
            ncct += 1
            for name, a, b in [
                ("cct_s", float(m.group(2)), r["cct_s"]),
                ("cct_cycles", float(m.group(3)), r["cct_cycles"]),
                ("err ms", float(m.group(4)), round(1000 * r["numerical_error_s"])),
                ("sims", int(m.group(5)), r["n_simulations"]),
            ]:
                if abs(a - b) > 1e-9:
                    bad.append(f"{k} {name} text {a} record {b}")
            if jrecs[k]["result"]["cct_s"] != r["cct_s"]:
                bad.append(f"{k} json != record")
        if "N-1 insecure" in ln and re.match(r"kundur/", ln):
            nins += 1
    sm = re.search(
        r"(\d+) CCT\(s\) found(?: \([^)]*\))?, (\d+) above the search limit \(robust\), (\d+) N-1 insecure \(CCT 0\), (\d+) failed",
        out,
    )
    if not sm:
        bad.append("no summary")
    else:
        if int(sm.group(1)) != ncct:
            bad.append(f"summary {sm.group(1)} CCTs, rows {ncct}")
        if int(sm.group(3)) != nins:
            bad.append(f"summary {sm.group(3)} N-1 insecure, rows {nins}")
    isl = re.search(r"(\d+) islanding machines", out)

    def isl_of(r):
        res = r.get("result") if isinstance(r.get("result"), dict) else {}
        out = list(res.get("islanded") or []) + [
            i for i in r.get("islanded") or [] if isinstance(i, dict)
        ]
        for v in r.values():
            if isinstance(v, dict) and v is not res:
                out += [i for i in v.get("islanded") or [] if isinstance(i, dict)]
        return out

    isl_jobs = sum(1 for r in recs.values() if any(i.get("machines") for i in isl_of(r)))
    mach = {m for r in recs.values() for i in isl_of(r) for m in i.get("machines", [])}
    if isl and int(isl.group(1)) != len(mach):
        bad.append(
            f"summary '{isl.group(0)}' while {len(mach)} machines ({sorted(mach)}) are islanded in {isl_jobs or '?'} jobs (screen says 'N fault(s) island machine(s) (M in all)')"
        )
    nc = out.count("NOT CONVERGED IN THE RUN'S END")
    if nc and "not converged" not in out.splitlines()[-1].lower():
        bad.append(
            f"{nc} rows NOT CONVERGED IN THE RUN'S END, counted among the summary's 'CCT(s) found' without a word"
        )
    return not bad, "; ".join(bad) or f"{ncct} CCT rows equal records and JSON"


@probe("SWEEP-2")
def sweep_end_concerns():
    """A CCT whose run ends off a normal operating point (`cct`: 'note: cleared at the CCT,
    at the end (t = 6 s) bus 101 at 0.564 pu: stable by the angle criterion, yet no normal
    operating point'; `screen`: 'ends off a normal operating point') is said so by
    `sweep-cct`'s text too for the same fault (kundur 10-20; its record holds
    end_concerns), and an unstable end that fails is named by the sweep's line as `cct`
    names it (code: stabctl/cli/format.py sweep_line)."""
    (WD / "f2.csv").write_text("bus,far_bus\n10,20\n")
    out_f = WD / "sw2.jsonl"
    rc, out, err, _ = run(
        [
            "sweep-cct",
            "kundur",
            "--faults",
            WD / "f2.csv",
            "--workers",
            "1",
            "--t-max",
            "0.5",
            "--out",
            out_f,
        ]
    )
    rcc, outc, _, _ = run(["cct", "kundur", "--fault", "10", "--far-bus", "20", "--t-max", "0.5"])
    recs = [json.loads(ln) for ln in out_f.read_text().splitlines() if ln.strip()]
    conc = recs[0]["result"].get("end_concerns")
    bad = []
    if conc and "no normal operating point" in outc and not any(c in out for c in conc):
        bad.append(
            f"record and cct say {conc} (cct: 'no normal operating point'); sweep-cct's text says nothing of it and its summary counts no such row (screen's does)"
        )
    import inspect  # noqa: F401

    src = Path(CLONE, "stabctl/cli/format.py").read_text()
    body = src[src.find("def sweep_line") : src.find("def ", src.find("def sweep_line") + 10)]
    if "unstable_end_failure" not in body or "end_concerns" not in body:
        bad.append(
            "sweep_line reads neither unstable_end_failure nor end_concerns"
            if "end_concerns" not in body and "unstable_end_failure" not in body
            else "sweep_line lacks one of unstable_end_failure/end_concerns"
        )
    return not bad, "; ".join(bad) or "said"


# ---------------------------------------------------------------- screen
@probe("SCREEN-1")
def screen_text_json_records():
    """`screen kundur --lines`: every row's CCT and cycles in the text equal --json's rows
    and the records; the summary counts equal the rows; a row's verdict and its caveats
    (docs/cli.md: an N-1 insecure fault stable at a later clearing is 'a verdict not
    monotone in the clearing time'; sweep-cct's text says 'yet stable when cleared at')
    appear in the text as in the JSON; the map is written (a PNG)."""
    out_f = WD / "scr.jsonl"
    args = ["screen", "kundur", "--lines", "--workers", "1", "--out", out_f]
    rc, out, err, _ = run([*args, "--plot", WD / "map.png"], timeout=600)
    if rc != 0:
        return False, f"exit {rc}: {err[-300:]}"
    rcj, outj, _, _ = run([*args, "--json"])
    rows = json.loads(outj)
    recs = [json.loads(ln) for ln in out_f.read_text().splitlines() if ln.strip()]
    bad = []
    if len(rows) != len(recs):
        bad.append(f"{len(rows)} JSON rows, {len(recs)} records")
    bykey = {r["key"]: r for r in rows}
    text_rows = [
        ln
        for ln in out.splitlines()
        if re.match(r"bus \d+( line to \d+( #\d)?)?\s+(>?[\d.]+)\s", ln)
    ]
    if len(text_rows) != len(rows):
        bad.append(f"{len(text_rows)} text rows, {len(rows)} JSON rows")
    for ln in text_rows:
        m = re.match(r"bus (\d+)(?: line to (\d+)(?: #(\d))?)?\s+(>?[\d.]+)\s+(\S+)", ln)
        b, fb, c = int(m.group(1)), m.group(2), m.group(3)
        key = (
            f"kundur/{b}-{fb}{'#' + c if c else ''}/t1/esd-none"
            if fb
            else f"kundur/bus{b}/t1/esd-none"
        )
        r = bykey.get(key)
        if r is None:
            bad.append(f"no JSON row {key}")
            continue
        if not m.group(4).startswith(">") and float(m.group(4)) != r["cct_s"]:
            bad.append(f"{key} text {m.group(4)} json {r['cct_s']}")
        if (
            "not monotone" in (r.get("reason") or "")
            and "yet stable" not in ln
            and "not monotone" not in ln
        ):
            bad.append(
                f"{key}: JSON '{r['reason'][r['reason'].find('yet') :]}' but the text row says only '{ln.split('  ')[-1].strip()}'"
            )
    sm = re.search(
        r"(\d+) CCT\(s\) found(?: \([^)]*\))?, (\d+) above the search limit \(robust\), (\d+) N-1 insecure \(CCT 0\), (\d+) failed",
        out,
    )
    counts = {"cct": 0, "above t_max": 0, "N-1 insecure": 0}
    for r in rows:
        counts[r["verdict"]] = counts.get(r["verdict"], 0) + 1
    if not sm or (int(sm.group(1)), int(sm.group(2)), int(sm.group(3))) != (
        counts["cct"],
        counts["above t_max"],
        counts["N-1 insecure"],
    ):
        bad.append(f"summary {sm and sm.groups()} rows {counts}")
    png = WD / "map.png"
    if not png.exists() or png.read_bytes()[:4] != b"\x89PNG":
        bad.append("map not written")
    return not bad, "; ".join(bad[:4]) + (
        f" (+{len(bad) - 4})" if len(bad) > 4 else ""
    ) or f"{len(rows)} rows equal in text, JSON, records"


@probe("SCREEN-2")
def screen_n1_insecure_independent():
    """An N-1 insecure row of `screen kundur --lines` ('unstable even when cleared at once')
    is checked with `simulate`: the trip alone (--trip 2 20 --t-trip 1) is unstable; and
    the JSON's claim 'stable when cleared at 0.033 s' is checked too (the label must not
    hide a fault stable when cleared in 2 cycles)."""
    s0, d0, rc0, e0 = sim_verdict(["kundur", "--trip", 2, 20, "--t-trip", 1, "--tf", 6])
    s1, d1, rc1, e1 = sim_verdict(
        ["kundur", "--fault", 2, "--far-bus", 20, "--clear-cycles", 2, "--tf", 6]
    )
    return (
        (s0 is False),
        f"trip alone stable={s0} (rc {rc0}); fault cleared at 2 cycles stable={s1} (rc {rc1}): N-1 insecure label {'holds' if s0 is False else 'contradicted'}"
        + ("" if s0 is False else f" {e0[-150:]}"),
    )


@probe("SCREEN-3")
def screen_vs_cct_flags():
    """Every flag `cct` prints for a fault (islanding, NOT CONVERGED IN THE RUN'S END, end
    concerns, an unstable end that fails) is in `screen`'s rows for the same fault
    (kundur 10-20, and the 3-101 + 13-120 failure through a sweep CSV can't be given, so
    the records' `unstable_end_failure` is checked to be carried into screen's --json)."""
    rc, out, err, _ = run(
        ["cct", "kundur", "--fault", "10", "--far-bus", "20", "--t-max", "0.5", "--json"]
    )
    d = json.loads(out)
    rows = json.loads(
        run(["screen", "kundur", "--lines", "--workers", "1", "--out", WD / "scr.jsonl", "--json"])[
            1
        ]
    )
    r = next(x for x in rows if x["key"] == "kundur/10-20/t1/esd-none")
    bad = []
    if r["cct_s"] != d["cct_s"]:
        bad.append(f"cct {d['cct_s']} screen {r['cct_s']}")
    if bool(r.get("run_end_check")) != bool(d.get("run_end_check")):
        bad.append("run_end_check differs")
    if r.get("end_concerns") != d.get("end_concerns"):
        bad.append("end_concerns differ")
    if "unstable_end_failure" not in r:
        bad.append(
            "screen --json rows carry no unstable_end_failure field (the records do): a row whose unstable end fails would list its leading machines as 'separated'"
        )
    return not bad, "; ".join(bad) or "same"


# ---------------------------------------------------------------- place
@probe("PLACE-1")
def place_text_json_out():
    """`place kundur --faults DEFAULT --required-clearing-cycles 12 --workers 1 --out F`:
    the header's MW, MWh, sites and cost, each site's MW, MWh, absorbed and delivered MWh
    (MJ / 3600) and each contingency row's times equal --out's JSON and --json; 'N of M
    contingencies stable' equals the JSON's n_met/n_contingencies; VERIFIED iff verified."""
    out_f = WD / "plan.json"
    args = [
        "place",
        "kundur",
        "--faults",
        "DEFAULT",
        "--required-clearing-cycles",
        "12",
        "--workers",
        "1",
    ]
    rc, out, err, dt = run([*args, "--out", out_f], timeout=900)
    if rc != 0:
        return False, f"exit {rc} after {dt:.0f} s: {err[-300:]}"
    d = json.loads(out_f.read_text())
    rcj, outj, errj, _ = run([*args, "--json"], timeout=900)
    dj = json.loads(outj) if rcj == 0 else {}
    bad = []
    for k in ("total_mw", "total_mwh", "n_sites", "verified", "n_met", "n_contingencies"):
        if dj.get(k) != d.get(k):
            bad.append(f"--json {k} {dj.get(k)} --out {d.get(k)}")
    m = re.search(r"\): ([\d.]+) MW, ([\d.]+) MWh at (\d+) site\(s\), cost ([\d.]+)", out)
    if not m:
        return False, f"no header: {out[:200]}"
    if (float(m.group(1)), float(m.group(2)), int(m.group(3))) != (
        round(d["total_mw"], 1),
        round(d["total_mwh"], 2),
        d["n_sites"],
    ):
        bad.append(f"header {m.groups()} json {d['total_mw']} {d['total_mwh']} {d['n_sites']}")
    if ("VERIFIED" in out) != bool(d["verified"]):
        bad.append("VERIFIED vs verified")
    if abs(sum(a["mw"] for a in d["allocation"]) - d["total_mw"]) > 0.05:
        bad.append("sites' MW do not sum to the total")
    for a in d["allocation"]:
        row = re.search(rf"^\s*{a['bus']}\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)", out, re.M)
        want = (
            round(a["mw"], 1),
            round(a["mwh"], 2),
            round(a["absorbed_mj"] / 3600, 3),
            round(a["delivered_mj"] / 3600, 3),
        )
        if not row or tuple(map(float, row.groups())) != want:
            bad.append(f"site {a['bus']} text {row and row.groups()} json {want}")
    sm = re.search(r"(\d+) of (\d+) contingencies stable", out)
    if not sm or (int(sm.group(1)), int(sm.group(2))) != (d["n_met"], d["n_contingencies"]):
        bad.append(f"count {sm and sm.groups()} json {d['n_met']}/{d['n_contingencies']}")
    for c in d["contingencies"]:
        row = re.search(
            rf"^{re.escape(c['name'])}\s+([\d.]+)\s+(\S+)\s+(\S+)\s+(yes|NO)", out, re.M
        )
        if row and (
            float(row.group(1)) != round(c["required_s"], 3) or (row.group(4) == "yes") != c["met"]
        ):
            bad.append(f"row {c['name']} {row.groups()}")
    return (
        not bad,
        "; ".join(bad)
        or f"{d['total_mw']} MW, {d['total_mwh']} MWh, {d['n_sites']} site(s) equal in text, --out and --json ({dt:.0f} s)",
    )


# ---------------------------------------------------------------- eig
def eig_probe(case, lo=None, hi=None):
    @probe(f"EIG-{case}")
    def p():
        """`eig CASE`'s text modes (f Hz, zeta) equal --json's modes and numpy's eigenvalues of
        `stabctl.linearise(stabctl.Simulator(case)).A`; Kundur's inter-area mode between 0.5
        and 0.7 Hz (Kundur, Example 12.6 / Klein-Rogers-Kundur 1991: about 0.6 Hz)."""
        rc, out, err, _ = run(["eig", case])
        rcj, outj, _, _ = run(["eig", case, "--json"])
        if rc != 0 or rcj != 0:
            return False, f"exit {rc}/{rcj}: {err[-200:]}"
        d = json.loads(outj)
        modes = {m["mode"]: m for m in d["modes"]}
        bad = []
        n = 0
        for ln in out.splitlines():
            m = re.match(r"\s*(\d+)\s+([\d.]+)\s+(-?[\d.]+)\s+(\S+)", ln)
            if not m:
                continue
            n += 1
            k = int(m.group(1))
            j = modes.get(k)
            if j is None:
                bad.append(f"mode {k} not in JSON")
                continue
            if (
                abs(float(m.group(2)) - j["freq_hz"]) > 0.0005
                or abs(float(m.group(3)) - j["damping_ratio"]) > 0.00005
                or m.group(4) != j["kind"]
            ):
                bad.append(
                    f"mode {k} text {m.group(2)} {m.group(3)} {m.group(4)} json {j['freq_hz']:.4f} {j['damping_ratio']:.5f} {j['kind']}"
                )
        em = d["electromechanical_modes"]
        if n != (len(em) if isinstance(em, list) else em):
            bad.append(
                f"{n} text rows, json electromechanical_modes {d['electromechanical_modes']}"
            )
        code = (
            "import json,sys,numpy as np,stabctl\n"
            f"lin=stabctl.linearise(stabctl.Simulator(stabctl.load_case({case!r})))\n"
            "ev=np.linalg.eigvals(np.asarray(lin.A));print(json.dumps([[e.real,e.imag] for e in ev]))\n"
        )
        rcn, outn, errn, _ = run(["-c", code], py=True)
        if rcn != 0:
            return False, f"numpy check failed: {errn[-300:]}"
        ev = [complex(a, b) for a, b in json.loads(outn)]
        import math

        for k, j in modes.items():
            if j["kind"] in ("local", "inter-area", "common") or j["freq_hz"] > 0:
                lam = complex(j["real_per_s"], j["imag_rad_per_s"])
                if min(abs(lam - e) for e in ev) > 1e-6 * max(1, abs(lam)):
                    bad.append(f"mode {k} {lam} not an eigenvalue of A")
                f = abs(lam.imag) / 2 / math.pi
                z = -lam.real / abs(lam) if abs(lam) else 1
                if abs(f - j["freq_hz"]) > 1e-9 or abs(z - j["damping_ratio"]) > 1e-9:
                    bad.append(f"mode {k} f/zeta inconsistent with its eigenvalue")
        if len(ev) != d["n_states"]:
            bad.append(f"A has {len(ev)} eigenvalues, n_states {d['n_states']}")
        ia = [m for m in d["modes"] if m["kind"] == "inter-area"]
        if lo is not None and not any(lo <= m["freq_hz"] <= hi for m in ia):
            bad.append(
                f"inter-area modes {[round(m['freq_hz'], 3) for m in ia]} outside {lo}-{hi} Hz"
            )
        return not bad, "; ".join(bad[:4]) or f"{n} modes equal in text, JSON and numpy" + (
            f"; inter-area {[round(m['freq_hz'], 3) for m in ia]} Hz" if ia else ""
        )

    return p


@probe("EIG-report")
def eig_report():
    """`eig kundur --report --out-dir R` writes reports/eig_kundur.md whose mode table equals
    --json's (frequencies and damping), and its PNGs."""
    rc, out, err, _ = run(["eig", "kundur", "--report", "--out-dir", WD / "R"])
    if rc != 0:
        return False, f"exit {rc}: {err[-300:]}"
    md = WD / "R" / "eig_kundur.md"
    if not md.exists():
        return False, f"no {md.name}: {sorted(p.name for p in (WD / 'R').glob('*'))}"
    d = json.loads(run(["eig", "kundur", "--json"])[1])
    text = md.read_text()
    bad = []
    for m in d["modes"]:
        if m["kind"] in ("local", "inter-area"):
            f, z = f"{m['freq_hz']:.3f}", f"{m['damping_ratio']:.4f}"
            if not re.search(
                rf"\|\s*{m['mode']}\s*\|[^\n]*{re.escape(f)}[^\n]*{re.escape(z)}", text
            ) and not (f in text and z in text):
                bad.append(f"mode {m['mode']} {f} Hz {z} not in the report")
    pngs = sorted(p.name for p in (WD / "R").glob("*.png"))
    for p in re.findall(r"\(([^)]+\.png)\)", text):
        if not (WD / "R" / p).exists():
            bad.append(f"report links {p}, not written")
    return not bad, "; ".join(bad) or f"report table equals JSON; {len(pngs)} PNGs"


# ---------------------------------------------------------------- estimate
@probe("TRACK-1")
def track_csv_summary():
    """`pmu serve` + `pmu record` a Kundur run, then `estimate track kundur --source FILE
    --esd-pct 5 --out t.csv`: one CSV row per frame, the columns' units in their names (Hz,
    mHz), t_s from 0 at the frame rate, rel = 1000 (f_i - f_COI) (docs/estimation.md 6.1:
    'relative speeds (mHz, forecast over the latency')' - so allowed to differ), the
    summary's largest |f_i - f_COI|, its machine and time and the ESD start count equal the
    CSV's."""
    port = 47000 + os.getpid() % 900
    srv = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "stabctl",
            "pmu",
            "serve",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--clear-cycles",
            "7",
            "--tf",
            "3",
            "--port",
            str(port),
            "--speed",
            "0",
        ],
        cwd=WD,
        env=ENV,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        time.sleep(1)
        for _ in range(30):
            rc, out, err, _ = run(
                ["pmu", "record", f"127.0.0.1:{port}", "--frames", "181", "-o", WD / "k.c37"],
                timeout=120,
            )
            if rc == 0 or "refused" not in err.lower() and "connect" not in err.lower():
                break
            time.sleep(1)
        if rc != 0:
            return False, f"record exit {rc}: {err[-200:]}"
    finally:
        try:
            srv.wait(timeout=30)
        except subprocess.TimeoutExpired:
            srv.kill()
            srv.wait()
    rc, out, err, _ = run(
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            WD / "k.c37",
            "--esd-pct",
            "5",
            "--out",
            WD / "t.csv",
        ]
    )
    if rc != 0:
        return False, f"track exit {rc}: {err[-200:]}"
    rows = list(csv.DictReader(open(WD / "t.csv")))
    bad = []
    cols = list(rows[0])
    if len(rows) != 181:
        bad.append(f"{len(rows)} rows for 181 frames")
    for c in cols:
        if c != "t_s" and not c.startswith("mode_") and not re.search(r"_(hz|mhz|s)$", c):
            bad.append(f"column {c} without unit")
    rel = [c for c in cols if c.startswith("rel_")]
    mx = max((abs(float(r[c])), c, float(r["t_s"])) for r in rows for c in rel)
    m = re.search(
        # the machine as every output names it since 2026-12-02: "G2 (bus 2; PMU B2:G2)"
        r"largest \|f_i - f_COI\| ([\d.]+) mHz \(.*?PMU (\S+?)\) at ([\d.]+) s\); (\d+) ESD "
        r"starts; wrote",
        out,
    )
    if not m:
        bad.append(f"summary {out.strip()[:200]}")
    else:
        if (
            abs(float(m.group(1)) - mx[0]) > 0.05
            or f"rel_{m.group(2)}_mhz" != mx[1]
            or abs(float(m.group(3)) - mx[2]) > 1e-3
        ):
            bad.append(f"summary {m.group(0)} CSV {mx}")
        starts = 0
        for c in [c for c in cols if c.startswith("mode_")]:
            prev = 0
            for r in rows:
                v = int(float(r[c]))
                starts += v != 0 and v != prev
                prev = v
        if starts != int(m.group(4)):
            bad.append(f"summary {m.group(4)} ESD starts, CSV {starts}")
    dts = {round(float(b["t_s"]) - float(a["t_s"]), 9) for a, b in zip(rows, rows[1:])}
    if any(abs(x - 1 / 60) > 1e-6 for x in dts):
        bad.append(f"frame spacings {sorted(dts)[:3]}")
    return not bad, "; ".join(bad) or f"{len(rows)} rows; summary equals CSV ({m.group(0)[:60]})"


@probe("RMSE-1")
def rmse_text_json():
    """`estimate rmse kundur ... --runs 2`: the text table's numbers equal --json's."""
    args = [
        "estimate",
        "rmse",
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--clear-cycles",
        "7",
        "--tf",
        "3",
        "--runs",
        "2",
        "--ambient-runs",
        "1",
        "--ambient-s",
        "5",
    ]
    rc, out, err, _ = run(args)
    rcj, outj, _, _ = run([*args, "--json"])
    if rc != 0 or rcj != 0:
        return False, f"exit {rc}/{rcj}: {err[-200:]}"
    d = json.loads(outj)
    flat = json.dumps(d)
    bad = []
    for ln in out.splitlines():
        m = re.match(r"(raw|kf|ekf)\s+(.*)", ln)
        if m:
            for v in re.findall(r"(\d+\.\d+) \+-", m.group(2)):
                val = float(v)
                found = any(
                    abs(val - float(x)) <= 0.0005 + 1e-12
                    for x in re.findall(r"-?\d+\.\d+(?:e-?\d+)?", flat)
                )
                if not found:
                    bad.append(f"{m.group(1)} {v} not in JSON")
    return not bad, "; ".join(bad[:4]) or "table equals JSON"


# ---------------------------------------------------------------- examples and docs
def example_probe(script):
    @probe(f"EX-{script.stem[:6]}")
    def p():
        """examples/X.py runs as written from a clean temporary directory (docs/examples.md:
        'seven short scripts, one per task (run by the tests)'), exit 0, no traceback."""
        cwd = WD / f"ex_{script.stem}"
        cwd.mkdir()
        rc, out, err, dt = run([script], py=True, cwd=cwd, timeout=600)
        ok = rc == 0 and "Traceback" not in err
        return ok, f"exit {rc} in {dt:.0f} s" + ("" if ok else f": {err.strip()[-250:]}")

    return p


@probe("DOC-readme")
def doc_readme():
    """README's one-minute start: each command prints the lines shown (CCT 0.154 s = 9.24
    cycles ...; Kundur's modes 0.612/1.292/1.340 Hz; miniwecc 'stable: largest angle from the
    COI 1.8940 rad'), and its Python snippet prints 0.154."""
    bad = []
    rc, out, err, _ = run(
        [
            "simulate",
            "miniwecc",
            "--fault",
            "83",
            "--far-bus",
            "33",
            "--clear-cycles",
            "6",
            "--esd-pct",
            "5",
        ]
    )
    if "stable: largest angle from the COI 1.8940 rad" not in out:
        bad.append(f"simulate: {[ln for ln in out.splitlines() if 'stable' in ln][:1]} rc {rc}")
    for want in [
        "3-phase fault at bus 83 at 1 s on line 83-33 (circuit 1), cleared at 1.1 s (after 100.0 ms), line tripped",
        "storage: 34 ESDs of 5 % of machine MVA at the generator HV buses",
    ]:
        if want not in out:
            bad.append(f"simulate lacks {want[:40]!r}")
    rc, out, err, _ = run(["cct", "kundur", "--fault", "3", "--far-bus", "101"])
    if (
        "CCT 0.154 s = 9.24 cycles (stable at 0.154 s, unstable at 0.155 s = 9.30 cycles; tolerance 1 ms"
        not in out
    ):
        bad.append(f"cct: {out.splitlines()[1:2]}")
    rc, out, err, _ = run(["eig", "kundur"])
    for want in [
        "   36   0.612   0.1319  inter-area G3 (bus 11) G4 (bus 12) vs G1 (bus 1) G2 (bus 2)  [areas 2 vs 1]",
        "   37   1.292   0.3637  local      G4 (bus 12) G2 (bus 2) vs G3 (bus 11) G1 (bus 1)",
        "   38   1.340   0.3560  local      G2 (bus 2) G3 (bus 11) vs G1 (bus 1) G4 (bus 12)",
    ]:
        if want not in out:
            bad.append(f"eig lacks {want.strip()[:30]!r}")
    code = "import stabctl\ncase = stabctl.load_case('kundur')\nsim = stabctl.Simulator(case)\nfault = stabctl.LineFault(3, 101, 1.0)\nprint(stabctl.critical_clearing_time(sim, fault).cct_s)\nmodes = stabctl.modal_analysis(stabctl.linearise(sim))\n"
    rc, out, err, _ = run(["-c", code], py=True)
    if out.strip() != "0.154":
        bad.append(f"python snippet printed {out.strip()!r} rc {rc} {err[-150:]}")
    rc, out, err, _ = run(["cases", "kundur", "--bus-table", "--line-table"])
    if rc != 0:
        bad.append(f"cases exit {rc}")
    return not bad, "; ".join(bad) or "README commands print what it shows"


@probe("DOC-cli")
def doc_cli():
    """docs/cli.md's short examples run as written: the study-events simulate example,
    `screen kundur --buses 3,101` (checked in CCT-4), `omib --fault-cycles 6 12 15`,
    `cct kundur --fault 3`, the cct --help examples."""
    bad = []
    for args in (
        [
            "simulate",
            "kundur",
            "--bus-fault",
            "3:0:0.05",
            "1",
            "1.1",
            "--trip",
            "3",
            "101",
            "--t-trip",
            "1.1",
            "--close",
            "3",
            "101",
            "1.6",
            "--vref-step",
            "2",
            "3",
            "0.02",
            "--pref-step",
            "1",
            "4",
            "0.05",
            "--tf",
            "10",
        ],
        ["omib", "--fault-cycles", "6", "12", "15"],
        ["cct", "kundur", "--fault", "3"],
        ["cases"],
        ["cases", "kundur"],
    ):
        rc, out, err, dt = run(args)
        if rc != 0 or "Traceback" in err:
            bad.append(f"{' '.join(args[:3])}: exit {rc} {err.strip()[-150:]}")
    return not bad, "; ".join(bad) or "ran"


def main():
    probes = [
        cct_text_json_sim,
        cct_unstable_end_failure,
        cct_doc_miniwecc,
        cct_bus_fault_vs_screen,
        cct_critical_group_of_failed_end,
        sweep_text_json_records,
        sweep_end_concerns,
        screen_text_json_records,
        screen_n1_insecure_independent,
        screen_vs_cct_flags,
        eig_probe("kundur", 0.5, 0.7),
        eig_probe("miniwecc"),
        eig_report,
        track_csv_summary,
        rmse_text_json,
        doc_readme,
        doc_cli,
    ]
    if not QUICK:
        probes.append(place_text_json_out)
        probes += [example_probe(p) for p in sorted(Path(CLONE, "examples").glob("*.py"))]
    KIT.main(
        probes,
        banner="work dir {wd}",
        summary="{ok} ok, {short} SHORT, {secs:.0f} s",
        keep_any=True,
        kept=None,
    )


if __name__ == "__main__":
    signal.signal(signal.SIGTERM, lambda *a: sys.exit(143))
    main()
