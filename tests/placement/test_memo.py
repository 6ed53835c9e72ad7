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

    with Memo(path) as memo:
        first = memo.wrap(run_map)(_square, [{"x": 3}, {"x": 0.1}])
        with pytest.raises(InputError, match="held by another plan of the same case"):
            Memo(path)  # while it is open, no other plan writes it
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


def test_a_line_cut_or_edited_is_passed_over_and_the_next_is_written_whole(tmp_path):
    """A line a killed writer left unfinished, or one edited by hand (its result no longer
    the one its sha was made of: round 39, a result "garbage" crashed `place` with a
    traceback on every run), is passed over and counted; a line added after a cut one
    starts on a line of its own (round 39: it was glued on, and lost)."""
    path = tmp_path / "c.jsonl"
    with Memo(path) as memo:
        memo.add("k1", {"cct_s": 0.154})
        memo.add("k2", {"cct_s": 0.408})
    lines = path.read_text().splitlines()
    edited = lines[1].replace("0.408", "0.816")
    path.write_text(f"{lines[0]}\n{edited}\n" + '{"key": "k3", "result": {"cct')  # a cut
    with Memo(path) as again:
        assert again.results == {"k1": {"cct_s": 0.154}} and again.n_damaged == 2
        again.add("k4", {"cct_s": 0.2})
        assert again.kept().startswith("2 finished simulation job(s) are kept in ")
    with Memo(path) as last:
        assert last.results == {"k1": {"cct_s": 0.154}, "k4": {"cct_s": 0.2}}


def test_a_memo_that_cannot_be_written_keeps_the_plan_going(tmp_path, monkeypatch):
    """A full disk or a quota while a plan runs (round 39: the plan failed): the result
    is kept for this plan, the file takes no more, one warning says so, and what an
    interrupt keeps is what the file holds."""
    path = tmp_path / "c.jsonl"
    with Memo(path) as memo:
        memo.add("k1", {"cct_s": 0.154})

        def full(fd, data):
            raise OSError(28, "No space left on device")

        monkeypatch.setattr(memo_module.os, "write", full)
        with pytest.warns(RuntimeWarning, match="cannot be written \\(No space left on device\\)"):
            memo.add("k2", {"cct_s": 0.408})
        memo.add("k3", {"cct_s": 0.5})  # no second warning, no write
        monkeypatch.undo()
        assert set(memo.results) == {"k1", "k2", "k3"}
        assert memo.kept().startswith("1 finished simulation job(s) are kept in ")
        assert "(later ones not: No space left on device)" in memo.kept()


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
        with pytest.raises(KeyboardInterrupt), Memo(path) as memo:
            plan("kundur", faults, req, PlanOptions(memo=memo), Study(run_map=cut))
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
    assert line.endswith("; resume with: stabctl " + " ".join(args))
    (kept,) = (tmp_path / "cache" / "stabctl-place").glob("*.jsonl")
    # a plan of other settings has a file of its own (round 39: a plan of the case that
    # ended removed the one another plan had kept)
    other = CliRunner().invoke(main, [*args[:-3], "20", "--workers", "1"])
    assert other.exit_code == 130 and len(list(kept.parent.glob("*.jsonl"))) == 2
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


