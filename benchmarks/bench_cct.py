"""Wall time and number of simulations of one CCT search per case and model conventions
(not a test).

Searches (defaults of `stabctl.stability.cct.critical_clearing_time`: tol 1 ms, t_end = fault + 5 s,
stop at separation, each convention's default step) for the paper's Case 2 fault
(miniWECC, bus 83, line 83-33, at 1 s) and Case 1 fault (Kundur, bus 3, line 3-101, at
1 s), pinned to one core, after a warm-up run (compilation and the power flow excluded;
the Simulator build is printed apart).  Each convention twice: without the numerical
error bar (the bisection alone, as before the error bar existed) and with it (the default:
the bracket rerun at half the step).  Target: the ieee default with its error bar at most
2x the pstess search without it (Kundur 0.1 s, miniWECC 1.7 s before), miniWECC <= 3 s.
Run: python benchmarks/bench_cct.py
"""

import os
import time

from stabctl.dynamics.driver import Simulator
from stabctl.io import load_case
from stabctl.stability.cct import SearchOptions, critical_clearing_time
from stabctl.studies.cases import CASE1, CASE2

SEARCHES = (  # case, fault, target s (None: no target), label
    ("miniwecc", CASE2.fault, 3.0, "Case 2: bus 83, line 83-33"),
    ("kundur", CASE1.fault, None, "Case 1: bus 3, line 3-101"),
)


def main():
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    print(
        f"{'case':9} {'fault':28} {'conv':7} {'h ms':>6} {'err bar':>7} {'build s':>8} "
        f"{'CCT s':>7} {'cycles':>7} {'err ms':>6} {'sims':>5} {'wall s':>7} {'target s':>9}"
    )
    for name, fault, target, label in SEARCHES:
        for conv in ("pstess", "ieee"):
            t = time.perf_counter()
            sim = Simulator(load_case(name), conventions=conv)
            build = time.perf_counter() - t
            sim.run(fault.events(0.05), t_end=fault.t_fault + 1.0)  # warm-up (compilation)
            for check in (False, True):
                res = min(
                    (
                        critical_clearing_time(sim, fault, SearchOptions(error_check=check))
                        for _ in range(3)
                    ),
                    key=lambda r: r.wall_time_s,
                )
                verdict = (
                    ""
                    if target is None or conv == "pstess"
                    else f"{target:9.1f} {'ok' if res.wall_time_s <= target else 'MISSED'}"
                )
                err = "-" if res.numerical_error_s is None else f"{1000 * res.numerical_error_s:g}"
                print(
                    f"{name:9} {label:28} {conv:7} {1000 * res.step_s:6.3g} "
                    f"{'yes' if check else 'no':>7} {build:8.2f} {res.cct_s:7.3f} "
                    f"{res.cct_cycles:7.2f} {err:>6} {res.n_simulations:5d} "
                    f"{res.wall_time_s:7.2f} {verdict}",
                    flush=True,
                )


if __name__ == "__main__":
    main()
