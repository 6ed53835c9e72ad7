"""Storage devices after a trip or a split (`stabctl.dynamics.partition`): each device
watches its machine against the centre of inertia (paper eq. 40) of the machine's island
in the current network stage, not of the islands before the disturbance.  A device whose
machine is tripped, or cut off alone from the main grid, sees relative speed 0 and idles;
the devices of the main grid follow the COI of the machines left there.  The compiled
loop's stop at separation judges the same machines as the verdict."""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault, GeneratorTrip
from stabctl.dynamics.integrator import run_options
from stabctl.io import load_case
from stabctl.storage.control import BangBangCOI, LinearFeedback
from stabctl.storage.devices import uniform_fleet

T_FAULT, T_CLEAR = 1.0, 1.1


@pytest.fixture(scope="module")
def kundur():
    case = load_case("kundur")
    return case, Simulator(case)


def own_relative_speed(res, keep):
    """omega_i - omega_COI (pu) of the machines `keep` (indices) against the COI of those
    machines alone (eq. 40, weights H * MVA), computed here from the recorded speeds."""
    M = res.inertia[keep]
    w = res.speed[:, keep]
    return w - (w @ M / M.sum())[:, None]


def check_bang_bang_follows(res, case, keep, after, margin_hz=0.01):
    """At the grid points `after` (bool, n_t), each device of the machines `keep` (device
    d at machine d) absorbs its rating where its machine runs more than the deadband
    (0.1 Hz, plus `margin_hz` for the located switching) ahead of the COI of `keep`,
    injects it where it runs that much behind and idles well inside the band, its bus
    voltage above the 0.8 pu gate."""
    r_hz = own_relative_speed(res, keep)[after] * case.freq_hz
    P = res.pesd[after][:, keep]
    pmax = np.array([res.meta["storage"][d]["pmax_mw"] for d in keep]) / case.base_mva
    buses = [res.meta["storage"][d]["bus"] for d in keep]
    v = res.vmag[after][:, [list(res.buses).index(b) for b in buses]]
    gate = v >= 0.8 + 1e-3
    above, below = r_hz > 0.1 + margin_hz, r_hz < -0.1 - margin_hz
    inside = np.abs(r_hz) < 0.1 - margin_hz
    assert ((above | below) & gate).any() and (inside & gate).any()  # cases to check
    assert np.all(P[above & gate] == np.broadcast_to(pmax, P.shape)[above & gate])
    assert np.all(P[below & gate] == -np.broadcast_to(pmax, P.shape)[below & gate])
    assert np.all(P[inside & gate] == 0.0)


def islanded_and_tripped(sim, fleet, t_clear=T_CLEAR, t_end=6.0, **kw):
    """The fault at bus 1 cleared at t_clear by opening G1's step-up transformer 1-10 (G1
    islanded, alone at bus 1; its device stays at bus 10, in the main grid), and the same
    fault cleared without the line and G1 tripped at that instant, with the fleet; each
    with its repeated grid times dropped (the zero-length interval between near- and
    far-end clearing)."""
    out = []
    for events in (
        [Fault(bus=1, t=T_FAULT, clear_near=t_clear, clear_far=t_clear, far_bus=10)],
        [Fault(bus=1, t=T_FAULT, clear_near=t_clear), GeneratorTrip(1, t_clear)],
    ):
        res = sim.run(events, t_end, storage=fleet, **kw)
        out.append((res, np.r_[np.diff(res.t) > 0, True]))
    return out


def test_an_islanded_generators_device_idles_and_the_others_follow_the_main_grid(kundur):
    """Kundur's bus-1 fault cleared at 1.1 s by opening 1-10 islands G1, which runs away
    with no load.  G1's device watches G1 against G1's own island, G1 alone: relative
    speed 0, it idles from the clearing on (before, it compared G1 with the COI of all
    four machines and absorbed its 45 MW for the rest of the run).  The devices of G2-G4
    follow the COI of G2-G4: their modes agree with the relative speeds computed here
    from the recorded speeds, and their powers, switchings and machines those of the run
    with G1 tripped at the clearing instant (the open line keeps a 1e7 pu reactance)."""
    case, sim = kundur
    fleet = uniform_fleet(case, 5)
    (isl, a), (trip, b) = islanded_and_tripped(sim, fleet)
    assert isl.meta["islanded"] == [{"t_s": T_CLEAR, "buses": [1], "machines": [1]}]
    assert isl.speed[-1, 0] > 1.1  # G1 runs away ...
    after = isl.t >= T_CLEAR
    assert np.all(isl.pesd[after, 0] == 0.0)  # ... and its device idles
    assert np.all(trip.pesd[trip.t >= T_CLEAR, 0] == 0.0)  # as the tripped G1's
    rest = [1, 2, 3]
    check_bang_bang_follows(isl, case, rest, after & (isl.t > T_CLEAR + 0.05))
    late = isl.t > T_CLEAR + 1e-9  # the result's relative speeds are what the devices see
    assert (
        np.abs(isl.relative_speed[late][:, rest] - own_relative_speed(isl, rest)[late]).max()
        < 1e-15
    )
    assert np.all(isl.relative_speed[late, 0] == 0.0)  # G1 alone in its island
    assert np.array_equal(isl.t[a], trip.t[b])
    assert np.abs(isl.pesd[a][:, rest] - trip.pesd[b][:, rest]).max() < 1e-9
    assert np.abs(isl.angle[a][:, rest] - trip.angle[b][:, rest]).max() < 1e-6
    assert np.abs(isl.speed[a][:, rest] - trip.speed[b][:, rest]).max() < 1e-8
    log_isl, log_trip = (np.array(r.meta["switchings"]) for r in (isl, trip))
    assert log_isl.shape == log_trip.shape and log_isl.shape[0] > 10
    assert np.array_equal(log_isl[:, 1:3], log_trip[:, 1:3])  # devices and modes
    assert np.abs(log_isl[:, 0] - log_trip[:, 0]).max() < 1e-6  # times, s
    for d in (1, 2, 3):
        mine, theirs = isl.meta["storage"][d], trip.meta["storage"][d]
        assert mine["switchings"] == theirs["switchings"] > 0
        assert mine["energy_absorbed_mj"] == pytest.approx(theirs["energy_absorbed_mj"], 1e-6)


