"""Playback sources (a classical machine with H = 0 and ``playback`` 1, ANDES PLBVFU1): E'
and the speed follow the targets a Playback event sets through their lags.  The run of
ANDES's own playback case is in tests/io/test_andes.py."""

import numpy as np
import pytest

from stabctl.case import MachineTable
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Playback
from stabctl.errors import CaseError, InputError
from stabctl.io import load_case


@pytest.fixture(scope="module")
def kundur_playback():
    """Kundur with G1 (bus 1) a playback source behind x'd = 0.3 pu (900 MVA), without
    its exciter, stabiliser and governor."""
    case = load_case("kundur")
    mac = case.machines.matrix()
    row = np.zeros(mac.shape[1])
    row[[0, 1, 2, 6]] = 1, 1, 900.0, 0.3  # number, bus, mva, x'd; x_d = 0, H = 0
    row[[21, 22]] = 1.0, 1.0  # pfrac, qfrac: all of the bus's generation
    row[MachineTable.FAMILY.col("playback") - 1 : MachineTable.FAMILY.col("pb_Tf")] = 1, 0.2, 0.2
    mac[0] = row
    others = {
        name: getattr(case, name).select(getattr(case, name).machine != 1)
        for name in ("exciters", "pss", "governors")
    }
    return case.replace(machines=MachineTable.from_matrix(mac), **others)


def test_the_speed_and_e_follow_their_targets_through_the_lags(kundur_playback):
    """A 0.001 pu speed step (with a 0.02 pu E' step) at 1 s: 0.2 s later the source's
    speed is 1 + 0.001 (1 - 1/e) (the first-order lag T_f, within the 5 ms step's 4e-8);
    before it, the source holds 1 pu (the 0.5 s point changes nothing)."""
    sim = Simulator(kundur_playback)
    assert sim.model.initial_residual[0] < 1e-8
    res = sim.run([Playback(1, (0.5, 1.0), (0.0, 0.02), (0.0, 0.001))], 1.2)
    k = np.searchsorted(res.t, 1.2)
    lag = 1 - np.exp(-1.0)
    assert res.speed[k, 0] == pytest.approx(1 + 0.001 * lag, abs=1e-7)
    assert np.all(res.speed[res.t < 1.0, 0] == 1.0)


def test_a_playback_of_another_machine_or_of_mismatched_values_is_refused(kundur_playback):
    sim = Simulator(kundur_playback)
    with pytest.raises(CaseError, match="machine 2 is not a playback source"):
        sim.run([Playback(2, (1.0,), (0.0,), (0.001,))], 2.0)
    with pytest.raises(InputError, match="one dV and one df per time"):
        sim.run([Playback(1, (1.0, 2.0), (0.0,), (0.001, 0.0))], 2.0)
    with pytest.raises(InputError, match=r"times \(at\) must rise"):
        sim.run([Playback(1, (1.0, 0.5), (0.0, 0.0), (0.001, 0.0))], 2.0)
