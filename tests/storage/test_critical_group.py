"""The bang-bang law on the critical group's reference (``BangBangCOI(coi="critical")``,
not the paper's): each device watches its machine against the COI of the other group,
SIME's critical machines of the fault or the rest (docs/placement.md section 8)."""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import CaseError, InputError
from stabctl.io import load_case
from stabctl.stability.sime import device_modes
from stabctl.storage.control import BangBangCOI, group_reference
from stabctl.storage.devices import pack, uniform_fleet


@pytest.fixture(scope="module")
def kundur():
    case = load_case("kundur")
    return case, Simulator(case)


def test_the_reference_is_the_other_groups_coi_per_island():
    """Closed forms (eq. 40 over each group): machines 0, 1 critical, 2, 3 the rest; in a
    second island holding only machine 4 (one group), the island's COI, its own speed."""
    speed = np.array([1.02, 1.01, 0.99, 0.995, 1.03])
    M = np.array([2.0, 1.0, 3.0, 1.0, 4.0])
    island = np.array([0, 0, 0, 0, 1])
    group = np.array([1, 1, 0, 0, 0])
    rest = (3.0 * 0.99 + 1.0 * 0.995) / 4.0
    crit = (2.0 * 1.02 + 1.0 * 1.01) / 3.0
    ref = group_reference(speed, M, island, group)
    np.testing.assert_allclose(ref, [rest, rest, crit, crit, 1.03], rtol=0, atol=1e-15)


def test_the_law_needs_its_group_and_packs_it(kundur):
    case, _ = kundur
    with pytest.raises(InputError, match="critical machines"):
        BangBangCOI(coi="critical")
    with pytest.raises(InputError, match="critical machines"):
        BangBangCOI(critical=(1,))
    fleet = uniform_fleet(case, 5, BangBangCOI(coi="critical", critical=(2, 1)))
    kept = np.array(sorted(case.bus_indices(fleet.buses)))
    assert list(pack(fleet, case, kept).group) == [1, 1, 0, 0]
    assert pack(uniform_fleet(case, 5), case, kept).group.size == 0
    with pytest.raises(CaseError, match="99"):
        pack(uniform_fleet(case, 5, BangBangCOI(coi="critical", critical=(99,))), case, kept)


def test_compiled_law_and_sime_modes_agree_on_case1(kundur):
    """The paper's Case 1 (bus 3, line 3-101, area 1's machines 1 and 2 separate): the
    devices' signs in the run equal the Table 3 modes `device_modes` derives from its
    speeds and voltages (placement's view of the law), except within a step of a
    switching; area 1 absorbs and area 2 injects after the clearing, as under the paper's
    law (paper Figs. 14-15)."""
    case, sim = kundur
    law = BangBangCOI(coi="critical", critical=(1, 2))
    fleet = uniform_fleet(case, 5, law)
    r = sim.run([fault_with_clearing(case, 3, 101, 1.0, 12)], t_end=4.0, storage=fleet)
    modes = device_modes(r, fleet.buses, [d.machine for d in fleet.devices], law, case.freq_hz)
    ran = np.sign(np.round(r.pesd, 12)).astype(int)
    differ = np.flatnonzero(np.any(modes != ran, axis=1))
    switch_t = np.array([t for t, *_ in r.meta["switchings"]])
    assert switch_t.size >= 4
    near = [np.min(np.abs(switch_t - r.t[k])) <= 2 * sim.default_h for k in differ]
    assert all(near), r.t[differ[~np.array(near, bool)]]
    k = np.searchsorted(r.t, 1.35)
    assert list(np.sign(r.pesd[k])) == [1, 1, -1, -1]


def test_cct_cli_finds_the_group_and_other_commands_refuse_it(kundur):
    """`stabctl cct --coi critical` names the machines that separate without storage
    (Case 1: 1 and 2) and the CCT without storage (the paper's Case 1, 0.154 s under the
    ieee conventions, docs/cli.md) beside the CCT with the law; a command that cannot
    find the group does not offer it (click's invalid choice)."""
    args = ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"]
    res = CliRunner().invoke(main, [*args, "--coi", "critical", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout)
    assert out["critical_group"] == {
        "machines": [1, 2],
        "buses": [1, 2],
        "cct_without_storage_s": 0.154,
        "separated": True,  # (False: the run failed before any machine separated)
    }
    assert out["cct_s"] > 0.154
    text = CliRunner().invoke(main, [*args, "--coi", "critical"])
    assert "machines G1 (bus 1), G2 (bus 2) separate without storage (CCT 0.154 s)" in text.stdout
    # a verdict with the law (still stable at a --t-max below its CCT) names the group too
    robust = [*args, "--coi", "critical", "--t-max", "0.16"]
    verdict = json.loads(CliRunner().invoke(main, [*robust, "--json"]).stdout)
    assert verdict["verdict"] == "above t_max"
    assert verdict["critical_group"] == out["critical_group"]
    text = CliRunner().invoke(main, robust).stdout
    assert text.startswith("CCT above the search limit")
    assert "machines G1 (bus 1), G2 (bus 2) separate without storage (CCT 0.154 s)" in text
    res = CliRunner().invoke(
        main, ["simulate", "kundur", "--fault", "3", "--esd-pct", "5", "--coi", "critical"]
    )
    assert res.exit_code == 2 and "Invalid value for '--coi': 'critical'" in res.output
