"""The files a run holds: an exclusive lock on an output that a long command appends to
or replaces, and the run's temporary files and directories.

A sweep's JSON-lines records, a screening's, ``stabctl paper``'s work directory: two
processes writing one of them at once lose records (one repairs a damaged line by renaming a
new file over the path while the other keeps appending to the old one) and both do all the
work.  :func:`exclusive` holds a POSIX advisory lock (``flock``) on a lock file beside the
output for as long as the output is written; a second writer is refused at once, with the
holder's process id, instead of waiting.  The lock goes with the process (a killed writer
holds nothing; its lock file, left behind, is taken over by the next writer); the lock
file is removed when the writer ends.

Temporary files and directories (`temp_file`, `temp_dir`): a run killed by SIGKILL
(``kill -9``, the out-of-memory killer) cannot remove them: an output's hidden temporary
file beside it (`stabctl.parallel.atomic_write`), ``stabctl paper``'s staging directory in
OUT_DIR, a sweep's directory of running marks in the temporary directory.  Each is made here
under a first name (ending ``.new``), locked (``flock``), and only then given its name, and
holds its lock for as long as its maker holds it; the lock goes with the process however it
ends.  Whoever next makes one of the same kind in the same directory (the next write of the
same output, the next sweep) removes those that are its user's and whose lock is free: their
maker is gone (one still under its first name only once older than `STALE_AFTER_S`, as its
maker may be about to lock it).  They hold nothing of the user's: a half-written output is
no output.  A file system whose locks cannot be taken (some NFS mounts) keeps them rather
than risk removing a live process's; one whose locks are each machine's own (NFS with
``local_lock=flock``) must not be shared by two machines writing the same output at once.

Work kept across an interrupt (`kept_path`: a plan's finished simulations,
`stabctl.placement.memo`; `estimate cct`'s finished searches) lives in this user's own
directory, ``$XDG_CACHE_HOME/<kind>/`` (``~/.cache`` when XDG_CACHE_HOME is unset), or,
where that cannot be made (a read-only home), ``<temporary directory>/<kind>-<uid>/``; each
made with mode 0700 and refused when it belongs to another user or others may write into it
(`unsafe_reason`, as numba's kernel cache, `stabctl._jit.cache`): whoever can write kept
results could hand a run results it never simulated.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import glob
import hashlib
import os
import re
import shutil
import stat
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from stabctl.errors import InputError

__all__ = [
    "KEPT_DAYS",
    "STALE_AFTER_S",
    "Held",
    "beside",
    "exclusive",
    "holder",
    "is_held",
    "kept_path",
    "kept_paths",
    "lock_path",
    "private_file",
    "remove_old_kept",
    "remove_stale",
    "temp_dir",
    "temp_file",
    "unsafe_entry_reason",
    "unsafe_reason",
]

#: a holder writes its pid just after it takes the lock: a refused writer reads it this
#: many times, 1 ms apart, before calling the holder unknown
PID_READS = 100


#: the longest file name most file systems take (ext4, xfs, tmpfs: 255 bytes)
NAME_MAX = 255
#: room kept in a helper file's name for what a temporary file adds (`temp_file`: 8 random
#: characters, the mark, ".new") and an output's suffix of up to 16 bytes (``.jsonl``)
_RANDOM = 36


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


def holder(path: str | os.PathLike) -> str | None:
    """Who holds the exclusive lock of output ``path`` (`exclusive`) now: the pid its
    holder wrote ("unknown" if none came), or None when no one holds it (a missing lock
    file included).  A look only: the lock may be taken or let go just after.

    Parameters
    ----------
    path : str or os.PathLike
        The output.

    Returns
    -------
    str or None
    """
    try:
        fd = os.open(lock_path(path), os.O_RDONLY)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return _holder(fd)
    except OSError:
        return None
    finally:
        os.close(fd)
    return None


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

    def refused(fd: int, exc: OSError) -> Exception:
        if not isinstance(exc, BlockingIOError):
            return exc
        return InputError(
            f"{path}: another stabctl process (pid {_holder(fd)}) is writing it; wait for "
            "it to end or choose another output"
        )

    return locked_at(lock, os.O_RDWR, 0o666, refused)


def locked_at(path, flags: int, mode: int, refused: Callable[[int, OSError], Exception]) -> int:
    """A descriptor of the file at `path` holding its exclusive lock (flock, not
    waiting), the file locked being the one at the path once locked: one its holder
    removed meanwhile (as it ended) is opened again, the new one.

    Parameters
    ----------
    path : str or path-like
        The file, made if missing.
    flags : int
        ``os.open`` flags besides O_CREAT (O_RDWR, O_APPEND, O_NOFOLLOW, ...).
    mode : int
        Its mode if made.
    refused : callable(fd, OSError) -> Exception
        The exception raised when the lock cannot be taken (BlockingIOError: another
        holds it; another OSError: a file system without locks), given the file's
        descriptor, closed after the call.

    Returns
    -------
    int
        The descriptor.

    Raises
    ------
    OSError
        The file cannot be opened or made.
    Exception
        `refused`'s.
    """
    while True:
        fd = os.open(path, flags | os.O_CREAT, mode)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            try:
                why = refused(fd, exc)
            finally:
                os.close(fd)
            raise why from None
        try:
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except FileNotFoundError:
            same = False
        if same:
            return fd
        os.close(fd)  # its holder removed it meanwhile: lock the file now at the path


#: a temporary file or directory still bearing its first name (ending `_UNLOCKED`) younger
#: than this (s, by its modification time) is never taken for a killed run's: its maker may
#: be about to lock it
STALE_AFTER_S = 60.0

#: the random part ``tempfile.mkstemp`` and ``mkdtemp`` put between prefix and suffix
_RANDOM_PART = "[a-z0-9_]{8}"
#: the end of a temporary file's or directory's name until its maker has locked it
_UNLOCKED = ".new"
#: what follows the random part of a name made here (before a file's suffix): whatever
#: lacks it (another program's, an editor's backup ``notes~``, or an earlier stabctl's,
#: never locked) is never removed
_MARK = "~stabctl"
#: the random characters mkstemp and mkdtemp put in a name
_RANDOM_CHARS = 8
#: names tried for a temporary file or directory (one taken between making and naming)
_NAMES = 100


#: the real paths of the temporary files and directories this process holds (`Held`)
_HELD: set[str] = set()


def is_held(path: str | os.PathLike) -> bool:
    """Whether `path` is a temporary file or directory this process holds (`temp_file`,
    `temp_dir`): an atomic write into one writes it in place, as it is already the
    temporary file of an atomic write (``simulate --out``'s writer, given the temporary
    file of `stabctl.parallel.atomic_writes`, left one of its own beside it).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    bool
    """
    return os.path.realpath(path) in _HELD


class Held:
    """A temporary file or directory of this process, locked while it is held.

    Parameters
    ----------
    path : str
        The file or directory.
    fd : int
        An open descriptor of it holding its lock; `release` closes it.
    """

    def __init__(self, path: str, fd: int) -> None:
        self.path = path
        self._fd: int | None = fd
        _HELD.add(os.path.realpath(path))

    def release(self) -> None:
        """Close the descriptor holding the lock (the file or directory itself stays)."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
            _HELD.discard(os.path.realpath(self.path))

    def remove(self) -> None:
        """Remove the directory (its contents with it) or file if still there, then release
        its lock."""
        try:
            if os.path.isdir(self.path) and not os.path.islink(self.path):
                shutil.rmtree(self.path, ignore_errors=True)
            else:
                os.unlink(self.path)
        except FileNotFoundError:
            pass
        finally:
            self.release()

    def __enter__(self) -> Held:
        return self

    def __exit__(self, *exc) -> None:
        self.remove()


