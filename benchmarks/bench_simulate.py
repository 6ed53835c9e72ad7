"""Wall time of 20 s simulations with the paper's Case 1 and Case 2 faults (not a test).

Prints the best of several runs after a warm-up (compilation excluded), the ratio to real
time, and the targets on one core: Kundur 20 s <= 0.05 s, miniWECC 20 s <= 0.3 s.
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
    print(f"{'case':10} {'run':44} {'step s':>9} {'wall s':>8} {'x real time':>12} {'target s':>9}")
    for pc, target in CASES:
        name, cyc = pc.case, pc.cycles["paper"]
        label = f"{pc.label}: {pc.fault.describe()}, {cyc} cycles"
        case = load_case(name)
        sim = Simulator(case)
        fault = [fault_with_clearing(case, pc.bus, pc.far_bus, pc.fault.t_fault, cyc)]
        for h in (default_step(case), 1 / 240):
            for what, ev in ((label, fault), ("no disturbance", [])):
                wall, _ = best_of(partial(sim.run, ev, t_end=20.0, h=h))
                print(f"{name:10} {what:44} {h:9.5f} {wall:8.3f} {20.0 / wall:12.0f} {target:9.2f}")


if __name__ == "__main__":
    main()
