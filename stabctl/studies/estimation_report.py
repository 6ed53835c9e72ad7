"""Estimation report: estimation accuracy, false ESD actions and CCT with the estimator in
the loop, for Kundur Case 1 (fault at bus 3, line 3-101) and miniWECC Case 2 (bus 83, line
83-33).  `write_estimation_report(out_dir)` writes reports/estimation_<case>.md.

Sources: RMSE during the post-fault swing, `stabctl.studies.estimate.estimator_errors`, the
code of `stabctl estimate rmse` (PMU noise seeds 0.., C37.118.1 limits as 3 sigma,
60 frames/s, 50 ms latency); false actions,
`stabctl.studies.estimation.false_actions` on 60 s without fault with ambient load fluctuation
(`stabctl.estimation.ambient`, AMBIENT: standard deviation 1 % of each load, correlation time 2 s,
seeds 0..AMBIENT_RUNS-1); CCT, `closed_loop.cct_study` (estimators in the loop, ESDs of 5 %
and 20 % of each generator's MVA; noise seeds per row by `closed_loop.SeedRule`).
"""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path

import numpy as np

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import InputError
from stabctl.estimation import ambient as am
from stabctl.estimation import closed_loop as cl
from stabctl.estimation.settings import PMUSettings
from stabctl.io import load_case
from stabctl.parallel import RunnerOptions
from stabctl.stability.cct import LineFault
from stabctl.storage.control import BangBangCOI
from stabctl.studies import estimation as study
from stabctl.studies.cases import PAPER_CASES
from stabctl.studies.estimate import ErrorRuns, estimator_errors

logger = logging.getLogger(__name__)

#: the paper's cases by case name; the RMSE runs clear after pc.cycles["estimation"]:
#: faults well inside the CCT under the ieee conventions (Kundur 9.4 cycles, miniWECC 4.6)
CASES = PAPER_CASES
RATINGS = (5.0, 20.0)
AMBIENT, AMBIENT_RUNS, AMBIENT_S = am.AmbientLoad(pct=1.0, tau_s=2.0), 5, 60.0
#: the RMSE runs: the fault run's end (s), which ends the error window, and the time from
#: the clearing to its start (s)
RMSE_T_END_S, RMSE_SETTLE_S = 10.0, 0.1


def case_figures(
    name: str, runs: int, cct_runs, records_dir: Path, workers=None, progress=None
) -> dict:
    """RMSE, false actions and CCT table of one case (see the module docstring); cct_runs:
    noise seeds per CCT row, a count or a `closed_loop.SeedRule`; the CCT sweep's resumable
    records go to records_dir; progress: callable(str) told each stage and each ambient run
    (None: this module's logger, `stabctl.progress`; the CCT sweep has its own bar)."""
    say = progress or logger.info
    pc = CASES[name]
    bus, far, cycles = pc.bus, pc.far_bus, pc.cycles["estimation"]
    case = load_case(name)
    ev = fault_with_clearing(case, bus, far, pc.fault.t_fault, cycles)
    say(f"estimation {name}: RMSE, {runs} PMU noise runs")
    rmse = rmse_figures(case, ev, runs)
    false = ambient_figures(
        case,
        progress=lambda r: say(
            f"estimation {name}: ambient load run {r + 1}/{AMBIENT_RUNS} ({AMBIENT_S:g} s)"
        ),
    )
    say(f"estimation {name}: CCT with the estimators in the loop, {_seeds_text(cct_runs)}")
    cct = cl.cct_study(
        name,
        LineFault(bus, far),
        RATINGS,
        cct_runs,
        records_dir / f"estimation_cct_{name}.jsonl",
        runner=RunnerOptions(workers),
    )
    return {
        "rmse": rmse,
        "false": false,
        "cct": cct,
        "cycles": cycles,
        "bus": bus,
        "far": far,
        "runs": runs,
        "cct_runs": cct_runs,
    }


