"""Storage devices and the paper's bang-bang COI controller (Section 5, Table 3)."""

import numpy as np
import pytest

from stabctl.dynamics.driver import CommandFrames, Simulator
from stabctl.dynamics.events import Fault, fault_with_clearing
from stabctl.errors import InputError
from stabctl.io import load_case
from stabctl.network.ybus import build_ybus
from stabctl.storage.control import BangBangCOI, LinearFeedback, desired_mode, desired_modes
from stabctl.storage.devices import (
    StorageDevice,
    StorageFleet,
    energy_excursion,
    hv_bus,
    pack,
    uniform_fleet,
)

DB_PU = 0.1 / 60  # 100 mHz deadband in pu speed


@pytest.fixture(scope="module")
def kundur():
    """PSTess conventions: the clearing cycles below are PSTess 1.1's (docs/storage.md);
    the ieee figures are in reports/paper.md."""
    case = load_case("kundur")
    return case, Simulator(case, conventions="pstess")


def arrays(case, controller=BangBangCOI()):
    fleet = uniform_fleet(case, 5, controller)
    return pack(fleet, case, np.array(sorted(case.bus_indices(fleet.buses))))


@pytest.mark.parametrize(
    "mode,r,v,expected",
    [
        (0, 2 * DB_PU, 1.0, 1),  # faster than the COI beyond the band: absorb
        (0, -2 * DB_PU, 1.0, -1),  # slower: inject
        (0, 0.5 * DB_PU, 1.0, 0),  # inside the deadband: idle
        (0, -0.5 * DB_PU, 1.0, 0),
        (1, 0.5 * DB_PU, 1.0, 0),  # back inside the band: stop (no hysteresis)
        (0, 2 * DB_PU, 0.79, 0),  # bus voltage below the 0.8 pu gate: idle
        (1, 2 * DB_PU, 0.79, 0),
        (-1, -2 * DB_PU, 0.8, -1),  # at the gate: acts
    ],
)
def test_table3_decisions(kundur, mode, r, v, expected):
    case, _ = kundur
    assert desired_mode(arrays(case), 0, mode, r, v) == expected


def test_table3_decisions_of_every_device_at_once(kundur):
    # one device per machine (G1..G4): each reads its own machine's relative speed
    case, _ = kundur
    sa = arrays(case)
    rel = np.array([2, -2, 0.5, 0.5]) * DB_PU  # per machine
    mac = np.asarray(sa.mac)
    modes = desired_modes(sa, np.where(mac == 3, 1, 0), rel)  # G4's device running
    assert list(modes) == [[1, -1, 0, 0][m] for m in mac]


def test_hysteresis_keeps_a_running_device_on_inside_the_band(kundur):
    case, _ = kundur
    sa = arrays(case, BangBangCOI(hysteresis_hz=0.05))
    assert desired_mode(sa, 0, 1, 0.7 * DB_PU, 1.0) == 1  # above db - hyst: stays on
    assert desired_mode(sa, 0, 1, 0.4 * DB_PU, 1.0) == 0  # below: off
    assert desired_mode(sa, 0, 0, 0.7 * DB_PU, 1.0) == 0  # an idle one does not start


def test_devices_sit_at_the_generator_hv_buses(kundur):
    case, _ = kundur
    # Kundur (PST numbering): generators 1, 2, 11, 12 step up to 10, 20, 110, 120
    assert [hv_bus(case, m) for m in (1, 2, 3, 4)] == [10, 20, 110, 120]
    fleet = uniform_fleet(case, 5)
    assert [d.pmax_mw for d in fleet.devices] == [45.0] * 4  # 5 % of 900 MVA
    with pytest.raises(InputError):
        uniform_fleet(case, 0)


