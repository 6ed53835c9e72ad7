"""stabctl against ANDES 2.0 on the same PSS/E cases and fault, like with like (not a test;
needs ``pip install "stabctl[andes]"``).

Cases: ANDES's Kundur (kundur.raw + kundur_full.dyr without its Toggle record) and
WECC-179 (wecc.raw + wecc_full.dyr, GENROU saturation set to 0), imported by
``stabctl.io.psse.load_psse`` with ``conventions="andes"`` (ANDES's reading of GENROU,
EXDC2 and IEEEG1, so that both tools solve the same equations) and read by ANDES from the
same files (``stabctl.io.andes``). Fault: three-phase at one bus through j1e-4 pu from
t = 1 s, cleared after 6 cycles without loss of a line.

Each tool is timed in two settings, and each one's error is measured against its own
converged fine-step reference (so that the error is the tool's numerical error, not the
small model difference between the tools, which is printed separately):

(a) its own defaults: stabctl's default step (``simulation.default_step``: the data file's,
    else half a cycle, 1/120 s for these PSS/E cases); ANDES 2.0's TDS defaults (implicit
    trapezoid, fixed step 1/30 s, Newton tolerance 1e-4), shown with numba off (ANDES's
    default) and on (``Runtime.numba = 1``, ANDES's documented fast configuration, its
    compilation cached and excluded);
(b) the largest step of the grid 1/30, 1/60, ... 1/1920 s whose largest rotor-speed error
    over the run is at most ACCURACY (1e-4 pu), each tool otherwise at its defaults
    (ANDES with numba on).

Studies (``--only``):

* ``sim``: 20 s simulation (stabctl: power flow + model + run; ANDES: power flow +
  time-domain run on a freshly loaded system, its stop-at-instability criterion off so
  that both run 20 s; loading and code set-up excluded for both); the error is the
  largest |speed - reference speed| over all machines and all output times (reference
  interpolated); references: stabctl at 1/7680 s, ANDES at 1/1920 s with Newton
  tolerance 1e-10;
* ``eig``: linearisation and eigenvalues (stabctl ``linearise`` + ``modal_analysis``,
  central differences with PSTess's perturbation 1e-4; ANDES ``PFlow`` + ``EIG``, its
  symbolic Jacobian): no step to choose, so one row; stabctl's error against its own
  linearisation with perturbation 1e-6 (converged), ANDES's Jacobian exact; and the
  largest relative difference between each of stabctl's electromechanical eigenvalues and
  ANDES's nearest one;
* ``cct``: 1 ms critical clearing time by the same bisection in both (stabctl
  ``cct.critical_clearing_time``, bolted fault; ANDES repeated runs to 5 s after the
  fault, fault j1e-4 pu, unstable when a rotor angle leaves the centre of inertia by more
  than pi or the run breaks down), at settings (a) and (b) of ``sim``, each CCT against
  the tool's own CCT at a fine step (stabctl 1/3840 s, ANDES 1/480 s, tolerance 1e-10).

Timings are the best of REPEAT runs (the machine has 2 cores and other users: the best
run is the one least disturbed); stabctl's compilation is excluded (a warm-up run).

Run: python benchmarks/bench_andes.py [--only sim eig cct] [--cases kundur wecc179]
     [--repeat N]
"""

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
from _timing import best_of

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.dynamics.grid import default_step
from stabctl.errors import InputError
from stabctl.io.andes import AndesFault, andes_modes, andes_system, strip_dyr
from stabctl.io.psse import load_psse
from stabctl.smallsignal.linearise import linearise
from stabctl.smallsignal.modal import modal_analysis
from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time

T_FAULT, CYCLES, T_END, TOL_CCT = 1.0, 6, 20.0, 0.001
ACCURACY = 1e-4  # pu rotor speed, for settings (b)
GRID = tuple(1 / n for n in (30, 60, 120, 240, 480, 960, 1920))
ANDES_DEFAULT = {"tstep": 1 / 30, "tol": 1e-4}  # ANDES 2.0 TDS defaults (checked below)
REF_OURS, REF_ANDES, REF_ANDES_TOL = 1 / 7680, 1 / 1920, 1e-10
CCT_REF_OURS, CCT_REF_ANDES = 1 / 3840, 1 / 480
CONVENTIONS = "andes"
CASES = {"kundur": ("kundur", 7), "wecc179": ("wecc", 1)}  # label: ANDES folder, fault bus
REPEAT = 3


