"""ESD sizing and placement study, a planner's question: least-cost sites, MW and MWh so
that every screened fault is stable when cleared after REQUIRED_CYCLES cycles at every
load level of LOAD_LEVELS, against the least uniform fleet meeting the same requirement
(`stabctl paper`, or `python analysis/placement_study.py`; `placement_study(case, out_dir)`
for reports).

For each case: (1) screen line faults at both ends of every line (in miniWECC of every line
at a generator's HV bus; in Kundur also bus faults; coarse CCT: 5 ms, t_max 0.5 s;
resumable, `stabctl.parallel`); every fault stable when cleared at once is a contingency
at each load level; (2) `stabctl.placement.plan.plan` by constraint generation, with
the least uniform fleet (bisection), each binding fault alone and the clearing margin of
every contingency; (3) the Pareto curve of cost against the required clearing time
(PARETO_CYCLES, at the base load: the fast variant `stabctl paper` runs); (4) the paper's
fault with today's target (the CCT of the uniform 5 % fleet), for continuity.  Writes
reports/placement_<case>.md, its JSON and three figures.
"""

from __future__ import annotations

import json
import logging
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from stabctl.errors import counted
from stabctl.io import load_case
from stabctl.parallel import run_sweep, strip_run_dependent, worker_pool
from stabctl.placement.energy import MJ_PER_MWH
from stabctl.placement.evaluation import Contingency, VerifyOptions
from stabctl.placement.loop import PlaceOptions, Study, WarmStart, _rounded, evaluations, place
from stabctl.placement.plan import PlanOptions, plan
from stabctl.placement.program import candidate_sites
from stabctl.placement.requirements import CostModel, Requirement, screening_brackets
from stabctl.plotting.figures import save_figure as _save
from stabctl.progress import HEARTBEAT_S, Heartbeat
from stabctl.stability.cct import LineFault, SearchOptions, cct_jobs
from stabctl.storage.devices import hv_bus
from stabctl.studies.cases import DEFAULT_FAULTS

logger = logging.getLogger(__name__)

UNIFORM_PCT = 5.0  # the paper's fleet (continuity section)
N_FAULTS = 10  # a case with more than 2 N_FAULTS lines: HV only
REQUIRED_CYCLES = 5.0  # normal clearing plus a margin (TPL-001 spirit)
LOAD_LEVELS = (0.9, 1.0, 1.1)  # fractions of the base load
PARETO_CYCLES = {"miniwecc": (4.0, 6.0), "kundur": (10.0, 12.0)}
#: Illustrative prices (M$): power conversion per MW, energy per MWh, per site
COSTS = CostModel(per_mw=0.3, per_mwh=0.4, per_site=2.0)
#: Screening: CCT resolution and limit (s).  The limit covers every clearing time the study
#: asks about (the largest required time plus MARGIN_CAP_S); a fault still stable there is
#: known stable at each of them without a run.
SCREEN_TOL, SCREEN_T_MAX, TOL = 0.005, 0.2, 1e-3
MARGIN_TOL, MARGIN_CAP_S = 0.005, 0.1  # clearing margins: resolution, largest shown (s)
T_MAX_PLACE = 1.0  # CCT search limit of the placement runs (s)
MAX_ITER, MAX_ITER_SIDE = 6, 4  # simulated allocations: per round; the others
HALF_STEP_N = 10  # tightest contingencies simulated at h/2


# -- contingencies -----------------------------------------------------------------------


def candidate_faults(case) -> list[LineFault]:
    """A fault at each end of every line (same kV at both ends, first circuit), the line
    tripped at clearing; in a case with more than 2 N_FAULTS lines only the lines with an
    end at a generator's HV bus, in a smaller case also a fault at every bus cleared
    without a trip (a small case has too few lines whose loss it survives)."""
    hv = {hv_bus(case, int(k)) for k in case.machines.number}
    kv = lambda b: case.buses.kv[case.bus_index(b)]  # noqa: E731
    lines = list(
        dict.fromkeys(
            (int(f), int(t))
            for f, t in zip(case.branches.from_bus, case.branches.to_bus)
            if kv(f) == kv(t)
        )
    )
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
    search = SearchOptions(tol=SCREEN_TOL, t_max=SCREEN_T_MAX, error_check=False)
    rep = run_sweep(
        cct_jobs(case_name, faults, search=search),
        out_dir / f"placement_{case_name}_screening.jsonl",
        workers=workers,
        progress=progress or False,
    )
    rows = []
    for f, rec in zip(faults, rep.records.values()):
        ok = rec["status"] == "ok"
        islands = (rec["result"] if ok else rec).get("islanded") or []
        rows.append(
            {
                "fault": f,
                "cct_s": rec["result"]["cct_s"] if ok else None,
                "t_unstable_s": rec["result"]["t_unstable_s"] if ok else None,
                "error": None if ok else rec.get("error") or rec.get("reason", ""),
                "islands_machines": any(e.get("machines") for e in islands),
            }
        )
    return rows


