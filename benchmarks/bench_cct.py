"""Wall time and number of simulations of one CCT search per case (not a test).

Searches (defaults of `stabctl.cct.critical_clearing_time`: tol 1 ms, t_end = fault + 5 s,
stop at separation) for the paper's Case 2 fault (miniWECC, bus 83, line 83-33, at 1 s)
and Case 1 fault (Kundur, bus 3, line 3-101, at 1 s), pinned to one core, after a warm-up
run (compilation and the power flow excluded; the Simulator build is printed apart).
Target: the miniWECC search <= 3 s on one core.
Run: python benchmarks/bench_cct.py
"""

import os
import time

from stabctl.case import load_case
from stabctl.cct import LineFault, critical_clearing_time
from stabctl.simulation import Simulator

SEARCHES = (  # case, fault, target s (None: no target), label
    ("miniwecc", LineFault(83, 33, 1.0), 3.0, "Case 2: bus 83, line 83-33"),
    ("kundur", LineFault(3, 101, 1.0), None, "Case 1: bus 3, line 3-101"),
)


def main():
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    print(f"{'case':9} {'fault':28} {'build s':>8} {'CCT s':>7} {'cycles':>7} {'sims':>5} "
          f"{'wall s':>7} {'target s':>9}")
    for name, fault, target, label in SEARCHES:
        t = time.perf_counter()
        sim = Simulator(load_case(name))
        build = time.perf_counter() - t
        sim.run(fault.events(0.05), t_end=fault.t_fault + 1.0)      # warm-up (compilation)
        res = critical_clearing_time(sim, fault)
        verdict = "" if target is None else \
            f"{target:9.1f} {'ok' if res.wall_time_s <= target else 'MISSED'}"
        print(f"{name:9} {label:28} {build:8.2f} {res.cct_s:7.3f} {res.cct_cycles:7.2f} "
              f"{res.n_simulations:5d} {res.wall_time_s:7.2f} {verdict}")


if __name__ == "__main__":
    main()
