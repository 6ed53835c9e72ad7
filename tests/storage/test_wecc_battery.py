"""Storage as a WECC battery (`StorageFleet(model="wecc")`, docs/storage.md): a REGCA1 with
a REECA1 in the storage current range and a REPCA1 plant taking the controller's power as
its reference.  Checked against closed forms: rest at the operating point, the step
response of the plant's chain of four first-order lags, the converter's current limit
P <= v Imax, and the REECA1 freeze below Vdip."""

import math
import platform

import numpy as np
import pytest

from stabctl.dynamics.driver import CommandFrames, Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import InputError
from stabctl.io import load_case
from stabctl.storage.control import ExternalCommands
from stabctl.storage.devices import WECC_BATTERY, StorageFleet, battery_case, uniform_fleet

#: the lags between the plant reference and the injected power: REPCA1's Pext lag Tg,
#: REECA1's reference filter Tpfilt and P order lag Tpord, REGCA1's converter lag Tg (s)
LAGS = 0.02


@pytest.fixture(scope="module")
def kundur():
    case = load_case("kundur")
    return case, Simulator(case)


def commanded(sim, fleet, modes_at, t_end=3.0, events=()):
    """A run whose devices take `modes_at(t)` (units of their rating) at every 1/60 s."""
    ext = StorageFleet(fleet.devices, ExternalCommands(), model="wecc", battery=fleet.battery)
    frames = CommandFrames(np.arange(0.0, t_end, 1 / 60), lambda t, part: modes_at(t))
    return sim.run_commanded(list(events), t_end, ext, frames)


def test_battery_rows_take_the_fields_and_refuse_unknown_ones(kundur):
    case, _sim = kundur
    fleet = uniform_fleet(case, 5, model="wecc")
    bcase, rows = battery_case(case, fleet)
    t = bcase.converters
    assert list(rows) == [0, 1, 2, 3] and list(t.bus) == [10, 20, 110, 120]
    assert np.all(t.mva == 45.0) and np.all(t.storage == 1) and np.all(t.Imax == 1.0)
    assert np.all(t.pfrac == 0) and np.all(t.repc == WECC_BATTERY["repc"])
    with pytest.raises(InputError, match="Imx not ibr_con fields"):
        StorageFleet(fleet.devices, model="wecc", battery={"Imx": 1.2})
    with pytest.raises(InputError, match="storage model must be one of"):
        uniform_fleet(case, 5, model="pv")


def test_idle_batteries_rest_at_the_operating_point(kundur):
    """Flat 10 s with the paper's controller: no device moves, no machine either."""
    case, sim = kundur
    res = sim.run([], t_end=10.0, storage=uniform_fleet(case, 5, model="wecc"))
    assert np.max(np.abs(res.pesd)) < 1e-12
    assert np.max(np.abs(res.speed - 1.0)) < 1e-10
    assert res.meta["switchings"] == []


def test_power_follows_the_reference_through_four_lags(kundur):
    """A step of the plant reference (+1 rating: absorb) at 1 s: the injected power is the
    step response of four first-order lags of 0.02 s, 1 - exp(-t/T) sum_{k<4} (t/T)^k/k!,
    times the rating; it settles at the reference where the bus voltage allows it, at the
    current limit v Imax (Imax 1 rating) where the absorption pulls v below 1 pu."""
    case, sim = kundur
    fleet = uniform_fleet(case, 5, model="wecc")
    res = commanded(sim, fleet, lambda t: np.where(t >= 1.0, 1.0, 0.0) * np.ones(4))
    rating = 45.0 / case.base_mva
    for tau in (0.02, 0.05, 0.1):
        i = int(np.argmin(np.abs(res.t - (1.0 + tau))))
        x = (res.t[i] - 1.0) / LAGS
        closed = 1.0 - math.exp(-x) * sum(x**k / math.factorial(k) for k in range(4))
        assert res.pesd[i] / rating == pytest.approx(closed * np.ones(4), abs=0.01)
    v = res.vmag[-1, case.bus_indices([10, 20, 110, 120])]
    assert np.all(v < 1.0)
    np.testing.assert_allclose(res.pesd[-1] / rating, np.minimum(1.0, v), rtol=1e-4)


