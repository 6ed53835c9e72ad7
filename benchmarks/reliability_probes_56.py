#!/usr/bin/env python
"""Round 59 (BC): issue 53's targets on systems the project has not documented
(docs/placement.md section 9 lists Kundur, miniWECC, WECC-179, IEEE 39, NPCC, ACTIVSg2000,
WECC-240, IEEE 14 xlsx, EI_33, PJM 5-bus, Nordic 44, ...): ANDES's IEEE 14 read as PSS/E
(ieee14.raw + ieee14.dyr through `import-psse`: GENROU, ST2CUT, ESST3A, EXST1, IEEEST,
TGOV1, IEEEG1), IEEE 14 with HYGOV and ESST3A (`ieee14_hygov.xlsx`), Kundur with EXDC2 and
IEEEST (`kundur_ieeest.xlsx`), ANDES's GB network (2224 buses, 394 GENCLS; a subset of
buses), and the static WSCC 9-bus and MATPOWER case14 (no dynamic data: a clear refusal).

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_56.py [BC1 ...]

BC_WORK=<dir> keeps (and reuses) the imported cases, screenings and plans there (default:
the run's work directory, removed at the end unless KEEP=1).  Per system n (1-4):
  BCn1  the import: exit 0, or a refusal naming what and where;
  BCn2  `screen CASE --lines --workers 1` (GB: --buses subset): exit 0 or 1, every
        `failed` row a numerical or input failure (no verdict words in its error: N-1
        insecure, islanding, robust), the summary's counts those of the rows;
  BCn3  N-1 insecure rows: `cct` says CCT 0, and the line trip alone (`simulate --trip`)
        loses synchronism (issue 53: "unstable at any clearing, CCT 0");
  BCn4  islanding rows: the buses named are the buses the trip cuts from every machine
        (graph of the branch table, computed here);
  BCn5-7 `place CASE --faults F --target-cct-gain G --set-aside-infeasible --workers 1`
        with up to 5 line faults from the screening (CCT found, no islanding), G = 5, 20,
        60: exit 0 with a label (VERIFIED / NOTHING TO PLACE / set aside with a reason),
        no traceback; then each contingency the plan says is met searched again here with
        the plan's devices (library `critical_clearing_time`, the plan's law, step, tol):
        its CCT at or above the required time and in the plan's 1 ms cell; with the
        sized MWh, stable cleared at the required time;
  BCn8  `cct --search sime` vs `--search bisection` on 3 faults: the same 1 ms cell.
  BC01-BC02 the static cases: `import-andes` then `screen`/`cct` refused with one error
        line naming the missing dynamic data (developers' guide: clear error, exit 2).
  BC49  GB: five line trips islanding a radial bus (`sweep-cct`): the island named.
  BC02  each +20 % plan's infeasibility figure (every site at its bound) = `cct --esd-pct 50`.
  BC03  GB: a plan for trips that island a load bus and a machine names the islanding.
Found (round 59, BC, at 3499fa4e; 33 ok, 1 SHORT): BC03 REAL: `place` never says that a
contingency's trip islands load (282-669: bus 669, 163.4 MW shed) or loses a machine (1-3:
G2 at bus 3), where cct/screen/sweep-cct name it; the plan's "met" judges the rest
silently (no "island" anywhere in stabctl/placement/; check runs' meta["islanded"]
dropped in evaluation._check_run, plan._rows has no field).  Otherwise: refusals clear and correct
(ieee14.dyr's TOGGLE records named with file:line and --skip-unsupported; Kundur's power
flow needs --no-q-limits, named; static wscc9/case14 "no dynamic data ... --static").
Screenings: 0 failed, summary = rows; plans exit 0 labelled, every met contingency's CCT
re-searched with the plan's devices in the plan's 1 ms cell; sime = bisection cells.
DOUBTFUL: --search sime costs more runs than bisection on IEEE 14 (14-15 vs 13-14) and GB
(18 vs 16-17); fewer on Kundur (11-12 vs 14-16); issue 53's 5 runs per CCT not reached.
Sources: issue 53 (targets: placement verified on systems not seen; 0 failed where the
verdict is N-1 insecurity or islanding; every CCT within its 1 ms cell of the
bisection's), docs/cli.md (screen's verdicts), docs/placement.md sections 7 and 9.
"""