def test_case1_unstable_without_and_stable_with_control(kundur):
    """The paper's Case 1 fault (bus 3, line 3-101 at 1 s, line tripped).  In PSTess 1.1's
    d2asbegp the no-storage CCT is 16 cycles and 5 % storage raises it to 18 cycles, so the
    paper's claim is checked at 17 cycles; its 21 cycles needs 20 % here (docs/storage.md)."""
    case, sim = kundur
    for cycles, pct in ((17, 5), (21, 20)):
        fault = [fault_with_clearing(case, 3, 101, 1.0, cycles)]
        without = sim.run(fault, t_end=6.0)
        with_esd = sim.run(fault, t_end=6.0, storage=uniform_fleet(case, pct))
        assert not without.stable and without.separated == [1, 2]
        assert with_esd.stable


def test_area1_absorbs_area2_injects_after_clearing(kundur):
    case, sim = kundur
    r = sim.run(
        [fault_with_clearing(case, 3, 101, 1.0, 17)], t_end=3.0, storage=uniform_fleet(case, 5)
    )
    k = np.searchsorted(r.t, 1.35)
    assert list(np.sign(r.pesd[k])) == [1, 1, -1, -1]  # paper Figs. 14-15: C1, C2 absorb


def test_switching_instants_are_located_not_rounded(kundur):
    """At every speed-boundary switching the relative speed equals +-100 mHz to 1e-4 Hz,
    far tighter than rounding to the 10 ms step would give (~5 mHz)."""
    case, sim = kundur
    r = sim.run(
        [fault_with_clearing(case, 3, 101, 1.0, 17)], t_end=6.0, storage=uniform_fleet(case, 5)
    )
    h = 0.01
    speed_switches = [
        (t, rel) for t, _, _, rel in r.meta["switchings"] if abs(abs(rel) - 0.1) < 0.01
    ]
    assert len(speed_switches) >= 8
    assert all(abs(abs(rel) - 0.1) < 1e-4 for _, rel in speed_switches)
    off_grid = [t for t, _ in speed_switches if abs(t / h - round(t / h)) > 1e-6]
    assert len(off_grid) == len(speed_switches)


def test_no_chattering_and_energy_accounting(kundur):
    case, sim = kundur
    r = sim.run(
        [fault_with_clearing(case, 3, 101, 1.0, 17)], t_end=6.0, storage=uniform_fleet(case, 5)
    )
    for dev in r.meta["storage"]:
        assert dev["switchings"] <= 20  # a few per swing, no chattering
        assert dev["peak_power_mw"] == pytest.approx(45.0)
        p = r.pesd[:, dev["device"] - 1] * case.base_mva
        absorbed = np.trapezoid(np.clip(p, 0, None), r.t)
        assert dev["energy_absorbed_mj"] == pytest.approx(absorbed, rel=0.05, abs=1.0)


def test_state_of_charge_extremes_are_integrated_between_switchings(kundur):
    """The highest and lowest stored energy are integrated over the sub-steps that end at
    each located switching, as the energy absorbed and delivered: a device that only
    absorbs (only injects) along the run peaks at exactly what it absorbed (delivered).
    The trapezoid of its power sampled on the 10 ms grid (`energy_excursion`) misses that
    by a fraction of a MJ: a step that contains a switching is averaged across it."""
    case, sim = kundur
    r = sim.run(
        [fault_with_clearing(case, 3, 101, 1.0, 21)], t_end=6.0, storage=uniform_fleet(case, 5)
    )
    assert not r.stable  # 5 % does not hold 21 cycles (docs/storage.md)
    for i, dev in enumerate(r.meta["storage"]):
        one_sided = {dev["energy_absorbed_mj"], dev["energy_delivered_mj"]}
        assert 0.0 in one_sided and max(one_sided) > 100.0
        assert dev["soc_high_mj"] == pytest.approx(dev["energy_absorbed_mj"], rel=1e-12)
        assert dev["soc_low_mj"] == pytest.approx(-dev["energy_delivered_mj"], rel=1e-12)
        sampled = energy_excursion(r.t, r.pesd[:, i] * case.base_mva)
        peak = max(sampled["soc_high_mj"], -sampled["soc_low_mj"])
        assert abs(peak - max(one_sided)) > 0.1