def in_scope(rows) -> list[dict]:
    """The screened faults the planner must meet: those stable when cleared at once (a
    CCT, or still stable at the screening's limit) whose trip cuts no generator off the
    main grid.  A fault that islands generators (`islands_machines`: their step-up
    transformer or the only line to them opened) loses them whatever the clearing time:
    a question of the island's frequency and of the generation lost, not of the ESDs'
    transient-stability law, so it is named out of scope (`islanding`) and not planned
    for."""
    return [
        r
        for r in rows
        if not r.get("islands_machines")
        and (r["cct_s"] is not None or "still stable" in (r["error"] or ""))
    ]


def islanding(rows) -> list[str]:
    """Names of the screened faults left out because they island generators (`in_scope`).

    Parameters
    ----------
    rows : list of dict
        The screening rows (`screen`).

    Returns
    -------
    list of str
        Each fault's short name, in screening order.
    """
    return [Contingency(r["fault"], 1).name for r in rows if r.get("islands_machines")]


def paper_continuity(case_name: str, sites, mva, kw: Study, say) -> dict:
    """The paper's fault alone with today's target: the CCT of the uniform 5 % fleet (its
    first unstable clearing time), from that fleet (`place`, MAX_ITER_SIDE allocations)."""
    fault = DEFAULT_FAULTS[case_name][0]
    plain = (Contingency(fault, T_MAX_PLACE),)
    base = evaluations(case_name, plain, None, kw)
    fleet = _rounded(UNIFORM_PCT / 100 * mva, sites)
    uni = evaluations(case_name, plain, fleet, kw, VerifyOptions(base=base, scan="full"))
    name = plain[0].name
    target = (Contingency(fault, uni[name]["cct_s"]),)
    res = place(
        case_name,
        target,
        kw,
        PlaceOptions(max_iter=MAX_ITER_SIDE),
        WarmStart(base=base, start=fleet, evaluations=uni),
        progress=lambda m: say(f"{case_name} paper's fault: {m}"),
    )
    return {
        "name": name,
        "cct_none_s": base[name]["cct_s"],
        "target_s": uni[name]["cct_s"],
        "uniform_mw": float(fleet.sum()),
        "total_mw": res.allocation.total_mw,
        "verified": res.verified,
        "allocation": res.allocation.rows(),
        "cct_s": res.evaluations[name]["cct_s"],
    }


