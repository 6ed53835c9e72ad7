"""ACTIVSg2000, the synthetic 2000-bus Texas grid (PSS/E RAW v33 + DYR, tests/data/activsg,
see its NOTICE), through `import-psse` as a planning engineer meets it: 98 wind and solar
plants without dynamic data (netted), no model stabctl lacks, 34 exciters and governors
whose power-flow point lies outside their own limits (left out, each named; PSS/E's
"initial conditions suspect").  Its 367 GGOV1 (stabctl.models.governors.ggov1) and 61
EXPIC1, 38 EXAC2 and 7 ESAC6A records (stabctl.models.exciters expic1, exac2, esac6a) are
read; two GGOV1 and two ESAC6A start outside their limits.  The references: the RAW
file's own solved power flow, and the flat run (every state still at rest after 10 s)."""

import gzip
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from runs import flat_run

from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.dynamics.infeasible import leave_out_infeasible
from stabctl.errors import InitialLimitError, InputError
from stabctl.io import load_case
from stabctl.io.psse import import_psse
from stabctl.io.psse_raw import split_fields
from stabctl.network.powerflow import solve_powerflow

DATA = Path(__file__).parents[1] / "data" / "activsg"
CYCLE = 1 / 60


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The RAW and DYR files, uncompressed."""
    out = tmp_path_factory.mktemp("activsg")
    paths = []
    for name in ("ACTIVSg2000.RAW", "ACTIVSg2000.dyr"):
        with gzip.open(DATA / f"{name}.gz", "rb") as src, open(out / name, "wb") as dst:
            shutil.copyfileobj(src, dst)
        paths.append(out / name)
    return paths


@pytest.fixture(scope="module")
def imported(files, tmp_path_factory):
    """(summary, case) of the command a user runs."""
    out = tmp_path_factory.mktemp("case") / "activsg2000.json"
    res = CliRunner().invoke(
        main,
        [
            "import-psse",
            *map(str, files),
            "-o",
            str(out),
            "--net-unmodelled",
            "--skip-unsupported",
            "--leave-out-infeasible",
            "--json",
        ],
    )
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout[res.stdout.index("{") :])
    return summary, load_case(str(out))


def raw_solution(raw: Path) -> dict[int, complex]:
    """Bus number -> the RAW file's solved voltage VM, VA (pu, rad), from its bus data."""
    lines = raw.read_text().splitlines()
    end = next(k for k, line in enumerate(lines) if "END OF BUS DATA" in line)
    fields = (split_fields(line) for line in lines[3:end])
    return {int(f[0]): float(f[7]) * np.exp(1j * np.deg2rad(float(f[8]))) for f in fields}


def test_the_import_says_what_it_left_out_and_netted(imported):
    summary, case = imported
    assert (summary["buses"], summary["machines"]) == (2000, 334)
    assert len(summary["netted"]) == 98  # 432 generators in service, 334 with a machine
    # every record left out is a model stabctl lacks, a stabiliser of an exciter left
    # out, or none; the out-of-service generators' records are not among them
    reasons = {r.split(": ", 1)[1] for r in summary["left_out"]}
    assert "no such generator in the RAW data (or out of service)" not in reasons
    assert not any(r.startswith("model ") and r.endswith("is not mapped") for r in reasons)
    assert len(summary["infeasible"]) == 36
    assert all(
        re.match(r"(exciter|governor) of G\d+ \(bus \d+, id '\w+'\): ", line)
        for line in summary["infeasible"]
    )
    assert len(case.exciters) == 328 and len(case.governors) == 304


def test_power_flow_reproduces_the_raw_solution(files, imported):
    """The RAW file is a solved case: stabctl's power flow (Q limits on, the wrong-side
    back-off, magnetizing admittance, PSS/E's Q limits of 0) lands on it within 5e-5 pu
    (measured 3.5e-5 pu and 2.8e-5 rad; 0.017 pu without the back-off)."""
    _, case = imported
    ref = raw_solution(files[0])
    pf = solve_powerflow(case, q_limits=True)
    v_ref = np.array([ref[int(b)] for b in case.buses.number])
    gap_v = np.max(np.abs(pf.vmag - np.abs(v_ref)))
    gap_a = np.max(np.abs(pf.vang - np.angle(v_ref)))
    print(f"\nACTIVSg2000 power flow vs RAW: {gap_v:.2e} pu, {gap_a:.2e} rad")
    assert gap_v < 5e-5 and gap_a < 5e-5


