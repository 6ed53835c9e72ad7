#!/usr/bin/env python
"""Twenty-second reliability round (round 41, part Q): the consistency of results across
the analysis commands: the same fault through `simulate`, `cct`, `screen`, `sweep-cct`,
`estimate cct` and `place`; step halving, trapezoid against Heun, conventions; `eig`'s
text, --json and report; the Python API against the CLI.  Kundur, IEEE 14 and IEEE 39
imported from ANDES.

    python benchmarks/reliability_probes_22.py

The package under test is this repository's (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's.  Prints per probe: id, ok/SHORT, reason; exits 1 if
any is SHORT.  About 3 minutes with a warm kernel cache.  The round found short: `eig`'s
text and report silent about unstable modes outside the electromechanical band, CCTs and
an insecure fault's window that depend on the run's end (a trip leaving the rest
drifting out of step), `screen`'s settings and stiff step unsaid, `estimate cct --json`
without its fault time, local modes' sides in quadrature, an API message naming a
default as given; all fixed.
"""

# ruff: noqa: E501, BLE001, SIM115, RUF015, RUF059, UP031 - a tester's script, kept as written

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
ENV = dict(os.environ, PYTHONPATH=CLONE)
W = tempfile.mkdtemp(prefix="probes_q.")
ENV["XDG_CACHE_HOME"] = os.path.join(W, "xdg")
RES = []