def study(case_name: str, records_dir: Path, workers: int, say, fast: bool = True) -> dict:
    """Every number of the report (JSON-able).  One pool of `workers` processes serves
    every simulation after the screening (resumable records).  The main plan: every
    screened fault stable when cleared at once, REQUIRED_CYCLES cycles, every load level
    of LOAD_LEVELS, with the least uniform fleet, each binding fault alone and the
    clearing margins (MARGIN_TOL); the Pareto points (PARETO_CYCLES[case]) at the base
    load with their least uniform fleets; the paper's fault with today's uniform-5 %
    target.  fast: the Pareto points at the base load only (the paper's study)."""
    case = load_case(case_name)
    sites = candidate_sites(case)
    mva = np.array([float(case.machines.mva[case.machine_index(s.machine)]) for s in sites])
    wall = time.perf_counter()
    done = _Evaluations(case_name)
    # twice the plans' own heartbeat (`stabctl.placement.plan`), which speak through this
    # one: it repeats its line only when no plan has spoken, not beside each of theirs
    with Heartbeat(say, done.line, every=2 * HEARTBEAT_S) as beat:
        say = beat
        beat.note("screening")
        rows = screen(
            case_name, records_dir, workers, lambda k, n: beat.note(f"screening {k}/{n} faults")
        )
        scope = in_scope(rows)
        faults = [r["fault"] for r in scope]
        brackets = screening_brackets(
            records_dir / f"placement_{case_name}_screening.jsonl", case_name, case.digest()
        )
        say(
            f"{case_name}: screened {counted(len(rows), 'fault')} in "
            f"{time.perf_counter() - wall:.0f} s;"
            f" {len(faults)} stable when cleared at once"
        )
        with worker_pool(workers) as pool_map:
            run_map = done.counting(pool_map)
            kw = Study(
                sites=sites, search=SearchOptions(tol=TOL, t_max=T_MAX_PLACE), run_map=run_map
            )
            common = PlanOptions(
                brackets=brackets,
                cost=COSTS,
                drop_infeasible=True,
                place=PlaceOptions(max_iter=MAX_ITER),
            )
            beat.note(f"plan for {REQUIRED_CYCLES:g} cycles")
            main = plan(
                case_name,
                faults,
                Requirement(cycles=REQUIRED_CYCLES),
                replace(
                    common,
                    load_levels=LOAD_LEVELS,
                    alone=True,
                    margins_tol=MARGIN_TOL,
                    half_step_n=HALF_STEP_N,
                    margins_cap_s=MARGIN_CAP_S,
                    uniform=True,
                ),
                kw,
                progress=lambda m: say(f"{case_name} {REQUIRED_CYCLES:g} cycles: {m}"),
            )

            def point(cyc):
                r = plan(
                    case_name,
                    faults,
                    Requirement(cycles=cyc),
                    replace(common, load_levels=(1.0,) if fast else LOAD_LEVELS, uniform=not fast),
                    kw,
                    progress=lambda m: say(f"{case_name} {cyc:g} cycles: {m}"),
                )
                return _pareto_point(cyc, r)

            # the Pareto points and the paper's fault at the same time (one thread each,
            # sharing the pool): their batches are too small to keep every worker busy
            beat.note("Pareto points and the paper's fault with the uniform 5 % target")
            with ThreadPoolExecutor(max_workers=len(PARETO_CYCLES[case_name]) + 1) as threads:
                paper_job = threads.submit(paper_continuity, case_name, sites, mva, kw, say)
                pareto = list(threads.map(point, PARETO_CYCLES[case_name]))
                paper = paper_job.result()
    pareto.append(_pareto_point(REQUIRED_CYCLES, main, LOAD_LEVELS))
    return {
        "case": case_name,
        "wall_time_s": time.perf_counter() - wall,
        "required_cycles": REQUIRED_CYCLES,
        "load_levels": list(LOAD_LEVELS),
        "costs": {"per_mw": COSTS.per_mw, "per_mwh": COSTS.per_mwh, "per_site": COSTS.per_site},
        "pareto_load_levels": [1.0] if fast else list(LOAD_LEVELS),
        "screening": [
            {
                "fault": r["fault"].describe(),
                "name": Contingency(r["fault"], 1).name,
                "cct_s": r["cct_s"],
                "error": r["error"],
            }
            for r in rows
        ],
        "islanding": islanding(rows),
        "n_faults": len(faults),
        "sites": [
            {"bus": s.bus, "machine": s.machine, "max_mw": s.max_mw, "mva": m}
            for s, m in zip(sites, mva)
        ],
        "plan": main.to_dict(),
        "mw_by_site": main.mw.tolist(),
        "pareto": sorted(pareto, key=lambda p: p["cycles"]),
        "paper_alone": paper,
    }


def _pareto_point(cycles: float, r, levels=(1.0,)) -> dict:
    u = r.uniform or {}
    return {
        "cycles": cycles,
        "load_levels": list(levels),
        "total_mw": r.total_mw,
        "total_mwh": float(r.mwh.sum()),
        "cost": r.cost["total"],
        "verified": r.verified,
        "n_sites": int(np.count_nonzero(r.mw)),
        "uniform_pct": u.get("pct"),
        "uniform_mw": u.get("total_mw"),
        "uniform_cost": (u.get("cost") or {}).get("total"),
        "uniform_verified": u.get("verified"),
        "set_aside": list(r.set_aside),
    }


class _Evaluations:
    """Counts the contingency evaluations a run_map (`counting`) was given, for the
    heartbeat's line (`line`) of one case; thread-safe."""

    def __init__(self, case_name: str):
        self.case, self.n, self._lock = case_name, 0, threading.Lock()

    def counting(self, run_map):
        """run_map that counts its jobs and hands ``done`` on to run_map (a
        `stabctl.parallel.worker_pool` map), so that the plan's heartbeat says each
        batch's fraction done and time left (`stabctl.placement.context.PlanContext.
        counting`)."""

        def counted(func, jobs, done=None):
            out = run_map(func, jobs, done=done)
            with self._lock:
                self.n += len(jobs)
            return out

        return counted

    def line(self, status: str) -> str:
        """The heartbeat's line of a status."""
        extra = f", {self.n} contingency evaluations done" if self.n else ""
        return f"{self.case}: {status}{extra} ..."


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


