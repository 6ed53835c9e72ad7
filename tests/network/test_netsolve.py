"""The kept-bus load solution (stabctl.network.solution.solve_nc, PST nc_load) on miniWECC's
network with a bolted fault at bus 40, where PST's 0.5 pu load switch leaves the
equations without a solution for some loads: the loads near the switch are held at their
impedance model, the hold is carried to the next evaluation, and released when the
voltage recovers.  Checked by the residual of the equations (to 1e-10) and by equality
with the solution found from scratch."""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator, _Run
from stabctl.dynamics.events import Fault
from stabctl.io import load_case
from stabctl.models.machines import internal_voltage
from stabctl.network.solution import (
    V_RELEASE,
    V_SWITCH,
    _load_mismatch,
    solve_nc,
)


@pytest.fixture(scope="module")
def fault_network():
    """(model, fault-on network, pre-fault network, internal voltages, kept-bus voltages)
    0.3 s into the fault, where the machines have swung and the hold is needed."""
    sim = Simulator(load_case("miniwecc"))
    m, sa, grid, nets = sim._prepare([Fault(40, 1.0, 1.6)], 2.0, None, None, "pst")
    run = _Run(sim, m, sa, grid, nets, True, np.pi, False)
    k = int(np.searchsorted(grid.t, 1.3))
    run.advance(k)
    n = m.mp.n
    psi = np.empty(n, complex)
    internal_voltage(m.params.MP, run.x[: 6 * n].reshape(6, n), psi, np.empty(n, complex))
    return m, nets[grid.interval[k]], nets[0], psi, run.V_nc.copy()


def solve(m, net, psi, V, held):
    p = m.params
    loads = p.loads.copy()
    it = solve_nc(net.Y21, net.Y22, net.Z22, psi, V, loads, held)
    F = np.empty(V.size, complex)
    resid = _load_mismatch(net.Y21 @ psi, net.Y22, V, loads, F, held)
    return it, resid


def test_fault_holds_loads_near_the_switch_and_reuses_the_hold(fault_network):
    m, fault, _, psi, V_fault = fault_network
    V, held = V_fault.copy(), np.zeros(V_fault.size, np.bool_)
    it, resid = solve(m, fault, psi, V, held)
    assert it >= 0 and resid < 1e-10
    assert 0 < held.sum() < held.size  # some loads, not all
    assert np.all(np.abs(V[held]) < V_RELEASE)
    # the next evaluation starts from the hold and lands on the same solution
    V2, held2 = V.copy(), held.copy()
    it2, resid2 = solve(m, fault, psi, V2, held2)
    assert it2 >= 0 and resid2 < 1e-10
    np.testing.assert_array_equal(held2, held)
    np.testing.assert_allclose(V2, V, atol=1e-9)


def test_hold_is_released_when_the_voltage_recovers(fault_network):
    m, fault, prefault, psi, V_fault = fault_network
    V, held = V_fault.copy(), np.zeros(V_fault.size, np.bool_)
    solve(m, fault, psi, V, held)
    assert held.any()
    # the pre-fault network with a stale hold: every load back above the switch, no hold
    V_held = m.V_nc0.copy()
    it, resid = solve(m, prefault, psi, V_held, held)
    assert it >= 0 and resid < 1e-10 and not held.any()
    V_free, free = m.V_nc0.copy(), np.zeros(m.V_nc0.size, np.bool_)
    solve(m, prefault, psi, V_free, free)
    np.testing.assert_allclose(V_held, V_free, atol=1e-9)
    assert np.all(np.abs(V_free) > V_SWITCH)


def test_lapack_solve_matches_numpy_and_reports_a_singular_matrix():
    from stabctl.network.solution import _lapack_solve

    rng = np.random.default_rng(3)
    A, b = rng.normal(size=(12, 12)), rng.normal(size=12)
    A_before = A.copy()
    x, info = _lapack_solve(A, b)
    assert info == 0 and np.allclose(A @ x, b, atol=1e-12)
    assert np.array_equal(A, A_before)  # the input is left alone
    _, info = _lapack_solve(np.array([[1.0, 2.0], [2.0, 4.0]]), np.ones(2))
    assert info == 2  # U[1, 1] = 0 (dgesv's INFO)


def test_a_converter_current_growing_with_the_voltage_is_solved_with_the_network():
    """A REGCA1 below its low-voltage gain's upper point Lvpnt1 draws an active current Ip
    (v - Lvpnt0)/(Lvpnt1 - Lvpnt0) that grows with its bus voltage v (ANDES regca1.py
    192-196; the network solution takes it as affine in |V|, its load rows): the solved
    kept-bus voltages satisfy the network equations with the currents the converters draw
    at those voltages (`conv.drawn_current`), to 1e-10 pu, whether the voltage is on the
    gain's slope or above it."""
    from stabctl.models import converters as conv
    from stabctl.storage.devices import StorageFleet, battery_case, uniform_fleet

    case = load_case("kundur")
    fleet = uniform_fleet(case, 5, model="wecc")
    for lvpnt1, on_slope in ((1.5, True), (0.8, False)):
        wecc = StorageFleet(fleet.devices, model="wecc", battery={"Lvpnt1": lvpnt1})
        m = Simulator(battery_case(case, wecc)[0]).model
        L, n, ni = m.layout, m.mp.n, m.cp.n
        x = m.x0.copy()
        xi = L.view(x, "ibr")
        xi[0] = 4.0  # Ip = 4 pu: every battery injecting (idle at the operating point)
        net = m.network()
        _dx, out = m.evaluate(x, net, m.V_nc0)
        psi = np.empty(n, complex)
        internal_voltage(m.params.MP, x[: 6 * n].reshape(6, n), psi, np.empty(n, complex))
        V = out.V_nc
        drawn = np.zeros(V.size, complex)
        slope = 0.0
        for k in range(ni):
            pos = int(m.cp.pos[k])
            rel, fix = conv.drawn_current(m.params.IP, xi, k, abs(V[pos]))
            drawn[pos] += np.conj(rel * abs(V[pos])) / np.conj(V[pos]) + fix
            up = conv.drawn_current(m.params.IP, xi, k, abs(V[pos]) + 0.01)[0]
            slope = max(slope, abs(up - rel) / 0.01)
        p = m.params
        loads = p.loads.copy()
        F = np.empty(V.size, complex)
        _load_mismatch(net.Y21 @ psi, net.Y22, V, loads, F, np.zeros(V.size, np.bool_))
        assert np.max(np.abs(F + drawn)) < 1e-10
        assert (slope > 1e-3) == on_slope  # the case is on the gain's slope or not


