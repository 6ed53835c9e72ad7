"""Two-machine COI equivalent (Table 2) and the minimum-time BVP (paper Section 4)."""

import numpy as np
import pytest

from stabctl.errors import InputError
from stabctl.smib.coi import PAPER_TWO_MACHINE, PAPER_TWO_MACHINE_T_RELEASE, TwoMachineCOI
from stabctl.smib.omib import simulate
from stabctl.smib.optimal import solve_min_time


def release_state():
    run = simulate(PAPER_TWO_MACHINE.equivalent(), PAPER_TWO_MACHINE_T_RELEASE, t_end=0.2)
    return run.delta_cl, run.omega_cl


def test_table2_states_at_fault_release():
    x1, x2 = release_state()
    assert x1 == pytest.approx(1.0734, abs=1e-3)
    assert x2 == pytest.approx(10.9956, abs=1e-3)


def test_equivalent_reproduces_two_machine_relative_motion_and_coi_momentum():
    tm = TwoMachineCOI(H1=2.0, H_rest=5.0, Pm=0.5, Pmax_pre=1.0, Pmax_fault=0.2, Pmax_post=0.9)
    P_C = 0.1
    m = tm.simulate_machines(t_clear=0.1, t_end=0.6, P_C=P_C)
    run = simulate(
        tm.equivalent(), 0.1, t_end=0.6, law=lambda f, w, M: ((f - tm.k_C * P_C) / M, P_C)
    )
    rel = np.interp(run.t, m["t"], m["delta1"] - m["delta2"])
    assert np.max(np.abs(rel - run.delta)) < 2e-5  # linear interpolation on a 1 ms grid
    # the storage is the only external power: COI speed falls by omega_s*P_C*t/(2(H1+H2))
    coi = (tm.H1 * m["omega1"] + tm.H_rest * m["omega2"]) / (tm.H1 + tm.H_rest)
    ws = 2 * np.pi * tm.f0
    expected = -ws * P_C * np.clip(m["t"] - 0.1, 0, None) / (2 * (tm.H1 + tm.H_rest))
    assert np.max(np.abs(coi - expected)) < 1e-7


@pytest.mark.parametrize("P_Cmax", [0.1, 0.3])
def test_min_time_bvp_gives_full_absorbing_pulse(P_Cmax):
    sol = solve_min_time(PAPER_TWO_MACHINE.equivalent(), release_state(), P_Cmax)
    assert sol.lambda2_positive and sol.l2.min() > 0
    assert np.abs(sol.l1[-1]) < 1e-8 and np.abs(sol.x2[-1]) < 1e-8  # transversality, target
    assert np.max(np.abs(sol.hamiltonian)) < 1e-6  # H = 0 along the optimum
    assert sol.T == pytest.approx(sol.T_pulse, abs=1e-6)  # = simulated full pulse
    assert sol.T < sol.T_uncontrolled


def test_bad_two_machine_inputs():
    with pytest.raises(InputError):
        TwoMachineCOI(H1=0.0, H_rest=6.0, Pm=0.5, Pmax_pre=1, Pmax_fault=0, Pmax_post=1)
    with pytest.raises(InputError):
        solve_min_time(PAPER_TWO_MACHINE.equivalent(), (1.0, 10.0), 0.0)