def case_files(folder: str, work: Path):
    """(RAW, DYR) of an ANDES case, the DYR made like for like (module doc)."""
    import andes

    src = Path(andes.__file__).parent / "cases" / folder
    dyr = work / f"{folder}.dyr"
    if folder == "kundur":
        strip_dyr(src / f"{folder}_full.dyr", dyr, {"TOGGLE"})
    else:
        strip_dyr(src / f"{folder}_full.dyr", dyr, (), unsaturated=True)
    return src / f"{folder}.raw", dyr


# -- runs --------------------------------------------------------------------------------


def ours_run(case, bus, t_end, h, clear=CYCLES / 60):
    """stabctl: (t, speeds (n_t, n_mac)) of the fault run at step h."""
    res = Simulator(case).run([Fault(bus, T_FAULT, T_FAULT + clear, x=1e-4)], t_end, h=h)
    return res.t, res.speed


def andes_load(raw, dyr, fault: AndesFault | None, numba: bool):
    """A freshly loaded ANDES system (default configuration, numba on or off), set up."""
    return andes_system(raw, dyr, fault, config_option=[f"Runtime.numba={int(numba)}"])


def andes_defaults_checked() -> None:
    """Stop if ANDES's own TDS defaults are not what this benchmark calls its defaults."""
    import andes
    from andes.routines.tds import TDS  # noqa: F401  (import check only)

    ss = andes.load(andes.get_case("kundur/kundur_full.xlsx"), no_output=True, default_config=True)
    got = {
        "tstep": ss.TDS.config.tstep,
        "tol": ss.TDS.config.tol,
        "method": ss.TDS.config.method,
        "fixt": ss.TDS.config.fixt,
        "numba": ss.runtime.numba,
    }
    want = {**ANDES_DEFAULT, "method": "trapezoid", "fixt": 1, "numba": 0}
    if any(
        abs(got[k] - want[k]) > 1e-12 if isinstance(want[k], float) else got[k] != want[k]
        for k in want
    ):
        raise SystemExit(f"ANDES defaults changed: {got}, expected {want}")


def andes_run(raw, dyr, bus, t_end, tstep, tol, numba=True, clear=CYCLES / 60):
    """ANDES: (wall s of PFlow + TDS, t, GENROU speeds in RAW order, system)."""
    ss = andes_load(raw, dyr, AndesFault(bus, T_FAULT, T_FAULT + clear), numba)
    ss.TDS.config.update(tf=t_end, tstep=tstep, tol=tol, criteria=0, no_tqdm=1)
    t0 = time.perf_counter()
    if not ss.PFlow.run() or not ss.TDS.run():
        raise RuntimeError("ANDES run failed")
    wall = time.perf_counter() - t0
    order = np.argsort(np.array(ss.GENROU.gen.v, dtype=float))
    t = np.array(ss.dae.ts.t)
    return wall, t, np.asarray(ss.dae.ts.x)[:, ss.GENROU.omega.a[order]], ss


def andes_best(raw, dyr, bus, t_end, tstep, tol, numba=True, repeat=REPEAT):
    """Best wall time over `repeat` freshly loaded runs, and the last run's output."""
    runs = [andes_run(raw, dyr, bus, t_end, tstep, tol, numba) for _ in range(repeat)]
    return min(r[0] for r in runs), runs[-1][1], runs[-1][2]


def speed_error(t, w, ref) -> float:
    """Largest |w - reference| (pu) over all machines at the run's own output times, the
    reference (t_ref, w_ref) linearly interpolated (it is 16 or more times finer)."""
    t_ref, w_ref = ref
    k = t <= t_ref[-1] + 1e-9
    return float(
        max(
            np.max(np.abs(w[k, j] - np.interp(t[k], t_ref, w_ref[:, j]))) for j in range(w.shape[1])
        )
    )