@pytest.mark.parametrize("name", ["kundur", "miniwecc"])
def test_the_sparse_reduction_is_the_dense_one(name, monkeypatch):
    """Above `DENSE_MAX` buses the network is reduced with a sparse LU (SuperLU) of its
    eliminated part, so that a 10 000-bus case needs memory in its kept buses only (a
    dense LU of order 10 400 took 1.7 GB): on Kundur and miniWECC, reduced both ways, a
    6-cycle fault's run gives the same speeds within 1e-12 pu."""
    import stabctl
    from stabctl.dynamics.events import fault_with_clearing
    from stabctl.network import solution

    case = stabctl.load_case(name)
    bus, far = (3, 101) if name == "kundur" else (83, 33)
    events = [fault_with_clearing(case, bus, far, 1.0, 6)]
    dense = stabctl.Simulator(case).run(events, t_end=2.0)
    monkeypatch.setattr(solution, "DENSE_MAX", 0)
    sparse = stabctl.Simulator(case).run(events, t_end=2.0)
    assert np.max(np.abs(sparse.speed - dense.speed)) < 1e-12
    assert np.max(np.abs(sparse.vmag - dense.vmag)) < 1e-10


def test_a_stage_updated_from_the_pre_event_reduction_is_the_stage_reduced_anew(monkeypatch):
    """A network reduced sparse reduces each stage that changes a few nodes by a low-rank
    (Woodbury) update of the pre-event network's reduction (`stabctl.network.lowrank`):
    a bolted fault, a line opened, a line cleared at one end (a fault node fed from the
    far end), a machine tripped and a load step on miniWECC give the matrices of the
    stage factorised anew within 1e-12 of their largest entry."""
    import stabctl
    from stabctl.dynamics.model import FAULT_B, StageConfig
    from stabctl.network import solution

    monkeypatch.setattr(solution, "DENSE_MAX", 0)
    case = stabctl.load_case("miniwecc")
    model = stabctl.Simulator(case).model
    assert model.network().factor is not None
    b83, row = case.bus_indices([83])[0], 0
    far = int(case.branches.to_bus[row])
    configs = [
        StageConfig(faults=((b83, -1j * FAULT_B),)),
        StageConfig(opened=(row,)),
        StageConfig(fault_feeds=((row, far, True),)),
        StageConfig(tripped_machines=(3,)),
        StageConfig(load_steps=((b83, 0.5 + 0.2j),)),
    ]
    for config in configs:
        updated = model._reduce(config)
        monkeypatch.setattr(model, "_pre_event_factor", lambda config: None)
        anew = model._reduce(config)
        monkeypatch.undo()
        monkeypatch.setattr(solution, "DENSE_MAX", 0)
        assert updated.factor is None and anew.factor is not None, config
        for name in ("Y11", "Y12", "Y21", "Y22", "R", "R_mac", "Z_mac"):
            a, b = getattr(updated, name), getattr(anew, name)
            assert a.shape == b.shape
            if b.size:
                assert np.abs(np.asarray(a) - b).max() <= 1e-12 * np.abs(b).max(), (config, name)


def test_a_low_rank_matrix_gives_the_same_numbers_read_by_rows_by_slice_or_whole():
    """An updated stage keeps R = [rec; 0] - G F (`stabctl.network.lowrank.LowRankRows`)
    and forms only the rows a run reads: the whole matrix is that formula's numbers bit
    for bit; rows read by index (the base's and an added node's) and a leading slice
    agree with them to rounding (a product of fewer rows may take another BLAS kernel);
    a non-finite G is found."""
    from stabctl.network.lowrank import LowRankRows

    rng = np.random.default_rng(1)
    top = rng.normal(size=(6, 4)) + 1j * rng.normal(size=(6, 4))
    G = rng.normal(size=(8, 2)) + 1j * rng.normal(size=(8, 2))
    F = rng.normal(size=(2, 4)) + 1j * rng.normal(size=(2, 4))
    dense = np.vstack([top, np.zeros((2, 4))]) - G @ F
    low = LowRankRows(top, G, F)
    assert low.shape == dense.shape and low.all_finite()
    assert np.array_equal(np.asarray(low), dense)
    rows = np.array([7, 0, 3, 3])
    scale = np.abs(dense).max()
    assert np.abs(low[rows] - dense[rows]).max() <= 1e-15 * scale
    assert np.abs(np.asarray(low[:5]) - dense[:5]).max() <= 1e-15 * scale
    G[1, 0] = np.nan
    assert not LowRankRows(top, G, F).all_finite()
