"""The estimation report tells the paper's progress callback each stage and ambient run,
and its RMSE table is what the command it names prints."""

import json
import shlex
from types import SimpleNamespace

from click.testing import CliRunner

from stabctl.cli import main
from stabctl.dynamics.events import fault_with_clearing
from stabctl.io import load_case
from stabctl.studies import estimation_report as er


def test_case_figures_reports_every_stage_and_ambient_run(tmp_path, monkeypatch):
    fake_sim = SimpleNamespace(run=lambda *a, **k: None)
    monkeypatch.setattr(er, "Simulator", lambda case, **options: fake_sim)
    monkeypatch.setattr(er, "rmse_figures", lambda *a, **k: {})
    monkeypatch.setattr(er.study, "false_actions", lambda *a, **k: {})
    monkeypatch.setattr(er.am, "simulate", lambda *a, **k: None)
    monkeypatch.setattr(er.cl, "cct_study", lambda *a, **k: {})
    said = []
    er.case_figures("kundur", 3, 2, tmp_path, progress=said.append)
    assert said[0] == "estimation kundur: RMSE, 3 PMU noise runs"
    assert [m for m in said if "ambient" in m] == [
        f"estimation kundur: ambient load run {r}/{er.AMBIENT_RUNS} (60 s)"
        for r in range(1, er.AMBIENT_RUNS + 1)
    ]
    assert said[-1] == "estimation kundur: CCT with the estimators in the loop, 2 noise seeds"


def test_the_rmse_table_is_what_its_command_prints():
    """Same fault, window and seeds: the report's figures (`rmse_figures`) equal the JSON
    of the `stabctl estimate rmse` command line the report names, to the last digit."""
    pc = er.CASES["kundur"]
    fig = {"bus": pc.bus, "far": pc.far_bus, "cycles": pc.cycles["estimation"], "runs": 2}
    command = er.rmse_command("kundur", fig)
    assert command.startswith("stabctl estimate rmse kundur --fault 3 --far-bus 101")
    res = CliRunner().invoke(main, [*shlex.split(command)[1:], "--json"])
    assert res.exit_code == 0, res.output
    printed = json.loads(res.stdout)
    case = load_case("kundur")
    ev = fault_with_clearing(case, pc.bus, pc.far_bus, pc.fault.t_fault, fig["cycles"])
    assert printed["window_s"] == [max(ev.times()) + er.RMSE_SETTLE_S, er.RMSE_T_END_S]
    assert printed["estimators"] == er.rmse_figures(case, ev, 2)