def _lock(fd: int) -> bool:
    """Take `fd`'s exclusive lock without waiting: False when another holds it or the
    file system takes no lock."""
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return False
    return True


def temp_file(directory: str | Path, prefix: str, suffix: str = "") -> tuple[int, Held]:
    """A new temporary file ``<prefix><8 random characters>~stabctl<suffix>`` in
    `directory` (``tempfile.mkstemp``, mode 0600), locked, after removing killed runs'
    files of the same name pattern there (`remove_stale`).  A `suffix` that would make the
    name longer than NAME_MAX is left out (a format chosen by extension has a short one).

    Parameters
    ----------
    directory : str or Path
        Where (it must exist).
    prefix, suffix : str
        The name's start and end.

    Returns
    -------
    fd : int
        The file open for reading and writing, for the caller to close.
    held : Held
        The file's path and lock, released by ``held.release()`` (or removed with it by
        ``held.remove()``); the lock outlives `fd`.

    Raises
    ------
    OSError
        The file cannot be made (`directory` gone: named).
    """
    room = NAME_MAX - len(os.fsencode(prefix + _MARK + _UNLOCKED)) - _RANDOM_CHARS
    suffix = suffix if len(os.fsencode(suffix)) <= room else ""
    remove_stale(directory, prefix, suffix, kind="file")
    ends = _MARK + suffix + _UNLOCKED
    for _ in range(_NAMES):
        fd, made = _made(lambda: tempfile.mkstemp(ends, prefix, directory), directory)
        lock = os.dup(fd)
        path = _named(made, lock, fd)
        if path is not None:
            return fd, Held(path, lock)
    raise FileExistsError(errno.EEXIST, "no free temporary file name", str(directory))


