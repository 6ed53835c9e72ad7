"""ESD sizing and placement study: least total MW that reaches, on every severe
contingency, the CCT gain of 5 % storage at every generator, against that uniform fleet
(`stabctl paper`, or `python analysis/placement_study.py`; `placement_study(case, out_dir)`
for reports).

For each case: (1) screen line faults at both ends of every line (in miniWECC of every line
at a generator's HV bus; in Kundur also bus faults; coarse CCT: 5 ms, t_max 0.5 s;
resumable, `stabctl.parallel`), keep the paper's fault and the most severe others (smallest
CCT, distinct lines first), up to 10; (2) CCT without storage (bisection, 1 ms) and with
the uniform 5 % fleet (first unstable clearing time, `placement_eval.scanned_cct`);
(3) `stabctl.placement.loop.place` from the uniform fleet with its CCTs as targets, for
all contingencies and for the paper's alone; (4) the Pareto curve: total MW for
25/50/75 % of each contingency's uniform gain (from uniform fleets of 1.25/2.5/3.75 %);
(5) the first-order SIME estimate of the MW the critical machines' sites need.  Writes
reports/placement_<case>.md, its JSON and three figures.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from stabctl.io import load_case  # noqa: E402
from stabctl.plotting.figures import save_figure as _save  # noqa: E402
from stabctl.stability.cct import LineFault, cct_jobs  # noqa: E402
from stabctl.studies.cases import DEFAULT_FAULTS  # noqa: E402
from stabctl.placement.program import candidate_sites  # noqa: E402
from stabctl.placement.evaluation import Contingency  # noqa: E402
from stabctl.placement.loop import _rounded, baseline, evaluations, place  # noqa: E402
from stabctl.storage.devices import hv_bus  # noqa: E402
from stabctl.parallel import run_sweep, strip_run_dependent, worker_pool  # noqa: E402

UNIFORM_PCT, BUDGET = 5.0, 0.25          # the paper's fleet; MW budget (fraction of it)
N_FAULTS = 10
GAIN_FRACTIONS = (0.25, 0.5, 0.75)        # Pareto points below the full uniform gain
UNIFORM_PCTS = (1.25, 2.5)                # smaller uniform fleets for comparison
SCREEN_TOL, SCREEN_T_MAX, TOL = 0.005, 0.5, 1e-3
MAX_ITER, MAX_ITER_SIDE = 8, 4            # simulated allocations: the main run; the others
HEARTBEAT_S = 8.0                         # longest silence of the progress callback (s)


# -- contingencies -----------------------------------------------------------------------

def candidate_faults(case) -> list[LineFault]:
    """A fault at each end of every line (same kV at both ends, first circuit), the line
    tripped at clearing; in a case with more than 2 N_FAULTS lines only the lines with an
    end at a generator's HV bus, in a smaller case also a fault at every bus cleared
    without a trip (a small case has too few lines whose loss it survives)."""
    hv = {hv_bus(case, int(k)) for k in case.machines.number}
    kv = lambda b: case.buses.kv[case.bus_index(b)]  # noqa: E731
    lines = list(dict.fromkeys((int(f), int(t)) for f, t in zip(case.branches.from_bus,
                                                                  case.branches.to_bus)
                               if kv(f) == kv(t)))
    if len(lines) > 2 * N_FAULTS:
        lines = [(f, t) for f, t in lines if f in hv or t in hv]
    faults = [LineFault(a, b) for f, t in lines for a, b in ((f, t), (t, f))]
    if len(lines) <= 2 * N_FAULTS:
        faults += [LineFault(int(b), None) for b in case.buses.number]
    return faults


def screen(case_name: str, out_dir: Path, workers: int, progress=None) -> list[dict]:
    """Coarse CCT of every candidate fault (resumable JSON lines in out_dir; no half-step
    error check, which a ranking does not use): [{"fault", "cct_s", "t_unstable_s"} or
    {"fault", "error"}].  progress: callable(done, total) after each fault."""
    faults = candidate_faults(load_case(case_name))
    rep = run_sweep(cct_jobs(case_name, faults, tol=SCREEN_TOL, t_max=SCREEN_T_MAX,
                             error_check=False),
                    out_dir / f"placement_{case_name}_screening.jsonl", workers=workers,
                    progress=progress or False)
    rows = []
    for f, rec in zip(faults, rep.records.values()):
        ok = rec["status"] == "ok"
        rows.append({"fault": f, "cct_s": rec["result"]["cct_s"] if ok else None,
                     "t_unstable_s": rec["result"]["t_unstable_s"] if ok else None,
                     "error": None if ok else rec.get("error", "")})
    return rows


def choose(rows, paper: LineFault, n: int = N_FAULTS) -> list[LineFault]:
    """The paper's fault and the n - 1 screened faults with the smallest CCT, one per
    line first, then second ends."""
    ranked = sorted((r for r in rows if r["cct_s"] is not None and r["fault"] != paper),
                    key=lambda r: r["cct_s"])
    line = lambda f: frozenset((f.bus, f.far_bus))  # noqa: E731
    chosen, lines = [paper], {line(paper)}
    for r in ranked:
        if len(chosen) < n and line(r["fault"]) not in lines:
            chosen.append(r["fault"])
            lines.add(line(r["fault"]))
    for r in ranked:
        if len(chosen) < n and r["fault"] not in chosen:
            chosen.append(r["fault"])
    return chosen


def targets(faults, base: dict, reference: dict, fraction: float) -> tuple:
    """Contingencies whose target is the CCT without storage plus `fraction` of the gain
    of the reference evaluations (by name), rounded up to the tolerance (s)."""
    out = []
    for f in faults:
        name = Contingency(f, 1.0).name
        b, r = base[name]["cct_s"], reference[name]["cct_s"]
        t = b + fraction * max(r - b, 0.0)
        out.append(Contingency(f, round(np.ceil(t / TOL - 1e-6) * TOL, 9)))
    return tuple(out)


# -- the study ---------------------------------------------------------------------------

def study(case_name: str, records_dir: Path, workers: int, say) -> dict:
    """Every number of the report (JSON-able).  One pool of `workers` processes serves
    every simulation after the screening; the uniform fleets, then the placement runs,
    are simulated concurrently (each is deterministic, so the numbers do not depend on
    the order the pool serves them in).  The CCT without storage starts from the
    screening's 5 ms bracket; the uniform fleets (rounded up to 0.1 MW per site, as every
    allocation) are the placement runs' starts and their first unstable clearing times
    the start evaluations."""
    case = load_case(case_name)
    sites = candidate_sites(case)
    mva = np.array([float(case.machines.mva[case.machine_index(s.machine)]) for s in sites])
    wall = time.perf_counter()
    with _heartbeat(say, case_name) as beat:
        say = beat.say
        rows = screen(case_name, records_dir, workers,
                      lambda k, n: beat.note(f"screening {k}/{n} faults"))
        faults = choose(rows, DEFAULT_FAULTS[case_name][0])
        say(f"{case_name}: screened {len(rows)} faults in {time.perf_counter() - wall:.0f} s;"
            f" kept {', '.join(Contingency(f, 1).name for f in faults)}")
        with worker_pool(workers) as pool_map:
            run_map = beat.counting(pool_map)
            kw = {"sites": sites, "tol": TOL, "run_map": run_map}
            brackets = {Contingency(r["fault"], 1).name: (r["cct_s"], r["t_unstable_s"])
                        for r in rows if r["cct_s"] is not None}
            beat.note("CCT without storage")
            base = baseline(case_name, faults, brackets=brackets, **kw)
            plain = targets(faults, base, base, 0.0)       # targets unused by a full scan
            fleets = {p: _rounded(p / 100 * mva, sites) for p in (UNIFORM_PCT, *UNIFORM_PCTS)}
            beat.note("uniform fleets")
            uniform = _concurrently({p: (lambda p=p: evaluations(
                case_name, plain, fleets[p], base=base, scan="full", **kw)) for p in fleets})
            say(f"{case_name}: uniform CCTs done at {time.perf_counter() - wall:.0f} s")
            paper = targets(faults[:1], base, uniform[UNIFORM_PCT], 1.0)

            def run(label, frac, cons, max_iter):
                pct = frac * UNIFORM_PCT
                start = fleets.get(pct, _rounded(pct / 100 * mva, sites))
                return place(case_name, cons, base=base, start=start,
                             start_evaluations=uniform.get(pct), max_iter=max_iter,
                             progress=lambda m: say(f"{case_name} {label}: {m}"), **kw)

            beat.note("placement runs")
            jobs = {"paper": lambda: run("paper's fault", 1.0, paper, MAX_ITER_SIDE)}
            for frac in (1.0, *GAIN_FRACTIONS):
                jobs[frac] = (lambda frac=frac: run(
                    f"{frac:.0%}", frac, targets(faults, base, uniform[UNIFORM_PCT], frac),
                    MAX_ITER if frac == 1.0 else MAX_ITER_SIDE))
            done = _concurrently(jobs)
    single = done.pop("paper")
    runs = {frac: done[frac] for frac in (1.0, *GAIN_FRACTIONS)}
    say(f"{case_name}: the paper's fault alone: {single.allocation.total_mw:.1f} MW")
    for frac, r in runs.items():
        say(f"{case_name}: {frac:.0%} of the uniform gain: {r.allocation.total_mw:.1f}"
            f" MW, {'verified' if r.verified else 'NOT verified'}")
    d = _summary(case_name, rows, faults, sites, mva, fleets, base, uniform, runs,
                 time.perf_counter() - wall)
    d["paper_alone"] = {"name": paper[0].name, "total_mw": single.allocation.total_mw,
                        "verified": single.verified, "allocation": single.allocation.rows(),
                        "cct_s": single.evaluations[paper[0].name]["cct_s"],
                        "target_s": paper[0].target_cct_s}
    inertia = np.asarray(case.machines.H * case.machines.mva, float)
    for c in d["contingencies"]:
        c["first_order_mw"] = critical_only_mw(case, sites, UNIFORM_PCT / 100 * mva, inertia,
                                               c["critical"])
    return d


def _concurrently(calls: dict) -> dict:
    """Run the callables of `calls` (key -> callable()) in threads: key -> result (the
    first exception raised is raised)."""
    with ThreadPoolExecutor(len(calls)) as ex:
        futures = {k: ex.submit(f) for k, f in calls.items()}
        return {k: f.result() for k, f in futures.items()}


class _Beat:
    """The progress callback, repeated with the latest status line (`note`) whenever
    nothing was said for HEARTBEAT_S; `counting` wraps a run_map to count evaluations."""

    def __init__(self, say, case_name: str):
        self._say, self.case, self.status, self.n = say, case_name, "", 0
        self.last = time.monotonic()
        self.lock = threading.Lock()

    def say(self, msg: str) -> None:
        with self.lock:
            self.last = time.monotonic()
        self._say(msg)

    def note(self, status: str) -> None:
        self.status = status

    def counting(self, run_map):
        def counted(func, jobs):
            out = run_map(func, jobs)
            with self.lock:
                self.n += len(jobs)
            return out
        return counted

    def tick(self) -> None:
        if time.monotonic() - self.last >= HEARTBEAT_S:
            extra = f", {self.n} contingency evaluations done" if self.n else ""
            self.say(f"{self.case}: {self.status}{extra} ...")


@contextmanager
def _heartbeat(say, case_name: str):
    beat = _Beat(say, case_name)
    stop = threading.Event()

    def loop():
        while not stop.wait(0.5):
            beat.tick()

    thread = threading.Thread(target=loop, daemon=True)
    thread.start()
    try:
        yield beat
    finally:
        stop.set()
        thread.join()


def critical_only_mw(case, sites, uniform_mw, inertia, critical) -> float:
    """First-order MW at the critical machines' sites giving the uniform fleet's effect on
    the single-machine equivalent (SIME, docs/placement.md section 6): a rating P_i moves
    the OMIB accelerating power by P_i M_nc / M_T at a critical machine and by
    P_i M_c / M_T at another (the bang-bang law makes both act against the swing), so
    the same effect from critical sites alone needs (sum_c P_c M_nc + sum_nc P_nc M_c) / M_nc.
    inertia: H * MVA per machine (n_mac,); uniform_mw: per site (MW)."""
    crit = np.isin(case.machines.number, critical)
    m_c, m_t = inertia[crit].sum(), inertia.sum()
    at_crit = np.array([s.machine in critical for s in sites])
    effect = uniform_mw[at_crit].sum() * (m_t - m_c) + uniform_mw[~at_crit].sum() * m_c
    return float(effect / (m_t - m_c))


def _summary(case_name, rows, faults, sites, mva, fleets, base, uniform, runs, wall) -> dict:
    names = [Contingency(f, 1).name for f in faults]
    main = runs[1.0]
    return {
        "case": case_name, "wall_time_s": wall, "uniform_pct": UNIFORM_PCT,
        "screening": [{"fault": r["fault"].describe(), "name": Contingency(r["fault"], 1).name,
                       "cct_s": r["cct_s"], "error": r["error"]} for r in rows],
        "sites": [{"bus": s.bus, "machine": s.machine, "max_mw": s.max_mw, "mva": m}
                  for s, m in zip(sites, mva)],
        "contingencies": [{"name": n, "fault": f.describe(), "cct_none_s": base[n]["cct_s"],
                           "cct_uniform_s": uniform[UNIFORM_PCT][n]["cct_s"],
                           "cct_optimised_s": main.evaluations[n]["cct_s"],
                           "target_s": c.target_cct_s,
                           "critical": main.base[n]["critical"]}
                          for n, f, c in zip(names, faults, main.contingencies)],
        "uniform_total_mw": {str(p): float(fleets[p].sum()) for p in uniform},
        "uniform_cct_s": {str(p): {n: ev[n]["cct_s"] for n in names} for p, ev in uniform.items()},
        "runs": {str(frac): {"verified": r.verified, "message": r.message,
                             "total_mw": r.allocation.total_mw, "n_sites": r.allocation.n_sites,
                             "mw_by_site": r.allocation.mw.tolist(),
                             "allocation": r.allocation.rows(),
                             "cct_s": {n: r.evaluations[n]["cct_s"] for n in names},
                             "targets_s": {c.name: c.target_cct_s for c in r.contingencies},
                             "iterations": r.iterations, "wall_time_s": r.wall_time_s,
                             "solve_times_s": r.solve_times_s}
                 for frac, r in runs.items()},
    }


# -- figures and report ------------------------------------------------------------------

def figure_allocation(d: dict, path: Path) -> None:
    """Bars per site: optimised rating and the uniform 5 % rating (MW)."""
    labels = [f"{s['bus']}\nG{s['machine']}" for s in d["sites"]]
    opt = np.array(d["runs"]["1.0"]["mw_by_site"])
    uni = np.array([s["mva"] for s in d["sites"]]) * d["uniform_pct"] / 100
    x = np.arange(len(labels))
    fig, ax = plt.subplots(figsize=(max(6, 0.35 * len(x) + 2), 4))
    ax.bar(x - 0.2, uni, 0.4, label=f"uniform {d['uniform_pct']:g} % ({uni.sum():.0f} MW)",
           color="0.7")
    ax.bar(x + 0.2, opt, 0.4, label=f"optimised ({opt.sum():.0f} MW)", color="C3")
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_xlabel("site (HV bus, generator)")
    ax.set_ylabel("ESD rating (MW)")
    ax.set_title(f"{d['case']}: ESD allocation per site")
    ax.legend()
    _save(fig, path)


def figure_cct(d: dict, path: Path) -> None:
    """CCT per contingency: no storage, uniform 5 % (the target), optimised."""
    cs = d["contingencies"]
    x = np.arange(len(cs))
    fig, ax = plt.subplots(figsize=(max(6, 0.7 * len(x) + 2), 4))
    for k, (key, label, color) in enumerate((
            ("cct_none_s", "no storage", "0.6"),
            ("cct_uniform_s", f"uniform {d['uniform_pct']:g} % = target", "C0"),
            ("cct_optimised_s", "optimised", "C3"))):
        ax.bar(x + (k - 1) * 0.27, [1000 * c[key] for c in cs], 0.27, label=label, color=color)
    ax.set_xticks(x, [c["name"] for c in cs], rotation=30, fontsize=8)
    ax.set_ylabel("CCT (ms), verified by simulation")
    ax.set_title(f"{d['case']}: CCT per contingency")
    ax.legend(fontsize=8)
    _save(fig, path)


def figure_pareto(d: dict, path: Path) -> None:
    """Total MW against the fraction of the uniform gain reached on every contingency."""
    fr = sorted(float(f) for f in d["runs"])
    opt = [d["runs"][str(f)]["total_mw"] for f in fr]
    uni = sorted((_uniform_fraction(d, p), d["uniform_total_mw"][p]) for p in d["uniform_total_mw"])
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot([100 * f for f in fr], opt, "o-", color="C3", label="optimised placement")
    ax.plot([100 * f for f, _ in uni], [m for _, m in uni], "s--", color="C0",
            label="uniform fleets (1.25, 2.5, 5 %)")
    ax.axhline(BUDGET * d["uniform_total_mw"][str(d["uniform_pct"])], color="k", lw=0.8,
               ls=":", label=f"{BUDGET:.0%} of the uniform 5 % total")
    ax.set_xlabel("CCT gain reached on every contingency (% of the uniform 5 % gain)")
    ax.set_ylabel("total ESD rating (MW)")
    ax.set_title(f"{d['case']}: total MW against target gain")
    ax.legend(fontsize=8)
    _save(fig, path)


def _uniform_fraction(d: dict, pct: str) -> float:
    """Smallest fraction of its uniform-5 % gain that a uniform fleet reaches over the
    contingencies that have a gain."""
    fr = []
    for c in d["contingencies"]:
        gain = c["cct_uniform_s"] - c["cct_none_s"]
        if gain > 0:
            fr.append((d["uniform_cct_s"][pct][c["name"]] - c["cct_none_s"]) / gain)
    return min(fr) if fr else 1.0


def report(d: dict, out_dir: Path, generated_by: str = "stabctl paper") -> Path:
    """Write placement_<case>.md, .json and the figures; returns the markdown path.
    generated_by: the command the report names as its source.  The files hold no
    run-dependent values (timings: `timing_line`)."""
    case = d["case"]
    figs = {k: f"placement_{case}_{k}.png" for k in ("allocation", "cct", "pareto")}
    figure_allocation(d, out_dir / figs["allocation"])
    figure_cct(d, out_dir / figs["cct"])
    figure_pareto(d, out_dir / figs["pareto"])
    (out_dir / f"placement_{case}.json").write_text(
        json.dumps(strip_run_dependent(d), indent=1, default=float))
    path = out_dir / f"placement_{case}.md"
    path.write_text("\n".join(_markdown(d, figs, generated_by)) + "\n")
    return path


def _markdown(d: dict, figs: dict, generated_by: str = "stabctl paper") -> list[str]:
    main, case = d["runs"]["1.0"], d["case"]
    u_total = d["uniform_total_mw"][str(d["uniform_pct"])]
    ok = main["verified"] and main["total_mw"] <= BUDGET * u_total   # the study's target
    lines = [f"# ESD sizing and placement: {case}", "",
             f"Generated by `{generated_by}` (method in docs/placement.md).  Every CCT below "
             "is simulated (PSTess models), with the paper's bang-bang law (100 mHz "
             "deadband, 0.8 pu gate, system COI).", "",
             f"**Result**: {main['total_mw']:.1f} MW at {main['n_sites']} site(s) reaches, on "
             f"all {len(d['contingencies'])} contingencies, the CCT that "
             f"{d['uniform_pct']:g} % storage at every generator ({u_total:.0f} MW) gives: "
             f"{100 * main['total_mw'] / u_total:.1f} % of the uniform total; the study's "
             f"target (at most {BUDGET:.0%} of it, verified) is {'met' if ok else 'not met'}"
             f"{'' if main['verified'] else ' (allocation not verified: ' + main['message'] + ')'}.",
             "", "## Contingencies", "", _screening_text(d), "",
             "| contingency | critical machines | CCT none (ms) | uniform 5 % = target (ms) "
             "| gain | optimised (ms) | met | first-order MW at critical sites |",
             "|---|---|---|---|---|---|---|---|"]
    for c in d["contingencies"]:
        gain = (c["cct_uniform_s"] - c["cct_none_s"]) / c["cct_none_s"]
        lines.append(f"| {c['name']} | {', '.join(f'G{k}' for k in c['critical'])} | "
                     f"{1000 * c['cct_none_s']:.0f} | {1000 * c['cct_uniform_s']:.0f} | "
                     f"{100 * gain:+.0f} % | {1000 * c['cct_optimised_s']:.0f} | "
                     f"{'yes' if c['cct_optimised_s'] >= c['target_s'] - 1e-9 else 'NO'} | "
                     f"{c['first_order_mw']:.0f} |")
    lines += ["", _first_order_text(d)]
    lines += ["", f"![CCT per contingency]({figs['cct']})", "", "## Allocation", "",
              "| HV bus | generator | MW | % of its MVA |", "|---|---|---|---|"]
    mva = {s["machine"]: s["mva"] for s in d["sites"]}
    for a in main["allocation"]:
        lines.append(f"| {a['bus']} | G{a['machine']} | {a['mw']:.1f} | "
                     f"{100 * a['mw'] / mva[a['machine']]:.1f} |")
    lines += ["", f"Total {main['total_mw']:.1f} MW against {u_total:.0f} MW uniform.", "",
              f"![allocation]({figs['allocation']})", "", "## Iterations (target: full gain)",
              "", "| allocation | MW | sites | meets all | rho | simulations |",
              "|---|---|---|---|---|---|"]
    for it in main["iterations"]:
        rho = "restoration" if np.isnan(it["rho"]) else f"{it['rho']:.2f}"
        lines.append(f"| {it['iteration']} | {it['total_mw']:.1f} | {it['n_sites']} | "
                     f"{'yes' if it['meets_targets'] else 'no'} | {rho} | "
                     f"{it['n_simulations']} |")
    lines += ["", f"Stopped: {main['message']}.", "", "## Total MW against target gain", "",
              "| target (% of each contingency's uniform gain) | optimised MW | sites | "
              "verified |", "|---|---|---|---|"]
    for f in sorted(d["runs"], key=float):
        r = d["runs"][f]
        lines.append(f"| {100 * float(f):.0f} % | {r['total_mw']:.1f} | {r['n_sites']} | "
                     f"{'yes' if r['verified'] else 'no'} |")
    for p in sorted(d["uniform_total_mw"], key=float):
        lines.append(f"| uniform {float(p):g} %: {100 * _uniform_fraction(d, p):.0f} % "
                     f"reached | {d['uniform_total_mw'][p]:.0f} (uniform) | "
                     f"{len(d['sites'])} | yes |")
    lines += ["", f"![Pareto]({figs['pareto']})"]
    return lines


def timing_line(d: dict) -> str:
    """The study's run-dependent figures (for a run log, not the report): wall times of
    the main loop and the study, and Clarabel's solve times."""
    main = d["runs"]["1.0"]
    solve = [t for r in d["runs"].values() for t in r["solve_times_s"]] or [float("nan")]
    return (f"{d['case']}: placement loop wall time {main['wall_time_s']:.0f} s (study "
            f"{d['wall_time_s']:.0f} s); convex solves: median {1000 * np.median(solve):.1f} "
            f"ms, longest {1000 * max(solve):.1f} ms (Clarabel's own time)")