# ruff: noqa
import json
import os
import re
import sys
from pathlib import Path

from _probe_kit import Kit, tail, tb

KIT = Kit("probes_bc56.", line="{pid:<6} {state:<5} {why}", timed=True, xdg=False)
CLONE, ENV, WD = KIT.clone, KIT.env, KIT.wd
run, rec, probe = KIT.cli, KIT.rec, KIT.probe
WORK = Path(os.environ.get("BC_WORK") or WD)
WORK.mkdir(parents=True, exist_ok=True)
ANDES = (
    Path(
        os.popen(f"{sys.executable} -c 'import andes, os; print(os.path.dirname(andes.__file__))'")
        .read()
        .strip()
    )
    / "cases"
)

# name -> (importer, inputs under ANDES's cases, import options, screen options, place options)
SYSTEMS = {
    1: (
        "ieee14psse",
        "import-psse",
        ["ieee14/ieee14.raw", "ieee14/ieee14.dyr"],
        ["--skip-unsupported"],
        [],
        [],
    ),
    2: ("ieee14hygov", "import-andes", ["ieee14/ieee14_hygov.xlsx"], [], [], []),
    3: (
        "kundurieeest",
        "import-andes",
        ["kundur/kundur_ieeest.xlsx"],
        [],
        ["--no-q-limits"],
        ["--no-q-limits"],
    ),
    4: ("gb", "import-andes", ["GBnetwork/GBnetwork.xlsx"], [], ["--buses", "GB_BUSES"], []),
}
GAINS = {5: 5, 6: 20, 7: 60}
QOFF = {
    3
}  # the power flow converges only with the PV buses' Q limits off (refused otherwise, naming it)


def mo(n):
    return ["--no-q-limits"] if n in QOFF else []


VERDICT_WORDS = ("cleared at once", "cleared instantly", "insecure", "island", "still stable")


def case_of(n):
    """(path, None) of system n's case file, imported once; (None, why) if refused."""
    name, how, inputs, opts, _s, _p = SYSTEMS[n]
    path = WORK / f"{name}.json"
    log = WORK / f"{name}.import.txt"
    if not path.exists() and not log.exists():
        rc, out, err, _ = KIT.run(
            [how, *[ANDES / i for i in inputs], "-o", path, *opts], timeout=900
        )
        log.write_text(json.dumps({"rc": rc, "out": out, "err": err}))
    if path.exists():
        return path, None
    d = json.loads(log.read_text())
    return None, f"exit {d['rc']}: {tail(d['err'], 300)}"


def gb_buses(case):
    """Six buses of the GB network: the HV buses of its six largest machines' neighbours."""
    sys.path.insert(0, CLONE)
    from stabctl.io import load_case

    c = load_case(str(case))
    order = sorted(range(len(c.machines)), key=lambda i: -c.machines.mva[i])
    buses = []
    for i in order:
        b = int(c.machines.bus[i])
        if b not in buses:
            buses.append(b)
        if len(buses) == 6:
            break
    return buses


def screening(n):
    """(rc, text, rows) of system n's screening (run once; the JSON rows read back from
    the records file, no search run again)."""
    name, *_r, sopts, _p = SYSTEMS[n]
    case, why = case_of(n)
    if case is None:
        raise RuntimeError(f"no case: {why}")
    keep = WORK / f"{name}.screen.json"
    if keep.exists():
        d = json.loads(keep.read_text())
        return d["rc"], d["text"], d["rows"]
    sopts = list(sopts)
    if "GB_BUSES" in sopts:
        sopts[sopts.index("GB_BUSES")] = ",".join(map(str, gb_buses(case)))
    out = WORK / f"{name}.screen.jsonl"
    base = ["screen", case, "--workers", 1, "--out", out, *sopts]
    if n != 4:
        base.append("--lines")
    rc, text, err, dt = KIT.run(base, timeout=2400)
    rc2, js, err2, _ = KIT.run([*base, "--json"], timeout=600)
    try:
        rows = json.loads(js)
    except ValueError:
        rows = None
    keep.write_text(json.dumps({"rc": rc, "text": text + err, "rows": rows, "secs": dt}))
    return rc, text + err, rows


