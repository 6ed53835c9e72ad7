"""The estimation report tells the paper's progress callback each stage and ambient run."""

from types import SimpleNamespace

from stabctl.studies import estimation_report as er


def test_case_figures_reports_every_stage_and_ambient_run(tmp_path, monkeypatch):
    fake_sim = SimpleNamespace(run=lambda *a, **k: None)
    monkeypatch.setattr(er, "Simulator", lambda case, **options: fake_sim)
    monkeypatch.setattr(er.study, "monte_carlo", lambda *a, **k: {})
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
