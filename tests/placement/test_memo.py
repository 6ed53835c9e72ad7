"""A placement interrupted and run again: its finished simulations are kept as they finish
(`stabctl.placement.memo`) and the plan run again simulates only the rest and ends with
the same plan as a run never interrupted (before, an interrupted `place` kept nothing)."""

from __future__ import annotations

import json
import os

import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.errors import InputError
from stabctl.locking import kept_path
from stabctl.parallel import worker_pool
from stabctl.placement import memo as memo_module
from stabctl.placement.loop import Study
from stabctl.placement.memo import Memo, job_key
from stabctl.placement.plan import PlanOptions, plan
from stabctl.placement.requirements import Requirement
from stabctl.stability.cct import LineFault


def _square(job: dict) -> dict:
    return {"y": job["x"] ** 2, "pair": (job["x"], 0.1 * job["x"])}


def test_a_job_s_key_is_its_function_and_its_content_not_its_key_order():
    assert job_key(_square, {"x": 1, "z": [1.5, 2]}) == job_key(_square, {"z": [1.5, 2], "x": 1})
    assert job_key(_square, {"x": 1}) != job_key(_square, {"x": 2})
    assert job_key(_square, {"x": 1}) != job_key(json.dumps, {"x": 1})


def test_kept_results_come_back_as_written_and_their_jobs_are_not_run_again(tmp_path):
    path = tmp_path / "m" / "c.jsonl"
    ran = []

    def run_map(func, jobs, done=None):
        out = []
        for i, j in enumerate(jobs):
            ran.append(j["x"])
            out.append(func(j))
            done(i + 1, len(jobs), i, out[-1])
        return out

    first = Memo(path).wrap(run_map)(_square, [{"x": 3}, {"x": 0.1}])
    assert ran == [3, 0.1] and oct(path.parent.stat().st_mode & 0o777) == "0o700"
    again = Memo(path)
    assert again.n_read == 2
    second = again.wrap(run_map)(_square, [{"x": 0.1}, {"x": 5}, {"x": 3}])
    assert ran == [3, 0.1, 5] and again.n_reused == 2  # only the new job ran
    # floats come back bit for bit, tuples as the lists JSON holds (as a fresh result is
    # handed back too, so that a resumed plan and one never interrupted see the same)
    assert first == [
        {"y": 9, "pair": [3, 0.30000000000000004]},
        {"y": 0.1**2, "pair": [0.1, 0.1 * 0.1]},
    ]
    assert second == [first[1], {"y": 25, "pair": [5, 0.5]}, first[0]]


def test_a_line_a_killed_writer_left_unfinished_is_passed_over_and_counted(tmp_path):
    path = tmp_path / "c.jsonl"
    memo = Memo(path)
    memo.add("k1", {"cct_s": 0.154})
    with open(path, "a") as fh:
        fh.write('{"key": "k2", "result": {"cct')  # SIGKILL in the middle of a write
    again = Memo(path)
    assert again.results == {"k1": {"cct_s": 0.154}} and again.n_damaged == 1


def test_a_memo_another_may_write_or_a_link_or_a_huge_file_is_refused(tmp_path, monkeypatch):
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    with pytest.raises(InputError, match="writable by others than its owner"):
        Memo(shared / "c.jsonl")
    own = tmp_path / "own"
    own.mkdir(mode=0o700)
    (own / "target.jsonl").write_text("")
    (own / "c.jsonl").symlink_to(own / "target.jsonl")
    with pytest.raises(InputError, match="not a regular file"):
        Memo(own / "c.jsonl")
    (own / "big.jsonl").write_text("x" * 100)
    monkeypatch.setattr(memo_module, "MAX_MEMO_BYTES", 10)
    with pytest.raises(InputError, match="100 bytes, more than"):
        Memo(own / "big.jsonl")


def test_the_memo_lives_in_the_user_s_cache_else_under_the_temporary_directory(
    tmp_path, monkeypatch
):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    assert kept_path("stabctl-place", "abc.jsonl") == tmp_path / "cache/stabctl-place/abc.jsonl"
    (tmp_path / "file").write_text("")  # a home whose cache cannot be made
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "file"))
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))
    monkeypatch.setattr("tempfile.tempdir", None)
    (tmp_path / "tmp").mkdir()
    second = kept_path("stabctl-place", "abc.jsonl")
    assert second == tmp_path / "tmp" / f"stabctl-place-{os.geteuid()}" / "abc.jsonl"


class _Interrupting:
    """A worker map in this process that raises KeyboardInterrupt (Ctrl-C) once `after`
    jobs have finished, as a user's Ctrl-C in the middle of a batch."""

    def __init__(self, after: int):
        self.after, self.n = after, 0

    def __call__(self, func, jobs, done=None):
        out = []
        for i, j in enumerate(jobs):
            if self.n >= self.after:
                raise KeyboardInterrupt
            out.append(func(j))
            self.n += 1
            if done is not None:
                done(i + 1, len(jobs), i, out[-1])
        return out