def summary_counts(text):
    """The screening summary's counts (CCT, robust, insecure, failed) from its last lines."""
    m = {}
    for key, pat in (
        ("cct", r"(\d+) CCT\(s\) found"),
        ("robust", r"(\d+) above the\s+search limit"),
        ("insecure", r"(\d+) N-1 insecure"),
        ("failed", r"(\d+) failed"),
        ("islanding", r"(\d+) (?:islanding|island)"),
    ):
        x = re.findall(pat, text)
        m[key] = int(x[-1]) if x else None
    return m


def row_name(r):
    return f"{r['bus']}-{r['far_bus']}" if r.get("far_bus") is not None else f"bus {r['bus']}"


def picked_faults(rows, k=5):
    """Up to k line faults with a CCT (no islanding, none of machines), spread over the CCTs."""
    ok = [
        r
        for r in rows
        if r["verdict"] == "cct"
        and r.get("far_bus") is not None
        and not r.get("islanded")
        and not r.get("islanded_machines")
        and r["cct_s"] >= 0.05
    ]
    if len(ok) < 3:  # bus faults too
        ok += [
            r
            for r in rows
            if r["verdict"] == "cct" and r.get("far_bus") is None and r["cct_s"] >= 0.05
        ]
    ok.sort(key=lambda r: r["cct_s"])
    seen = set()  # one circuit of a double line (the CSV names bus pairs)
    ok = [
        r
        for r in ok
        if not ((r["bus"], r["far_bus"]) in seen or seen.add((r["bus"], r["far_bus"])))
    ]
    if len(ok) <= k:
        return ok
    return [ok[round(i * (len(ok) - 1) / (k - 1))] for i in range(k)]


