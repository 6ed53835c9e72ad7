"""Ybus and the Newton power flow against PSTess and closed forms.

References: tests/data/pstess/*_loadflow_bus.csv, the solved bus matrices PSTess 1.1
(GNU Octave 7.3) starts its simulations from (copied from shared/reference/pstess; MIT,
see LICENSE and NOTICE there).
"""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from stabctl.case import PQ, PV
from stabctl.errors import CaseError, PowerFlowError, UnknownBusError, WrongTypeError
from stabctl.io import load_case
from stabctl.network import ybus as network
from stabctl.network.powerflow import solve_powerflow

DATA = Path(__file__).parents[1] / "data" / "pstess"
REFS = {
    "kundur": "kundur_d2asbegp_default_loadflow_bus.csv",
    "miniwecc": "miniwecc_base_default_loadflow_bus.csv",
}


def reference(name):
    return np.loadtxt(DATA / REFS[name], delimiter=",")


# ---------------------------------------------------------------------------- PSTess


@pytest.mark.parametrize("name", ["kundur", "miniwecc"])
def test_powerflow_matches_pstess(name):
    res = solve_powerflow(load_case(name))
    ref = reference(name)
    got = res.bus_matrix()
    assert got.shape == ref.shape == (load_case(name).n_bus, 15)
    np.testing.assert_array_equal(got[:, 0], ref[:, 0])  # bus order
    assert np.max(np.abs(got[:, 1] - ref[:, 1])) < 1e-4  # |V|, pu
    assert np.max(np.abs(got[:, 2] - ref[:, 2])) < 1e-2  # angle, deg
    np.testing.assert_allclose(got[:, 3:7], ref[:, 3:7], atol=1e-4)  # Pg Qg Pl Ql
    np.testing.assert_array_equal(got[:, 7:], ref[:, 7:])  # G B type limits kV
    np.testing.assert_allclose(res.vang, np.deg2rad(ref[:, 2]), atol=1e-2 * np.pi / 180)
    assert res.max_mismatch <= 1e-8 and res.iterations <= 10


def test_kundur_pstess_generation_and_swing():
    res = solve_powerflow(load_case("kundur"))
    k = res.case.bus_index
    assert res.pgen[k(1)] == pytest.approx(7.26106622, abs=1e-6)  # swing P from reference
    assert res.vang_deg[k(1)] == 18.5  # swing angle fixed
    assert res.qgen[k(12)] == pytest.approx(1.763058068, abs=1e-6)
    assert np.all(res.vmag[res.case.buses.kind == PV] == 1.01)


def test_solved_case_is_the_bus_solution():
    res = solve_powerflow(load_case("kundur"))
    solved = res.solved_case()
    np.testing.assert_array_equal(solved.buses.matrix(), res.bus_matrix())
    again = solve_powerflow(solved)  # starting at the solution: no iteration
    assert again.iterations == 0


def test_power_balance_equals_losses():
    case = load_case("miniwecc")
    res = solve_powerflow(case)
    flows = res.branch_flows()
    shunt = np.sum(case.buses.gshunt * res.vmag**2)
    losses = np.sum(flows["loss"].real) + shunt
    assert np.sum(res.pgen) - np.sum(res.pload) == pytest.approx(losses, abs=1e-7)
    # every branch end power equals the Ybus injection
    inj = np.zeros(case.n_bus, complex)
    np.add.at(inj, case.bus_indices(case.branches.from_bus), flows["s_from"])
    np.add.at(inj, case.bus_indices(case.branches.to_bus), flows["s_to"])
    inj += (case.buses.gshunt - 1j * case.buses.bshunt) * res.vmag**2
    np.testing.assert_allclose(inj.real, res.pgen - res.pload, atol=1e-7)


# ---------------------------------------------------------------------------- limits


def test_q_limit_switches_pv_to_pq_at_the_limit():
    case = load_case("kundur")
    i = case.bus_index(2)  # Qg = 1.942 in the reference
    qmax = np.where(case.buses.number == 2, 1.8, case.buses.qmax)
    case = case.replace(buses=case.buses.replace(qmax=qmax))
    res = solve_powerflow(case)
    assert res.kind[i] == PQ and res.q_limited[i] and res.q_limited.sum() == 1
    assert res.qgen[i] == pytest.approx(1.8, abs=1e-9)
    assert res.tap_iterations == 1
    assert res.qload[i] == pytest.approx(0.0, abs=1e-8)
    assert res.vmag[i] < 1.01  # voltage no longer held
    assert res.bus_matrix()[i, 9] == 3
    assert not solve_powerflow(case, q_limits=False).q_limited.any()