def rmse_figures(case, event, runs: int) -> dict:
    """The RMSE table's figures per estimator: `stabctl estimate rmse`'s own code
    (`stabctl.studies.estimate.estimator_errors`, default PMUs, noise seeds 0..runs-1, no
    storage) on `event` run to RMSE_T_END_S, errors from RMSE_SETTLE_S after the clearing;
    `rmse_command` gives the command line that prints them."""
    mc = ErrorRuns(
        runs=runs,
        seed=0,
        pmu_at="terminal",
        coi="system",
        control=BangBangCOI(),
        ambient=AMBIENT,
        ambient_s=0.0,
        ambient_runs=1,
    )
    d = estimator_errors(
        case,
        event,
        mc,
        settings=PMUSettings(),
        esd_pct=None,
        settle_s=RMSE_SETTLE_S,
        t_end=RMSE_T_END_S,
    )
    return d["estimators"]


def rmse_command(name: str, fig: dict) -> str:
    """The `stabctl estimate rmse` command line printing the RMSE table of a case."""
    return (
        f"stabctl estimate rmse {name} --fault {fig['bus']} --far-bus {fig['far']} "
        f"--clear-cycles {fig['cycles']:g} --tf {RMSE_T_END_S:g} "
        f"--settle-ms {1000 * RMSE_SETTLE_S:g} --runs {fig['runs']} --ambient-s 0"
    )


def ambient_figures(
    case, h: float | None = None, runs: int = AMBIENT_RUNS, t_end: float = AMBIENT_S, progress=None
) -> dict:
    """The false-actions figures (`stabctl.studies.estimation.false_actions`, default PMUs,
    noise seeds 0..runs-1) of `runs` runs of t_end s without fault with the AMBIENT load
    fluctuation (load seeds 0..runs-1), integrated with step h (s; None: the case's
    default).
    progress: callable(r) told before run r.  Raises as `ambient.simulate`."""
    sim = Simulator(case, step=h)
    flat = []
    for r in range(runs):
        if progress:
            progress(r)
        flat.append(am.simulate(sim, t_end, replace(AMBIENT, seed=r)))
    return study.false_actions(case, flat, PMUSettings(), 0)


def _seeds_text(cct_runs) -> str:
    """The noise seeds of the CCT rows, in words."""
    if not isinstance(cct_runs, cl.SeedRule):
        return f"{cct_runs} noise seeds"
    r = cct_runs
    return (
        f"noise seeds in batches of {r.batch} until the {100 * r.confidence:g} % interval "
        f"of the mean CCT is within +-{r.half_width_cycles:g} cycle (at most {r.max_runs})"
    )


