"""What a run killed by SIGKILL leaves (stabctl.locking): removed by the next run that makes
the same kind of temporary file or directory in the same place, never a live run's."""

import os
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import pytest

from stabctl import locking as scratch
from stabctl.parallel import atomic_write, atomic_writes

ROOT = Path(__file__).resolve().parents[1]


def _killed_maker(tmp_path, code: str) -> str:
    """The path a child process made with `code` (it prints it) before it was SIGKILLed."""
    child = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(code)],
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        cwd=tmp_path,
    )
    path = os.path.join(tmp_path, child.stdout.readline().strip())
    child.send_signal(signal.SIGKILL)
    child.communicate()  # reaps it and closes its pipe
    return path


MAKE_FILE = """
    import os, time
    from stabctl.parallel import atomic_write
    def write(f):
        print(os.readlink(f"/proc/self/fd/{f.fileno()}"), flush=True)
        time.sleep(60)
    atomic_write("out.csv", write)
"""

MAKE_DIR = """
    import time
    from stabctl import locking as scratch
    held = scratch.temp_dir("stabctl-running-", ".")
    print(held.path, flush=True)
    time.sleep(60)
"""


def test_an_output_s_temporary_file_left_by_a_killed_write_goes_with_the_next_write(tmp_path):
    left = _killed_maker(tmp_path, MAKE_FILE)
    assert Path(left).name.startswith(".out.csv.") and Path(left).exists()
    atomic_write(tmp_path / "out.csv", lambda f: f.write("t\n"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]


def test_a_killed_run_s_directory_goes_with_the_next_of_its_kind(tmp_path):
    left = _killed_maker(tmp_path, MAKE_DIR)
    (Path(left) / "mark").write_text("x")
    other = tmp_path / "stabctl-estimate-abcdefgh"  # another kind: not removed
    other.mkdir()
    os.utime(other, (0, 0))
    with scratch.temp_dir("stabctl-running-", tmp_path) as held:
        assert not Path(left).exists()
        assert Path(held.path).is_dir()
    assert sorted(p.name for p in tmp_path.iterdir()) == [other.name]


def test_a_live_run_s_temporary_files_stay_however_old(tmp_path):
    fd, held = scratch.temp_file(tmp_path, ".r.jsonl.", ".jsonl")
    os.close(fd)  # the lock outlives the descriptor the caller writes with
    live = scratch.temp_dir("stabctl-running-", tmp_path)
    for p in (held.path, live.path):
        os.utime(p, (0, 0))
    assert scratch.remove_stale(tmp_path, ".r.jsonl.", ".jsonl") == []
    assert scratch.remove_stale(tmp_path, "stabctl-running-", kind="directory") == []
    held.release()
    live.release()
    assert scratch.remove_stale(tmp_path, ".r.jsonl.", ".jsonl") == [held.path]
    assert scratch.remove_stale(tmp_path, "stabctl-running-", kind="directory") == [live.path]


def test_unnamed_yet_young_links_and_other_names_stay(tmp_path):
    killed = tmp_path / ".paper-abcd1234~stabctl"  # a killed run's, however young: unlocked
    killed.mkdir()
    young = tmp_path / ".paper-efgh5678~stabctl.new"  # maybe a live run's, about to be locked
    young.mkdir()
    target = tmp_path / "target"
    target.mkdir()
    link = tmp_path / ".paper-linkxxxx~stabctl"
    link.symlink_to(target)
    work = tmp_path / ".paper-work"  # paper's records: not a temporary directory
    work.mkdir()
    longer = tmp_path / ".paper-abcd12345~stabctl"  # not what mkdtemp makes
    longer.mkdir()
    unmarked = tmp_path / ".paper-abcd5678"  # an earlier stabctl's, which locked nothing
    unmarked.mkdir()
    backup = tmp_path / ".paper-draft_v2~"  # an editor's backup
    backup.mkdir()
    a_file = tmp_path / ".paper-abcd9999~stabctl"  # a file named as a temporary directory
    a_file.write_text("mine")
    for p in (work, longer, unmarked, backup, a_file):
        os.utime(p, (0, 0))
    os.utime(link, (0, 0), follow_symlinks=False)
    assert scratch.remove_stale(tmp_path, ".paper-", kind="directory") == [str(killed)]
    old = time.time() - scratch.STALE_AFTER_S - 1
    os.utime(young, (old, old))
    assert scratch.remove_stale(tmp_path, ".paper-", kind="directory") == [str(young)]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [link.name, target.name, work.name, longer.name, unmarked.name, backup.name, a_file.name]
    )