def test_tap_changer_moves_one_step_like_lftap():
    case = load_case("kundur")
    j = case.bus_index(4)  # V = 0.998 in the reference
    vmin = case.buses.vmin.copy()
    vmin[j] = 0.999
    case = case.replace(buses=case.buses.replace(vmin=vmin))
    res = solve_powerflow(case)
    # (0.999-0.998)/0.999 < tapstep -> one step down: 0.975 - 0.00625
    assert res.taps[2] == pytest.approx(0.96875, abs=1e-12)
    assert res.tap_iterations == 2 and res.vmag[j] > 0.999
    # without the tap changer the clipped voltage cannot reach the solution (PST: no
    # convergence) -> the error names the bus
    with pytest.raises(
        PowerFlowError, match=r"did not converge after 50 iteration\(s\).*at bus (3|4) "
    ):
        solve_powerflow(case, tap_changing=False)


def test_injection_acts_as_negative_load():
    from stabctl.case import InjectionTable

    case = load_case("kundur")
    inj = InjectionTable.from_matrix([[4, 1.0, 0.2]])
    with_inj = solve_powerflow(case.replace(injections=inj))
    b = case.buses
    less = b.replace(pload=b.pload - 1.0 * (b.number == 4), qload=b.qload - 0.2 * (b.number == 4))
    reduced = solve_powerflow(case.replace(buses=less))
    np.testing.assert_allclose(with_inj.vmag, reduced.vmag, atol=1e-10)
    np.testing.assert_allclose(with_inj.vang, reduced.vang, atol=1e-10)
    assert with_inj.pload[case.bus_index(4)] == pytest.approx(9.76, abs=1e-8)


# ---------------------------------------------------------------------------- failures


def test_nonconvergence_names_iterations_and_bus():
    case = load_case("kundur")
    heavy = case.replace(
        buses=case.buses.replace(pload=case.buses.pload * 5, qload=case.buses.qload * 5)
    )
    with pytest.raises(PowerFlowError) as e:
        solve_powerflow(heavy, max_iter=15, tap_changing=False)
    msg = str(e.value)
    assert "did not converge after 15 iteration(s)" in msg and re.search(r"at bus \d+", msg)
    bus = int(re.search(r"at bus (\d+)", msg).group(1))
    assert bus in case.buses.number


def test_a_start_no_solution_is_near_is_solved_again_from_a_flat_start_and_said():
    """Round 32: a bus added on a short branch with its RAW voltage left at 1 pu, 0 deg
    made import-psse refuse a case that solves from a flat start (its first iterate
    clipped to the 0.5 pu limit for good).  miniWECC with every load bus started at
    0.3 pu and 120 deg off: the same solution as from its own voltages, with a warning
    that says how it was reached; a case with no solution fails both ways and says so.
    (Kundur does not solve from a flat start with PST's Q limits, applied from the first
    iterate: that stays an error, as in PST.)"""
    case = load_case("miniwecc")
    b = case.buses
    ref = solve_powerflow(case)
    off = case.replace(
        buses=b.replace(
            vmag=np.where(b.kind == PQ, 0.3, b.vmag), vang_deg=b.vang_deg + 120 * (b.kind == PQ)
        )
    )
    with pytest.warns(
        RuntimeWarning, match="from the case's own voltages; solved from a flat start"
    ):
        got = solve_powerflow(off)
    assert np.abs(got.vmag - ref.vmag).max() < 1e-9
    assert np.abs(got.vang - ref.vang).max() < 1e-9
    assert got.max_mismatch <= 1e-8 and list(got.kind) == list(ref.kind)
    hopeless = off.replace(buses=off.buses.replace(pload=30 * b.pload))
    with pytest.raises(PowerFlowError, match=r"from a flat start.*did not converge either"):
        solve_powerflow(hopeless)


def test_islanded_bus_raises_powerflowerror():
    case = load_case("kundur")
    row = network.circuit_row(case, 3, 4)  # the only branch to load bus 4
    with pytest.raises(
        PowerFlowError,
        match=r"bus\(es\) 4 have no path to a swing bus: an "
        r"island left by the dropped branch",
    ):
        solve_powerflow(case, drop=[row])


def with_dead_island(case):
    """Kundur with a bus 99 joined to bus 1 by an open branch (x = OPEN_X, PST's opening),
    carrying a copy of machine 1 (number 99) with its exciter, PSS and governor and a
    non-conforming load: an island without a swing bus."""
    from stabctl.network.topology import OPEN_X

    def added(table, rows, **values):
        extra = table.select(rows)
        extra = extra.replace(**{k: np.full(len(extra), v) for k, v in values.items()})
        return type(table).from_matrix(np.vstack([table.matrix(), extra.matrix()]))

    k1 = np.flatnonzero(case.machines.number == 1)
    return case.replace(
        buses=added(case.buses, [1], number=99),  # a PV bus's row
        branches=added(case.branches, [0], from_bus=1, to_bus=99, x=OPEN_X),
        machines=added(case.machines, k1, number=99, bus=99),
        exciters=added(case.exciters, case.exciters.machine == 1, machine=99),
        pss=added(case.pss, case.pss.machine == 1, machine=99),
        governors=added(case.governors, case.governors.machine == 1, machine=99),
        loads=added(case.loads, [0], bus=99),
    )


