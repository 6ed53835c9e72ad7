"""`stabctl paper` reports and records are reproducible files: sweep records are made in a
work directory, the old records are replaced only when the whole run succeeded, and
timings go to a separate run log."""

import json
import os
from pathlib import Path

import pytest

from stabctl.errors import InputError
from stabctl.parallel import Job, natural_key, run_sweep, strip_run_dependent, write_reproducible
from stabctl.studies import paper


def square(inputs: dict) -> dict:
    x = inputs["x"]
    return {"y": x * x, "wall_time_s": 0.001 * x}  # a run-dependent field inside


class Boom(RuntimeError):
    pass


def _fake_section(fail_after_sweep: list):
    """A resumable section: a sweep of 12 jobs into records_dir, then its markdown."""

    def section_fake(fig_dir: Path, records_dir: Path, progress=None) -> str:
        """Fake part: squares."""
        rep = run_sweep(
            [Job(f"sq/seed{x}", square, {"x": x}) for x in (10, 2, 1, 11, 0, 3)],
            records_dir / "fake_squares.jsonl",
            workers=1,
            progress=False,
        )
        if fail_after_sweep:
            raise Boom("interrupted")
        return "## squares\n\n" + ", ".join(str(r["result"]["y"]) for r in rep.records.values())

    return section_fake


@pytest.fixture
def fake_parts(monkeypatch):
    fail = []
    monkeypatch.setattr(paper, "PARTS", {"fake": ()})
    monkeypatch.setattr(paper, "RESUMABLE", {"fake": (_fake_section(fail), "fake_*.jsonl")})
    return fail


def test_old_records_kept_until_the_run_completes(tmp_path, fake_parts):
    old = tmp_path / "fake_squares.jsonl"
    old.write_text('{"key": "old", "inputs": {}, "status": "ok", "result": {}}\n')
    (tmp_path / "paper.md").write_text("old report\n")
    fake_parts.append(True)  # the section fails
    with pytest.raises(Boom):
        paper.write_paper_report(tmp_path, progress=lambda m: None, only=["fake"])
    assert old.read_text().startswith('{"key": "old"')  # not deleted, not replaced
    assert (tmp_path / "paper.md").read_text() == "old report\n"
    work = tmp_path / paper.WORK_DIR / "fake_squares.jsonl"
    assert len(work.read_text().splitlines()) == 6  # finished jobs kept, timed
    assert all("wall_time_s" in json.loads(x) for x in work.read_text().splitlines())
    assert not list(tmp_path.glob(".paper-[!w]*"))  # no temporary report dirs

    fake_parts.clear()  # --resume: nothing rerun
    calls = []
    paper.write_paper_report(tmp_path, progress=calls.append, only=["fake"], resume=True)
    lines = [json.loads(x) for x in old.read_text().splitlines()]
    assert [r["key"] for r in lines] == [f"sq/seed{x}" for x in (0, 1, 2, 3, 10, 11)]
    assert all(set(r) == {"key", "inputs", "status", "result"} for r in lines)
    assert lines[4]["result"] == {"y": 100}  # nested timing left out
    assert "squares" in (tmp_path / "paper.md").read_text()
    assert not (tmp_path / paper.WORK_DIR).exists()
    log = json.loads((tmp_path / paper.RUN_LOG).read_text())
    assert log["resume"] is True and log["records"]["fake_squares.jsonl"]["jobs"] == 6
    assert log["sections"][0]["section"] == "Fake part: squares."
    assert [m for _, m in log["progress"]] == calls


def test_a_second_paper_run_on_one_directory_is_refused(tmp_path, fake_parts):
    """One run per output directory: while a run holds out/.paper-work's lock another is
    refused with its pid, before it touches the work directory."""
    from stabctl.errors import InputError
    from stabctl.locking import exclusive

    with exclusive(tmp_path / paper.WORK_DIR):
        with pytest.raises(InputError, match=rf"another stabctl process \(pid {os.getpid()}\)"):
            paper.write_paper_report(tmp_path, progress=lambda m: None, only=["fake"])
        assert not (tmp_path / paper.WORK_DIR).exists()
    paper.write_paper_report(tmp_path, progress=lambda m: None, only=["fake"])
    assert not (tmp_path / paper.WORK_DIR).exists()  # its sweeps' locks removed with it


def test_two_runs_give_identical_reports_and_records(tmp_path, fake_parts):
    a, b = tmp_path / "a", tmp_path / "b"
    for out in (a, b):
        paper.write_paper_report(out, progress=lambda m: None, only=["fake"])
    for name in ("paper.md", "fake_squares.jsonl"):
        assert (a / name).read_bytes() == (b / name).read_bytes()
    # a fresh run (no --resume) recomputes rather than reusing the records in OUT
    (a / "fake_squares.jsonl").write_text("")
    paper.write_paper_report(a, progress=lambda m: None, only=["fake"])
    assert (a / "fake_squares.jsonl").read_bytes() == (b / "fake_squares.jsonl").read_bytes()


