"""`stabctl paper`: reproduce the paper's tables and figures into a markdown report.

Each section is a function returning markdown and saving its figures; `write_paper_report`
assembles them in a temporary directory and moves the finished files into place, so an
interrupted or failed run leaves no half-written report.
"""

from __future__ import annotations

import json
import logging
import os
import platform
import shutil
import time
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from stabctl.errors import InputError
from stabctl.locking import exclusive, temp_dir
from stabctl.outdir import output_directory
from stabctl.parallel import (
    naming,
    read_records,
    set_aside_damaged,
    signals_held,
    write_reproducible,
)
from stabctl.plotting import figures as plotting
from stabctl.smib.coi import PAPER_TWO_MACHINE, PAPER_TWO_MACHINE_T_RELEASE
from stabctl.smib.feedback import PAPER_LAWS, settling_time
from stabctl.smib.omib import PAPER_OMIB, clearing_table, eac_summary, simulate
from stabctl.smib.optimal import solve_min_time
from stabctl.studies import paper_storage
from stabctl.studies.scorecard import claim, gather

logger = logging.getLogger(__name__)

#: Paper Table 1: fault cycles -> (delta at clearing rad, d(delta)/dt rad/s, stable).
PAPER_TABLE1 = {6: (0.6519, 3.1374, True), 12: (1.1228, 6.2747, True), 15: (1.4753, 7.8421, False)}
#: Paper Table 2: states of the two-machine equivalent at fault release.
PAPER_TABLE2 = {"x1_rad": 1.0734, "x2_rad_s": 10.9956}
#: Storage rating used for the minimum-time study (pu); the paper's value is not given in
#: the text we reproduce from, so we show three ratings.
MIN_TIME_RATINGS_PU = (0.1, 0.2, 0.5)


#: the relative error below which a printed figure of the paper's and ours agree (its
#: figures carry 4-5 digits; Table 1's speeds differ by 0.15 % through its omega0)
TABLE_AGREES = 0.005


def _rel(ours: float, ref: float) -> str:
    return f"{100 * abs(ours - ref) / abs(ref):.2f} %"