def temp_dir(prefix: str, directory: str | Path | None = None) -> Held:
    """A new temporary directory ``<prefix><8 random characters>~stabctl`` in `directory`
    (the temporary directory by default; ``tempfile.mkdtemp``, mode 0700), locked, after
    removing killed runs' directories of the same name pattern there (`remove_stale`).
    Used as a context manager it is removed, contents and all, when the block ends.

    Parameters
    ----------
    prefix : str
        The name's start.
    directory : str or Path or None, optional
        Where; None: ``tempfile.gettempdir()``.

    Returns
    -------
    Held
        Its path and lock (``held.remove()`` removes it).

    Raises
    ------
    OSError
        The directory cannot be made (`directory` gone: named, with TMPDIR for the
        temporary directory).
    """
    where = str(directory) if directory is not None else tempfile.gettempdir()
    remove_stale(where, prefix, kind="directory")
    for _ in range(_NAMES):
        made = _made(lambda: tempfile.mkdtemp(_MARK + _UNLOCKED, prefix, where), where,
                     directory is None)  # fmt: skip
        fd = os.open(made, os.O_RDONLY | os.O_DIRECTORY)
        path = _named(made, fd)
        if path is not None:
            return Held(path, fd)
    raise FileExistsError(errno.EEXIST, "no free temporary directory name", where)


def _made(make, where, tmpdir: bool = False):
    """``make()`` (mkstemp, mkdtemp), its failure for a directory that is gone said so:
    "No such file or directory" named the temporary's own name (TMPDIR removed while a
    run went on, a sweep's output directory removed)."""
    try:
        return make()
    except FileNotFoundError:
        if os.path.isdir(where):
            raise
        hint = " (the temporary directory: set TMPDIR to one that exists)" if tmpdir else ""
        raise FileNotFoundError(
            errno.ENOENT, f"the directory is gone (removed while stabctl ran?){hint}", str(where)
        ) from None


def _named(made: str, fd: int, also: int | None = None) -> str | None:
    """Lock the new temporary file or directory `made` (through its descriptor `fd`) and
    only then give it its name, `made` without `_UNLOCKED`, so that whatever bears such a
    name unlocked is a killed run's; None (`made` removed, `fd` and `also` closed) if that
    name is taken.  Interrupted (Ctrl-C) meanwhile, it removes `made` and closes both."""
    try:
        _lock(fd)
        path = made[: -len(_UNLOCKED)]
        if not os.path.lexists(path):
            os.rename(made, path)
            return path
    except BaseException:
        _discard(made, fd, also)
        raise
    _discard(made, fd, also)
    return None


def _discard(made: str, *fds: int | None) -> None:
    """Remove the new temporary `made` and close its descriptors."""
    with contextlib.suppress(OSError):
        if os.path.isdir(made):
            os.rmdir(made)
        else:
            os.unlink(made)
    for fd in fds:
        if fd is not None:
            os.close(fd)