@pytest.mark.filterwarnings("ignore:.*(left out|netted).*:UserWarning")
def test_without_the_leave_out_the_case_is_refused_by_name(files):
    """stabctl refuses to start a control outside its limits (the ESDC2A at bus 6216,
    whose saturation data give V_R = 11.4 pu against VRMAX = 1.17); the leave-out names
    all 36 (6 exciters, each with its stabiliser -- the ESDC2A, an ESST4B, two ESAC6A
    whose K_D = 22.5 gives V_A0 = 36.9 pu against VAMAX = 9.08, and two SCRX without TE
    whose EMAX 5 lies below their E_fd0/V_t, 6.42 and 5.11 pu, since round 53 clipped as
    PSS/E does -- 28 governors dispatched above Tmax and 2 GGOV1 whose fuel order starts
    above Vmax)."""
    case = import_psse(*files, on_unsupported="skip", unmodelled="net").case
    # the first exciter type checked refuses first (the registry's order: the DC
    # exciters' module is checked last since 2026-12-02)
    with pytest.raises(InitialLimitError, match="ESST4B at rest") as err:
        Simulator(case, background_compile=False)
    assert err.value.table == "exc_con"
    left, names = leave_out_infeasible(case)
    dc = "exciter of G157 (bus 6216, id '1'): initial DC regulator output V_R = "
    assert sum(n.startswith(dc) for n in names) == 1
    assert sum(n.startswith("exciter") for n in names) == 6 and len(names) == 36
    scrx = [n for n in names if "bus fed" in n]
    assert [n.split(" (bus ")[1][:4] for n in scrx] == ["3105", "6266"]
    esac6a = [n for n in names if "ESAC6A" in n]
    assert [n.split(" (bus ")[1][:4] for n in esac6a] == ["4030", "6110"]
    assert all("V_A = 36." in n and "[VAmin, VAmax] = [-9.0800, 9.0800]" in n for n in esac6a)
    assert len(left.pss) == len(case.pss) - 6 and len(left.governors) == len(case.governors) - 30


def test_flat_run_stays_at_rest(imported):
    """10 s without disturbance at a quarter cycle and at the default half cycle (18
    EXAC2 in sub-intervals): every state within 1e-8 of its initial value (the
    flat-run target; measured 1.8e-13 at both)."""
    _, case = imported
    for step in (CYCLE / 4, CYCLE / 2):
        drift, _ = flat_run(case, step=step, q_limits=True)
        print(f"\nACTIVSg2000 flat 10 s at {step * 1e3:.3f} ms: largest drift {drift:.2e}")
        assert drift < 1e-8


def test_six_cycle_fault_is_stable_and_converged_in_the_step(imported):
    """A 6-cycle fault at 345 kV bus 2021 cleared by tripping line 2021-2002, the case read as
    PSS/E (the default): stable, its largest angle from the COI the same at half the step
    (measured 1.17712, 1.17707 and 1.17699 rad at a half, a quarter and an eighth of a
    cycle on 2026-12-03, 1.13828, 1.13831 and 1.13829 before the readings of 2026-12-02;
    half a cycle, the default step, with 18 EXAC2 in sub-intervals). Without sub-intervals
    half a cycle is refused by name: the EXAC2 at bus 1079 (K_A = 1000, T_A = 0.05
    s, K_F = 0.49, T_E = 0.55 s, a saturated exciter) has a regulator and exciter mode at
    -12 +- 184j 1/s, which Heun's method keeps only below h = 4.85 ms
    (`exac2.heun_step_limit`); with them (the default, `stabctl.dynamics.subinterval`) the
    EXAC2s whose loops are faster than the step take sub-steps of their own and the data's
    time constants set the step, half a cycle. The GENSAL at bus 6268 starts at E_fd0 = 10.2
    pu; with PSS/E's quadratic exciter saturation its ESDC1A's computed K_E is -3.66 (PST's
    exponential made it -3573 and the field voltage ran away at the fault,
    docs/pst_models.md 12.6)."""
    _, case = imported
    sim = Simulator(case)
    fault = Fault(bus=2021, t=1.0, clear_near=1.0 + 6 * CYCLE, far_bus=2002)
    with pytest.raises(InputError, match=r"exc_con row 9: EXAC2 regulator.*h < 0.0048538"):
        Simulator(case, subintervals=False).run([fault], t_end=5.0, h=CYCLE / 2)
    assert sim.default_h == pytest.approx(CYCLE / 2)
    assert np.isfinite(sim.exciter_hmax(sim.model, CYCLE / 2)).sum() == 18
    spread = []
    for h in (CYCLE / 2, CYCLE / 4, CYCLE / 8):
        res = sim.run([fault], t_end=5.0, h=h)
        assert res.stable
        spread.append(res.max_angle_from_coi)
    print("\nACTIVSg2000 fault 2021: spread " + " / ".join(f"{s:.5f}" for s in spread) + " rad")
    assert abs(spread[0] - spread[1]) < 1e-3 * spread[1]
    assert abs(spread[1] - spread[2]) < 1e-3 * spread[2]


