"""`stabctl paper`, multi-machine part: the paper's Cases 1 and 2 and Table 4 (Section 5).

Case 1: Kundur two-area (PSTess d2asbegp), three-phase fault at PST bus 3 on line 3-101 at
1 s, line tripped.  Case 2: miniWECC, 6-cycle fault at bus 83, line 83-33 tripped.  ESDs of a
percentage of each machine's MVA at every generator HV bus, bang-bang COI control (Table 3).
Table 4: CCT versus ESD rating, run as a resumable sweep (`stabctl.parallel`) whose records
stay in `<report dir>/table4_<case>.jsonl`.  The same with WECC batteries beside ideal
devices (`section_wecc`, records `wecc_<case>.jsonl`).
"""

from __future__ import annotations

import itertools
import logging
from pathlib import Path

import numpy as np

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.io import load_case
from stabctl.parallel import default_workers, run_sweep, worker_pool
from stabctl.plotting import figures as plotting
from stabctl.stability.cct import SearchOptions, cached_simulator, cct_jobs, critical_clearing_time
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import uniform_fleet
from stabctl.studies.cases import CASE1, CASE2, PaperCase
from stabctl.studies.scorecard import claim
from stabctl.studies.sweeps import controlled_cct_jobs

logger = logging.getLogger(__name__)

RATINGS_PCT = (5, 10, 15, 20, 25, 30)
#: Paper Table 4 (Case 2, miniWECC): CCT increase (%) over no storage per ESD rating (% of
#: generator power), as printed: 0, 5, 15, 20, 25, 30 % -> 0, 20, 40, 60, 60, 60 % (the
#: paper gives no 10 % row; its text: "5% ... increased by 20%", the maximum reached at 20 %).
PAPER_TABLE4 = {0: 0, 5: 20, 15: 40, 20: 60, 25: 60, 30: 60}
CASES = {"case1": (CASE1.case, CASE1.fault), "case2": (CASE2.case, CASE2.fault)}
#: the points of CCT gain within which a gain of ours and the paper's agree: its CCTs are
#: whole cycles of about 5 (one cycle 20 points)
TABLE4_AGREES_PCT = 10


def _run_pair(pc: PaperCase, cycles, pct, conventions="ieee", halve=False):
    """The paper case's fault cleared after `cycles`, without and with pct % ESDs at the
    default step (at half of it with halve), and the case."""
    case = load_case(pc.case)
    sim = Simulator(case, conventions=conventions)
    h = sim.default_h / 2 if halve else None
    fault = [fault_with_clearing(case, pc.bus, pc.far_bus, pc.fault.t_fault, cycles)]
    return (
        sim.run(fault, t_end=pc.t_end, h=h),
        sim.run(fault, t_end=pc.t_end, h=h, storage=uniform_fleet(case, pct)),
        case,
    )


def _halved(pair, *args, **kw) -> str:
    """'same' when both verdicts of `pair` (without, with) hold at half the step, else
    what changes: the step-convergence check of a verdict."""
    half = _run_pair(*args, halve=True, **kw)[:2]  # type: ignore[misc]
    diff = [
        f"{what} {'stable' if h.stable else 'unstable'}"
        for what, p, h in zip(("without", "with"), pair, half)
        if p.stable != h.stable
    ]
    return "same" if not diff else ", ".join(diff)


def _verdict(case, res) -> str:
    names = ", ".join(case.machine_name(m) for m in res.separated)
    return (
        "stable"
        if res.stable
        else f"loses synchronism at {res.t_separation:.2f} s (machine(s) {names})"
    )


