"""Fixed injections (``case.injections``: HVDC converters' set points) in a run: constant
power at their buses, as the power flow has them.  Before, the power flow booked them in
neither the generation nor the load and the dynamic model lost them: a Kundur case with
one started off equilibrium (0.55 on exc.VTR.G2) and was refused."""

import numpy as np

from stabctl.case import InjectionTable, LoadTable
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.io import load_case

#: 0.5 + j0.1 pu injected at bus 3, a bus without load or machine
P, Q, BUS = 0.5, 0.1, 3


def test_an_injection_is_the_constant_power_negative_load_it_stands_for():
    """The same 0.5 + j0.1 pu given as an injection and as a constant-power load of -0.5 -
    j0.1 pu (load_con p_power = q_power = 1) at bus 3: both start at rest and follow one
    trajectory through a 6-cycle fault at bus 3 itself (the kept bus's constant power
    turned into an admittance below 0.5 pu, as any constant-power load)."""
    case = load_case("kundur")
    injected = case.replace(injections=InjectionTable.from_matrix([[BUS, P, Q]]))
    b = case.buses
    k = case.bus_index(BUS)
    as_load = case.replace(
        buses=b.replace(
            pload=np.where(np.arange(len(b)) == k, -P, b.pload),
            qload=np.where(np.arange(len(b)) == k, -Q, b.qload),
        ),
        loads=LoadTable.from_matrix([*case.loads.matrix().tolist(), [BUS, 1, 1, 0, 0]]),
    )
    runs = []
    for c in (injected, as_load):
        sim = Simulator(c)
        assert sim.model.initial_residual[0] < 1e-8
        runs.append(sim.run([Fault(BUS, 1.0, 1.1)], 3.0))
    assert np.max(np.abs(runs[0].speed - 1)) > 1e-3
    np.testing.assert_allclose(runs[0].speed, runs[1].speed, atol=1e-12)
    np.testing.assert_allclose(runs[0].vmag, runs[1].vmag, atol=1e-10)