def test_resume_starts_from_the_records_in_out(tmp_path, fake_parts):
    paper.write_paper_report(tmp_path, progress=lambda m: None, only=["fake"])
    first = (tmp_path / "fake_squares.jsonl").read_bytes()
    log = json.loads((tmp_path / paper.RUN_LOG).read_text())
    assert log["records"]["fake_squares.jsonl"]["job_wall_s"] >= 0
    paper.write_paper_report(tmp_path, progress=lambda m: None, only=["fake"], resume=True)
    assert (tmp_path / "fake_squares.jsonl").read_bytes() == first
    # reused records carry no timing: the run log says so with a zero sum
    log = json.loads((tmp_path / paper.RUN_LOG).read_text())
    assert log["records"]["fake_squares.jsonl"] == {
        "jobs": 6,
        "failed": 0,
        "job_wall_s": 0,
        "longest_job_s": None,
        "longest_job": None,
        "simulations": 0,
        "above_limit": 0,
        "insecure": 0,
        "failures": 0,
    }


def test_the_run_summary_counts_verdicts_apart_from_failures(tmp_path):
    """A screening's records hold CCTs, verdicts (above the search limit, N-1 insecure) and
    failures: the run log counts each from the records (`screening.verdict`), and the
    summary says them apart (the placement screening of miniWECC printed "-87 failed" when
    its 87 robust faults, once recorded as failures, became verdicts)."""
    from stabctl.stability.screening import ABOVE, INSECURE

    recs = [
        {"key": "a", "status": "ok", "result": {"cct_s": 0.1}},
        {"key": "b", "status": "verdict", "verdict": ABOVE, "reason": "still stable"},
        {"key": "c", "status": "verdict", "verdict": ABOVE, "reason": "still stable"},
        {"key": "d", "status": "verdict", "verdict": INSECURE, "reason": "unstable at once"},
        {"key": "e", "status": "failed", "error": "SimulationError: diverged"},
    ]
    f = tmp_path / "r.jsonl"
    f.write_text("".join(json.dumps(r) + "\n" for r in recs))
    counts = paper._verdicts(f)
    assert counts == {"above_limit": 2, "insecure": 1, "failures": 1}
    log = {
        "sections": [],
        "records": {"r.jsonl": {"jobs": 5, "failed": 1, "simulations": 7, **counts}},
        "total_s": 1.0,
        "cores": 2,
    }
    line = paper.run_summary(log).splitlines()[1]
    assert line.strip() == (
        "r.jsonl: 5 jobs (2 above the search limit, robust; 1 N-1 insecure; 1 failed), "
        "7 simulations"
    )


def test_strip_and_natural_order():
    rec = {
        "key": "k",
        "wall_time_s": 1.0,
        "worker": "h:1",
        "result": {"cct_s": 0.3, "wall_time_s": 2.0, "runs": [{"solve_time_s": 1, "x": 1}]},
    }
    assert strip_run_dependent(rec) == {"key": "k", "result": {"cct_s": 0.3, "runs": [{"x": 1}]}}
    keys = ["k/esd10", "k/esd5", "k/esd-none", "k/seed10", "k/seed9", "k/0.05s/seed1"]
    assert sorted(keys, key=natural_key) == [
        "k/0.05s/seed1",
        "k/esd5",
        "k/esd10",
        "k/esd-none",
        "k/seed9",
        "k/seed10",
    ]


def test_write_reproducible_keeps_last_line_per_key(tmp_path):
    src, dst = tmp_path / "src.jsonl", tmp_path / "dst.jsonl"
    src.write_text(
        '{"key": "b", "status": "failed", "wall_time_s": 1.5, "traceback": "x"}\n'
        '{"key": "a", "status": "ok", "result": {"v": 1}, "wall_time_s": 0.5}\n'
        '{"key": "b", "status": "ok", "result": {"v": 2}, "wall_time_s": 2.5}\n'
    )
    info = write_reproducible(src, dst)
    assert dst.read_text() == (
        '{"key": "a", "status": "ok", "result": {"v": 1}}\n'
        '{"key": "b", "status": "ok", "result": {"v": 2}}\n'
    )
    assert info == {
        "jobs": 2,
        "failed": 0,
        "job_wall_s": 3.0,
        "longest_job_s": 2.5,
        "longest_job": "b",
    }
    assert not list(tmp_path.glob(".dst*"))


