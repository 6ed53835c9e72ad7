"""Intervals stepped finer where a machine's subtransient time constant in the interval's
network is shorter than the step (`Simulator.stiff_substeps`).

ANDES's IEEE 39 (ieee39_full.xlsx) gives nine of its ten GENROU an x"d below their
leakage reactance (G5: x"d 0.00571 pu on its 1080.2 MVA, x'd 1.32, T"do 0.03 s).  With a
bolted fault at such a machine's terminal its damper's time constant is T"do x"d / x'd
(0.13 ms for G5): every run of a terminal fault at the default 8.3 ms diverged in its
first fault-on step ("numerical instability ... use a smaller step"), and 4.2, 3 and 2 ms
did too, so a screening recorded nine of its 39 bus faults failed.  The references: the
closed form of the short-circuit time constant, runs at a uniform step far below every
time constant, and the cases whose time constants the default step already respects,
whose grids stay as they were."""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault, stages
from stabctl.io import load_case

andes = pytest.importorskip("andes")


def networks(sim, events, t_end):
    """The network of each interval of a run of `events` to t_end, as the run has them."""
    _, configs = stages(sim.case, events, t_end, sim.op.V)
    return [sim.model.network(c) for c in configs]


@pytest.fixture(scope="module")
def ieee39(tmp_path_factory):
    """ANDES's ieee39_full imported as `stabctl import-andes` imports it."""
    from stabctl.io.andes_case import read_andes_case

    return read_andes_case(andes.get_case("ieee39/ieee39_full.xlsx")).case


def test_a_bolted_terminal_fault_gives_the_short_circuit_time_constant(ieee39):
    """With a bolted fault at G5's terminal (bus 34) the machine sees no reactance: its
    subtransient time constant is the closed form T"do x"d / x'd (q axis alike); in the
    network before the fault it sees its step-up transformer and the grid, and the
    constant is longer."""
    sim = Simulator(ieee39)
    m = sim.model
    g5 = int(np.flatnonzero(ieee39.machines.bus == 34)[0])
    mac = ieee39.machines
    closed = min(
        mac.Tdopp[g5] * mac.xdpp[g5] / mac.xdp[g5], mac.Tqopp[g5] * mac.xqpp[g5] / mac.xqp[g5]
    )
    fault_on = networks(sim, [Fault(34, 1.0, 1.05)], 2.0)[1]
    T = m.subtransient_time_constants(fault_on, 1.0)
    assert T[g5] == pytest.approx(closed, rel=1e-3)  # the bolted fault: a 1e7 pu shunt
    assert closed == pytest.approx(0.13e-3, rel=0.01)
    before = m.subtransient_time_constants(networks(sim, [], 2.0)[0], 1.0)
    assert closed < before[g5] < mac.Tdopp[g5]


def test_terminal_faults_run_at_the_default_step_and_converge_with_it(ieee39):
    """Every bolted fault at a generator terminal of IEEE 39 runs at the default step
    (before: numerical instability), and the largest angle from the COI comes within
    0.015 rad of a run at a uniform 0.05 ms (below a third of the shortest time
    constant, G5's 0.13 ms), closer at half the step: the error the half-step check
    reports is the stiff intervals' too."""
    sim = Simulator(ieee39)
    for bus in (30, 34, 39):
        events = [Fault(bus, 1.0, 1.05)]
        h = sim.default_h
        at_h = sim.run(events, t_end=1.4).max_angle_from_coi
        half = sim.run(events, t_end=1.4, h=h / 2).max_angle_from_coi
        fine = Simulator(ieee39, step=5e-5).run(events, t_end=1.4).max_angle_from_coi
        assert abs(at_h - fine) < 0.015, (bus, at_h, fine)
        assert abs(half - fine) <= abs(at_h - fine) + 1e-4, (bus, half, at_h, fine)


def test_a_run_at_half_the_step_halves_the_stiff_intervals_steps_too(ieee39):
    """The fault-on interval at bus 34 is cut into as many steps per nominal step at h/2
    as at h, so its steps halve with the nominal step."""
    sim = Simulator(ieee39)
    h = sim.default_h
    events = [Fault(34, 1.0, 1.05)]
    grids = [sim.run(events, t_end=1.2, h=x).t for x in (h, h / 2)]
    steps = [np.diff(t[(t > 1.0 + 1e-9) & (t < 1.05 - 1e-9)]) for t in grids]
    assert steps[0].max() < 0.5e-3  # cut far below 8.3 ms
    assert steps[1].max() == pytest.approx(steps[0].max() / 2, rel=1e-6)


def test_a_cct_search_says_the_shortest_step_its_runs_took(ieee39):
    """`cct` printed "step 8.333 ms" where its runs stepped at about 4.1 ms throughout
    (G5's 7.5 ms time constant in IEEE 39's own network): the result gives the shortest
    step of an interval cut (`stiff_step_s`), the grids' own."""
    from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time

    sim = Simulator(ieee39)
    fault = LineFault(26, 29)
    res = critical_clearing_time(sim, fault, SearchOptions(tol=0.02, error_check=False))
    run = sim.run(fault.events(res.cct_s), t_end=fault.t_fault + 5.0)
    shortest = min(c["step_s"] for c in run.meta["stiff_intervals"])
    # the search's shortest over all its runs: at most this run's; each cut in two here
    assert sim.default_h / 3 < res.stiff_step_s <= shortest < sim.default_h / 2 + 1e-12
    assert res.to_dict()["stiff_step_s"] == res.stiff_step_s


@pytest.mark.parametrize("name, bus", [("kundur", 1), ("miniwecc", 83)])
def test_cases_whose_time_constants_the_step_respects_keep_their_grid(name, bus):
    """Kundur and miniWECC (their shortest short-circuit subtransient time constants
    22.7 and 15.4 ms against the 5 ms step): no interval is cut, a terminal fault's
    included."""
    sim = Simulator(load_case(name))
    m = sim.model
    for net in networks(sim, [Fault(bus, 1.0, 1.1)], 3.0):
        assert sim.stiff_substeps(m, net) == 1
    t = sim.run([Fault(bus, 1.0, 1.1)], t_end=1.5).t
    assert np.allclose(np.diff(t)[np.diff(t) > 0], sim.default_h, rtol=1e-9, atol=0)
