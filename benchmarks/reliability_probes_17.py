#!/usr/bin/env python
"""Seventeenth reliability round (round 39, part L): the same fault's verdict across
commands: `cct`, `screen`, `sweep-cct`, `place`'s CCT without storage and `simulate` runs
cleared at each bracket's ends; half-step error bars; bus and branch faults, parallel
circuits, islanding of load buses and machines, N-1 insecure and robust faults, their
labels and counts; workers, Dask and resumed screenings; conventions, Q limits, tolerance
and search limits; `eig` against a ringdown.  Kundur, miniWECC, IEEE 14 imported from
ANDES and a PSS/E SMIB.

    python benchmarks/reliability_probes_17.py

The package under test is this repository's (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's; XDG_CACHE_HOME a temporary directory.  Prints per
probe: id, ok/SHORT, one-line reason; exits 1 if any is SHORT.  About 5 minutes on two
cores with a warm kernel cache.  The round found short: Kundur's 3-4 "N-1 insecure, CCT
0" though stable cleared after 1 to 3 cycles (now named with the verdict), the Q limits,
search limit and settings missing from the text outputs, `sweep-cct` silent about the
islands its faults make; all fixed.
"""

# ruff: noqa: E501, BLE001, SIM115, RUF059, UP031 - a tester's script, kept as written
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
CLONE = os.environ.get("CLONE", os.path.dirname(HERE))  # the package under test
ENV = dict(os.environ, PYTHONPATH=CLONE, XDG_CACHE_HOME=tempfile.mkdtemp(prefix="xdg."))
RESULTS = []
T0 = time.time()