def section_omib(fig_dir: Path) -> str:
    """Section 2: Table 1, phase plane (Figs. 4-5), EAC and energy-function checks."""
    sys_ = PAPER_OMIB
    rows = clearing_table(sys_, PAPER_TABLE1)
    eac = eac_summary(sys_)
    lines = [
        "## 1. One-machine infinite bus (paper Section 2, Table 1)",
        "",
        f"H = {sys_.H} s, f0 = {sys_.f0} Hz, Pm = {sys_.Pm} pu, delta0 = {sys_.delta0:.4f} rad, "
        f"Pmax = {sys_.Pmax_pre:.4f} pu (X = {sys_.X:.4f} pu), bolted fault at the generator "
        "bus, post-fault network = pre-fault.",
        "",
        "| cycles | delta_cl (rad) | paper | error | d(delta)/dt (rad/s) | paper | error "
        "| verdict | paper |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    runs = {}
    for r in rows:
        cyc = int(r["cycles"])
        d_ref, w_ref, st_ref = PAPER_TABLE1[cyc]
        runs[cyc] = simulate(sys_, r["t_clear_s"], t_end=2.0)
        lines.append(
            f"| {cyc} | {r['delta_cl_rad']:.4f} | {d_ref} | {_rel(r['delta_cl_rad'], d_ref)} | "
            f"{r['omega_cl_rad_s']:.4f} | {w_ref} | {_rel(r['omega_cl_rad_s'], w_ref)} | "
            f"{'stable' if r['stable'] else 'unstable'} | {'stable' if st_ref else 'unstable'} |"
        )
    drift = _energy_drift(sys_, runs)
    lines.append(_table1_claim(rows))
    ratios = [PAPER_TABLE1[int(r["cycles"])][1] / r["omega_cl_rad_s"] for r in rows]
    swings = [
        (PAPER_TABLE1[int(r["cycles"])][0] - sys_.delta0) / (r["delta_cl_rad"] - sys_.delta0)
        for r in rows
    ]
    lines += [
        "",
        "The speeds at clearing are the closed form of a bolted fault, d(delta)/dt = Pm "
        "omega0 t_cl / 2H (pi rad/s at 6 cycles); the paper's are "
        f"{100 * (1 - max(ratios)):.2f}-{100 * (1 - min(ratios)):.2f} % lower, and its angle "
        f"increments delta_cl - delta0 {100 * (1 - max(swings)):.2f}-"
        f"{100 * (1 - min(swings)):.2f} % (its angles rounded to 1e-4 rad), as with omega0 = "
        f"{2 * np.pi * sys_.f0 * float(np.mean(ratios)):.1f} rad/s instead of 2 pi f0 = "
        f"{2 * np.pi * sys_.f0:.2f}: a constant of the paper's, not of the model (the "
        "verdicts agree).",
        "",
        "Equal-area criterion (eq. 11) and energy function (eq. 10):",
        "",
        f"- critical clearing angle {eac['delta_cr_rad']:.4f} rad; CCT closed form "
        f"{eac['t_cr_s']:.5f} s ({eac['t_cr_cycles']:.2f} cycles), time-domain bisection "
        f"{eac['t_cr_bisection_s']:.5f} s ({eac['bisection_runs']} runs): difference "
        f"{1e3 * abs(eac['t_cr_s'] - eac['t_cr_bisection_s']):.3f} ms.",
        "- accelerating area A1 versus kinetic energy at clearing M*omega_cl^2/2 "
        "(pu*s), and the decelerating area still available:",
        "",
        "| cycles | A1 | kinetic energy | available A2 | max energy drift after clearing |",
        "|---|---|---|---|---|",
    ]
    for cyc, run in runs.items():
        a1 = sys_.accelerating_area(run.delta_cl)
        ke = 0.5 * sys_.M * run.omega_cl**2
        lines.append(
            f"| {cyc} | {a1:.6f} | {ke:.6f} | {sys_.decelerating_area(run.delta_cl):.6f} "
            f"| {drift[cyc]:.1e} |"
        )
    plotting.omib_phase_plane(sys_, runs, fig_dir / "fig04_omib_phase_plane.png")
    plotting.omib_equal_area(sys_, runs[12], fig_dir / "fig05_omib_equal_area.png")
    lines += [
        "",
        "![phase plane](fig04_omib_phase_plane.png)",
        "![equal area](fig05_omib_equal_area.png)",
        "",
    ]
    return "\n".join(lines)


def _table1_claim(rows) -> str:
    """The scorecard's row of Table 1: the largest errors of the angles and speeds at
    clearing, and the verdicts."""
    err = {
        key: max(abs(r[key] / PAPER_TABLE1[int(r["cycles"])][col] - 1) for r in rows)
        for key, col in (("delta_cl_rad", 0), ("omega_cl_rad_s", 1))
    }
    same = all(bool(r["stable"]) == PAPER_TABLE1[int(r["cycles"])][2] for r in rows)
    verdicts = ", ".join("stable" if r["stable"] else "unstable" for r in rows)
    cycles = ", ".join(str(int(r["cycles"])) for r in rows)
    return claim(
        "1",
        f"Table 1: delta_cl and d(delta)/dt at {cycles} cycles; "
        + ", ".join("stable" if PAPER_TABLE1[int(r["cycles"])][2] else "unstable" for r in rows),
        f"angles within {100 * err['delta_cl_rad']:.2f} %, speeds within "
        f"{100 * err['omega_cl_rad_s']:.2f} %; {verdicts}",
        same and max(err.values()) < TABLE_AGREES,
        "the speeds' gap is the paper's omega0 = 376.5 rad/s",
    )


def _energy_drift(sys_, runs) -> dict[int, float]:
    """Largest |V(t) - V(t_clear)| after clearing along each run (pu*s), eq. (10)."""
    out = {}
    for cyc, run in runs.items():
        k = run.t >= run.t_clear
        v = sys_.energy(run.delta[k], run.omega[k])
        out[cyc] = float(np.max(np.abs(v - v[0])))
    return out


def section_feedback(fig_dir: Path) -> str:
    """Section 3: the four feedback laws on the 15-cycle case (Fig. 7 and a table)."""
    sys_ = PAPER_OMIB
    t_cl, t_end = 15 / sys_.f0, 10.0
    runs = {"no control": simulate(sys_, t_cl, t_end=t_end)}
    for law in PAPER_LAWS:
        law.check(sys_.M)
        runs[law.name] = simulate(sys_, t_cl, t_end=t_end, law=law)
    lines = [
        "## 2. Feedback laws (paper Section 3, 15-cycle fault, control after clearing)",
        "",
        "Eq. (14) is garbled in the source text; we read it as "
        "P_eC = Ka |d2delta/dt2| sgn(d delta/dt), consistent with the paper's description. "
        "Laws using the acceleration form an algebraic loop with the swing equation, "
        "resolved exactly (see `stabctl.smib.feedback`).",
        "",
        "| law | stable | max angle (rad) | max speed dev. after clearing (rad/s) | "
        f"settling time, 5 % band (s, within {t_end} s) | peak |P_C| (pu) |",
        "|---|---|---|---|---|---|",
    ]
    settle = {}
    for name, run in runs.items():
        k = run.t >= run.t_clear
        ts = settling_time(run.t, run.omega, run.t_clear) if run.stable else float("inf")
        settle[name] = ts
        lines.append(
            f"| {name} | {'yes' if run.stable else 'no'} | {run.delta.max():.4f} | "
            f"{np.abs(run.omega[k]).max():.4f} | "
            f"{'never' if np.isinf(ts) else f'{ts:.2f}'} | {np.abs(run.P_C).max():.3f} |"
        )
    plotting.feedback_phase_plane(sys_, runs, fig_dir / "fig07_feedback_phase_plane.png")
    lines.append(_feedback_claim(runs, settle))
    lines += [
        "",
        'Settling time "never": the speed does not stay inside the band within '
        f"{t_end:g} s (an unstable run leaves it for good). "
        "The acceleration-only law changes the effective inertia but adds no damping, "
        "so it never settles; the sign law always absorbs energy from the swing "
        "(P_C * omega >= 0).",
        "",
        "![feedback](fig07_feedback_phase_plane.png)",
        "",
    ]
    return "\n".join(lines)


def _feedback_claim(runs: dict, settle: dict) -> str:
    """The scorecard's row of Fig. 7 (paper Section 3's text): the four laws keep the
    15-cycle fault stable; the speed law advances the angle most, the acceleration law
    swings the speed most, the sign law swings least and settles first; the combined law
    swings less than either alone, angle and speed."""
    acc, speed, both, sign = (runs[law.name] for law in PAPER_LAWS)
    laws = (acc, speed, both, sign)

    def swing(r):  # largest speed deviation after clearing, rad/s
        return float(np.abs(r.omega[r.t >= r.t_clear]).max())

    held = {
        "all four stable": all(r.stable for r in laws),
        "speed law: widest angle": speed.delta.max() == max(r.delta.max() for r in laws),
        "acceleration law: widest speed swing": swing(acc) == max(swing(r) for r in laws),
        "sign law: smallest angle": sign.delta.max() == min(r.delta.max() for r in laws),
        "sign law: settles first": settle[PAPER_LAWS[3].name]
        == min(settle[law.name] for law in PAPER_LAWS),
        "combined law: angle below both alone": both.delta.max()
        < min(acc.delta.max(), speed.delta.max()),
        "combined law: speed swing below both alone": swing(both) < min(swing(acc), swing(speed)),
    }
    failed = [s for s, ok in held.items() if not ok]
    return claim(
        "2",
        "Fig. 7 and its text, 15-cycle fault: " + "; ".join(held),
        f"{len(held) - len(failed)} of {len(held)} hold"
        + (f" (not: {'; '.join(failed)})" if failed else ""),
        not failed,
        "each law's swings are in section 2's table" if failed else "",
    )


def section_two_machine_and_min_time(fig_dir: Path) -> str:
    """Section 4: Table 2 (two-machine COI equivalent) and minimum-time control (Figs. 10-11)."""
    tm = PAPER_TWO_MACHINE
    eq = tm.equivalent()
    rel = simulate(eq, PAPER_TWO_MACHINE_T_RELEASE, t_end=PAPER_TWO_MACHINE_T_RELEASE + 0.01)
    x_r = (rel.delta_cl, rel.omega_cl)
    lines = [
        "## 3. Two-machine COI equivalent and minimum-time control (paper Section 4)",
        "",
        f"H1 = {tm.H1} s against the rest H_rest = {tm.H_rest} s (H = {tm.H:.4f} s), "
        f"Pm = {tm.Pm} pu, Pmax = {tm.Pmax_pre} pu, delta0 = {eq.delta0:.4f} rad, "
        f"{PAPER_TWO_MACHINE_T_RELEASE * 60:.0f}-cycle bolted fault. Table 2 fixes only "
        "H, delta0 and the fault duration; the split of H only sets the storage share "
        f"k_C = {tm.k_C:.4f}.",
        "",
        "| state at release | ours | paper | error |",
        "|---|---|---|---|",
        f"| x1(tr) (rad) | {x_r[0]:.4f} | {PAPER_TABLE2['x1_rad']} | "
        f"{_rel(x_r[0], PAPER_TABLE2['x1_rad'])} |",
        f"| x2(tr) (rad/s) | {x_r[1]:.4f} | {PAPER_TABLE2['x2_rad_s']} | "
        f"{_rel(x_r[1], PAPER_TABLE2['x2_rad_s'])} |",
        "",
        "Minimum-time problem (eqs. 27-39), solved as a free-final-time two-point BVP "
        "(scipy solve_bvp): lambda2 > 0 on the whole interval, so the optimal input is the "
        "full absorbing pulse P_C = P_Cmax.",
        "",
        "| P_Cmax (pu) | T from BVP (s) | T of simulated full pulse (s) | T without storage (s) "
        "| min lambda2 | max abs(H) | lambda2 > 0 |",
        "|---|---|---|---|---|---|---|",
    ]
    sols = {}
    for pc in MIN_TIME_RATINGS_PU:
        s = solve_min_time(eq, x_r, pc)
        sols[pc] = s
        lines.append(
            f"| {pc} | {s.T:.5f} | {s.T_pulse:.5f} | {s.T_uncontrolled:.5f} | "
            f"{s.l2.min():.3e} | {np.abs(s.hamiltonian).max():.1e} | "
            f"{'yes' if s.lambda2_positive else 'no'} |"
        )
    worst = max(
        abs(x_r[0] / PAPER_TABLE2["x1_rad"] - 1), abs(x_r[1] / PAPER_TABLE2["x2_rad_s"] - 1)
    )
    lines += [
        claim(
            "3",
            f"Table 2: state at release x1 = {PAPER_TABLE2['x1_rad']} rad, x2 = "
            f"{PAPER_TABLE2['x2_rad_s']} rad/s",
            f"{x_r[0]:.4f} rad, {x_r[1]:.4f} rad/s (within {100 * worst:.3f} %)",
            worst < TABLE_AGREES,
        ),
        claim(
            "3",
            "eq. 39: the minimum-time input is the full absorbing pulse (lambda2 > 0)",
            f"lambda2 > 0 at {sum(s.lambda2_positive for s in sols.values())} of "
            f"{len(sols)} ratings ({', '.join(f'{pc:g}' for pc in sols)} pu); BVP and "
            "simulated pulse end within "
            f"{max(abs(s.T - s.T_pulse) for s in sols.values()) * 1e3:.2f} ms",
            all(s.lambda2_positive for s in sols.values()),
        ),
    ]
    plotting.min_time_figures(
        eq,
        x_r,
        sols,
        fig_dir / "fig10_min_time_states.png",
        fig_dir / "fig11_min_time_costates.png",
    )
    lines += [
        "",
        "![states](fig10_min_time_states.png)",
        "![costates](fig11_min_time_costates.png)",
        "",
    ]
    return "\n".join(lines)


def section_estimation(fig_dir: Path, records_dir: Path, progress=None) -> str:
    """PMU estimation and estimator-in-the-loop control: separate reports."""
    from stabctl.studies.estimation_report import write_estimation_report

    paths = write_estimation_report(fig_dir, runs=20, records_dir=records_dir, progress=progress)
    links = ", ".join(f"[{p.stem}]({p.name})" for p in paths)
    return "\n".join(
        [
            "## 7. Estimated speeds in the control loop",
            "",
            "PMU model (IEEE C37.118.1 limits), Kalman filters, RMSE versus truth, "
            "false actions in ambient noise and CCT with ideal measurements, raw "
            f"PMU frequency and each estimator in the loop: {links}.",
            "",
        ]
    )


def section_placement(fig_dir: Path, records_dir: Path, progress=None) -> str:
    """ESD sizing and placement: separate reports per case."""
    from stabctl.studies.placement import placement_study

    paths = [
        placement_study(case, fig_dir, records_dir=records_dir, progress=progress)
        for case in ("kundur", "miniwecc")
    ]
    links = ", ".join(f"[{p.stem}]({p.name})" for p in paths)
    return "\n".join(
        [
            "## 8. Where to put how much storage",
            "",
            "Least-cost ESD sites, MW and MWh (convex programs, cvxpy + Clarabel, "
            "constraint generation) such that every screened fault is stable when "
            "cleared after 5 cycles at 90, 100 and 110 % load, verified by "
            "simulation, against the least uniform fleet meeting the same "
            "requirement, with the Pareto curve of cost against the required "
            f"clearing time: {links}.",
            "",
        ]
    )


def section_convergence(fig_dir: Path, progress=None) -> str:
    """Section 9: CCT of the paper's faults against the step under both conventions.

    progress(str), if given, hears each CCT search (case, conventions, step)."""
    from stabctl.studies.convergence import PAPER_FAULTS, cct_versus_step, markdown_table

    lines = [
        "## 9. Step convergence: IEEE 421.5 limiters against PSTess's",
        "",
        "CCT of the Case-1 and Case-2 faults (bisection to 1 ms) at steps from 10 ms to "
        "0.5 ms. ieee (the default): every limiter non-windup as IEEE Std 421.5-2016, "
        "the step never longer than h, each step on the network of its interval. "
        "pstess: PSTess 1.1 bit for bit, including the smpexc limiter that keeps the "
        "field voltage's derivative at the ceiling (docs/conventions.md lists every "
        "difference with its PSTess source line). Each CCT search also reruns its final "
        "bracket at half the step: `numerical_error_s` in `stabctl cct --json`.",
        "",
    ]
    for name, fault in PAPER_FAULTS.items():
        table = cct_versus_step(name, fault, progress=progress)
        freq = 60.0
        ieee = [c for _, c, _ in table["ieee"]["rows"]]
        pst = [c for _, c, _ in table["pstess"]["rows"]]
        lines += [f"### {name}: {fault.describe()}", ""]
        lines += markdown_table(name, table, freq)
        lines += [
            "",
            f"- ieee: {1000 * min(ieee):.0f}-{1000 * max(ieee):.0f} ms over the "
            f"steps ({1000 * (max(ieee) - min(ieee)):.0f} ms spread, the tolerance is "
            f"1 ms); pstess: {1000 * min(pst):.0f}-{1000 * max(pst):.0f} ms "
            f"({1000 * (max(pst) - min(pst)):.0f} ms spread).",
            "",
        ]
    lines += [
        "Under ieee the CCT moves by at most one 1 ms lattice cell between halvings "
        "(resolved to 0.1 ms on Kundur: 153.3, 154.1, 154.3, 154.3, 154.4, 154.4 ms at "
        "10, 5, 2.5, 1.25, 0.625, 0.3125 ms, docs/conventions.md: differences shrinking "
        "about fourfold per halving, second order). Kundur's default ieee step is half "
        "its fastest time constant (T_R = 10 ms), so the default CCT is within the "
        "tolerance of the converged one; so is miniWECC's (a governor's T_5 = 10 ms: 5 "
        "ms, 2.4 times its data-file step 1/480 s, the pstess default; ST3 exciters, "
        "whose PSTess limiter already zeroes the derivative, so both conventions "
        "converge).",
        "",
    ]
    return "\n".join(lines)


#: Report parts: key -> sections (each returns markdown and writes its figures).
PARTS: dict[str, tuple[Callable[[Path], str], ...]] = {
    "analytic": (section_omib, section_feedback, section_two_machine_and_min_time),
    "cases": (paper_storage.section_case1, paper_storage.section_case2),
    "table4": (),
    "wecc": (),
    "estimation": (),
    "placement": (),
    "convergence": (section_convergence,),
}
#: Sections of PARTS long enough to report their progress (called with progress=...)
TALKING = {section_convergence}
#: Parts whose sweeps keep resumable records (JSON lines): key -> (section(fig_dir,
#: records_dir, progress), record files).  The records are made in WORK_DIR and copied
#: into the report directory, reproducibly (`sweep.write_reproducible`), at the end.
RESUMABLE = {
    "table4": (paper_storage.section_table4, "table4_*.jsonl"),
    "wecc": (paper_storage.section_wecc, "wecc_*.jsonl"),
    "estimation": (section_estimation, "estimation_cct_*.jsonl"),
    "placement": (section_placement, "placement_*_screening.jsonl"),
}
#: Sub-directory of the report directory holding the records of the run in progress
#: (with timings, for --resume); removed when the run completes.
WORK_DIR = ".paper-work"
#: The run's timings and other run-dependent values, in the report directory (the
#: reports themselves hold none).
RUN_LOG = "run_log.json"


def write_paper_report(
    out_dir: str | os.PathLike,
    progress: Callable[[str], None] | None = None,
    resume: bool = False,
    only=None,
) -> Path:
    """Build the report parts (`PARTS`; all, or the keys in `only`) into out_dir/paper.md
    with their PNG figures and sub-reports; returns the path.

    Files are written to a temporary directory first and moved into out_dir only when all
    sections succeeded.  The sweeps of the RESUMABLE parts record each finished job in
    out_dir/WORK_DIR (started afresh unless `resume`; with `resume`, a part without
    records there starts from the records already in out_dir).  When every section has
    succeeded, the records are written to out_dir without run-dependent fields, sorted
    (each file replaced only when its new version is complete), WORK_DIR is removed and
    the run's timings (seconds per section, per record file, every progress line) go to
    out_dir/RUN_LOG: the reports and records of two runs of the same code are identical.
    progress: callable(str) told every progress line (None: this module's logger, level
    INFO, `stabctl.progress`).

    One run per out_dir at a time: the run holds WORK_DIR's lock
    (`stabctl.locking.exclusive`) throughout.  A run that fails or is interrupted leaves
    WORK_DIR only with records in it, and out_dir only if it existed or holds files
    (`stabctl.outdir.output_directory`); an OSError naming no file (a full disk) names
    out_dir.

    Raises:
        InputError: an unknown part in `only`; another run is writing out_dir (names its
            pid).
    """
    keys = list(PARTS) if not only else list(only)
    bad = [k for k in keys if k not in PARTS]
    if bad:
        raise InputError(f"unknown report part(s) {bad}; choose from {list(PARTS)}")
    # a write that names no file (a full disk) names the report directory; on an error,
    # the directories created here and left empty are removed again
    out = Path(out_dir)
    with naming(out), output_directory(out), exclusive(out / WORK_DIR):
        try:
            return _write_locked(out, keys, progress, resume)
        except BaseException:
            try:  # no records to resume from: no work directory either
                (out / WORK_DIR).rmdir()
            except OSError:  # records kept for --resume (or never created)
                pass
            raise


def _write_locked(out: Path, keys: list, progress, resume: bool) -> Path:
    """`write_paper_report`'s work once it holds the lock of out/WORK_DIR."""
    work = out / WORK_DIR
    work.mkdir(exist_ok=True)
    for key in keys:
        if key not in RESUMABLE:
            continue
        pattern = RESUMABLE[key][1]
        if not resume:
            for f in work.glob(pattern):
                f.unlink()
        elif not any(work.glob(pattern)):
            for f in out.glob(pattern):
                shutil.copyfile(f, work / f.name)
        if resume:  # every part's records looked at before any part runs
            for f in sorted(work.glob(pattern)):
                set_aside_damaged(
                    f, remedy="remove it (its part runs again) or run without --resume"
                )
    t_start = time.perf_counter()
    log: dict[str, Any] = {
        "command": "stabctl paper",
        "parts": keys,
        "resume": bool(resume),
        "started": datetime.now(UTC).isoformat(timespec="seconds"),
        "stabctl": _version(),
        "python": platform.python_version(),
        "cores": len(os.sched_getaffinity(0))
        if hasattr(os, "sched_getaffinity")
        else os.cpu_count(),
        "sections": [],
        "records": {},
        "progress": [],
    }

    def say(msg: str) -> None:
        log["progress"].append([round(time.perf_counter() - t_start, 1), msg])
        (progress or logger.info)(msg)

    with temp_dir(".paper-", out) as held:
        tmp = Path(held.path)
        parts = [
            "# stabctl: reproduction of the paper's results",
            "",
            "Generated by `stabctl paper`. Errors are relative to the paper's printed values.",
            "",
        ]
        for key in keys:
            for section in PARTS[key]:
                parts.append(
                    _timed(
                        log,
                        key,
                        section,
                        say,
                        lambda s: s(tmp, **({"progress": say} if s in TALKING else {})),
                    )
                )
            if key in RESUMABLE:
                parts.append(
                    _timed(
                        log,
                        key,
                        RESUMABLE[key][0],
                        say,
                        lambda s: s(tmp, work, progress=say),
                        " (resumable records)",
                    )
                )
        score, parts[4:] = gather(parts[4:])
        (tmp / "paper.md").write_text("\n".join(parts[:4] + score + parts[4:]), "utf-8")
        finished = [
            f
            for key in keys
            for f in (sorted(work.glob(RESUMABLE[key][1])) if key in RESUMABLE else ())
        ]
        for f in finished:  # every output made beside the others, then all moved at once
            log["records"][f.name] = {
                **write_reproducible(f, tmp / f.name),
                "simulations": _simulations(tmp / f.name),
                **_verdicts(tmp / f.name),
            }
        log["total_s"] = round(time.perf_counter() - t_start, 1)
        (tmp / RUN_LOG).write_text(json.dumps(log, indent=1) + "\n", "utf-8")
        with signals_held():  # an interrupt between two moves left the directory half new
            for f in tmp.iterdir():
                os.replace(f, out / f.name)
    for f in finished:
        f.unlink()
    try:
        work.rmdir()
    except OSError:  # something else left there: keep it
        pass
    return out / "paper.md"


def _simulations(records: Path) -> int:
    """Simulations the finished jobs of a sweep record file ran (their results'
    ``n_simulations``, a count or a list of counts)."""
    n = 0
    for rec in read_records(records).values():
        count = (rec.get("result") or {}).get("n_simulations", 0)
        n += sum(count) if isinstance(count, list) else int(count)
    return n


def _verdicts(records: Path) -> dict:
    """Of a sweep record file's jobs (`stabctl.stability.screening.verdict`): those whose
    search found the fault still stable at its upper limit (robust, ``above_limit``), those
    unstable even when cleared at once (``insecure``, N-1 insecure) and those without a
    verdict (``failures``); verdicts are not failures."""
    from stabctl.stability.screening import ABOVE, INSECURE, verdict

    found = [verdict(rec) for rec in read_records(records).values()]
    return {
        "above_limit": found.count(ABOVE),
        "insecure": found.count(INSECURE),
        "failures": found.count("failed"),
    }


def run_summary(log: dict) -> str:
    """The end-of-run summary of `stabctl paper` from its run log (`RUN_LOG`): seconds per
    section, jobs and simulations per sweep record file, the total."""
    lines = [f"{'wall s':>8}  section"]
    lines += [f"{s['seconds']:8.1f}  {s['section']}" for s in log["sections"]]
    lines += [
        f"{'':8}  {name}: {r['jobs']} jobs ("
        + (f"{r['above_limit']} above the search limit, robust; " if r.get("above_limit") else "")
        + (f"{r['insecure']} N-1 insecure; " if r.get("insecure") else "")
        + f"{r.get('failures', r['failed'])} failed), {r['simulations']} simulations"
        for name, r in log["records"].items()
    ]
    lines.append(f"{log['total_s']:8.1f}  in all (wall), on {log['cores']} cores")
    return "\n".join(lines)


def _timed(log: dict, key: str, section, say, call, note: str = "") -> str:
    """Run one section (`call(section)`), announcing it and logging its seconds."""
    title = section.__doc__.splitlines()[0]
    say(f"paper: {title}{note}")
    t0 = time.perf_counter()
    text = call(section)
    log["sections"].append(
        {"part": key, "section": title, "seconds": round(time.perf_counter() - t0, 1)}
    )
    return text


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("stabctl")
    except Exception:  # noqa: BLE001 - not installed (source tree)
        return "unknown"