def _device_table(res, only_active=True) -> list[str]:
    rows = [
        "| device | bus | machine | rating MW | switchings | absorbed MJ | delivered MJ "
        "| peak MW used |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for d in res.meta["storage"]:
        if only_active and d["switchings"] == 0:
            continue
        rows.append(
            f"| {d['device']} | {d['bus']} | {d['machine']} | {d['pmax_mw']:.0f} | "
            f"{d['switchings']} | {d['energy_absorbed_mj']:.1f} | "
            f"{d['energy_delivered_mj']:.1f} | {d['peak_power_mw']:.1f} |"
        )
    return rows


def section_case1(fig_dir: Path) -> str:
    """Case 1 (Kundur): speeds without and with control, ESD powers (paper Figs. 14-15)."""
    lines = [
        "## 4. Case 1: Kundur two-area system (paper Figs. 14-15)",
        "",
        "Three-phase fault at PST bus 3 (Kundur bus 7) on line 3-101 (Kundur 7-8) at "
        "t = 1 s, line tripped at clearing; ESDs at the generator HV buses 10, 20, 110, "
        "120; bang-bang COI control, 100 mHz deadband, 0.8 pu voltage gate; ieee "
        "conventions (IEEE 421.5 limiters, 5 ms step) unless marked pstess (PSTess 1.1 "
        "exactly, its 10 ms step).",
        "",
        "| conventions | clearing | ESD rating | without control | with control | "
        "verdicts at half the step |",
        "|---|---|---|---|---|---|",
    ]
    runs = {}
    paper, fig = CASE1.cycles["paper"], CASE1.cycles["figure"]
    for conv, cycles, pct in (
        ("ieee", paper, 5),
        ("ieee", paper, 30),
        ("ieee", fig, 5),
        ("pstess", paper, 5),
        ("pstess", paper, 20),
        ("pstess", 17, 5),
    ):
        without, with_, case = _run_pair(CASE1, cycles, pct, conv)
        runs[(conv, cycles, pct)] = (without, with_)
        half = _halved((without, with_), CASE1, cycles, pct, conv)
        lines.append(
            f"| {conv} | {cycles} cycles | {pct} % | {_verdict(case, without)} | "
            f"{_verdict(case, with_)} | {half} |"
        )
    without, with_ = runs[("ieee", fig, 5)]
    plotting.storage_case_figure(
        without,
        with_,
        fig_dir / "fig14_15_case1.png",
        "Case 1, Kundur, 11-cycle fault, 5 % ESDs (ieee conventions)",
        case=case,
    )
    lines += [
        "",
        "The paper's 21-cycle fault is far beyond this model's critical clearing "
        "time. With IEEE 421.5 limiters the no-storage CCT is 9.2 cycles (154 ms at the "
        "5 ms default step and converged; section 9) and 5 % ESDs raise it to 11.9 "
        "cycles; even 30 % ESDs clear only 20.5 cycles. PSTess 1.1's own model gives 16.1 "
        "and 18.2 cycles at its 10 ms step, but that is its smpexc limiter: the field "
        "voltage's derivative is never zeroed at the ceiling and the machine sees Efd_max "
        "+ h dEfd/dt, several pu above the 5 pu ceiling with K_A = 200, so the field "
        "forcing (and the CCT) grows with the step and shrinks towards ours as the step "
        "is reduced (section 9). The paper, run on PST with a 10 ms step, most likely "
        "carries the same inflation, which with its dispatch can put 21 cycles within "
        "reach of 5 %. The qualitative result is reproduced at 11 cycles: area 1 "
        "separates without control and every machine stays in step with it; as in the "
        "paper, C1 and C2 (area 1) absorb and C3 and C4 inject after clearing:",
        "",
    ]
    lines += _device_table(with_, only_active=False)
    lines += ["", "![Case 1](fig14_15_case1.png)", ""]
    lines += _case1_claims(runs, case, paper, fig)
    return "\n".join(lines)


def _case1_claims(runs: dict, case, paper: float, fig: float) -> list[str]:
    """The scorecard's rows of Case 1: the paper's 21-cycle fault stabilised by 5 % ESDs
    (Fig. 14), and which devices absorb and which inject after clearing (Fig. 15), from
    the runs of section 4."""
    at_paper = {conv: runs[(conv, paper, 5)] for conv in ("ieee", "pstess")}
    without, with_ = runs[("ieee", fig, 5)]
    t_clear = CASE1.fault.t_fault + fig / case.freq_hz
    first = first_actions(with_, t_clear)
    signs = {d: ("absorbs" if s > 0 else "injects") for d, s in first.items()}
    return [
        claim(
            "4",
            f"Fig. 14: the {paper:g}-cycle fault on line 7-8 loses synchronism without "
            "control and is stable with 5 % ESDs",
            "; ".join(
                f"{conv}: {'stable' if w.stable else 'unstable'} with 5 %"
                for conv, (_, w) in at_paper.items()
            )
            + f"; at {fig:g} cycles (ieee): "
            + f"{'stable' if with_.stable else 'unstable'} with 5 %, "
            + f"{'stable' if without.stable else 'unstable'} without",
            at_paper["ieee"][1].stable and not at_paper["ieee"][0].stable,
            f"{paper:g} cycles is beyond 5 % here (Table 4's CCTs, section 6); the result is "
            f"reproduced at {fig:g} cycles",
        ),
        claim(
            "4",
            "Fig. 15: after clearing C1 and C2 absorb, C3 and C4 inject",
            ", ".join(f"C{d} {s}" for d, s in signs.items()) + f" first ({fig:g} cycles)",
            [signs.get(d) for d in (1, 2, 3, 4)] == ["absorbs"] * 2 + ["injects"] * 2,
        ),
    ]


def first_actions(res, t_from: float) -> dict[int, float]:
    """The sign of each storage device's first power after `t_from` (s): +1 absorbing,
    -1 injecting; a device that never acts is left out.

    Parameters
    ----------
    res : SimulationResult
        A run with storage (``pesd``, (n_t, n_dev), + absorbs; ``devices``, the device
        numbers).
    t_from : float
        The time from which to look, s (a fault's clearing).

    Returns
    -------
    dict
        Device number -> +1.0 or -1.0.
    """
    after = res.t > t_from
    out = {}
    for k, d in enumerate(res.devices):
        p = res.pesd[after, k]
        acting = np.flatnonzero(p != 0)
        if acting.size:
            out[int(d)] = float(np.sign(p[acting[0]]))
    return out


def section_case2(fig_dir: Path) -> str:
    """Case 2 (miniWECC): the Colstrip unit without and with 5 % ESDs (Figs. 17-19)."""
    without, with_, case = _run_pair(CASE2, CASE2.cycles["figure"], 5)
    plotting.storage_case_figure(
        without,
        with_,
        fig_dir / "fig17_19_case2.png",
        "Case 2, miniWECC, 6-cycle fault at bus 83, 5 % ESDs "
        "(thick: machines 13 and 14, named by the paper)",
        case=case,
        highlight=(13, 14),
    )
    lines = [
        "## 5. Case 2: miniWECC (paper Figs. 17-19)",
        "",
        "6-cycle three-phase fault at bus 83 at t = 1 s, line 83-33 tripped; an ESD of 5 % "
        "of machine MVA at each of the 34 generator HV buses.",
        "",
        f"- without control: {_verdict(case, without)}",
        f"- with control: {_verdict(case, with_)}",
        "- verdicts at half the step: "
        + _halved((without, with_), CASE2, CASE2.cycles["figure"], 5),
        "",
        "Only machine 14 (Colstrip, bus 32) separates without control, as in PSTess; the "
        "paper names machines 13 and 14. Devices that switched (the others stay inside "
        "the deadband):",
        "",
    ]
    lines += _device_table(with_)
    lines += ["", "![Case 2](fig17_19_case2.png)", ""]
    names = ", ".join(case.machine_name(m) for m in without.separated) or "none"
    lines.append(
        claim(
            "5",
            f"Figs. 17-19: the {CASE2.cycles['figure']:g}-cycle fault at bus 83 loses "
            "synchronism without control (machines 13 and 14) and is stable with 5 % ESDs",
            f"without: {'stable' if without.stable else f'unstable ({names} separating)'}; "
            f"with 5 %: {'stable' if with_.stable else 'unstable'}",
            with_.stable and not without.stable,
            "machine 14 alone separates here, as in PSTess; the paper names 13 and 14",
        )
    )
    return "\n".join(lines)


def table4(case_key: str, out_dir: Path, progress: bool = True) -> dict:
    """CCT of a case's fault at every rating (None = no storage), as a resumable sweep whose
    records are kept in out_dir/table4_<case>.jsonl.  Returns {rating: CCT result dict}."""
    name, fault = CASES[case_key]
    ratings = (None,) + RATINGS_PCT
    jobs = cct_jobs(name, [fault], ratings)
    return _sweep_results(jobs, ratings, out_dir / f"table4_{name}.jsonl", "Table 4", progress)


def _sweep_results(jobs, keys, path: Path, what: str, progress: bool) -> dict:
    """Run the resumable sweep of `jobs` with its records in `path` and return {key: CCT
    result dict}, keys in job order; RuntimeError naming `what` and the job if one
    failed."""
    report = run_sweep(jobs, path, progress=progress)
    out = {}
    for job, key in zip(report.records.values(), keys):
        if job["status"] != "ok":
            raise RuntimeError(f"{what} job {job['key']}: {job.get('error') or job.get('reason')}")
        out[key] = job["result"]
    return out


def section_table4(fig_dir: Path, out_dir: Path, progress=None) -> str:
    """Table 4: CCT versus ESD rating for Cases 1 and 2, with energy and peak power used.

    The sweep records go to out_dir; progress(str) hears when a case is done (None: this
    module's logger, `stabctl.progress`)."""
    say = progress or logger.info
    lines = [
        "## 6. Table 4: CCT versus ESD rating",
        "",
        "Bisection on the clearing time to 1 ms (`stabctl.stability.cct`, ieee conventions, "
        "each "
        "CCT's numerical error from rerunning its bracket at half the step in the `err` "
        "column), stability = no rotor angle leaves the COI by more than pi within 5 s "
        "of the fault. The paper's Table 4 (miniWECC): ESD power 0 / 5 / 15 / 20 / 25 / "
        "30 % of generator power gives a CCT increase of 0 / 20 / 40 / 60 / 60 / 60 %. "
        "The energy and peak power columns are from a run of the case's fault (Case 1: 11 "
        "cycles, Case 2: 6 cycles) at that rating (what the paper does not give); in "
        "brackets, how much each moves when that run is repeated at half the step. "
        "Those runs switch their devices many times about the deadband, so rounding "
        "moves them too: built with other numpy and scipy releases, or with the "
        "simulator's arithmetic changed in its last bits (magnitudes as square roots of "
        "sums of squares instead of hypot), the miniWECC energies moved by up to 3 MJ "
        "(4 % of the smallest), the CCTs not at all.",
        "",
    ]
    results = {}
    for key, cycles in (("case2", CASE2.cycles["figure"]), ("case1", CASE1.cycles["figure"])):
        name, fault = CASES[key]
        res = results[key] = table4(key, out_dir)
        say(f"Table 4, {name}: {len(res)} CCT searches done; energy runs follow")
        base = res[None]["cct_s"]
        lines += [
            f"### {key.replace('case', 'Case ')}: {name}, {fault.describe()}",
            "",
            "| ESD % of MVA | CCT s | err ms | CCT cycles | increase % | paper % | sims | "
            "absorbed MJ (all) | delivered MJ (all) | peak MW used (max device) |",
            "|---|---|---|---|---|---|---|---|---|---|",
            f"| 0 | {base:.3f} | {_err_ms(res[None])} | {res[None]['cct_cycles']:.1f} | 0 "
            f"| {'0' if key == 'case2' else '-'} | {res[None]['n_simulations']} | | | |",
        ]
        case = load_case(name)
        sim = Simulator(case)
        ev = [fault_with_clearing(case, fault.bus, fault.far_bus, 1.0, cycles)]
        for pct in RATINGS_PCT:
            r = res[pct]
            full, half = (
                _storage_figures(sim.run(ev, t_end=8.0, h=h, storage=uniform_fleet(case, pct)))
                for h in (sim.default_h, sim.default_h / 2)
            )
            paper = PAPER_TABLE4.get(pct, "-") if key == "case2" else "-"
            lines.append(
                f"| {pct} | {r['cct_s']:.3f} | {_err_ms(r)} | {r['cct_cycles']:.1f} | "
                f"{100 * (r['cct_s'] / base - 1):.0f} | {paper} | {r['n_simulations']} | "
                + " | ".join(f"{a:.0f} ({abs(a - b):.1f})" for a, b in zip(full, half))
                + " |"
            )
        lines.append("")
    plotting.cct_versus_rating(
        results,
        RATINGS_PCT,
        fig_dir / "table4_cct_vs_rating.png",
        paper_row=PAPER_TABLE4,
        paper_label="paper Table 4 (Case 2)",
    )
    say(
        f"Table 4, {CASES['case2'][0]}: ratings {', '.join(map(str, NO_GATE_PCT))} % "
        "rerun without the 0.8 pu voltage gate"
    )
    lines += _table4_hypotheses(results["case2"])
    lines.append(_table4_claim(results["case2"]))
    lines += [
        "",
        "The figure shows the paper's row beside ours.",
        "",
        "![CCT versus rating](table4_cct_vs_rating.png)",
        "",
    ]
    return "\n".join(lines)


def _table4_claim(res: dict) -> str:
    """The scorecard's row of Table 4 (miniWECC): the CCT gains at the paper's ratings
    against its row, agreeing within TABLE4_AGREES_PCT points each."""
    base = res[None]["cct_s"]
    ours = {p: 100 * (res[p]["cct_s"] / base - 1) for p in RATINGS_PCT if p in PAPER_TABLE4}
    worst = max(abs(g - PAPER_TABLE4[p]) for p, g in ours.items())
    return claim(
        "6",
        "Table 4 (miniWECC): CCT gain "
        + " / ".join(f"{PAPER_TABLE4[p]}" for p in ours)
        + " % at "
        + " / ".join(f"{p}" for p in ours)
        + " % ESDs, flat from 20 %",
        " / ".join(f"{g:.0f}" for g in ours.values()) + " %",
        worst <= TABLE4_AGREES_PCT,
        "larger gains, still rising at 30 %; the hypotheses tested are in section 6",
    )


def wecc_table(case_key: str, out_dir: Path, progress: bool = True) -> dict:
    """CCT of a case's fault at every rating with ideal devices and with WECC batteries
    (`stabctl.storage.devices.battery_case`), one resumable sweep whose records are kept
    in out_dir/wecc_<case>.jsonl.  Returns {(model, rating): CCT
    result dict}, rating None (no storage) under "ideal" only."""
    name, fault = CASES[case_key]
    ratings = (None,) + RATINGS_PCT
    jobs = [
        *controlled_cct_jobs(name, [fault], ratings, BangBangCOI()),
        *controlled_cct_jobs(name, [fault], RATINGS_PCT, BangBangCOI(), esd_model="wecc"),
    ]
    keys = [("ideal", pct) for pct in ratings] + [("wecc", pct) for pct in RATINGS_PCT]
    return _sweep_results(jobs, keys, out_dir / f"wecc_{name}.jsonl", "WECC battery", progress)


def section_wecc(fig_dir: Path, out_dir: Path, progress=None) -> str:
    """Case 2 and Table 4 with WECC batteries beside the ideal devices: the verdicts of
    the Case 2 fault and the CCT gain per rating for both cases.

    The sweep records go to out_dir; progress(str) hears when a case is done (None: this
    module's logger, `stabctl.progress`)."""
    say = progress or logger.info
    lines = [
        "## 6b. Storage as a WECC battery",
        "",
        "Each ESD as a WECC battery instead of an ideal power source (`--esd-model wecc`, "
        "docs/storage.md): a REGCA1 converter (lag 20 ms) with a REECA1 in the storage "
        "current range (apparent current limit 1 pu of its rating, active-current "
        "priority, frozen below 0.8 pu) and a REPCA1 plant that takes the bang-bang "
        "law's power as its reference, through four 20 ms lags. Same law, deadband and "
        "0.8 pu gate; ieee conventions, default step; each CCT's numerical error from "
        "its bracket rerun at half the step in `err`.",
        "",
    ]
    cycles = CASE2.cycles["figure"]
    without, ideal, case = _run_pair(CASE2, cycles, 5)
    sim = Simulator(case)
    fault = [fault_with_clearing(case, CASE2.bus, CASE2.far_bus, CASE2.fault.t_fault, cycles)]
    wecc = [
        sim.run(fault, t_end=CASE2.t_end, h=h, storage=uniform_fleet(case, 5, model="wecc"))
        for h in (sim.default_h, sim.default_h / 2)
    ]
    lines += [
        f"Case 2, {cycles} cycles, 5 %: without storage {_verdict(case, without)}; ideal ESDs "
        f"{_verdict(case, ideal)}; WECC batteries {_verdict(case, wecc[0])} (at half the step: "
        f"{_verdict(case, wecc[1])}).",
        "",
    ]
    for key in ("case2", "case1"):
        name, fault_ = CASES[key]
        res = wecc_table(key, out_dir)
        say(f"WECC batteries, {name}: {len(res)} CCT searches done")
        base = res[("ideal", None)]["cct_s"]
        lines += [
            f"### {key.replace('case', 'Case ')}: {name}, {fault_.describe()}",
            "",
            f"No storage: CCT {base:.3f} s (err {_err_ms(res[('ideal', None)])} ms).",
            "",
            "| ESD % of MVA | ideal CCT s | err ms | increase % | WECC CCT s | err ms | "
            "increase % |",
            "|---|---|---|---|---|---|---|",
        ]
        for pct in RATINGS_PCT:
            a, b = res[("ideal", pct)], res[("wecc", pct)]
            lines.append(
                f"| {pct} | {a['cct_s']:.3f} | {_err_ms(a)} | "
                f"{100 * (a['cct_s'] / base - 1):.0f} | {b['cct_s']:.3f} | {_err_ms(b)} | "
                f"{100 * (b['cct_s'] / base - 1):.0f} |"
            )
        top = RATINGS_PCT[-1]
        gain = [res[(m, top)]["cct_s"] - base for m in ("ideal", "wecc")]
        lines += [
            "",
            f"At {top} % the batteries' CCT gain is {100 * gain[1] / gain[0]:.0f} % of the "
            "ideal devices'. Two things separate them: the current limit (P <= v Imax) "
            "and the low-voltage power logic cut the batteries' power while voltages are "
            "depressed, and the batteries inject reactive current in a dip (REECA1's "
            "Kqv) and control their voltage (REPCA1), which the ideal devices do not.",
            "",
        ]
    return "\n".join(lines)


def _storage_figures(run) -> tuple[float, float, float]:
    """Energy absorbed and delivered by all devices (MJ) and the largest peak power of one
    device (MW) in a run with storage."""
    st = run.meta["storage"]
    return (
        sum(d["energy_absorbed_mj"] for d in st),
        sum(d["energy_delivered_mj"] for d in st),
        max(d["peak_power_mw"] for d in st),
    )


def _err_ms(r: dict) -> str:
    e = r.get("numerical_error_s")
    return "-" if e is None else f"{1000 * e:g}"


#: Case-2 ratings (%) whose CCT the Table 4 hypotheses rerun without the voltage gate
NO_GATE_PCT = (5, 15, 20, 30)


def no_gate_cct(job: dict) -> float:
    """CCT (s) of the Case-2 fault with uniform ESDs of job["pct"] % and no 0.8 pu
    voltage gate (worker entry of `stabctl.parallel.worker_pool`; bisection to 1 ms)."""
    name, fault = CASES["case2"]
    pct = job["pct"]
    sim = cached_simulator(name)
    return critical_clearing_time(
        sim,
        fault,
        SearchOptions(error_check=False),
        storage=uniform_fleet(sim.case, pct, BangBangCOI(v_gate_pu=0.0)),
    ).cct_s


def _table4_hypotheses(res: dict) -> list[str]:
    """Why the miniWECC gains differ from the paper's Table 4, tested with runs: the CCT
    counted in whole cycles, and the 0.8 pu voltage gate (ratings rerun without it)."""
    _name, _fault = CASES["case2"]
    base_cyc = int(res[None]["cct_cycles"])
    whole = {p: 100 * (int(res[p]["cct_cycles"]) / base_cyc - 1) for p in RATINGS_PCT}
    with worker_pool(min(default_workers(), len(NO_GATE_PCT))) as run:
        no_gate = dict(zip(NO_GATE_PCT, run(no_gate_cct, [{"pct": p} for p in NO_GATE_PCT])))
    base = res[None]["cct_s"]
    lines = [
        "Why our miniWECC gains differ from the paper's row, hypotheses tested with runs:",
        "",
        "| ESD % | paper % | ours % (1 ms) | ours in whole cycles % | ours without the "
        "0.8 pu voltage gate % |",
        "|---|---|---|---|---|",
    ]
    for p in RATINGS_PCT:
        ng = f"{100 * (no_gate[p] / base - 1):.0f}" if p in no_gate else "-"
        lines.append(
            f"| {p} | {PAPER_TABLE4.get(p, '-')} | "
            f"{100 * (res[p]['cct_s'] / base - 1):.0f} | {whole[p]:.0f} | {ng} |"
        )
    common = [p for p in RATINGS_PCT if p in PAPER_TABLE4]
    larger = all(whole[p] > PAPER_TABLE4[p] for p in common)
    gains = [res[p]["cct_s"] for p in RATINGS_PCT]
    rising = all(b > a for a, b in itertools.pairwise(gains))
    no_gate_ccts = [no_gate[p] for p in sorted(no_gate)]
    gate_caps = not all(b > a for a, b in itertools.pairwise(no_gate_ccts))
    lines += [
        "",
        f"- Whole cycles: our base CCT is {res[None]['cct_cycles']:.2f} cycles "
        f"({base_cyc} whole cycles). The paper's 20 / 40 / 60 % are exactly 5 -> 6 -> 7 "
        "-> 8 cycles on a 5-cycle base; counted that way ours give the fourth column: "
        + (
            "coarse counting alone does not produce the paper's row, our gains are "
            "larger at every rating."
            if larger
            else "coarse counting brings them close to the paper's at some ratings."
        ),
        f"- Voltage gate: without it the 30 % gain is {100 * (no_gate[30] / base - 1):.0f} % "
        f"instead of {100 * (res[30]['cct_s'] / base - 1):.0f} %: the 0.8 pu gate idles the "
        "devices near the fault through the longer faults and makes the returns "
        "diminish; "
        + (
            "but with or without it our CCT keeps rising up to 30 %, so it does not "
            "produce the paper's flat 60 % either."
            if not gate_caps and rising
            else "it is part of the saturation."
        ),
        "- What the runs support: "
        + (
            "the paper's saturation at 60 % and its smaller gains come from what we "
            "cannot reproduce (its dispatch, PST version, exciter data or ESD network "
            "model, none given in the paper); in our model every added percent still "
            "buys clearing time at 30 %."
            if rising
            else "our gains saturate too, at the rating where the CCT stops growing."
        ),
    ]
    return lines