def test_current_limit_caps_the_power_at_v_imax(kundur):
    """Imax 0.8 of the rating: a full-rating reference gives P = v Imax (active-current
    priority, no reactive current at rest), below the reference."""
    case, sim = kundur
    fleet = StorageFleet(
        uniform_fleet(case, 5).devices, model="wecc", battery={"Imax": 0.8, "PMAX": 1.0}
    )
    res = commanded(sim, fleet, lambda t: -np.ones(4))
    rating = 45.0 / case.base_mva
    v = res.vmag[-1, case.bus_indices([10, 20, 110, 120])]
    np.testing.assert_allclose(-res.pesd[-1] / rating, 0.8 * v, rtol=1e-4)
    assert np.all(-res.pesd / rating <= 0.8 * 1.2)


def test_case1_battery_and_ideal_device_switch_alike_and_the_battery_lags(kundur):
    """Kundur Case 1 (11 cycles, 5 %): the batteries keep the system stable as the ideal
    devices do, switch as often (the same law on nearly the same speeds), and their power
    never exceeds the rating by more than the voltage rise allows (P = v Ip, Ip <= 1/v at
    the order)."""
    case, sim = kundur
    ev = [fault_with_clearing(case, 3, 101, 1.0, 11)]
    ideal = sim.run(ev, t_end=6.0, storage=uniform_fleet(case, 5))
    wecc = sim.run(ev, t_end=6.0, storage=uniform_fleet(case, 5, model="wecc"))
    assert ideal.stable and wecc.stable
    rating = 45.0 / case.base_mva
    assert np.max(np.abs(wecc.pesd)) / rating < 1.02  # measured 1.005
    assert [d["switchings"] for d in wecc.meta["storage"]] == [4, 4, 4, 4]
    # the power lags its command: differences as large as the command at switchings
    assert np.max(np.abs(wecc.pesd - wecc.meta["pesd_command"])) / rating > 1.0


