"""Torsional shafts (stabctl.models.shafts, ANDES SHAFT5) on the built-in Kundur case: the
operating point is an equilibrium with each spring carrying the turbine torque (the static
balance of a chain of springs in series), the default step resolves the torsional modes
and a step that cannot is refused naming the shaft, a shaft's errors name its row.  The
agreement with ANDES (fault speeds, torsional and electromechanical modes) is in
tests/io/test_andes.py."""

import numpy as np
import pytest

from stabctl.case import ShaftTable
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.errors import CaseError, InputError
from stabctl.io import load_case
from stabctl.smallsignal.linearise import linearise
from stabctl.smallsignal.modal import modal_analysis

#: ANDES 2.0's SHAFT5 defaults (andes/models/shaft/shaft5.py): machine, MHP, MIP, MLP, MEX,
#: KHP, KIP, KLP, KEX; damping 0
ROW = [1, 0.092, 0.156, 0.858, 0.068, 19.303, 34.929, 52.038, 1.55]


@pytest.fixture(scope="module")
def kundur_shaft():
    case = load_case("kundur")
    return case.replace(shafts=ShaftTable.from_matrix([ROW]))


def test_each_spring_carries_the_turbine_torque_at_the_operating_point(kundur_shaft):
    sim = Simulator(kundur_shaft)
    m = sim.model
    assert m.initial_residual[0] < 1e-8
    x = m.layout.view(m.x0, "shaft")[:, 0]
    delta, pm = m.x0[0], m.pmech0[0]  # machine 1's angle (state 0) and P_m
    d_hp, d_ip, d_lp, d_ex = x[0], x[2], x[4], x[6]
    K_hp, K_ip, K_lp = ROW[5:8]
    np.testing.assert_allclose(
        [K_lp * (d_lp - delta), K_ip * (d_ip - d_lp), K_hp * (d_hp - d_ip)], pm, rtol=1e-12
    )
    assert d_ex == delta and np.all(x[1::2] == 1.0)
    assert m.state_name(m.layout.blocks["shaft"][0].start + 1) == "shaft.wHP.G1"


def test_the_default_step_resolves_the_fastest_torsional_mode_and_a_larger_one_is_refused(
    kundur_shaft,
):
    """The linearised torsional modes (with the network) are the free chain's
    (`torsional_frequencies`: 14.8, 20.7, 37.4, 67.1 Hz) within 0.1 %: Kundur's 900 MVA
    rotor (M = 13 s) is heavy beside the turbine masses; the default step keeps w h = 0.05
    on the fastest; a 5 ms step (w h = 2.1) is refused naming shaft_con."""
    sim = Simulator(kundur_shaft)
    free = sim.model.tp.torsional_frequencies(sim.model.mp.basrad)[0]
    lam = modal_analysis(linearise(sim)).eigenvalues
    fast = np.sort(np.abs(lam.imag[np.abs(lam.imag) > 2 * np.pi * 5]))
    assert fast.size == 4
    np.testing.assert_allclose(fast, free, rtol=1e-3)  # measured 2.1e-4
    assert sim.default_h * free[-1] == pytest.approx(0.05)
    with pytest.raises(InputError, match="shaft_con torsional mode"):
        Simulator(kundur_shaft, step=0.005)


def test_a_fault_run_converges_in_the_default_step(kundur_shaft):
    """Bus-3 fault, 6 cycles: the speeds at the default step and at half of it agree to
    2e-7 pu (measured 3.6e-8; the swing is 6.1e-3 pu)."""
    sim = Simulator(kundur_shaft)
    ev = [Fault(3, 1.0, 1.1)]
    a = sim.run(ev, 3.0)
    b = sim.run(ev, 3.0, h=sim.default_h / 2)
    w_b = np.column_stack([np.interp(a.t, b.t, b.speed[:, k]) for k in range(4)])
    assert np.max(np.abs(a.speed - 1)) > 5e-3
    assert np.max(np.abs(a.speed - w_b)) < 2e-7


@pytest.mark.parametrize(
    "change, needle",
    [
        ({0: 9}, "machine 9 does not exist"),
        ({1: 0.0}, "field 'MHP': must be > 0"),
        ({7: -1.0}, "KLP"),
    ],
)
def test_a_bad_shaft_row_is_refused_by_row_and_field(change, needle):
    row = list(ROW)
    for k, v in change.items():
        row[k] = v
    with pytest.raises(CaseError, match=needle):
        Simulator(load_case("kundur").replace(shafts=ShaftTable.from_matrix([row])))
