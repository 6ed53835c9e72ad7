"""Progress, one way everywhere (stabctl.progress): the heartbeat repeats its status when
nothing was said, the bar is silent when asked, and the command line shows the library's
log lines on stderr, once however often it runs."""

from __future__ import annotations

import logging
import re
import time

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


def test_a_plans_batch_says_its_fraction_done_and_time_left():
    """Placement's stretches of simulations (`PlanContext.counting`): the heartbeat's
    status names each batch's jobs done, their share and the time left at the pace so far;
    the simulations the jobs report are counted."""
    from stabctl.parallel import worker_pool
    from stabctl.placement.context import PlanContext

    class Beat:
        def __init__(self):
            self.notes = []

        def note(self, status):
            self.notes.append(status)

    pl = PlanContext("kundur", (), None, None, None, None, 1e-3, 0.5, None, n_runs=7)
    beat = Beat()
    with worker_pool(1) as run:
        counted = pl.counting(run, beat)
        counted(_simulated, [{"n": 3}, {"n": 4}, {"n": 5}, {"n": 6}])
    ran = r", started \d\d:\d\d into the plan"  # when the batch started (no whole named)
    assert re.fullmatch(
        "4 _simulated job\\(s\\) running, 7 runs simulated before them" + ran, beat.notes[0]
    )
    for k, note in enumerate(beat.notes[1:], 1):
        assert note.startswith(f"_simulated: {k} of 4 job(s) done ({k / 4:.0%}), about ")
        assert re.search(" s left in this batch, 7 runs simulated before them" + ran + "$", note)
    assert beat.notes[-1].startswith("_simulated: 4 of 4 job(s) done (100%), about 0 s left")
    assert pl.n_runs == 7 + 18
    # a caller's own map without `done` still runs, with the batch's first status only
    beat = Beat()
    pl.counting(lambda func, jobs: [func(j) for j in jobs], beat)(_simulated, [{"n": 1}])
    assert len(beat.notes) == 1 and pl.n_runs == 26


def test_the_papers_plans_say_their_batches_fraction_done():
    """`stabctl paper`'s placement counts its evaluations on the way to the plan
    (`stabctl.studies.placement._Evaluations`): its map hands ``done`` on, so the plan's
    batches say their fraction done and time left there too (issue 54: "placement's
    stretches show no fraction or time left"; the paper's log repeated "335 evaluate
    job(s) running" for minutes)."""
    from stabctl.parallel import worker_pool
    from stabctl.placement.context import PlanContext
    from stabctl.studies.placement import _Evaluations

    class Beat:
        def __init__(self):
            self.notes = []

        def note(self, status):
            self.notes.append(status)

    pl = PlanContext("kundur", (), None, None, None, None, 1e-3, 0.5, None)
    beat, evaluations = Beat(), _Evaluations("kundur")
    with worker_pool(1) as run:
        pl.counting(evaluations.counting(run), beat)(_simulated, [{"n": 1}, {"n": 2}])
    assert [n.split(",")[0] for n in beat.notes[1:]] == [
        "_simulated: 1 of 2 job(s) done (50%)",
        "_simulated: 2 of 2 job(s) done (100%)",
    ]
    assert evaluations.n == 2 and pl.n_runs == 3
    assert evaluations.line("plan") == "kundur: plan, 2 contingency evaluations done ..."
