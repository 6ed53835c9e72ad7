"""The CLI: omib figures, bad arguments, and the paper report."""

import json

from click.testing import CliRunner

from stabctl.cli import main


def test_omib_json_reports_table1_and_eac():
    res = CliRunner().invoke(main, ["omib", "--fault-cycles", "6", "12", "15", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert [c["stable"] for c in out["cases"]] == [True, True, False]
    assert abs(out["eac"]["t_cr_s"] - out["eac"]["t_cr_bisection_s"]) < 1e-3


def test_bad_arguments_exit_nonzero_with_message():
    runner = CliRunner()
    for args in (
        ["omib", "--H", "-3"],
        ["omib", "--pm", "1.5", "--pmax", "1.0"],
        ["omib", "--delta0", "2.0"],
    ):
        res = runner.invoke(main, args)
        assert res.exit_code == 2
        assert "error:" in res.output


def test_paper_report_written(tmp_path):
    res = CliRunner().invoke(main, ["paper", "--out-dir", str(tmp_path), "--only", "analytic"])
    assert res.exit_code == 0, res.output
    text = (tmp_path / "paper.md").read_text()
    assert "Table 1" in text and "1.0734" in text
    assert (tmp_path / "fig07_feedback_phase_plane.png").stat().st_size > 10000
    assert not list(tmp_path.glob(".paper-*"))  # no temporary leftovers


def test_paper_rejects_unknown_part(tmp_path):
    res = CliRunner().invoke(main, ["paper", "--out", str(tmp_path), "--only", "nope"])
    assert res.exit_code != 0 and not (tmp_path / "paper.md").exists()
