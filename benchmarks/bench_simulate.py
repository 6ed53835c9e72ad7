"""Wall time of 20 s simulations with the paper's Case 1 and Case 2 faults (not a test).

Prints the best of several runs after a warm-up (compilation excluded), the ratio to real
time, and the targets on one core: Kundur 20 s <= 0.05 s, miniWECC 20 s <= 0.3 s (Heun,
the simulator's method).  The last row of each case: the implicit trapezoid (`method="trapezoid"`,
ANDES's method, a Python loop; no target) at 5 ms on the same fault.
Run: python benchmarks/bench_simulate.py
"""

from functools import partial

from _timing import best_of

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.dynamics.grid import default_step
from stabctl.io import load_case
from stabctl.studies.cases import CASE1, CASE2

CASES = ((CASE1, 0.05), (CASE2, 0.3))  # paper case, target s (20 s run, one core)


def main():
    print(
        f"{'case':10} {'run':44} {'method':>9} {'step s':>9} {'wall s':>8} {'x real time':>12}"
        f" {'target s':>9}"
    )
    for pc, target in CASES:
        name, cyc = pc.case, pc.cycles["paper"]
        label = f"{pc.label}: {pc.fault.describe()}, {cyc} cycles"
        case = load_case(name)
        sim = Simulator(case)
        fault = [fault_with_clearing(case, pc.bus, pc.far_bus, pc.fault.t_fault, cyc)]
        runs = [
            (h, what, ev, "heun")
            for h in (default_step(case), 1 / 240)
            for what, ev in ((label, fault), ("no disturbance", []))
        ]
        runs.append((0.005, label, fault, "trapezoid"))
        for h, what, ev, method in runs:
            wall, _ = best_of(partial(sim.run, ev, t_end=20.0, h=h, method=method))
            goal = f"{target:9.2f}" if method == "heun" else f"{'-':>9}"
            print(
                f"{name:10} {what:44} {method:>9} {h:9.5f} {wall:8.3f} {20.0 / wall:12.0f} {goal}"
            )


if __name__ == "__main__":
    main()