def test_voltage_gate_idles_devices_near_the_fault(kundur):
    case, sim = kundur
    r = sim.run(
        [fault_with_clearing(case, 3, 101, 1.0, 17)], t_end=2.0, storage=uniform_fleet(case, 5)
    )
    on = (r.t > 1.0) & (r.t < 1.28)
    v10 = r.vmag[on, r.bus(10)]
    assert np.all(v10 < 0.8) and np.all(r.pesd[on, 0] == 0)


def _ungated_device_at_bus_10():
    """G1's device at its HV bus 10 (no load there), bang-bang without the voltage gate, so
    that it is commanded through a fault at its own bus."""
    dev = StorageDevice(bus=10, machine=1, pmax_mw=45.0)
    return StorageFleet((dev,), BangBangCOI(v_gate_pu=0.0))


@pytest.mark.parametrize("x", [0.01, 0.03, 0.1])  # bus 10 at 0.24-0.30, 0.49-0.60, 0.76-0.87 pu
def test_recorded_device_power_is_what_the_network_takes(kundur, x):
    # Kirchhoff's current law at bus 10, which has no load and no machine: the real power
    # the network takes there, Re(V conj((Y V)_10)) with Y the bus admittance matrix (the
    # fault's shunt is a pure reactance), is the device's power, at every recorded point:
    # below the 0.5 pu switch the network drops the device (0), above it the command.
    case, sim = kundur
    Y = build_ybus(case)
    r = sim.run([Fault(10, 1.0, 1.5, x=x)], t_end=2.5, storage=_ungated_device_at_bus_10())
    V = r.vmag * np.exp(1j * r.vang)
    b = r.bus(10)
    taken = (V[:, b] * np.conj(Y[[b]] @ V.T)[0]).real
    np.testing.assert_allclose(r.pesd[:, 0], -taken, rtol=0, atol=1e-9)
    assert np.any(r.pesd[:, 0] != 0.0)  # (the device acts in each run)


def test_dropped_device_keeps_its_state_of_charge(kundur):
    # the fault holds bus 10 at 0.24-0.30 pu, below the 0.5 pu switch, to the end of the
    # run: the device is commanded to absorb its rating from 1.05 s, the network takes
    # none of it, so no energy moves (the device is idle, inside its deadband, before)
    _case, sim = kundur
    r = sim.run([Fault(10, 1.0, None, x=0.01)], t_end=1.4, storage=_ungated_device_at_bus_10())
    dev = r.meta["storage"][0]
    assert [m for _, _, m, _ in r.meta["switchings"]] == [1]
    assert np.all(r.pesd == 0.0) and dev["peak_power_mw"] == 0.0
    # and the summary says so: commanded from its switching to the end, all of it idle
    t_on = r.meta["switchings"][0][0]
    assert dev["commanded_s"] == pytest.approx(1.4 - t_on, abs=2 * np.diff(r.t).max())
    assert dev["commanded_idle_s"] == dev["commanded_s"] > 0
    for key in ("energy_absorbed_mj", "energy_delivered_mj", "soc_high_mj", "soc_low_mj"):
        assert dev[key] == 0.0


def test_energy_limit_stops_absorption_when_full(kundur):
    case, sim = kundur
    dev = StorageDevice(bus=10, machine=1, pmax_mw=45.0, energy_mj=10.0, soc0=0.5)
    fleet = StorageFleet((dev,), BangBangCOI())
    r = sim.run([fault_with_clearing(case, 3, 101, 1.0, 17)], t_end=3.0, storage=fleet)
    absorbed = r.meta["storage"][0]["energy_absorbed_mj"]
    delivered = r.meta["storage"][0]["energy_delivered_mj"]
    assert absorbed - delivered <= 5.0 + 0.5  # room for 5 MJ at 50 % SOC


