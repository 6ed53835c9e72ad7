"""Speed effects of the subtransient machine (mac_con column 24, docs/pst_models.md 1.5-1.6):
with them (PST mac_sub) the stator voltage is speed times the subtransient flux and the
mechanical torque is Pm/omega; without them (ANDES's GENROU) both use speed 1.  Checked by
closed forms at the power-flow point of the Kundur case (D0 = 0), where the electrical and
mechanical torques balance."""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.model import StageConfig
from stabctl.errors import CaseError
from stabctl.io import load_case

DW = 0.01  # speed offset of machine 1, pu


def accelerations(speed_effects: float):
    """d omega / dt of every machine with machine 1 at 1 + DW and nothing else moved, and
    the machines' electrical powers (system base) there and at the operating point."""
    case = load_case("kundur")
    n = len(case.machines)
    case = case.replace(machines=case.machines.replace(speed_effects=np.full(n, speed_effects)))
    m = Simulator(case).model_for(())
    net = m.network(StageConfig())
    x = m.x0.copy()
    _, out0 = m.evaluate(x.copy(), net, m.V_nc0)
    x[n] += DW  # omega of machine 1 (states: delta, omega, ...)
    dx, out = m.evaluate(x, net, m.V_nc0)
    return dx[n : 2 * n], out.pelect, out0.pelect, m


def test_without_speed_effects_a_speed_offset_alone_leaves_the_torques_balanced():
    acc, pe, pe0, _ = accelerations(0.0)
    assert np.max(np.abs(acc)) < 1e-9
    np.testing.assert_allclose(pe, pe0, atol=1e-9)


def test_with_speed_effects_the_stator_voltage_and_torque_scale_with_speed():
    acc, pe, pe0, m = accelerations(1.0)
    # the network sees machine 1's internal voltage times 1 + DW: its power changes
    assert abs(pe[0] - pe0[0]) > 1e-3
    # its mechanical torque is Pm / (1 + DW): a deceleration of at least Pm DW/(1+DW)/2H
    H, pm = m.mp.H[0], m.pmech0[0]
    assert acc[0] < -pm * DW / (1 + DW) / (2 * H) * 0.5


def test_speed_effects_must_be_0_or_1():
    case = load_case("kundur")
    with pytest.raises(CaseError, match="speed_effects"):
        case.machines.replace(speed_effects=np.full(len(case.machines), 0.5))