def fmt_step(h: float) -> str:
    n = round(1 / h)
    return f"1/{n} s" if abs(1 / n - h) < 1e-12 else f"{h:g} s"


# -- studies -----------------------------------------------------------------------------


def study_sim(files, repeat):
    print(
        f"\n== 20 s simulation, {CYCLES}-cycle bus fault: wall s (best of {repeat}), "
        f"largest speed error against the tool's own converged run (pu)"
    )
    chosen = {}
    for label, raw, dyr, bus in files:
        case = load_psse(raw, dyr, conventions=CONVENTIONS)
        ref_o = ours_run(case, bus, T_END, REF_OURS)
        ref_a = andes_run(raw, dyr, bus, T_END, REF_ANDES, REF_ANDES_TOL)[1:3]
        print(
            f"\n{label}: references stabctl {fmt_step(REF_OURS)}, ANDES {fmt_step(REF_ANDES)} "
            f"tol {REF_ANDES_TOL:g}; the two references differ by "
            f"{speed_error(ref_o[0], ref_o[1], ref_a):.1e} pu (model difference)"
        )
        # the error of every step of the grid, for (b)
        err_o = {}
        for h in GRID:
            try:
                err_o[h] = speed_error(*ours_run(case, bus, T_END, h), ref_o)
            except InputError:  # refused: explicit method, step too large
                err_o[h] = float("inf")
        err_a = {}
        for h in GRID[:-1]:
            try:
                err_a[h] = speed_error(
                    *andes_run(raw, dyr, bus, T_END, h, ANDES_DEFAULT["tol"])[1:3], ref_a
                )
            except RuntimeError:
                err_a[h] = float("inf")
        print("  step      " + "".join(f"{fmt_step(h):>11}" for h in GRID))
        print(
            "  stabctl   "
            + "".join(_err(err_o[h]) for h in GRID)
            + "  (-: step refused, above twice the fastest time constant)"
        )
        print(
            "  ANDES     "
            + "".join(_err(err_a[h]) for h in GRID[:-1])
            + f"  (ANDES tol {ANDES_DEFAULT['tol']:g}; -: run failed)"
        )
        h_o = max((h for h in GRID if err_o[h] <= ACCURACY), default=None)
        h_a = max((h for h in GRID[:-1] if err_a[h] <= ACCURACY), default=None)
        chosen[label] = (h_o, h_a)
        h_def = default_step(case)
        rows = [
            (
                "stabctl",
                f"(a) defaults: step {fmt_step(h_def)}",
                *_ours_timed(case, bus, h_def, ref_o, repeat),
            ),
            (
                "ANDES",
                f"(a) defaults: step {fmt_step(ANDES_DEFAULT['tstep'])}, tol "
                f"{ANDES_DEFAULT['tol']:g}, numba off",
                *_andes_timed(raw, dyr, bus, ANDES_DEFAULT["tstep"], ref_a, repeat, False),
            ),
            (
                "ANDES",
                f"(a) defaults + numba on: step {fmt_step(ANDES_DEFAULT['tstep'])}, "
                f"tol {ANDES_DEFAULT['tol']:g}",
                *_andes_timed(raw, dyr, bus, ANDES_DEFAULT["tstep"], ref_a, repeat, True),
            ),
        ]
        if h_o is not None:
            rows.append(
                (
                    "stabctl",
                    f"(b) error <= {ACCURACY:g} pu: step {fmt_step(h_o)}",
                    *_ours_timed(case, bus, h_o, ref_o, repeat),
                )
            )
        if h_a is not None:
            rows.append(
                (
                    "ANDES",
                    f"(b) error <= {ACCURACY:g} pu: step {fmt_step(h_a)}, tol "
                    f"{ANDES_DEFAULT['tol']:g}, numba on",
                    *_andes_timed(raw, dyr, bus, h_a, ref_a, repeat, True),
                )
            )
        _table(rows)
    return chosen


def _err(e: float) -> str:
    return f"{'-':>11}" if not np.isfinite(e) else f"{e:11.1e}"