def test_linear_speed_law_is_proportional_and_clipped(kundur):
    case, sim = kundur
    fleet = StorageFleet(uniform_fleet(case, 5).devices, LinearFeedback(Kv=0.5))
    r = sim.run([fault_with_clearing(case, 3, 101, 1.0, 17)], t_end=3.0, storage=fleet)
    k = np.searchsorted(r.t, 1.5)
    rel = (r.speed[k] - r.coi_speed[k]) * 2 * np.pi * 60  # rad/s
    expected = np.clip(0.5 * rel, -0.45, 0.45)
    # the law is held over each step: compare with the speeds one step earlier as well
    rel_prev = (r.speed[k - 1] - r.coi_speed[k - 1]) * 2 * np.pi * 60
    assert np.all(
        np.minimum(abs(r.pesd[k] - expected), abs(r.pesd[k] - np.clip(0.5 * rel_prev, -0.45, 0.45)))
        < 0.02
    )


def test_cli_simulate_with_storage(tmp_path):
    import json

    from click.testing import CliRunner

    from stabctl.cli import main

    # ieee conventions: CCT 9.24 cycles without storage, 11.94 with 5 % (reports/paper.md)
    args = [
        "simulate",
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--clear-cycles",
        "11",
        "--tf",
        "5",
        "--json",
    ]
    plain = json.loads(CliRunner().invoke(main, args).stdout)
    res = CliRunner().invoke(main, args + ["--esd-pct", "5", "--out", str(tmp_path / "r.csv")])
    out = json.loads(res.stdout)
    assert not plain["stable"] and out["stable"]
    assert [d["bus"] for d in out["storage"]] == [10, 20, 110, 120]
    header = (tmp_path / "r.csv").read_text().splitlines()[0].split(",")
    assert header[-4:] == [f"pesd_pu.D{d}" for d in (1, 2, 3, 4)]
    # the storage settings and every switching as a record with named fields
    assert out["esd"]["pct_of_machine_mva"] == 5 and out["esd"]["devices"] == 4
    assert out["esd"]["deadband_hz"] == 0.1 and out["esd"]["v_gate_pu"] == 0.8
    sw = out["switchings"]
    assert len(sw) == sum(d["switchings"] for d in out["storage"]) > 0
    assert all(
        set(r) == {"t_s", "device", "bus", "machine", "mode", "mode_code", "rel_speed_hz"}
        for r in sw
    )
    by_dev = {d["device"]: d for d in out["storage"]}
    for r in sw:
        assert r["t_s"] >= 1.0 and r["t_s"] <= 5.0 and r["bus"] == by_dev[r["device"]]["bus"]
        assert (r["mode"], r["mode_code"]) in {("absorb", 1), ("idle", 0), ("inject", -1)}
        # Table 3: a device starts absorbing only when its machine runs > 100 mHz fast
        # (the crossing is located inside the step, to a fraction of a mHz)
        if r["mode"] == "absorb":
            assert r["rel_speed_hz"] > 0.1 - 1e-4
        if r["mode"] == "inject":
            assert r["rel_speed_hz"] < -0.1 + 1e-4
    assert "switchings" not in plain and plain["esd"] is None
    # the text output and the plot say that storage acted
    text = CliRunner().invoke(
        main, args[:-1] + ["--esd-pct", "5", "--plot", str(tmp_path / "r.png")]
    )
    assert text.exit_code == 0, text.output
    assert "storage: 4 ESDs of 5 % of machine MVA" in text.stdout
    assert f"{len(sw)} switchings, 4 of 4 devices acted" in text.stdout
    assert (tmp_path / "r.png").stat().st_size > 10000
    bad = CliRunner().invoke(main, args + ["--esd-pct", "-5"])
    assert bad.exit_code == 2