def markdown(name: str, fig: dict, generated_by: str = "stabctl paper") -> str:
    """The report text of one case; generated_by: the command named as its source."""
    lines = [
        f"# Speed estimation and ESD control in the loop: {name}",
        "",
        f"Fault at bus {fig['bus']}, line {fig['bus']}-{fig['far']} (generated by "
        f"`{generated_by}`). PMUs at the generator terminals, C37.118.1 "
        "limits as 3 sigma, 60 frames/s, 50 ms latency.",
        "",
        f"## Speed RMSE during the post-fault swing ({fig['cycles']:g}-cycle fault, no "
        f"storage, {fig['runs']} runs; mHz, mean +- std)",
        "",
        f"Errors at the frame time stamps from {1000 * RMSE_SETTLE_S:g} ms after the "
        f"clearing to {RMSE_T_END_S:g} s; `{rmse_command(name, fig)}` prints this table "
        "(its default --tf ends 5 s after the fault start, a shorter window of larger "
        "swings).",
        "",
        "| estimator | speed | COI | relative | relative, forecast to arrival |",
        "|---|---|---|---|---|",
    ]
    for e, m in fig["rmse"].items():

        def cell(k, m=m):
            std = m[k]["std"]
            return f"{m[k]['mean']:.2f}" + ("" if std is None else f" +- {std:.2f}")

        lines.append(
            f"| {e} | {cell('speed_rmse_mhz')} | {cell('coi_rmse_mhz')} | "
            f"{cell('rel_rmse_mhz')} | {cell('rel_forecast_rmse_mhz')} |"
        )
    lines += [
        "",
        f"## False ESD actions, {AMBIENT_S:g} s without fault (deadband 100 mHz)",
        "",
        "Ambient load fluctuation (`stabctl.estimation.ambient`): every load's P an "
        "Ornstein-Uhlenbeck "
        f"process, standard deviation {AMBIENT.pct:g} %, correlation time "
        f"{AMBIENT.tau_s:g} s; {AMBIENT_RUNS} runs (load and PMU noise seeds 0.."
        f"{AMBIENT_RUNS - 1}). The `true` row is the simulated truth: its spread is the "
        "ambient spread of the relative speeds.  The PMU frequency is the phase advance "
        "over the PMU's two-cycle estimation window (`pmu.window_estimates`), so the "
        "rows are converged in the integration step: Kundur raw / kf / ekf 10.24 / "
        "10.04 / 9.96 mHz at 5 ms and 10.44 / 10.22 / 9.96 at 4.17, 2.08 and 1.04 ms; "
        "miniWECC 52.86 / 52.54 / 53.92 at 5 ms, 52.75 / 52.42 / 53.90 at 2.5 ms "
        "(`analysis/ambient_step.py`, docs/estimation.md 3).",
        "",
        "| estimate | actions per run | largest abs(f_i - f_COI), mHz (mean, max over runs) "
        "| largest std of f_i - f_COI, mHz |",
        "|---|---|---|---|",
    ]
    for e, m in fig["false"].items():
        lines.append(
            f"| {e} | {m['actions']['mean']:.2f} | {m['max_rel_mhz']['mean']:.2f}, "
            f"{m['max_rel_mhz']['max']:.2f} | {m['std_rel_mhz']['mean']:.2f} |"
        )
    lines += [
        "",
        f"## CCT with the estimator in the loop (cycles; {_seeds_text(fig['cct_runs'])}"
        "; ideal: one run; bisection tolerance 1/4 cycle)",
        "",
        "Each CCT is the cold bisection's on the 1/4-cycle lattice, the search of the ideal "
        "row. With an estimator in the loop the verdict need not be monotone in the "
        "clearing time (a longer clearing can be stable where a shorter one is not), so a "
        "CCT is the bisection's answer, not the longest clearing with every shorter one "
        "stable. Interval: Student t over the seeds, at least the lattice bound "
        "(`stabctl.estimation.closed_loop.SeedRule`).",
        "",
        "| rating | estimator | mean | interval of the mean | std | min | max | "
        "mean vs ideal | runs (failed) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for p, row in fig["cct"].items():
        for e, s in row.items():

            def num(k, s=s):
                return "-" if s[k] is None else f"{s[k]:.2f}"

            ideal = row.get("ideal", {}).get("mean")
            rel = "-" if None in (s["mean"], ideal) else f"{100 * (s['mean'] / ideal - 1):+.1f} %"
            ci = "-" if s.get("half_width") in (None, np.inf) else f"+-{s['half_width']:.2f}"
            lines.append(
                f"| {p:g} % | {e} | {num('mean')} | {ci} | {num('std')} | "
                f"{num('min')} | {num('max')} | {rel} | {s['runs']} ({s['failed']}) |"
            )
    return "\n".join(lines) + "\n"


def write_estimation_report(
    out_dir="reports",
    runs: int = 20,
    cct_runs=cl.SeedRule(),
    workers=None,
    cases=tuple(CASES),
    records_dir=None,
    generated_by: str = "stabctl paper",
    progress=None,
) -> list[Path]:
    """Write reports/estimation_<case>.md for each of `cases` (default both).  runs:
    Monte-Carlo runs of the RMSE study; cct_runs: noise seeds per CCT row, a count or a
    `closed_loop.SeedRule`; workers: processes of the CCT sweep; records_dir:
    where the CCT sweeps keep their resumable records (default out_dir); generated_by: the
    command the report names as its source; progress: callable(str) told each stage.  Returns the
    paths.  Raises InputError for an unknown case."""
    unknown = set(cases) - set(CASES)
    if unknown:
        raise InputError(f"no estimation study for case(s) {sorted(unknown)}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in cases:
        records = Path(records_dir or out_dir)
        records.mkdir(parents=True, exist_ok=True)
        fig = case_figures(name, runs, cct_runs, records, workers, progress)
        path = out_dir / f"estimation_{name}.md"
        path.write_text(markdown(name, fig, generated_by), "utf-8")
        paths.append(path)
    return paths
