"""Interruptions: SIGKILL of a sweep's main process leaves no worker running;
SIGINT (Ctrl-C) ends every long command the same way: exit 130 and one line saying what was
kept and the command that resumes; SIGTERM the same with exit 143, also while a command
waits on a PMU stream that never ends; SIGHUP to the whole process group (a closed
terminal) the same with exit 129."""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner
from pmu_streams import endless_server, kundur_stream, on_the_wire

from stabctl.cli import main

STABCTL = [sys.executable, "-m", "stabctl.cli"]


def _children(pid: int) -> set[int]:
    """Every live descendant of pid (from /proc)."""
    kids: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            kids.setdefault(ppid, []).append(int(entry.name))
    out, todo = set(), [pid]
    while todo:
        for k in kids.get(todo.pop(), []):
            out.add(k)
            todo.append(k)
    return out


def _signal_group_after_first_record(tmp_path, args, out, sig, env=None):
    """Start ``stabctl args`` in tmp_path in a session of its own; once its records file
    `out` holds a line, send `sig` to its process group (as a terminal does) and wait for
    the end: (the process, its stderr, the descendants it had then)."""
    proc = subprocess.Popen(
        STABCTL + args,
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        preexec_fn=_default_sigint,
        env=env,
    )
    try:
        assert _wait_for(lambda: out.exists() and out.read_text().count("\n") >= 1, 300)
        kids = _children(proc.pid)
        os.killpg(proc.pid, sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc, err, kids


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _wait_for(cond, timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.1)
    return cond()


def _default_sigint():
    """In the child before exec: SIGINT and SIGHUP back to their defaults.  A process
    started with them ignored (pytest as a background job of a non-interactive shell, by
    some CI runners: SIGINT; under nohup: SIGHUP) passes SIG_IGN on to its children, and
    Python then installs no KeyboardInterrupt handler, stabctl no hangup handler: the
    signal under test would be ignored."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)


@pytest.fixture(autouse=True)
def _signals_at_their_defaults():
    """The in-process tests (CliRunner) under the dispositions a terminal gives: SIGINT
    raising KeyboardInterrupt, SIGHUP its default, whatever pytest was started with (a
    background job ignores SIGINT, nohup SIGHUP); the pytest process's own restored after."""
    old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGHUP)}
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)


