"""Placement on a system beyond the two home cases (docs/placement.md, "Plans on other
systems"): a complete plan on ANDES's IEEE 39 (imported with `stabctl import-andes`),
checked against the definition of a verified plan by independent simulation, and the
infeasibility verdict that keeps a device which lowers a CCT out of its proof (checked
against a closed-form CCT)."""

import json
import types

import numpy as np
import pytest
from click.testing import CliRunner
from plan_checks import stable_when_cleared

from stabctl.cli import main
from stabctl.io import load_case
from stabctl.placement.evaluation import Contingency
from stabctl.placement.loop import _raise_if_infeasible, bound_allocations
from stabctl.placement.plan import PlanOptions, plan
from stabctl.placement.program import CCTCut, InfeasibleError
from stabctl.placement.requirements import Requirement
from stabctl.stability.cct import LineFault


@pytest.fixture(scope="module")
def ieee39(tmp_path_factory):
    """ANDES's ieee39_full imported as `stabctl import-andes` does (docs/placement.md)."""
    andes = pytest.importorskip("andes")
    out = tmp_path_factory.mktemp("ieee39") / "ieee39_full.json"
    res = CliRunner().invoke(
        main, ["import-andes", andes.get_case("ieee39/ieee39_full.xlsx"), "-o", str(out)]
    )
    assert res.exit_code == 0, res.output
    return str(out)


def test_ieee39_plan_is_verified_by_its_definition(ieee39):
    """Fault 16-17 (line tripped), CCT +5 %: the plan ends verified, and independent runs
    cleared at its required time are stable with the plan's devices and unstable without
    storage (the definition of a contingency that needs storage and gets it); the total
    is the sum of the sites, and the CCT with storage reaches the requirement."""
    fault = LineFault(16, 17)
    res = plan(ieee39, [fault], Requirement(gain_pct=5), PlanOptions(max_rounds=3))
    assert res.verified and not res.set_aside
    (row,) = res.contingencies
    t = row["required_s"]
    # requirement: CCT without storage + 5 %, rounded up to the 1 ms tolerance
    assert t == pytest.approx(np.ceil(row["cct_no_storage_s"] * 1.05 / 1e-3 - 1e-9) * 1e-3)
    sites = res.allocation()
    assert sites and res.total_mw == pytest.approx(sum(r["mw"] for r in sites))
    assert all(r["mw"] >= 1.0 and r["mwh"] > 0 for r in sites)
    assert stable_when_cleared(load_case(ieee39), fault, t, sites)
    assert not stable_when_cleared(load_case(ieee39), fault, t, [])
    assert row["met"] and row["cct_s"] >= t


def closed_form_setup(target_s):
    """A contingency whose CCT is the linear function 0.2 s + 1e-4 s/MW P_1 - 2e-4 s/MW
    P_2 of two sites' ratings (100 MW bounds): the device at site 2 lowers it, as the
    paper's law can (docs/placement.md section 8).  verify evaluates it exactly and
    counts its calls; the CCT without storage is 0.2 s."""
    c = Contingency(LineFault(1, 2), target_s)
    calls = []

    def verify(mw, which):
        calls.append(np.array(mw))
        return {c.name: {"cct_s": 0.2 + 1e-4 * mw[0] - 2e-4 * mw[1]} for c in which}

    setup = types.SimpleNamespace(
        contingencies=(c,),
        upper=np.array([100.0, 100.0]),
        bound_ccts={},
        verify=verify,
        base={c.name: {"cct_s": 0.2}},
    )
    cut = CCTCut(c.name, target_s, 0.2, np.array([1e-4, -2e-4]), np.zeros(2))
    return setup, cut, calls


def test_a_device_that_lowers_the_cct_is_not_forced_into_the_infeasibility_proof():
    """Every site at its bound gives 0.19 s, site 1 alone 0.21 s: a target of 0.21 s is
    met, so no verdict (the proof used to simulate every site at its bound only and set
    such a contingency aside); 0.22 s is missed at both, and the verdict names both
    CCTs and the one without storage (which site 1 alone raises: no word of storage
    lowering it).  Each bound allocation is simulated once."""
    setup, cut, calls = closed_form_setup(0.21)
    ub, helpful = bound_allocations(cut, setup.upper)
    assert list(ub) == [100.0, 100.0] and list(helpful) == [100.0, 0.0]
    _raise_if_infeasible(setup, [cut])  # no error
    assert len(calls) == 2
    setup, cut, calls = closed_form_setup(0.22)
    with pytest.raises(InfeasibleError, match=r"0\.190 s with every.* and 0\.210 s with only"):
        _raise_if_infeasible(setup, [cut])
    with pytest.raises(InfeasibleError, match=r"simulated \(0\.200 s without storage\)$"):
        _raise_if_infeasible(setup, [cut])
    with pytest.raises(InfeasibleError) as exc:
        _raise_if_infeasible(setup, [cut])
    assert exc.value.contingencies == ("1-2",) and len(calls) == 2  # memoised
    # a cut whose every site helps: one allocation, every site at its bound
    every = CCTCut("1-2", 0.22, 0.2, np.array([1e-4, 2e-4]), np.zeros(2))
    assert len(bound_allocations(every, setup.upper)) == 1


