"""stabctl against ANDES 2.0 on the same PSS/E cases and fault (not a test; needs
``pip install "stabctl[andes]"``).

Cases: ANDES's Kundur (kundur.raw + kundur_full.dyr without its Toggle record) and
WECC-179 (wecc.raw + wecc_full.dyr, GENROU saturation set to 0), imported by
``stabctl.psse.load_psse`` with ``conventions="andes"`` (ANDES's reading of GENROU,
EXDC2 and IEEEG1, so that both tools solve the same equations) and read by ANDES from the
same files (``stabctl.andes_xval``). Fault: three-phase at one bus through j1e-4 pu from
t = 1 s, cleared after 6 cycles without loss of a line; fixed step 5 ms in both tools.

Prints one table per study with each tool's wall time and the ratio ANDES / stabctl:

* ``sim``: 20 s simulation (stabctl: power flow + model + run, best of 3 after a warm-up
  that compiles; ANDES: power flow + time-domain run, not stopped at loss of synchronism,
  on a freshly loaded system, best of 2; loading and code set-up excluded for both), and
  each tool's verdict at 20 s (a rotor angle more than pi from the centre of inertia);
* ``eig``: linearisation and eigenvalues (stabctl ``linearise`` + ``modal_analysis``;
  ANDES ``PFlow`` + ``EIG``), and the largest relative difference between each of
  stabctl's electromechanical eigenvalues and ANDES's nearest one;
* ``cct``: 1 ms critical clearing time by bisection (stabctl
  ``cct.critical_clearing_time``, a bolted fault; ANDES the same bisection over repeated
  runs to 5 s after the fault, fault j1e-4 pu, unstable when a rotor angle leaves the
  centre of inertia by more than pi or the run breaks down);
* ``scaling``: stabctl's 20 s run on kundur (PST data), miniwecc (PST data) and WECC-179,
  and stabctl and ANDES on WECC-179 for 5, 10, 20, 40 s simulated, with the peak Python
  memory of one run (tracemalloc, numpy buffers included; stabctl: model and run, ANDES:
  loading, set-up and run).

ANDES runs with its default configuration (equations not compiled with numba).

Run: python benchmarks/bench_andes.py [--only sim eig cct scaling]
"""

import argparse
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from _timing import best_of
from stabctl.andes_xval import (AndesFault, andes_modes, andes_separated, andes_speeds,
                                andes_stable, andes_system, strip_dyr)
from stabctl.case import load_case
from stabctl.cct import LineFault, critical_clearing_time
from stabctl.events import Fault
from stabctl.linearise import linearise
from stabctl.modal import modal_analysis
from stabctl.psse import load_psse
from stabctl.simulation import Simulator

STEP, T_FAULT, CYCLES, TOL = 0.005, 1.0, 6, 0.001
CONVENTIONS = "andes"
CASES = (("kundur", "kundur", 7), ("wecc179", "wecc", 1))  # label, ANDES folder, fault bus


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


def ours_run(case, bus, t_end, clear=CYCLES / 60):
    sim = Simulator(case)
    return sim.run([Fault(bus, T_FAULT, T_FAULT + clear, x=1e-4)], t_end, h=STEP)


def andes_timed(raw, dyr, bus, t_end, clear=CYCLES / 60):
    """Wall time of PFlow + TDS to t_end (not stopped at loss of synchronism) on a freshly
    loaded system, and its result."""
    ss = andes_system(raw, dyr, AndesFault(bus, T_FAULT, T_FAULT + clear))
    ss.TDS.config.criteria = 0
    t0 = time.perf_counter()
    out = andes_speeds(ss, t_end, STEP)
    return time.perf_counter() - t0, ss, out


def row(*cells):
    print("  ".join(f"{c:>12}" if not isinstance(c, float) else f"{c:12.3f}" for c in cells))


def study_sim(files):
    print("\n20 s simulation, 6-cycle bus fault (wall s; verdict at 20 s)")
    row("case", "stabctl", "ANDES", "ANDES/ours", "stabctl", "ANDES")
    for label, (raw, dyr), bus in files:
        case = load_psse(raw, dyr, conventions=CONVENTIONS)
        verdict = ours_run(case, bus, 20.0).stable  # and compile
        ours, _ = best_of(lambda: ours_run(case, bus, 20.0), 3, warm_up=False)
        runs = [andes_timed(raw, dyr, bus, 20.0) for _ in range(2)]
        theirs = min(r[0] for r in runs)
        row(label, ours, theirs, theirs / ours, _word(verdict),
            _word(not andes_separated(runs[0][1])))