@pytest.mark.parametrize(
    "law",
    [BangBangCOI(), BangBangCOI(coi="rest"), LinearFeedback(Kv=0.5)],
    ids=["bang-bang", "bang-bang-rest", "linear"],
)
def test_a_tripped_generators_device_does_nothing_after_the_trip(kundur, law):
    """G4 tripped at 1 s (its rotor runs away, more than pi ahead by 3 s): its device sees
    relative speed 0 from the trip on, under every law and reference (the "rest" of an
    island of one machine is empty: 0, not a division by zero), and delivers nothing;
    before, it braked the out-of-service G4 at its full rating.  The devices of G1-G3
    follow the COI of G1-G3: the bang-bang modes agree with the relative speeds computed
    here, the linear law's powers are Kv (omega_i - omega_COI) to round-off."""
    case, sim = kundur
    fleet = uniform_fleet(case, 5, law)
    res = sim.run([GeneratorTrip(4, 1.0)], 3.0, storage=fleet)
    assert res.stable and res.meta["tripped"] == [{"t_s": 1.0, "machines": [4]}]
    after = res.t >= 1.0
    assert np.all(res.pesd[after, 3] == 0.0)
    assert np.all(np.isfinite(res.pesd))
    keep = [0, 1, 2]
    if isinstance(law, LinearFeedback):
        after[-1] = False  # the end point records the powers of the last step
        r = own_relative_speed(res, keep)[after]
        pmax = fleet.devices[0].pmax_mw / case.base_mva
        want = np.clip(law.Kv * 2 * np.pi * case.freq_hz * r, -pmax, pmax)
        assert np.abs(want).max() > 0.1 * pmax
        assert np.abs(res.pesd[after][:, keep] - want).max() < 1e-9
    elif law.coi == "system":
        check_bang_bang_follows(res, case, keep, after)
    else:
        assert res.meta["storage"][0]["switchings"] > 0


def test_the_compiled_loop_stops_a_run_for_judged_machines_only(kundur):
    """With stop_at_separation the compiled loop itself judges the stage's partition: G4
    tripped (running away) never stops the run, which goes to its end; with a 1 % fleet
    the bus-1 fault cleared at 1.5 s by opening 1-10 stops where G2 leaves the COI of
    G2-G4 (4.89 s, the full run's verdict; G1 islanded and running away is not judged),
    its trajectory the full run's up to there, and the switchings the devices counted are
    those of the result's log (the storage figures end with the trajectory: before, the
    run was cut after pieces of 0.1 s, and G3's device switched once more in the piece
    after the separation)."""
    case, sim = kundur
    res = sim.run([GeneratorTrip(4, 1.0)], 3.0, stop_at_separation=True)
    assert res.stable and res.t[-1] == 3.0
    fleet = uniform_fleet(case, 1)
    (full, _), _ = islanded_and_tripped(sim, fleet, t_clear=1.5)
    (stopped, _), _ = islanded_and_tripped(sim, fleet, t_clear=1.5, stop_at_separation=True)
    assert not full.stable and full.separated == [2]
    assert full.t_separation == pytest.approx(4.89, abs=1e-9) and full.speed[-1, 0] > 1.1
    assert stopped.t[-1] == stopped.t_separation == full.t_separation
    assert stopped.separated == [2]
    n = stopped.t.size
    assert np.array_equal(stopped.angle, full.angle[:n])
    assert np.array_equal(stopped.pesd, full.pesd[:n])
    counted = [d["switchings"] for d in stopped.meta["storage"]]
    logged = np.bincount([s[1] - 1 for s in stopped.meta["switchings"]], minlength=4)
    assert counted == list(logged)


def test_run_options_hold_each_stages_islands(kundur):
    """The compiled loop's options: one row per network stage; without partitions every
    row is the islands before the disturbance, every machine judged; with them, each
    stage's partition (G4 tripped at 1 s: alone in an island of its own, not judged)."""
    _, sim = kundur
    plain = run_options(False, sim.inertia, sim.island, (), 3, np.pi, True)
    assert plain.inertia.shape == plain.island.shape == plain.judged.shape == (3, 4)
    assert np.all(plain.inertia == sim.inertia) and np.all(plain.island == sim.island)
    assert plain.judged.all() and plain.island.dtype == np.int64
    parts = sim.run([GeneratorTrip(4, 1.0)], 1.5).partitions
    opts = run_options(False, sim.inertia, sim.island, parts, len(parts), np.pi, True)
    assert opts.island.tolist() == [[0, 0, 0, 0], [0, 0, 0, 1]]
    assert opts.judged.tolist() == [[True] * 4, [True, True, True, False]]
    assert np.array_equal(opts.inertia[0], sim.inertia)