def test_dead_islands_are_left_out_with_everything_on_them():
    # PSS/E's isolated buses: the island goes with its branch, machine, controls and load,
    # and what is left is the case as it was
    from stabctl.network.topology import without_dead_islands

    kundur = load_case("kundur")
    case = with_dead_island(kundur)
    with pytest.raises(PowerFlowError, match=r"bus\(es\) 99 have no path .*--leave-out-islands"):
        solve_powerflow(case)
    live, lines = without_dead_islands(case)
    assert lines == ("island of bus(es) 99 without a swing bus (1 machine(s), 1 load(s))",)
    assert live.equals(kundur)
    assert without_dead_islands(kundur) == (kundur, ())


def test_a_device_reading_across_the_cut_is_refused():
    from stabctl.network.topology import without_dead_islands

    case = with_dead_island(load_case("kundur"))
    g = case.governors
    crossed = case.replace(governors=g.replace(machine2=np.where(g.machine == 2, 99, 0)))
    with pytest.raises(CaseError, match=r"governor of machine 2: reads machine 99 \(machine2\)"):
        without_dead_islands(crossed)


# ---------------------------------------------------------------------------- Ybus


def pst_y_sparse(case):
    """Dense re-implementation of PSTess y_sparse.m: C_from (1/t) and C_to incidence."""
    br, n = case.branches, case.n_bus
    f = case.bus_indices(br.from_bus)
    t = case.bus_indices(br.to_bus)
    a = np.where(br.tap != 0, 1.0 / np.where(br.tap != 0, br.tap, 1.0), 1.0)
    a = a * np.exp(-1j * np.deg2rad(br.phase_deg))
    cf = np.zeros((n, len(br)), complex)
    ct = np.zeros((n, len(br)))
    cf[f, np.arange(len(br))] = a
    ct[t, np.arange(len(br))] = 1.0
    chrg = np.diag(0.5j * br.b)
    y = np.diag(1.0 / (br.r + 1j * br.x))
    cl = cf - ct
    Y = cf @ chrg @ cf.conj().T + ct @ chrg @ ct.T + cl @ y @ cl.conj().T
    return Y + np.diag(case.buses.gshunt + 1j * case.buses.bshunt)


@pytest.mark.parametrize("name", ["kundur", "miniwecc"])
def test_ybus_equals_pst_incidence_formula(name):
    case = load_case(name)
    y = network.build_ybus(case)
    assert sp.isspmatrix_csr(y) and y.dtype == complex
    np.testing.assert_allclose(y.toarray(), pst_y_sparse(case), atol=1e-9)


def test_ybus_with_phase_shift_and_tap_follows_pst():
    case = load_case("kundur")
    br = case.branches
    case = case.replace(
        branches=br.replace(
            phase_deg=np.where(np.arange(len(br)) == 6, 5.0, 0.0),
            tap=np.where(np.arange(len(br)) == 6, 1.05, br.tap),
        )
    )
    np.testing.assert_allclose(network.build_ybus(case).toarray(), pst_y_sparse(case), atol=1e-9)


def test_ybus_row_sums_are_shunts_without_charging_and_taps():
    case = load_case("kundur")
    br = case.branches
    flat = case.replace(branches=br.replace(b=np.zeros(len(br)), tap=np.ones(len(br))))
    y = network.build_ybus(flat)
    np.testing.assert_allclose(
        y @ np.ones(case.n_bus), case.buses.gshunt + 1j * case.buses.bshunt, atol=1e-9
    )
    # with charging: row sum = shunt + half the charging of each incident branch
    y = network.build_ybus(case.replace(branches=br.replace(tap=np.ones(len(br)))))
    half = np.zeros(case.n_bus)
    np.add.at(half, case.bus_indices(br.from_bus), br.b / 2)
    np.add.at(half, case.bus_indices(br.to_bus), br.b / 2)
    np.testing.assert_allclose(y @ np.ones(case.n_bus), 1j * (case.buses.bshunt + half), atol=1e-9)


def test_ybus_symmetric_without_phase_shifters():
    y = network.build_ybus(load_case("miniwecc"))
    assert abs(y - y.T).max() < 1e-12


def test_ybus_two_bus_closed_form():
    case = load_case("kundur")
    row = 2  # 3-4 transformer, x = 0.005, tap 0.975
    ba = network.branch_admittances(case, [row])
    y, t = 1 / 0.005j, 0.975
    assert ba.yff[0] == pytest.approx(y / t**2) and ba.ytt[0] == pytest.approx(y)
    assert ba.yft[0] == pytest.approx(-y / t) and ba.ytf[0] == pytest.approx(-y / t)