def test_commanded_devices_follow_the_schedule_at_exact_times(kundur):
    """Estimator-in-the-loop hook: modes decided at 60 frames/s from the (here ideal)
    speeds take effect exactly at frame time + latency, and reproduce the internal
    controller's verdict."""
    from stabctl.storage.control import ExternalCommands

    case, sim = kundur
    fleet = uniform_fleet(case, 5)
    mac = np.array([case.machine_index(d.machine) for d in fleet.devices])

    def decide(t, part):
        w = part.speed[-1]
        rel = (w - w @ part.inertia / part.inertia.sum())[mac] * 60
        return np.where(rel > 0.1, 1, np.where(rel < -0.1, -1, 0))

    frames = np.arange(0, 6, 1 / 60)
    ev = [fault_with_clearing(case, 3, 101, 1.0, 17)]
    res = sim.run_commanded(
        ev,
        6.0,
        StorageFleet(fleet.devices, ExternalCommands()),
        CommandFrames(frames, decide, latency=0.05),
    )
    assert res.stable and sim.run(ev, t_end=6.0).stable is False
    times = np.array([t for t, *_ in res.meta["switchings"]])
    assert times.size >= 8
    assert np.allclose(np.min(np.abs(times[:, None] - (frames + 0.05)[None, :]), axis=1), 0)
    with pytest.raises(InputError):
        sim.run_commanded(ev, 6.0, fleet, CommandFrames(frames, decide))  # not ExternalCommands


def test_boundary_chattering_is_bounded_measured_and_removed_by_hysteresis(kundur):
    """On the deadband boundary the ideal relay would switch infinitely often (a sliding
    mode); each device switches at most once per step, time keeps advancing, chattering is
    counted, and 20 mHz of hysteresis removes it."""
    case, sim = kundur
    fault = [fault_with_clearing(case, 3, 101, 1.0, 21)]
    plain = sim.run(fault, t_end=10.0, storage=uniform_fleet(case, 20))
    assert plain.stable and np.all(np.diff(plain.t) >= 0)
    assert np.ptp(plain.speed[-200:], axis=0).max() > 0  # dynamics not frozen
    chatter = [d["chattering"] for d in plain.meta["storage"]]
    assert sum(chatter) > 0 and max(d["switchings"] for d in plain.meta["storage"]) < 1000
    hyst = sim.run(
        fault, t_end=10.0, storage=uniform_fleet(case, 20, BangBangCOI(hysteresis_hz=0.02))
    )
    assert hyst.stable and all(d["chattering"] == 0 for d in hyst.meta["storage"])


def test_a_uniform_fleet_has_no_device_at_an_infinite_bus(tmp_path):
    """PSS/E's GENROU run (a GENROU against PSS/E's infinite bus, a GENCLS of H = 0 at bus
    101): `simulate --esd-pct 5` put a device at the infinite bus, which stands for the
    rest of the system (`place` takes it for no site).  The fleet has the GENROU's device
    only, and the storage line names the infinite bus left without one."""
    from pathlib import Path

    from click.testing import CliRunner

    from stabctl.cli import main
    from stabctl.io.psse import load_psse
    from stabctl.io.pst import write_case_json

    d = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU"
    case = load_psse(d / "ThreeBusMulti.raw", d / "ThreeBus_GENROU.dyr")
    assert sorted(zip(case.machines.bus, case.machines.H))[0] == (101, 0.0)
    fleet = uniform_fleet(case, 5)
    assert [(d.machine, d.bus) for d in fleet.devices] == [(2, 102)]
    path = write_case_json(case, tmp_path / "g.json")
    args = ["simulate", str(path), "--fault", "102", "--far-bus", "103", "--esd-pct", "5"]
    res = CliRunner().invoke(main, [*args, "--tf", "2"])
    assert res.exit_code == 0, res.output
    assert "storage: 1 ESDs of 5 % of machine MVA" in res.stdout
    assert "; none at the infinite bus(es) G1 (bus 101, id '1') (H = 0)" in res.stdout