def _word(stable: bool) -> str:
    return "stable" if stable else "unstable"


def study_eig(files):
    print("\nEigenvalues at the power flow (wall s; electromechanical modes)")
    row("case", "stabctl", "ANDES", "ANDES/ours", "n modes EM", "max rel diff")
    for label, (raw, dyr), _ in files:
        case = load_psse(raw, dyr, conventions=CONVENTIONS)
        modal_analysis(linearise(case))
        ours, _ = best_of(lambda: modal_analysis(linearise(case)), 3, warm_up=False)
        ss = andes_system(raw, dyr)
        t0 = time.perf_counter()
        lam_andes = andes_modes(ss)
        theirs = time.perf_counter() - t0
        ma = modal_analysis(linearise(case))
        em = ma.eigenvalues[ma.electromechanical]
        diff = max(np.min(np.abs(lam_andes - lam)) / abs(lam) for lam in em)
        row(label, ours, theirs, theirs / ours, len(em), f"{100 * diff:.2f} %")


def andes_cct(raw, dyr, bus):
    """stabctl's search (1 ms lattice, upper bound doubled from 0.1 s) over ANDES runs:
    (CCT s, runs)."""
    runs = [0]

    def stable(k):
        runs[0] += 1
        fault = AndesFault(bus, T_FAULT, T_FAULT + k * TOL)
        return andes_stable(raw, dyr, fault, T_FAULT + 5.0, STEP)

    lo, hi = 0, 100
    while stable(hi):
        lo, hi = hi, 2 * hi
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo * TOL, runs[0]


def study_cct(files):
    print("\n1 ms CCT of the bus fault (bisection)")
    row("case", "stabctl s", "runs", "CCT ms", "ANDES s", "runs", "CCT ms", "ANDES/ours")
    for label, (raw, dyr), bus in files:
        sim = Simulator(load_psse(raw, dyr, conventions=CONVENTIONS))
        fault = LineFault(bus, None, T_FAULT)
        critical_clearing_time(sim, fault, tol=TOL, h=STEP)  # compile
        t0 = time.perf_counter()
        res = critical_clearing_time(sim, fault, tol=TOL, h=STEP)
        ours = time.perf_counter() - t0
        t0 = time.perf_counter()
        cct, n = andes_cct(raw, dyr, bus)
        theirs = time.perf_counter() - t0
        row(label, ours, res.n_simulations, 1e3 * res.cct_s, theirs, n, 1e3 * cct, theirs / ours)


def peak_mib(fn) -> float:
    tracemalloc.start()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak / 2**20


def study_scaling(files):
    print("\nstabctl 20 s run vs system size (wall s, peak MiB)")
    row("case", "buses", "machines", "wall s", "peak MiB")
    pst = [("kundur (PST)", load_case("kundur"), 3), ("miniwecc (PST)", load_case("miniwecc"), 83)]
    ours = [(label, load_psse(raw, dyr, conventions=CONVENTIONS), bus)
            for label, (raw, dyr), bus in files]
    for label, case, bus in pst + ours:
        ours_run(case, bus, 20.0)
        wall, _ = best_of(lambda: ours_run(case, bus, 20.0), 3, warm_up=False)
        mem = peak_mib(lambda: ours_run(case, bus, 20.0))
        row(label, case.n_bus, len(case.machines), wall, mem)
    label, (raw, dyr), bus = files[-1]
    case = load_psse(raw, dyr, conventions=CONVENTIONS)
    print(f"\n{label}: wall s and peak MiB vs simulated time")
    row("t_end s", "stabctl s", "ANDES s", "ANDES/ours", "stabctl MiB", "ANDES MiB")
    for t_end in (5.0, 10.0, 20.0, 40.0):
        ours_s, _ = best_of(lambda: ours_run(case, bus, t_end), 3, warm_up=False)
        theirs_s = andes_timed(raw, dyr, bus, t_end)[0]
        ours_m = peak_mib(lambda: ours_run(case, bus, t_end))
        theirs_m = peak_mib(lambda: andes_timed(raw, dyr, bus, t_end))
        row(t_end, ours_s, theirs_s, theirs_s / ours_s, ours_m, theirs_m)


STUDIES = {"sim": study_sim, "eig": study_eig, "cct": study_cct, "scaling": study_scaling}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", choices=list(STUDIES), default=list(STUDIES))
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        files = [(label, case_files(folder, Path(tmp)), bus) for label, folder, bus in CASES]
        for name in args.only:
            STUDIES[name](files)


if __name__ == "__main__":
    main()
