"""Why storage can lower a CCT, by runs (docs/placement.md section 8).

For one line fault of a case, the CCT (1 ms, the case's default step, no half-step
rerun) without storage and with a uniform fleet (every generator, PCT % of its MVA)
under the paper's law (COI of the system) and the critical group's reference
(``coi="critical"``, the group from the search without storage), each with the
paper's 0.8 pu voltage gate and without a gate, the devices at the generators' HV
buses (the default) or at their terminal buses.  Then, one run cleared 5 ms before the
CCT without storage: how much of the critical machine's device power its machine
carries (its electrical power with the device minus without, at four instants), at
each site, and its bus voltage (what the gate sees).

Run: python analysis/storage_lowers_cct.py CASE.json BUS FAR_BUS [PCT]
(IEEE 39: ieee39_full.json from `stabctl import-andes ieee39/ieee39_full.xlsx`, fault
26 29, 20 %: seconds; ACTIVSg2000 2021 2002: about an hour on one core).
"""

import sys
import time

import numpy as np

from stabctl.dynamics.driver import Simulator
from stabctl.errors import AboveSearchLimit, InsecureContingency
from stabctl.io import load_case
from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import uniform_fleet

SEARCH = SearchOptions(error_check=False)
INSTANTS = (0.05, 0.2, 0.3, 0.5)  # s after the fault start


def cct_text(sim, fault, fleet=None) -> str:
    """The CCT (s) and the machines separating just above it, or the verdict."""
    try:
        r = critical_clearing_time(sim, fault, SEARCH, storage=fleet)
    except AboveSearchLimit:
        return f"> {SEARCH.t_max:g} s"
    except InsecureContingency:
        return "N-1 insecure"
    return f"{r.cct_s:.3f} s (machines {', '.join(map(str, r.separated))})"


def leverage(case, fault, t_clear, critical, pct) -> None:
    """The critical machines' share of their own devices' power, per site."""
    for at in ("hv", "terminal"):
        law = BangBangCOI(v_gate_pu=0.0)
        fleet = uniform_fleet(case, pct, law, at=at)
        sim = Simulator(case, injection_buses=[d.bus for d in fleet.devices])
        ev = fault.events(t_clear)
        with_esd, without = sim.run(ev, t_end=2.0, storage=fleet), sim.run(ev, t_end=2.0)
        for m in critical:
            i = case.machine_index(m)
            k = np.searchsorted(with_esd.t, [fault.t_fault + s for s in INSTANTS])
            k0 = np.searchsorted(without.t, [fault.t_fault + s for s in INSTANTS])
            dpe = (with_esd.pelect[k, i] - without.pelect[k0, i]) * case.base_mva
            pesd = with_esd.pesd[k, i] * case.base_mva
            v = with_esd.vmag[k, with_esd.bus(fleet.devices[i].bus)]
            print(
                f"  machine {m}, device at bus {fleet.devices[i].bus} ({at}): at "
                + ", ".join(
                    f"{s:g} s {d:.1f} of {p:.1f} MW, {u:.2f} pu"
                    for s, d, p, u in zip(INSTANTS, dpe, pesd, v)
                )
            )


def main(path, bus, far_bus, pct=20.0) -> None:
    """Print the table and the leverage runs (module docstring)."""
    case, fault = load_case(path), LineFault(int(bus), int(far_bus), 1.0)
    pct = float(pct)
    t0 = time.perf_counter()
    base = critical_clearing_time(Simulator(case), fault, SEARCH)
    critical = tuple(base.separated)
    print(f"{case.name}, fault {bus} line {bus}-{far_bus}, storage {pct:g} % at every generator")
    print(f"no storage: CCT {base.cct_s:.3f} s, machines {list(critical)} separate")
    for at in ("hv", "terminal"):
        for gate in (0.8, 0.0):
            for coi in ("system", "critical"):
                law = BangBangCOI(
                    v_gate_pu=gate, coi=coi, critical=critical if coi == "critical" else ()
                )
                fleet = uniform_fleet(case, pct, law, at=at)
                sim = Simulator(case, injection_buses=[d.bus for d in fleet.devices])
                print(f"{at:8s} gate {gate:.1f} pu  coi {coi:8s}: {cct_text(sim, fault, fleet)}")
    print("device power carried by the critical machines (gate 0, cleared 5 ms before the CCT):")
    leverage(case, fault, base.cct_s - 0.005, critical, pct)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main(*sys.argv[1:])