def _start(args, tmp_path):
    return subprocess.Popen(
        STABCTL + [str(a) for a in args],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_default_sigint,
    )


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and prctl: Linux")
def test_sigkill_of_a_sweep_leaves_no_worker_running(tmp_path):
    proc = _start(
        [
            "sweep-cct",
            "miniwecc",
            "--faults",
            "DEFAULT",
            "--esd-pct",
            "none,5,10",
            "--workers",
            "2",
            "--out",
            "k.jsonl",
        ],
        tmp_path,
    )
    try:
        # two workers (and the resource tracker) started: after the kernels' compile, up
        # to a few minutes when the cache is cold and the other tests load both cores
        assert _wait_for(lambda: len(_children(proc.pid)) >= 3, 300), _children(proc.pid)
        time.sleep(1.0)  # the workers are inside their jobs
        kids = _children(proc.pid)
        proc.send_signal(signal.SIGKILL)
        proc.wait(10)
        assert _wait_for(lambda: not any(_alive(k) for k in kids), 10), [
            k for k in kids if _alive(k)
        ]
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.communicate()  # reaps it and closes its pipes


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc: Linux")
@pytest.mark.parametrize(
    "sig,status", [(signal.SIGINT, 130), (signal.SIGTERM, 143), (signal.SIGHUP, 129)]
)
def test_sigint_or_sigterm_of_a_screening_ends_with_the_resume_command(tmp_path, sig, status):
    """Ctrl-C (SIGINT), SIGTERM (kill, a batch system's time limit) or SIGHUP (the ssh
    session closed; it used to kill the command and leave its lock file) to a screening on
    two workers: the resume line, exit status 130, 143 or 129, no traceback, no leaked
    semaphore, no worker left, no lock file, and only whole records in the file."""
    args = ["screen", "kundur", "--tol-ms", "0.05", "--workers", "2", "--out", "s.jsonl"]
    proc = _start(args, tmp_path)
    out = tmp_path / "s.jsonl"
    try:
        assert _wait_for(lambda: out.exists() and out.read_text().count("\n") >= 1, 300)
        kids = _children(proc.pid)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == status, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("interrupted: finished searches are in s.jsonl (")
    assert last.endswith("resume with: stabctl " + " ".join(args)), last
    assert "Traceback" not in err and "Aborted" not in err and "leaked" not in err
    assert _wait_for(lambda: not any(_alive(k) for k in kids), 10)
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.endswith(".lock")) == []
    import json

    assert all(
        json.loads(line)["status"] in ("ok", "failed") for line in out.read_text().splitlines()
    )


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc: Linux")
@pytest.mark.parametrize(
    "scheduler", [[], pytest.param(["--scheduler", "local"], marks=pytest.mark.dask)]
)
def test_a_hangup_of_the_whole_process_group_ends_a_sweep_with_one_line(tmp_path, scheduler):
    """SIGHUP to a sweep's process group (its terminal closed: the parent, its workers and
    multiprocessing's resource tracker all get it), in a local pool or on a local Dask
    cluster: exit status 129 and the resume line alone.  The tracker, which ignores only
    SIGINT and SIGTERM, died of it; the shutdown started another, which printed a
    traceback (KeyError: '/mp-...') for each semaphore it had never registered."""

    if scheduler:
        pytest.importorskip("distributed")
    args = ["sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5,10,20"]
    args += ["--tol-ms", "0.05", "--workers", "2", *scheduler, "--out", "h.jsonl"]
    out = tmp_path / "h.jsonl"
    proc, err, kids = _signal_group_after_first_record(tmp_path, args, out, signal.SIGHUP)
    assert proc.returncode == 129, err
    said = [line for line in err.splitlines() if line.strip() and not line.startswith("h.jsonl")]
    assert len(said) == 1 and said[0].startswith("interrupted: finished jobs are in h.jsonl ("), err
    assert _wait_for(lambda: not any(_alive(k) for k in kids), 10)


