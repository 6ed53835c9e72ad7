"""Runs share their quiet start (`stabctl.dynamics.prefix`): the copied stretch is the
trajectory the run integrates itself, bit for bit."""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.grid import time_grid
from stabctl.dynamics.prefix import quiet_end, reach
from stabctl.stability.cct import LineFault

QUANTITIES = ("t", "speed", "angle", "pelect", "pmech", "efd", "vmag", "vang")


def _whole(sim, events, t_end, **kw):
    """The run integrated from t = 0 (a monitor that never stops it keeps the prefix
    out: `Simulator.run`, monitor)."""
    return sim.run(events, t_end, monitor=lambda partial: None, **kw)


@pytest.mark.parametrize(("name", "bus", "far_bus"), [("kundur", 3, 101), ("wecc", 40, 44)])
@pytest.mark.parametrize("voltages", [True, False])
def test_a_run_from_a_shared_quiet_start_equals_the_run_integrated_whole(
    request, name, bus, far_bus, voltages
):
    """Three clearing times of one fault, the later runs from the first's quiet start
    (the second before the fault at 1 s): every recorded quantity equals the run
    integrated from t = 0, bit for bit, the unstable one's separation included."""
    case = request.getfixturevalue(name).case
    sim = Simulator(case)
    fault = LineFault(bus, far_bus)
    for tc in (0.05, 0.12, 0.3):
        events = fault.events(tc)
        shared = sim.run(events, 3.0, stop_at_separation=True, voltages=voltages)
        whole = _whole(sim, events, 3.0, stop_at_separation=True, voltages=voltages)
        for q in QUANTITIES:
            np.testing.assert_array_equal(getattr(shared, q), getattr(whole, q), err_msg=q)
        assert shared.stable == whole.stable and shared.separated == whole.separated
    assert len(sim._prefixes) == 1  # one quiet start served the three


def test_the_quiet_start_of_another_step_or_fault_time_is_its_own(kundur):
    """A run at half the step or with the fault at another time does not take the
    prefix of another: its trajectory equals its whole run."""
    sim = Simulator(kundur.case)
    base = LineFault(3, 101)
    sim.run(base.events(0.1), 2.0)
    for events, h in (
        (base.events(0.1), sim.default_h / 2),
        (LineFault(3, 101, t_fault=0.5).events(0.1), None),
    ):
        shared = sim.run(events, 2.0, h=h)
        whole = _whole(sim, events, 2.0, h=h)
        for q in QUANTITIES:
            np.testing.assert_array_equal(getattr(shared, q), getattr(whole, q), err_msg=q)
    assert len(sim._prefixes) == 3


def test_the_quiet_start_ends_one_point_before_the_first_event():
    """The first interval of a grid with a fault at 1 s and h = 0.3 s: points 0, 0.25,
    0.5, 0.75 (ceil(1/0.3) = 4 equal steps), then the fault's point 1.0: the prefix
    ends at index 3 (the step ending at the event may already use the next network);
    a grid without events has none."""
    g = time_grid([0.0, 1.0, 1.1], 2.0, 0.3)
    np.testing.assert_allclose(g.t[:5], [0.0, 0.25, 0.5, 0.75, 1.0])
    assert quiet_end(g.interval) == 3
    assert quiet_end(time_grid([0.0], 2.0, 0.3).interval) == 0


def test_the_limiters_reach_is_the_nominal_step_on_the_ieee_grid():
    """ieee: every step at most h, so the reach is h whatever the events; PSTess's grid:
    its longest step (fix(length/h) steps, up to 2h: 1.0 s in 3 steps of 1/3 s at h =
    0.3 s)."""
    h = 0.3
    for starts in ([0.0, 1.0, 1.1], [0.0, 1.0, 1.17]):
        g = time_grid(starts, 2.0, h)
        assert np.max(g.h) <= h and reach(g.h, g.step) == h
    g = time_grid([0.0, 1.0], 2.0, h, pstess=True)
    assert reach(g.h, g.step) == pytest.approx(1 / 3)


def test_runs_with_a_bang_bang_fleet_share_their_quiet_start_bit_for_bit(kundur):
    """The paper's 5 % fleet (bang-bang on the COI speed): the devices' powers, switching
    logs and energy statistics of a run from the shared quiet start equal the whole run's;
    another fleet rating gets its own prefix."""
    from stabctl.storage.devices import uniform_fleet

    sim = Simulator(kundur.case)
    fault = LineFault(3, 101)
    for pct in (5, 5, 10):
        fleet = uniform_fleet(kundur.case, pct)
        for tc in (0.1, 0.2):
            shared = sim.run(fault.events(tc), 3.0, storage=fleet)
            whole = _whole(sim, fault.events(tc), 3.0, storage=fleet)
            for q in (*QUANTITIES, "pesd"):
                np.testing.assert_array_equal(getattr(shared, q), getattr(whole, q), err_msg=q)
            assert whole.meta["switchings"] and whole.meta["storage"]  # the devices acted
            for key in ("switchings", "storage"):  # the log and each device's figures
                assert repr(shared.meta[key]) == repr(whole.meta[key]), key
    assert len(sim._prefixes) == 2  # one per fleet rating


def test_a_prefix_keeps_no_model_alive(kundur):
    """A prefix refers to its model weakly: once the simulator's model cache drops a
    fleet's model (`MODELS_KEPT`), the prefixes do not keep it (and its reduced networks)
    in memory."""
    import gc
    import weakref

    from stabctl.dynamics.bounded import BoundedCache
    from stabctl.dynamics.driver import MODELS_KEPT
    from stabctl.storage.devices import uniform_fleet

    sim = Simulator(kundur.case)
    fleet = uniform_fleet(kundur.case, 5)
    sim.run(LineFault(3, 101).events(0.1), 2.0, storage=fleet)
    assert len(sim._prefixes) == 1
    model = weakref.ref(sim.model_for(fleet.buses))
    assert model() is not None and model() is not sim.model
    sim._models = BoundedCache(MODELS_KEPT)  # as if 8 other fleets had pushed it out
    gc.collect()
    assert model() is None