def test_an_interrupted_plan_run_again_simulates_only_the_rest_and_gives_the_same_plan(tmp_path):
    faults = [LineFault(3, 101), LineFault(13, 101)]
    req = Requirement(gain_pct=10)
    with worker_pool(1) as run_map:
        whole = plan("kundur", faults, req, PlanOptions(), Study(run_map=run_map))
        cut = _Interrupting(after=7)
        path = tmp_path / "kundur.jsonl"
        with pytest.raises(KeyboardInterrupt):
            plan("kundur", faults, req, PlanOptions(memo=Memo(path)), Study(run_map=cut))
        kept = Memo(path)
        assert kept.n_read == 7  # every job finished before the interrupt, the batch's too
        counted = _Interrupting(after=10**9)
        again = plan("kundur", faults, req, PlanOptions(memo=kept), Study(run_map=counted))
    a, b = whole.to_dict(), again.to_dict()
    a.pop("wall_time_s"), b.pop("wall_time_s")
    assert a == b  # the same plan, its simulation count included
    assert kept.n_reused == 7 and counted.n == kept.n_written > 0


def test_cli_place_says_what_an_interrupt_keeps_and_uses_it_when_run_again(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    args = ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "10", "--workers", "1"]
    cut = _Interrupting(after=5)
    monkeypatch.setattr("stabctl.placement.loop.worker_pool", lambda *a: _Held(cut))
    monkeypatch.setattr("sys.argv", ["stabctl", *args])
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 130, res.output
    line = res.stderr.strip().splitlines()[-1]
    assert line.startswith("interrupted: 5 finished simulation job(s) are kept in ")
    assert line.endswith("; run again with: stabctl " + " ".join(args))
    (kept,) = (tmp_path / "cache" / "stabctl-place").glob("*.jsonl")
    monkeypatch.setattr(
        "stabctl.placement.loop.worker_pool", lambda *a: _Held(_Interrupting(after=10**9))
    )
    res = CliRunner().invoke(main, [*args, "--json"])
    assert res.exit_code == 0, res.output
    assert (
        f"5 finished simulation job(s) of an interrupted plan of this case read from {kept}"
        in res.stderr
    )
    assert "5 simulation job(s) taken from the interrupted plan" in res.stderr
    assert json.loads(res.stdout)["verified"] and not kept.exists()  # removed once it ended


class _Held:
    """`worker_pool`'s with-block around a given map."""

    def __init__(self, run_map):
        self.run_map = run_map

    def __enter__(self):
        return self.run_map

    def __exit__(self, *exc):
        return False


def test_cli_estimate_cct_keeps_its_finished_searches_when_interrupted(tmp_path, monkeypatch):
    """`estimate cct`'s searches are a sweep whose records it kept in a temporary
    directory, removed on an interrupt ("nothing is kept"): they are now kept in this
    user's cache, named by every setting, read by the same command run again (its sweep
    skips the recorded searches) and removed once it ends."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    args = ["estimate", "cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"]
    seen = []

    def interrupted(case, fault, ratings, runs, out, **kw):
        seen.append(out)
        record = {"key": "kundur/ideal/0", "status": "ok", "result": {"cct_cycles": 12.0}}
        with open(out, "a") as fh:
            fh.write(json.dumps(record) + "\n")
        raise KeyboardInterrupt

    monkeypatch.setattr("stabctl.estimation.closed_loop.cct_study", interrupted)
    monkeypatch.setattr("sys.argv", ["stabctl", *args])
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 130, res.output
    (kept,) = seen
    assert kept.parent == tmp_path / "cache" / "stabctl-estimate" and kept.exists()
    assert res.stderr.strip().splitlines()[-1] == (
        f"interrupted: 1 finished CCT search(es) are kept in {kept}; the same command runs "
        f"only the others; run again with: stabctl {' '.join(args)}"
    )
    row = {"mean": 12.0, "std": 0.0, "min": 12.0, "max": 12.0, "runs": 1, "failed": 0}
    row |= {"values": [12.0], "errors": [], "half_width": None}

    def finished(case, fault, ratings, runs, out, **kw):
        seen.append(out)
        return {ratings[0]: {"ideal": row}}

    monkeypatch.setattr("stabctl.estimation.closed_loop.cct_study", finished)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert seen[1] == kept and not kept.exists()  # the same file, removed once it ended
    assert f"1 finished CCT search(es) of an interrupted run of this command read from {kept}" in (
        res.stderr
    )
    # another setting, another file
    res = CliRunner().invoke(main, [*args, "--seed", "1"])
    assert res.exit_code == 0 and seen[2] != kept