# -- figures and report ------------------------------------------------------------------


def figure_allocation(d: dict, path: Path) -> None:
    """Bars per site: optimised rating and the least uniform fleet's (MW); a case that
    needs no storage says so instead of drawing empty bars."""
    labels = [f"{s['bus']}\nG{s['machine']}" for s in d["sites"]]
    opt = np.array(d["mw_by_site"])
    u = d["plan"]["uniform"] or {}
    uni = np.array(u.get("mw_by_site") or np.zeros(len(opt)))
    x = np.arange(len(labels))
    fig, ax = plt.subplots(figsize=(max(6, 0.35 * len(x) + 2), 4))
    ax.set_title(f"{d['case']}: allocation for {d['required_cycles']:g}-cycle clearing")
    if not opt.any() and not uni.any():
        ax.text(
            0.5,
            0.5,
            f"no storage needed: all {d['plan']['n_contingencies']} contingencies are stable\n"
            f"without storage when cleared after {d['required_cycles']:g} cycles",
            ha="center",
            va="center",
            transform=ax.transAxes,
        )
        ax.set_axis_off()
        _save(fig, path)
        return
    ax.bar(
        x - 0.2,
        uni,
        0.4,
        color="0.7",
        label=f"least uniform, {u.get('pct') or 0:g} % ({uni.sum():.0f} MW)",
    )
    ax.bar(x + 0.2, opt, 0.4, label=f"optimised ({opt.sum():.0f} MW)", color="C3")
    ax.set_xticks(x, labels, fontsize=7)
    ax.set_xlabel("site (HV bus, generator)")
    ax.set_ylabel("ESD rating (MW)")
    ax.legend()
    _save(fig, path)


def figure_margins(d: dict, path: Path) -> None:
    """Verified clearing margin (CCT with the allocation minus the required clearing
    time, ms) of every contingency, per load level, sorted."""
    fig, ax = plt.subplots(figsize=(7, 4))
    for k, load in enumerate(d["load_levels"]):
        m = sorted(
            1000 * r["margin_s"]
            for r in d["plan"]["contingencies"]
            if r["load"] == load and r["margin_s"] is not None
        )
        ax.plot(np.arange(len(m)), m, ".-", ms=3, color=f"C{k}", label=f"load {load:g}")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("contingency (sorted by margin)")
    ax.set_ylabel("clearing margin (ms)")
    ax.set_title(f"{d['case']}: margin over the {d['required_cycles']:g}-cycle requirement")
    ax.legend(fontsize=8)
    _save(fig, path)


def _requirement(q: dict) -> tuple:
    """What a cost point was asked to meet besides its clearing time: its load levels and
    the contingencies set aside as infeasible (points differing in them do not compare)."""
    return tuple(q["load_levels"]), tuple(q.get("set_aside") or [])


def figure_pareto(d: dict, path: Path) -> None:
    """Cost against the required clearing time, optimised and least uniform; points are
    joined only when they meet the same load levels with the same contingencies (a point
    at more load levels, or with a contingency set aside, is another requirement)."""
    fig, ax = plt.subplots(figsize=(6.5, 4))
    groups: dict = {}
    for q in d["pareto"]:
        groups.setdefault(_requirement(q), []).append(q)
    for k, ((levels, aside), pts) in enumerate(groups.items()):
        what = "base load" if levels == (1.0,) else "loads " + ", ".join(f"{x:g}" for x in levels)
        what += f", {', '.join(aside)} set aside" if aside else ""
        ax.plot(
            [q["cycles"] for q in pts],
            [q["cost"] for q in pts],
            "os^Dv"[k % 5] + "-",
            color=f"C{3 + k}",
            mfc="none" if aside else None,
            label=f"optimised ({what})",
        )
        uni = [(q["cycles"], q["uniform_cost"]) for q in pts if q["uniform_cost"] is not None]
        if uni:
            ax.plot(*zip(*uni), "os^Dv"[k % 5] + "--", color="C0", label=f"least uniform ({what})")
    ax.set_xticks(sorted({q["cycles"] for q in d["pareto"]}))
    ax.set_xlabel("required clearing time (cycles)")
    ax.set_ylabel("cost (M$, illustrative prices)")
    costs = [c for q in d["pareto"] for c in (q["cost"], q["uniform_cost"]) if c is not None]
    if min(costs) > 0:  # the least uniform fleet costs tens of times the optimised one
        ax.set_yscale("log")
    ax.set_title(f"{d['case']}: cost against required clearing time")
    ax.legend(fontsize=7)
    _save(fig, path)


