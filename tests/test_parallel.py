"""Parallel sweeps: one JSON line per job written as it finishes, resume, failures recorded
with their reason, interrupt safety (in process and through a real SIGINT to a process
pool), Dask, and the `stabctl sweep-cct` command.  Kundur only, to keep it short."""

import collections
import itertools
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from contextlib import nullcontext
from pathlib import Path

import pytest
from click.testing import CliRunner
from dask_cluster import separate_cluster

from stabctl.cli import main
from stabctl.errors import InputError
from stabctl.locking import lock_path
from stabctl.parallel import (
    Job,
    atomic_write,
    check_scheduler,
    pooled,
    process_pool,
    read_records,
    run_sweep,
    set_aside_damaged,
    stop_pool,
)
from stabctl.stability.cct import (
    LineFault,
    SearchOptions,
    cached_simulator,
    cct_job,
    cct_jobs,
)
from stabctl.studies.cases import DEFAULT_FAULTS

# -- job functions (module level: spawned workers import them by name; one inputs dict) --


def square(inputs):
    x = inputs["x"]
    return {"y": x * x}


def boom(inputs):
    x = inputs["x"]
    raise ValueError(f"bad x = {x}")


def refuse(inputs):
    x = inputs["x"]
    raise InputError(f"no result for {x}")


def interrupt(inputs):
    raise KeyboardInterrupt


def sleepy(inputs):
    x = inputs["x"]
    time.sleep(x)
    return {"slept": x}


def ctrl_c_parent(inputs):
    """Press Ctrl-C on the sweep's own process (the pool's parent) after x s, or, with
    inputs["after"] = [path, n], once the records file at path holds n lines (within a
    minute, however loaded the machine); the time of the press is written to path.sig."""
    time.sleep(inputs["x"])
    if "after" in inputs:
        path, n = Path(inputs["after"][0]), inputs["after"][1]
        for _ in range(600):
            if path.exists() and len(path.read_text().splitlines()) >= n:
                break
            time.sleep(0.1)
        Path(f"{path}.sig").write_text(repr(time.time()))
    os.kill(os.getppid(), signal.SIGINT)
    return {}


def crash(inputs):
    x = inputs["x"]
    os._exit(x)  # the worker process dies (as on a segfault or OOM kill)


def killed_once(inputs):
    """Killed (SIGKILL, as the out-of-memory killer does) the first time it runs, while
    a sibling job sleeps; done the next time (a file in inputs["dir"] remembers)."""
    flag = Path(inputs["dir"]) / f"killed-{inputs['x']}"
    if not flag.exists():
        flag.touch()
        time.sleep(0.5)
        os.kill(os.getpid(), signal.SIGKILL)
    return {"y": inputs["x"]}


def warns_advice(inputs):
    """Warns, in its caller's words (`stabctl.errors.advice`), the same text for every
    job; returns {"y": x}."""
    import warnings

    from stabctl.errors import advice

    warnings.warn(f"a setting to check: {advice('h=...', '--step')}", UserWarning, stacklevel=1)
    return {"y": inputs["x"]}


def stops_once(inputs):
    """Stopped (SIGSTOP) the first time it runs, its pid written to inputs["flag"]
    first; done, once continued, with {"y": x}."""
    flag = Path(inputs["flag"])
    if inputs["stop"] and not flag.exists():
        flag.write_text(str(os.getpid()))
        os.kill(os.getpid(), signal.SIGSTOP)
    return {"y": inputs["x"]}


def dies_if(inputs):
    """The worker process dies (os._exit) if inputs["die"], each time; else {}."""
    if inputs["die"]:
        os._exit(1)
    return {}


def slow_square(inputs):
    time.sleep(0.2)
    return square(inputs)


def simulator_identity(inputs):
    return {"id": id(cached_simulator(inputs["case"])), "pid": os.getpid()}


def pid(inputs):
    return {"pid": os.getpid()}


def jobs_of(func, *args):
    return [Job(f"{func.__name__}/{a}", func, {"x": a}) for a in args]


def lines(path):
    return [json.loads(s) for s in path.read_text().splitlines()]


# ------------------------------------------------------------------------- CCT sweeps


def test_kundur_cct_sweep_in_processes_then_resume(tmp_path):
    out = tmp_path / "cct.jsonl"
    jobs = cct_jobs("kundur", DEFAULT_FAULTS["kundur"])
    rep = run_sweep(jobs, out, workers=2, progress=False)
    assert (rep.ran, rep.skipped, rep.failed) == (2, 0, 0)
    recs = lines(out)
    assert sorted(r["key"] for r in recs) == sorted(j.key for j in jobs) == sorted(rep.records)
    by_key = {r["key"]: r for r in recs}
    case1 = by_key["kundur/3-101/t1/esd-none"]
    assert case1["status"] == "ok" and case1["inputs"]["bus"] == 3
    res1 = case1["result"]
    assert res1["cct_cycles"] >= 9 and res1["cct_cycles"] < res1["t_unstable_cycles"] <= 10
    assert res1["numerical_error_s"] == 0.0 and res1["conventions"] == "ieee"
    assert len({r["worker"] for r in recs}) == 2  # ran in two processes
    before = out.read_bytes()
    again = run_sweep(jobs, out, workers=2, progress=False)
    assert (again.ran, again.skipped) == (0, 2) and out.read_bytes() == before
    assert again.records == rep.records


def test_failures_are_recorded_with_their_reason(tmp_path):
    """Errors are recorded as failed with their reason; a CCT above the search limit is a
    verdict (status "verdict", stabctl.errors.Verdict), not counted as failed and not
    rerun by retry_failed, with the runs that reached it (the bisection's check at 0 and
    its first probe, at t_max)."""
    out = tmp_path / "mixed.jsonl"
    too_low = Job(
        "cct-above-limit", cct_job, {"case": "kundur", "bus": 3, "far_bus": 101, "t_max": 0.1}
    )
    jobs = jobs_of(square, 2) + jobs_of(boom, 3) + jobs_of(refuse, 4) + [too_low]
    rep = run_sweep(jobs, out, workers=2, progress=False)
    assert (rep.ran, rep.failed) == (4, 2)
    recs = {r["key"]: r for r in lines(out)}
    assert recs["square/2"] == {**recs["square/2"], "status": "ok", "result": {"y": 4}}
    bad = recs["boom/3"]
    assert bad["status"] == "failed" and bad["error"] == "ValueError: bad x = 3"
    assert "in boom" in bad["traceback"] and bad["inputs"] == {"x": 3}
    assert recs["refuse/4"]["error"] == "InputError: no result for 4"
    assert "traceback" not in recs["refuse/4"]  # stabctl errors: reason only
    above = recs["cct-above-limit"]
    assert (above["status"], above["verdict"]) == ("verdict", "above t_max")
    assert "above the search limit t_max = 0.1 s" in above["reason"]
    assert above["n_simulations"] == 2
    # failed jobs are finished: skipped on resume unless retried
    assert run_sweep(jobs, out, workers=1, progress=False).ran == 0
    retry = run_sweep(jobs, out, workers=1, progress=False, retry_failed=True)
    assert (retry.ran, retry.failed) == (2, 2)
    assert len(lines(out)) == 6 and read_records(out)["boom/3"]["status"] == "failed"


def test_a_dying_worker_is_recorded_not_dropped(tmp_path):
    out = tmp_path / "crash.jsonl"
    rep = run_sweep(jobs_of(crash, 3) + jobs_of(square, 1, 2), out, workers=2, progress=False)
    assert sorted(r["key"] for r in lines(out)) == ["crash/3", "square/1", "square/2"]
    died = rep.records["crash/3"]
    assert died["status"] == "failed" and died["error"].startswith("worker failed: Broken")
    again = run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False, retry_failed=True)
    assert all(r["status"] == "ok" for r in again.records.values())


def test_a_worker_killed_once_loses_no_job_and_records_none_it_did_not_run(tmp_path):
    """A worker killed mid-sweep breaks the process pool, and every job not finished is
    lost with it: they run again on a new pool (said in a warning), the ones then running
    alone first; no job is recorded failed, each once, every result as its job gives
    it (the sweep's records against a run without the kill)."""
    out = tmp_path / "kill.jsonl"
    jobs = [Job("killed_once/1", killed_once, {"x": 1, "dir": str(tmp_path)})]
    jobs += jobs_of(slow_square, *range(2, 12))
    with pytest.warns(RuntimeWarning, match="a worker process died"):
        rep = run_sweep(jobs, out, workers=2, progress=False)
    assert (rep.ran, rep.failed) == (11, 0)
    recs = lines(out)
    assert sorted(r["key"] for r in recs) == sorted(j.key for j in jobs)  # each once
    assert all(r["status"] == "ok" for r in recs)
    assert all(
        r["result"]["y"] == r["inputs"]["x"] ** 2 for r in recs if r["key"] != "killed_once/1"
    )


def test_simulator_built_once_per_case_per_process(tmp_path):
    jobs = [Job(f"id/{i}", simulator_identity, {"case": "kundur"}) for i in range(3)]
    rep = run_sweep(jobs, tmp_path / "ids.jsonl", workers=1, progress=False)
    assert len({r["result"]["id"] for r in rep.records.values()}) == 1


def test_sweeps_on_one_pool_reuse_its_workers(tmp_path):
    with pooled(1) as pool:
        a = run_sweep(jobs_of(pid, 1), tmp_path / "a.jsonl", progress=False, pool=pool)
        b = run_sweep(jobs_of(pid, 2), tmp_path / "b.jsonl", progress=False, pool=pool)
    pids = {r["result"]["pid"] for rep in (a, b) for r in rep.records.values()}
    assert len(pids) == 1 and os.getpid() not in pids


# --------------------------------------------------------------------- interruptions


def test_interrupt_keeps_finished_lines_and_resume_runs_the_rest(tmp_path):
    out = tmp_path / "partial.jsonl"
    jobs = jobs_of(square, 1, 2) + jobs_of(interrupt, 0) + jobs_of(square, 3)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(jobs, out, workers=1, progress=False)
    assert [r["key"] for r in lines(out)] == ["square/1", "square/2"]
    rest = run_sweep(jobs_of(square, 1, 2, 3), out, workers=1, progress=False)
    assert (rest.ran, rest.skipped) == (1, 2)
    assert [r["key"] for r in lines(out)] == ["square/1", "square/2", "square/3"]


def test_a_sweep_stopped_before_its_first_record_leaves_no_file(tmp_path):
    """A sweep interrupted before any job finished (the finding: a Dask sweep waiting for
    a worker, Ctrl-C) left an empty records file of 0 records: the file is made by the
    first record, and an existing one is left as it was (its last line's missing newline
    is added by the first record)."""
    out = tmp_path / "none.jsonl"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(jobs_of(interrupt, 0), out, workers=1, progress=False)
    assert not out.exists()
    out.write_text('{"key": "square/1", "inputs": {"x": 1}, "status": "ok", "result": {"y": 1}}')
    before = out.read_bytes()
    with pytest.raises(KeyboardInterrupt):
        run_sweep(jobs_of(interrupt, 0), out, workers=1, progress=False)
    assert out.read_bytes() == before
    run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
    assert [r["key"] for r in lines(out)] == ["square/1", "square/2"]


