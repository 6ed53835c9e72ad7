"""An exclusive lock on an output that a long command appends to or replaces.

A sweep's JSON-lines records, a screening's, ``stabctl paper``'s work directory: two
processes writing one of them at once lose records (one repairs a damaged line by renaming a
new file over the path while the other keeps appending to the old one) and both do all the
work.  :func:`exclusive` holds a POSIX advisory lock (``flock``) on a lock file beside the
output for as long as the output is written; a second writer is refused at once, with the
holder's process id, instead of waiting.  The lock goes with the process (a killed writer
holds nothing; its lock file, left behind, is taken over by the next writer); the lock
file is removed when the writer ends.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from stabctl.errors import InputError

__all__ = ["beside", "exclusive", "lock_path"]

#: a holder writes its pid just after it takes the lock: a refused writer reads it this
#: many times, 1 ms apart, before calling the holder unknown
PID_READS = 100


#: the longest file name most file systems take (ext4, xfs, tmpfs: 255 bytes)
NAME_MAX = 255
#: room kept in a helper file's name for what tempfile.mkstemp adds (8 random characters)
_RANDOM = 10


def beside(name: str, suffix: str) -> str:
    """The hidden name of a helper file of output file ``name`` (its lock, its temporary
    copy): ``.<name><suffix>``, or, when that would pass NAME_MAX bytes with the random
    part a temporary file adds, ``.<the name's start>-<a hash of it><suffix>``: a legal
    output name of 245-255 bytes was refused ("File name too long") for its helper's.

    Parameters
    ----------
    name : str
        The output file's name (no directory).
    suffix : str
        What follows it (``".lock"``, ``"."``).

    Returns
    -------
    str
    """
    full = f".{name}{suffix}"
    if len(os.fsencode(full)) + _RANDOM <= NAME_MAX:
        return full
    digest = hashlib.sha256(os.fsencode(name)).hexdigest()[:16]
    return f".{os.fsencode(name)[:100].decode(errors='ignore')}-{digest}{suffix}"


def lock_path(path: str | os.PathLike) -> Path:
    """The lock file of output ``path``: ``.<name>.lock`` beside the file it names, its
    symbolic links followed (``<name>.lock`` for a name that is already hidden), so that
    two names of one file (a link to it, ``./x`` and an absolute path) take one lock."""
    path = Path(os.path.realpath(path))
    if path.name.startswith("."):
        return path.with_name(beside(path.name, ".lock")[1:])
    return path.with_name(beside(path.name, ".lock"))


@contextmanager
def exclusive(path: str | os.PathLike) -> Iterator[Path]:
    """Hold the exclusive lock of output ``path`` (a file or a directory) while the block
    runs; yields the lock file's path, which is removed when the block ends.

    A lock file removed by its holder while another process had it open must not be
    locked by that process: the lock counts only if the locked file is still the one at
    the lock path (same inode), else the lock is taken again.

    Raises
    ------
    InputError
        Another process holds the lock: names the output and the holder's pid.
    OSError
        The lock file cannot be created (the directory is not writable).
    """
    lock = lock_path(path)
    lock.parent.mkdir(parents=True, exist_ok=True)
    fd = _locked(lock, path)
    own = None
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        own = _file_locked(path)
        yield lock
    finally:
        lock.unlink(missing_ok=True)  # still holding it: no one else has this file
        os.close(fd)  # releases the lock
        if own is not None:
            os.close(own)


def _file_locked(path) -> int | None:
    """A descriptor of the output file itself holding its exclusive lock, None if it is
    no regular file yet: a writer through another name of the same file (a hard link,
    whose lock file beside it is another) finds it held.

    Raises
    ------
    InputError
        Another process holds it.
    """
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # not there yet, or no file to read (a directory's own lock suffices)
        return None
    if not os.path.isfile(path):
        os.close(fd)
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        raise InputError(
            f"{path}: another stabctl process is writing this file under another name (a "
            "link to it); wait for it to end or choose another output"
        ) from None
    return fd


def _holder(fd: int) -> str:
    """The pid the lock's holder wrote in the lock file, "unknown" if none comes (the
    holder is between taking the lock and writing its pid, see `exclusive`)."""
    for _ in range(PID_READS):
        pid = os.pread(fd, 32, 0).decode(errors="replace").strip()
        if pid:
            return pid
        time.sleep(1e-3)
    return "unknown"


def _locked(lock: Path, path) -> int:
    """A descriptor of ``lock`` holding its exclusive lock (see `exclusive`)."""
    while True:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise InputError(
                f"{path}: another stabctl process (pid {holder}) is writing it; wait for "
                "it to end or choose another output"
            ) from None
        try:
            same = os.fstat(fd).st_ino == os.stat(lock).st_ino
        except FileNotFoundError:
            same = False
        if same:
            return fd
        os.close(fd)  # its holder removed it meanwhile: lock the file now at the path