def _first_order_text(d: dict) -> str:
    """The SIME first-order reading of the result (docs/placement.md section 6)."""
    groups = {}
    for c in d["contingencies"]:
        key = tuple(sorted(c["critical"]))
        groups[key] = max(groups.get(key, 0.0), c["first_order_mw"])
    bound = sum(groups.values())
    u_total = d["uniform_total_mw"][str(d["uniform_pct"])]
    pa = d["paper_alone"]
    return (f"Last column: the MW that the critical machines' own sites need for the uniform "
            f"fleet's effect on the single-machine equivalent, to first order (an ESD at a "
            f"critical machine weighs M_nc/M_T, elsewhere M_c/M_T).  Summed over the "
            f"{len(groups)} distinct critical groups: {bound:.0f} MW = "
            f"{100 * bound / u_total:.0f} % of the uniform total, which is what this "
            f"contingency set asks at best to first order.  The paper's fault alone "
            f"({pa['name']}) needs {pa['total_mw']:.1f} MW = "
            f"{100 * pa['total_mw'] / u_total:.1f} % of the uniform total (verified CCT "
            f"{1000 * pa['cct_s']:.0f} ms, target {1000 * pa['target_s']:.0f} ms; "
            + ", ".join(f"{a['mw']:.0f} MW at bus {a['bus']} (G{a['machine']})"
                        for a in pa["allocation"]) + ").")