def test_a_machine_against_an_infinite_bus_gets_a_site_the_infinite_bus_none(psse_omib, tmp_path):
    """PSS/E's OMIB: the infinite bus (machine 1, H = 0, its speed the reference) is no
    candidate site (named, it is refused) and takes no share of what a device draws
    (its distribution factor 0; the machine's between 0 and 1); `place` plans without a
    traceback, and a contingency set aside says its CCT without storage (the CCT search's)
    and that the device lowers it: at bus 102 the 0.8 pu voltage gate idles it while
    the machine still runs ahead (docs/placement.md section 8)."""
    from stabctl.dynamics.coi import machine_inertia
    from stabctl.dynamics.driver import Simulator
    from stabctl.errors import InputError
    from stabctl.placement.program import candidate_sites
    from stabctl.smallsignal.linearise import esd_columns
    from stabctl.stability.cct import critical_clearing_time
    from stabctl.stability.sime import distribution_factors

    case = load_case(psse_omib)
    assert [s.machine for s in candidate_sites(case)] == [2]
    with pytest.raises(InputError, match=r"G1 \(bus 101, id '1'\) is an infinite bus"):
        candidate_sites(case, machines=[1, 2])
    sim = Simulator(case)
    beta = distribution_factors(
        esd_columns(sim, [102]), [102], [1, 2], machine_inertia(case), case.base_mva
    )
    assert beta[0, 0] == 0 and 0 < beta[1, 0] < 1
    base = critical_clearing_time(sim, LineFault(102, None)).cct_s
    faults = tmp_path / "faults.csv"
    faults.write_text("bus,far_bus\n102,\n")
    res = CliRunner().invoke(
        main,
        ["place", psse_omib, "--faults", str(faults), "--target-cct-gain", "10",
         "--set-aside-infeasible", "--workers", "1"],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert f"({base:.3f} s without storage: the devices lower it" in res.output
    assert "0 of 0 contingencies stable at their required clearing time (1 more set aside" in (
        res.output
    )
    costs = tmp_path / "costs.csv"
    costs.write_text("machine,cost_mw\n2,1\n1,0.5\n")  # the infinite bus's row: no site
    res = CliRunner().invoke(
        main,
        ["place", psse_omib, "--faults", str(faults), "--target-cct-gain", "10",
         "--site-costs", str(costs)],
    )  # fmt: skip
    assert res.exit_code == 2
    assert "costs.csv:3: machine 1 is an infinite bus (H = 0), no ESD site" in res.output


def test_place_takes_the_power_flow_without_q_limits_a_case_needs(tmp_path):
    """ANDES's Kundur system with an induction motor converges only with the PV buses'
    Q limits off (ANDES's own power flow): `place` refuses it with Q limits on, naming
    the option, and with `--no-q-limits` (as `simulate`, `cct` and `screen` take it)
    plans and verifies it, its JSON recording the setting."""
    andes = pytest.importorskip("andes")
    case = str(tmp_path / "kundur_motor.json")
    src = andes.get_case("kundur/kundur_motor.xlsx")
    res = CliRunner().invoke(main, ["import-andes", src, "-o", case])
    assert res.exit_code == 0, res.output
    faults = tmp_path / "faults.csv"
    faults.write_text("bus,far_bus\n6,7\n")
    args = ["place", case, "--faults", str(faults), "--target-cct-gain", "10", "--workers", "1"]
    refused = CliRunner().invoke(main, args)
    assert refused.exit_code == 2 and "--no-q-limits" in refused.output
    res = CliRunner().invoke(main, [*args, "--no-q-limits", "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["verified"] and d["settings"]["q_limits"] is False


def test_a_contingency_that_cannot_be_simulated_is_set_aside_by_name(tmp_path):
    """ANDES's Kundur system with a wind turbine: a bolted fault at bus 9, beside the
    converter, leaves the network equations without a solution as soon as it is on (ANDES
    stops there too: tests/io/test_andes.py::test_converter_case_bus_faults_match_andes,
    whose stored ANDES run of bus 9 ends at the fault).  `place --set-aside-infeasible`
    sets that contingency aside as not simulable, with the failure's words, and plans
    for the other (verified); without the option the plan stops (exit 2) naming the
    fault and the option."""
    andes = pytest.importorskip("andes")
    case = str(tmp_path / "kundur_wtdta1.json")
    src = andes.get_case("kundur/kundur_wtdta1.xlsx")
    res = CliRunner().invoke(main, ["import-andes", src, "-o", case, "--skip-unsupported"])
    assert res.exit_code == 0, res.output
    faults = tmp_path / "faults.csv"
    faults.write_text("bus,far_bus\n8,\n9,10\n")
    args = ["place", case, "--faults", str(faults), "--target-cct-gain", "10"]
    args += ["--no-q-limits", "--workers", "1"]
    stopped = CliRunner().invoke(main, args)
    assert stopped.exit_code == 2
    assert "fault at bus 9 on line 9-10" in stopped.output
    assert "--set-aside-infeasible" in stopped.output
    res = CliRunner().invoke(main, [*args, "--set-aside-infeasible", "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert list(d["not_simulable"]) == ["9-10"]
    assert "did not converge" in d["not_simulable"]["9-10"]
    assert "current sources" in d["not_simulable"]["9-10"]
    assert d["verified"] and [r["name"] for r in d["contingencies"]] == ["8"]
    assert d["contingencies"][0]["met"] and not d["set_aside"]
    text = CliRunner().invoke(main, [*args, "--set-aside-infeasible"])
    assert text.exit_code == 0, text.output
    assert "1 more set aside as not simulable, below" in text.output
    assert "set aside as not simulable without storage: 9-10: fault at bus 9" in text.output
    faults.write_text("bus,far_bus\n9,10\n")
    none = CliRunner().invoke(main, [*args, "--set-aside-infeasible"])
    assert none.exit_code == 0, none.output
    assert "NOTHING TO PLACE (every contingency set aside as not simulable (9-10)" in none.output