def _ours_timed(case, bus, h, ref, repeat):
    ours_run(case, bus, T_END, h)  # compile
    wall, (t, w) = best_of(lambda: ours_run(case, bus, T_END, h), repeat, warm_up=False)
    return wall, speed_error(t, w, ref)


def _andes_timed(raw, dyr, bus, h, ref, repeat, numba):
    if numba:
        andes_run(raw, dyr, bus, 1.5, h, ANDES_DEFAULT["tol"], True)  # compile (cached)
    wall, t, w = andes_best(raw, dyr, bus, T_END, h, ANDES_DEFAULT["tol"], numba, repeat)
    return wall, speed_error(t, w, ref)


def _table(rows):
    print(f"  {'tool':<8} {'settings':<58} {'wall s':>8} {'error pu':>9}")
    for tool, settings, wall, err in rows:
        print(f"  {tool:<8} {settings:<58} {wall:8.3f} {err:9.1e}")


def study_eig(files, repeat):
    print(
        f"\n== Eigenvalues at the power flow: wall s (best of {repeat}); electromechanical "
        "(EM) modes"
    )
    print(
        f"  {'case':<8} {'stabctl s':>9} {'ANDES s':>8} {'EM':>3} {'stabctl err':>11} "
        f"{'vs ANDES (max, median)':>24}"
    )
    for label, raw, dyr, _ in files:
        case = load_psse(raw, dyr, conventions=CONVENTIONS)
        modal_analysis(linearise(case))
        ours, ma = best_of(lambda case=case: modal_analysis(linearise(case)), repeat, warm_up=False)
        fine = modal_analysis(linearise(case, rel_step=1e-6))
        em = ma.eigenvalues[ma.electromechanical]
        em_fine = fine.eigenvalues[fine.electromechanical]
        own = max(np.min(np.abs(em_fine - lam)) / abs(lam) for lam in em)
        walls = []
        for _ in range(repeat):
            ss = andes_load(raw, dyr, None, numba=False)
            t0 = time.perf_counter()
            lam_andes = andes_modes(ss)
            walls.append(time.perf_counter() - t0)
        diff = np.array([np.min(np.abs(lam_andes - lam)) / abs(lam) for lam in em])
        print(
            f"  {label:<8} {ours:9.3f} {min(walls):8.3f} {len(em):3d} {100 * own:10.1e}% "
            f"{100 * diff.max():11.2f} %, {100 * np.median(diff):.2f} %"
        )
    print(
        "  stabctl err: largest relative change of an EM eigenvalue from the default "
        "perturbation 1e-4 to 1e-6; ANDES's Jacobian is symbolic (no step)"
    )


def andes_cct(raw, dyr, bus, tstep, tol):
    """stabctl's search (1 ms lattice, upper bound doubled from 0.1 s) over ANDES runs:
    (CCT s, runs, seconds spent loading and setting up the case for each run)."""
    runs, loading = [0], [0.0]

    def stable(k):
        runs[0] += 1
        t0 = time.perf_counter()
        ss = andes_load(raw, dyr, AndesFault(bus, T_FAULT, T_FAULT + k * TOL_CCT), True)
        loading[0] += time.perf_counter() - t0
        ss.TDS.config.update(tf=T_FAULT + 5.0, tstep=tstep, tol=tol, criteria=0, no_tqdm=1)
        if not ss.PFlow.run() or not ss.TDS.run():
            return False
        delta = np.asarray(ss.dae.ts.x)[:, ss.GENROU.delta.a]
        m = np.asarray(ss.GENROU.M.v) * np.asarray(ss.GENROU.Sn.v)
        return not np.max(np.abs(delta - (delta @ m / m.sum())[:, None])) > np.pi

    lo, hi = 0, 100
    while stable(hi):
        lo, hi = hi, 2 * hi
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo * TOL_CCT, runs[0], loading[0]


