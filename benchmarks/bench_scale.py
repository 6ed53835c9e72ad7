"""Scale study: stabctl's cost against the size of the system, beside ANDES at ANDES's
defaults (not a test; ANDES needed for the cases read from its case folder).

Systems (smallest to largest): stabctl's built-in Kundur and miniWECC
(``stabctl.io.load_case``); IEEE 39 (ANDES's ``ieee39/ieee39_full.xlsx`` through
``import_andes``, its Toggle left out); NPCC, WECC-179 and N44 (ANDES's PSS/E files through
``load_psse(..., conventions="andes")``, their Toggle records removed; WECC's and N44's
machine saturation set to 0 and N44's STAB2A / IEEET2 removed, as tests/io/test_andes.py,
so that ANDES reads the same data); the GB network (ANDES's ``GBnetwork/GBnetwork.xlsx``,
2224 buses, 394 GENCLS machines whose dynamic data ANDES's README calls "randomly
generated", through ``import_andes``, its two Toggle records left out); ACTIVSg2000 (the
synthetic 2000-bus Texas grid, PSS/E RAW + DYR of tests/data/activsg through
``import_psse(..., on_unsupported="skip", unmodelled="net")`` and ``leave_out_infeasible``,
as docs/cli.md's PSS/E section: 334 machines, 247 exciters, 246 PSS, 18 governors; no ANDES
column, ANDES lacks its GGOV1, EXPIC1, EXAC2 and ESAC6A and nets nothing).  Cases imported
through ANDES, NPCC and N44 are run without PV Q limits (ANDES's default,
``q_limits=False``; the GB power flow does not converge with them in stabctl: worst mismatch
1.4e-3 pu at bus 1282 after 50 iterations).  Fault bus: the largest machine's HV bus, but
see FAULT_BUS.  Kundur's ANDES column is ANDES's own Kundur (kundur_full.xlsx), not
stabctl's built-in data; miniWECC has no ANDES case.

Per system, in a fresh subprocess each (so that its peak RSS is its own; BLAS / OpenMP
limited to one thread in both tools' subprocesses, one core each):

* stabctl: ``Simulator`` set-up (power flow + model + network reduction), then a 20 s run
  with a three-phase bus fault (j1e-4 pu, 1 s to 1.1 s, no line lost) at the step the case
  gets by default (``Simulator.default_h``), wall per simulated second, best of REPEAT,
  compilation excluded (a warm-up run); peak RSS of the subprocess after everything
  (``resource.getrusage``, includes the interpreter, numba and the imports) and the
  tracemalloc peak of building the simulator + one 20 s run (numpy arrays included);
  ``linearise`` (the state matrix, no ESD inputs) + electromechanical modes:
  dense (``modal_analysis``, full eigen-decomposition) up to SPARSE_ABOVE states, above it
  sparse shift-invert (``scipy.sparse.linalg.eigs`` with sigma = j 2 pi f at shifts across
  0.1-2 Hz) — for the largest cases (BOTH_EIG) both are timed; one 1 ms CCT of a bolted fault at the
  same bus (``critical_clearing_time``, no half-step check), one search;
* ANDES 2.0 at its defaults (trapezoid, 1/30 s, tol 1e-4): PFlow + TDS to 20 s with the
  same fault (its stop-at-instability criterion off), numba on if it compiles (else off,
  said), best of ANDES_REPEAT on freshly loaded systems; PFlow + EIG wall.

Then the log-log slope of stabctl's cost against the number of states (least squares).

GB screening on Dask (``--screen N``): N bus faults of the GB network as ``cct_jobs`` (1 ms,
no half-step check) on a local Dask cluster of 2 workers (``run_sweep(scheduler="local")``);
per-job wall from the records; the time of the whole 2224-bus screening on W workers is
extrapolated as T(W) = ceil(2224 / W) * t_job (t_job the mean measured wall of a whole job,
failed ones and each worker's one case load + simulator set-up included; perfect scaling,
no scheduler overhead, each worker one core).

Run: python benchmarks/bench_scale.py [--systems kundur gb ...] [--repeat 3]
     [--andes-repeat 3] [--no-andes] [--screen 6]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from _timing import best_of

T_FAULT, T_CLEAR, T_END, X_FAULT, TOL_CCT = 1.0, 1.1, 20.0, 1e-4, 1e-3
REPEAT, ANDES_REPEAT = 3, 3
SPARSE_ABOVE = 1500  # states: dense eig below, sparse shift-invert above
#: the systems where both are timed (the largest ones: which pays is the question)
BOTH_EIG = ("gb", "activsg2000")
SHIFTS_HZ = (0.2, 0.6, 1.0, 1.4, 1.8)
GB_BUSES = 2224
WORKERS_EXTRAPOLATED = (8, 32, 128)
ANDES_DEFAULT = {"tstep": 1 / 30, "tol": 1e-4}

#: fault buses other than the largest machine's HV bus: there the GB network's machines slip
#: poles and run away (a speed 0.5 pu off synchronous at 9.6 s, NumericalInstabilityError);
#: at bus 1001 the 0.1 s fault separates machines (CCT below 0.1 s) without running away;
#: IEEE 39's largest machine's bus (29): a CCT probe cleared at 352 ms raises a numerical
#: instability (exc.VR.G9 alternating) at h, h/2 and h/4 alike, so bus 16 (the tests');
#: ACTIVSg2000's largest machine's HV bus: machine 205 slips poles and runs away (1.5 pu at
#: 6.4 s; most of its governors, GGOV1, are left out), so the 345 kV bus 2021 of its tests
FAULT_BUS = {
    "gb": 1001,
    "ieee39": 16,
    "activsg2000": 2021,
    "ieee14": 9,
    "ieee14_solar": 9,
    "ieee14_wt3": 9,
    "kundur_wt": 7,
}
#: cases read from ANDES's spreadsheets (its disturbance records left out); the IBR ones
#: (the 1.5x cost-per-state target, docs/scale.md) beside ieee14_full, the same network without them
ANDES_XLSX = {
    "ieee39": ("ieee39/ieee39_full.xlsx", ("Toggle",)),
    "gb": ("GBnetwork/GBnetwork.xlsx", ("Toggle",)),
    "ieee14": ("ieee14/ieee14_full.xlsx", ()),
    "ieee14_solar": ("ieee14/ieee14_solar.xlsx", ("Toggle",)),
    "ieee14_wt3": ("ieee14/ieee14_wt3.xlsx", ("Toggle",)),
    "kundur_wt": ("kundur/kundur_wtdta1.xlsx", ("Toggle", "Fault")),
}
SYSTEMS = (
    "kundur",
    "ieee39",
    "npcc",
    "miniwecc",
    "wecc179",
    "n44",
    "gb",
    "activsg2000",
    "ieee14",
    "ieee14_solar",
    "ieee14_wt3",
    "kundur_wt",
)
#: today's cases, against which the IBR cases' cost per state and step is compared
TODAY = ("kundur", "miniwecc")
IBR = ("ieee14_solar", "ieee14_wt3", "kundur_wt")
ACTIVSG = Path(__file__).parents[1] / "tests" / "data" / "activsg"


def _cases_dir() -> Path:
    import andes

    return Path(andes.__file__).parent / "cases"


def _psse(folder, raw, dyr, work, drop=("TOGGLE",), unsaturated=False):
    from stabctl.io.andes import strip_dyr

    src = _cases_dir() / folder
    out = Path(work) / f"{folder}.dyr"
    strip_dyr(src / dyr, out, set(drop), unsaturated=unsaturated)
    return src / raw, out


def load_system(label: str, work: str):
    """(case, q_limits, fault bus or None = the largest machine's HV bus, ANDES files
    (path, dyr, off) or None)."""
    from stabctl.io import load_case
    from stabctl.io.andes_case import import_andes
    from stabctl.io.psse import load_psse

    if label == "activsg2000":
        return _activsg2000(work), True, FAULT_BUS[label], None
    if label in ("kundur", "miniwecc"):
        andes_files = None
        if label == "kundur":  # ANDES's own Kundur (its data, not stabctl's built-in)
            andes_files = (_cases_dir() / "kundur" / "kundur_full.xlsx", None, ("Toggle",))
        return load_case(label), True, None, andes_files
    if label in ANDES_XLSX:
        name, off = ANDES_XLSX[label]
        path = _cases_dir() / name
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "left out Toggle"
            case = import_andes(path, on_unsupported="skip")
        return case, False, FAULT_BUS.get(label), (path, None, off)
    raw, dyr = {
        "npcc": lambda: _psse("npcc", "npcc.raw", "npcc_full.dyr", work),
        "wecc179": lambda: _psse("wecc", "wecc.raw", "wecc_full.dyr", work, unsaturated=True),
        "n44": lambda: _psse(
            "nordic44",
            "N44_BC.raw",
            "N44_BC.dyr",
            work,
            drop=("STAB2A", "IEEET2", "TOGGLE"),
            unsaturated=True,
        ),
    }[label]()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        case = load_psse(raw, dyr, conventions="andes", on_unsupported="skip")
    return case, label != "n44" and label != "npcc", None, (raw, dyr, ())


def _activsg2000(work: str):
    """ACTIVSg2000 imported as docs/cli.md's PSS/E section does (files uncompressed in work)."""
    import gzip
    import shutil

    from stabctl.dynamics.infeasible import leave_out_infeasible
    from stabctl.io.psse import import_psse

    paths = []
    for name in ("ACTIVSg2000.RAW", "ACTIVSg2000.dyr"):
        with gzip.open(ACTIVSG / f"{name}.gz", "rb") as src, open(Path(work) / name, "wb") as dst:
            shutil.copyfileobj(src, dst)
        paths.append(Path(work) / name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the records left out and the generators netted
        case = import_psse(*paths, on_unsupported="skip", unmodelled="net").case
    return leave_out_infeasible(case)[0]


def fault_bus(case) -> int:
    """The HV bus of the largest machine (MVA), so that the 1 ms CCT is below 1 s."""
    from stabctl.storage.devices import hv_bus

    k = int(case.machines.number[int(np.argmax(case.machines.mva))])
    return int(hv_bus(case, k))


# -- stabctl (in its own subprocess) -----------------------------------------------------


def em_modes_sparse(A: np.ndarray, n_em: int):
    """Eigenvalues near j 2 pi f for f in SHIFTS_HZ by shift-invert Arnoldi on sparse A,
    about n_em / len(SHIFTS_HZ) + 4 per shift, merged (the 0.1-2 Hz band)."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import eigs

    As = sp.csc_matrix(A, dtype=complex)  # complex shift: complex arithmetic
    k = max(6, math.ceil(1.5 * n_em / len(SHIFTS_HZ)) + 4)
    found = []
    for f in SHIFTS_HZ:
        found.append(
            eigs(As, k=min(k, A.shape[0] - 2), sigma=2j * np.pi * f, return_eigenvectors=False)
        )
    lam = np.concatenate(found)
    lam = lam[(lam.imag >= 2 * np.pi * 0.1) & (lam.imag <= 2 * np.pi * 2.0)]
    return np.unique(np.round(lam, 6))


def ours(label: str, repeat: int) -> dict:
    import tracemalloc

    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import Fault
    from stabctl.errors import NumericalInstabilityError, SimulationError
    from stabctl.smallsignal.linearise import active_states, linearise
    from stabctl.smallsignal.modal import modal_analysis
    from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time

    with tempfile.TemporaryDirectory() as work:
        case, q_limits, bus, _ = load_system(label, work)
    bus = fault_bus(case) if bus is None else bus
    Simulator(case, q_limits=q_limits)  # loads the compiled kernels
    t = time.perf_counter()
    sim = Simulator(case, q_limits=q_limits)
    setup = time.perf_counter() - t
    events = [Fault(bus, T_FAULT, T_CLEAR, x=X_FAULT)]
    sim.run(events, 1.5)  # compile
    wall, res = best_of(lambda: sim.run(events, T_END), repeat, warm_up=False)
    n_steps = len(res.t) - 1
    tracemalloc.start()
    Simulator(case, q_limits=q_limits).run(events, T_END)
    traced = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    out = {
        "label": label,
        "buses": int(case.n_bus),
        "machines": len(case.machines),
        "h": sim.default_h,
        "setup_s": setup,
        "run_s": wall,
        "stable": bool(res.stable),
        "traced_mb": traced / 2**20,
        "fault_bus": bus,
        "us_per_step": 1e6 * wall / n_steps,
    }
    out["states"] = int(np.count_nonzero(active_states(sim.model)))
    try:
        linearise(sim, esd_buses=())  # compile
    except SimulationError as exc:  # e.g. a kink at the operating point (docs/modal.md)
        out["lin_error"] = str(exc)[:200]
        return _with_rss(out)
    t = time.perf_counter()
    sys_ = linearise(sim, esd_buses=())
    lin = time.perf_counter() - t
    n = sys_.nstates
    if n <= SPARSE_ABOVE or label in BOTH_EIG:
        t = time.perf_counter()
        ma = modal_analysis(sys_)
        out["dense_s"] = time.perf_counter() - t
        out["n_em"] = int(len(ma.electromechanical))
        em = ma.eigenvalues[ma.electromechanical]
    if n > SPARSE_ABOVE or label in BOTH_EIG:
        t = time.perf_counter()
        lam = em_modes_sparse(np.asarray(sys_.A), out.get("n_em", n // 4))
        out["sparse_s"] = time.perf_counter() - t
        out["n_sparse"] = int(lam.size)
        if "n_em" in out:  # how many of the dense EM modes the shifts found
            out["sparse_found"] = int(
                sum(
                    np.min(np.abs(lam - e)) < 1e-4 * abs(e)
                    for e in em
                    if 0.1 <= e.imag / 2 / np.pi <= 2.0
                )
            )
            out["dense_em_in_band"] = int(sum(0.1 <= e.imag / 2 / np.pi <= 2.0 for e in em))
    out["lin_s"] = lin
    out["eig_method"] = "dense" if n <= SPARSE_ABOVE else "sparse shift-invert"
    for h in sim.default_h / np.array([1, 2, 4]):  # a finer step if a probe blows up
        try:
            t = time.perf_counter()
            cct = critical_clearing_time(
                sim,
                LineFault(bus, None, T_FAULT),
                SearchOptions(tol=TOL_CCT, error_check=False),
                h=h,
            )
            out.update(
                cct_s=time.perf_counter() - t,
                cct_ms=1e3 * cct.cct_s,
                cct_runs=cct.n_simulations,
                cct_h=h,
            )
            out.pop("cct_error", None)
            break
        except NumericalInstabilityError as exc:
            out["cct_note"] = f"at step {h:.5f} s: {exc}"[:170] + "..."
            out["cct_error"] = "a probe numerically unstable at h, h/2 and h/4"
        except Exception as exc:  # noqa: BLE001 - reported in the table, e.g. CCT > t_max
            out["cct_error"] = f"{type(exc).__name__}: {exc}"[:200]
            break
    return _with_rss(out)


def _with_rss(out: dict) -> dict:
    """out with this process's peak RSS (MB) added."""
    import resource

    out["rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return out


# -- ANDES (in its own subprocess) -------------------------------------------------------


def andes(label: str, repeat: int) -> dict:
    from stabctl.io.andes import AndesFault, andes_modes, andes_system

    with tempfile.TemporaryDirectory() as work:
        case, _, bus, files = load_system(label, work)
        if files is None:
            return {"label": label, "andes_error": "no ANDES case"}
        bus = fault_bus(case) if bus is None else bus
        path, dyr, off = files
        out = {"label": label}

        def tds(numba, t_end=T_END):
            ss = andes_system(
                path,
                dyr,
                AndesFault(bus, T_FAULT, T_CLEAR, x=X_FAULT),
                config_option=[f"Runtime.numba={int(numba)}"],
                off=off,
            )
            ss.TDS.config.update(tf=t_end, criteria=0, no_tqdm=1)
            t = time.perf_counter()
            if not ss.PFlow.run():
                raise RuntimeError(
                    "ANDES power flow did not converge (PFlow.run() False, "
                    f"{ss.PFlow.config.max_iter} iterations at most)"
                )
            if not ss.TDS.run():
                raise RuntimeError("ANDES TDS failed")
            return time.perf_counter() - t

        numba = True
        try:
            tds(True, 1.5)  # numba compile (cached)
        except RuntimeError as exc:
            out["andes_error"] = str(exc)
            return out
        except Exception:  # noqa: BLE001 - numba fails to compile: ANDES's default, off
            numba = False
        out["numba"] = numba
        try:
            out["andes_tds_s"] = min(tds(numba) for _ in range(repeat))
        except RuntimeError as exc:
            out["andes_error"] = str(exc)
        try:
            ss = andes_system(path, dyr, off=off)
            t = time.perf_counter()
            lam = andes_modes(ss)
            out["andes_eig_s"] = time.perf_counter() - t
            out["andes_states"] = int(lam.size)
        except RuntimeError as exc:
            out.setdefault("andes_error", str(exc))
    return out


# -- GB screening on Dask ----------------------------------------------------------------


def screen_gb(n_jobs: int, workers: int = 2) -> dict:
    from stabctl.io.pst import write_case_json
    from stabctl.parallel import run_sweep
    from stabctl.stability.cct import LineFault, cct_jobs

    with tempfile.TemporaryDirectory() as work:
        case, q_limits, _, _ = load_system("gb", work)
        path = write_case_json(case, Path(work) / "gb.json")
        buses = [int(b) for b in case.buses.number[:: max(1, case.n_bus // n_jobs)][:n_jobs]]
        t = time.perf_counter()
        jobs = cct_jobs(
            str(path),
            [LineFault(b, None, T_FAULT) for b in buses],
            tol=TOL_CCT,
            q_limits=q_limits,
            error_check=False,
        )
        prepare = time.perf_counter() - t
        t = time.perf_counter()
        rep = run_sweep(
            jobs, Path(work) / "gb.jsonl", workers=workers, scheduler="local", progress=False
        )
        wall = time.perf_counter() - t
        t = time.perf_counter()
        from stabctl.dynamics.driver import Simulator

        Simulator(case, q_limits=q_limits)
        setup = time.perf_counter() - t
    recs = list(rep.records.values())
    ok = [r for r in recs if r["status"] == "ok"]
    return {
        "jobs": len(recs),
        "ok": len(ok),
        "wall_s": wall,
        "prepare_s": prepare,
        "setup_s": setup,
        "per_job_s": [r["result"]["wall_time_s"] for r in ok],
        "job_wall_s": [r["wall_time_s"] for r in recs if r["wall_time_s"] is not None],
        "runs": [r["result"]["n_simulations"] for r in ok],
        "cct_ms": [1e3 * r["result"]["cct_s"] for r in ok],
        "failed": [f"{r['key']}: {r.get('error', '')[:150]}" for r in recs if r["status"] != "ok"],
    }


# -- the table ---------------------------------------------------------------------------


def _sub(part: str, label: str, repeat: int) -> dict:
    cmd = [sys.executable, __file__, "--part", part, "--systems", label, "--repeat", str(repeat)]
    one_core = {v: "1" for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    p = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, **one_core})
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
    if p.returncode or not lines:
        return {"label": label, f"{part}_error": (p.stderr.strip().splitlines() or ["?"])[-1]}
    return json.loads(lines[-1])


def _f(x, fmt="{:.2f}", missing="-"):
    return missing if x is None else fmt.format(x)


def table(rows, andes_rows, repeat, andes_repeat):
    print(
        f"\nstabctl: 20 s run, bus fault j{X_FAULT:g} pu {T_FAULT:g}-{T_CLEAR:g} s, the "
        f"case's default step, best of {repeat}, compile excluded; ANDES 2.0 at its "
        f"defaults (trapezoid 1/30 s, tol 1e-4), best of {andes_repeat}"
    )
    head = (
        f"{'system':<9}{'buses':>6}{'mach':>5}{'states':>7}{'step':>7}{'setup s':>8}"
        f"{'s/sim s':>8}{'us/step':>8}{'RSS MB':>7}{'trace MB':>9}{'lin s':>7}{'EM s':>7}"
        f"{'EM':>4}"
        f"{'CCT s':>7}{'CCT ms':>7}{'runs':>5}{'ANDES s/sim s':>14}{'ANDES EIG s':>12}"
    )
    print(head)
    for r, a in zip(rows, andes_rows):
        em_s = r.get("dense_s") if r.get("eig_method") == "dense" else r.get("sparse_s")
        andes_tds = a.get("andes_tds_s")
        print(
            f"{r['label']:<9}{r.get('buses', 0):6d}{r.get('machines', 0):5d}"
            f"{r.get('states', 0):7d}{_f(r.get('h'), '{:.4f}'):>7}"
            f"{_f(r.get('setup_s')):>8}{_f(r.get('run_s') and r['run_s'] / T_END, '{:.3f}'):>8}"
            f"{_f(r.get('us_per_step'), '{:.0f}'):>8}{_f(r.get('rss_mb'), '{:.0f}'):>7}"
            f"{_f(r.get('traced_mb'), '{:.1f}'):>9}"
            f"{_f(r.get('lin_s')):>7}{_f(em_s):>7}{r.get('n_em', r.get('n_sparse', 0)):4d}"
            f"{_f(r.get('cct_s')):>7}{_f(r.get('cct_ms'), '{:.0f}'):>7}"
            f"{r.get('cct_runs', 0):5d}"
            f"{_f(andes_tds and andes_tds / T_END, '{:.3f}'):>14}"
            f"{_f(a.get('andes_eig_s')):>12}"
        )
    for r, a in zip(rows, andes_rows):
        notes = [f"{k}: {v}" for k, v in {**r, **a}.items() if k.endswith(("error", "note"))]
        if r.get("cct_h") and r["cct_h"] != r["h"]:
            notes.append(f"CCT at step {r['cct_h']:.5f} s")
        if "numba" in a:
            notes.append(
                f"ANDES numba {'on' if a['numba'] else 'off (did not compile)'}, "
                f"{a.get('andes_states', '?')} states"
            )
        if r.get("sparse_s") is not None:
            notes.append(
                f"EM modes: dense {_f(r.get('dense_s'))} s, sparse shift-invert at "
                f"{len(SHIFTS_HZ)} shifts {_f(r['sparse_s'])} s "
                f"({r.get('sparse_found', '?')} of {r.get('dense_em_in_band', '?')} "
                f"dense EM modes in 0.1-2 Hz found)"
            )
        if "run_s" in r:
            notes.append(
                f"20 s run {r['run_s']:.2f} s, fault bus {r['fault_bus']}, "
                f"{'stable' if r['stable'] else 'unstable'}"
            )
        print(f"  {r['label']}: " + "; ".join(notes))
    ok = [r for r in rows if "run_s" in r and r.get("states")]
    if len(ok) >= 2:
        for what, key in (
            ("20 s run", "run_s"),
            ("20 s run per step", "us_per_step"),
            ("set-up", "setup_s"),
            ("CCT", "cct_s"),
            ("linearise", "lin_s"),
        ):
            pts = [(np.log(r["states"]), np.log(r[key])) for r in ok if r.get(key)]
            if len(pts) >= 2:
                x, y = np.array(pts).T
                print(f"log-log slope of {what} wall against states: {np.polyfit(x, y, 1)[0]:.2f}")
    per_state_table(ok)


def per_state_table(ok) -> None:
    """Cost per state and step of each run, and of the IBR cases against today's (the
    target: at most 1.5 times)."""
    cost = {r["label"]: r["us_per_step"] / r["states"] for r in ok}
    today = {k: cost[k] for k in TODAY if k in cost}
    print("\ncost per state and step (20 s run, µs):")
    for k, c in cost.items():
        vs = ", ".join(f"{c / t:.2f} x {name}'s" for name, t in today.items())
        print(f"  {k:<13}{c:8.3f}" + (f"  ({vs})" if vs and k in IBR else ""))
    if not today:
        print("  (run kundur and miniwecc too for the IBR target)")


def screening_table(s: dict) -> None:
    t = np.array(s["per_job_s"])
    print(
        f"\nGB bus-fault screening on a local Dask cluster of 2 workers: {s['jobs']} jobs "
        f"(1 ms CCT, no half-step check), {s['ok']} ok, wall {s['wall_s']:.1f} s "
        f"(cluster start + worker set-up included); job preparation in the parent "
        f"{s['prepare_s']:.1f} s"
    )
    if t.size:
        print(
            f"per-job wall (CCT search): mean {t.mean():.1f} s, min {t.min():.1f}, max "
            f"{t.max():.1f} ({np.mean(s['runs']):.1f} runs per search; CCTs "
            f"{', '.join(f'{c:.0f}' for c in s['cct_ms'])} ms); whole jobs (a worker's "
            f"first includes its case load and set-up) "
            f"{', '.join(f'{x:.1f}' for x in s['job_wall_s'])} s; simulator set-up "
            f"{s['setup_s']:.1f} s"
        )
        t_job = float(np.mean(s["job_wall_s"]))
        ideal = math.ceil(s["jobs"] / 2) * t_job
        print(
            f"extrapolated whole screening ({GB_BUSES} buses), T(W) = ceil({GB_BUSES}/W) * "
            f"t_job, t_job = {t_job:.1f} s the mean whole-job wall (failed jobs and each "
            f"worker's one set-up included); measured here {s['wall_s']:.1f} s against "
            f"T(2) = {ideal:.1f} s for {s['jobs']} jobs (the rest: cluster start, uneven "
            f"finish)"
        )
        for w in (1, 2, *WORKERS_EXTRAPOLATED):
            print(f"  W = {w:4d}: {math.ceil(GB_BUSES / w) * t_job / 60:8.1f} min")
    for f in s["failed"]:
        print(f"  failed: {f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--systems", nargs="+", choices=SYSTEMS, default=list(SYSTEMS))
    ap.add_argument("--repeat", type=int, default=REPEAT)
    ap.add_argument("--andes-repeat", type=int, default=ANDES_REPEAT)
    ap.add_argument("--no-andes", action="store_true")
    ap.add_argument(
        "--screen",
        type=int,
        default=0,
        metavar="N",
        help="GB bus faults to screen on a local Dask cluster (0: none)",
    )
    ap.add_argument("--part", choices=("ours", "andes"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.part:  # the subprocess of one system
        fn = ours if args.part == "ours" else andes
        print(json.dumps(fn(args.systems[0], args.repeat)))
        return
    rows, andes_rows = [], []
    for label in args.systems:
        rows.append(_sub("ours", label, args.repeat))
        andes_rows.append({} if args.no_andes else _sub("andes", label, args.andes_repeat))
        print(json.dumps([rows[-1], andes_rows[-1]]), flush=True)
    table(rows, andes_rows, args.repeat, args.andes_repeat)
    if args.screen:
        screening_table(screen_gb(args.screen))


if __name__ == "__main__":
    main()