def test_cct_cli_and_sweep_jobs_take_the_wecc_model(kundur):
    """`stabctl cct --esd-model wecc` gives the library's CCT with WECC batteries; sweep
    jobs of that model are keyed apart from the ideal devices' (records never mix)."""
    import json

    from click.testing import CliRunner

    from stabctl.cli import main
    from stabctl.stability.cct import LineFault, critical_clearing_time
    from stabctl.storage.control import BangBangCOI
    from stabctl.studies.sweeps import controlled_cct_jobs

    case, sim = kundur
    args = ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5", "--json"]
    res = CliRunner().invoke(main, [*args, "--esd-model", "wecc"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    lib = critical_clearing_time(
        sim, LineFault(3, 101, 1.0), storage=uniform_fleet(case, 5, model="wecc")
    )
    assert out["esd_model"] == "wecc" and out["cct_s"] == pytest.approx(lib.cct_s)
    jobs = controlled_cct_jobs("kundur", [LineFault(3, 101, 1.0)], [None, 5], BangBangCOI())
    wecc = controlled_cct_jobs(
        "kundur", [LineFault(3, 101, 1.0)], [None, 5], BangBangCOI(), esd_model="wecc"
    )
    assert wecc[0].key == jobs[0].key and wecc[1].key == jobs[1].key + "/wecc"
    assert wecc[1].inputs["esd_model"] == "wecc"


def test_estimators_in_the_loop_command_wecc_batteries(kundur):
    """The closed loop (PMU frames, estimator, Table 3) commands the batteries' plant
    reference: with exact measurements (estimator "ideal") Case 1 at 11 cycles stays
    stable, the power drawn is the converters' and the law's is kept; an ambient load
    fluctuation, whose loads are not batteries, is refused."""
    from stabctl.estimation import closed_loop as cl
    from stabctl.estimation.ambient import AmbientLoad

    case, sim = kundur
    ev = [fault_with_clearing(case, 3, 101, 1.0, 11)]
    loop = cl.LoopOptions(5.0, "ideal", esd_model="wecc")
    run = cl.run_closed_loop(sim, ev, 6.0, loop)
    assert run.result.stable and len(run.result.meta["switchings"]) > 0
    cmd = run.result.meta["pesd_command"]
    assert np.max(np.abs(cmd)) == pytest.approx(0.45)
    assert np.max(np.abs(run.result.pesd - cmd)) > 0.1  # the converters lag the law
    with pytest.raises(InputError, match="ambient load fluctuation runs with ideal ESDs"):
        cl.run_closed_loop(sim, ev, 6.0, loop, ambient=AmbientLoad())


@pytest.mark.parametrize("command", [-1.0, 1.0])
def test_state_of_charge_stops_a_battery_empty_or_full(kundur, command):
    """WECC REEC_C's state of charge (the device's energy as the battery's En, SOCinit):
    90 MJ batteries at half charge, commanded their full rating out (-1) or in (+1) from
    1 s, deliver or take 45 MJ (half their energy, within the 20 ms lags' tail, 3 %) and
    then nothing: the current command's range closes at SOCmin or SOCmax."""
    from dataclasses import replace

    case, sim = kundur
    fleet = uniform_fleet(case, 5, model="wecc")
    fleet = replace(fleet, devices=tuple(replace(d, energy_mj=90.0) for d in fleet.devices))
    res = commanded(sim, fleet, lambda t: np.where(t >= 1.0, command, 0.0) * np.ones(4), 4.0)
    rating = 45.0 / case.base_mva
    energy = np.trapezoid(res.pesd, res.t, axis=0) * case.base_mva  # MJ absorbed (+)
    np.testing.assert_allclose(energy * command, 45.0, rtol=0.03)  # measured 45.8-46.0
    assert np.max(np.abs(res.pesd[res.t > 3.5])) < 1e-3 * rating
    step = lambda t: np.where(t >= 1.0, command, 0.0) * np.ones(4)  # noqa: E731
    unlimited = commanded(sim, uniform_fleet(case, 5, model="wecc"), step, 4.0)
    assert np.all(np.abs(unlimited.pesd[-1]) > 0.9 * rating)  # without En: at its rating


#: a commanded run whose commands fall between grid points (5 ms step, frames every 1/60 s,
#: 12.3 ms latency: every command splits a step), its results saved to the file argv[1]
_SPLIT_RUN = """
import sys
import numpy as np
from stabctl.dynamics.driver import CommandFrames, Simulator
from stabctl.io import load_case
from stabctl.storage.control import ExternalCommands
from stabctl.storage.devices import StorageFleet, uniform_fleet

case = load_case("kundur")
ext = StorageFleet(uniform_fleet(case, 5, model="wecc").devices, ExternalCommands(), model="wecc")
modes = lambda t, part: np.where(t >= 0.3, 1.0, -0.5) * np.ones(4)
frames = CommandFrames(np.arange(0.0, 1.0, 1 / 60), modes, latency=0.0123)
res = Simulator(case).run_commanded([], 1.0, ext, frames)
np.savez(sys.argv[1], speed=res.speed, angle=res.angle, pesd=res.pesd, vmag=res.vmag)
"""


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="MALLOC_PERTURB_ is glibc's")
def test_commanded_batteries_read_no_uninitialised_memory(tmp_path):
    """A command between grid points splits the step, and the model is evaluated again
    there: the derivatives of the slots no model writes (the converters' memory such as
    REECA1's held PI states, REECD1's slots of a REECA1) must be 0, not whatever the
    memory held.  glibc's MALLOC_PERTURB_ fills each allocation with a byte of its
    choosing (0x7f, 0xfe): the runs are bit for bit those of an ordinary process, and
    finite (with the derivatives left unwritten, 0x7f7f... = 1.4e306 per slot changed
    them)."""
    import os
    import subprocess
    import sys

    runs = []
    for perturb in (None, "128", "1"):
        env = {k: v for k, v in os.environ.items() if k != "MALLOC_PERTURB_"}
        if perturb is not None:
            env["MALLOC_PERTURB_"] = perturb
        out = tmp_path / f"run{perturb}.npz"
        done = subprocess.run(
            [sys.executable, "-c", _SPLIT_RUN, str(out)],
            env=env,
            capture_output=True,
            text=True,
            timeout=900,
        )
        assert done.returncode == 0, done.stderr
        runs.append(dict(np.load(out)))
    for name, ref in runs[0].items():
        assert np.all(np.isfinite(ref)), name
        for other in runs[1:]:
            np.testing.assert_array_equal(other[name], ref, err_msg=name)


def test_simulate_names_the_wecc_batteries_converter_columns(tmp_path):
    """Round 35: with --esd-model wecc the CSV held pibr_pu.C1..C4 (the batteries as
    converters) that --json's converter_names did not name (null on a case without
    converters of its own); each is named with its bus."""
    import csv
    import json

    from click.testing import CliRunner

    from stabctl.cli import main

    out = tmp_path / "w.csv"
    args = ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"]
    args += ["--esd-model", "wecc", "--tf", "1.2", "--json", "--out", str(out)]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    names = json.loads(res.stdout)["converter_names"]
    with out.open() as f:
        columns = next(csv.reader(f))
    numbers = [c.split(".C")[1] for c in columns if c.startswith("pibr_pu.C")]
    assert numbers == sorted(names, key=int) == ["1", "2", "3", "4"]
    assert names["1"] == "C1 (bus 10, WECC battery)"