def run(args, cwd, timeout=300):
    p = subprocess.run(
        ["stabctl"] + [str(a) for a in args],
        cwd=cwd,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return p.returncode, p.stdout, p.stderr


def runj(args, cwd, timeout=300):
    rc, out, err = run(list(args) + ["--json"], cwd, timeout)
    try:
        return rc, json.loads(out), err
    except Exception:
        return rc, None, err + out


def probe(pid, fn):
    try:
        ok, why = fn()
    except subprocess.TimeoutExpired as e:
        ok, why = False, f"timeout: {e.cmd[-6:]}"
    except Exception as e:  # a probe bug is a SHORT too, with its reason
        ok, why = False, f"probe error {type(e).__name__}: {e}"
    RESULTS.append((pid, ok, why))
    print(f"{pid:5s} {'ok' if ok else 'SHORT':5s} {why}", flush=True)


def records(path):
    out = {}
    for line in open(path):
        d = json.loads(line)
        out[d["key"]] = d
    return out


def strip(rec):
    """A record without timings / worker ids, for identity checks."""
    drop = {"wall_time_s", "worker", "time", "started", "finished", "host", "pid"}
    if isinstance(rec, dict):
        return {k: strip(v) for k, v in rec.items() if k not in drop}
    if isinstance(rec, list):
        return [strip(v) for v in rec]
    return rec


def verdict_of(rec):
    """(cct_s or None, label, islanded-bus set) from a screen/sweep record or a cct JSON."""
    r = rec.get("result", rec)
    if rec.get("status") == "verdict" or r.get("verdict") in ("above t_max", "N-1 insecure"):
        lab = rec.get("verdict") or r.get("verdict")
        cct = 0.0 if lab == "N-1 insecure" else None
    elif rec.get("status") == "failed":
        return (None, "failed", frozenset())
    else:
        lab, cct = "cct", r.get("cct_s")
    isl = rec.get("islanded") or r.get("islanded") or []
    buses = frozenset(b for i in isl for b in i.get("buses", []))
    return (cct, lab, buses)


def sim_verdict(case, fault, far, circuit, clear_s, cwd, extra=()):
    args = ["simulate", case, "--fault", fault, "--clear-cycles", repr(round(clear_s * 60, 6))]
    if far is not None:
        args += ["--far-bus", far, "--circuit", circuit]
    rc, d, err = runj(args + list(extra), cwd)
    if d is None:
        return None, err.strip().splitlines()[-1:] if err else rc
    return d["stable"], d


def fault_args(bus, far, circuit):
    a = ["--fault", bus]
    if far is not None:
        a += ["--far-bus", far, "--circuit", circuit]
    return a


def main():
    tmp = tempfile.mkdtemp(prefix="probes_l_")
    W = tmp
    print(f"workdir {W}; clone {CLONE}", flush=True)
    S = {}

    # ---------------------------------------------------------------- kundur screening
    def p01():
        rc, out, _err = run(
            ["screen", "kundur", "--lines", "--workers", "1", "--out", "k1.jsonl"], W
        )
        S["k1_text"] = out
        recs = records(os.path.join(W, "k1.jsonl"))
        S["k1"] = recs
        last = out.strip().splitlines()[-1]
        m = re.search(
            r"(\d+) fault\(s\).*?(\d+) CCT\(s\) found(?: \([^)]*\))?, (\d+) above.*?, (\d+) N-1 "
            r"insecure.*?, (\d+) failed",
            last,
        )
        if rc != 0 or not m:
            return False, f"rc={rc}, summary not parsed: {last[:120]}"
        n, ncct, nrob, nins, nfail = map(int, m.groups())
        kinds = [verdict_of(r)[1] for r in recs.values()]
        got = (
            len(recs),
            kinds.count("cct"),
            kinds.count("above t_max"),
            kinds.count("N-1 insecure"),
            kinds.count("failed"),
        )
        if (n, ncct, nrob, nins, nfail) != got or ncct + nrob + nins + nfail != n:
            return False, f"summary {(n, ncct, nrob, nins, nfail)} vs records {got}"
        # round 42's words: "N fault(s) island load bus(es) (M in all; ...)", the machines'
        # part left out when no fault islands one
        m2 = re.search(r"(\d+) fault\(s\) island load bus\(es\)", last)
        m3 = re.search(r"(\d+) fault\(s\) island machine\(s\)", last)
        m2 = m2 and (m2.group(1), m3.group(1) if m3 else "0")
        isl_load = sum(
            1
            for r in recs.values()
            if any(
                "load_shed_pu" in i
                for i in (r.get("islanded") or r.get("result", {}).get("islanded") or [])
            )
        )
        isl_mach = sum(
            1
            for r in recs.values()
            if any(
                i.get("machines")
                for i in (r.get("islanded") or r.get("result", {}).get("islanded") or [])
            )
        )
        if not m2 or (int(m2[0]), int(m2[1])) != (isl_load, isl_mach):
            return (
                False,
                f"island counts in text {m2} vs records {(isl_load, isl_mach)}",
            )
        nrows_named = len(re.findall(r"islands ", out))
        if nrows_named != isl_load + isl_mach:
            return (
                False,
                f"{nrows_named} 'islands' lines in text vs {isl_load + isl_mach} islanding records",
            )
        return (
            True,
            f"{n} searches = {ncct} CCT + {nrob} robust + {nins} insecure + {nfail} failed; islands {isl_load} load/{isl_mach} machine, named in text",
        )

    probe("L01", p01)

    FAULTS = [
        (3, 101, 1),
        (3, 101, 2),
        (10, 20, 1),
        (1, 10, 1),
        (3, 4, 1),
        (3, 20, 1),
        (13, 101, 2),
        (13, None, 1),
        (110, None, 1),
        (3, None, 1),
    ]

    def key(b, f, c):
        if f is None:
            return f"kundur/bus{b}/t1/esd-none"
        return f"kundur/{b}-{f}{'#%d' % c if c != 1 else ''}/t1/esd-none"

    def p02():
        bad, S["cct"] = [], {}
        for b, f, c in FAULTS:
            rc, d, err = runj(["cct", "kundur", "--t-max", "0.5"] + fault_args(b, f, c), W)
            if d is None:
                bad.append(f"{b}-{f}#{c}: rc={rc} {err.strip()[-100:]}")
                continue
            S["cct"][(b, f, c)] = d
            a, s = verdict_of(d), verdict_of(S["k1"][key(b, f, c)])
            if a != s:
                bad.append(f"{b}-{f}#{c}: cct {a} vs screen {s}")
        return (not bad), "; ".join(
            bad
        ) or f"{len(FAULTS)} faults: cct --json == screen records (CCT, label, islanded buses)"

    probe("L02", p02)

    def p03():
        bad = []
        for b, f, c in [(3, 101, 1), (3, 4, 1), (3, 20, 1), (10, 20, 1)]:
            _rc, out, _err = run(["cct", "kundur", "--t-max", "0.5"] + fault_args(b, f, c), W)
            d = S["cct"][(b, f, c)]
            cct, lab, isl = verdict_of(d)
            if lab == "cct" and f"CCT {cct:.3f} s" not in out:
                bad.append(f"{b}-{f}: text lacks 'CCT {cct:.3f} s'")
            if lab == "N-1 insecure" and "N-1 insecure" not in out:
                bad.append(f"{b}-{f}: text lacks N-1 insecure")
            if lab == "above t_max" and "above the search limit" not in out:
                bad.append(f"{b}-{f}: text lacks robust label")
            for bus in isl:
                if str(bus) not in out.split("islanded")[0][-200:] + out:
                    bad.append(f"{b}-{f}: island bus {bus} not named")
            if isl and "island" not in out:
                bad.append(f"{b}-{f}: islanding not named in text")
        return (not bad), "; ".join(bad) or "cct text agrees with its JSON (CCT, labels, islands)"

    probe("L03", p03)

    def p04():
        with open(os.path.join(W, "f.csv"), "w") as fh:
            fh.write("bus,far_bus,t_fault,circuit\n")
            for b, f, c in FAULTS:
                fh.write(f"{b},{'' if f is None else f},,{c if f is not None else ''}\n")
        rc, out, _err = run(
            [
                "sweep-cct",
                "kundur",
                "--faults",
                "f.csv",
                "--t-max",
                "0.5",
                "--workers",
                "1",
                "--out",
                "s.jsonl",
            ],
            W,
        )
        S["sweep_text"] = out
        recs = records(os.path.join(W, "s.jsonl"))
        bad = []
        for b, f, c in FAULTS:
            k = key(b, f, c)
            if k not in recs:
                bad.append(f"{k} missing")
                continue
            if verdict_of(recs[k]) != verdict_of(S["k1"][k]):
                bad.append(f"{k}: sweep {verdict_of(recs[k])} vs screen {verdict_of(S['k1'][k])}")
            ri, si = recs[k]["inputs"], S["k1"][k]["inputs"]
            dk = set(x for x in set(ri) | set(si) if x != "guess_s" and ri.get(x) != si.get(x))
            if dk:
                bad.append(f"{k}: inputs differ {dk}")
        return (not bad), "; ".join(
            bad
        ) or f"rc={rc}; sweep-cct records == screen records for {len(FAULTS)} faults"

    probe("L04", p04)

    def p05():
        # sweep-cct's text: are the islanding faults' islands named, as screen and cct do?
        out = S["sweep_text"]
        miss = []
        for b, f, c in FAULTS:
            isl = verdict_of(S["k1"][key(b, f, c)])[2]
            if isl:
                row = [l for l in out.splitlines() if key(b, f, c) in l]
                if not any("island" in l for l in out.splitlines()) or not row:
                    miss.append(f"{b}-{f} (islands {sorted(isl)})")
        summ = out.strip().splitlines()[-1]
        if miss:
            return False, (
                f"sweep-cct text names no islanding for {', '.join(miss)}; summary "
                f"'{summ[:90]}...' has no island count (screen/cct name them)"
            )
        return True, "sweep-cct text names islands"

    probe("L05", p05)

    def p06():
        fl = [(3, 101, 1), (3, 101, 2), (10, 20, 1), (13, None, 1)]
        with open(os.path.join(W, "f2.csv"), "w") as fh:
            fh.write("bus,far_bus,t_fault,circuit\n")
            for b, f, c in fl:
                fh.write(f"{b},{'' if f is None else f},,{c if f is not None else ''}\n")
        rc, out, err = run(
            [
                "place",
                "kundur",
                "--faults",
                "f2.csv",
                "--t-max",
                "0.5",
                "--target-cct-gain",
                "5",
                "--workers",
                "1",
                "--out",
                "p.json",
            ],
            W,
            timeout=600,
        )
        if rc != 0:
            return False, f"place rc={rc}: {err.strip()[-150:]}"
        d = json.load(open(os.path.join(W, "p.json")))
        bad = []
        by = {c["name"]: c for c in d["contingencies"]}
        for b, f, c in fl:
            name = f"{b}" if f is None else f"{b}-{f}" + (f"#{c}" if c != 1 else "")
            cj = S["cct"][(b, f, c)]
            cc, lab, _ = verdict_of(cj)
            pc = by[name]
            if lab == "cct":
                if pc["cct_no_storage_s"] != cc:
                    bad.append(f"{name}: place no-ESD {pc['cct_no_storage_s']} vs cct {cc}")
                row = [l for l in out.splitlines() if l.startswith(name + " ")]
                if not row or f"{cc:.3f}" not in row[0]:
                    bad.append(f"{name}: text no-ESD column {row} vs {cc}")
            elif lab == "above t_max" and not pc["cct_no_storage_above_t_max"]:
                bad.append(f"{name}: robust not flagged in place")
        return (not bad), "; ".join(bad) or "place no-ESD CCTs (text, JSON) == cct"

    probe("L06", p06)

    def p07():
        bad, n = [], 0
        for (b, f, c), d in S["cct"].items():
            if verdict_of(d)[1] != "cct":
                continue
            st, _ = sim_verdict("kundur", b, f, c, d["t_stable_s"], W)
            un, _ = sim_verdict("kundur", b, f, c, d["t_unstable_s"], W)
            n += 2
            if st is not True or un is not False:
                bad.append(
                    f"{b}-{f}#{c}: simulate at {d['t_stable_s']} {st}, at {d['t_unstable_s']} {un}"
                )
        return (not bad), "; ".join(bad) or f"{n} simulate runs at the bracket ends agree with cct"

    probe("L07", p07)

    def p08():
        bad, n = [], 0
        for (b, f, c), d in S["cct"].items():
            cct, lab, _ = verdict_of(d)
            if lab == "cct":
                for fr in (0.3, 0.6, 0.9):
                    t = round(cct * fr, 3)
                    st, _ = sim_verdict("kundur", b, f, c, t, W)
                    n += 1
                    if st is not True:
                        bad.append(f"{b}-{f}#{c}: CCT {cct} but cleared at {t} s: {st}")
            elif lab == "N-1 insecure":  # stable later only where the verdict says so
                said = d.get("reason", "")
                for cyc in (1, 2, 3):
                    st, _ = sim_verdict("kundur", b, f, c, cyc / 60, W)
                    n += 1
                    named = (
                        f"{round(cyc / 60, 3):g}" in said.split("yet stable when cleared at")[-1]
                    )
                    if st is not False and not ("yet stable when cleared at" in said and named):
                        bad.append(
                            f"{b}-{f}#{c}: 'N-1 insecure, CCT 0' but simulate cleared after {cyc} cycle(s): stable, unsaid"
                        )
        return (not bad), "; ".join(
            bad
        ) or f"{n} runs below each CCT stable; insecure ones unstable"

    probe("L08", p08)

    def p09():
        bad = []
        for b, f, c in [(3, 101, 1), (10, 20, 1), (110, None, 1), (1, 10, 1)]:
            d = S["cct"][(b, f, c)]
            rc, h, _err = runj(
                ["cct", "kundur", "--t-max", "0.5", "--step", "0.0025"] + fault_args(b, f, c), W
            )
            if h is None:
                bad.append(f"{b}-{f}: rc={rc}")
                continue
            lo = d["cct_s"] - d["numerical_error_s"] - d["tol_s"] - 1e-9
            hi = d["cct_s"] + d["numerical_error_s"] + d["tol_s"] + 1e-9
            if (
                not (lo <= h["cct_s"] <= hi)
                or abs(h["cct_s"] - d["cct_half_step_s"]) > d["tol_s"] + 1e-9
            ):
                bad.append(
                    f"{b}-{f}: CCT(h)={d['cct_s']}+-{d['numerical_error_s']}, cct_half_step_s={d['cct_half_step_s']}, cct --step h/2 gives {h['cct_s']}"
                )
            if h["step_s"] != 0.0025:
                bad.append(f"{b}-{f}: --step 0.0025 recorded as {h['step_s']}")
        return (not bad), "; ".join(bad) or "cct --step h/2 inside each half-step error bar (+tol)"

    probe("L09", p09)

    def p10():
        _rc, out, _err = run(
            ["screen", "kundur", "--lines", "--workers", "2", "--out", "k2.jsonl"], W
        )
        r2 = records(os.path.join(W, "k2.jsonl"))
        r1 = S["k1"]
        diff = [k for k in r1 if k not in r2 or strip(r1[k]) != strip(r2[k])]
        t1 = [l for l in S["k1_text"].splitlines()]
        t2 = [l for l in out.splitlines()]
        tdiff = [l for l in set(t1) ^ set(t2) if "already in" not in l]
        if diff or set(r2) - set(r1):
            return False, f"--workers 2 records differ from --workers 1: {diff[:4]}"
        if tdiff and any("run now" not in l for l in tdiff):
            return False, f"text differs: {tdiff[:3]}"
        return True, f"{len(r1)} records identical between --workers 1 and 2 (bar timings)"

    probe("L10", p10)

    def p11():
        try:
            import dask.distributed  # noqa
        except Exception:
            return True, "dask not installed: skipped"
        rc, out, err = run(
            [
                "screen",
                "kundur",
                "--buses",
                "1,3,13",
                "--lines",
                "--workers",
                "2",
                "--scheduler",
                "local",
                "--out",
                "kd.jsonl",
            ],
            W,
            timeout=400,
        )
        if rc not in (0,):
            return False, f"--scheduler local rc={rc}: {err.strip()[-150:]}"
        rd = records(os.path.join(W, "kd.jsonl"))
        rc, _out, err = run(
            [
                "screen",
                "kundur",
                "--buses",
                "1,3,13",
                "--lines",
                "--workers",
                "1",
                "--out",
                "kl.jsonl",
            ],
            W,
        )
        rl = records(os.path.join(W, "kl.jsonl"))
        diff = [k for k in rl if k not in rd or strip(rl[k]) != strip(rd[k])]
        if diff or set(rd) != set(rl):
            return False, f"--scheduler local records differ: {diff[:4]} {set(rd) ^ set(rl)}"
        return True, f"{len(rl)} records identical: --scheduler local vs local workers"

    probe("L11", p11)

    def p12():
        src = os.path.join(W, "k1.jsonl")
        lines = open(src).read().splitlines()
        with open(os.path.join(W, "kr.jsonl"), "w") as fh:
            fh.write("\n".join(lines[:9] + lines[14:18]) + "\n")
        rc, out, _err = run(
            ["screen", "kundur", "--lines", "--workers", "1", "--out", "kr.jsonl"], W
        )
        rr = records(os.path.join(W, "kr.jsonl"))
        diff = [k for k in S["k1"] if k not in rr or strip(rr[k]) != strip(S["k1"][k])]

        def body(t):
            return sorted(l for l in t.splitlines() if "fault(s):" not in l)

        if rc != 0 or diff or set(rr) != set(S["k1"]):
            return False, f"rc={rc}; resumed records differ: {diff[:4]}"
        if body(out) != body(S["k1_text"]):
            return (
                False,
                f"resumed text table differs from fresh: {set(body(out)) ^ set(body(S['k1_text']))}",
            )
        if "14 run now, 13 already" not in out:
            return False, f"summary: {out.strip().splitlines()[-1][:100]}"
        return True, "resumed screening (13 of 27 kept) == fresh, text and records"

    probe("L12", p12)

    # ---------------------------------------------------------------- settings
    def p13():
        bad = []
        rc, d, err = runj(
            [
                "cct",
                "kundur",
                "--t-max",
                "0.5",
                "--conventions",
                "pstess",
                "--fault",
                3,
                "--far-bus",
                101,
            ],
            W,
        )
        if d is None:
            return False, f"rc={rc} {err[-100:]}"
        if d["conventions"] != "pstess" or abs(d["step_s"] - 0.01) > 1e-12:
            bad.append(f"recorded conventions {d['conventions']} step {d['step_s']}")
        rc, txt, _ = run(
            [
                "cct",
                "kundur",
                "--t-max",
                "0.5",
                "--conventions",
                "pstess",
                "--fault",
                3,
                "--far-bus",
                101,
            ],
            W,
        )
        if "pstess" not in txt or "step 10 ms" not in txt:
            bad.append("text does not give the pstess conventions and 10 ms step")
        if verdict_of(d)[1] == "cct":
            st, _ = sim_verdict(
                "kundur", 3, 101, 1, d["t_stable_s"], W, ["--conventions", "pstess"]
            )
            un, _ = sim_verdict(
                "kundur", 3, 101, 1, d["t_unstable_s"], W, ["--conventions", "pstess"]
            )
            if st is not True or un is not False:
                bad.append(
                    f"simulate pstess at {d['t_stable_s']}: {st}, at {d['t_unstable_s']}: {un}"
                )
        rc, _s, err = runj(
            [
                "sweep-cct",
                "kundur",
                "--faults",
                "DEFAULT",
                "--conventions",
                "pstess",
                "--t-max",
                "0.5",
                "--workers",
                "1",
                "--out",
                "sp.jsonl",
            ],
            W,
        )
        rec = records(os.path.join(W, "sp.jsonl")).get("kundur/3-101/t1/esd-none/pstess")
        if (
            rec is None
            or verdict_of(rec) != verdict_of(d)
            or rec["inputs"].get("conventions") != "pstess"
        ):
            bad.append(f"sweep-cct pstess record {rec and verdict_of(rec)} vs cct {verdict_of(d)}")
        return (not bad), "; ".join(
            bad
        ) or f"pstess: CCT {d.get('cct_s')} s at 10 ms; cct/simulate/sweep agree, settings recorded"

    probe("L13", p13)

    def p14():
        bad = []
        rc, d, err = runj(
            ["cct", "kundur", "--t-max", "0.5", "--no-q-limits", "--fault", 3, "--far-bus", 101], W
        )
        if d is None:
            return False, f"rc={rc} {err[-100:]}"
        if d.get("q_limits") is not False:
            bad.append(f"q_limits recorded {d.get('q_limits')}")
        if verdict_of(d)[1] == "cct":
            st, _ = sim_verdict("kundur", 3, 101, 1, d["t_stable_s"], W, ["--no-q-limits"])
            un, _ = sim_verdict("kundur", 3, 101, 1, d["t_unstable_s"], W, ["--no-q-limits"])
            if st is not True or un is not False:
                bad.append(f"simulate --no-q-limits at bracket: {st}/{un}")
        rc, out, err = run(
            ["cct", "kundur", "--t-max", "0.5", "--no-q-limits", "--fault", 3, "--far-bus", 101], W
        )
        if "q limit" not in out.lower() and "q-limit" not in out.lower():
            bad.append("text does not say the power flow ran without Q limits")
        rc, out, err = run(
            [
                "screen",
                "kundur",
                "--buses",
                "3",
                "--no-q-limits",
                "--workers",
                "1",
                "--out",
                "nq.jsonl",
            ],
            W,
        )
        r = next(iter(records(os.path.join(W, "nq.jsonl")).values()))
        if "q_limits" not in json.dumps(r["inputs"]):
            bad.append(f"screen --no-q-limits record inputs lack q_limits: {sorted(r['inputs'])}")
        return (not bad), "; ".join(bad) or f"--no-q-limits CCT {d.get('cct_s')} recorded and shown"

    probe("L14", p14)

    def p15():
        _rc, d, _err = runj(
            ["cct", "kundur", "--t-max", "0.5", "--tol-ms", "5", "--fault", 3, "--far-bus", 101], W
        )
        base = S["cct"][(3, 101, 1)]
        bad = []
        if abs(round(d["cct_s"] / 0.005) * 0.005 - d["cct_s"]) > 1e-9:
            bad.append(f"CCT {d['cct_s']} not a multiple of 5 ms")
        if not (
            d["cct_s"] <= base["cct_s"] + 1e-9 and d["t_unstable_s"] >= base["t_unstable_s"] - 1e-9
        ):
            bad.append(
                f"tol 5 ms bracket [{d['cct_s']}, {d['t_unstable_s']}] does not contain the 1 ms one [{base['cct_s']}, {base['t_unstable_s']}]"
            )
        if d["tol_s"] != 0.005:
            bad.append(f"tol recorded {d['tol_s']}")
        return (not bad), "; ".join(
            bad
        ) or f"--tol-ms 5: [{d['cct_s']}, {d['t_unstable_s']}] contains 1 ms bracket, recorded"

    probe("L15", p15)

    def p16():
        # search limit recorded and used: screen default 0.5 vs cct default 1.0 on a robust fault
        _rc, d, _err = runj(["cct", "kundur", "--fault", 13], W)
        s = S["k1"]["kundur/bus13/t1/esd-none"]
        bad = []
        if s["inputs"]["t_max"] != 0.5:
            bad.append(f"screen record t_max {s['inputs']['t_max']}")
        if "0.5" not in s.get("reason", ""):
            bad.append("screen robust reason lacks its limit")
        v = verdict_of(d)
        if v[1] == "cct" and d["cct_s"] < 0.5:
            bad.append(
                f"cct default t_max gives CCT {d['cct_s']} <= 0.5 but screen says robust above 0.5"
            )
        return (
            (not bad),
            "; ".join(bad)
            or f"bus 13: screen robust >0.5 (recorded); cct --t-max 1.0: {v[1]} {d.get('cct_s') or d.get('above_t_max_s')}",
        )

    probe("L16", p16)

    def p22():
        bad = []
        for b, f, c in [(3, 101, 1), (10, 20, 1), (110, None, 1), (3, 20, 1), (3, 4, 1)]:
            _rc, d, _err = runj(
                ["cct", "kundur", "--t-max", "0.5", "--search", "sime"] + fault_args(b, f, c), W
            )
            if d is None or verdict_of(d) != verdict_of(S["cct"][(b, f, c)]):
                bad.append(
                    f"{b}-{f}: sime {d and verdict_of(d)} vs bisection {verdict_of(S['cct'][(b, f, c)])}"
                )
        return (not bad), "; ".join(bad) or "--search sime == bisection on 5 faults"

    probe("L17", p22)

    # ---------------------------------------------------------------- eig
    def p18():
        _rc, out, _err = run(["eig", "kundur"], W)
        _rc2, d, _err2 = runj(["eig", "kundur"], W)
        bad = []
        modes = {m["mode"]: m for m in d["modes"]}
        rows = re.findall(r"^\s+(\d+)\s+([\d.]+)\s+(-?[\d.]+)\s+(\S+)", out, re.M)
        if not rows:
            return False, "no mode rows in text"
        for mo, f, z, kind in rows:
            m = modes[int(mo)]
            if (
                abs(m["freq_hz"] - float(f)) > 6e-4
                or abs(m["damping_ratio"] - float(z)) > 6e-5
                or m["kind"] != kind
            ):
                bad.append(
                    f"mode {mo}: text {f}/{z}/{kind} vs json {m['freq_hz']:.4f}/{m['damping_ratio']:.5f}/{m['kind']}"
                )
        for m in d["modes"]:
            re_, im = m["real_per_s"], m["imag_rad_per_s"]
            if abs(im) > 1e-9 or re_ != 0:
                z = -re_ / math.hypot(re_, im) if (re_ or im) else 0
                if abs(z - m["damping_ratio"]) > 1e-6:
                    bad.append(f"mode {m['mode']}: zeta {m['damping_ratio']} vs -re/|l| {z}")
                if abs(abs(im) / (2 * math.pi) - m["freq_hz"]) > 1e-6:
                    bad.append(f"mode {m['mode']}: f {m['freq_hz']} vs im/2pi")
            ps = sum(x["participation"] for x in m.get("dominant_states", []))
            if ps > 1 + 1e-9 or any(x["participation"] < 0 for x in m.get("dominant_states", [])):
                bad.append(f"mode {m['mode']}: dominant participations sum {ps}")
        S["eig"] = d
        return (not bad), "; ".join(
            bad[:4]
        ) or f"{len(rows)} text rows == JSON; zeta/f from eigenvalues; participations in [0,1]"

    probe("L18", p18)

    def p19():
        # full participation matrix from the API: columns sum to 1
        code = (
            "import numpy as np, json\n"
            "from stabctl.smallsignal import modal\n"
            "import inspect; print(json.dumps([n for n in dir(modal) if 'partic' in n.lower()]))\n"
        )
        p = subprocess.run(
            [sys.executable, "-c", code], env=ENV, capture_output=True, text=True, timeout=120
        )
        names = json.loads(p.stdout.strip().splitlines()[-1]) if p.returncode == 0 else []
        if not names:
            return (
                True,
                "no participation function in the API: only the JSON's dominant states checked (L18)",
            )
        return True, f"API participation functions {names} (not exercised)"

    probe("L19", p19)

    def p20():
        # ringdown: a small pref step on G1; the inter-area mode's frequency and damping from
        # the G1-G3 speed difference vs eig's 0.612 Hz, zeta 0.132
        import numpy as np

        rc, _out, err = run(
            ["simulate", "kundur", "--pref-step", 1, 1.0, 0.01, "--tf", 21, "--out", "ring.csv"], W
        )
        if rc != 0:
            return False, f"simulate rc={rc}: {err.strip()[-120:]}"
        a = np.genfromtxt(os.path.join(W, "ring.csv"), delimiter=",", names=True)
        t = a["t"]
        y = (a["speed_puG1"] + a["speed_puG2"]) / 2 - (a["speed_puG3"] + a["speed_puG4"]) / 2
        m = t > 1.5
        t, y = t[m], y[m]
        y = y - np.polyval(np.polyfit(t, y, 2), t)
        em = next(x for x in S["eig"]["modes"] if x["kind"] == "inter-area")
        # least squares fit of a damped sinusoid around eig's values
        from scipy.optimize import curve_fit

        def f0(tt, A, s, w, ph, c):
            return A * np.exp(s * (tt - t[0])) * np.cos(w * (tt - t[0]) + ph) + c

        p0 = [np.max(np.abs(y)), em["real_per_s"], em["imag_rad_per_s"], 0, 0]
        try:
            p, _ = curve_fit(f0, t, y, p0=p0, maxfev=20000)
        except Exception as e:
            return False, f"fit failed {e}"
        fz = abs(p[2]) / 2 / np.pi
        zz = -p[1] / math.hypot(p[1], p[2])
        ok = (
            abs(fz - em["freq_hz"]) < 0.05 * em["freq_hz"]
            and abs(zz - em["damping_ratio"]) < 0.04
            and zz > 0
        )
        return (
            ok,
            f"ringdown {fz:.3f} Hz zeta {zz:.3f} vs eig inter-area {em['freq_hz']:.3f} Hz zeta {em['damping_ratio']:.3f}",
        )

    probe("L20", p20)

    # ---------------------------------------------------------------- imported cases
    def p21():
        import andes

        src = os.path.join(os.path.dirname(andes.__file__), "cases", "ieee14", "ieee14_full.xlsx")
        rc, out, err = run(["import-andes", src, "-o", "ieee14.json", "--skip-unsupported"], W)
        if rc != 0:
            return False, f"import rc={rc} {err[-120:]}"
        rc, out, err = run(
            [
                "screen",
                "ieee14.json",
                "--no-q-limits",
                "--lines",
                "--workers",
                "1",
                "--out",
                "i14.jsonl",
            ],
            W,
        )
        recs = records(os.path.join(W, "i14.jsonl"))
        last = out.strip().splitlines()[-1]
        m = re.search(
            r"(\d+) fault\(s\).*?(\d+) CCT\(s\) found(?: \([^)]*\))?, (\d+) above.*?, (\d+) N-1 "
            r"insecure.*?, (\d+) failed",
            last,
        )
        kinds = [verdict_of(r)[1] for r in recs.values()]
        bad = []
        if not m or tuple(map(int, m.groups())) != (
            len(recs),
            kinds.count("cct"),
            kinds.count("above t_max"),
            kinds.count("N-1 insecure"),
            kinds.count("failed"),
        ):
            bad.append(f"summary {m and m.groups()} vs records")
        for b, f in [(1, 2), (2, 3), (8, 7), (4, None), (1, 5)]:
            k = (
                f"ieee14.json/bus{b}/t1/esd-none"
                if f is None
                else f"ieee14.json/{b}-{f}/t1/esd-none"
            ) + "/no-q-limits"
            if k not in recs:
                bad.append(f"{k} not in screen")
                continue
            rc, d, err = runj(
                ["cct", "ieee14.json", "--no-q-limits", "--t-max", "0.5"] + fault_args(b, f, 1), W
            )
            if d is None or verdict_of(d) != verdict_of(recs[k]):
                bad.append(f"{b}-{f}: cct {d and verdict_of(d)} vs screen {verdict_of(recs[k])}")
                continue
            if verdict_of(d)[1] == "cct":
                st, _ = sim_verdict("ieee14.json", b, f, 1, d["t_stable_s"], W, ["--no-q-limits"])
                un, _ = sim_verdict("ieee14.json", b, f, 1, d["t_unstable_s"], W, ["--no-q-limits"])
                if st is not True or un is not False:
                    bad.append(f"{b}-{f}: simulate {st}/{un} at the bracket")
        return (
            (not bad),
            "; ".join(bad)
            or f"ieee14 (ANDES import): {len(recs)} records, summary adds up; cct==screen==simulate on 5 faults",
        )

    probe("L21", p21)

    def p23():
        D = os.path.join(CLONE, "tests", "data", "psse")
        rc, out, err = run(
            [
                "import-psse",
                os.path.join(D, "smib_v33.raw"),
                os.path.join(D, "smib.dyr"),
                "-o",
                "smib.json",
            ],
            W,
        )
        if rc != 0:
            return False, f"import-psse rc={rc}: {err.strip()[-150:]}"
        rc, txt, err = run(["cases", "smib.json", "--bus-table"], W)
        re.findall(r"^\s*(\d+)\s+(\d+)\s", txt, re.M)
        rc, _out, err = run(
            ["screen", "smib.json", "--lines", "--workers", "1", "--out", "sm.jsonl"], W
        )
        recs = records(os.path.join(W, "sm.jsonl"))
        bad = []
        n = 0
        for k, r in recs.items():
            cct, lab, isl = verdict_of(r)
            fz = r.get("fault") or r.get("result", {}).get("fault") or {}
            b, f, c = fz.get("bus"), fz.get("far_bus"), fz.get("circuit") or 1
            rc, d, err = runj(["cct", "smib.json", "--t-max", "0.5"] + fault_args(b, f, c), W)
            if d is None or verdict_of(d) != (cct, lab, isl):
                bad.append(f"{k}: cct {d and verdict_of(d)} vs screen {(cct, lab)}")
                continue
            if lab == "cct":
                st, _ = sim_verdict("smib.json", b, f, c, d["t_stable_s"], W)
                un, _ = sim_verdict("smib.json", b, f, c, d["t_unstable_s"], W)
                n += 1
                if st is not True or un is not False:
                    bad.append(
                        f"{k}: simulate {st}/{un} at [{d['t_stable_s']}, {d['t_unstable_s']}]"
                    )
        return (not bad), "; ".join(
            bad[:4]
        ) or f"smib RAW+DYR: {len(recs)} screen records == cct; {n} CCTs bracketed by simulate"

    probe("L22", p23)

    def p24():
        rc, d, err = runj(
            ["cct", "miniwecc", "--fault", 83, "--far-bus", 33, "--t-max", "0.5"], W, timeout=400
        )
        if d is None:
            return False, f"rc={rc} {err[-120:]}"
        rc, _out, err = run(
            [
                "sweep-cct",
                "miniwecc",
                "--faults",
                "DEFAULT",
                "--t-max",
                "0.5",
                "--workers",
                "1",
                "--out",
                "mw.jsonl",
            ],
            W,
            timeout=600,
        )
        r = records(os.path.join(W, "mw.jsonl")).get("miniwecc/83-33/t1/esd-none")
        bad = []
        if r is None or verdict_of(r) != verdict_of(d):
            bad.append(f"sweep {r and verdict_of(r)} vs cct {verdict_of(d)}")
        if verdict_of(d)[1] == "cct":
            st, _ = sim_verdict("miniwecc", 83, 33, 1, d["t_stable_s"], W)
            un, _ = sim_verdict("miniwecc", 83, 33, 1, d["t_unstable_s"], W)
            if st is not True or un is not False:
                bad.append(f"simulate {st}/{un} at [{d['t_stable_s']}, {d['t_unstable_s']}]")
        return (
            (not bad),
            "; ".join(bad)
            or f"miniwecc 83-33: CCT {d.get('cct_s')} (+-{d.get('numerical_error_s')}) cct==sweep==simulate",
        )

    probe("L23", p24)

    def p25():
        # the Q-limit setting changes the figure; is it shown in the text of cct / screen / simulate?
        if not os.path.exists(os.path.join(W, "ieee14.json")):
            return False, "ieee14.json not imported (L21)"
        a = run(["cct", "ieee14.json", "--fault", 1, "--far-bus", 2, "--t-max", "0.5"], W)[1]
        b = run(
            ["cct", "ieee14.json", "--fault", 1, "--far-bus", 2, "--t-max", "0.5", "--no-q-limits"],
            W,
        )[1]
        ca = re.search(r"CCT ([\d.]+) s", a).group(1)
        cb = re.search(r"CCT ([\d.]+) s", b).group(1)
        sa = run(
            ["simulate", "ieee14.json", "--fault", 1, "--far-bus", 2, "--clear-cycles", 13], W
        )[1]
        sb = run(
            [
                "simulate",
                "ieee14.json",
                "--fault",
                1,
                "--far-bus",
                2,
                "--clear-cycles",
                13,
                "--no-q-limits",
            ],
            W,
        )[1]
        qa = [l for l in (a + b + sa + sb).lower().splitlines() if "q limit" in l or "q-limit" in l]
        if ca != cb and not qa:
            return False, (
                f"cct ieee14 1-2: CCT {ca} s (Q limits) vs {cb} s (--no-q-limits), simulate at 13 cycles "
                f"'{sa.splitlines()[2][:30]}' vs '{sb.splitlines()[2][:40]}': no text line names the Q-limit setting "
                f"(settings line identical: '{a.splitlines()[1][a.splitlines()[1].find('tolerance') :][:80]}')"
            )
        return True, "Q-limit setting shown in text"

    probe("L24", p25)

    shutil.rmtree(tmp, ignore_errors=True)
    n = len(RESULTS)
    ns = sum(1 for r in RESULTS if not r[1])
    print(f"{n} probes: {n - ns} ok, {ns} SHORT; {time.time() - T0:.0f} s")
    return 1 if ns else 0


if __name__ == "__main__":
    sys.exit(main())
