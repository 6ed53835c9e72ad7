"""Progress, one way everywhere (stabctl.progress): the heartbeat repeats its status when
nothing was said, the bar is silent when asked, and the command line shows the library's
log lines on stderr, once however often it runs."""

from __future__ import annotations

import logging
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