def run(args, timeout=300):
    p = subprocess.run(
        ["stabctl", *map(str, args)],
        cwd=W,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    return p.returncode, p.stdout, p.stderr


def runj(args, timeout=300):
    rc, out, err = run([*args, "--json"], timeout)
    try:
        return rc, json.loads(out), err
    except Exception:
        return rc, None, err + out


def probe(pid, fn):
    t = time.time()
    try:
        ok, why = fn()
    except Exception as e:  # the probe's own failure counts as SHORT, with its reason
        ok, why = False, f"probe error {type(e).__name__}: {e}"[:300]
    RES.append(ok)
    print(f"{pid:<28} {'ok' if ok else 'SHORT'}  {why}  [{time.time() - t:.0f} s]", flush=True)


def kundur_variant(name, table, changes):
    d = json.load(open(os.path.join(CLONE, "stabctl/case/data/kundur.json")))
    cols = d["tables"][table]["columns"]
    for r in d["tables"][table]["rows"]:
        for k, v in changes.items():
            r[cols.index(k)] = v
    d["name"] = name
    path = os.path.join(W, name + ".json")
    json.dump(d, open(path, "w"))
    return path


def sim_verdict(case, bus, far, circuit, clear_s, extra=()):
    args = ["simulate", case, "--fault", bus, "--clear-cycles", repr(clear_s * 60)]
    if far is not None:
        args += ["--far-bus", far, "--circuit", circuit or 1]
    rc, d, err = runj([*args, *extra])
    if d is None:
        return None, err[-200:]
    return d["stable"], d


# ---------------------------------------------------------------- eig
def q01():
    """An exciter-unstable Kundur (KA 2000, TA 0.05, TR 0.2): 4 modes with Re > 0."""
    path = kundur_variant("kundur_exc", "exciters", {"KA": 2000, "TA": 0.05, "TR": 0.2})
    rc, d, err = runj(["eig", path])
    unstable = [m for m in d["modes"] if m["real_per_s"] > 1e-6]
    rc2, txt, _ = run(["eig", path])
    rc3, _, _ = run(["eig", path, "--report", "--out-dir", os.path.join(W, "rep")])
    rep = open(os.path.join(W, "rep", "eig_kundur_exc.md")).read()
    said = [s for s in (txt, rep) if re.search(r"unstable|positive real|growing", s, re.I)]
    least = re.search(r"Least-damped[^\n]*", rep).group(0)
    why = (
        f"{len(unstable)} modes with Re>0 (largest {max(m['real_per_s'] for m in unstable):.2f} 1/s at "
        f"{unstable[0]['freq_hz']:.2f} Hz, kind {unstable[0]['kind']}); text rc {rc2} and --report "
        f"{'mention' if said else 'never mention'} them (report: 'Least-damped electromechanical mode: ... "
        f"{least[-30:]}')"
    )
    return bool(said) or not unstable, why


def q02():
    """Kundur --no-pss: the 0.634 Hz mode has zeta < 0; text vs --report vs --json."""
    rc, txt, _ = run(["eig", "kundur", "--no-pss"])
    rc, d, _ = runj(["eig", "kundur", "--no-pss"])
    run(["eig", "kundur", "--no-pss", "--report", "--out-dir", os.path.join(W, "rep")])
    rep = open(os.path.join(W, "rep", "eig_kundur_nopss.md")).read()
    neg = [m for m in d["modes"] if m["real_per_s"] > 1e-6]
    in_rep = "(unstable)" in rep
    in_txt = "unstable" in txt.lower()
    in_json = any(k in json.dumps(d) for k in ('"unstable"', '"stable"'))
    return in_txt or not neg, (
        f"{len(neg)} unstable mode(s) ({neg[0]['freq_hz']:.3f} Hz); report says "
        f"unstable: {in_rep}; text says so: {in_txt}; json has a stable flag: {in_json}"
    )


def q03():
    """eig text rows = --json figures to the printed precision (kundur, --no-pss, ieee14)."""
    bad, n = [], 0
    for args in (["kundur"], ["kundur", "--no-pss"], [IEEE14]):
        rc, txt, _ = run(["eig", *args])
        rc, d, _ = runj(["eig", *args])
        modes = {m["mode"]: m for m in d["modes"]}
        for line in txt.splitlines():
            m = re.match(r"\s*(\d+)\s+([\d.]+)\s+(-?[\d.]+)\s+(\S+)", line)
            if not m:
                continue
            n += 1
            j = modes[int(m.group(1))]
            if (
                f"{j['freq_hz']:.3f}" != m.group(2)
                or f"{j['damping_ratio']:.4f}" != m.group(3)
                or (m.group(4) != j["kind"] and j["kind"] in ("local", "inter-area", "common"))
            ):
                bad.append(
                    f"{args}: {line.strip()[:50]} vs json {j['freq_hz']:.3f} {j['damping_ratio']:.4f} {j['kind']}"
                )
    return not bad, "; ".join(bad) or f"{n} text rows equal their json modes"


# ---------------------------------------------------------------- cct window
def q04():
    """Kundur 1-10 (G1 islanded): CCT at the default run end vs --tf 10 vs its printed error."""
    out = {}
    for tf in (None, 10):
        extra = [] if tf is None else ["--tf", tf]
        rc, d, err = runj(["cct", "kundur", "--fault", 1, "--far-bus", 10, "--t-max", 0.5, *extra])
        out[tf] = d
    rc, txt, err = run(["cct", "kundur", "--fault", 1, "--far-bus", 10, "--t-max", 0.5])
    a, b = out[None], out[10]
    diff = abs(a["cct_s"] - b["cct_s"])
    bar = a["numerical_error_s"] + a["tol_s"]
    warned = re.search(r"run end|--tf|late", txt + err)
    st, sd = sim_verdict("kundur", 1, 10, 1, 0.2, ["--tf", 20])
    return diff <= bar + 1e-9 or bool(warned), (
        f"default run end: CCT {a['cct_s']} s +- {a['numerical_error_s']} s; --tf 10: {b['cct_s']} s "
        f"(moved {diff * 1000:.0f} ms, > error bar {bar * 1000:.0f} ms); cleared at 0.2 s (< CCT) with "
        f"--tf 20 simulate says {'stable' if st else 'loss of synchronism at %.2f s' % sd['t_separation_s']}; "
        f"no warning in the cct output: {not warned}"
    )


def q05():
    """Kundur 2-20: 'N-1 insecure ... yet stable when cleared at 0.017 s' vs the same clearing run longer."""
    rc, txt, err = run(["cct", "kundur", "--fault", 2, "--far-bus", 20])
    claims = "0.017" in txt
    st, d = sim_verdict("kundur", 2, 20, 1, 1 / 60, ["--tf", 20])
    ok = not (claims and st is False)
    return ok, (
        f"cct says stable when cleared at 0.017 s: {claims}; simulate cleared after 1 cycle with "
        f"--tf 20: {'stable' if st else 'separates at t = %.3f s' % d['t_separation_s']} "
        "(the trip alone separates 4.4 s after it; MIN_AFTER_CLEARING_S is 3.5 s)"
    )


# ---------------------------------------------------------------- imported case: screen/cct/simulate
def q06():
    """ieee14 (ANDES) screen --lines: every CCT row's bracket ends through simulate, and 3 rows vs cct."""
    out = os.path.join(W, "s14.jsonl")
    rc, txt, err = run(
        ["screen", IEEE14, "--lines", "--t-max", 0.5, "--workers", 2, "--out", out], 900
    )
    if rc not in (0, 1):
        return False, f"screen rc {rc}: {err[-200:]}"
    recs = [json.loads(l) for l in open(out)]
    bad, n, ncct = [], 0, 0
    oks = [r for r in recs if r["status"] == "ok"]
    for r in oks[:10]:
        i, res = r["inputs"], r["result"]
        ncct += 1
        for t, want in ((res["t_stable_s"], True), (res["t_unstable_s"], False)):
            st, d = sim_verdict(IEEE14, i["bus"], i["far_bus"], i["circuit"], t)
            n += 1
            if st is not want:
                bad.append(
                    f"{r['key']}: cleared at {t} s simulate {'stable' if st else 'unstable'} "
                    f"(screen CCT {res['cct_s']} +- {res['numerical_error_s']})"
                )
    for r in oks[:3]:
        i, res = r["inputs"], r["result"]
        args = ["cct", IEEE14, "--fault", i["bus"], "--t-max", 0.5]
        if i["far_bus"] is not None:
            args += ["--far-bus", i["far_bus"], "--circuit", i["circuit"]]
        rc, d, err = runj(args)
        rct, txt, _ = run(args)
        if (
            d is None
            or d["cct_s"] != res["cct_s"]
            or d["numerical_error_s"] != res["numerical_error_s"]
        ):
            bad.append(f"{r['key']}: cct {d and d['cct_s']} vs screen {res['cct_s']}")
        elif f"CCT {d['cct_s']:.3f} s" not in txt or f"{d['t_unstable_s']:.3f} s" not in txt:
            bad.append(
                f"{r['key']}: cct text does not show json's {d['cct_s']}/{d['t_unstable_s']}"
            )
    return not bad, "; ".join(bad[:4]) or (
        f"{len(recs)} faults, {ncct} CCT rows checked: {n} simulate runs at the bracket ends agree; "
        "3 rows equal cct --json and its text"
    )


def q07():
    """ieee14: cct --step h/2 inside the error bar cct printed; pstess conventions likewise (kundur)."""
    bad = []
    for case, args in (
        (IEEE14, ["--fault", 2, "--far-bus", 4]),
        (IEEE14, ["--fault", 4]),
        ("kundur", ["--fault", 3, "--far-bus", 101, "--conventions", "pstess"]),
    ):
        rc, d, err = runj(["cct", case, *args])
        rc, h2, err = runj(["cct", case, *args, "--step", d["step_s"] / 2])
        if h2 is None:
            bad.append(f"{args}: half step rc {rc} {err[-120:]}")
            continue
        if d["cct_s"] is None:
            continue
        lim = d["numerical_error_s"] + d["tol_s"] + 1e-9
        if (
            abs(h2["cct_s"] - d["cct_s"]) > lim
            or abs(h2["cct_s"] - d["cct_half_step_s"]) > d["tol_s"] + 1e-9
        ):
            bad.append(
                f"{case} {args}: CCT {d['cct_s']} +- {d['numerical_error_s']} (h/2 {d['cct_half_step_s']}), "
                f"cct --step h/2 {h2['cct_s']}"
            )
    return not bad, "; ".join(bad) or "every --step h/2 CCT within the printed error bar"


def q08():
    """sweep-cct vs cct on Kundur: bus fault, circuit 2, and a branch fault that islands a machine."""
    csv = os.path.join(W, "f.csv")
    open(csv, "w").write("bus,far_bus,t_fault,circuit\n3,,1,\n13,101,1,2\n10,20,1,1\n")
    out = os.path.join(W, "sw.jsonl")
    rc, d, err = runj(
        ["sweep-cct", "kundur", "--faults", csv, "--out", out, "--workers", 2, "--t-max", 0.5], 600
    )
    if d is None:
        return False, f"sweep rc {rc}: {err[-200:]}"
    recs = {
        json.dumps([r["inputs"]["bus"], r["inputs"]["far_bus"], r["inputs"]["circuit"]]): r
        for r in map(json.loads, open(out))
    }
    bad = []
    for bus, far, c in ((3, None, 1), (13, 101, 2), (10, 20, 1)):
        args = ["cct", "kundur", "--fault", bus, "--t-max", 0.5]
        if far:
            args += ["--far-bus", far, "--circuit", c]
        rc, cj, err = runj(args)
        r = recs.get(json.dumps([bus, far, c if far else 1])) or recs.get(
            json.dumps([bus, far, None])
        )
        if r is None:
            bad.append(f"{bus}-{far}#{c}: no sweep record ({list(recs)})")
            continue
        res = r.get("result", {})
        if (
            res.get("cct_s") != cj["cct_s"]
            or res.get("numerical_error_s") != cj["numerical_error_s"]
            or res.get("fault") != cj["fault"]
        ):
            bad.append(
                f"{bus}-{far}#{c}: sweep {res.get('cct_s')} {res.get('fault')} vs cct {cj['cct_s']} {cj['fault']}"
            )
    return not bad, "; ".join(
        bad
    ) or "3 sweep-cct records equal cct --json (CCT, error, fault labels)"


def q09():
    """API vs CLI: critical_clearing_time on Kundur 3-101 and bus 3 (t_max 0.5)."""
    code = (
        "from stabctl import load_case, Simulator, LineFault, critical_clearing_time\n"
        "from stabctl.stability.cct import SearchOptions\n"
        "c=load_case('kundur'); s=Simulator(c)\n"
        "a=critical_clearing_time(s, LineFault(3,101,1.0)); b=critical_clearing_time(s, LineFault(3,None,1.0), SearchOptions(t_max=0.5))\n"
        "print(a.cct_s, a.numerical_error_s, b.cct_s, b.numerical_error_s)"
    )
    p = subprocess.run(
        [sys.executable, "-c", code], env=ENV, capture_output=True, text=True, timeout=300, cwd=W
    )
    api = [float(x) for x in p.stdout.split()]
    _, a, _ = runj(["cct", "kundur", "--fault", 3, "--far-bus", 101])
    _, b, _ = runj(["cct", "kundur", "--fault", 3, "--t-max", 0.5])
    cli = [a["cct_s"], a["numerical_error_s"], b["cct_s"], b["numerical_error_s"]]
    return api == cli, f"api {api} cli {cli}"


def q10():
    """API: SearchOptions(t_lo=0.2) alone: the message should name what the user gave."""
    code = (
        "from stabctl import load_case, Simulator, LineFault, critical_clearing_time\n"
        "from stabctl.stability.cct import SearchOptions\n"
        "c=load_case('kundur'); s=Simulator(c)\n"
        "critical_clearing_time(s, LineFault(3,101,1.0), SearchOptions(t_lo=0.2))"
    )
    p = subprocess.run(
        [sys.executable, "-c", code], env=ENV, capture_output=True, text=True, timeout=300, cwd=W
    )
    last = (p.stderr.strip().splitlines() or [""])[-1]
    ok = p.returncode != 0 and ("t_hi" not in last or "default" in last)
    return ok, f"rc {p.returncode}: {last[:200]}"


def q11():
    """simulate --method trapezoid vs heun at Kundur 3-101's bracket ends (0.154 / 0.155 s)."""
    bad = []
    for m in ("heun", "trapezoid"):
        for t, want in ((0.154, True), (0.155, False)):
            st, d = sim_verdict("kundur", 3, 101, 1, t, ["--method", m])
            if st is not want:
                bad.append(f"{m} at {t}: {'stable' if st else 'unstable'}")
    return not bad, "; ".join(bad) or "both methods agree with cct's bracket"


def q12():
    """ieee39 (ANDES) screen --buses subset: text settings and --json vs cct (stiff step stated?)."""
    out = os.path.join(W, "s39.jsonl")
    rc, txt, err = run(
        ["screen", IEEE39, "--buses", "4,16", "--workers", 2, "--out", out, "--t-max", 0.5], 600
    )
    rc2, rows, _ = runj(
        ["screen", IEEE39, "--buses", "4,16", "--workers", 2, "--out", out, "--t-max", 0.5], 600
    )
    rc3, ctxt, _ = run(["cct", IEEE39, "--fault", 16, "--t-max", 0.5])
    rc4, cj, _ = runj(["cct", IEEE39, "--fault", 16, "--t-max", 0.5])
    bad = []
    row = [r for r in rows if r["bus"] == 16][0]
    if row["cct_s"] != cj["cct_s"]:
        bad.append(f"screen {row['cct_s']} vs cct {cj['cct_s']}")
    if cj.get("stiff_step_s") and "intervals where" in ctxt and "intervals where" not in txt:
        bad.append(
            f"cct's text states the stiff step ({cj['stiff_step_s'] * 1000:.3g} ms) where the runs step; "
            "screen's settings line says only 'step 8.333 ms'"
        )
    keys = set().union(*(r.keys() | r.get("settings", {}).keys() for r in rows))  # round 41: nested
    missing = [
        k for k in ("step_s", "tol_s", "t_max_s", "conventions", "stiff_step_s") if k not in keys
    ]
    if missing:
        bad.append(f"screen --json rows (a bare list) carry none of {missing}")
    return not bad, "; ".join(bad) or "screen text/json state the same settings as cct"


def q13():
    """place's CCT without storage vs cct (Kundur 1-10 and 13-101, defaults)."""
    csv = os.path.join(W, "pf.csv")
    open(csv, "w").write("bus,far_bus\n1,10\n13,101\n")
    rc, txt, err = run(
        ["place", "kundur", "--faults", csv, "--target-cct-gain", 10, "--workers", 2], 600
    )
    got = dict(re.findall(r"^(\d+-\d+)\s+[\d.]+\s+([\d.]+)", txt, re.M))
    bad = []
    for b, f in ((1, 10), (13, 101)):
        rc, d, _ = runj(["cct", "kundur", "--fault", b, "--far-bus", f])
        if got.get(f"{b}-{f}") is None or abs(float(got[f"{b}-{f}"]) - d["cct_s"]) > 1e-9:
            bad.append(f"{b}-{f}: place no-ESD {got.get(f'{b}-{f}')} vs cct {d['cct_s']}")
    verified = "VERIFIED" in txt
    return not bad, "; ".join(bad) or (
        f"place's no-ESD CCTs {got} equal cct's (place {'VERIFIED' if verified else 'not verified'} "
        "its plan for 1-10 on the same 5-s window, see Q04)"
    )


def q14():
    """estimate cct --json: the fault's start time stated (the runs fault at 1 s)."""
    rc, d, err = runj(
        ["estimate", "cct", "kundur", "--fault", 3, "--far-bus", 101, "--esd-pct", 5, "--runs", 1],
        600,
    )
    f = (d or {}).get("fault", {})
    return f.get("t_fault_s") is not None, f"rc {rc}: fault {f}"


def q15():
    """eig kundur --no-pss: a local mode's text grouping vs its participation and speed shape."""
    rc, d, _ = runj(["eig", "kundur", "--no-pss"])
    bad = []
    for i in d["electromechanical_modes"]:
        m = [x for x in d["modes"] if x["mode"] == i][0]
        if m["kind"] != "local":
            continue
        dom = set(m["dominant_machines"])
        shape = m["speed_shape"]
        ref = shape[f"G{m['group'][0]}"][1]
        quad = [
            f"G{k} {shape[f'G{k}'][0]:.2f}@{shape[f'G{k}'][1]:.0f}deg"
            for k in m["group"] + m["against"]
            if 60 < abs(((shape[f"G{k}"][1] - ref) + 180) % 360 - 180) < 120
        ]
        if quad or not (
            dom <= set(m["group"][:1] + m["against"][:1]) or len(dom & set(m["group"])) == 1
        ):
            bad.append(
                f"mode {i} ({m['freq_hz']:.3f} Hz, local): text 'G{m['group']} vs G{m['against']}', "
                f"participation dominant {sorted(dom)}, in quadrature with the reference: {quad}"
            )
    return not bad, "; ".join(bad) or "groups follow the participation"


def main():
    global IEEE14
    import andes  # noqa: F401 - the imported case's source

    src = subprocess.run(
        [sys.executable, "-c", "import andes; print(andes.get_case('ieee14/ieee14_full.xlsx'))"],
        capture_output=True,
        text=True,
        env=ENV,
    ).stdout.strip()
    IEEE14 = os.path.join(W, "ieee14.json")
    rc, out, err = run(["import-andes", src, "-o", IEEE14])
    print(f"imported {src} rc {rc}", flush=True)
    global IEEE39
    src39 = src.replace("ieee14/ieee14_full", "ieee39/ieee39_full")
    IEEE39 = os.path.join(W, "ieee39.json")
    rc, out, err = run(["import-andes", src39, "-o", IEEE39])
    print(f"imported {src39} rc {rc}", flush=True)
    try:
        for pid, fn in (
            ("Q01.eig_unstable_hidden", q01),
            ("Q02.eig_text_unstable", q02),
            ("Q03.eig_text_vs_json", q03),
            ("Q04.cct_run_end_1-10", q04),
            ("Q05.n1_yet_stable_window", q05),
            ("Q06.ieee14_screen_sim_cct", q06),
            ("Q07.half_step_bars", q07),
            ("Q08.sweep_vs_cct", q08),
            ("Q09.api_vs_cli", q09),
            ("Q10.api_t_lo_message", q10),
            ("Q11.trapezoid_vs_heun", q11),
            ("Q12.ieee39_screen_settings", q12),
            ("Q13.place_no_esd_vs_cct", q13),
            ("Q14.estimate_cct_fault_time", q14),
            ("Q15.eig_local_groups", q15),
        ):
            probe(pid, fn)
    finally:
        shutil.rmtree(W, ignore_errors=True)
    print(f"{len(RES)} probes, {sum(RES)} ok, {len(RES) - sum(RES)} SHORT")
    sys.exit(0 if all(RES) else 1)


if __name__ == "__main__":
    main()