def test_terminal_voltages_behind_the_machine_impedance_equal_the_bus_voltages(imported):
    """A run that records no bus voltage takes each machine's terminal voltage as psi -
    Z_mac I_mac (its internal node behind its impedance, O(n_mac)); one recording every bus
    reads the machines' buses from the network's full solution.  The two are the same
    voltages in exact arithmetic, so the trajectories agree to round-off (a 6-cycle fault
    at bus 2021, line 2021-2002 tripped, 3 s: measured 1.8e-13 rad, 1e-10 pu field voltage)."""
    _, case = imported
    sim = Simulator(case)
    fault = Fault(bus=2021, t=1.0, clear_near=1.0 + 6 * CYCLE, far_bus=2002)
    every_bus = sim.run([fault], t_end=3.0)
    machines_only = sim.run([fault], t_end=3.0, voltages=False)
    assert every_bus.vmag.shape[1] == case.n_bus and machines_only.vmag.size == 0
    assert np.abs(every_bus.angle - machines_only.angle).max() < 1e-9
    assert np.abs(every_bus.efd - machines_only.efd).max() < 1e-6


def _esst4b_as_andes_reads_it(case):
    """The case with its ESST4B exciters' PIs read as ANDES 2.0 reads them (exc_con
    psse_st1 0: tracking anti-windup) instead of PSS/E's non-windup limits."""
    from stabctl.case import ExciterTable
    from stabctl.models.exciters import EXCITER

    m = case.exciters.matrix().copy()
    m[m[:, 0] == 12, EXCITER.col("psse_st1") - 1] = 0.0
    return case.replace(exciters=ExciterTable.from_matrix(m))


def test_sime_keeps_the_lowest_end_of_a_verdict_that_is_not_monotone(imported):
    """With its ESST4B read as ANDES reads them (tracking anti-windup, whose integrals wind
    back while a regulator rides its limit), bus 4162 is unstable cleared at 0.224-0.3 s
    but stable again at 0.392 s (unstable at 0.393, 0.4 and 0.5 s).  The sime search runs
    t_max (0.5 s) first; were that run's margin used at once, with 0.4 s's, it
    extrapolated to 0.393 s and called the CCT 0.392 s.  It waits for the doubling, whose
    0.3 s probe finds the bisection's CCT, 0.223 s (the earlier screening's record of this
    fault).  Read as PSS/E reads them (non-windup limits, round 53) the verdict is
    monotone, the CCT 0.394 s by both searches."""
    from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time

    fault = LineFault(4162, None, 1.0)
    sim = Simulator(_esst4b_as_andes_reads_it(imported[1]))
    res = critical_clearing_time(sim, fault, SearchOptions(method="sime", t_max=0.5))
    assert res.bracket == (0.223, 0.224)
    assert res.probes[0] == (0.5, False) and (0.3, False) in res.probes
    psse = Simulator(imported[1])
    for method in ("sime", "bisection"):
        res = critical_clearing_time(psse, fault, SearchOptions(method=method, t_max=0.5))
        assert res.bracket == (0.394, 0.395) and (0.3, True) in res.probes
