"""Switched shunts (stabctl.network.switched_shunts, stabctl.models.shunts; ANDES ShuntSw):
the levels and the level a shunt starts at (ANDES's SwBlock rule), the power flow's
stepping to the band, and the run's discrete control with its delay.  The agreement with
ANDES (power flow and a fault run) is in tests/io/test_andes.py."""

import numpy as np
import pytest

from stabctl.case import BranchTable, BusTable, Case, SwitchedShuntTable
from stabctl.models import shunts
from stabctl.network import switched_shunts as sws
from stabctl.network.powerflow import solve_powerflow

BUS = [[1, 1.0, 0, 0, 0, 0, 0, 0, 0, 1], [2, 1.0, 0, 0, 0, 0.5, 0.1, 0, 0, 3]]
LINE = [[1, 2, 0.0, 0.2, 0.0, 1.0, 0.0]]


def row(b0, vref=1.0, dv=0.02, dt=0.1):
    """A shunt at bus 2: two steps of 0.025 then three of 0.05 (levels 0, 0.025, 0.05,
    0.1, 0.15, 0.2 pu)."""
    return [1, 2, b0, 0.0, vref, dv, dt, 2, 0.025, 0.0, 3, 0.05, 0.0]


def two_bus(b0, **kw):
    return Case(
        "sw",
        100.0,
        60.0,
        BusTable.from_matrix(BUS),
        BranchTable.from_matrix(LINE),
        switched_shunts=SwitchedShuntTable.from_matrix([row(b0, **kw)]),
    )


@pytest.mark.parametrize(
    "b0, level", [(0.0, 0), (0.025, 1), (0.03, 2), (0.1, 3), (0.12, 4), (0.5, 5), (-0.1, 0)]
)
def test_a_shunt_starts_at_its_b0_rounded_up_to_a_level(b0, level):
    t = two_bus(b0).switched_shunts
    np.testing.assert_allclose(sws.levels(t, 0).imag, [0, 0.025, 0.05, 0.1, 0.15, 0.2])
    assert sws.initial_levels(t)[0] == level


def test_the_power_flow_steps_the_shunt_to_the_first_level_inside_its_band():
    """From 0 pu the load bus sits below 0.98 pu; the flow adds one level at a time and
    stops at the first whose voltage is in 1 +- 0.02 (the level below it is not)."""
    case = two_bus(0.0)
    pf = solve_powerflow(case)
    level = int(pf.shunt_levels[0])
    assert abs(pf.vmag[1] - 1.0) <= 0.02
    below = solve_powerflow(
        case.replace(
            switched_shunts=case.switched_shunts.replace(
                b0=[sws.levels(case.switched_shunts, 0)[level - 1].imag], dv=[1.0]
            )
        )
    )
    assert below.vmag[1] < 0.98 and level > 0


def test_in_a_run_the_shunt_steps_once_per_delay():
    """Below its band: one level up, the delay set to dt; then, while the delay runs
    down, no step and the delay's rate -1; at the top level no step."""
    P = np.array([[0.0, 0.98, 1.02, 0.1, 5, 2]])
    x = np.array([[2.0], [0.0]])
    dx = np.zeros_like(x)
    shunts.switch(P, x, 0, 0.9, dx)
    assert (x[0, 0], x[1, 0], dx[1, 0]) == (3.0, 0.1, -1.0)
    shunts.switch(P, x, 0, 0.9, dx)
    assert x[0, 0] == 3.0 and dx[1, 0] == -1.0
    x[1, 0] = 0.0
    shunts.switch(P, x, 0, 1.1, dx)  # above the band: down
    assert x[0, 0] == 2.0
    x[:, 0] = [5.0, 0.0]
    shunts.switch(P, x, 0, 0.9, dx)
    assert x[0, 0] == 5.0 and dx[1, 0] == 0.0