@pytest.mark.heavy
def test_analytic_part_is_byte_identical_twice(tmp_path):
    for out in (tmp_path / "a", tmp_path / "b"):
        paper.write_paper_report(out, progress=lambda m: None, only=["analytic"])
    assert (tmp_path / "a/paper.md").read_bytes() == (tmp_path / "b/paper.md").read_bytes()
    log = json.loads((tmp_path / "a" / paper.RUN_LOG).read_text())
    assert [s["part"] for s in log["sections"]] == ["analytic"] * 3
    assert all(s["seconds"] >= 0 for s in log["sections"])


def test_placement_report_holds_no_timings(tmp_path):
    """The placement report and its JSON, from the committed study figures: no wall or
    solve times (they go to the run log through `timing_line`), named source command."""
    from stabctl.studies.placement import report, timing_line

    root = Path(__file__).resolve().parents[2]
    d = json.loads((root / "reports" / "placement_kundur.json").read_text())
    if "plan" not in d:
        pytest.skip(
            "reports/placement_kundur.json predates the planner study: "
            "regenerate it with `stabctl paper --only placement`"
        )
    d["wall_time_s"], d["plan"]["wall_time_s"] = 12.0, 3.0  # as a fresh study has
    d["plan"]["n_simulations"] = 40
    md = report(d, tmp_path).read_text()
    assert "Generated by `stabctl paper`" in md and "issue" not in md
    assert "wall time" not in md
    saved = json.loads((tmp_path / "placement_kundur.json").read_text())
    assert saved == strip_run_dependent(d) and "wall_time_s" not in saved
    assert "placement plan wall time 3 s, 40 runs (study 12 s)" in timing_line(d)
    (tmp_path / "x").mkdir()
    other = report(d, tmp_path / "x", generated_by="python analysis/placement_study.py")
    assert "Generated by `python analysis/placement_study.py`" in other.read_text()


def _committed_study(case: str) -> dict:
    root = Path(__file__).resolve().parents[2]
    return json.loads((root / "reports" / f"placement_{case}.json").read_text())


def test_placement_report_counts_units_and_empty_tables(tmp_path, monkeypatch):
    """The committed studies' reports: every contingency accounted for (faults x load
    levels = checked + out of scope + set aside), energies in MWh (1 MWh = 3600 MJ), every
    cost with its unit, no table without rows (Kundur needs no storage), and no Pareto
    line joining points asked to meet different load levels or contingencies."""
    from stabctl.studies import placement

    lines_drawn = []
    monkeypatch.setattr(placement, "_save", lambda fig, path: lines_drawn.append(fig))
    for case in ("miniwecc", "kundur"):
        d = _committed_study(case)
        p = d["plan"]
        md = placement.report(d, tmp_path).read_text()
        total = d["n_faults"] * len(d["load_levels"])
        assert total == p["n_contingencies"] + len(p["out_of_scope"]) + len(p["set_aside"])
        assert f"verified on {p['n_met']} of {p['n_contingencies']} contingencies" in md
        for a in p["allocation"]:
            assert f"| {a['absorbed_mj'] / 3600:.3f} | {a['delivered_mj'] / 3600:.3f} |" in md
        assert " MJ" not in md and "| cost |" not in md and "uniform cost |" not in md
        rows = md.splitlines()
        for k in range(len(rows) - 2):
            if rows[k + 1].startswith("|---"):
                assert rows[k + 2].startswith("|"), f"{case}: a table without rows: {rows[k]}"
        pareto = lines_drawn[-1].axes[0].get_lines()
        by_cycles = {q["cycles"]: (q["load_levels"], q["set_aside"]) for q in d["pareto"]}
        for line in pareto:
            assert len({str(by_cycles[x]) for x in line.get_xdata()}) == 1
    assert (
        "1 more set aside as infeasible (61-63@110%)"
        in (tmp_path / "placement_miniwecc.md").read_text()
    )
    assert "None: every contingency is stable without storage." in md  # Kundur


def test_resume_refuses_a_damaged_work_file_before_any_part_runs(tmp_path, fake_parts):
    """`paper --resume` with a work file none of whose lines is a record ran the other
    parts first (miniWECC's Table 4, some 15 s) and then refused with "give another
    file", an option paper lacks.  It refuses at once, with the remedies paper has."""
    ran = []
    monkeypatch_parts = {"first": (lambda fig_dir: ran.append(1) or "## first",)}
    paper.PARTS.update(monkeypatch_parts)
    work = tmp_path / paper.WORK_DIR
    work.mkdir()
    (work / "fake_squares.jsonl").write_text("garbage\n{\n")
    with pytest.raises(InputError) as err:
        paper.write_paper_report(
            tmp_path, progress=lambda m: None, only=["first", "fake"], resume=True
        )
    assert ran == [] and str(err.value).endswith(
        "remove it (its part runs again) or run without --resume"
    )
