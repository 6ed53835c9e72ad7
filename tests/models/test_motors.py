"""Induction motors (stabctl.models.motors, ANDES 2.0 Motor5): the energising current of a
motor without flux is the bus voltage over its stator impedance, its power is its torque
plus the stator loss at every instant (the stator equation's energy balance), it stands
still while off, and a run switches it on and off at the events' times.  The agreement
with ANDES's run of its own case is in tests/io/test_andes.py."""

import numpy as np
import pytest

from stabctl.case import BranchTable, BusTable, Case, MotorTable
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import MotorSwitch
from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.models import motors as mot

BUS = [[1, 1.0, 0, 0, 0, 0, 0, 0, 0, 1], [2, 1.0, 0, 0.0, 0.0, 0, 0, 0, 0, 3]]
LINE = [[1, 2, 0.0, 0.1, 0.0, 1.0, 0.0]]
#: a 50 MVA motor on a 100 MVA system, ANDES's default data otherwise
MOTOR = [1, 2, 0, 50.0]


def two_bus(*rows):
    tab = MotorTable.from_matrix([list(r) for r in rows] or [MOTOR])
    return Case(
        "m", 100.0, 60.0, BusTable.from_matrix(BUS), BranchTable.from_matrix(LINE), motors=tab
    )


def evaluate(x, V, on=1.0):
    p = mot.motor_params(two_bus())
    dx = np.zeros_like(x)
    S = mot.derivatives(p.packed(), x, 0, V, on, dx)
    return p, S, dx


def test_a_motor_without_flux_draws_the_voltage_over_its_stator_impedance():
    """E" = 0 at the first switching: I = V / Z, S = |V|^2 / conj(Z) (system base: Z of
    the motor base times Sb/Sn = 2), and the slip starts to move at a / M."""
    V = 0.95 * np.exp(0.3j)
    p, S, dx = evaluate(np.zeros((5, 1)), V)
    Z = 2 * (0.01 + 1j * (0.15 + 0.15 * 0.04 * 5 / (0.15 * 0.04 + 0.15 * 5 + 0.04 * 5)))
    np.testing.assert_allclose(S, abs(V) ** 2 / np.conj(Z), rtol=1e-12)
    np.testing.assert_allclose(mot.admittance(p)[0], 1 / Z, rtol=1e-12)
    assert dx[0, 0] == pytest.approx((0.1 + 0.02 + 0.02) / (2 * 3.0))  # a/M, both x Sn/Sb


def test_the_power_drawn_is_the_air_gap_torque_plus_the_stator_loss():
    """p - T_e = Re((j V - E") conj(I_dq)) = r_s |I|^2 at any state (motor running at
    1.5 % slip with fluxes off their steady values)."""
    x = np.array([[0.015], [0.05], [0.8], [0.04], [0.85]])
    V = 0.98 * np.exp(-0.2j)
    p, S, _ = evaluate(x, V)
    Idq = (1j * V - (x[3, 0] + 1j * x[4, 0])) / p.Z[0]
    te = x[3, 0] * Idq.real + x[4, 0] * Idq.imag
    np.testing.assert_allclose(S.real, te + p.rs[0] * abs(Idq) ** 2, rtol=1e-12)


def test_off_it_draws_nothing_and_stands_still():
    x = np.array([[0.015], [0.05], [0.8], [0.04], [0.85]])
    _, S, dx = evaluate(x, 1.0 + 0j, on=0.0)
    assert S == 0 and np.all(dx == 0)


def test_switched_on_and_off_the_bus_voltage_dips_and_returns():
    """Kundur with a 100 MVA motor at bus 3 switched on at 1 s (its inrush, |V|/|Z| = 5 pu
    of mostly reactive current, dips the bus) and off at 4 s: before 1 s the run is the
    flat one; after 4 s the bus voltage returns towards its power-flow value."""
    case = load_case("kundur").replace(motors=MotorTable.from_matrix([[1, 3, 0, 100.0]]))
    sim = Simulator(case)
    assert sim.model.initial_residual[0] < 1e-8
    res = sim.run([MotorSwitch(1, 1.0), MotorSwitch(1, 4.0, on=False)], 8.0)
    b = case.bus_index(3)
    v = res.vmag[:, b]
    before, during = v[res.t < 0.999], v[(res.t > 1.0) & (res.t < 1.05)]
    assert np.ptp(before) < 1e-10
    assert during.min() < before[0] - 0.02  # the inrush dip
    assert abs(v[-1] - before[0]) < 5e-3  # back near the power-flow voltage


def test_a_motor_in_service_at_the_start_and_an_unknown_motor_are_refused():
    with pytest.raises(CaseError, match="in_service"):
        two_bus([1, 2, 1, 50.0])
    with pytest.raises(CaseError, match="motor 2 does not exist"):
        Simulator(load_case("kundur").replace(motors=MotorTable.from_matrix([[1, 3, 0, 100]]))).run(
            [MotorSwitch(2, 1.0)], 2.0
        )
