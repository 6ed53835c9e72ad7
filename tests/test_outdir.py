"""Output directories made for a command's files are gone again when it stops before
writing them (`stabctl.outdir`): an interrupted `stabctl eig --report --out-dir NEW`
left an empty NEW behind."""

import pytest

from stabctl.outdir import output_directory


def test_directories_made_for_a_block_that_raises_are_removed(tmp_path):
    (tmp_path / "kept").mkdir()
    with pytest.raises(KeyboardInterrupt), output_directory(tmp_path / "kept" / "a" / "b"):
        raise KeyboardInterrupt
    assert [p.name for p in tmp_path.iterdir()] == ["kept"]
    assert list((tmp_path / "kept").iterdir()) == []  # it existed before: kept


def test_a_directory_holding_files_or_a_finished_block_stays(tmp_path):
    with pytest.raises(RuntimeError), output_directory(tmp_path / "a" / "b") as out:
        (out.parent / "partial.txt").write_text("x")  # what a command keeps on purpose
        raise RuntimeError("failed")
    assert not (tmp_path / "a" / "b").exists() and (tmp_path / "a" / "partial.txt").exists()
    with output_directory(tmp_path / "c") as out:
        pass
    assert out.is_dir()


def test_an_eigenvalue_report_interrupted_while_drawing_leaves_no_directory(tmp_path, monkeypatch):
    import stabctl.plotting.figures as figures
    from stabctl.io import load_case
    from stabctl.studies.eigenvalues import eig_study, write_report

    st = eig_study(load_case("kundur"))

    def interrupted(*args, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(figures, "mode_shape_compass", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_report(st, tmp_path / "new" / "report")
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    md = write_report(st, tmp_path / "new" / "report")
    assert md.exists() and len(list(md.parent.iterdir())) == 4  # the report, 3 figures