def test_a_failed_write_leaves_no_temporary_file(tmp_path):
    def fail(f):
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError):
        atomic_write(tmp_path / "out.csv", fail)
    assert list(tmp_path.iterdir()) == []


def test_a_writer_given_atomic_writes_temporary_file_writes_it_in_place(tmp_path):
    """simulate --out's CSV writer writes through atomic_write itself: given the temporary
    file of atomic_writes, it made a second one beside it, which a SIGKILL left behind and
    no later run of the command would remove."""
    seen = []

    def write(tmp):
        def inner(f):
            f.write("t\n")
            seen.extend(sorted(p.name for p in tmp_path.iterdir()))

        atomic_write(tmp, inner)

    atomic_writes([(tmp_path / "out.csv", write)])
    assert len(seen) == 1 and seen[0].startswith(".out.csv.")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.csv"]
    assert (tmp_path / "out.csv").read_text() == "t\n"


STREAM = """
    import sys
    from stabctl.parallel import atomic_write, atomic_writes
    print("before", flush=True)
    atomic_write(sys.argv[1], lambda f: f.write(b"FRAMES\\n"), mode="wb")
    atomic_writes([(sys.argv[1], lambda p: open(p, "w").write("CSV\\n"))])
    print("after", flush=True)
"""


def test_an_output_that_is_stdout_appends_to_where_stdout_goes(tmp_path):
    """`--out x.csv` with x.csv a link to /dev/stdout and stdout appended to a log
    (``>> run.log``): the log was replaced by the output (its earlier lines lost), as the
    link resolved through /proc/self/fd/1 to the log, a regular file renamed over.  The
    output is written through the descriptor, after what the log held."""
    log = tmp_path / "run.log"
    log.write_text("earlier line\n")
    (tmp_path / "x.csv").symlink_to("/dev/stdout")
    for target in (tmp_path / "x.csv", "/dev/stdout", "/proc/self/fd/1"):
        with open(log, "a") as out:
            subprocess.run(
                [sys.executable, "-c", textwrap.dedent(STREAM), str(target)],
                stdout=out,
                check=True,
                env={**os.environ, "PYTHONPATH": str(ROOT)},
            )
    assert log.read_text() == "earlier line\n" + "before\nFRAMES\nCSV\nafter\n" * 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.log", "x.csv"]


def test_an_output_linked_to_stdout_that_is_a_pipe_is_called_a_pipe(tmp_path):
    """`--out x.csv`, x.csv a link to /dev/stdout, stdout a pipe: refused as "a broken
    symbolic link (to /dev/stdout ...)", as /proc/self/fd/1 resolves to 'pipe:[...]'; a
    pipe is no file simulate writes (by design), and it is called what it is."""
    (tmp_path / "x.csv").symlink_to("/dev/stdout")
    res = subprocess.run(
        [sys.executable, "-m", "stabctl", "simulate", "kundur", "--tf", "0.05", "--out", "x.csv"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert res.returncode == 2 and res.stderr == (
        "error: --out x.csv: not a regular file (a device, a pipe or a link to one); give a file\n"
    )


def test_a_gone_directory_is_named_and_a_long_suffix_fits(tmp_path, monkeypatch):
    """TMPDIR removed while a run went on ended "error: .../stabctl-running-...~.new: No
    such file or directory"; a legal 222-byte name with a 19-byte text after its last dot
    failed ("File name too long") for its temporary's name."""
    gone = tmp_path / "gone"
    with pytest.raises(FileNotFoundError, match=r"the directory is gone") as err:
        scratch.temp_dir("stabctl-running-", gone)
    assert err.value.filename == str(gone)
    monkeypatch.setattr(tempfile, "tempdir", str(gone))
    with pytest.raises(FileNotFoundError, match=r"set TMPDIR to one that exists"):
        scratch.temp_dir("stabctl-running-")
    name = "a" * 202 + "." + "b" * 19
    atomic_write(tmp_path / name, lambda f: f.write("x"))
    assert (tmp_path / name).read_text() == "x"