@pytest.mark.dask
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc: Linux")
@pytest.mark.parametrize("sig,status", [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_a_signal_to_a_screening_on_a_local_dask_cluster_says_only_what_it_kept(
    tmp_path, sig, status
):
    """SIGTERM or SIGHUP to a screening on `--scheduler local`: its worker processes
    printed two Dask warnings per running job they cancelled as the cluster closed
    ("Async instruction ... ended with CancelledError"), and often a worker whose heartbeat
    met the scheduler closed an error with its traceback ("Failed to communicate with
    scheduler during heartbeat"); only the resume line is said."""
    pytest.importorskip("distributed")
    args = ["screen", "kundur", "--tol-ms", "0.05", "--workers", "2", "--scheduler", "local"]
    args += ["--out", "s.jsonl"]
    proc = _start(args, tmp_path)
    out = tmp_path / "s.jsonl"
    try:
        assert _wait_for(lambda: out.exists() and out.read_text().count("\n") >= 1, 300)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == status, err
    said = [line for line in err.splitlines() if not line.startswith("s.jsonl:")]  # the bar
    assert said[-1].startswith("interrupted: finished searches are in s.jsonl ("), err
    assert "CancelledError" not in err and "distributed" not in err, err


@pytest.mark.dask
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc: Linux")
def test_ctrl_c_at_the_terminal_of_a_screening_on_a_local_dask_cluster_says_one_line(tmp_path):
    """Ctrl-C at a terminal (SIGINT to the whole process group) of a screening on
    `--scheduler local`: each Dask worker process got it too and printed its traceback
    (CancelledError, KeyboardInterrupt) before the interrupted line.  Exit status 130,
    the interrupted line alone, the records valid, the cluster's scratch directory gone
    and no process left."""
    import glob
    import json

    pytest.importorskip("distributed")
    scratch = tmp_path / "tmp"  # the command's temporary directory: its own, as other
    scratch.mkdir()  # tests' clusters come and go in the machine's
    args = ["screen", "kundur", "--lines", "--tol-ms", "0.05", "--workers", "2"]
    args += ["--scheduler", "local", "--out", "s.jsonl"]
    out = tmp_path / "s.jsonl"
    env = {**os.environ, "TMPDIR": str(scratch)}
    proc, err, kids = _signal_group_after_first_record(tmp_path, args, out, signal.SIGINT, env)
    assert proc.returncode == 130, err
    said = [line for line in err.splitlines() if line.strip() and not line.startswith("s.jsonl")]
    assert len(said) == 1, err
    assert said[0].startswith("interrupted: finished searches are in s.jsonl ("), err
    assert all(json.loads(line) for line in out.read_text().splitlines())
    assert not glob.glob(str(scratch / "stabctl-dask-*"))
    assert _wait_for(lambda: not any(_alive(k) for k in kids), 10)


@pytest.mark.parametrize(
    "command,target,kept",
    [
        (
            ["paper", "--out-dir", "rep", "--only", "analytic"],
            "stabctl.studies.paper.write_paper_report",
            # no sweep record to resume from (round 35: it said records were kept)
            "nothing is kept",
        ),
        (
            ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "10"],
            "stabctl.placement.plan.plan",
            "nothing is kept",
        ),
        (
            ["estimate", "cct", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"],
            "stabctl.estimation.closed_loop.cct_study",
            "nothing is kept",
        ),
        (
            ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", "o.jsonl"],
            "stabctl.parallel.run_sweep",
            "finished jobs are in o.jsonl (0 recorded); they are skipped; resume with:",
        ),
        (
            ["screen", "kundur", "--out", "s.jsonl"],
            "stabctl.stability.screening.screen",
            "finished searches are in s.jsonl (0 recorded); they are skipped; resume with:",
        ),
        # a live loop or stream is not resumed (it said "the work starts again; resume")
        (
            ["pmu", "control", "kundur", "127.0.0.1:4712", "--esd-pct", "5"],
            "stabctl.estimation.c37_loop.serve_controller",
            "the controller stopped (a closed loop is not resumed); run again with: stabctl",
        ),
        (
            ["pmu", "serve", "kundur", "--fault", "3", "--far-bus", "101", "--port", "0"],
            "stabctl.cli.pmu._serve",
            "the server stopped (a live stream is not resumed: its PDCs connect again); run",
        ),
    ],
)
def test_every_long_command_ends_the_same_way_on_ctrl_c(
    tmp_path, monkeypatch, command, target, kept
):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # no other run's kept work
    module, name = target.rsplit(".", 1)

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(
        sys.modules[module] if module in sys.modules else __import__(module, fromlist=[name]),
        name,
        interrupted,
    )
    monkeypatch.setattr(sys, "argv", ["stabctl", *command])
    res = CliRunner().invoke(main, command)
    assert res.exit_code == 130, (res.output, res.exception)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("interrupted: "), res.stderr
    assert kept in lines[0]
    resume = " ".join(command) + (" --resume" if command[0] == "paper" else "")
    again = (
        "run again with: " if command[0] == "pmu" or kept == "nothing is kept" else "resume with: "
    )
    assert lines[0].endswith(again + "stabctl " + resume)


def test_an_interrupted_paper_says_where_its_records_are_kept(tmp_path, monkeypatch):
    """With sweep records in its work directory, an interrupted `paper` says they are kept
    there for --resume (round 35: it said so, naming the output directory, when none
    had been kept)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rep" / ".paper-work").mkdir(parents=True)
    (tmp_path / "rep" / ".paper-work" / "table4_cct.jsonl").write_text('{"key": "k"}\n')

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr("stabctl.studies.paper.write_paper_report", interrupted)
    command = ["paper", "--out-dir", "rep", "--only", "table4"]
    monkeypatch.setattr(sys, "argv", ["stabctl", *command])
    res = CliRunner().invoke(main, command)
    assert res.exit_code == 130
    assert res.stderr.strip() == (
        "interrupted: finished sweep records are kept in rep/.paper-work for --resume; "
        "resume with: stabctl paper --out-dir rep --only table4 --resume"
    )


@pytest.fixture(scope="module")
def kundur_on_the_wire():
    """CFG-2 and data frames (bytes) of Kundur's bus-3 fault stream: 2 s, 60 frames/s."""
    pytest.importorskip("pyc37")
    _, _, cfg, frames = kundur_stream()
    return on_the_wire(cfg, frames)


@pytest.mark.parametrize("sig,status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_sigint_or_sigterm_ends_estimate_track_of_an_endless_stream(
    tmp_path, kundur_on_the_wire, sig, status
):
    """`estimate track --until 100` of a server that sends a frame each 0.1 s and never
    closes, so the command waits on the stream: SIGINT or SIGTERM ends it within 10 s with
    exit status 130 or 143 and one line saying how many data frames had come, that they
    are not tracked (it said only "nothing is kept") and where they are kept: written as
    a partial recording beside --out (round 29: they were lost), which tracks; no
    traceback, nothing on stdout and no e.csv, not even in part (outputs are written
    whole or not at all)."""
    with endless_server(*kundur_on_the_wire) as (port, streaming):
        args = ["estimate", "track", "kundur", "--source", f"tcp://127.0.0.1:{port}"]
        args += ["--until", "100", "--out", "e.csv"]
        proc = _start(args, tmp_path)
        try:
            # 'start' sent: the command is receiving, inside its interrupt handling (up to
            # minutes when the estimators' kernels compile first)
            assert _wait_for(lambda: streaming.is_set() or proc.poll() is not None, 300)
            assert proc.poll() is None, proc.communicate()[1]
            time.sleep(0.5)  # a few frames received
            proc.send_signal(sig)
            try:
                out, err = proc.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                _, err = proc.communicate()
                pytest.fail(f"still running 10 s after {sig.name}: {err[-500:]}")
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
    assert proc.returncode == status, err
    said = re.fullmatch(
        rf"interrupted: nothing is tracked \(e.csv not written\): the (\d+) data frames from "
        rf"tcp://127.0.0.1:{port} had come, short of t = 100 s, and a stream is tracked once "
        rf"received; 127.0.0.1:{port} sent them; the (\d+) data frames received are in "
        r"e.received.c37, a partial recording \(track it: stabctl estimate track kundur "
        r"--source FILE --out ...\); run again with: stabctl " + re.escape(" ".join(args)),
        err.strip().splitlines()[-1],
    )
    assert said and int(said[1]) >= 1 and int(said[2]) >= int(said[1]), err
    assert "Traceback" not in err and out == ""
    assert [p.name for p in tmp_path.iterdir()] == ["e.received.c37"]
    res = subprocess.run(
        [sys.executable, "-m", "stabctl", "estimate", "track", "kundur", "--source"]
        + ["e.received.c37", "--out", "r.csv"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0 and f"tracked {said[2]} frames from e.received.c37" in res.stdout, (
        res.stderr
    )


@pytest.mark.parametrize(
    "target",
    ["stabctl.cli.estimate.stream_controller", "stabctl.estimation.sources.read_frames"],
    ids=["setting-up", "before-the-first-frame"],
)
def test_estimate_track_interrupted_before_any_frame_came_says_none_was_estimated(
    tmp_path, monkeypatch, target
):
    """Interrupted while its estimators were set up (compiled, seconds) or before a frame
    had come, `estimate track` said only "nothing is kept; the work starts again", though
    its help promises the frames estimated: the line says that no frame was estimated
    because none had come, and that --out is not written."""
    monkeypatch.chdir(tmp_path)
    module, name = target.rsplit(".", 1)

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(__import__(module, fromlist=[name]), name, interrupted)
    args = ["estimate", "track", "kundur", "--source", "tcp://127.0.0.1:9", "--frames", "181"]
    args += ["--out", "t.csv"]
    monkeypatch.setattr(sys, "argv", ["stabctl", *args])
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 130, (res.output, res.exception)
    assert res.stderr.strip().splitlines() == [
        "interrupted: no frame was estimated: none had come from tcp://127.0.0.1:9 yet, so "
        "nothing is kept (t.csv not written); run again with: stabctl " + " ".join(args)
    ]
    assert list(tmp_path.iterdir()) == []


def test_an_import_interrupted_after_its_case_was_written_says_so(tmp_path, monkeypatch):
    """`import-psse` writes the case, then prints its summary; interrupted in between
    (ACTIVSg2000's summary takes a while) it said "nothing is kept; the work starts
    again" beside a whole case file.  It says the file had been written whole."""
    from stabctl.cli import io as cli_io

    data = Path(__file__).parents[1] / "data" / "psse"
    monkeypatch.chdir(tmp_path)

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_io, "_imported", interrupted)
    args = ["import-psse", str(data / "five_bus_v33.raw"), str(data / "five_bus.dyr")]
    args += ["-o", "five.json"]
    monkeypatch.setattr(sys, "argv", ["stabctl", *args])
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 130, (res.output, res.exception)
    assert res.stderr.strip().splitlines()[-1] == (
        "interrupted: five.json had been written whole; run again with: stabctl " + " ".join(args)
    )
    assert (tmp_path / "five.json").stat().st_size > 0


def _record_interrupted(tmp_path, cfg2: bytes, data: list, sig) -> tuple:
    """`pmu record --frames 121 -o r.c37` of an endless stream of `data`, sent `sig` once
    a few frames came: (exit status, stdout, stderr, the server's port, the command)."""
    with endless_server(cfg2, data) as (port, streaming):
        args = ["pmu", "record", f"127.0.0.1:{port}", "--frames", "121", "-o", "r.c37"]
        proc = _start(args, tmp_path)
        try:
            assert _wait_for(lambda: streaming.is_set() or proc.poll() is not None, 60)
            assert proc.poll() is None, proc.communicate()[1]
            time.sleep(0.5)  # a few frames received
            proc.send_signal(sig)
            out, err = proc.communicate(timeout=10)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
    return proc.returncode, out, err, port, args


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX")
def test_a_hangup_the_command_was_started_ignoring_is_still_ignored():
    """``nohup stabctl ...`` starts with SIGHUP ignored, so that the command goes on when
    its terminal closes; a command took SIGHUP over regardless and ended on it (exit
    129).  A signal ignored at the start stays ignored while the command runs and after."""
    import click

    from stabctl.cli.options import reports_errors

    @click.command()
    @reports_errors
    def long_work():
        signal.raise_signal(signal.SIGHUP)
        click.echo("went on")

    old = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        res = CliRunner().invoke(long_work, [])
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGHUP, old)
    assert res.exit_code == 0 and "went on" in res.output, (res.output, res.exception)


@pytest.mark.parametrize("goes_on", [True, False], ids=["works-on", "returns"])
@pytest.mark.parametrize("sig,status", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_an_interrupt_dropped_by_a_callback_from_c_still_ends_the_command(sig, status, goes_on):
    """A signal handled while Python code that C called runs (llvmlite's object-cache
    notification, a ctypes callback, as numba compiles) raised its interrupt there, and
    ctypes printed it ("Exception ignored on calling ctypes callback function ...
    Terminated: 15") and dropped it: `stabctl compile` ran on with its compile child.  The
    interrupt is delivered again and ends the command with its one line and status,
    whether the command works on after the callback or returns at once."""
    import ctypes

    import click

    from stabctl.cli.options import reports_errors

    @ctypes.CFUNCTYPE(None)
    def from_c():
        signal.raise_signal(sig)

    @click.command()
    @reports_errors
    def long_work():
        from_c()
        for _ in range(200 if goes_on else 0):  # 10 s at most
            time.sleep(0.05)
        click.echo("went on")

    res = CliRunner().invoke(long_work, [])
    assert res.exit_code == status, (res.output, res.exception)
    assert res.stderr.startswith("interrupted: ") and "Exception ignored" not in res.stderr
    assert ("went on" in res.stdout) is not goes_on


def _run_script(tmp_path, name: str, text: str, *, module: bool = False, **env):
    """Run `text` as the Python script `name`.py in tmp_path (as ``python -m name`` with
    `module`), SIGINT at its default, `env` added to the environment."""
    (tmp_path / f"{name}.py").write_text(text)
    paths = [str(tmp_path), *filter(None, [os.environ.get("PYTHONPATH")])]
    return subprocess.run(
        [sys.executable, *(["-m", name] if module else [str(tmp_path / f"{name}.py")])],
        cwd=tmp_path,
        env=dict(os.environ, PYTHONPATH=os.pathsep.join(paths), **env),
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=_default_sigint,
    )


_RUN_AS_STRING = """
import ctypes, signal, sys

import click

from stabctl.cli.options import reports_errors


@click.command()
@reports_errors
def start_up():
    run = ctypes.pythonapi.PyRun_String
    run.restype = ctypes.py_object
    run.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.py_object, ctypes.py_object]
    names = {"signal": signal}
    run(b"signal.raise_signal(signal.SIGINT)", 257, names, names)  # 257: Py_file_input


start_up()
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a process's signal status")
def test_ctrl_c_inside_python_code_c_runs_as_a_string_ends_with_status_130(tmp_path):
    """Ctrl-C while an extension module imported inside a command started (Cython's
    module start-ups run Python code as a string, ``PyRun_String``), under ``python -m``:
    the command printed its `interrupted:` line and exited 130, and then the interpreter,
    which remembers a bare KeyboardInterrupt that went through such code, killed itself
    with SIGINT (status -2 instead of 130; one start-up in ten under load)."""
    proc = _run_script(tmp_path, "string_start_up", _RUN_AS_STRING, module=True)
    assert proc.returncode == 130, (proc.returncode, proc.stderr)
    assert proc.stderr.startswith("interrupted: ") and "Traceback" not in proc.stderr


_SIGNALS_AFTER_THE_COMMAND = """
import signal

import click

from stabctl.__main__ import install
from stabctl.cli.options import reports_errors

install()


@click.command()
@reports_errors
def done():
    click.echo("written")


done.main([], standalone_mode=False)
for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
    signal.raise_signal(sig)
print("ended", flush=True)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="SIGHUP")
def test_a_signal_after_the_command_ended_leaves_its_status(tmp_path):
    """A signal in the moment between a command's end (its outputs written) and the
    process's went to the entry point's handler, which said "interrupted: nothing is
    kept" and exit 130 (or 143, 129): a finished command reported as not run.  Once the
    command has ended such signals are ignored."""
    proc = _run_script(tmp_path, "after", _SIGNALS_AFTER_THE_COMMAND)
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, "written\nended\n", "")


_HALF_BUILT_AT_EXIT = """
import os

import click

import stabctl.cli
from stabctl.__main__ import main
from stabctl.cli.options import Terminated, reports_errors


class HalfBuilt:  # an object whose construction a signal cut short
    def __del__(self):
        self.closed = self._owned  # AttributeError, as llvmlite's OutputString


@click.command()
@reports_errors
def cut_short():
    stabctl.left = HalfBuilt()  # freed as the interpreter ends
    raise Terminated(int(os.environ["SIGNUM"]))


stabctl.cli.main = cut_short
main()
"""


@pytest.mark.parametrize("sig,status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_objects_a_signal_left_half_built_say_nothing_as_the_process_ends(tmp_path, sig, status):
    """A signal in the middle of a constructor (llvmlite's ``OutputString`` while numba
    loaded its cache) left an object without its attributes, whose ``__del__`` printed
    "Exception ignored in ... Traceback ... AttributeError" under the `interrupted:` line
    as the process ended.  A process ending on a signal drops what finalisers raise."""
    proc = _run_script(tmp_path, "half_built", _HALF_BUILT_AT_EXIT, SIGNUM=str(int(sig)))
    assert proc.returncode == status, proc.stderr
    assert proc.stderr.startswith("interrupted: ") and len(proc.stderr.splitlines()) == 1


_DROPPED_EARLY = """
import signal

import click

from stabctl.__main__ import install
from stabctl.cli.options import reports_errors

install()


class Finaliser:  # Python runs __del__ where it cannot raise: what it raises is dropped
    def __del__(self):
        signal.raise_signal(signal.SIGHUP)


Finaliser()  # freed at once: the signal's EarlyInterrupt dropped
print("went on", flush=True)


@click.command()
@reports_errors
def work():
    click.echo("worked")


work.main([], standalone_mode=False)
"""


def test_an_early_signal_python_could_not_raise_ends_the_command_without_a_traceback(tmp_path):
    """A SIGHUP during the start-up's imports raised the entry point's `EarlyInterrupt`
    inside an import lock's weakref callback, where Python cannot raise: it printed
    "Exception ignored in ... Traceback ... EarlyInterrupt: 1" before the `interrupted:`
    line, or was lost.  It is dropped quietly and remembered: the command ends on it as
    it starts (exit 129, one line)."""
    proc = _run_script(tmp_path, "dropped", _DROPPED_EARLY)
    assert proc.returncode == 129, proc.stderr
    assert proc.stdout == "went on\n"
    assert proc.stderr.startswith("interrupted: ") and len(proc.stderr.splitlines()) == 1


def _catches(pid: int, sig: int) -> bool:
    """Whether process pid has a handler for sig (its SigCgt mask in /proc)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return False
    mask = next(x for x in status.splitlines() if x.startswith("SigCgt:")).split()[1]
    return bool(int(mask, 16) >> (sig - 1) & 1)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc: Linux")
@pytest.mark.parametrize("module", ["stabctl", "stabctl.cli"])
@pytest.mark.parametrize("sig,status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_during_start_up_ends_with_one_interrupted_line(tmp_path, module, sig, status):
    """Ctrl-C in the first second or so (the imports, before the command's own handlers)
    printed a traceback ending in KeyboardInterrupt; SIGTERM killed the process without a
    word.  Both end as later: one `interrupted:` line (the entry point's, or the command's
    when the signal came after its handlers), exit 130 or 143, never a traceback.  The
    signal is sent as soon as the process catches SIGTERM (the entry point's handlers,
    installed before any import of the command: the interpreter's own start-up is not
    ours to handle), then after fixed delays."""
    seen = []
    for delay in (None, 0.2, 0.5, 1.0):
        proc = subprocess.Popen(
            [sys.executable, "-m", module, "simulate", "kundur", "--tf", "3600"],
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=_default_sigint,
        )
        try:
            started = _started(proc.pid)
            assert started or delay is not None
            time.sleep(delay or 0.0)
            proc.send_signal(sig)
            out, err = proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
        assert proc.returncode == status, (delay, proc.returncode, err, out[-300:])
        assert "Traceback" not in err and "Aborted" not in err, err
        said = [x for x in err.splitlines() if x.startswith("interrupted:")]
        assert len(said) == 1, err
        assert said[0].endswith("run again with: stabctl simulate kundur --tf 3600"), said
        seen.append(said[0])
    assert "nothing is kept" in seen[0], seen


def _started(pid: int, timeout: float = 30) -> bool:
    """Wait (polling every 2 ms) until process pid catches SIGTERM; whether it did."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if _catches(pid, signal.SIGTERM):
            return True
        time.sleep(0.002)
    return False


@pytest.mark.parametrize("sig,status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupted_recording_keeps_the_frames_received(
    tmp_path, kundur_on_the_wire, sig, status
):
    """`pmu record --frames 121` of a server that sends a frame each 0.1 s, interrupted
    (Ctrl-C, SIGTERM): it kept nothing of what it had received.  Exit status 130 or 143,
    the frames received written as a partial recording (whole frames, CFG-2 first, read
    back as they were sent), named on the one ``interrupted:`` line with their count and
    last time stamp; a second interrupted recording to the same file leaves it as it
    was and writes its frames beside it (r.partial.c37), and says so."""
    cfg2, data = kundur_on_the_wire
    kept = b""
    for again in (False, True):
        code, out, err, port, args = _record_interrupted(tmp_path, cfg2, data, sig)
        assert code == status and "Traceback" not in err and out == "", err
        [line] = err.strip().splitlines()
        said = re.fullmatch(
            rf"interrupted: 127.0.0.1:{port} after (\d+) data frames, the last stamped "
            r"(\S+) s, before 121 frames; (.*); run again with: stabctl "
            + re.escape(" ".join(args)),
            line,
        )
        assert said, line
        n = int(said[1])
        assert n >= 1 and float(said[2]) == pytest.approx((n - 1) / 60, abs=1e-4)
        if again:
            assert said[3] == (
                f"the {n} received are in r.partial.c37, a partial recording (r.c37 is left "
                "as it was)"
            )
            assert (tmp_path / "r.partial.c37").read_bytes() == cfg2 + b"".join(data[:n])
        else:
            assert said[3] == f"the {n} received are in r.c37, a partial recording"
            kept = cfg2 + b"".join(data[:n])
        assert (tmp_path / "r.c37").read_bytes() == kept
        assert sorted(p.name for p in tmp_path.iterdir()) == ["r.c37", "r.partial.c37"][: 1 + again]
