"""What a run killed by SIGKILL leaves (stabctl.locking): removed by the next run that makes
the same kind of temporary file or directory in the same place, never a live run's."""

import os
import signal
import subprocess
import sys
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
    child.wait()
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
    assert scratch.remove_stale(tmp_path, "stabctl-running-") == []
    held.release()
    live.release()
    assert scratch.remove_stale(tmp_path, ".r.jsonl.", ".jsonl") == [held.path]
    assert scratch.remove_stale(tmp_path, "stabctl-running-") == [live.path]


def test_unnamed_yet_young_links_and_other_names_stay(tmp_path):
    killed = tmp_path / ".paper-abcd1234~"  # a killed run's, however young: unlocked
    killed.mkdir()
    young = tmp_path / ".paper-efgh5678~.new"  # maybe a live run's, about to be locked
    young.mkdir()
    target = tmp_path / "target"
    target.mkdir()
    link = tmp_path / ".paper-linkxxxx~"
    link.symlink_to(target)
    work = tmp_path / ".paper-work"  # paper's records: not a temporary directory
    work.mkdir()
    longer = tmp_path / ".paper-abcd12345~"  # not what mkdtemp makes
    longer.mkdir()
    unmarked = tmp_path / ".paper-abcd5678"  # an earlier stabctl's, which locked nothing
    unmarked.mkdir()
    for p in (work, longer, unmarked):
        os.utime(p, (0, 0))
    os.utime(link, (0, 0), follow_symlinks=False)
    assert scratch.remove_stale(tmp_path, ".paper-") == [str(killed)]
    old = time.time() - scratch.STALE_AFTER_S - 1
    os.utime(young, (old, old))
    assert scratch.remove_stale(tmp_path, ".paper-") == [str(young)]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        [link.name, target.name, work.name, longer.name, unmarked.name]
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