@pytest.fixture
def sigint_raises():
    """SIGINT raising KeyboardInterrupt in this process for the test, as in a terminal:
    pytest started with SIGINT ignored (nohup, a background job, some CI runners) would
    ignore the Ctrl-C under test."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


def test_ctrl_c_on_a_process_pool_keeps_finished_lines(tmp_path, sigint_raises):
    out = tmp_path / "ctrl_c.jsonl"
    slow = jobs_of(sleepy, 30.0, 40.0)
    press = Job("ctrl_c_parent/0", ctrl_c_parent, {"x": 0.0, "after": [str(out), 2]})
    jobs = [*jobs_of(square, 1, 2), press, *slow]
    with pytest.raises(KeyboardInterrupt):
        run_sweep(jobs, out, workers=2, progress=False)
    # ended at the press, not after the sleeping jobs (30 s on): killed, not waited for
    assert time.time() - float(Path(f"{out}.sig").read_text()) < 20
    keys = [r["key"] for r in lines(out)]
    assert {"square/1", "square/2"} <= set(keys) and not any(k.startswith("sleepy") for k in keys)
    rest = run_sweep(
        jobs_of(square, 1, 2) + jobs_of(sleepy, 0.01, 0.02), out, workers=1, progress=False
    )
    assert (rest.ran, rest.skipped) == (2, 2)


def test_line_cut_by_a_kill_is_moved_aside_and_its_job_rerun(tmp_path):
    out = tmp_path / "cut.jsonl"
    run_sweep(jobs_of(square, 1), out, workers=1, progress=False)
    with out.open("a") as f:
        f.write('{"key": "square/2", "inp')  # killed mid-write
    with pytest.warns(
        UserWarning,
        match=r"line\(s\) 2 not a whole sweep record .*moved to "
        r".*cut\.jsonl\.damaged; their jobs run again",
    ):
        rep = run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
    assert (rep.ran, rep.skipped) == (1, 1)
    text = out.read_text().splitlines()
    assert [json.loads(t)["key"] for t in text] == ["square/1", "square/2"]
    assert (tmp_path / "cut.jsonl.damaged").read_text() == '{"key": "square/2", "inp\n'


def test_damaged_line_in_the_middle_is_moved_aside_too(tmp_path):
    out = tmp_path / "mid.jsonl"
    run_sweep(jobs_of(square, 1, 2, 3), out, workers=1, progress=False)
    text = out.read_text().splitlines()
    text[1] = text[1][:20] + "\x00garbage"
    out.write_text("\n".join(text) + "\n")
    with pytest.warns(UserWarning, match=r"line\(s\) 2 not a whole sweep record"):
        rep = run_sweep(jobs_of(square, 1, 2, 3), out, workers=1, progress=False)
    assert (rep.ran, rep.skipped) == (1, 2)
    assert sorted(json.loads(t)["key"] for t in out.read_text().splitlines()) == [
        "square/1",
        "square/2",
        "square/3",
    ]


_HOLD = (
    "import sys, time\n"
    "from stabctl.locking import exclusive\n"
    "with exclusive(sys.argv[1]):\n"
    "    print('held', flush=True)\n"
    "    time.sleep(120)\n"
)


def _holder(path):
    """Another process holding the output lock of path (until killed)."""
    proc = subprocess.Popen(
        [sys.executable, "-c", _HOLD, str(path)], stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout.readline() == "held\n"
    return proc


def test_a_second_writer_of_a_sweep_file_is_refused_with_the_holders_pid(tmp_path):
    """Two sweeps on one file: the second is refused at once, naming the first's pid, and
    neither repairs nor appends; a killed holder holds nothing (the lock goes with its
    process), so the next sweep takes its lock file over, runs and finds the first one's
    records."""
    out = tmp_path / "one.jsonl"
    run_sweep(jobs_of(square, 1), out, workers=1, progress=False)
    with out.open("a") as f:
        f.write('{"key": "square/2", "inp')  # a cut line the second writer must not move
    before = out.read_bytes()
    holder = _holder(out)
    try:
        with pytest.raises(
            InputError, match=rf"one\.jsonl: another stabctl process \(pid {holder.pid}\)"
        ):
            run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
        assert out.read_bytes() == before and not (tmp_path / "one.jsonl.damaged").exists()
        res = CliRunner().invoke(
            main, ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", str(out)]
        )
        assert res.exit_code == 2 and f"(pid {holder.pid})" in res.stderr
    finally:
        holder.kill()
        holder.communicate()  # reaps it and closes its pipe
    assert lock_path(out).exists()  # left by the killed holder: taken over
    with pytest.warns(UserWarning, match="not a whole sweep record"):
        rep = run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
    assert (rep.ran, rep.skipped) == (1, 1)
    assert not lock_path(out).exists()  # removed by the writer that ends


def test_a_second_writer_through_a_link_to_the_sweep_file_is_refused(tmp_path, monkeypatch):
    """Two sweeps on one file named twice (a symbolic link to it, ./x against x, a hard
    link): each took the lock beside the name it was given, both ran, and the file held
    97 records of 51 jobs.  The lock is taken beside the file the name leads to, and on
    the file itself (a hard link's lock file is another)."""
    out = tmp_path / "one.jsonl"
    run_sweep(jobs_of(square, 1), out, workers=1, progress=False)
    link = tmp_path / "link.jsonl"
    link.symlink_to(out.name)
    monkeypatch.chdir(tmp_path)
    assert lock_path(link) == lock_path("./one.jsonl") == lock_path(out)
    holder = _holder(out)
    try:
        for other in (link, "./one.jsonl"):
            with pytest.raises(InputError, match=rf"another stabctl process \(pid {holder.pid}\)"):
                run_sweep(jobs_of(square, 1, 2), other, workers=1, progress=False)
    finally:
        holder.kill()
        holder.communicate()  # reaps it and closes its pipe
    assert len(out.read_text().splitlines()) == 1
    hard = tmp_path / "hard.jsonl"  # a hard link: its lock file beside it is another
    os.link(out, hard)
    holder = _holder(out)
    try:
        with pytest.raises(InputError, match="another stabctl process is writing this file"):
            run_sweep(jobs_of(square, 1, 2), hard, workers=1, progress=False)
    finally:
        holder.kill()
        holder.communicate()  # reaps it and closes its pipe
    rep = run_sweep(jobs_of(square, 1, 2), hard, workers=1, progress=False)
    assert (rep.ran, rep.skipped) == (1, 1)  # the holder gone, the link is written


def _link_then_lock(inputs):
    """A job that makes a hard link to the sweep's file (made by the first record) and
    tries to take that file's lock through it, as a second sweep on the link would."""
    from stabctl.locking import _file_locked

    if inputs["x"] == 1:
        return {"x": 1}
    os.link(inputs["out"], inputs["hard"])
    try:
        fd = _file_locked(inputs["hard"])
    except InputError as exc:
        return {"refused": str(exc)}
    os.close(fd)
    return {"refused": None}


def test_a_hard_link_made_to_the_sweep_file_mid_sweep_finds_it_locked(tmp_path):
    """Round 32: a hard link made while a sweep ran, to the file its first record made
    (the lock on the file itself is taken when the sweep starts, and there was no file
    then), let a second sweep append to it too: 4 jobs recorded twice, and the file
    refused on the next resume.  The file a sweep makes is locked as it is made."""
    out, hard = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
    jobs = [
        Job(f"j/{x}", _link_then_lock, {"x": x, "out": str(out), "hard": str(hard)}) for x in (1, 2)
    ]
    run_sweep(jobs, out, workers=1, progress=False)
    said = read_records(out)["j/2"]["result"]["refused"]
    assert said is not None and "another stabctl process is writing this file" in said


_WRITER = """
import sys, time
from stabctl.errors import InputError
from stabctl.parallel import Job, run_sweep


def slow(inputs):
    time.sleep(0.02)
    return {"x": inputs["x"]}


try:
    jobs = [Job(f"j/{i}", slow, {"x": i}) for i in range(30)]
    rep = run_sweep(jobs, sys.argv[1], workers=1, progress=False)
    print("ran", rep.ran, rep.skipped)
except InputError as exc:
    print("refused", exc)
"""


@pytest.mark.parametrize("writers", [2, 5])
def test_concurrent_writers_of_one_sweep_file_never_duplicate_or_lose_records(tmp_path, writers):
    """Several sweeps started at once on one file: each runs (all or the rest) or is
    refused naming the pid of the one writing; the file ends with every job once, whole."""
    out = tmp_path / "shared.jsonl"
    script = tmp_path / "writer.py"
    script.write_text(_WRITER)
    procs = [
        subprocess.Popen([sys.executable, str(script), str(out)], stdout=subprocess.PIPE, text=True)
        for _ in range(writers)
    ]
    said = [p.communicate(timeout=120)[0].strip() for p in procs]
    assert all(p.returncode == 0 for p in procs), said
    ran = [t for t in said if t.startswith("ran")]
    refused = [t for t in said if t.startswith("refused")]
    assert ran and len(ran) + len(refused) == writers, said
    assert all(re.search(r"\(pid \d+\) is writing it", t) for t in refused), refused
    assert sum(int(t.split()[1]) for t in ran) == 30  # the jobs ran once in all
    keys = [json.loads(line)["key"] for line in out.read_text().splitlines()]
    assert sorted(keys) == sorted(f"j/{i}" for i in range(30))


def test_a_record_whose_write_fails_is_cut_off_so_the_file_holds_whole_records(
    tmp_path, monkeypatch
):
    """A disk full in the middle of a record: the sweep ends with the error and the file
    holds the records written before it, whole (a rerun needs no repair)."""
    import errno

    import stabctl.parallel as par

    out = tmp_path / "full.jsonl"
    run_sweep(jobs_of(square, 1), out, workers=1, progress=False)
    real_open = Path.open

    class HalfDisk:
        """Writes half of the second record it gets, then fails as a full disk."""

        def __init__(self, f):
            self.f, self.calls = f, 0

        def write(self, data):
            self.calls += 1
            if self.calls == 2:
                self.f.write(bytes(data[: len(data) // 2]))
                raise OSError(errno.ENOSPC, "No space left on device")
            return self.f.write(data)

        def __getattr__(self, name):
            return getattr(self.f, name)

    def half_open(path, mode="r", *args, **kwargs):
        f = real_open(path, mode, *args, **kwargs)
        return HalfDisk(f) if mode == "a+b" else f

    monkeypatch.setattr(par.Path, "open", half_open)
    with pytest.raises(OSError, match="No space left"):
        run_sweep(jobs_of(square, 1, 2, 3), out, workers=1, progress=False)
    monkeypatch.undo()
    assert [r["key"] for r in lines(out)] == ["square/1", "square/2"]
    rep = run_sweep(jobs_of(square, 1, 2, 3), out, workers=1, progress=False)
    assert (rep.ran, rep.skipped) == (1, 2)


def test_a_sweep_without_room_for_its_records_is_refused_before_it_runs(tmp_path, monkeypatch):
    import collections
    import shutil

    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(10**9, 10**9 - 10000, 10000))
    # in the unit that shows them (the figures rounded to "0.0 MiB" each before)
    with pytest.raises(InputError, match=r"3 job\(s\) need up to 24.0 KiB .*, 9.8 KiB are free"):
        run_sweep(jobs_of(square, 1, 2, 3), tmp_path / "n.jsonl", workers=1, progress=False)
    assert not (tmp_path / "n.jsonl").exists()


def test_written_files_get_the_mode_of_the_users_umask(tmp_path):
    """Files written whole (imported cases, CSVs, reports) and a sweep file rewritten after
    a repair get 0o666 less the umask, as any new file, not the temporary file's 0o600."""
    old = os.umask(0o027)
    try:
        atomic_write(tmp_path / "case.json", lambda f: f.write("{}"))
        out = tmp_path / "r.jsonl"
        run_sweep(jobs_of(square, 1), out, workers=1, progress=False)
        with out.open("a") as f:
            f.write('{"key": "square/2", "inp')
        with pytest.warns(UserWarning, match="not a whole sweep record"):
            run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
    finally:
        os.umask(old)
    assert [(p.stat().st_mode & 0o777) for p in (tmp_path / "case.json", out)] == [0o640] * 2


# ---------------------------------------------------------------------------- errors


def test_duplicate_keys_changed_inputs_and_bad_workers_write_nothing(tmp_path):
    out = tmp_path / "e.jsonl"
    with pytest.raises(InputError, match="duplicate job key 'square/1'"):
        run_sweep(jobs_of(square, 1, 1), out, progress=False)
    with pytest.raises(InputError, match="workers must be >= 1"):
        run_sweep(jobs_of(square, 1), out, workers=0, progress=False)
    assert not out.exists()
    run_sweep(jobs_of(square, 1), out, workers=1, progress=False)
    changed = [Job("square/1", square, {"x": 5})]
    with pytest.raises(InputError, match="'square/1' with other inputs \\(x: 1 there, 5 now\\)"):
        run_sweep(changed, out, workers=1, progress=False)


def test_scheduler_without_dask_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(InputError, match=r"needs Dask distributed.*stabctl\[dask\]"):
        run_sweep(
            jobs_of(square, 1),
            tmp_path / "d.jsonl",
            scheduler="tcp://127.0.0.1:8786",
            progress=False,
        )
    assert not (tmp_path / "d.jsonl").exists()


@pytest.mark.parametrize(
    "address, needle",
    [
        ("tls://127.0.0.1:8786", "give 'local' or a Dask scheduler's tcp://host:port"),
        ("ucx://127.0.0.1:8786", "give 'local' or a Dask scheduler's tcp://host:port"),
        ("tcp://", "give 'local' or a Dask scheduler's tcp://host:port"),
        ("tcp://127.0.0.1:99999", "tcp://127.0.0.1:99999: port 99999 is out of range"),
        ("127.0.0.1:0", "127.0.0.1:0: port 0 is out of range"),
    ],
)
def test_scheduler_addresses_are_checked_before_any_contact(tmp_path, address, needle):
    """Another scheme, no host or a port outside 1-65535 are refused before any contact,
    the port named as out of range (port 0 was taken for Dask's 8786 without a word)."""
    with pytest.raises(InputError, match=needle):
        run_sweep(jobs_of(square, 1), tmp_path / "d.jsonl", scheduler=address, progress=False)
    assert not (tmp_path / "d.jsonl").exists()
    assert check_scheduler("127.0.0.1") == "tcp://127.0.0.1:8786"
    assert check_scheduler("tcp://[::1]:5") == "tcp://[::1]:5"  # IPv6 keeps its brackets
    assert check_scheduler("[::1]") == "tcp://[::1]:8786"


@pytest.mark.dask
@pytest.mark.parametrize(
    "address, needle",
    [
        ("", "--scheduler '': an empty address"),
        ("  ", "--scheduler '  ': an empty address"),
        ("tcp://[::1", "--scheduler tcp://[::1: not an address (Invalid IPv6 URL)"),
        ("local:4", "--scheduler local:4: 'local' takes no port"),
        # round 29: a host named LOCAL looked up, Dask's ValueError of a bare inproc://
        ("LOCAL", "--scheduler 'LOCAL': give 'local' (in lower case)"),
        ("inproc://x", "--scheduler inproc://x: not an address of a Dask cluster in this"),
    ],
)
def test_a_scheduler_that_is_no_address_is_refused_not_run_locally(tmp_path, address, needle):
    """An empty scheduler ran the sweep on local processes without a word (the callers
    tested its truth), an unclosed IPv6 bracket was urlsplit's ValueError, and 'local:4'
    was a host named local (10 s to time out): each refused before any contact or job,
    by `check_scheduler`, `run_sweep` and `RunnerOptions` alike."""
    from stabctl.parallel import RunnerOptions

    for call in (
        lambda: check_scheduler(address),
        lambda: run_sweep(jobs_of(square, 1), tmp_path / "d.jsonl", scheduler=address),
        lambda: RunnerOptions(1, address),
    ):
        with pytest.raises(InputError, match=re.escape(needle)):
            call()
    assert not (tmp_path / "d.jsonl").exists()


def test_a_records_file_starting_with_a_byte_order_mark_is_read_whole(tmp_path, recwarn):
    """A records file whose first line starts with a UTF-8 byte-order mark (an editor's)
    had that valid line moved to .damaged and its job run again: the mark is skipped."""
    out = tmp_path / "d.jsonl"
    run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
    out.write_bytes(b"\xef\xbb\xbf" + out.read_bytes())
    report = run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
    assert report.ran == 0 and report.skipped == 2
    assert not (tmp_path / "d.jsonl.damaged").exists()
    assert sorted(read_records(out)) == ["square/1", "square/2"]
    assert not [w for w in recwarn if "d.jsonl" in str(w.message)]


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-32"])
def test_a_records_file_in_utf_16_or_32_is_named_so(tmp_path, encoding):
    """Round 46: a records file saved in UTF-16 (`place --screening`) was refused as "line
    1: not a whole sweep record (cut by a kill?)"; a resumed sweep would have set every
    line aside.  It is refused naming its encoding and what to do, the file untouched."""
    out = tmp_path / "d.jsonl"
    run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
    saved = out.read_text().encode(encoding)
    out.write_bytes(saved)
    for call in (
        lambda: read_records(out, whole="--screening"),
        lambda: run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False),
    ):
        with pytest.raises(InputError, match=r"d.jsonl: not UTF-8 text \(UTF-16 or UTF-32"):
            call()
    assert out.read_bytes() == saved and not (tmp_path / "d.jsonl.damaged").exists()


_NOT_DASK = "what answers there closed the connection or does not speak Dask's protocol"


@pytest.mark.parametrize(
    "reply, why",
    [
        (b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\nhi" * 50, f"{{}}: {_NOT_DASK}"),
        (b"", "{} .*it accepted the connection and sent no Dask handshake"),
        ("echo", f"{{}}: {_NOT_DASK} \\(\\w+: "),
        ("hang up", f"{{}}: {_NOT_DASK} \\(\\w+: "),
    ],
    ids=["web-server", "silent", "echo", "hang-up"],
)
def test_a_service_that_is_not_a_dask_scheduler_is_a_clear_error_within_the_time_box(
    tmp_path, monkeypatch, reply, why
):
    """A web server where the scheduler should be: "Unable to allocate 3.07 EiB" (a length
    read from its HTTP reply) or a hang; a peer that accepts and says nothing: a hang
    (Dask's handshake has no time-out).  Now one InputError within SCHEDULER_TIMEOUT_S
    naming the address.  Round 32: an echo server read as "no answer within 10 s
    (AssertionError: )" after 1 s, and one that hangs up in Dask's raw words; both now
    say that what answers is no Dask scheduler."""
    pytest.importorskip("distributed")
    import socket
    import threading

    monkeypatch.setattr("stabctl.parallel.SCHEDULER_TIMEOUT_S", 3.0)
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    held = []  # each connection stays open: the peer neither answers nor hangs up

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            held.append(conn)
            if reply == "hang up":
                conn.close()
            elif reply == "echo":
                threading.Thread(target=echo, args=(conn,), daemon=True).start()
            else:
                conn.sendall(reply)

    def echo(conn):
        try:
            while data := conn.recv(65536):
                conn.sendall(data)
        except OSError:
            return

    threading.Thread(target=serve, daemon=True).start()
    t0 = time.perf_counter()
    try:
        with pytest.raises(
            InputError,
            match="no Dask scheduler answers at " + why.format(f"tcp://127.0.0.1:{port}"),
        ):
            run_sweep(
                jobs_of(square, 1),
                tmp_path / "d.jsonl",
                scheduler=f"tcp://127.0.0.1:{port}",
                progress=False,
            )
    finally:
        server.close()
        for conn in held:
            conn.close()
    assert time.perf_counter() - t0 < 20
    assert not (tmp_path / "d.jsonl").exists()
    # the client whose start failed is closed, not left to Dask's finaliser
    assert_no_dask_client_left()


def test_a_scheduler_address_nothing_listens_at_is_said_so(tmp_path, monkeypatch):
    """Nothing listening at the address (a port closed): the sweep said "it accepted the
    connection and sent no Dask handshake" after its wait; it now says nothing listens
    there, after the wait a starting scheduler gets."""
    pytest.importorskip("distributed")
    import socket

    monkeypatch.setattr("stabctl.parallel.SCHEDULER_TIMEOUT_S", 2.0)
    with socket.socket() as s:  # a port free a moment ago, nothing listening
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(InputError, match=r"\(nothing listens there \(Connection refused\)"):
        run_sweep(jobs_of(square, 1), tmp_path / "d.jsonl", scheduler=f"tcp://127.0.0.1:{port}")
    assert not (tmp_path / "d.jsonl").exists()
    # a host no name service knows was "nothing listens there" too (round 29)
    with pytest.raises(InputError, match=r"\(the host no-such-host\.invalid is not known here"):
        run_sweep(jobs_of(square, 1), tmp_path / "d.jsonl", scheduler="no-such-host.invalid")
    assert_no_dask_client_left()


def assert_no_dask_client_left():
    """No distributed Client or local cluster of this process open (each closed, none
    left to Dask's finaliser, which closes a forgotten client whenever the garbage
    collector finds it: the finding, in the middle of a later client's start), none
    registered as Dask's default client, and dask.config's scheduler not set to it."""
    import gc

    import dask
    import distributed
    from distributed.client import _global_clients
    from distributed.deploy.spec import SpecCluster

    # type(), not isinstance(): gc also holds weak proxies, whose isinstance() raises
    # ReferenceError once their object is gone (the whole suite has some)
    alive = [
        o
        for o in gc.get_objects()
        if issubclass(type(o), distributed.Client) and o.status not in ("closed", "newly-created")
    ]
    assert alive == []
    assert dict(_global_clients) == {}
    with pytest.raises(ValueError, match="No clients found"):
        distributed.default_client()
    assert dask.config.get("scheduler", None) != "dask.distributed"
    clusters = [c for c in SpecCluster._instances if c.status.name != "closed"]
    assert clusters == []


class _Refused(Exception):
    pass


def _refuse_the_file(monkeypatch):
    # the sweep's file refused once the cluster has started (e.g. a disk gone): the
    # records' generator is closed before its first record
    def refused(self):
        raise _Refused("disk gone")

    monkeypatch.setattr("stabctl.parallel._appender.__enter__", refused)


def _interrupt_the_client_start(monkeypatch):
    # Ctrl-C as the client's start ends (its constructor raises KeyboardInterrupt)
    import distributed

    start = distributed.Client.start

    def interrupted(self, **kwargs):
        start(self, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(distributed.Client, "start", interrupted)


def _stop_after_the_first_record(done, total):
    raise KeyboardInterrupt  # Ctrl-C once the first record is written


@pytest.mark.dask
@pytest.mark.parametrize(
    "how, raised",
    [
        ("normally", None),
        ("file refused", _Refused),
        ("ctrl-c in the client's start", KeyboardInterrupt),
        ("ctrl-c after the first record", KeyboardInterrupt),
    ],
)
def test_a_local_dask_sweep_leaves_no_client_or_cluster_open(tmp_path, monkeypatch, how, raised):
    """`run_sweep(..., scheduler="local")` (``--scheduler local``) however it ends: its
    Client and LocalCluster are closed when it returns or raises (the finding: a sweep
    whose file was refused after the cluster started left both open, and Dask's finaliser
    closed them inside a later client's start, which hung); a sweep that finds every job
    done starts none.  Nothing is left in the temporary directory (the cluster's workers
    kept their ``dask-scratch-space`` there)."""
    pytest.importorskip("distributed")
    import tempfile

    temp = tmp_path / "tmp"
    temp.mkdir()
    monkeypatch.setenv("TMPDIR", str(temp))
    monkeypatch.setattr(tempfile, "tempdir", None)  # gettempdir() reads TMPDIR again
    out = tmp_path / "d.jsonl"
    progress = False
    if how == "file refused":
        _refuse_the_file(monkeypatch)
    elif how == "ctrl-c in the client's start":
        _interrupt_the_client_start(monkeypatch)
    elif how == "ctrl-c after the first record":
        progress = _stop_after_the_first_record
    jobs = jobs_of(square, 1, 2)
    if raised is None:
        rep = run_sweep(jobs, out, scheduler="local", workers=1, progress=progress)
        assert rep.records["square/2"]["result"] == {"y": 4}
    else:
        with pytest.raises(raised):
            run_sweep(jobs, out, scheduler="local", workers=1, progress=progress)
    assert_no_dask_client_left()
    assert list(temp.iterdir()) == []
    assert len(read_records(out)) == {"normally": 2, "ctrl-c after the first record": 1}.get(how, 0)
    if how == "normally":  # every job done: the sweep returns without starting a cluster
        import distributed

        def no_start(*args, **kwargs):
            raise AssertionError("a Dask client or cluster started")

        monkeypatch.setattr(distributed.Client, "__init__", no_start)
        monkeypatch.setattr(distributed.LocalCluster, "__init__", no_start)
        again = run_sweep(jobs, out, scheduler="local", workers=1, progress=False)
        assert (again.ran, again.skipped) == (0, 2)
        assert_no_dask_client_left()


@pytest.mark.dask
def test_a_local_dask_sweep_says_nothing_of_port_8787_in_use(tmp_path):
    """A local cluster's scheduler serves no dashboard, but its HTTP server took port 8787
    and, that port held by another cluster on the machine, warned "Port 8787 is already
    in use ... Hosting the HTTP server on port N instead" on every `--scheduler local`
    run: it takes a free port."""
    pytest.importorskip("distributed")
    import socket
    import warnings

    taken = socket.socket()
    try:
        taken.bind(("127.0.0.1", 8787))
        taken.listen()
    except OSError:  # held by another process: in use all the same
        pass
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            run_sweep(
                jobs_of(square, 1),
                tmp_path / "d.jsonl",
                scheduler="local",
                workers=1,
                progress=False,
            )
    finally:
        taken.close()
    assert [str(w.message) for w in caught if "8787" in str(w.message)] == []


@pytest.mark.dask
def test_dask_cluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, processes=False, dashboard_address=None) as c:
        rep = run_sweep(
            jobs_of(square, 1, 2) + jobs_of(boom, 3),
            tmp_path / "d.jsonl",
            scheduler=c.scheduler_address,
            progress=False,
        )
    assert (rep.ran, rep.failed) == (3, 1)
    assert rep.records["square/2"]["result"] == {"y": 4}
    assert rep.records["boom/3"]["error"] == "ValueError: bad x = 3"


@pytest.mark.dask
def test_a_cluster_without_a_worker_is_said_and_waited_for(tmp_path, monkeypatch, caplog):
    """A scheduler with no worker (the finding: `screen --scheduler` sat at 0/2 for ever
    without a word): after DASK_NO_WORKER_YET_S the sweep says, once, that the cluster has
    no worker and that it waits for one; it keeps waiting, and runs its jobs once a
    worker joins."""
    import threading

    distributed = pytest.importorskip("distributed")
    monkeypatch.setattr("stabctl.parallel.DASK_NO_WORKER_YET_S", 0.5)
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as c:
        joins = threading.Timer(3.0, c.scale, (1,))
        joins.start()
        try:
            with caplog.at_level("WARNING", logger="stabctl.parallel"):
                rep = run_sweep(
                    jobs_of(square, 1, 2),
                    tmp_path / "d.jsonl",
                    scheduler=c.scheduler_address,
                    progress=False,
                )
        finally:
            joins.join()
    assert (rep.ran, rep.failed) == (2, 0)
    said = [r.getMessage() for r in caplog.records if "has no worker" in r.getMessage()]
    assert said == [
        f"the Dask cluster at {c.scheduler_address} has no worker (none for 0.5 s): waiting "
        "for one to join; Ctrl-C stops the sweep, keeping its finished records"
    ]


@pytest.mark.dask
def test_a_worker_running_another_stabctl_is_refused_by_name(tmp_path, monkeypatch):
    """A Dask worker importing a copy of stabctl with one edit (the finding: it ran the
    sweep's jobs without a word, both sides reporting version 0.1.0): no job runs there,
    and the sweep stops with one InputError naming the worker and both package digests,
    no record written; `place`'s map (`worker_pool`) refuses it alike."""
    import shutil

    pytest.importorskip("distributed")
    from stabctl._jit.cache import _PKG, package_digest
    from stabctl.parallel import worker_pool

    other = tmp_path / "other"
    shutil.copytree(_PKG, other / "stabctl", ignore=shutil.ignore_patterns("__pycache__"))
    init = other / "stabctl" / "__init__.py"
    init.write_text(init.read_text() + "\n# an uncommitted edit\n")
    theirs = package_digest(other / "stabctl")
    assert theirs != package_digest()
    out = tmp_path / "d.jsonl"
    needle = (
        r"Dask worker tcp://127\.0\.0\.1:\d+ runs another stabctl than this one \(package "
        rf"digest {theirs[:12]} there, {package_digest()[:12]} here\)"
    )
    monkeypatch.chdir(tmp_path)  # `python -m` puts the working directory first on the path
    with separate_cluster(1, path=(other, Path(__file__).parent)) as (address, _, _):
        with pytest.raises(InputError, match=needle):
            run_sweep(jobs_of(square, 1, 2), out, scheduler=address, progress=False)
        with worker_pool(1, address) as pool_map, pytest.raises(InputError, match=needle):
            pool_map(square, [{"x": 1}])
    assert not out.exists()


@pytest.mark.dask
def test_local_dask_cluster_records_a_dead_worker_as_failed_and_resumes(tmp_path):
    pytest.importorskip("distributed")
    out = tmp_path / "d.jsonl"
    rep = run_sweep(
        jobs_of(square, 1, 2) + jobs_of(crash, 3), out, scheduler="local", workers=2, progress=False
    )
    assert (rep.ran, rep.failed) == (3, 1)
    assert rep.records["square/2"]["result"] == {"y": 4}
    assert "crash/3" in read_records(out) and "Killed" in rep.records["crash/3"]["error"]
    again = run_sweep(jobs_of(square, 1, 2, 4), out, scheduler="local", workers=1, progress=False)
    assert (again.ran, again.skipped) == (1, 2)


@pytest.mark.dask
def test_a_scheduler_killed_mid_sweep_records_no_job_it_did_not_run(tmp_path, caplog):
    """A Dask scheduler and its worker started apart (as on a cluster), the scheduler
    killed while 8 one-second jobs run on one worker (the finding: the sweep exited 0 and
    recorded the never-run jobs as failed, which the next run skipped): the finished
    jobs are recorded, the others are not, the sweep ends with SweepIncomplete naming how
    many were not run, and the same call on a new cluster runs exactly those."""
    pytest.importorskip("distributed")
    from stabctl.parallel import SweepIncomplete

    out = tmp_path / "d.jsonl"
    jobs = jobs_of(sleepy, *[1.0 + 0.01 * k for k in range(8)])
    with separate_cluster(1) as (address, sched, _):
        written = []

        def kill_after_three(done, total):
            written.append(done)
            if done == 3:
                sched.kill()

        with pytest.raises(SweepIncomplete) as lost:
            run_sweep(jobs, out, scheduler=address, progress=kill_after_three)
        said = str(lost.value)  # the cluster named, distributed's reason whole or cut
        # lost by a job's future, or found by the sweep's question to the scheduler (which
        # notices the kill first is a race): either names the cluster and the reason
        hit = re.match(
            rf"\d of 8 jobs not run: the Dask cluster at {address} (lost them|closed its "
            r"connection) \((its scheduler stopped or was killed: )?(.*?)\)"
            r"( \(not run: [^;]*\))?; the finished",
            said,
        )
        assert hit, said
        kind, text = hit.group(3).split(": ", 1)  # at a word (textwrap.shorten), marked " ..."
        assert kind.isidentifier() and len(text) <= 160
        kept = read_records(out)
        assert 3 <= len(kept) < 8 and all(r["status"] == "ok" for r in kept.values())
        # distributed's own log of the lost connection (a traceback on stderr) is not
        # shown: the SweepIncomplete line says it
        assert not [r for r in caplog.records if r.name.startswith("distributed.")]
    with separate_cluster(1) as (address, _, _):
        rest = run_sweep(jobs, out, scheduler=address, progress=False)
    assert (rest.ran, rest.skipped, rest.failed) == (8 - len(kept), len(kept), 0)
    assert len(lines(out)) == 8


@pytest.mark.dask
def test_a_scheduler_killed_mid_map_is_said_as_jobs_not_run_not_a_traceback(caplog):
    """`worker_pool`'s map on a Dask cluster started apart (`place --scheduler`, `paper`),
    the scheduler killed mid-map: the placement stopped with distributed's
    FutureCancelledError and a traceback (exit 1), where a sweep names the jobs the
    cluster lost.  The map ends with SweepIncomplete saying so, distributed's own log of
    the lost connection not shown."""
    pytest.importorskip("distributed")
    from stabctl.parallel import SweepIncomplete, worker_pool

    jobs = [{"x": 1.0 + 0.01 * k} for k in range(6)]
    with separate_cluster(1) as (address, sched, _):

        def kill_after_two(done, total, *_):
            if done == 2:
                sched.kill()

        with (
            worker_pool(1, scheduler=address) as run_map,
            pytest.raises(SweepIncomplete) as lost,
        ):
            run_map(sleepy, jobs, kill_after_two)
        said = str(lost.value)
        # which of the two the sweep sees first depends on timing: the jobs' futures lost,
        # or the scheduler's connection closed under its poll (`_DaskWorkers.ask`)
        why = "(lost them|closed its connection \\(its scheduler stopped or was killed)"
        assert re.match(rf"[1-4] of 6 jobs not run: the Dask cluster at {address} {why}", said)
        assert not [r for r in caplog.records if r.name.startswith("distributed.")]


def counted_cct(inputs):
    """`cct_job`, each run's start and end appended to the file $STABCTL_TEST_RUNS (one
    line each: start|end, key, pid), so that a test counts how often each job ran."""
    key = inputs["key_for_count"]
    job = {k: v for k, v in inputs.items() if k != "key_for_count"}
    with open(os.environ["STABCTL_TEST_RUNS"], "a") as f:
        f.write(f"start {key} {os.getpid()}\n")
    try:
        return cct_job(job)
    finally:  # a raised verdict ends the job too
        with open(os.environ["STABCTL_TEST_RUNS"], "a") as f:
            f.write(f"end {key} {os.getpid()}\n")


@pytest.mark.dask
def test_a_worker_killed_mid_screening_loses_no_job_and_repeats_none(tmp_path, caplog):
    """Kundur line faults (error_check off) on a scheduler with two workers started apart
    (`dask worker --nthreads 1 --no-nanny`), one SIGKILLed mid-sweep while it runs a job:
    Dask runs that job on the other worker; each job is in the file once, ok, with the CCT
    the same search gives in this process; no finished job ran again (the finding: the
    finished jobs of the dead worker ran again, their futures being still held); the loss
    is said on the sweep's log."""
    pytest.importorskip("distributed")
    faults = [LineFault(b, f, t) for t in (1.0, 1.5) for b, f in ((3, 101), (13, 101), (13, 14))]
    faults += [LineFault(3, 101, 2.0), LineFault(13, 101, 2.0)]
    cct = cct_jobs("kundur", faults, search=SearchOptions(error_check=False))
    jobs = [Job(j.key, counted_cct, {**j.inputs, "key_for_count": j.key}) for j in cct]
    reference = run_sweep(cct, tmp_path / "here.jsonl", workers=1, progress=False).records
    runs = tmp_path / "runs.txt"
    out = tmp_path / "dask.jsonl"
    killed: list[int] = []
    with separate_cluster(2, {"STABCTL_TEST_RUNS": str(runs)}) as (address, _, workers):

        def kill_at_second(done, total, *_):
            # the worker of the record just written has begun its next job (0.4-0.8 s)
            if done == 2:
                pid = int(read_records(out)[last_key(out)]["worker"].rsplit(":", 1)[1])
                [worker] = [w for w in workers if w.pid == pid]
                worker.kill()
                killed.append(pid)

        with caplog.at_level("WARNING", logger="stabctl.parallel"):
            rep = run_sweep(jobs, out, scheduler=address, progress=kill_at_second)
    assert killed and (rep.ran, rep.failed) == (len(jobs), 0)
    recs = lines(out)
    assert sorted(r["key"] for r in recs) == sorted(j.key for j in jobs)  # each once
    for r in recs:
        assert r["status"] == "ok"
        assert r["result"]["cct_s"] == reference[r["key"]]["result"]["cct_s"]
    assert killed[0] not in {int(r["worker"].rsplit(":", 1)[1]) for r in recs[2:]}
    marks = [line.split() for line in runs.read_text().splitlines()]
    ends = sorted(key for what, key, _ in marks if what == "end")
    assert ends == sorted(j.key for j in jobs)  # every job finished once, none again
    on_killed = {(what, key) for what, key, pid in marks if int(pid) == killed[0]}
    cut = {key for what, key in on_killed if what == "start" and ("end", key) not in on_killed}
    starts = collections.Counter(key for what, key, _ in marks if what == "start")
    # the job cut by the kill ran again, to its end, on the other worker; no other
    assert len(cut) <= 1 and {key for key, n in starts.items() if n > 1} == cut
    assert max(starts.values()) <= 2
    assert "Dask worker(s) lost: 1 of 2 left" in caplog.text


@pytest.mark.dask
def test_a_sweep_whose_last_worker_dies_records_no_job_it_did_not_run(tmp_path, monkeypatch):
    """The one worker of a cluster started apart killed mid-sweep (the finding: the sweep
    waited for ever): after DASK_NO_WORKER_S without a worker, SweepIncomplete names the
    jobs not run; the finished ones are recorded, none as failed."""
    pytest.importorskip("distributed")
    from stabctl.parallel import SweepIncomplete

    monkeypatch.setattr("stabctl.parallel.DASK_NO_WORKER_S", 2.0)
    out = tmp_path / "d.jsonl"
    jobs = jobs_of(sleepy, *[0.5 + 0.01 * k for k in range(6)])
    with separate_cluster(1) as (address, _, [worker]):

        def kill_at_second(done, total, *_):
            if done == 2:
                worker.kill()

        t0 = time.perf_counter()
        with pytest.raises(
            SweepIncomplete,
            match=r"4 of 6 jobs not run: the Dask cluster at tcp://127.0.0.1:\d+ has had no "
            r"worker for 2 s \(its last one died or left; a worker that cannot import this "
            r"stabctl dies on its first job: its log then ends in an ImportError\) \(not "
            r"run: sleepy/0.5\d, ",
        ):
            run_sweep(jobs, out, scheduler=address, progress=kill_at_second)
    assert time.perf_counter() - t0 < 30
    kept = lines(out)
    assert len(kept) == 2 and all(r["status"] == "ok" for r in kept)


def marked_sleep(inputs):
    """Sleep inputs["x"] s; the start and the end appended to $STABCTL_TEST_RUNS."""
    with open(os.environ["STABCTL_TEST_RUNS"], "a") as f:
        f.write(f"start {inputs['x']} {os.getpid()}\n")
    time.sleep(inputs["x"])
    with open(os.environ["STABCTL_TEST_RUNS"], "a") as f:
        f.write(f"end {inputs['x']} {os.getpid()}\n")
    return {"x": inputs["x"], "pid": os.getpid()}


@pytest.mark.dask
def test_worker_pool_on_dask_survives_a_killed_worker_without_rerunning_finished_jobs(
    tmp_path,
):
    """`worker_pool`'s map (place --scheduler) on two workers started apart, one killed
    while it runs a job: every result, in job order; every job ran to its end once (the
    finding: the futures were all held until the end, so Dask ran the dead worker's
    finished jobs again)."""
    pytest.importorskip("distributed")
    from stabctl.parallel import worker_pool

    runs = tmp_path / "runs.txt"
    jobs = [{"x": 0.4 + 0.01 * k} for k in range(8)]
    killed: list[int] = []
    with separate_cluster(2, {"STABCTL_TEST_RUNS": str(runs)}) as (address, _, workers):

        def kill_at_second(done, total, *_):
            if done == 2:
                ended = [line.split() for line in runs.read_text().splitlines()]
                pid = int(next(pid for what, _, pid in reversed(ended) if what == "end"))
                [worker] = [w for w in workers if w.pid == pid]
                worker.kill()
                killed.append(pid)

        with worker_pool(1, address) as run_map:
            results = run_map(marked_sleep, jobs, done=kill_at_second)
    assert killed and [r["x"] for r in results] == [j["x"] for j in jobs]
    marks = [line.split() for line in runs.read_text().splitlines()]
    ends = collections.Counter(x for what, x, _ in marks if what == "end")
    assert sorted(ends) == sorted(str(j["x"]) for j in jobs) and set(ends.values()) == {1}


def last_key(path: Path) -> str:
    return lines(path)[-1]["key"]


# ------------------------------------------------------------------------------- CLI


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def assert_bad_input(res, tmp_path, needle):
    assert res.exit_code == 2, res.output
    err = res.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and needle in err[0], res.stderr
    assert res.stdout == "" and list(tmp_path.iterdir()) == []


def test_cli_sweep_cct_default_faults_json_then_resume(tmp_path):
    out = tmp_path / "k.jsonl"
    res = run(
        "sweep-cct",
        "kundur",
        "--faults",
        "DEFAULT",
        "--out",
        out,
        "--workers",
        1,
        "--tol-ms",
        5,
        "--json",
    )
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert (d["ran"], d["skipped"], d["failed"]) == (2, 0, 0)
    assert [r["key"] for r in d["records"]] == [
        "kundur/3-101/t1/esd-none",
        "kundur/13-101/t1/esd-none",
    ]
    assert len(lines(out)) == 2
    res = run("sweep-cct", "kundur", "--faults", "DEFAULT", "--out", out, "--tol-ms", 5)
    assert res.exit_code == 0, res.output
    assert "kundur/3-101/t1/esd-none" in res.stdout
    assert "2 job(s): 0 run now, 2 already in" in res.stdout


@pytest.mark.dask
def test_cli_sweep_cct_on_a_local_dask_cluster_leaves_none_open(tmp_path, monkeypatch):
    """`stabctl sweep-cct --scheduler local` (the users' path to the finding): the
    cluster and its client are closed when the command ends; run again with every job in
    the file, it starts none."""
    distributed = pytest.importorskip("distributed")
    out = tmp_path / "k.jsonl"
    args = ("sweep-cct", "kundur", "--faults", "DEFAULT", "--out", out, "--tol-ms", 5)
    res = run(*args, "--scheduler", "local", "--workers", 1, "--json")
    assert res.exit_code == 0, res.output
    assert [r["status"] for r in json.loads(res.stdout)["records"]] == ["ok", "ok"]
    assert_no_dask_client_left()

    def no_start(*args, **kwargs):
        raise AssertionError("a Dask client or cluster started")

    monkeypatch.setattr(distributed.Client, "__init__", no_start)
    monkeypatch.setattr(distributed.LocalCluster, "__init__", no_start)
    res = run(*args, "--scheduler", "local", "--workers", 1)
    assert res.exit_code == 0, res.output
    assert "2 job(s): 0 run now, 2 already in" in res.stdout
    assert_no_dask_client_left()


@pytest.mark.parametrize("recorded, given", [(None, 6), (6.0, None)])
def test_a_sweep_resumed_with_the_default_run_end_given_or_left_out_reruns_nothing(
    tmp_path, monkeypatch, recorded, given
):
    """Records made without --tf (t_end None) were refused by a rerun with --tf 6 ("other
    inputs (t_end: None there, 6.0 now)"), though 6 s is the default run end of a fault
    at 1 s (+ 5 s); the effective run ends are compared, either way round, and nothing
    runs again.  Another run end (--tf 7) is still other inputs."""
    import stabctl.stability.cct as cct

    monkeypatch.setattr(cct, "compile_here", lambda *a, **k: None)  # no run needed here
    out = tmp_path / "k.jsonl"
    jobs = cct_jobs("kundur", [LineFault(3, 101)], search=SearchOptions(t_end=recorded))
    assert jobs[0].inputs["t_end"] == recorded
    record = {"key": jobs[0].key, "inputs": jobs[0].inputs, "status": "failed", "error": "x"}
    out.write_text(json.dumps(record) + "\n")
    faults = tmp_path / "f.csv"
    faults.write_text("bus,far_bus\n3,101\n")
    args = ("sweep-cct", "kundur", "--faults", faults, "--workers", 1, "--out", out)
    res = run(*args, *(() if given is None else ("--tf", given)))
    assert res.exit_code == 1, res.output  # the record it keeps is a failure
    assert "1 job(s): 0 run now, 1 already in" in res.stdout
    res = run(*args, "--tf", 7)
    assert res.exit_code == 2, res.output
    assert f"with other inputs (t_end: {recorded!r} there, 7.0 now)" in res.stderr
    assert lines(out) == [record]


def test_cli_sweep_cct_faults_csv(tmp_path):
    faults = tmp_path / "faults.csv"
    faults.write_text("bus,far_bus,t_fault\n3,101,0.5\n")
    res = run(
        "sweep-cct",
        "kundur",
        "--faults",
        faults,
        "--out",
        tmp_path / "o.jsonl",
        "--workers",
        1,
        "--tol-ms",
        5,
        "--json",
    )
    assert res.exit_code == 0, res.output
    rec = json.loads(res.stdout)["records"][0]
    assert rec["key"] == "kundur/3-101/t0.5/esd-none" and rec["status"] == "ok"


def test_cli_sweep_cct_names_the_records_in_its_file_that_are_not_its_own(tmp_path):
    """A screening's records in a sweep's --out were kept and never mentioned (a
    screening warns of a sweep's in its file; probe round 31)."""
    out = tmp_path / "s.jsonl"
    res = run("screen", "kundur", "--buses", "3", "--out", out, "--workers", 1)
    assert res.exit_code == 0, res.output
    faults = tmp_path / "faults.csv"
    faults.write_text("bus,far_bus\n3,101\n")
    res = run(
        "sweep-cct", "kundur", "--faults", faults, "--out", out, "--workers", 1, "--tol-ms", 5
    )
    assert res.exit_code == 0, res.output
    assert (
        f"warning: {out} holds 1 record(s) of none of this sweep's 1 job(s), kept in the "
        "file and not counted here: line 1: job kundur/bus3/t1/esd-none (another run's)"
    ) in " ".join(res.stderr.split())
    assert len(lines(out)) == 2


@pytest.mark.parametrize(
    "args, needle",
    [
        (("--faults", "missing.csv"), "fault list missing.csv"),
        (("--faults", "DEFAULT", "--esd-pct", "abc"), "--esd-pct 'abc'"),
        (("--faults", "DEFAULT", "--workers", 0), "--workers 0: must be in [1, 1024]"),
        (("--faults", "DEFAULT", "--tol-ms", -1), "--tol-ms"),
        # --workers was left unused without a word (probe round 31)
        (
            ("--faults", "DEFAULT", "--workers", 7, "--scheduler", "tcp://127.0.0.1:9"),
            "--workers 7 with --scheduler tcp://127.0.0.1:9: the jobs run on that cluster's",
        ),
    ],
)
def test_cli_sweep_cct_bad_input(tmp_path, args, needle):
    res = run("sweep-cct", "kundur", "--out", tmp_path / "o.jsonl", *args)
    assert_bad_input(res, tmp_path, needle)


def test_cli_sweep_cct_unknown_line_fails_before_any_job(tmp_path):
    faults = tmp_path / "faults.csv"
    faults.write_text("bus,far_bus\n3,13\n")
    res = run("sweep-cct", "kundur", "--faults", faults, "--out", tmp_path / "o.jsonl")
    assert res.exit_code == 2 and "no branch between bus 3 and bus 13" in res.stderr
    assert not (tmp_path / "o.jsonl").exists()


def test_ratings_parse_none_and_lists():
    from stabctl.cli.stability import _ratings

    assert _ratings(()) == [None]
    assert _ratings(("none,5", "10")) == [None, 5.0, 10.0]
    with pytest.raises(InputError, match="--esd-pct: 5 given twice"):
        _ratings(("none,5", "10", "5"))  # was merged without a word
    assert [j.key for j in cct_jobs("kundur", [LineFault(3, 101)], [None, 5.0])] == [
        "kundur/3-101/t1/esd-none",
        "kundur/3-101/t1/esd5",
    ]


def test_sweep_jobs_with_another_controller_are_keyed_apart():
    # the paper's controller: exactly cct_jobs' jobs (earlier records resume); another:
    # the ratings' jobs carry it in their inputs and keys
    from stabctl.stability.cct import cct_jobs
    from stabctl.storage.control import BangBangCOI
    from stabctl.studies.cases import default_faults
    from stabctl.studies.sweeps import controlled_cct_job, controlled_cct_jobs

    faults = default_faults("kundur")[:1]
    plain = cct_jobs("kundur", faults, [None, 5.0])
    assert controlled_cct_jobs("kundur", faults, [None, 5.0], BangBangCOI()) == plain
    other = controlled_cct_jobs("kundur", faults, [None, 5.0], BangBangCOI(deadband_hz=0.05))
    assert other[0] == plain[0]
    assert other[1].key == plain[1].key + "/ctrl-db0.05-vg0.8-system-hy0"
    assert other[1].func is controlled_cct_job
    assert other[1].inputs["controller"]["deadband_hz"] == 0.05


@pytest.mark.dask
def test_worker_pool_runs_on_a_local_dask_cluster():
    # `place --scheduler local`: the evaluations go to Dask, results in job order
    pytest.importorskip("distributed")
    from stabctl.parallel import worker_pool

    seen: list = []
    with worker_pool(1, "local") as run_map:
        assert run_map(dict, [{"a": 1}, {"b": 2}]) == [{"a": 1}, {"b": 2}]
        done = run_map(dict, [{"a": 1}, {"b": 2}], done=lambda k, n, *_: seen.append((k, n)))
    assert done == [{"a": 1}, {"b": 2}] and seen == [(1, 2), (2, 2)]  # told as each finished


def test_worker_pool_on_processes_loses_no_job_when_a_worker_is_killed(tmp_path):
    """`worker_pool`'s map on two processes (`place --workers 2`, `paper`), one job's
    worker killed (SIGKILL) the first time it runs: the map stopped with
    BrokenProcessPool and a traceback, the plan lost.  The pool is replaced for the jobs
    not finished, with a warning, and every result comes back in job order; the pool is
    kept for the next map.  A job that kills its worker every time ends the map with
    SweepIncomplete after `POOL_RESTARTS` restarts, naming the jobs not run."""
    from stabctl.parallel import POOL_RESTARTS, SweepIncomplete, worker_pool

    jobs = [{"x": k, "dir": str(tmp_path)} for k in range(6)]
    with worker_pool(2) as run_map:
        with pytest.warns(
            RuntimeWarning, match=r"a worker process died .*: \d+ job\(s\) not finished run again"
        ):
            got = run_map(killed_once, jobs)
        assert got == [{"y": k} for k in range(6)]
        assert run_map(killed_once, jobs[:2]) == [{"y": 0}, {"y": 1}]  # the new pool, kept
        with (
            pytest.warns(RuntimeWarning),
            pytest.raises(
                SweepIncomplete,
                match=rf"1 of 2 jobs not run: worker processes died {POOL_RESTARTS + 1} times",
            ),
        ):
            run_map(dies_if, [{"die": True}, {"die": False}])


def _not_collected(got):
    """The warnings of `got` but a ResourceWarning: the garbage collector may close, while
    this test records, a file some earlier test of its process left open (CI, 2026-12-01:
    "unclosed file <_io.FileIO name=20 mode='rb'>"), which is none of the pool's."""
    return [w for w in got if not issubclass(w.category, ResourceWarning)]


@pytest.mark.parametrize("words", ["library", "cli"])
def test_a_worker_s_warnings_are_given_once_by_the_parent_in_its_words(tmp_path, capfd, words):
    """`estimate cct --step 0.0185` gave its step warning once from the command and once
    more from each worker process (in the library's words, two workers' lines glued
    together between the progress bar's updates).  A worker's warnings come back with
    its job's result and are given in the parent, as its own (a command says each text
    once), worded for the parent's front: a command's options, not Python arguments."""
    import warnings

    from stabctl import parallel
    from stabctl.errors import speaking

    jobs = [{"x": k} for k in range(4)]
    expected = "a setting to check: " + ("--step" if words == "cli" else "h=...")
    with (
        speaking(words),
        parallel.worker_pool(2) as run_map,
        warnings.catch_warnings(record=True) as got,
    ):
        warnings.simplefilter("always")
        assert run_map(warns_advice, jobs) == [{"y": k} for k in range(4)]
    got = _not_collected(got)
    assert {str(w.message) for w in got} == {expected} and len(got) == 4  # one per job
    assert "warning" not in capfd.readouterr().err  # none shown by a worker itself
    with speaking(words), warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        jobs = [Job(f"w/{k}", warns_advice, {"x": k}) for k in range(3)]
        run_sweep(jobs, tmp_path / "w.jsonl", workers=2, progress=False)
    got = _not_collected(got)
    assert {str(w.message) for w in got} == {expected} and len(got) == 3
    assert "warning" not in capfd.readouterr().err


def test_a_stopped_worker_is_named_and_its_job_goes_on_once_continued(
    tmp_path, monkeypatch, caplog
):
    """A worker process stopped (SIGSTOP) left a sweep or a placement waiting without a
    word.  While no job finishes the pool's workers are looked at, and the stopped one is
    named once, at once (a logged warning, as a lost Dask worker), with how its job goes
    on; continued, every result comes back."""
    import threading

    from stabctl import parallel

    monkeypatch.setattr(parallel, "STALL_CHECK_S", 0.2)
    flag = tmp_path / "stopped"
    jobs = [{"x": k, "stop": k == 1, "flag": str(flag)} for k in range(3)]

    def cont():  # continued 2 s after it stopped, as an operator would
        while not flag.exists() or not flag.read_text():
            time.sleep(0.05)
        time.sleep(2.0)
        os.kill(int(flag.read_text()), signal.SIGCONT)

    helper = threading.Thread(target=cont, daemon=True)
    helper.start()
    with parallel.worker_pool(2) as run_map, caplog.at_level("WARNING", "stabctl.parallel"):
        got = run_map(stops_once, jobs)
    helper.join(5)
    assert got == [{"y": k} for k in range(3)]
    pid = int(flag.read_text())
    named = [r.getMessage() for r in caplog.records if "is stopped" in r.getMessage()]
    assert named == [
        f"worker process {pid} is stopped (SIGSTOP, SIGTSTP or a debugger): the job it runs "
        f"waits until it is continued (kill -CONT {pid}); killed instead, its job runs "
        "again on a new worker"
    ]


def test_an_output_file_without_any_record_is_left_alone(tmp_path):
    """`screen --out f.csv` with f.csv a faults table moved the whole table to
    f.csv.damaged and wrote records in its place; a file of several lines none of which is
    a record is refused (nothing moved), while a single cut line, a first record cut by a
    kill, is still set aside."""
    table = tmp_path / "f.csv"
    table.write_text("bus,far_bus\n3,101\n")
    with pytest.raises(InputError, match=r"f.csv: none of its 2 lines is a sweep record"):
        run_sweep([Job("square/2", square, {"x": 2})], table, workers=1, progress=False)
    assert table.read_text() == "bus,far_bus\n3,101\n" and not (tmp_path / "f.csv.damaged").exists()
    cut = tmp_path / "cut.jsonl"
    cut.write_text('{"key": "square/2", "inp')
    with pytest.warns(UserWarning, match="cut by a kill"):
        assert set_aside_damaged(cut) == [1]


def test_a_record_without_its_result_is_not_a_whole_record(tmp_path):
    """A line with status ok and no result (a file edited by hand) crashed sweep-cct and
    screen with KeyError; it is now a damaged line like a cut one."""
    from stabctl.parallel import read_records, set_aside_damaged

    out = tmp_path / "o.jsonl"
    good = {"key": "a", "status": "ok", "result": {"cct_s": 0.2}}
    out.write_text(json.dumps(good) + "\n" + json.dumps({"key": "b", "status": "ok"}) + "\n")
    with pytest.warns(UserWarning, match="line 2: not a sweep record"):
        assert list(read_records(out)) == ["a"]
    with pytest.warns(UserWarning, match="moved to"):
        assert set_aside_damaged(out) == [2]


def test_a_job_recorded_twice_is_refused_unless_the_first_failed(tmp_path):
    """A key appended again with another CCT was taken silently (the last line won)."""
    from stabctl.parallel import read_records

    out = tmp_path / "o.jsonl"
    rec = {"key": "a", "status": "ok", "result": {"cct_s": 0.2}}
    failed = {"key": "a", "status": "failed", "error": "SimulationError: x"}
    out.write_text(json.dumps(failed) + "\n" + json.dumps(rec) + "\n")
    assert read_records(out)["a"]["result"]["cct_s"] == 0.2  # a retry after a failure
    with out.open("a") as f:
        f.write(json.dumps({**rec, "result": {"cct_s": 0.999}}) + "\n")
    with pytest.raises(InputError, match="line 3: job a is recorded again"):
        read_records(out)


def test_a_repaired_records_file_keeps_its_mode(tmp_path):
    """A records file of mode 0640 repaired (a cut last line set aside) under umask 0002
    became 0664: `atomic_write` gave the file it replaced a new file's mode.  A file
    replaced keeps its permission bits; a new one still follows the umask."""
    out = tmp_path / "r.jsonl"
    old = os.umask(0o002)
    try:
        run_sweep(jobs_of(square, 1), out, workers=1, progress=False)
        out.chmod(0o640)
        with out.open("a") as f:
            f.write('{"key": "square/2", "inp')
        with pytest.warns(UserWarning, match="not a whole sweep record"):
            run_sweep(jobs_of(square, 1, 2), out, workers=1, progress=False)
        atomic_write(tmp_path / "new.txt", lambda f: f.write("x"))
    finally:
        os.umask(old)
    assert out.stat().st_mode & 0o777 == 0o640
    assert (tmp_path / "new.txt").stat().st_mode & 0o777 == 0o664


def test_atomic_write_keeps_links_and_writes_devices_in_place(tmp_path):
    """A link named as the output stays a link (its file is replaced), and a device such
    as /dev/null (or /dev/stdout) is written in place: never a regular file renamed over
    it, which had turned /dev/stdout into a file."""
    real = tmp_path / "real.json"
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    assert atomic_write(link, lambda f: f.write("new")) == link
    assert link.is_symlink() and real.read_text() == "new"
    sink = tmp_path / "sink"
    sink.symlink_to(os.devnull)
    atomic_write(sink, lambda f: f.write(b"frames"), mode="wb")
    assert sink.is_symlink() and Path(os.devnull).is_char_device()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.json", "real.json", "sink"]


def test_atomic_write_creates_no_directory_a_broken_link_points_to(tmp_path):
    """A link to a file in a missing directory had that directory created and the file
    written there; a link that leads nowhere (broken or a loop) is an OSError, nothing
    created, the link left as it was."""
    broken = tmp_path / "broken.csv"
    broken.symlink_to(tmp_path / "missing" / "dir" / "x.csv")
    with pytest.raises(OSError):
        atomic_write(broken, lambda f: f.write("rows"))
    loop = tmp_path / "loop.csv"
    loop.symlink_to(loop.name)
    with pytest.raises(OSError):
        atomic_write(loop, lambda f: f.write("rows"))
    assert not (tmp_path / "missing").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.csv", "loop.csv"]


def test_a_record_of_another_case_is_refused_naming_its_line(tmp_path):
    """A kundur sweep resumed into a file holding a miniwecc record kept the foreign record
    without a word (the report listed only this run's jobs); refused, naming the file, the
    line, the job and its case, the file unchanged."""
    out = tmp_path / "o.jsonl"
    jobs = [Job(f"kundur/{x}", square, {"case": "kundur", "x": x}) for x in (1, 2)]
    run_sweep(jobs[:1], out, workers=1, progress=False)
    foreign = {"key": "miniwecc/3", "inputs": {"case": "miniwecc", "x": 3}, "status": "ok"}
    with out.open("a") as f:
        f.write(json.dumps({**foreign, "result": {"y": 9}}) + "\n")
    before = out.read_text()
    with pytest.raises(
        InputError,
        match=r"o.jsonl line 2: job miniwecc/3 was run on case 'miniwecc', not on this run's "
        r"\(kundur\)",
    ):
        run_sweep(jobs, out, workers=1, progress=False)
    assert out.read_text() == before


def test_records_of_the_same_case_file_named_otherwise_say_so(tmp_path, monkeypatch):
    """A screening of ./case.json resumed (or read by place --screening) as case.json was
    refused as "another case's records" though the file is the same: records are keyed by
    the case as given, and the message now says it is the same file and how to name it."""
    from stabctl.io import load_case
    from stabctl.io.pst import write_case_json

    monkeypatch.chdir(tmp_path)
    write_case_json(load_case("kundur"), tmp_path / "case.json")
    args = ["screen", "--buses", "3", "--workers", "1", "--tol-ms", "20", "--out", "s.jsonl"]
    assert run(args[0], "./case.json", *args[1:]).exit_code == 0
    before = (tmp_path / "s.jsonl").read_text()
    for other in ("case.json", str(tmp_path / "case.json")):
        res = run(args[0], other, *args[1:])
        assert res.exit_code == 2
        assert (
            f"was run on case './case.json', this run's {other!r} is the same file named "
            "otherwise: records are keyed by the case as the command gives it; give it as "
            "'./case.json'" in res.stderr
        )
    assert (tmp_path / "s.jsonl").read_text() == before


@pytest.mark.parametrize(
    "command",
    [
        ("sweep-cct", "case.json", "--faults", "f.csv"),
        ("screen", "case.json", "--buses", "3"),
    ],
)
def test_records_of_a_case_file_edited_since_are_refused(tmp_path, monkeypatch, command):
    """sweep-cct and screen of a case file, the file edited (every H doubled), the same
    command again: the records were keyed by the file's name, so the rerun said its job
    was already there and kept the old CCT.  Each job records the digest of the case's
    content: refused, naming the file, the line, the job, the case and that it changed,
    the records left as they were; records without a digest are refused likewise."""
    from stabctl.io import load_case
    from stabctl.io.pst import write_case_json

    monkeypatch.chdir(tmp_path)
    kundur = load_case("kundur")
    write_case_json(kundur, "case.json")
    (tmp_path / "f.csv").write_text("bus,far_bus\n3,101\n")
    args = (*command, "--workers", 1, "--tol-ms", 20, "--out", "o.jsonl")
    assert run(*args).exit_code == 0
    before = (tmp_path / "o.jsonl").read_text()
    first = json.loads(before.splitlines()[0])
    assert first["inputs"]["case_digest"] == kundur.digest()
    write_case_json(
        kundur.replace(machines=kundur.machines.replace(H=2 * kundur.machines.H)), "case.json"
    )
    res = run(*args)
    assert res.exit_code == 2 and res.stdout == "", res.output
    assert (
        f"error: o.jsonl line 1: job {first['key']} was run on case 'case.json' as it was "
        f"then: its content has changed since (digest {kundur.digest()} there, "
    ) in res.stderr
    assert "give another output file (--out)" in res.stderr
    assert (tmp_path / "o.jsonl").read_text() == before
    write_case_json(kundur, "case.json")
    del first["inputs"]["case_digest"]
    (tmp_path / "o.jsonl").write_text(json.dumps(first) + "\n")
    res = run(*args)
    assert res.exit_code == 2, res.output
    assert "line 1: job" in res.stderr and "before records carried the digest" in res.stderr


def test_a_stopped_pool_leaves_no_worker_behind():
    """An interrupted sweep's pool (`stop_pool`) kills its running workers and reaps
    them before the sweep exits: none is left, not even as a zombie."""
    pool = process_pool(2)
    futures = [pool.submit(sleepy, {"x": 30}) for _ in range(2)]
    deadline = time.monotonic() + 60
    while not all(f.running() for f in futures) and time.monotonic() < deadline:
        time.sleep(0.05)
    procs = list(pool._processes.values())
    assert len(procs) == 2
    stop_pool(pool)
    assert all(p.exitcode is not None for p in procs)


def test_a_record_giving_a_key_twice_is_refused_naming_its_line(tmp_path):
    """json keeps the last value of a key given twice: a record edited to hold two
    results was read with the second without a word (and --screening, resumed sweeps and
    check_records_case all read records so)."""
    from stabctl.parallel import check_records_case, read_records, set_aside_damaged

    out = tmp_path / "o.jsonl"
    rec = {"key": "a", "status": "ok", "result": {"cct_s": 0.2}}
    out.write_text(json.dumps(rec) + "\n" + json.dumps(rec)[:-1] + ', "result": {"cct_s": 0.9}}\n')
    needle = rf'{out} line 2: key "result" given twice in one object \(an object, then an object\)'
    for read in (read_records, set_aside_damaged, lambda p: check_records_case(p, {}, "")):
        with pytest.raises(InputError, match=needle):
            read(out)


# ------------------------------------------------------- records of impossible types


def square_record_problem(rec):
    """The schema of `square`'s records, for the tests: y is x squared."""
    if rec["status"] == "ok" and rec["result"].get("y") != rec["inputs"]["x"] ** 2:
        return f"result.y {rec['result'].get('y')!r} is not x squared"
    return None


@pytest.mark.parametrize(
    ("edit", "why"),
    [
        (lambda r: r.update(result={}), r"result\.y None is not x squared"),
        (lambda r: r["result"].update(y="abc"), r"result\.y 'abc' is not x squared"),
        (
            lambda r: r.update(status="verdict", verdict={"a": 1}),
            r"status verdict without its verdict \(a text",
        ),
        (
            lambda r: (r.pop("result"), r.update(status="failed", error={"a": 1})),
            r"status failed without its error \(a text",
        ),
        (lambda r: r.update(status=["ok"]), r'status \["ok"\] is none of ok, verdict, failed'),
        (lambda r: r.update(inputs=[1]), r"inputs \[1\] is not an object"),
        (lambda r: r.update(wall_time_s=-1), r"wall_time_s -1 is not a time in s"),
    ],
)
def test_a_record_its_job_cannot_have_written_is_set_aside_and_its_job_rerun(tmp_path, edit, why):
    """A record line of valid JSON with fields of the wrong types (result {}, a CCT as
    text, a verdict or error that is an object) crashed the formatters of a resumed sweep
    with a traceback, or was shown as the job's result; it is a damaged line: moved aside
    with a warning naming the line and why, and its job run again."""
    out = tmp_path / "t.jsonl"
    jobs = [Job(f"square/{x}", square, {"x": x}, check=square_record_problem) for x in (2, 3)]
    run_sweep(jobs, out, workers=1, progress=False)
    recs = lines(out)
    edit(recs[1])
    out.write_text("".join(json.dumps(r) + "\n" for r in recs))
    damaged = rf"t\.jsonl: line\(s\) 2 not a whole sweep record \({why}"
    with pytest.warns(UserWarning, match=damaged):
        rep = run_sweep(jobs, out, workers=1, progress=False)
    assert (rep.ran, rep.skipped) == (1, 1)
    assert rep.records["square/3"]["result"] == {"y": 9}
    assert [r["key"] for r in lines(out)] == ["square/2", "square/3"]
    assert json.loads((tmp_path / "t.jsonl.damaged").read_text()) == recs[1]
    with pytest.raises(InputError, match=rf"screening records .*t\.jsonl\.damaged line 1: .*{why}"):
        read_records(tmp_path / "t.jsonl.damaged", "screening records", square_record_problem)


def _cct_record(**result):
    """A CCT record as `cct_job` writes it (Kundur 3-101), with `result` changed."""
    r = {
        "cct_s": 0.14,
        "cct_cycles": 8.4,
        "numerical_error_s": 0.0,
        "cct_half_step_s": 0.14,
        "t_stable_s": 0.14,
        "t_unstable_s": 0.16,
        "t_unstable_cycles": 9.6,
        "n_simulations": 7,
        "separated_machines": [3, 4],
        "islanded": [],
    }
    r.update(result)
    return {"key": "k", "inputs": {"t_max": 1.0}, "status": "ok", "result": r}


@pytest.mark.parametrize(
    ("rec", "why"),
    [
        (_cct_record(cct_s=-5.0, cct_cycles=-300), r"result\.cct_s -5\.0 is not a clearing time"),
        (_cct_record(cct_s=1e300), r"result\.cct_s 1e\+300 is not a clearing time in \[0, 1\]"),
        (_cct_record(cct_s=None), r"result\.cct_s null"),
        (_cct_record(cct_s="abc"), r"result\.cct_s \"abc\""),
        (_cct_record(t_unstable_s=0.1), r"result\.t_unstable_s 0\.1 is not"),
        (_cct_record(cct_cycles=float("nan")), r"result\.cct_cycles NaN"),
        (_cct_record(n_simulations=True), r"result\.n_simulations true"),
        (_cct_record(separated_machines="x"), r"result\.separated_machines \"x\""),
        (_cct_record(islanded=[{"buses": "4"}]), r"result\.islanded"),
        # edited by hand within its numbers' ranges (round 29): a CCT inside its own
        # bracket, cycles not its seconds, a bracket its probes never ran
        (_cct_record(cct_s=0.15), r"^result\.cct_s 0\.15 is not its t_stable_s 0\.14"),
        (_cct_record(cct_cycles=99), r"^result\.cct_cycles 99 is not its cct_s 0\.14 at 60 Hz"),
        (_cct_record(tol_s=0.01), r"^result bracket 0\.14-0\.16 s is not its tol_s 0\.01 wide"),
        (
            _cct_record(
                cct_s=0.18,
                t_stable_s=0.18,
                t_unstable_s=0.2,
                cct_cycles=10.8,
                t_unstable_cycles=12.0,
                probes=[[1.0, False], [0.14, True], [0.16, False]],
            ),
            r"^result\.probes have no stable run at 0\.18 s, the bracket's stable end",
        ),
        (
            {"key": "k", "status": "verdict", "verdict": "robust"},
            r"verdict \"robust\" is none of a CCT search's",
        ),
        *(
            (
                {"key": "k", "status": "verdict", "verdict": "above t_max", "n_simulations": n},
                rf"^n_simulations {w} is not a count >= 1",
            )
            for n, w in ((0, "0"), (2.5, "2.5"), (True, "true"), ("3", '"3"'))
        ),
        *(
            ({**_cct_record(), "inputs": {"t_max": 1.0, "guess_s": g}}, rf"inputs\.guess_s {w}")
            for g, w in (("abc", '"abc"'), (-5, "-5"), (float("nan"), "NaN"), (True, "true"))
        ),
        (
            {**_cct_record(), "inputs": {"t_max": 1.0, "guess_s": 2.0}},
            r"not a clearing time in \[0, 1\]",
        ),
        # a record relabelled by hand (key and inputs of 13-101, result of 3-101's
        # search) or whose inputs were edited (a 20 ms bracket taken for a 10 ms search)
        (
            {**_cct_record(fault={"bus": 3, "far_bus": 101}), "inputs": {"bus": 13}},
            r"result\.fault\.bus 3 is not the record's inputs\.bus 13: the answer of another",
        ),
        (
            {**_cct_record(tol_s=0.02), "inputs": {"t_max": 1.0, "tol": 0.01}},
            r"result\.tol_s 0\.02 is not the record's inputs\.tol 0\.01",
        ),
        (_cct_record(end_concerns=5), r"end_concerns 5 is not a list of phrases"),
        # the record without storage relabelled as the 5 % one, and a verdict's
        (
            {**_cct_record(esd_pct=None), "inputs": {"t_max": 1.0, "esd_pct": 5}},
            r"result\.esd_pct None is not the record's inputs\.esd_pct 5",
        ),
        (
            {
                "key": "k",
                "inputs": {"bus": 3, "esd_pct": None},
                "status": "verdict",
                "verdict": "above t_max",
                "fault": {"bus": 13},
                "esd_pct": None,
            },
            r"^fault\.bus 13 is not the record's inputs\.bus 3: the answer of another search",
        ),
        (
            _cct_record(end_concerns=["bus 3 at 0.5 pu"], end_t_s="6"),
            r"end_t_s \"6\" is not a time in s",
        ),
        (
            {**_cct_record(t_max_s=0.5), "inputs": {"t_max": 1.0}},
            r"result\.t_max_s 0\.5 is not the record's inputs\.t_max 1\.0",
        ),
    ],
)
def test_the_schema_of_cct_records_refuses_what_no_search_writes(rec, why):
    from stabctl.stability.cct import cct_record_problem

    assert cct_record_problem(_cct_record()) is None
    assert re.search(why, cct_record_problem(rec) or "")


@pytest.mark.parametrize(
    "edit",
    [
        lambda r: r.update(result={}),
        lambda r: r["result"].update(cct_s="abc"),
        lambda r: r["result"].update(cct_s=None),
        lambda r: r["result"].update(cct_s=-5.0, cct_cycles=-300),
        lambda r: r["result"].update(cct_s=1e300),
        lambda r: r["result"].update(separated_machines="x"),
        lambda r: r.update(status="verdict", verdict={"a": 1}),
        lambda r: (r.pop("result"), r.update(status="failed", error={"a": 1})),
    ],
)
def test_sweep_cct_reruns_a_record_of_impossible_fields_instead_of_showing_it(tmp_path, edit):
    """`stabctl sweep-cct` resumed on a record edited to impossible fields: no traceback,
    no CCT of -5 s or 1e300 s shown; the line is moved aside by name and the job runs
    again."""
    out = tmp_path / "t.jsonl"
    faults = tmp_path / "f1.csv"
    faults.write_text("bus,far_bus\n3,101\n")
    args = ["sweep-cct", "kundur", "--faults", faults, "--workers", 1, "--tol-ms", 20]
    assert run(*args, "--out", out).exit_code == 0
    good = lines(out)[0]
    edit(rec := json.loads(json.dumps(good)))
    out.write_text(json.dumps(rec) + "\n")
    res = run(*args, "--out", out)
    assert res.exit_code == 0, res.output
    assert "1 run now, 0 already" in res.output
    assert re.search(r"warning: .*t\.jsonl: line\(s\) 1 not a whole sweep record \(", res.output)
    assert f"{good['result']['cct_s']:7.3f}" in res.output
    assert lines(out)[0]["result"]["cct_s"] == good["result"]["cct_s"]


def test_a_records_file_above_the_input_cap_is_refused_before_it_is_read(tmp_path):
    """A sweep's own --out, 280 MB of blank lines, was read for 112 s without a word (only
    its lines were bounded) before the sweep appended to it; it is refused at once by the
    cap of JSON text read whole, naming it, and left as it is (round 44: a 223 MiB file of
    records under the 256 MiB cap of every input peaked at 1.8 GiB)."""
    from stabctl.jsontext import MAX_JSON_BYTES

    out = tmp_path / "big.jsonl"
    with out.open("wb") as f:
        f.truncate(MAX_JSON_BYTES + 2**20)  # sparse: no disk used
    said = r"big\.jsonl: 65 MiB, above the 64 MiB a file of JSON text read whole may have"
    t0 = time.perf_counter()
    for read in (set_aside_damaged, read_records):
        with pytest.raises(InputError, match=said):
            read(out)
    with pytest.raises(InputError, match=said):
        run_sweep(jobs_of(square, 1), out, workers=1, progress=False)
    assert time.perf_counter() - t0 < 5
    assert out.stat().st_size == MAX_JSON_BYTES + 2**20
    assert not (tmp_path / "big.jsonl.damaged").exists()


def test_lines_that_are_not_records_are_named_up_to_a_bound(tmp_path, recwarn):
    """Round 44: 9 million lines that are not records each gave their own warning (1.9
    GiB, 195 s) before "none of its lines is a sweep record": `read_records` names the
    first LINES_NAMED and counts the rest, `set_aside_damaged` refuses a file whose first
    LINES_WITHOUT_RECORD lines hold no record there, without reading on."""
    from stabctl.parallel import LINES_NAMED, LINES_WITHOUT_RECORD

    out = tmp_path / "m.jsonl"
    out.write_text("".join(f'{{"key": "k{i}", "a": 1}}\n' for i in range(LINES_WITHOUT_RECORD + 5)))
    assert read_records(out) == {}
    said = [str(w.message) for w in recwarn]
    assert len(said) == LINES_NAMED + 1
    assert said[0].startswith(f"{out} line 1: not a sweep record (")
    more = LINES_WITHOUT_RECORD + 5 - LINES_NAMED
    assert said[-1] == f"{out}: {more} more line(s) not sweep records, ignored"
    with pytest.raises(
        InputError, match=rf"none of its first {LINES_WITHOUT_RECORD} lines is a sweep"
    ):
        set_aside_damaged(out)
    assert out.stat().st_size > 0 and not (tmp_path / "m.jsonl.damaged").exists()


def test_failures_recorded_before_and_not_rerun_are_counted_and_told(tmp_path):
    """A failed record resumed without --retry-failed was shown as failed with no word
    that it had not been run again: the report counts them, and sweep-cct says that
    --retry-failed reruns them (exit status 1, as a fresh sweep with a failed job: a
    failure is no verdict, and a script checking the status sees it)."""
    out = tmp_path / "f.jsonl"
    run_sweep(jobs_of(boom, 1) + jobs_of(square, 2), out, workers=1, progress=False)
    rep = run_sweep(jobs_of(boom, 1) + jobs_of(square, 2), out, workers=1, progress=False)
    assert (rep.ran, rep.failed, rep.failed_before) == (0, 0, 1)
    rep = run_sweep(jobs_of(boom, 1), out, workers=1, progress=False, retry_failed=True)
    assert (rep.ran, rep.failed, rep.failed_before) == (1, 1, 0)

    faults = tmp_path / "f1.csv"
    faults.write_text("bus,far_bus\n3,101\n")
    args = ["sweep-cct", "kundur", "--faults", faults, "--workers", 1, "--tol-ms", 20]
    cct = tmp_path / "c.jsonl"
    assert run(*args, "--out", cct).exit_code == 0
    rec = lines(cct)[0]
    rec.pop("result")
    rec.update(status="failed", error="worker failed: BrokenProcessPool")
    cct.write_text(json.dumps(rec) + "\n")
    res = run(*args, "--out", cct)
    assert res.exit_code == 1
    assert res.stdout.splitlines()[-1] == (
        "1 job(s) recorded as failed before were not run again; --retry-failed reruns them"
    )
    assert res.stderr == (
        f"1 job failed (listed above with the reasons, recorded in {cct}; --retry-failed "
        "reruns them): exit status 1\n"
    )
    res = run(*args, "--out", cct, "--retry-failed")
    assert res.exit_code == 0 and "--retry-failed" not in res.output


_BIG_RECORDS = """
import resource, sys
from stabctl.parallel import Job, run_sweep
resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))
jobs = [Job(f"pad/{k}", dict, {"pad": "x" * 1500}) for k in range(4)]
try:
    run_sweep(jobs, sys.argv[1], workers=1, progress=False)
except OSError as exc:
    print(exc.filename, exc.strerror)
"""


def test_a_write_past_the_file_size_limit_names_the_file(tmp_path):
    """Under ``ulimit -f`` (and on a full disk) write() fails naming no file, and every
    output said only 'error: File too large': the records appender and the atomic writer
    name the output (never their temporary file), and keep it whole."""
    import errno

    out = tmp_path / "u.jsonl"
    res = subprocess.run(
        [sys.executable, "-c", _BIG_RECORDS, str(out)], capture_output=True, text=True
    )
    assert res.stdout == f"{out} File too large\n", res.stderr
    assert [r["key"] for r in lines(out)] == ["pad/0"]  # whole lines only: the next cut off

    def full(f):
        f.write("half")
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(OSError) as caught:
        atomic_write(tmp_path / "x.csv", full)
    assert caught.value.filename == str(tmp_path / "x.csv")
    assert not [p for p in os.listdir(tmp_path) if "x.csv" in p]  # no temporary file left

    def other(f):
        (tmp_path / "missing" / "y").read_text()  # an error naming another file stays

    with pytest.raises(FileNotFoundError) as caught:
        atomic_write(tmp_path / "x.csv", other)
    assert caught.value.filename == str(tmp_path / "missing" / "y")


def test_screen_says_a_failure_is_an_earlier_run_s_and_retry_failed_reruns_it(tmp_path):
    """`screen` showed a search recorded as failed by an earlier run as this run's result,
    with no hint and no --retry-failed: the row is marked recorded before, the last line
    says --retry-failed reruns it, and --retry-failed does (sweep-cct's code path)."""
    out = tmp_path / "sc.jsonl"
    args = ["screen", "kundur", "--buses", "3", "--workers", "1", "--tol-ms", "20"]
    assert CliRunner().invoke(main, [*args, "--out", str(out)]).exit_code == 0
    rec = json.loads(out.read_text())
    rec.update(status="failed", error="SimulationError: diverged")
    rec.pop("result", None)
    rec.pop("verdict", None)
    out.write_text(json.dumps(rec) + "\n")
    res = CliRunner().invoke(main, [*args, "--out", str(out)])
    assert res.exit_code == 1, res.output
    assert "SimulationError: diverged (recorded before)" in res.stdout
    assert res.stdout.endswith(
        "1 search(es) recorded as failed before were not run again; --retry-failed reruns them\n"
    )
    res = CliRunner().invoke(main, [*args, "--out", str(out), "--retry-failed"])
    assert res.exit_code == 0 and "1 CCT(s) found" in res.stdout, res.output
    assert "recorded before" not in res.stdout


def test_an_output_name_near_the_file_system_s_limit_gets_helper_files_that_fit(tmp_path):
    """A legal 255-byte output name was refused for its lock's or temporary copy's name
    (".<name>.lock": File name too long): helpers of such a name are shortened with a
    hash, one per name, and the sweep writes it."""
    from stabctl.locking import NAME_MAX, lock_path

    a, b = "a" * 249 + ".jsonl", "a" * 248 + "b.jsonl"
    locks = {lock_path(tmp_path / n).name for n in (a, b)}
    assert len(locks) == 2 and all(len(x) + 10 <= NAME_MAX for x in locks)
    assert lock_path(tmp_path / "r.jsonl").name == ".r.jsonl.lock"  # short names as before
    jobs = [Job(f"square/{x}", square, {"x": x}) for x in (2, 3)]
    rep = run_sweep(jobs, tmp_path / a, workers=1, progress=False)
    assert rep.ran == 2 and len((tmp_path / a).read_text().splitlines()) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == [a]  # no helper left


def test_a_finished_study_s_records_that_cannot_be_written_are_shown_read_only(
    tmp_path, monkeypatch
):
    """Showing a finished study again from records that cannot be written (an archive, a
    read-only mount) was refused ("the file is not writable") though nothing was to be
    written: they are read without a lock and shown; with jobs left, the refusal says how
    many.  (Root writes any file: the check is the one `os.access` answers.)"""
    out = tmp_path / "r.jsonl"
    jobs = [Job(f"square/{x}", square, {"x": x}) for x in (2, 3)]
    run_sweep(jobs, out, workers=1, progress=False)
    before = out.read_bytes()
    real = os.access
    monkeypatch.setattr(
        os,
        "access",
        lambda p, mode, **kw: real(p, mode, **kw) and not (Path(p) == out and mode & os.W_OK),
    )
    rep = run_sweep(jobs, out, workers=1, progress=False)
    assert (rep.ran, rep.skipped) == (0, 2) and rep.records["square/3"]["result"] == {"y": 9}
    assert out.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["r.jsonl"]
    more = [*jobs, Job("square/4", square, {"x": 4})]
    with pytest.raises(InputError, match=r"not writable and 1 of 3 job\(s\) are not in it"):
        run_sweep(more, out, workers=1, progress=False)


def test_a_dask_worker_whose_heartbeats_stop_is_named_once(monkeypatch, caplog):
    """A SIGSTOPped worker of `--scheduler local` kept a sweep waiting 7 min without a
    word: a worker whose heartbeat (the scheduler's last_seen) has not moved for
    SILENT_WORKER_S is named once, by address; one whose heartbeats go on is not."""
    from stabctl import parallel

    class Scheduler:  # its view: worker a beats, worker b has stopped
        beats = 0.0

        def identity(self, n_workers=-1):
            Scheduler.beats += 1.0
            return {
                "n_workers": 2,
                "workers": {
                    "tcp://a:1": {"last_seen": Scheduler.beats},
                    "tcp://b:2": {"last_seen": 5.0},
                },
            }

    class Client:  # asks as distributed's does, with a time-out
        scheduler = Scheduler()

        def sync(self, func, callback_timeout=None, **kw):
            return func(**kw)

    watch = parallel._DaskWorkers(Client())
    caplog.set_level("WARNING", logger=parallel._log.name)
    for now in (0.0, 10.0, 20.0, 29.0):
        watch.name_silent(now)
    assert "sent no heartbeat" not in caplog.text  # b silent for 29 s only
    for now in (30.0, 40.0, 50.0):
        watch.name_silent(now)
    said = [r.getMessage() for r in caplog.records if "heartbeat" in r.getMessage()]
    assert len(said) == 1 and said[0].startswith(
        "Dask worker tcp://b:2 has sent no heartbeat for 30 s"
    )


def test_a_scheduler_that_closes_its_connection_gives_the_jobs_up_in_stabctl_s_words():
    """Round 32: a scheduler killed mid-sweep sometimes ended it with Dask's own words
    ("error: in <TCP (closed) ConnectionPool.identity ...>: ConnectionResetError"), the
    address and the jobs left unnamed: the question to the scheduler met the connection
    closed.  It now gives the jobs up at once (`_NoWorker`, the sweep's SweepIncomplete
    naming the address), as a silent scheduler after SCHEDULER_GIVE_UP_S."""
    pytest.importorskip("distributed")
    from distributed.comm.core import CommClosedError

    from stabctl import parallel

    class Client:
        class scheduler:
            address = "tcp://127.0.0.1:1"
            identity = None

        def sync(self, func, callback_timeout=None, **kw):
            raise CommClosedError(
                "in <TCP (closed) ConnectionPool.identity local=tcp://127.0.0.1:2 remote="
                "tcp://127.0.0.1:1>: ConnectionResetError: [Errno 104] Connection reset by peer"
            )

    with pytest.raises(parallel._NoWorker) as err:
        parallel._DaskWorkers(Client()).ask(n_workers=0)
    assert err.value.why.startswith(
        "closed its connection (its scheduler stopped or was killed: CommClosedError: in <TCP"
    )


def _kundur_file(path: Path, h_times: float = 1.0) -> None:
    """Kundur's case written to `path`, every machine's H times `h_times`."""
    import stabctl

    d = json.loads((Path(stabctl.__file__).parent / "case/data/kundur.json").read_text())
    m = d["tables"]["machines"]
    h = m["columns"].index("H")
    for row in m["rows"]:
        row[h] *= h_times
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(d))


@pytest.mark.parametrize("workers", [1, 2])
def test_a_case_file_changed_under_a_sweep_stops_it_recording_nothing(
    tmp_path, monkeypatch, workers
):
    """Each job carries the digest of the case its client read; a worker that reads
    another content (the file edited mid-sweep, in this process too; a Dask worker's own
    file of that name) runs nothing and the sweep stops, the job unrecorded (a rerun then
    runs it)."""
    from stabctl.errors import UnsharedCaseError

    monkeypatch.chdir(tmp_path)
    _kundur_file(tmp_path / "c.json")
    faults = [LineFault(3, 101, 1.0), LineFault(13, 120, 1.0)]
    jobs = cct_jobs("c.json", faults, search=SearchOptions(tol=0.005))
    _kundur_file(tmp_path / "c.json", h_times=3.0)
    out = tmp_path / "o.jsonl"
    said = r"case 'c.json' on the worker .* is not the client's"
    with pytest.raises(UnsharedCaseError, match=said):
        run_sweep(jobs, out, workers=workers, progress=False)
    assert not out.exists() or not read_records(out)


@pytest.mark.dask
def test_a_dask_worker_reading_its_own_case_file_runs_nothing(tmp_path, monkeypatch):
    """The finding (probe round 31): `sweep-cct c.json --scheduler tcp://...` with a worker
    started in another folder ran the worker's own c.json (H x3: CCT 0.33 s for Kundur's
    0.150 s), exit 0; without a c.json there, its jobs were recorded failed and a rerun
    skipped them.  Now the sweep stops naming the worker's folder, nothing recorded."""
    pytest.importorskip("distributed")
    from stabctl.errors import UnsharedCaseError

    monkeypatch.chdir(tmp_path)
    _kundur_file(tmp_path / "c.json")
    _kundur_file(tmp_path / "w" / "c.json", h_times=3.0)
    (tmp_path / "bare").mkdir()
    jobs = cct_jobs("c.json", [LineFault(3, 101, 1.0)], search=SearchOptions(tol=0.005))
    out = tmp_path / "o.jsonl"
    for folder, said in (("w", "is not the client's"), ("bare", "cannot be read on the worker")):
        both = rf"(?=.*{said})(?=.*working directory [^)]*/{folder}\))"
        refused = pytest.raises(UnsharedCaseError, match=both)
        with separate_cluster(1, cwd=tmp_path / folder) as (address, _, _), refused:
            run_sweep(jobs, out, scheduler=address, progress=False)
        assert not out.exists() or not read_records(out)


@pytest.mark.dask
@pytest.mark.parametrize("continued", [True, False])
def test_a_stopped_scheduler_is_said_then_waited_for_or_given_up(
    tmp_path, monkeypatch, caplog, continued
):
    """A Dask scheduler stopped (SIGSTOP) mid-sweep kept the sweep waiting without a word
    (probe round 31: 300 s, nothing said): the client's own question to it waits for
    ever.  Now each question has a time-out and the silence is said once; continued, every
    job is recorded, none twice; never continued, the scheduler is given up after
    SCHEDULER_GIVE_UP_S, the jobs not run unrecorded (SweepIncomplete), the finished kept."""
    pytest.importorskip("distributed")
    import threading

    from stabctl import parallel
    from stabctl.parallel import SweepIncomplete

    out = tmp_path / "d.jsonl"
    jobs = jobs_of(sleepy, *[0.5 + 0.01 * k for k in range(4)])
    with separate_cluster(1) as (address, sched, _):

        def stop_after_one(done, total):
            if done == 1:
                # the short waits from the stop on only: set before the sweep, a loaded
                # machine's slow first answers gave the scheduler up before any job ran
                monkeypatch.setattr(parallel, "SCHEDULER_ANSWER_S", 0.5)
                monkeypatch.setattr(parallel, "SILENT_SCHEDULER_S", 2.0)
                monkeypatch.setattr(parallel, "SCHEDULER_GIVE_UP_S", 30.0 if continued else 4.0)
                os.kill(sched.pid, signal.SIGSTOP)
                if continued:
                    threading.Timer(6.0, os.kill, (sched.pid, signal.SIGCONT)).start()

        given_up = rf"of 4 jobs not run: the Dask cluster at {address} has not answered for"
        try:
            with (
                caplog.at_level("WARNING", "stabctl.parallel"),
                nullcontext() if continued else pytest.raises(SweepIncomplete, match=given_up),
            ):
                report = run_sweep(jobs, out, scheduler=address, progress=stop_after_one)
        finally:
            os.kill(sched.pid, signal.SIGCONT)
    # each silence is said once, and its end; a loaded machine may make a slow answer after
    # SIGCONT a second silence, said again only after the scheduler answered in between
    said = [
        "silent" if "has not answered" in m else "again"
        for m in (r.getMessage() for r in caplog.records)
        if "has not answered" in m or "answers again" in m
    ]
    assert said[0] == "silent" and all(a != b for a, b in itertools.pairwise(said))
    assert said[-1] == ("again" if continued else "silent")
    first = next(r.getMessage() for r in caplog.records if "has not answered" in r.getMessage())
    assert first.startswith(f"the Dask scheduler at {address} has not")
    kept = lines(out)
    assert all(r["status"] == "ok" for r in kept)
    if continued:
        assert (report.ran, report.failed) == (4, 0) and len(kept) == 4
    else:
        assert 1 <= len(kept) < 4


def test_a_relative_case_name_is_read_where_and_as_it_is_now(tmp_path, monkeypatch):
    """cached_simulator kept one Simulator per case name: 'c.json' asked in another folder
    (a notebook's chdir), or after the file was edited, gave the first one read."""
    import numpy as np

    _kundur_file(tmp_path / "a" / "c.json")
    _kundur_file(tmp_path / "b" / "c.json", h_times=3.0)
    monkeypatch.chdir(tmp_path / "a")
    h = cached_simulator("c.json").case.machines.H
    monkeypatch.chdir(tmp_path / "b")
    np.testing.assert_allclose(cached_simulator("c.json").case.machines.H, 3 * h)
    _kundur_file(tmp_path / "b" / "c.json", h_times=2.0)
    np.testing.assert_allclose(cached_simulator("c.json").case.machines.H, 2 * h)


def test_a_worker_shows_a_warning_in_one_line_as_the_command_line_does(capfd):
    """A warning given in a pool's worker (the estimators' model warns of a governor it
    leaves out, `estimate cct`) was shown as Python shows it: the file, line and source
    line in the middle of the progress bar.  It is one ``warning:`` line, as the command
    line's own."""
    import functools
    import warnings

    pool = process_pool(1)
    try:
        say = functools.partial(warnings.warn, "the model holds\n   two lines", UserWarning)
        pool.submit(say).result(timeout=120)
    finally:
        pool.shutdown()
    err = capfd.readouterr().err
    assert "warning: the model holds two lines\n" in err
    assert "UserWarning" not in err and ".py:" not in err


def _three_cct_jobs():
    faults = [LineFault(3, 101), LineFault(13, 101), LineFault(3, 4)]
    return cct_jobs("kundur", faults, search=SearchOptions(error_check=False, t_max=0.5))


def test_a_records_file_deleted_mid_sweep_is_made_again(tmp_path):
    """The records file deleted after the first record (round 34): every later record
    went to the deleted file, the sweep exited 0 and a rerun did all the work again.  It
    is made again from the records the sweep holds open, with a warning, and a rerun runs
    nothing."""
    out = tmp_path / "r.jsonl"
    jobs = _three_cct_jobs()

    def delete_after_the_first(done, total):
        if done == 1:
            out.unlink()

    with pytest.warns(UserWarning, match=r"r.jsonl: deleted while the sweep ran: made again"):
        rep = run_sweep(jobs, out, workers=1, progress=delete_after_the_first)
    assert rep.ran == 3
    assert sorted(r["key"] for r in read_records(out).values()) == sorted(j.key for j in jobs)
    assert run_sweep(jobs, out, workers=1).ran == 0
    assert not list(tmp_path.glob("*.kept"))


def test_a_records_file_whose_directory_is_removed_mid_sweep_is_made_again(tmp_path):
    """The records file's directory removed after the first record (round 37): the sweep
    ended "error: .../r.jsonl.XXXX.kept: No such file or directory", naming a file the
    user never made.  Directory and file are made again from the records held open."""
    import shutil

    out = tmp_path / "D" / "r.jsonl"
    out.parent.mkdir()
    jobs = _three_cct_jobs()

    def remove_after_the_first(done, total):
        if done == 1:
            shutil.rmtree(out.parent)

    with pytest.warns(UserWarning, match=r"deleted while the sweep ran \(its directory too"):
        rep = run_sweep(jobs, out, workers=1, progress=remove_after_the_first)
    assert rep.ran == 3
    assert sorted(r["key"] for r in read_records(out).values()) == sorted(j.key for j in jobs)


def test_a_records_file_replaced_mid_sweep_stops_it_with_its_records_kept(tmp_path):
    """The records file replaced by another (an empty file moved over it) after the first
    record: the sweep stops, naming where its records are kept (the two it had finished),
    and the file now at the path is left as it is."""
    from stabctl.parallel import SweepIncomplete

    out, other = tmp_path / "r.jsonl", tmp_path / "other.jsonl"
    jobs = _three_cct_jobs()

    def replace_after_the_first(done, total):
        if done == 1:
            other.write_text("")
            os.replace(other, out)

    with pytest.raises(SweepIncomplete, match=r"r.jsonl was replaced by another file") as err:
        run_sweep(jobs, out, workers=1, progress=replace_after_the_first)
    (kept,) = tmp_path.glob("r.jsonl.*.kept")
    assert str(kept) in str(err.value) and out.read_text() == ""
    assert len(read_records(kept)) == 2  # the first, and the second that found it replaced


def test_a_controlled_sweep_s_record_relabelled_to_another_controller_is_set_aside(tmp_path):
    """Round 35: a record of a sweep with another controller (or WECC batteries) whose key
    and inputs were relabelled was taken as the other run's answer on resume ("1 already
    in"): the result did not carry what it answers, as `cct_job`'s carries its rating.  It
    carries the controller and the devices' model now, and such a record is set aside."""
    from stabctl.storage.control import BangBangCOI
    from stabctl.studies.sweeps import controlled_cct_jobs

    out = tmp_path / "r.jsonl"
    search = SearchOptions(error_check=False, t_max=0.5)
    fault = [LineFault(3, 101)]
    (wide,) = controlled_cct_jobs(
        "kundur", fault, [5.0], BangBangCOI(deadband_hz=0.05), search=search
    )
    (narrow,) = controlled_cct_jobs(
        "kundur", fault, [5.0], BangBangCOI(deadband_hz=0.2), search=search
    )
    run_sweep([wide], out, workers=1)
    rec = json.loads(out.read_text())
    assert rec["result"]["controller"] == wide.inputs["controller"]
    rec.update(key=narrow.key, inputs=narrow.inputs)  # the 0.05 Hz answer relabelled 0.2 Hz
    out.write_text(json.dumps(rec) + "\n")
    with pytest.warns(UserWarning, match=r"result.controller .* is not the record's inputs"):
        again = run_sweep([narrow], out, workers=1)
    assert again.ran == 1


def test_signals_held_delivers_an_interrupt_after_the_block(tmp_path):
    """`signals_held` (the final moves of `stabctl paper` and `atomic_writes`): a Ctrl-C
    inside the block is delivered after it, so the block's renames happen all or none."""
    from stabctl.parallel import signals_held

    done = []
    with pytest.raises(KeyboardInterrupt), signals_held():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)
        done.append("renamed")  # reached: the interrupt waited
    assert done == ["renamed"]


def test_a_bar_in_a_log_file_is_not_redrawn_at_every_job(tmp_path, capsys):
    """Round 35: on a stderr that is no terminal (a log file) each job drew its bar twice
    (the update, then the failed= count), 49 frames on one line for 24 faults, some
    10 000 for an N-1 of ACTIVSg2000.  It is drawn at its start and end (and every
    `stabctl.progress.LOG_INTERVAL_S`), with the count."""
    jobs = [Job(f"sq{x}", square, {"x": x}) for x in range(40)]
    run_sweep(jobs, tmp_path / "r.jsonl", workers=1, progress=True)
    err = capsys.readouterr().err
    assert err.count("\r") <= 3 and "40/40" in err and "failed=0" in err


def test_a_sweep_s_bar_can_name_its_work_instead_of_its_records_file(tmp_path, capsys):
    """Round 35: `estimate cct`'s bar read "cct.jsonl: 77%", the name of a temporary file
    the user never sees; a sweep's bar takes the name its caller gives (`label`)."""
    jobs = [Job(f"sq{x}", square, {"x": x}) for x in range(3)]
    run_sweep(jobs, tmp_path / "cct.jsonl", workers=1, progress=True, label="estimate cct")
    err = capsys.readouterr().err
    assert "estimate cct: 100%" in err and "cct.jsonl" not in err


def _remove_marks(inputs):
    """A job that removes its sweep's directory of running marks (`_marked`), as another
    program's clean-up of the temporary directory did during a sweep."""
    import glob
    import shutil

    for d in glob.glob(os.path.join(os.environ["TMPDIR"], "stabctl-running-*")):
        shutil.rmtree(d, ignore_errors=True)
    return {"y": inputs["x"] ** 2}


def test_a_sweep_whose_marks_directory_is_removed_runs_on(tmp_path, monkeypatch):
    """Every job after a clean-up of the temporary directory removed the sweep's marks
    directory was recorded failed ("FileNotFoundError ... stabctl-running-..."), and the
    sweep ended "error: <dir>: No such file or directory": the marks are a help only."""
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    monkeypatch.setattr(tempfile, "tempdir", None)
    jobs = [Job(f"marks/{x}", _remove_marks, {"x": x}) for x in range(4)]
    rep = run_sweep(jobs, tmp_path / "r.jsonl", workers=2, progress=False)
    recs = [json.loads(x) for x in (tmp_path / "r.jsonl").read_text().splitlines()]
    assert rep.ran == 4 and sorted(r["result"]["y"] for r in recs) == [0, 1, 4, 9]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.jsonl"]


def _blocked_signals():
    """The signals a worker process has blocked (its mask, as its job runs)."""
    return sorted(int(s) for s in signal.pthread_sigmask(signal.SIG_BLOCK, []))


def test_workers_start_with_the_group_signals_blocked_and_the_parent_s_mask_is_kept():
    """A spawned worker ignored SIGINT only once its initializer ran, and a Ctrl-C to the
    process group while its interpreter started printed "Fatal Python error:
    init_import_site" and a traceback (round 58 AZ21).  Workers are now started with
    the group's signals blocked (inherited through fork and exec), which stay blocked
    and ignored in the worker; this process's own mask is as it was once they started."""
    before = signal.pthread_sigmask(signal.SIG_BLOCK, [])
    pool = process_pool(1)
    try:
        blocked = pool.submit(_blocked_signals).result(timeout=120)
    finally:
        pool.shutdown()
    assert {int(signal.SIGINT), int(signal.SIGTERM), int(signal.SIGHUP)} <= set(blocked)
    assert signal.pthread_sigmask(signal.SIG_BLOCK, []) == before