for n, (NAME, *_rest) in SYSTEMS.items():

    @probe(f"BC{n}1")
    def _(n=n):
        case, why = case_of(n)
        if case is not None:
            return True, f"{SYSTEMS[n][0]}: imported ({case.stat().st_size} bytes)"
        d = json.loads((WORK / f"{SYSTEMS[n][0]}.import.txt").read_text())
        clear = d["rc"] == 2 and not tb(d["err"]) and "error" in d["err"]
        return clear, f"{SYSTEMS[n][0]}: refused, {why}"

    @probe(f"BC{n}2")
    def _(n=n):
        rc, text, rows = screening(n)
        if rows is None:
            return False, f"screen exit {rc}: {tail(text, 300)}"
        by = {}
        for r in rows:
            by[r["verdict"]] = by.get(r["verdict"], 0) + 1
        isl = sum(bool(r.get("islanded") or r.get("islanded_machines")) for r in rows)
        failed = [r for r in rows if r["verdict"] == "failed"]
        verdict_like = [
            r for r in failed if any(w in (r.get("error") or "").lower() for w in VERDICT_WORDS)
        ]
        s = summary_counts(text)
        same = (
            s["cct"] == by.get("cct", 0)
            and s["insecure"] == by.get("N-1 insecure", 0)
            and s["failed"] == by.get("failed", 0)
        )
        ok = (
            rc in (0, 1)
            and (rc == 1) == bool(failed)
            and not verdict_like
            and same
            and not tb(text)
        )
        fl = "; ".join(f"{row_name(r)}: {(r.get('error') or '')[:90]}" for r in failed[:3])
        return ok, (
            f"{SYSTEMS[n][0]}: exit {rc}, {len(rows)} faults: {by}, islanding {isl}; "
            f"summary {s}; failed: {fl or 'none'}"
        )

    @probe(f"BC{n}3")
    def _(n=n):
        case, _w = case_of(n)
        _rc, _t, rows = screening(n)
        ins = [r for r in rows if r["verdict"] == "N-1 insecure" and r.get("far_bus") is not None]
        if not ins:
            return True, f"{SYSTEMS[n][0]}: no N-1 insecure line fault"
        bad, seen = [], []
        for r in ins[:2]:
            rc, out, err = run(
                ["cct", case, "--fault", r["bus"], "--far-bus", r["far_bus"], "--json", *mo(n)], 900
            )
            try:
                d = json.loads(out)
            except ValueError:
                d = {}
            rc2, out2, err2 = run(
                [
                    "simulate",
                    case,
                    "--trip",
                    r["bus"],
                    r["far_bus"],
                    "--t-trip",
                    1.0,
                    "--tf",
                    6,
                    "--json",
                    *mo(n),
                ],
                600,
            )
            try:
                s = json.loads(out2)
            except ValueError:
                s = {}
            st = s.get("verdict")
            seen.append(
                f"{row_name(r)}: cct {d.get('verdict')} {d.get('cct_s')}, trip alone stable={st}"
            )
            if d.get("verdict") != "N-1 insecure" or st not in ("separated", "de-energised"):
                bad.append(
                    f"{row_name(r)} cct exit {rc} {tail(err, 100)} / simulate exit {rc2} {tail(out2 + err2, 160)}"
                )
        return not bad, f"{SYSTEMS[n][0]}: {seen}; {bad or ''}"

    @probe(f"BC{n}4")
    def _(n=n):
        case, _w = case_of(n)
        _rc, _t, rows = screening(n)
        isl = [r for r in rows if r.get("islanded") and r.get("far_bus") is not None]
        if not isl:
            return True, f"{SYSTEMS[n][0]}: no load islanding among {len(rows)} faults"
        sys.path.insert(0, CLONE)
        from stabctl.io import load_case

        c = load_case(str(case))
        fb, tb_ = list(map(int, c.branches.from_bus)), list(map(int, c.branches.to_bus))
        gen = set(map(int, c.machines.bus))
        bad, seen = [], []
        for r in isl[:4]:
            adj = {}
            dropped = False
            for a, b in zip(fb, tb_):
                if not dropped and {a, b} == {r["bus"], r["far_bus"]}:
                    dropped = True  # circuit 1
                    continue
                adj.setdefault(a, set()).add(b)
                adj.setdefault(b, set()).add(a)
            reach, todo = set(gen), list(gen)
            while todo:
                x = todo.pop()
                for y in adj.get(x, ()):
                    if y not in reach:
                        reach.add(y)
                        todo.append(y)
            cut = sorted(set(map(int, c.buses.number)) - reach)
            seen.append(f"{row_name(r)}: {r['islanded']} (graph {cut})")
            if sorted(r["islanded"]) != cut:
                bad.append(row_name(r))
        return not bad, f"{SYSTEMS[n][0]}: {seen}"

    for k, gain in GAINS.items():

        @probe(f"BC{n}{k}")
        def _(n=n, gain=gain):
            name = SYSTEMS[n][0]
            case, _w = case_of(n)
            _rc, _t, rows = screening(n)
            faults = picked_faults(rows)
            if not faults:
                return True, f"{name}: no fault with a CCT to place for"
            fcsv = WORK / f"{name}.faults.csv"
            fcsv.write_text(
                "bus,far_bus\n"
                + "".join(
                    f"{r['bus']},{'' if r['far_bus'] is None else r['far_bus']}\n" for r in faults
                )
            )
            plan = WORK / f"{name}.plan{gain}.json"
            rc, out, err, dt = KIT.run(
                [
                    "place",
                    case,
                    "--faults",
                    fcsv,
                    "--target-cct-gain",
                    gain,
                    "--set-aside-infeasible",
                    "--workers",
                    1,
                    "--out",
                    plan,
                    *SYSTEMS[n][5],
                ],
                timeout=2400,
            )
            (WORK / f"{name}.plan{gain}.txt").write_text(f"exit {rc} {dt:.0f} s\n{out}\n{err}")
            label = next(
                (w for w in ("NOTHING TO PLACE", "NOT verified", "VERIFIED") if w in out),
                None,
            )
            head = f"{name} +{gain} %: exit {rc}, {label}, {dt:.0f} s"
            if rc != 0 or tb(err) or label is None:
                return False, f"{head}: {tail(out + err, 300)}"
            p = json.loads(plan.read_text())
            vout = WORK / f"{name}.plan{gain}.verify.jsonl"
            r2, o2, e2, _ = KIT.run_argv(
                [sys.executable, str(WORK / "verify_plan.py"), str(case), str(plan)], 2400
            )
            vout.write_text(o2 + e2)
            lines = [json.loads(x) for x in o2.splitlines() if x.startswith("{")]
            miss = [
                x
                for x in lines[1:]
                if x.get("met")
                and x.get("cct_here_s") is not None
                and not (
                    x.get("met_here")
                    and x.get("same_cell", True)
                    and x.get("finite_energy_stable_at_required", True)
                )
                or "cct_here_error" in x
                or "finite_energy_error" in x
            ]
            facts = [
                f"{x['name']} req {x['required_s']} plan {x['plan_cct_s']} here {x.get('cct_here_s')}"
                for x in lines[1:]
                if x.get("met")
            ]
            return r2 == 0 and not miss, (
                f"{head}: {p['total_mw']:.1f} MW at {p['n_sites']} sites, {p['n_met']} of "
                f"{p['n_contingencies']} met; set aside {len(p.get('infeasible') or []) + len(p.get('n1_insecure') or []) + len(p.get('not_simulable') or [])}; "
                f"independent: {facts}; {'MISS ' + json.dumps(miss)[:400] if miss else ''}"
                f"{'' if r2 == 0 else tail(e2, 200)}"
            )

    @probe(f"BC{n}8")
    def _(n=n):
        name = SYSTEMS[n][0]
        case, _w = case_of(n)
        _rc, _t, rows = screening(n)
        faults = picked_faults(rows, 3)
        bad, seen = [], []
        for r in faults:
            cells = {}
            for m in ("bisection", "sime"):
                a = ["cct", case, "--fault", r["bus"], "--search", m, "--json", *mo(n)]
                if r["far_bus"] is not None:
                    a[4:4] = ["--far-bus", r["far_bus"]]
                rc, out, err = run(a, 900)
                try:
                    d = json.loads(out)
                    cells[m] = (d.get("cct_s"), d.get("n_simulations"))
                except ValueError:
                    cells[m] = (f"exit {rc}: {tail(err, 80)}", None)
            b, s = cells["bisection"][0], cells["sime"][0]
            seen.append(f"{row_name(r)} {cells}")
            if not (isinstance(b, float) and isinstance(s, float) and abs(b - s) < 1e-6):
                bad.append(row_name(r))
        return not bad, f"{name}: {seen}"


