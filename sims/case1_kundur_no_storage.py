"""Paper Case 1 without storage: Kundur two-area system (PSTess d2asbegp), three-phase fault
at PST bus 3 (Kundur bus 7) on line 3-101 (7-8) at t = 1 s, cleared after 21 cycles at both
ends, the faulted circuit tripped.  Expected: area 1 (machines 1 and 2) loses synchronism
with area 2 (machines 3 and 4).

Prints the verdict, brackets the critical clearing time by a scan over clearing cycles, and
saves reports/case1_no_storage.png (speeds, angles from the COI, bus voltages).

    python sims/case1_kundur_no_storage.py [--out reports]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from stabctl.io import load_case
from stabctl.dynamics.events import fault_with_clearing
from stabctl.plotting.figures import simulation_overview
from stabctl.dynamics.simulation import Simulator

FAULT_BUS, FAR_BUS, T_FAULT, CYCLES, T_END = 3, 101, 1.0, 21, 5.0


def main(out_dir: Path) -> None:
    case = load_case("kundur")
    sim = Simulator(case)
    res = sim.run([fault_with_clearing(case, FAULT_BUS, FAR_BUS, T_FAULT, CYCLES)], t_end=T_END)
    print(f"Case 1 (no storage): {case.name}, fault at bus {FAULT_BUS} on line "
          f"{FAULT_BUS}-{FAR_BUS} at {T_FAULT} s, cleared after {CYCLES} cycles, line tripped")
    if res.stable:
        print(f"  verdict: stable (largest angle from the COI {res.max_angle_spread:.3f} rad)")
    else:
        print(f"  verdict: loss of synchronism at t = {res.t_separation:.3f} s; machines "
              f"{', '.join(map(str, res.separated))} separate from the rest")
    print(f"  wall time {res.meta.get('wall_time_s', float('nan')):.2f} s")

    print("  clearing-time scan (cycles: verdict):")
    last_stable = first_unstable = None
    for cyc in range(6, CYCLES + 1, 1):
        r = sim.run([fault_with_clearing(case, FAULT_BUS, FAR_BUS, T_FAULT, cyc)], t_end=T_END,
                    stop_at_separation=True)
        print(f"    {cyc:3d}: " + ("stable" if r.stable else
                                  f"machines {r.separated} separate at {r.t_separation:.3f} s"))
        if r.stable:
            last_stable = cyc
        elif first_unstable is None:
            first_unstable = cyc
    if last_stable is not None and first_unstable is not None:
        print(f"  critical clearing time between {last_stable} and {first_unstable} cycles "
              f"({last_stable / case.freq_hz:.3f}-{first_unstable / case.freq_hz:.3f} s)")

    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "case1_no_storage.png"
    simulation_overview(res, path, title=f"Case 1, no storage: Kundur, {CYCLES}-cycle fault at "
                        f"bus {FAULT_BUS}, line {FAULT_BUS}-{FAR_BUS} tripped")
    print(f"  wrote {path}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("reports"), help="report directory")
    main(ap.parse_args().out)