def remove_stale(
    directory: str | Path, prefix: str, suffix: str = "", kind: str = "file"
) -> list[str]:
    """Remove the temporary files (or directories) a killed run left in `directory`:
    those named ``<prefix><8 random characters>~stabctl<suffix>`` (as `temp_file` and
    `temp_dir` name them once locked), of `kind`, this user's, not symbolic links, whose
    lock is free; those still named as first made (ending ``.new``) only once older than
    `STALE_AFTER_S`.  Nothing is raised: one that cannot be read, locked or removed stays.

    Parameters
    ----------
    directory : str or Path
        Where to look (not below it).
    prefix, suffix : str
        The names' start and end.
    kind : {"file", "directory"}
        What is removed (a user's directory named like a temporary file stays).

    Returns
    -------
    list of str
        The paths removed.
    """
    pattern = re.compile(
        re.escape(prefix)
        + _RANDOM_PART
        + re.escape(_MARK + suffix)
        + f"({re.escape(_UNLOCKED)})?"
        + r"\Z"
    )
    try:
        names = [n for n in os.listdir(directory) if pattern.match(n)]
    except OSError:
        return []
    removed = []
    for name in names:
        path = os.path.join(directory, name)
        if _remove_if_stale(path, kind == "directory"):
            removed.append(path)
    return removed


def _remove_if_stale(path: str, want_dir: bool) -> bool:
    """Remove `path` if it is a killed run's (`remove_stale`): a directory if `want_dir`,
    else a regular file; True if removed."""
    try:
        st = os.lstat(path)
    except OSError:
        return False
    is_dir = stat.S_ISDIR(st.st_mode)
    if (
        not (is_dir if want_dir else stat.S_ISREG(st.st_mode))
        or st.st_uid != os.getuid()
        or (path.endswith(_UNLOCKED) and time.time() - st.st_mtime < STALE_AFTER_S)
    ):
        return False
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | (os.O_DIRECTORY if is_dir else 0))
    except OSError:
        return False
    try:
        now = os.fstat(fd)
        if (now.st_dev, now.st_ino) != (st.st_dev, st.st_ino) or not _lock(fd):
            return False
        if is_dir:
            shutil.rmtree(path, ignore_errors=True)
            return not os.path.lexists(path)
        try:
            os.unlink(path)
        except OSError:
            return False
        return True
    finally:
        os.close(fd)


# -- files kept across an interrupt: this user's own directories ------------------------


def unsafe_reason(directory: Path) -> str:
    """Why numba must not load kernels from `directory` ('' if it may): it belongs to
    another user than this one or root, or others than its owner may write into it (a
    kernel index is a pickle: whoever can plant one runs code in every process that
    loads it).

    Parameters
    ----------
    directory : Path
        A cache directory (a link to one followed); one not there yet is safe (numba
        makes it with this process's umask).

    Returns
    -------
    str
        The reason, naming the directory, or ''.
    """
    try:
        st = directory.stat()
    except OSError:
        return ""
    return _unsafe_owner_or_mode(directory, st)


def unsafe_entry_reason(path: Path) -> str:
    """Why numba must not unpickle the cache file `path` (a kernel's ``*.nbi`` index or
    ``*.nbc`` data; '' if it may): it is not a regular file (a symbolic link, even to a
    safe file: its target is whatever the link's writer chose), or, as a directory
    (`unsafe_reason`), it belongs to another user than this one or root or is writable by
    others than its owner (whoever can write it runs code in the process that loads it).

    Parameters
    ----------
    path : Path
        The file; one that is missing is safe (numba finds no entry).

    Returns
    -------
    str
        The reason, naming the file, or ''.
    """
    try:
        st = path.lstat()
    except OSError:
        return ""  # missing or unreadable: numba's own open of it says so
    if not stat.S_ISREG(st.st_mode):
        return f"{path} is not a regular file"
    return _unsafe_owner_or_mode(path, st)