def test_tripping_one_of_two_parallel_circuits_halves_the_coupling():
    case = load_case("kundur")
    rows = network.find_branches(case, 101, 3)
    assert rows.tolist() == [4, 5]  # both 3-101 circuits
    i, j = case.bus_index(3), case.bus_index(101)
    full = network.build_ybus(case)
    tripped = network.build_ybus(case, drop=[network.circuit_row(case, 3, 101, 1)])
    assert tripped[i, j] == pytest.approx(full[i, j] / 2)
    assert tripped[j, j] == pytest.approx(full[j, j] - (1 / (0.011 + 0.11j) + 0.1925j / 2))
    net = network.Network.from_case(case).without([4])
    assert abs(net.ybus - tripped).max() < 1e-12 and 4 not in net.in_service
    assert abs(full - network.branch_stamp(case, [4]) - tripped).max() < 1e-12


def test_branch_lookup_errors():
    case = load_case("kundur")
    with pytest.raises(CaseError, match="circuit 3 between bus 3 and bus 101 does not exist"):
        network.circuit_row(case, 3, 101, 3)
    with pytest.raises(CaseError, match="no branch between bus 1 and bus 2"):
        network.circuit_row(case, 1, 2)
    with pytest.raises(UnknownBusError, match="bus 5 "):
        network.find_branches(case, 5, 3)
    with pytest.raises(CaseError, match="cannot remove row 15"):
        network.build_ybus(case, drop=[14])
    # round 43: -1 was named "row 0"; 1.5 removed row 1
    with pytest.raises(CaseError, match=r"cannot remove branch index -1: .* 0 to 13"):
        solve_powerflow(case, drop=[-1])
    for odd in (1.5, "3", None, True):
        with pytest.raises(WrongTypeError, match=r"0-based whole-number indices, got "):
            network.build_ybus(case, drop=[odd])
    with pytest.raises(CaseError, match="line row 5 is not in service"):
        network.Network.from_case(case, drop=[4]).without([4])


def test_add_shunts():
    case = load_case("kundur")
    y = network.build_ybus(case)
    y2 = network.add_shunts(y, [0, 0, 3], [1 + 1j, 2, -5j])
    d = (y2 - y).toarray()
    assert d[0, 0] == 3 + 1j and d[3, 3] == -5j and np.count_nonzero(d) == 2


@pytest.mark.filterwarnings("ignore:.*tap iterations:RuntimeWarning")
def test_a_flow_that_fails_only_with_q_limits_says_so():
    """Kundur with three times its reactive load and +-5 Mvar at its generators diverges
    with the Q limits and converges without them: the error says the second (as ANDES
    solves its cases), and a flow that fails both ways says nothing of it."""
    case = load_case("kundur")
    b = case.buses
    pv = b.kind == PV
    tight = case.replace(
        buses=b.replace(
            qmax=np.where(pv, 0.05, b.qmax), qmin=np.where(pv, -0.05, b.qmin), qload=3 * b.qload
        )
    )
    with pytest.raises(PowerFlowError, match="with the PV buses' Q limits off it converges"):
        solve_powerflow(tight)
    assert solve_powerflow(tight, q_limits=False).max_mismatch < 1e-8
    hopeless = case.replace(buses=b.replace(pload=30 * b.pload))
    with pytest.raises(PowerFlowError) as err:
        solve_powerflow(hopeless)
    assert "Q limits off" not in str(err.value)


def _with_kind(case, bus, kind):
    kinds = case.buses.kind.copy()
    kinds[case.bus_index(bus)] = kind
    return case.replace(buses=case.buses.replace(kind=kinds))


def test_two_swing_buses_of_one_island_are_held_and_said():
    """Kundur's PV bus 2 made a second swing bus (kind 1): the flow holds both at their
    magnitude and angle, as PSS/E holds several type-3 buses, and says so naming both (it
    ran without a word); a swing bus per island (an island of its own for bus 99) says
    nothing."""
    case = _with_kind(load_case("kundur"), 2, 1)
    with pytest.warns(
        UserWarning,
        match=r"case 'kundur': buses 1 and 2 are both swing buses \(kind 1\) of one island: "
        r"the power flow holds each at its voltage magnitude and angle",
    ):
        res = solve_powerflow(case)
    for bus in (1, 2):
        i = case.bus_index(bus)
        assert res.vmag[i] == case.buses.vmag[i]
        assert res.vang_deg[i] == pytest.approx(case.buses.vang_deg[i], abs=1e-12)
    islands = _with_kind(with_dead_island(load_case("kundur")), 99, 1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        solve_powerflow(islands)
        solve_powerflow(load_case("kundur"))
