"""The paper's Case 2: a 6-cycle fault beside the Colstrip unit of the miniWECC, without
storage and with an ESD of 5 % of each generator's MVA under the bang-bang COI law; the
speeds and the device powers plotted to case2.png.

    python examples/case2_with_storage.py
"""

from pathlib import Path

import stabctl
from stabctl.plotting.figures import storage_case_figure
from stabctl.studies.cases import CASE2


def main():
    case = stabctl.load_case(CASE2.case)
    sim = stabctl.Simulator(case)
    events = CASE2.fault.events(6 / case.freq_hz)  # cleared after 6 cycles
    runs = []
    for label, storage in (("without storage", None), ("5 % ESDs", stabctl.uniform_fleet(case, 5))):
        res = sim.run(events, t_end=6.0, storage=storage)
        runs.append(res)
        print(
            f"{label}: stable={res.stable}, largest angle from the COI "
            f"{res.max_angle_from_coi:.3f} rad"
        )
    storage_case_figure(*runs, Path("case2.png"), "Case 2, 5 % ESDs", case=case, highlight=(13, 14))
    print("wrote case2.png")


if __name__ == "__main__":
    main()
