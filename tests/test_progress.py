"""Progress, one way everywhere (stabctl.progress): the heartbeat repeats its status when
nothing was said, the bar is silent when asked, and the command line shows the library's
log lines on stderr, once however often it runs."""

from __future__ import annotations

import logging
import re
import time

from stabctl import progress
from stabctl.progress import Heartbeat, bar


def test_heartbeat_repeats_its_status_only_after_a_silence():
    said = []
    with Heartbeat(said.append, line="still {}".format, every=0.2) as beat:
        beat("start")
        time.sleep(0.8)  # no status yet: nothing repeated
        beat.note("busy")
        deadline = time.monotonic() + 5
        while "still busy" not in said and time.monotonic() < deadline:
            time.sleep(0.05)
    assert said[0] == "start" and "still busy" in said
    n = len(said)
    time.sleep(0.8)  # left: the thread has stopped
    assert len(said) == n


def test_heartbeat_without_a_listener_says_nothing_and_starts_no_thread():
    with Heartbeat(None, every=0.01) as beat:
        beat("nobody hears this")
        beat.note("busy")
        assert not beat._thread.is_alive()


def test_bar_is_silent_when_asked(capsys):
    with bar(3, "jobs", show=False) as b:
        for _ in range(3):
            b.update()
    assert capsys.readouterr().err == ""
    with bar(2, "jobs") as b:
        b.update(2)
    assert "jobs" in capsys.readouterr().err


def test_the_command_line_shows_library_log_lines_on_stderr_once(capsys):
    from stabctl.cli import _ECHO, _log_to_stderr

    root = logging.getLogger("stabctl")
    before = (root.level, list(root.handlers))
    try:
        _log_to_stderr()
        _log_to_stderr()
        assert root.handlers.count(_ECHO) == 1
        logging.getLogger("stabctl.placement.plan").info("round 1: 12.0 MW")
        assert capsys.readouterr().err == "round 1: 12.0 MW\n"
    finally:
        root.setLevel(before[0])
        root.handlers[:] = before[1]


def test_a_bar_in_a_log_file_moves_while_no_job_ends_and_ends_once(capsys, monkeypatch):
    """Round 57 AV: `screen --workers 1` into a log file kept "0%| 0/171" as its only
    line for 80 s (a bar drawn only as jobs end), a sweep's bar said "<00:04" left of
    its last three jobs for two minutes and drew its 100 % twice with two rates.  On a
    stderr that is no terminal the bar is drawn again whenever LOG_INTERVAL_S passed
    without a frame, with a `BatchClock`'s time left, and its full frame once, at its
    close."""
    monkeypatch.setattr(progress, "LOG_INTERVAL_S", 0.5)
    with progress.bar(3, "log") as shown:
        time.sleep(2.3)  # no job ends: drawn again, its elapsed time moving
        shown.update()
        shown.update(2)
    frames = [f for f in capsys.readouterr().err.replace("\n", "\r").split("\r") if f.strip()]
    waiting = [f for f in frames if "0/3" in f]
    assert len(waiting) >= 2 and len({f.split("[")[1] for f in waiting}) >= 2
    assert "none ended in 2 s" in waiting[-1]  # the time left is a BatchClock's
    assert sum("3/3" in f for f in frames) == 1 and "100%" in frames[-1]


def test_a_log_line_said_during_a_bar_stands_above_it_not_on_its_line(capsys):
    """A library log line said while a progress bar is shown (the finding: the warning
    that a Dask cluster has no worker was appended to the bar's "0/2" line) clears the bar
    first, so that the line is one of its own, and the bar is drawn again below it."""
    from stabctl.cli import _log_to_stderr

    root = logging.getLogger("stabctl")
    before = (root.level, list(root.handlers))
    try:
        _log_to_stderr()
        with bar(2, "jobs"):
            capsys.readouterr()
            logging.getLogger("stabctl.parallel").warning("no worker")
            err = capsys.readouterr().err
    finally:
        root.setLevel(before[0])
        root.handlers[:] = before[1]
    said, redrawn = err.split("no worker\n")
    assert said.endswith("\r") and "jobs" not in said  # the bar's line cleared first
    assert "jobs" in redrawn


def _simulated(job: dict) -> dict:
    """A stand-in job reporting its simulations (`PlanContext.counting` adds them)."""
    return {"n_simulations": job["n"]}


def test_worker_pool_tells_each_finished_job_in_process_and_in_processes():
    import json

    from stabctl.parallel import worker_pool

    jobs = [{"n": k} for k in range(5)]
    for workers in (1, 2):
        seen: list = []
        with worker_pool(workers) as run:
            out = run(json.dumps, jobs, done=lambda *a, seen=seen: seen.append(a))
            assert run(json.dumps, jobs) == out  # without done, as before
        assert out == [json.dumps(j) for j in jobs]  # job order, whatever the finishing order
        assert [s[:2] for s in seen] == [(k, 5) for k in range(1, 6)]
        # each finished job's index and result (kept at once: `stabctl.placement.memo`)
        assert sorted((i, r) for *_, i, r in seen) == list(enumerate(out))


class _Beat:
    """A heartbeat that keeps its latest status (`Heartbeat.note`)."""

    status = None

    def note(self, status):
        self.status = status


