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


def test_omib_with_a_small_pm_gives_its_cct_beyond_a_second():
    """`omib --pm 0.01` (in range) was refused as "the CCT is not within [0, 1.0] s":
    its EAC CCT, 1.72 s, is checked by a bisection reaching past it; with a Pm so small
    that no bisection runs, the line says so."""
    res = CliRunner().invoke(main, ["omib", "-c", "6", "--pm", "0.01", "--json"])
    assert res.exit_code == 0, res.output
    eac = json.loads(res.output)["eac"]
    assert eac["t_cr_s"] > 1.0 and abs(eac["t_cr_s"] - eac["t_cr_bisection_s"]) < 1e-3
    res = CliRunner().invoke(main, ["omib", "-c", "6", "--pm", "1e-300"])
    assert res.exit_code == 0, res.output
    assert "bisection not run (it tries clearings up to 10 s)" in res.output


def test_omib_tables_the_durations_shortest_first():
    """Durations from -c and from the positional MORE_CYCLES, given in any order, are
    tabled shortest first, in the text and in the JSON."""
    args = ["omib", "-c", "6", "12", "-c", "15"]
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    assert [c["cycles"] for c in json.loads(res.output)["cases"]] == [6.0, 12.0, 15.0]
    res = CliRunner().invoke(main, ["omib", "-c", "15", "6", "-c", "12"])
    assert res.exit_code == 0, res.output
    rows = [line.split()[0] for line in res.output.splitlines()[1:4]]
    assert rows == ["6.00", "12.00", "15.00"]


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
