"""The 240-bus reduced WECC (PSS/E RAW v32 + DYR, tests/data/wecc240, see its NOTICE)
through `import-psse` as shipped, with no option: 103 machines (GENROU with SEXS, GAST,
TGOV1, HYGOV, IEEEST), 37 REGCA1 + REECB1 + REPCA1 plants and 52 plants regulating a
remote bus (RAW IREG).  The references: the RAW file's own solved power flow and the flat
run (every state at rest after 10 s)."""

import gzip
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from runs import flat_run

from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.io import load_case
from stabctl.network.powerflow import solve_powerflow

DATA = Path(__file__).parents[1] / "data" / "wecc240"
NAMES = ("240busWECC_2018_PSS32_fixed_shunts.raw", "240busWECC_2018_PSS.dyr")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The RAW and DYR files, uncompressed."""
    out = tmp_path_factory.mktemp("wecc240")
    for name in NAMES:
        with gzip.open(DATA / f"{name}.gz", "rb") as src, open(out / name, "wb") as dst:
            shutil.copyfileobj(src, dst)
    return [out / name for name in NAMES]


@pytest.fixture(scope="module")
def imported(files, tmp_path_factory):
    """(summary, case) of `stabctl import-psse RAW DYR` with no option."""
    out = tmp_path_factory.mktemp("case") / "wecc240.json"
    res = CliRunner().invoke(main, ["import-psse", *map(str, files), "-o", str(out), "--json"])
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout[res.stdout.index("{") :]), load_case(str(out))


def test_it_imports_whole(imported):
    summary, case = imported
    assert (summary["buses"], summary["machines"], summary["converters"]) == (243, 103, 37)
    assert summary["left_out"] == [] and summary["netted"] == [] and summary["changed"] == []
    assert summary["infeasible"] == []
    rr = case.remote_regulation
    assert len(rr) == 52 and np.all(rr.share == 1.0)  # one plant per regulated bus
    # machines named by bus and RAW ID, numbered past the converters' generators (the
    # RAW's 25th-27th generators, at bus 2233, are machines 20-22)
    at_2233 = [
        case.machine_name(k) for k, b in zip(case.machines.number, case.machines.bus) if b == 2233
    ]
    assert at_2233 == [
        "G20 (bus 2233, id 'DG')",
        "G21 (bus 2233, id 'EG')",
        "G22 (bus 2233, id 'TG')",
    ]


def test_power_flow_lands_on_the_raw_solution(imported):
    """Within 1e-4 pu of the RAW's solution (measured 5.2e-6 pu, 5.3e-6 rad) with the
    limits PSS/E solved it with: its bus 3731 generates -188.9 Mvar below its QB of -121,
    which the import names; with Q limits on, that bus is held at QB."""
    summary, case = imported
    gap = summary["powerflow_against_raw"]
    assert gap["raw_q_outside_limits"] == [
        {"bus": 3731, "qgen_mvar": -188.883, "qmin_mvar": -121.0, "qmax_mvar": 200.0}
    ]
    free = gap["without_q_limits"]
    assert free["vmag_diff_pu"] < 1e-4 and free["angle_diff_rad"] < 1e-4
    pf = solve_powerflow(case, q_limits=False)
    rr = case.remote_regulation
    assert np.abs(pf.vmag[case.bus_indices(rr.regulated)] - rr.vset).max() < 1e-9


def test_flat_run_stays_at_rest(imported):
    """Every state (machines, exciters, governors, stabilisers, converter plants) within
    1e-8 of its start after 10 s (measured 2.7e-13)."""
    _, case = imported
    drift, _ = flat_run(case, step=1 / 120, q_limits=False)
    assert drift < 1e-8


def test_a_bus_fault_converges_with_the_step(imported):
    """Five-cycle bolted fault at Four Corners 500 kV (bus 1001): stable, the largest angle
    spread within 5e-3 rad between 1/480 s and 1/960 s (measured 0.9610 and 0.9632 on
    2026-12-03; 0.9066 and 0.9064 before SEXS clipped Efd as PSS/E does)."""
    _, case = imported
    sim = Simulator(case, q_limits=False)
    fault = [Fault(bus=1001, t=1.0, clear_near=1.0 + 5 / 60)]
    spread = []
    for h in (1 / 480, 1 / 960):
        res = sim.run(fault, t_end=5.0, h=h)
        assert res.stable
        spread.append(res.max_angle_from_coi)
    assert abs(spread[0] - spread[1]) < 5e-3


def test_the_linear_model_with_its_stiff_stabilisers_is_the_runs(imported):
    """The case's IEEEST (3900 pu/pu from speed to an output limited to +-0.1) saturate
    a linearisation step of 1e-4 on both sides; taken at smaller steps, no mode is in the
    right half plane, as the nonlinear run says: a 1e-6 pu Vref step on machine 84 (the
    stabiliser that gave +5.85 1/s) does not grow."""
    from stabctl.dynamics.events import VrefStep
    from stabctl.smallsignal.linearise import linearise_model

    _, case = imported
    sim = Simulator(case, q_limits=False)
    lm = linearise_model(sim.model)
    assert np.linalg.eigvals(lm.A).real.max() < 1e-6
    run = sim.run([VrefStep(84, 1.0, 1e-6)], t_end=3.0, h=1 / 480)
    dev = np.abs(run.efd[:, 83] - run.efd[0, 83])
    assert dev.max() < 5e-5 and dev[-1] < 2 * dev[np.searchsorted(run.t, 1.5)]