@probe("BC49")
def _():
    """GB: line trips that island a radial bus (load buses 456, 652, 669; generator buses
    2074, 2): `sweep-cct` names the island's buses (the radial bus, from the branch
    table), keeps a CCT or verdict for the rest, and counts none as failed."""
    case, _w = case_of(4)
    pairs = [(457, 456), (326, 652), (282, 669), (1842, 2074), (1, 2)]
    f = WORK / "gb_island.csv"
    f.write_text("bus,far_bus\n" + "".join(f"{a},{b}\n" for a, b in pairs))
    out = WORK / "gb_island_probe.jsonl"
    out.unlink(missing_ok=True)
    rc, o, e, _ = KIT.run(
        ["sweep-cct", case, "--faults", f, "--workers", 1, "--t-max", 0.5, "--out", out], 900
    )
    named = {}
    for ln in o.splitlines():
        m = re.search(r"gb\.json/(\d+)-(\d+)/.*bus\(es\) \[([\d, ]+)\] islanded", ln)
        if m:
            named[(int(m.group(1)), int(m.group(2)))] = [int(x) for x in m.group(3).split(",")]
    bad = [p for p in pairs if named.get(p) != [p[1]]]
    ok = rc == 0 and not bad and " 0 failed" in o and not tb(e)
    return ok, f"gb: exit {rc}; islands named {named}; {tail(o, 260)}"