def test_cli_place_keeps_its_memo_until_its_output_is_written(tmp_path, monkeypatch):
    """Round 39: the memo was removed as the plan returned, before `--out` was written: a
    full disk there (or Ctrl-C while the output went out) lost every simulation.  It is
    removed once the command has ended; an output that fails keeps it."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    args = ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "10", "--workers", "1"]

    def full(path, write, *a, **k):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr("stabctl.parallel.atomic_write", full)
    res = CliRunner().invoke(main, [*args, "--out", "plan.json"])
    assert res.exit_code == 2 and "plan.json: No space left on device" in res.stderr
    (kept,) = (tmp_path / "cache" / "stabctl-place").glob("*.jsonl")
    monkeypatch.undo()
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    res = CliRunner().invoke(main, [*args, "--out", "plan.json"])
    assert res.exit_code == 0 and "simulation job(s) taken from the interrupted plan" in (
        res.stderr
    )
    assert json.loads((tmp_path / "plan.json").read_text())["verified"] and not kept.exists()


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
        f"only the others; resume with: stabctl {' '.join(args)}"
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


# -- round 39's review of the above ------------------------------------------------------


def test_a_wrapped_map_tells_the_caller_s_indices_and_takes_a_map_without_done(tmp_path):
    """`done` is told of each job by its index in the caller's jobs, counting the jobs
    handed back as done, and of those kept at once, before any job runs (``done(kept,
    n)``: round 57 AV, a plan run again said "42 evaluate job(s) running" for 28 s with
    41 kept); a map that takes no ``done`` (a `Study.run_map` of its own) is called
    without it, its results kept from what it returns."""
    seen = []
    with Memo(tmp_path / "c.jsonl") as memo:
        plain = lambda func, jobs: [func(j) for j in jobs]  # noqa: E731
        memo.wrap(plain)(_square, [{"x": 1}, {"x": 3}])
        with_done = lambda func, jobs, done=None: [  # noqa: E731
            done(k + 1, len(jobs), k, func(j)) or func(j) for k, j in enumerate(jobs)
        ]
        out = memo.wrap(with_done)(
            _square, [{"x": 1}, {"x": 2}, {"x": 3}, {"x": 4}], done=lambda *a: seen.append(a)
        )
    assert [o["y"] for o in out] == [1, 4, 9, 16]
    assert seen[0] == (2, 4)
    assert [(k, n, i, r["y"]) for k, n, i, r in seen[1:]] == [(3, 4, 1, 4), (4, 4, 3, 16)]


def test_what_a_memo_keeps_is_what_its_file_holds_closed_or_removed(tmp_path):
    path = tmp_path / "c.jsonl"
    memo = Memo(path)
    memo.add("k1", {"cct_s": 0.1})
    memo.close()  # (let go at the command's end, before a late interrupt is reported)
    assert memo.kept().startswith("1 finished simulation job(s) are kept in ")
    again = Memo(path)
    again.remove()
    assert again.kept().startswith("no simulation had finished, so nothing is kept")
    assert not path.exists()


def test_two_parameter_done_callbacks_are_still_called(tmp_path):
    """worker_pool's ``done(k, n)`` of before is called so; one of four parameters gets
    the job's index and result (round 39's review: a two-parameter callback raised)."""
    seen = []
    with worker_pool(1) as run:
        run(_square, [{"x": 1}, {"x": 2}], done=lambda k, n: seen.append((k, n)))
    assert seen == [(1, 2), (2, 2)]


def test_an_insecure_window_run_that_fails_leaves_the_verdict(monkeypatch):
    """A run of the insecure window that fails (the fault on beyond what the model
    solves) is no window, and never turns the N-1 insecure verdict into a failure."""
    from stabctl.errors import InsecureContingency, SimulationError
    from stabctl.stability import cct

    def fails(k):
        raise SimulationError("the network has no solution while the fault is on")

    with pytest.raises(InsecureContingency) as said:
        cct._lower_bound_unstable(0, LineFault(3, 4), 1e-3, fails, 500, 60.0)
    assert str(said.value).endswith("N-1 insecure, CCT 0")


def test_a_refused_plan_keeps_its_memo_and_old_memos_go(tmp_path, monkeypatch):
    """A plan refused (a scheduler not answering when it is run again, round 39's review:
    its kept simulations were removed) keeps its memo; a memo untouched for KEPT_DAYS
    days and held by no one is removed by the next plan."""
    from stabctl import locking

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    args = ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "10", "--workers", "1"]
    old = tmp_path / "cache" / "stabctl-place" / "old.jsonl"
    old.parent.mkdir(parents=True, mode=0o700)
    old.write_text("")
    os.utime(old, (0, 0))

    class Refusing(_Interrupting):
        def __call__(self, func, jobs, done=None):
            out = []
            for i, j in enumerate(jobs):
                if self.n >= self.after:  # the scheduler gone
                    raise InputError("no Dask scheduler answers at tcp://127.0.0.1:1")
                out.append(func(j))
                self.n += 1
                done(i + 1, len(jobs), i, out[-1])
            return out

    monkeypatch.setattr("stabctl.placement.loop.worker_pool", lambda *a: _Held(Refusing(5)))
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2 and "no Dask scheduler answers" in res.stderr
    (kept,) = old.parent.glob("*.jsonl")  # the old one gone, this plan's kept
    assert kept != old and kept.read_text().count("\n") >= 5
    assert locking.KEPT_DAYS == 30


def test_a_second_estimate_cct_leaves_the_running_one_s_records(tmp_path, monkeypatch):
    """The same estimate cct started while one runs is refused by name before it reads
    or registers anything (round 39's review: its refusal removed the running one's
    records)."""
    from stabctl.locking import exclusive

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    args = ["estimate", "cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"]
    seen = []

    def interrupted(case, fault, ratings, runs, out, **kw):
        seen.append(out)
        raise KeyboardInterrupt

    monkeypatch.setattr("stabctl.estimation.closed_loop.cct_study", interrupted)
    assert CliRunner().invoke(main, args).exit_code == 130
    (records,) = seen
    records.write_text('{"key": "k", "status": "ok", "result": {}}\n')
    with exclusive(records):  # the first run, running
        res = CliRunner().invoke(main, args)
    assert res.exit_code == 2 and "the same estimate cct is running (pid " in res.stderr
    assert records.read_text().count("\n") == 1


def test_kept_work_goes_under_the_temporary_directory_without_a_home(tmp_path, monkeypatch):
    from stabctl.locking import kept_paths

    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")  # to be ignored (XDG)
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    home, temp = kept_paths("stabctl-place", "a.jsonl")
    assert home.is_absolute() and home.parts[-3:] == (".cache", "stabctl-place", "a.jsonl")

    def no_home():
        raise RuntimeError("Could not determine home directory.")

    monkeypatch.setattr("pathlib.Path.home", no_home)
    assert kept_paths("stabctl-place", "a.jsonl") == (temp,)


def test_estimate_cct_whose_cache_fills_runs_its_searches_in_a_temporary_file(
    tmp_path, monkeypatch
):
    """Round 39 (probe K25): a cache that filled while `estimate cct` recorded its
    searches failed the command ("No space left on device"); they are run again in a
    temporary file, with a warning."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    args = ["estimate", "cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"]
    row = {"mean": 12.0, "std": 0.0, "min": 12.0, "max": 12.0, "runs": 1, "failed": 0}
    row |= {"values": [12.0], "errors": [], "half_width": None}
    seen = []

    def study(case, fault, ratings, runs, out, **kw):
        seen.append(out)
        if "cache" in str(out):
            raise OSError(28, "No space left on device", str(out))
        return {ratings[0]: {"ideal": row}}

    monkeypatch.setattr("stabctl.estimation.closed_loop.cct_study", study)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "cannot be written (No space left on device): the searches are run again" in (res.stderr)
    assert len(seen) == 2 and "cache" not in str(seen[1])


def test_a_job_repeated_within_a_plan_is_not_counted_as_an_interrupted_plan_s(tmp_path):
    """Round 42: a fresh plan said "1 simulation job(s) taken from the interrupted plan"
    for a job it had itself run earlier (a repeat within the plan): only jobs read from
    the file of an earlier plan count as taken from it (`n_reused`), the others are
    repeats (`n_repeated`)."""
    path = tmp_path / "m" / "c.jsonl"

    def run_map(func, jobs, done=None):
        return [func(j) for j in jobs]

    with Memo(path) as memo:
        mapped = memo.wrap(run_map)
        mapped(_square, [{"x": 3}])
        mapped(_square, [{"x": 3}, {"x": 4}])
        assert (memo.n_read, memo.n_reused, memo.n_repeated) == (0, 0, 1)
    with Memo(path) as again:  # the same plan run again: the file's jobs are taken from it
        again.wrap(run_map)(_square, [{"x": 3}, {"x": 4}, {"x": 5}])
        assert (again.n_read, again.n_reused, again.n_repeated) == (2, 2, 0)
