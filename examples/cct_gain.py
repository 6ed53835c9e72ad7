"""Case 1's critical clearing time (Kundur) without storage and with ESDs of 5 and 10 % of
each generator's MVA: the CCT gain, which the paper's Table 4 reports for miniWECC's
Case 2 (`stabctl paper` runs that table).

    python examples/cct_gain.py
"""

import stabctl


def main():
    case = stabctl.load_case("kundur")
    sim = stabctl.Simulator(case)
    fault = stabctl.LineFault(3, 101, 1.0)  # paper Case 1
    base = stabctl.critical_clearing_time(sim, fault).cct_s
    print(f"no storage: CCT {1000 * base:.0f} ms")
    for pct in (5, 10):
        cct = stabctl.critical_clearing_time(sim, fault, storage=stabctl.uniform_fleet(case, pct))
        gain = 100 * (cct.cct_s / base - 1)
        print(f"{pct:>2} % ESDs: CCT {1000 * cct.cct_s:.0f} ms, gain {gain:.0f} %")


if __name__ == "__main__":
    main()
