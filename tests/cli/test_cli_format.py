"""Text output of the CCT reports: times with the decimals their tolerance needs."""

import pytest

from stabctl.cli.format import cycle_decimals, print_cct, print_screening, sweep_line, time_decimals
from stabctl.io import load_case


@pytest.mark.parametrize(
    "tol_s,decimals",
    [(None, 3), (0.05, 3), (1e-3, 3), (2e-3, 3), (1e-4, 4), (5e-4, 4), (2.5e-4, 5), (1e-6, 6)],
)
def test_time_decimals_show_every_multiple_of_the_tolerance(tol_s, decimals):
    assert time_decimals(tol_s) == decimals
    assert cycle_decimals(tol_s) == max(2, decimals - 1)


def _cct(tol_s):
    return {
        "fault": {"bus": 3, "far_bus": 101, "circuit": 1, "t_fault_s": 1.0, "trips": []},
        "cct_s": 0.1541,
        "cct_cycles": 0.1541 * 60,
        "numerical_error_s": 0.0002,
        "cct_half_step_s": 0.1539,
        "conventions": "ieee",
        "t_stable_s": 0.1541,
        "t_unstable_s": 0.1542,
        "t_unstable_cycles": 0.1542 * 60,
        "tol_s": tol_s,
        "step_s": 1 / 120,
        "n_simulations": 20,
        "n_simulations_half_step": 2,
        "early_stops": 3,
        "search": "bisection",
        "wall_time_s": 1.0,
        "separated_machines": [1, 2],
        "islanded": [],
    }


def test_a_cct_at_a_tolerance_below_1_ms_prints_its_bracket_apart(capsys):
    """At --tol-ms 0.1 the bracket printed 'stable at 0.154 s, unstable at 0.154 s' and
    'numerical error 0.2 ms (CCT at half the step 0.154 s)'."""
    print_cct(load_case("kundur"), None, _cct(1e-4))
    text = capsys.readouterr().out
    assert "CCT 0.1541 s = 9.246 cycles (stable at 0.1541 s, unstable at 0.1542 s" in text
    assert "numerical error 0.2 ms (CCT at half the step 0.1539 s)" in text
    assert "lose synchronism when cleared at 0.1542 s" in text


def test_a_cct_at_the_default_tolerance_prints_as_before(capsys):
    d = _cct(1e-3)
    d.update(cct_s=0.154, t_stable_s=0.154, t_unstable_s=0.155, cct_half_step_s=0.153)
    d.update(numerical_error_s=0.001, cct_cycles=9.24, t_unstable_cycles=9.3)
    print_cct(load_case("kundur"), None, d)
    text = capsys.readouterr().out
    assert "CCT 0.154 s = 9.24 cycles (stable at 0.154 s, unstable at 0.155 s = 9.30" in text
    assert "numerical error 1 ms (CCT at half the step 0.153 s)" in text


def test_the_sweep_and_screening_tables_print_cct_at_their_tolerance(capsys):
    d = _cct(1e-4)
    line = sweep_line("kundur/3-101/t1/esdnone", {"status": "ok", "result": d})
    assert " 0.1541    9.246    0.2    20       -" in line
    row = {
        "bus": 3,
        "far_bus": 101,
        "status": "ok",
        "verdict": "cct",
        "cct_s": 0.1541,
        "cct_cycles": 9.246,
        "numerical_error_s": 0.0002,
        "separated": [],
    }
    print_screening(load_case("kundur"), [row], 1e-4)
    assert "bus 3 line to 101       0.1541   9.246    0.2  -" in capsys.readouterr().out


def test_a_count_of_one_takes_the_singular():
    """Messages said "1 contingencies", "1 branches", "1 seeds": a count and its noun agree
    wherever a count is printed (`stabctl.errors.counted`)."""
    from pathlib import Path

    from click.testing import CliRunner

    from stabctl.cli import main
    from stabctl.cli.format import estimator_cct_lines
    from stabctl.errors import counted
    from stabctl.estimation.settings import PMUSettings

    assert [counted(n, "contingency", "contingencies") for n in (0, 1, 2)] == [
        "0 contingencies",
        "1 contingency",
        "2 contingencies",
    ]
    stats = {"mean": 9.0, "std": 0.0, "min": 9.0, "max": 9.0, "runs": 1, "failed": 0}
    first = estimator_cct_lines({"kf": stats}, 3, 101, 5, PMUSettings(), 1, 0)[0]
    assert ", 1 seed from 0 (cycles" in first, first
    psse = Path(__file__).parents[1] / "data" / "psse"
    with CliRunner().isolated_filesystem():
        res = CliRunner().invoke(
            main,
            ["import-psse", str(psse / "smib_v33.raw"), str(psse / "smib.dyr"), "-o", "c.json"],
        )
    assert res.exit_code == 0, res.output
    assert "wrote c.json: 2 buses, 1 branch, 2 machines, 0 exciters," in res.stdout


def test_a_relative_speed_rmse_never_formed_prints_as_a_dash(capsys):
    """Round 39: a PMU implausible in every frame leaves the raw estimator no relative
    speed; `estimate rmse --source` printed "raw None / 19.8852 / 19.8831"."""
    from stabctl.cli.format import _source_compare

    src = {
        "on_wire": {"raw": {"rel_rmse_mhz": 19.88521}},
        "in_process": {"raw": {"rel_rmse_mhz": 19.88312}},
    }
    _source_compare(src, {"raw": {"rel_rmse_mhz": {"mean": None}}})
    assert capsys.readouterr().out.splitlines()[-1] == "  raw      - / 19.8852 / 19.8831"


def test_an_island_of_negative_load_says_its_infeed_lost_not_a_negative_load_shed():
    """Round 42: WECC-179's bus 72 (load -1525 MW, generation written as load) islanded by
    its line 72-74's trip was said "load shed -1525.0 MW, -50.0 Mvar"; the island's power
    is its load in pu on the case's base (Kundur: 100 MVA)."""
    from stabctl.cli.format import islanding_lines

    case = load_case("kundur")
    lost = {"t_s": 1.0, "buses": [72], "load_shed_pu": [-15.25, -0.5]}
    shed = {"t_s": 1.0, "buses": [4], "load_shed_pu": [9.76, 1.0]}
    assert islanding_lines(case, [lost, shed], timed=False) == [
        "bus(es) [72] islanded from every generator: de-energised, infeed lost 1525.0 MW, "
        "50.0 Mvar (negative load)",
        "bus(es) [4] islanded from every generator: de-energised, load shed 976.0 MW, 100.0 Mvar",
    ]