def _screening_text(d: dict) -> str:
    ok = [r for r in d["screening"] if r["cct_s"] is not None]
    fail = len(d["screening"]) - len(ok)
    n_bus = sum(1 for r in d["screening"] if "-" not in r["name"])
    n_line = len(d["screening"]) - n_bus
    scope = " at a generator HV bus" if n_line > 4 * N_FAULTS else ""
    buses = f" and {n_bus} bus faults cleared without a trip" if n_bus else ""
    return (f"Screened {n_line} line faults (each end of every line{scope}, line tripped)"
            f"{buses}; coarse CCT, {1000 * SCREEN_TOL:g} ms, up to "
            f"{SCREEN_T_MAX:g} s: {len(ok)} with a CCT, {fail} without one (unstable even "
            "when cleared at once, or still stable at the limit).  Kept: the paper's "
            f"fault and the {len(d['contingencies']) - 1} most severe others (distinct "
            "lines first).  Targets: the CCT of the uniform fleet, taken as the first "
            "unstable clearing time (scan from the CCT without storage in 5 ms steps, then "
            "1 ms bisection), as for every optimised allocation.  The loop starts from the "
            "uniform fleet (which meets every target) and only accepts verified savings.")


def placement_study(case_name: str, out_dir="reports", workers: int = 2, progress=None,
                    records_dir=None, generated_by: str = "stabctl paper") -> Path:
    """Run the study for one case (kundur or miniwecc: the paper's fault must be in
    `stabctl.studies.cases.DEFAULT_FAULTS`) and write its report into out_dir; returns the markdown
    path.  workers: processes; progress: callable(str) (default: stderr); records_dir:
    where the resumable screening records go (default out_dir); generated_by: the command
    the report names as its source.  Raises as
    `stabctl.placement.loop.place` (InfeasibleError, InputError, SimulationError)."""
    out = Path(out_dir)
    records = Path(records_dir or out)
    for d in (out, records):
        d.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda msg: print(msg, file=sys.stderr, flush=True))
    d = study(case_name, records, workers, say)
    say(timing_line(d))
    return report(d, out, generated_by)