def _unsafe_owner_or_mode(path: Path, st: os.stat_result) -> str:
    """The reason a cache directory or file of status `st` is unsafe by its owner (another
    user than this one or root) or its mode (writable by others than its owner), or ''."""
    if st.st_uid not in (os.geteuid(), 0):
        return f"{path} belongs to user {st.st_uid}"
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return f"{path} is writable by others than its owner"
    return ""


def private_file(path: str | os.PathLike) -> Path:
    """`path` once its directory is made (mode 0700, parents too) and both are checked.

    Parameters
    ----------
    path : str or os.PathLike
        The file (it need not be there yet).

    Returns
    -------
    Path

    Raises
    ------
    InputError
        The directory cannot be made, belongs to another user or may be written by others
        than its owner, or the file is there and is not a regular file (a link) or is
        another user's or writable by others; naming which.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    except OSError as exc:
        raise InputError(f"{path.parent}: cannot be made ({exc.strerror})") from None
    why = unsafe_reason(path.parent) or unsafe_entry_reason(path)
    if why:
        raise InputError(f"{why}: not used to keep finished work")
    return path


def kept_paths(kind: str, name: str) -> tuple[Path, ...]:
    """The two places of the file `name` of this user's directory for `kind` (module
    docstring), first choice first: the cache directory's, the temporary directory's.

    Parameters
    ----------
    kind : str
        The directory's name, e.g. ``"stabctl-place"``.
    name : str
        The file's name.

    Returns
    -------
    tuple of Path
        Neither made nor checked (`private_file` does both); the temporary directory's
        alone when there is no cache directory (no home: HOME unset and no passwd entry).
    """
    temp = Path(tempfile.gettempdir()) / f"{kind}-{os.geteuid()}" / name
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if os.path.isabs(xdg):  # a relative one is to be ignored (XDG Base Directory)
        return Path(xdg) / kind / name, temp
    try:
        return Path.home() / ".cache" / kind / name, temp
    except RuntimeError:  # no home directory to be found
        return (temp,)


def kept_path(kind: str, name: str) -> Path:
    """The file `name` of this user's directory for `kind` (module docstring): the cache
    directory's, else the temporary directory's (`kept_paths`), whichever can be made
    and written first.

    Parameters
    ----------
    kind : str
        The directory's name, e.g. ``"stabctl-estimate"``.
    name : str
        The file's name.

    Returns
    -------
    Path
        Checked by `private_file`.

    Raises
    ------
    InputError
        Neither place can be used, naming both reasons.
    """
    why = []
    for path in kept_paths(kind, name):
        try:
            private_file(path)
            fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, 0o600)
        except InputError as exc:
            why.append(str(exc))
            continue
        except OSError as exc:  # a read-only file system, a directory of another kind
            why.append(f"{path}: cannot be written ({exc.strerror})")
            continue
        os.close(fd)
        return path
    raise InputError("; ".join(why))


#: kept work untouched for this many days is removed by the next command that keeps work
#: of its kind there (`remove_old_kept`): a plan refused, or never run again, leaves its
#: file, which nothing else removes
KEPT_DAYS = 30


def remove_old_kept(directory: str | os.PathLike, pattern: str = "*.jsonl") -> list[Path]:
    """Remove the files `pattern` of a directory of kept work (`kept_paths`) not modified
    for KEPT_DAYS days and not held by a running command (``flock``), with the files
    their reading set aside beside them (``<name>.damaged...``).

    Parameters
    ----------
    directory : str or os.PathLike
        This user's directory of kept work of one kind (a missing one holds nothing).
    pattern : str, optional
        The kept files' names.

    Returns
    -------
    list of Path
        The files removed.
    """
    old = time.time() - KEPT_DAYS * 86400
    gone = []
    for path in Path(directory).glob(pattern):
        try:
            if path.is_symlink() or path.stat().st_mtime > old:
                continue
            fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # held: a command keeps work there now
            os.close(fd)
            continue
        try:
            for also in (path, *path.parent.glob(glob.escape(path.name) + ".damaged*")):
                also.unlink(missing_ok=True)
            gone.append(path)
        except OSError:
            pass
        finally:
            os.close(fd)
    return gone