def _told(beat, lines):
    """A map that runs its jobs here, telling ``done`` and keeping the heartbeat's line
    after each job (the status worked out as the heartbeat's repeat does)."""

    def run(func, jobs, done=None):
        out = []
        for k, job in enumerate(jobs, 1):
            out.append(func(job))
            done(k, len(jobs), k - 1, out[-1])
            lines.append(beat.status())
        return out

    return run


def test_a_plans_batch_says_its_fraction_done_and_time_left():
    """Placement's stretches of simulations (`PlanContext.counting`): the heartbeat's
    status names each batch's jobs done, their share and the time left at the pace so far,
    worked out again at each repeat; the simulations the jobs report are counted."""
    from stabctl.placement.context import PlanContext

    pl = PlanContext("kundur", (), None, None, None, None, 1e-3, 0.5, None, n_runs=7)
    beat, lines = _Beat(), []
    pl.counting(_told(beat, lines), beat)(_simulated, [{"n": 3}, {"n": 4}, {"n": 5}, {"n": 6}])
    ran = r"; the batch handed in \d\d:\d\d into the plan, 7 runs simulated before it$"
    assert [re.split("[,;]", ln)[0] for ln in lines] == [
        f"_simulated: {k} of 4 job(s) done ({25 * k}%)" for k in range(1, 5)
    ]
    assert all(re.search(ran, ln) for ln in lines)
    assert "the time left known at the next job's end" in lines[0]
    assert pl.n_runs == 7 + 18
    # a caller's own map without `done` still runs, its status the batch's start
    beat = _Beat()
    pl.counting(lambda func, jobs: [func(j) for j in jobs], beat)(_simulated, [{"n": 1}])
    assert beat.status().startswith("_simulated: 0 of 1 job(s) done (0%), none ended in ")
    assert pl.n_runs == 26


def test_a_batch_clock_moves_between_finishes():
    """`BatchClock` (round 57 AV: a placement log repeated "40 of 42 job(s) done (95%),
    about 2 s left" for a minute, said "1 of 111 done, about 11317 s left" of a batch
    that had waited 96 s behind another plan's in the shared pool and ended 105 s later,
    and "334 of 335 (100%)"): the pace counts from the first finish, the time left goes
    down with the clock, once spent the line says how long the jobs left have run, and
    the share is rounded down."""
    from stabctl.progress import BatchClock

    now = [100.0]
    clock = BatchClock(111, clock=lambda: now[0])
    now[0] = 196.0
    assert clock.line() == "0 of 111 job(s) done (0%), none ended in 96 s"
    clock.done(1)
    assert clock.line().endswith("the time left known at the next job's end")
    now[0] = 197.0
    clock.done(2)
    assert clock.line() == "2 of 111 job(s) done (1%), about 109 s left"  # 1 s a job
    now[0] = 207.0
    assert clock.line() == "2 of 111 job(s) done (1%), about 99 s left"
    now[0] = 400.0
    assert clock.line() == (
        "2 of 111 job(s) done (1%), the 109 left running 203 s since the last ended "
        "(the pace so far gave them 109 s)"
    )
    last = BatchClock(335, clock=lambda: now[0])
    last.done(334)
    assert last.line().startswith("334 of 335 job(s) done (99%), ")
    last.done(335)
    assert last.line() == "335 of 335 job(s) done (100%)"
    # the kept jobs of a plan run again, told at once (`stabctl.placement.memo`): the
    # pace is that of the jobs run after them
    kept = BatchClock(42, clock=lambda: now[0])
    kept.done(41)
    now[0] += 30.0
    assert kept.line().startswith("41 of 42 job(s) done (97%), the time left known at")


def test_the_papers_plans_say_their_batches_fraction_done():
    """`stabctl paper`'s placement counts its evaluations on the way to the plan
    (`stabctl.studies.placement._Evaluations`): its map hands ``done`` on, so the plan's
    batches say their fraction done and time left there too (issue 54: "placement's
    stretches show no fraction or time left"; the paper's log repeated "335 evaluate
    job(s) running" for minutes)."""
    from stabctl.placement.context import PlanContext
    from stabctl.studies.placement import _Evaluations

    pl = PlanContext("kundur", (), None, None, None, None, 1e-3, 0.5, None)
    beat, evaluations, lines = _Beat(), _Evaluations("kundur"), []
    pl.counting(evaluations.counting(_told(beat, lines)), beat)(_simulated, [{"n": 1}, {"n": 2}])
    assert [re.split("[,;]", n)[0] for n in lines] == [
        "_simulated: 1 of 2 job(s) done (50%)",
        "_simulated: 2 of 2 job(s) done (100%)",
    ]
    assert evaluations.n == 2 and pl.n_runs == 3
    assert evaluations.line("plan") == "kundur: plan, 2 contingency evaluations done ..."


def test_simulate_says_it_writes_the_outputs_of_a_long_run(monkeypatch, tmp_path):
    """Round 57 AV: `simulate wecc240.json --tf 660 --out x.npz` cleared its bar at 96 %
    and wrote for 24 s without a line.  A run long enough to show its bar
    (`RUN_SHOWN_AFTER_S`) says that its outputs are being written; a short one does not."""
    from click.testing import CliRunner

    from stabctl.cli import main

    args = ["simulate", "kundur", "--tf", "0.2", "--out", str(tmp_path / "k.npz")]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0 and "writing" not in res.stderr, res.output
    monkeypatch.setattr(progress, "RUN_SHOWN_AFTER_S", 0.0)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert f"writing {tmp_path / 'k.npz'} ...\n" in res.stderr
