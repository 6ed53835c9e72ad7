"""ACTIVSg2000's 20 s fault per integration method and step, against the target of 1.3 s
in-run on one core (not a test).

ACTIVSg2000 is imported as docs/cli.md's PSS/E section (``import-psse ... --net-unmodelled``,
`bench_scale._activsg2000`).  Its EXAC2 at bus 1079 (K_A = 1000, T_A = 0.05 s) has a
regulator-exciter mode that Heun's method keeps stable only below 4.85 ms: with the fast
exciter loops in sub-intervals (the default, `stabctl.dynamics.subinterval`) the default
step (`Simulator.default_h`) is half a cycle and 18 EXAC2 take sub-steps of their own;
without them (the ``heun-single`` rows, ``subintervals=False``) 1.2 ms.

Fault: bench_scale's, j1e-4 pu at bus 2021 from 1.0 s to 1.1 s, no line lost, 20 s.  Per
setting: the in-run wall (``meta`` wall of the run, best of --repeat after a warm-up run of
1.15 s that compiles), and the largest difference over the run from the converged reference
(Heun at REF_STEP) of the machines' angles from their centre of inertia (rad) and of their
speeds (pu), at the reference's grid points that the run shares (all of them for the steps
below).  The trapezoid's own step-halving difference is the 1/60 s row's difference from
the 1/120 s row, printed below the table.

Run (one core, as bench_scale): OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
    python benchmarks/bench_activsg.py [--repeat 1] [--methods heun trapezoid] [--tf 20]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings

import numpy as np
from bench_scale import _activsg2000

from stabctl.dynamics.coi import coi_of_islands
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.errors import InputError

BUS, T_FAULT, T_CLEAR, X_FAULT, T_END = 2021, 1.0, 1.1, 1e-4, 20.0
TARGET_S = 1.3
#: the converged reference: Heun without sub-intervals at 1/600 s (under half Heun's
#: 4.85 ms stability limit of this case)
REF_STEP = 1 / 600
#: (method, step s or None for the default): heun with the fast exciter loops in
#: sub-intervals (the default), heun-single without (`Simulator(subintervals=False)`)
SETTINGS = (
    ("heun", None),
    ("heun", 1 / 240),
    ("heun-single", None),
    ("trapezoid", 1 / 120),
    ("trapezoid", 1 / 60),
)


def _key(t) -> np.ndarray:
    """Grid times as integers of 1/2400 s (every step here divides into them)."""
    return np.round(np.asarray(t) * 2400).astype(np.int64)


def _relative_angles(sim, res) -> np.ndarray:
    return res.angle - np.array([coi_of_islands(a, sim.inertia, sim.island) for a in res.angle])


def _difference(sim, res, ref) -> tuple[float, float]:
    """(largest angle-from-COI difference rad, largest speed difference pu) at shared times."""
    k, kr = _key(res.t), _key(ref.t)
    _, i, j = np.intersect1d(k, kr, return_indices=True)
    da = np.max(np.abs(_relative_angles(sim, res)[i] - _relative_angles(sim, ref)[j]))
    dw = np.max(np.abs(res.speed[i] - ref.speed[j]))
    return float(da), float(dw)


def run(sim, events, method, h, repeat, tf=T_END):
    """(best in-run wall s, result) of `repeat` runs of tf s after a warm-up (Heun's
    without the bus voltages, which the comparison does not read)."""
    voltages = method != "heun"
    sim.run(events, 1.15, h=h, method=method, voltages=voltages)
    best, res = np.inf, None
    for _ in range(repeat):
        res = sim.run(events, tf, h=h, method=method, voltages=voltages)
        best = min(best, res.meta["wall_time_s"])
    return best, res


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument(
        "--methods",
        nargs="+",
        choices=("heun", "heun-single", "trapezoid"),
        default=["heun", "heun-single", "trapezoid"],
        help="the rows to run (the trapezoid's take minutes: about 7 solves of its 6467-state "
        "sparse matrix a step after the fault and some 40 matrices, docs/cli.md)",
    )
    ap.add_argument(
        "--tf",
        type=float,
        default=T_END,
        help=f"the runs' end (s; default {T_END:g}): the trapezoid's 20 s rows take 2-6 minutes",
    )
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        case = _activsg2000(work)
    sim, single = Simulator(case), Simulator(case, subintervals=False)
    events = [Fault(BUS, T_FAULT, T_CLEAR, x=X_FAULT)]
    print(
        f"ACTIVSg2000, fault j{X_FAULT:g} pu at bus {BUS} {T_FAULT}-{T_CLEAR} s, {args.tf:g} s run,"
        f" best of {args.repeat}; default step {sim.default_h * 1e3:.3f} ms ({sim.fastest[1]}),"
        f" {single.default_h * 1e3:.3f} ms without sub-intervals ({single.fastest[1]});"
        f" reference Heun without sub-intervals at {REF_STEP * 1e3:.3f} ms; target {TARGET_S} s"
        " in-run"
    )
    t = time.perf_counter()
    ref = single.run(events, args.tf, h=REF_STEP, voltages=False)
    print(f"reference run: {time.perf_counter() - t:.1f} s wall")
    print(
        f"{'method':10} {'step ms':>8} {'wall s':>8} {'vs target':>9} {'d angle rad':>12} "
        f"{'d speed pu':>11}"
    )
    results = {}
    for method, h in SETTINGS:
        if method not in args.methods:
            continue
        who = single if method == "heun-single" else sim
        step = who.default_h if h is None else h
        try:
            wall, res = run(who, events, method.split("-")[0], step, args.repeat, args.tf)
        except InputError as err:
            print(f"{method:10} {step * 1e3:8.3f}  refused: {err}")
            continue
        results[(method, h)] = res
        da, dw = _difference(sim, res, ref)
        print(
            f"{method:10} {step * 1e3:8.3f} {wall:8.2f} {wall / TARGET_S:8.1f}x {da:12.2e} "
            f"{dw:11.2e}"
        )
    coarse, fine = results.get(("trapezoid", 1 / 60)), results.get(("trapezoid", 1 / 120))
    if coarse is not None and fine is not None:
        da, dw = _difference(sim, coarse, fine)
        print(f"trapezoid 1/60 s against 1/120 s (its halved step): {da:.2e} rad, {dw:.2e} pu")


if __name__ == "__main__":
    warnings.simplefilter("ignore")
    main()