def report(d: dict, out_dir: Path, generated_by: str = "stabctl paper") -> Path:
    """Write placement_<case>.md, .json and the figures; returns the markdown path.
    generated_by: the command the report names as its source.  The files hold no
    run-dependent values (timings: `timing_line`)."""
    case = d["case"]
    figs = {k: f"placement_{case}_{k}.png" for k in ("allocation", "margins", "pareto")}
    figure_allocation(d, out_dir / figs["allocation"])
    figure_margins(d, out_dir / figs["margins"])
    figure_pareto(d, out_dir / figs["pareto"])
    (out_dir / f"placement_{case}.json").write_text(
        json.dumps(strip_run_dependent(d), indent=1, default=float), "utf-8"
    )
    path = out_dir / f"placement_{case}.md"
    path.write_text("\n".join(_markdown(d, figs, generated_by)) + "\n", "utf-8")
    return path


def _num(x, fmt: str) -> str:
    return "-" if x is None else format(x, fmt)


def _ms(x) -> str:
    return "-" if x is None else f"{1000 * x:.0f}"


def _markdown(d: dict, figs: dict, generated_by: str = "stabctl paper") -> list[str]:
    p, case, cyc = d["plan"], d["case"], d["required_cycles"]
    u = p["uniform"] or {}
    mva = {s["machine"]: s["mva"] for s in d["sites"]}
    c = p["cost"]
    ratio = (100 * p["total_mw"] / u["total_mw"]) if u.get("total_mw") else None
    loads = ", ".join(f"{x:g}" for x in d["load_levels"])
    lines = [
        f"# ESD sizing and placement: {case}",
        "",
        f"Generated by `{generated_by}` (method in docs/placement.md, section 7).  "
        "Every verdict below is simulated (PSTess models) with the paper's bang-bang "
        "law (100 mHz deadband, 0.8 pu gate, system COI).",
        "",
        f"**Requirement**: every screened fault stable when cleared after {cyc:g} "
        f"cycles ({1000 * cyc / 60:.1f} ms), at load levels {loads} (loads and "
        "dispatch scaled, power flow re-solved).  "
        f"**Result**: {p['total_mw']:.1f} MW and {p['total_mwh']:.2f} MWh at "
        f"{p['n_sites']} site(s), cost {c['total']:.1f} M$; "
        + (
            f"{ratio:.1f} % of the MW of the least uniform fleet meeting the same "
            f"requirement ({u['pct']:g} % of every MVA = {u['total_mw']:.0f} MW, cost "
            f"{u['cost']['total']:.1f} M$)"
            if ratio is not None
            else "no uniform fleet needed"
        )
        + "; "
        + ("verified on" if p["verified"] else "NOT verified on")
        + f" {p['n_met']} of {counted(p['n_contingencies'], 'contingency', 'contingencies')}"
        + (
            f", {len(p['set_aside'])} more set aside as infeasible ({', '.join(p['set_aside'])})"
            if p.get("set_aside")
            else ""
        )
        + f" ({p['message']}).",
        "",
        f"Costs (illustrative): {d['costs']['per_mw']:g} M$/MW, "
        f"{d['costs']['per_mwh']:g} M$/MWh, {d['costs']['per_site']:g} M$ per site.",
        "",
        "## Contingencies",
        "",
        _screening_text(d),
        "",
        "## Allocation",
        "",
        "| HV bus | generator | MW | % of its MVA | MWh | absorbed MWh | delivered MWh "
        "| energy set by |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for a in p["allocation"]:
        lines.append(
            f"| {a['bus']} | G{a['machine']} | {a['mw']:.1f} | "
            f"{100 * a['mw'] / mva[a['machine']]:.1f} | {a['mwh']:.2f} | "
            f"{a.get('absorbed_mj', 0) / MJ_PER_MWH:.3f} | "
            f"{a.get('delivered_mj', 0) / MJ_PER_MWH:.3f} | "
            f"{a.get('set_by', '-')} |"
        )
    lines += [
        "",
        "| | MW | MWh | sites | cost of MW (M$) | cost of MWh (M$) | cost of sites (M$) "
        "| total (M$) |",
        "|---|---|---|---|---|---|---|---|",
        f"| optimised | {p['total_mw']:.1f} | {p['total_mwh']:.2f} | {p['n_sites']} | "
        f"{c['mw']:.1f} | {c['mwh']:.2f} | {c['site']:.1f} | {c['total']:.1f} |",
    ]
    if u.get("total_mw") is not None:
        uc = u["cost"]
        lines.append(
            f"| least uniform ({u['pct']:g} %) | {u['total_mw']:.1f} | "
            f"{u['mwh']:.2f} | {len(d['sites']) if u['total_mw'] else 0} | {uc['mw']:.1f} | "
            f"{uc['mwh']:.2f} | {uc['site']:.1f} | {uc['total']:.1f} |"
        )
    lines += [
        "",
        "The energy of each device is twice the largest state-of-charge excursion "
        f"along the runs cleared at {cyc:g} cycles (a device started half full), plus 5 "
        "%; the runs that set it were simulated again with that finite energy."
        + (
            ""
            if u.get("max_energy_diff_mwh") is None
            else " For the least uniform fleet those runs"
            + _energy_sentence(u)
            + " (the optimised allocation's: see the half-step check)."
        ),
        "",
        f"![allocation]({figs['allocation']})",
        "",
        "## What drives it: each binding fault alone",
        "",
        "| fault | load levels solved | least MW alone | sites | verified |",
        "|---|---|---|---|---|",
    ]
    for a in p["alone"]:
        mw = "infeasible" if a["total_mw"] is None else f"{a['total_mw']:.1f}"
        where = ", ".join(f"G{x['machine']} {x['mw']:.0f}" for x in a.get("allocation", []))
        lines.append(
            f"| {a['fault']} | {', '.join(a.get('contingencies', []))} | {mw} | "
            f"{where} | {'yes' if a['verified'] else 'no'} |"
        )
    lines += [
        "",
        "## Constraint generation",
        "",
        "| round | solved for | MW | failing the check after it |",
        "|---|---|---|---|",
    ]
    for r in p["rounds"]:
        if r["total_mw"] is None:
            lines.append(
                f"| {r['round']} | {', '.join(r['active'])} | - | set aside as "
                f"infeasible: {', '.join(r.get('set_aside', []))} |"
            )
            continue
        lines.append(
            f"| {r['round']} | {', '.join(r['active'])} | {r['total_mw']:.1f} | "
            f"{', '.join(r['failing']) or 'none'} |"
        )
    lines += [
        "",
        "## Clearing margin of every contingency at every load level",
        "",
        "CCT with the allocation (ms; 1 ms for the contingencies solved for, "
        f"{1000 * MARGIN_TOL:g} ms for the others, shown up to "
        f"{1000 * MARGIN_CAP_S:g} ms: '>' = still stable there) minus the required "
        f"{cyc:g}-cycle clearing time; every contingency was also simulated cleared at "
        "the required time.",
        "",
        "| fault | CCT without storage, base load (ms) | "
        + " | ".join(f"margin at {x:g} (ms)" for x in d["load_levels"])
        + " |",
        "|---|---|" + "---|" * len(d["load_levels"]),
    ]
    by: dict = {}
    for r in p["contingencies"]:
        by.setdefault(r["fault_name"], {})[r["load"]] = r
    screen_cct = {
        r["name"]: _ms(r["cct_s"])
        if r["cct_s"] is not None
        else f">{1000 * SCREEN_T_MAX:g}"
        if "still stable" in (r["error"] or "")
        else "-"
        for r in d["screening"]
    }
    order = sorted(
        by,
        key=lambda f: min(
            (x["margin_s"] if x["margin_s"] is not None else 9.0) for x in by[f].values()
        ),
    )
    for f in order:
        cells = []
        for x in d["load_levels"]:
            r = by[f].get(x)
            if r is None:
                cells.append("-")
            elif r["margin_s"] is None:
                cells.append("stable" if r["met"] else "FAILS")
            else:
                cells.append(
                    (">" if r.get("margin_at_least") else "")
                    + f"{1000 * r['margin_s']:+.0f}"
                    + ("" if r["met"] else " FAILS")
                )
        lines.append(f"| {f} | {screen_cct.get(f, '-')} | " + " | ".join(cells) + " |")
    lines += ["", f"![margins]({figs['margins']})", ""] + _half_step_lines(p.get("half_step"))
    lines += [
        "## Cost against the required clearing time",
        "",
        (
            "The other points at the base load only and without their uniform "
            "reference (the fast variant that `stabctl paper` runs)."
            if d.get("pareto_load_levels") == [1.0]
            else "Every point at every load level."
        ),
        "",
        "| required (cycles) | load levels | optimised MW | MWh | sites | cost (M$) | "
        "least uniform % | uniform MW | uniform cost (M$) | verified | set aside as "
        "infeasible |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for q in d["pareto"]:
        lines.append(
            f"| {q['cycles']:g} | {', '.join(f'{x:g}' for x in q['load_levels'])} | "
            f"{q['total_mw']:.1f} | {q['total_mwh']:.2f} | {q['n_sites']} | "
            f"{q['cost']:.1f} | {_num(q['uniform_pct'], 'g')} | "
            f"{_num(q['uniform_mw'], '.0f')} | "
            f"{_num(q['uniform_cost'], '.1f')} | "
            f"{'yes' if q['verified'] else 'no'} | "
            f"{', '.join(q.get('set_aside') or []) or 'none'} |"
        )
    pa = d["paper_alone"]
    lines += [
        "",
        f"![Pareto]({figs['pareto']})",
        "",
        "## Continuity: the paper's fault with the uniform 5 % target",
        "",
        f"The paper's fault {pa['name']} alone, target the first unstable clearing "
        f"time of 5 % storage at every generator ({pa['uniform_mw']:.0f} MW): "
        f"{1000 * pa['target_s']:.0f} ms (without storage {1000 * pa['cct_none_s']:.0f}"
        f" ms).  Least allocation from that fleet: {pa['total_mw']:.1f} MW = "
        f"{100 * pa['total_mw'] / pa['uniform_mw']:.1f} % of it, verified CCT "
        f"{1000 * pa['cct_s']:.0f} ms ({'verified' if pa['verified'] else 'NOT verified'}"
        "; "
        + ", ".join(
            f"{a['mw']:.0f} MW at bus {a['bus']} (G{a['machine']})" for a in pa["allocation"]
        )
        + ").",
    ]
    return _empty_tables_said(lines, f"None: {p['message']}.")


def _empty_tables_said(lines: list[str], text: str) -> list[str]:
    """A markdown table with a header and no rows (Kundur needs no storage: nothing is
    installed, solved for or binding) replaced by `text`."""
    out: list[str] = []
    k = 0
    while k < len(lines):
        empty = _is_row(lines, k) and _is_row(lines, k + 1) and not _is_row(lines, k + 2)
        empty = empty and lines[k + 1].startswith("|---")
        out.append(text if empty else lines[k])
        k += 2 if empty else 1
    return out


def _is_row(lines: list[str], k: int) -> bool:
    return k < len(lines) and lines[k].startswith("|")


def timing_line(d: dict) -> str:
    """The study's run-dependent figures (for a run log, not the report): wall times of
    the main plan and the study, and the runs simulated."""
    p = d["plan"]
    return (
        f"{d['case']}: placement plan wall time {p['wall_time_s']:.0f} s, "
        f"{p['n_simulations']} runs (study {d['wall_time_s']:.0f} s)"
    )


def _energy_sentence(e: dict) -> str:
    """The energy's half-step figures (`stabctl.placement.energy.energy_half_step`) as the end of a
    sentence about the runs that set each site's energy."""
    pct = e["max_energy_diff_pct"]
    return (
        ", simulated again at half the step, change a site's energy need (twice its "
        f"largest state-of-charge excursion) by at most {e['max_energy_diff_mwh']:.3f} MWh"
        + ("" if pct is None else f" ({pct:.1f} % of it)")
        + "; the sized energies, "
        "margin and rounding included, "
        + ("cover" if e["energy_covered_half"] else "do **not** cover")
        + " the half-step needs"
    )


def _half_step_lines(hs) -> list[str]:
    """The half-step check of the tightest contingencies
    (`stabctl.placement.references.half_step`)."""
    if not hs:
        return []
    h = 1000 * hs["h_s"]
    out = [
        "## Half-step check",
        "",
        f"The {len(hs['rows'])} contingencies of least margin simulated again with the "
        f"allocation at half the step ({h / 2:.3g} ms instead of {h:.3g} ms): "
        + ("all stable" if hs["all_stable"] else "**not all stable**")
        + " when cleared at the required time; their CCTs differ from the full step's by "
        f"at most {1000 * hs['max_cct_diff_s']:.0f} ms beyond the resolution of each."
        + (
            ""
            if hs["max_energy_diff_mwh"] is None
            else " The runs that set each site's energy" + _energy_sentence(hs) + "."
        ),
        "",
        "| contingency | required (ms) | CCT, step h (ms) | CCT, step h/2 (ms) | "
        "stable at the required time, h/2 |",
        "|---|---|---|---|---|",
    ]
    for r in hs["rows"]:
        out.append(
            f"| {r['name']} | {1000 * r['required_s']:.0f} | "
            f"{1000 * r['cct_s']:.0f} (to {1000 * r['cct_tol_s']:g}) | "
            f"{1000 * r['cct_half_s']:.0f} | {'yes' if r['stable_half'] else 'NO'} |"
        )
    return out + [""]


def _contingency_count(d: dict) -> str:
    """'360, of which 16 out of scope and 1 set aside as infeasible: 343 verified'."""
    p = d["plan"]
    total = d["n_faults"] * len(d["load_levels"])
    parts = [
        f"{n} {what}"
        for n, what in (
            (len(p["out_of_scope"]), "out of scope"),
            (len(p.get("set_aside") or []), "set aside as infeasible"),
        )
        if n
    ]
    if not parts:
        return f"{total} in all"
    return f"{total}, of which {' and '.join(parts)} (below): {p['n_contingencies']} checked"


def _screening_text(d: dict) -> str:
    ok = [r for r in d["screening"] if r["cct_s"] is not None]
    n_bus = sum(1 for r in d["screening"] if "-" not in r["name"])
    n_line = len(d["screening"]) - n_bus
    scope = " at a generator HV bus" if n_line > 4 * N_FAULTS else ""
    buses = f" and {n_bus} bus faults cleared without a trip" if n_bus else ""
    p = d["plan"]
    return (
        f"Screened {n_line} line faults (each end of every line{scope}, line tripped)"
        f"{buses}; coarse CCT without storage, {1000 * SCREEN_TOL:g} ms, up to "
        f"{SCREEN_T_MAX:g} s: {len(ok)} with a CCT.  "
        + (
            f"Out of scope, islanding generators (their trip cuts them off the main grid, "
            f"lost whatever the clearing time: the island's frequency, not the ESD law's "
            f"question): {', '.join(d['islanding'])}.  "
            if d.get("islanding")
            else ""
        )
        + f"Every {'other ' if d.get('islanding') else ''}fault stable when cleared at "
        f"once ({d['n_faults']}) is a contingency at each of the "
        f"{len(d['load_levels'])} load levels: {_contingency_count(d)}.  "
        + (
            f"Out of scope, unstable without storage even when cleared at once (the "
            f"line trip alone) at that load level, which no clearing time can help "
            f"(N-1 insecure there): {', '.join(p['out_of_scope'])}.  "
            if p["out_of_scope"]
            else ""
        )
        + (
            "Set aside as infeasible with storage at the candidate sites (every site at "
            "its bound, simulated): " + "; ".join(p["infeasible"]) + ".  "
            if p.get("infeasible")
            else ""
        )
        + "Constraint generation: simulated once without storage cleared at the required "
        "time, the most binding failing contingencies (up to 12) are solved for; "
        "every contingency is then simulated with the allocation cleared at the "
        "required time, and those that fail are added."
    )


def placement_study(
    case_name: str,
    out_dir="reports",
    workers: int = 2,
    progress=None,
    records_dir=None,
    generated_by: str = "stabctl paper",
    fast: bool = True,
) -> Path:
    """Run the study for one case (kundur or miniwecc: the paper's fault must be in
    `stabctl.studies.cases.DEFAULT_FAULTS`) and write its report into out_dir; returns the
    markdown path.  workers: processes; progress: callable(str) (default: this module's
    logger, level INFO, `stabctl.progress`);
    records_dir: where the resumable screening records go (default out_dir);
    generated_by: the command the report names as its source; fast: the Pareto points at
    the base load only (`study`).  Raises as `stabctl.placement.plan.plan`
    (InfeasibleError, InputError, SimulationError)."""
    out = Path(out_dir)
    records = Path(records_dir or out)
    for folder in (out, records):
        folder.mkdir(parents=True, exist_ok=True)
    say = progress or logger.info
    d = study(case_name, records, workers, say, fast)
    say(timing_line(d))
    return report(d, out, generated_by)