@probe("BC02")
def _():
    """A plan's infeasibility proof checked from outside: the CCT it says every site at its
    bound (50 % of each machine's MVA, --max-site-pct's default) reaches is `cct
    --esd-pct 50`'s, in the same 1 ms cell (the +20 % plans of BCn6, first contingency
    of each set aside)."""
    bad, seen = [], []
    for n in (1, 2, 3, 4):
        name = SYSTEMS[n][0]
        txt = WORK / f"{name}.plan20.txt"
        if not txt.exists():
            continue
        m = re.search(
            r"contingency (\S+) \(fault at bus (\d+)(?: on line \d+-(\d+))? at [\d.]+ s\) "
            r"reaches a CCT of only ([\d.]+) s with every candidate site at its bound",
            txt.read_text(),
        )
        if not m:
            continue
        a = ["cct", WORK / f"{name}.json", "--fault", m.group(2), "--esd-pct", 50, "--json", *mo(n)]
        if m.group(3):
            a[4:4] = ["--far-bus", m.group(3)]
        rc, out, err = run(a, 900)
        try:
            got = json.loads(out).get("cct_s")
        except ValueError:
            got = f"exit {rc} {tail(err, 100)}"
        seen.append(f"{name} {m.group(1)}: plan {m.group(4)}, cct --esd-pct 50 {got}")
        if not isinstance(got, float) or abs(got - float(m.group(4))) > 1e-6:
            bad.append(name)
    return not bad and bool(seen), "; ".join(seen)


@probe("BC03")
def _():
    """GB: a plan for contingencies whose trips island a load bus (282-669: bus 669, 163.4
    MW shed; 457-456) and a machine (1-3: G2 at bus 3 lost), which `cct`, `screen` and
    `sweep-cct` name: the plan (text or --out JSON) should say so too (docs/cli.md: the
    islanding named with the verdict; issue 53 item 2); then its met contingencies
    re-searched here with its devices."""
    case, _w = case_of(4)
    f = WORK / "gb_islfaults.csv"
    f.write_text("bus,far_bus\n282,669\n457,456\n1,3\n")
    plan = WORK / "gb_isl.plan5.json"
    rc, out, err, dt = KIT.run(
        [
            "place",
            case,
            "--faults",
            f,
            "--target-cct-gain",
            5,
            "--set-aside-infeasible",
            "--workers",
            1,
            "--out",
            plan,
        ],
        timeout=1200,
    )
    if rc != 0 or not plan.exists():
        return False, f"place exit {rc}: {tail(err, 200)}"
    said = "island" in (out + plan.read_text()).lower()
    r2, o2, e2, _ = KIT.run_argv(
        [sys.executable, str(WORK / "verify_plan.py"), str(case), str(plan)], 1200
    )
    lines = [json.loads(x) for x in o2.splitlines() if x.startswith("{")]
    ver = [
        f"{x['name']} req {x['required_s']} plan {x['plan_cct_s']} here {x.get('cct_here_s')}"
        for x in lines[1:]
        if x.get("met")
    ]
    good = all(x.get("met_here") and x.get("same_cell") for x in lines[1:] if x.get("met"))
    head = next((ln for ln in out.splitlines() if ln.startswith("case ")), "")[:160]
    return said and good, (
        f"gb +5 %: exit {rc}, {dt:.0f} s; {head}; islanding named in the plan: {said} "
        f"(cct/sweep-cct name 669 with 163.4 MW shed and G2 lost); independent: {ver}"
    )


@probe("BC01")
def _():
    out = []
    bad = []
    for rel in ("wscc9/wscc9.xlsx", "matpower/case14.m"):
        stem = Path(rel).stem
        path = WORK / f"{stem}.json"
        rc, o, e, _ = KIT.run(["import-andes", ANDES / rel, "-o", path], timeout=600)
        if rc != 0:
            out.append(f"{rel}: import exit {rc}: {tail(e, 160)}")
            if rc != 2 or tb(e):
                bad.append(rel)
            continue
        rc2, o2, e2, _ = KIT.run(
            ["screen", path, "--workers", 1, "--out", WORK / f"{stem}.s.jsonl"], 300
        )
        rc3, o3, e3, _ = KIT.run(["cct", path, "--fault", 4], 300)
        out.append(
            f"{rel}: imported; screen exit {rc2}: {tail(e2, 160)}; cct exit {rc3}: {tail(e3, 160)}"
        )
        if rc2 != 2 or rc3 != 2 or tb(e2 + e3) or (WORK / f"{stem}.s.jsonl").exists():
            bad.append(rel)
    return not bad, "; ".join(out)


VERIFY = Path(__file__).resolve().parent / "reliability_probes_56_verify.py"

if __name__ == "__main__":
    (WORK / "verify_plan.py").write_text(VERIFY.read_text())
    KIT.main(banner="work dir {wd}; BC_WORK " + str(WORK))