def study_cct(files, repeat, chosen):
    print(
        f"\n== {1e3 * TOL_CCT:g} ms CCT of the bus fault by bisection: wall s (stabctl best "
        f"of {repeat}; ANDES one search, whose runs each load and set up the case afresh: "
        "that part shown apart), CCT error against the tool's own fine-step CCT"
    )
    for label, raw, dyr, bus in files:
        sim = Simulator(load_psse(raw, dyr, conventions=CONVENTIONS))
        fault = LineFault(bus, None, T_FAULT)
        ref_o = critical_clearing_time(sim, fault, SearchOptions(tol=TOL_CCT), h=CCT_REF_OURS).cct_s
        ref_a = andes_cct(raw, dyr, bus, CCT_REF_ANDES, REF_ANDES_TOL)[0]
        print(
            f"\n{label}: references stabctl {1e3 * ref_o:.0f} ms ({fmt_step(CCT_REF_OURS)}), "
            f"ANDES {1e3 * ref_a:.0f} ms ({fmt_step(CCT_REF_ANDES)}, tol {REF_ANDES_TOL:g})"
        )
        h_o, h_a = chosen.get(label, (None, None))
        rows = [
            ("stabctl", "(a) defaults", default_step(sim.case)),
            ("ANDES", "(a) defaults, numba on", ANDES_DEFAULT["tstep"]),
        ]
        if h_o:
            rows.append(("stabctl", f"(b) step of <= {ACCURACY:g} pu", h_o))
        if h_a:
            rows.append(("ANDES", f"(b) step of <= {ACCURACY:g} pu, numba on", h_a))
        print(
            f"  {'tool':<8} {'settings':<34} {'step':>9} {'wall s':>8} {'runs':>4} "
            f"{'CCT ms':>7} {'error ms':>8} {'loading s':>9}"
        )
        for tool, what, h in rows:
            if tool == "stabctl":
                critical_clearing_time(sim, fault, SearchOptions(tol=TOL_CCT), h=h)  # compile
                wall, res = best_of(
                    lambda: critical_clearing_time(sim, fault, SearchOptions(tol=TOL_CCT), h=h),
                    repeat,
                    warm_up=False,
                )
                cct, n, ref, load = res.cct_s, res.n_simulations, ref_o, 0.0
            else:
                t0 = time.perf_counter()
                cct, n, load = andes_cct(raw, dyr, bus, h, ANDES_DEFAULT["tol"])
                wall, ref = time.perf_counter() - t0, ref_a
            print(
                f"  {tool:<8} {what:<34} {fmt_step(h):>9} {wall:8.2f} {n:4d} "
                f"{1e3 * cct:7.0f} {1e3 * (cct - ref):+8.0f} {load:9.2f}"
            )


STUDIES = ("sim", "eig", "cct")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", choices=STUDIES, default=list(STUDIES))
    ap.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    ap.add_argument("--repeat", type=int, default=REPEAT, help="timed runs (best of)")
    ap.add_argument(
        "--cct-steps",
        nargs=2,
        type=int,
        default=None,
        metavar=("N_OURS", "N_ANDES"),
        help="with --only cct (no sim study): the (b) steps 1/N_OURS and "
        "1/N_ANDES s found by an earlier sim study",
    )
    args = ap.parse_args()
    andes_defaults_checked()
    import andes

    print(
        f"ANDES {andes.__version__}; ANDES defaults: TDS trapezoid, fixed step "
        f"{fmt_step(ANDES_DEFAULT['tstep'])}, tol {ANDES_DEFAULT['tol']:g}, numba off; "
        f"accuracy for (b): {ACCURACY:g} pu speed; cases read with "
        f"conventions={CONVENTIONS!r}; best of {args.repeat}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        files = [
            (label, *case_files(CASES[label][0], Path(tmp)), CASES[label][1])
            for label in args.cases
        ]
        chosen = {}
        if "sim" in args.only or "cct" in args.only:
            steps = (None, None) if not args.cct_steps else tuple(1 / n for n in args.cct_steps)
            chosen = (
                study_sim(files, args.repeat)
                if "sim" in args.only
                else {label: steps for label, *_ in files}
            )
        if "eig" in args.only:
            study_eig(files, args.repeat)
        if "cct" in args.only:
            study_cct(files, args.repeat, chosen)


if __name__ == "__main__":
    main()
