"""Run many independent jobs in parallel, recording each as it finishes (resumable).

A `Job` is a key, a top-level (picklable) function and its JSON-able inputs (a dict the
function takes as its one argument); the function returns a JSON-able dict.  `run_sweep` runs the
jobs in local processes (`concurrent.futures.ProcessPoolExecutor`, one worker per available
core, started with "spawn" so that no thread or lock of the parent is inherited) or, given a
scheduler address, on a Dask distributed cluster (optional: `pip install "stabctl[dask]"`;
the same stabctl must be installed on the workers: each job runs only on a worker whose
`stabctl._jit.cache.package_digest` is the client's, and a worker running another stops
the sweep with an InputError naming it and both digests).

Output: a JSON-lines file, one line per finished job, appended and flushed as each job
completes, so an interrupted sweep (Ctrl-C, a killed job) keeps every finished job:

    {"key": ..., "inputs": {...}, "status": "ok", "result": {...}, "wall_time_s": ...,
     "worker": "host:pid"}          (one line in the file)
    {"key": ..., "inputs": {...}, "status": "failed", "error": "SimulationError: ...", ...}
    {"key": ..., "inputs": {...}, "status": "verdict", "verdict": "N-1 insecure",
     "reason": "...", "n_simulations": 3, ...}

A job that raises a `stabctl.errors.Verdict` (a robust fault, an N-1 insecure one) is
recorded as that verdict, not as a failure, with the runs that reached it when the study
counted them (``n_simulations``) and its islanding, if any.  A job that raises anything
else is recorded as failed with the exception's type and message (and the traceback for
anything but a stabctl error), never dropped.  A worker process that dies in a local pool
(killed, out of memory) breaks the pool and every job not finished with it: they run
again on a new pool, those then running first and each alone, and a job whose worker
dies again alone is recorded failed; a job never run is never recorded (`_local`).  On
Dask a job whose worker died runs again on another worker (the scheduler's
``distributed.scheduler.allowed-failures``, default 3) and is recorded failed only when
it killed a worker each time (KilledWorker); each job is released once recorded, so that
a worker's death makes no finished job run again.  Jobs a Dask cluster could not run (its
scheduler gone, or no worker left for DASK_NO_WORKER_S) are not recorded:
`SweepIncomplete` names them, and the same call runs them.
Rerunning with the same file skips the keys already there (failed ones too, unless
`retry_failed`); the last line of a key wins.  One sweep per file at a time: a sweep
holds the file's lock (`stabctl.locking.exclusive`) from its repair to its last line, and
a second one is refused with the holder's pid.  A sweep's Dask client (and the local
cluster of ``scheduler="local"``) is closed when the sweep returns or raises, however
(`dask_client`), and is never made Dask's default client.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import inspect
import io
import json
import logging
import math
import multiprocessing
import os
import re
import shutil
import signal
import socket
import stat
import sys
import tempfile
import textwrap
import threading
import time
import traceback
import warnings
from collections.abc import Callable, Generator, Iterable, Iterator, Mapping
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import ExitStack, closing, contextmanager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeGuard

import numpy as np

from stabctl.errors import (
    InputError,
    SimulationError,
    StabctlError,
    UnsharedCaseError,
    Verdict,
    WrongTypeError,
    front,
    is_whole_number,
    require_flag,
    speaking,
)
from stabctl.jsontext import MAX_JSON_BYTES, input_file, parse_json, wide_unicode
from stabctl.locking import beside, exclusive, is_held, temp_dir, temp_file
from stabctl.progress import bar as progress_bar

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Job:
    """One unit of work: `func(inputs)` -> JSON-able dict, identified by `key` in the
    output file.  func must be importable by name (a module-level function); `inputs` is
    recorded with its result, so a rerun resumes only jobs with the same inputs.
    `check`, if given, is the schema of the job's records: ``check(record)`` says what
    makes a record of the job one its func cannot have written (a CCT out of its range, a
    list of machines that is text), or None; a resumed sweep handles such a record as a
    damaged line (`set_aside_damaged`), never as the job's result.  `compared`, if given,
    maps a job's inputs (as they read back from the file) to the form a resumed sweep
    compares (an input left to its default and the same value given count as the same
    inputs: a CCT search's t_end None and the fault time + 5 s it stands for,
    `stabctl.stability.cct.compared_inputs`); else the inputs are compared as they are."""

    key: str
    func: Callable[..., dict]
    inputs: Mapping = field(default_factory=dict)
    check: Callable[[dict], str | None] | None = None
    compared: Callable[[dict], dict] | None = None


@dataclass(frozen=True)
class RunnerOptions:
    """Where and how a study's many runs go (the CLI's ``--workers``, ``--scheduler``).

    Attributes
    ----------
    workers : int or None
        Local worker processes (None: one per available core; 1: in this process), or the
        size of a ``scheduler="local"`` Dask cluster.
    scheduler : str or None
        Dask scheduler address ('tcp://host:8786'), 'local' for a local Dask cluster, or
        None for local processes.
    progress : bool or callable
        A progress bar on stderr (True), none (False), or ``callable(done, total)`` called
        after each finished job.

    Raises
    ------
    WrongTypeError
        workers not a whole number, scheduler not a text, progress neither a bool nor a
        callable (`check_runner`).
    InputError
        workers < 1, or a scheduler address `check_scheduler` refuses.
    """

    workers: int | None = None
    scheduler: str | None = None
    progress: bool | Callable = True

    def __post_init__(self) -> None:
        check_runner(self.workers, self.scheduler, self.progress, "RunnerOptions")
        if self.workers is not None:  # 2.0 held as 2, as a count is shown
            object.__setattr__(self, "workers", int(self.workers))


@dataclass
class SweepReport:
    """Outcome of `run_sweep`: `records` maps every job key (in job order) to its line in
    the output file (finished now or before); ran / skipped / failed count this call's
    jobs (failed: among those run now); failed_before counts the jobs recorded as failed
    before and not run again (without `retry_failed`), failed_before_keys their keys;
    ran_keys the keys of the jobs run now (the others' records read from the file);
    wall_time_s is this call's."""

    out: Path
    records: dict
    ran: int
    skipped: int
    failed: int
    wall_time_s: float
    failed_before: int = 0
    failed_before_keys: tuple = ()
    ran_keys: tuple = ()


#: Dask runs a job again this many times when its task fails outside `run_job` (which
#: records the job's own errors, never retried), e.g. its function cannot be unpickled on
#: a worker.  A job whose worker died is run again by the Dask scheduler itself
#: (allowed-failures) and recorded failed (KilledWorker) only when it killed a worker
#: each time.
DASK_RETRIES = 1


def default_workers() -> int:
    """Cores available to this process."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def run_job(func: Callable[..., dict], key: str, inputs: Mapping) -> dict:
    """Run one job (in a worker) and return its output record; raises no Exception but
    `UnsharedCaseError` (the job's case is not its client's where it runs: the job is not
    run, and its sweep stops without recording it)."""
    wall = time.perf_counter()
    rec: dict
    try:
        rec = {"status": "ok", "result": func(dict(inputs))}
    except UnsharedCaseError:
        raise
    except Verdict as exc:  # an answer without a number (robust, N-1 insecure)
        rec = {"status": "verdict", "verdict": exc.label, "reason": " ".join(str(exc).split())}
        if exc.islanded:
            rec["islanded"] = list(exc.islanded)
        if exc.n_simulations is not None:
            rec["n_simulations"] = exc.n_simulations
        if exc.end_concerns:
            rec["end_concerns"], rec["end_t_s"] = list(exc.end_concerns), exc.end_t_s
        rec.update(exc.searched)
    except Exception as exc:  # noqa: BLE001 - every failure is recorded with its reason
        rec = _failure_fields(exc)
    return {
        "key": key,
        "inputs": dict(inputs),
        **rec,
        "wall_time_s": time.perf_counter() - wall,
        "worker": f"{socket.gethostname()}:{os.getpid()}",
    }


def _failure_fields(exc: BaseException) -> dict:
    msg = " ".join(str(exc).split())
    fields = {
        "status": "failed",
        "error": f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__,
    }
    if not isinstance(exc, StabctlError):
        fields["traceback"] = "".join(traceback.format_exception(exc))
    return fields


class SweepIncomplete(SimulationError):
    """Jobs a sweep could not run (its cluster went away): none of them is recorded, so
    the same command runs them."""


def _lost(job: Job, exc: BaseException) -> dict:
    """Record of a job whose worker failed outside the job (died, was lost)."""
    fields = _failure_fields(exc)
    fields["error"] = f"worker failed: {fields['error']}"
    return {
        "key": job.key,
        "inputs": dict(job.inputs),
        **fields,
        "wall_time_s": None,
        "worker": None,
    }


#: longest line a records file may hold, bytes: a sweep record is a few kB; a longer line
#: means a file that is not a records file (read in bounded pieces, never whole)
MAX_RECORD_LINE = 16 * 2**20
REAP_TIMEOUT = 30.0  # s a stopped pool waits for its killed workers to be reaped


def _record_lines(
    path: Path, check: Callable[[dict], str | None] | None = None
) -> Iterator[tuple[int, str, dict | None, str]]:
    """(line number, line, the record or None, why not) of every non-blank line of a
    records file (UTF-8, a byte-order mark before the first line skipped: an editor's, not
    part of the record), each read in at most MAX_RECORD_LINE bytes: the record is None,
    and `why` says why, when the line is not a whole sweep record (`_record`; `check` the
    schema of the records' kind, see `Job`).  Raises InputError, before a byte is read,
    for a file that is not a regular one of at most
    `stabctl.jsontext.MAX_JSON_BYTES` (JSON text read whole) or one in UTF-16 or UTF-32,
    and at a longer line or a line giving a key twice."""
    input_file(path, "records file", MAX_JSON_BYTES)
    with path.open("rb") as raw:  # (round 46: each line "cut by a kill?")
        start = raw.read(4)
    if wide_unicode(start):
        raise InputError(
            f"{path}: not UTF-8 text (UTF-16 or UTF-32: a byte-order mark or NUL bytes at its "
            "start), not a file of sweep records; save it as UTF-8"
        )
    with path.open(encoding="utf-8-sig", errors="replace") as f:
        for n, line in enumerate(iter(lambda: f.readline(MAX_RECORD_LINE + 1), ""), start=1):
            if len(line) > MAX_RECORD_LINE:
                raise InputError(
                    f"{path}: line {n} is longer than {MAX_RECORD_LINE // 2**20} MiB: not a "
                    "file of sweep records; give another file"
                )
            if line.strip():
                rec, why = _record(line, f"{path} line {n}", check)
                yield n, line, rec, why


#: why a line that is not JSON is no record (the last line of a sweep killed mid-write)
_CUT = "cut by a kill?"


def _record(line: str, where: str, check=None) -> tuple[dict | None, str]:
    """(the sweep record of a line, "") or (None, why it is none): the record must be a
    JSON object with a string key, a known status and that status's field of its type
    (`_problem`), and pass `check`, the schema of its kind, if given.  Raises InputError,
    naming ``where``, for a line giving a key twice (no kill cuts a line so: an edited
    record, whose value json would take the last of)."""
    try:
        rec = parse_json(line, where)
    except InputError:
        raise
    except (ValueError, RecursionError):  # a damaged or absurdly nested line
        return None, _CUT
    why = _problem(rec) or (check(rec) if check is not None else None)
    return (None, why) if why else (rec, "")


#: what a whole record of each status holds: its result, its verdict or its error, and
#: of which type (`run_job`, `_failure_fields`)
_STATUS_FIELD: dict[str, tuple[str, type]] = {
    "ok": ("result", dict),
    "verdict": ("verdict", str),
    "failed": ("error", str),
}


def _problem(rec) -> str | None:
    """What makes a parsed line no sweep record of any kind, or None: not an object, no
    string key, an unknown status, the status's field missing or of another type (the
    result an object, the verdict and error texts), inputs that are not an object, a
    wall time that is not one."""
    if not isinstance(rec, dict):
        return "not a JSON object"
    if not isinstance(rec.get("key"), str):
        return "no job key"
    status = rec.get("status")
    if not isinstance(status, str) or status not in _STATUS_FIELD:  # a list is unhashable
        return f"status {shown(status)} is none of {', '.join(_STATUS_FIELD)}"
    name, kind = _STATUS_FIELD[status]
    value = rec.get(name)
    if not isinstance(value, kind) or (kind is str and not value):
        what = "an object" if kind is dict else "a text"
        return f"status {status} without its {name} ({what}; {shown(value)} there)"
    if not isinstance(rec.get("inputs", {}), dict):
        return f"inputs {shown(rec['inputs'])} is not an object"
    wall = rec.get("wall_time_s")
    if wall is not None and not (is_number(wall) and wall >= 0):
        return f"wall_time_s {shown(wall)} is not a time in s"
    if not isinstance(rec.get("reason", ""), str):
        return f"reason {shown(rec['reason'])} is not a text"
    return None


def is_number(x) -> TypeGuard[float]:
    """Whether a value read from JSON is a finite number (not a bool, which JSON keeps
    apart but Python counts as an int).

    Parameters
    ----------
    x : object

    Returns
    -------
    bool
    """
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def shown(value) -> str:
    """A value read from a record, for a message: as JSON, cut at 40 characters.

    Parameters
    ----------
    value : object

    Returns
    -------
    str
    """
    try:
        text = json.dumps(value)
    except (TypeError, ValueError):  # pragma: no cover - records are read from JSON
        text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def read_records(
    path: str | Path, whole: str | None = None, check: Callable[[dict], str | None] | None = None
) -> dict[str, dict]:
    """Records of an output file: key -> last line of that key (a retry's record after
    its failed one).  Lines that are not whole sweep records (a line cut by a kill, a
    record without its result, one `check` refuses) are skipped with a warning, unless
    `whole` is given; a missing file gives {}.

    Parameters
    ----------
    path : str or pathlib.Path
        The records file.
    whole : str, optional
        The file is an input that must be whole (e.g. ``"--screening"``, named in the
        message): a line that is not a sweep record is an error, not skipped (the records
        read would be part of the file's, presented as all of them).
    check : callable, optional
        The schema of the records' kind (`Job`): ``check(record)`` says what makes a
        record one its job cannot have written, or None.

    Returns
    -------
    dict
        Key -> record.

    Raises
    ------
    InputError
        A file that is not a regular one or is larger than
        `stabctl.jsontext.MAX_JSON_BYTES`, a line longer than MAX_RECORD_LINE, a line
        giving a key twice, a job recorded twice other than after a failure (a file
        edited by hand: which result holds?), or with `whole` a line that is not a sweep
        record (its number named, and why).
    """
    path = Path(path)
    if not path.exists():
        return {}
    records: dict[str, dict] = {}
    first: dict[str, int] = {}
    ignored = 0
    for n, _, rec, why in _record_lines(path, check):
        if rec is None and whole is not None:
            raise InputError(
                f"{whole} {path} line {n}: not a whole sweep record ({why}): the records "
                "must be whole; repair or remove the line, or rerun the screening"
            )
        if rec is None:
            ignored += 1
            if ignored <= LINES_NAMED:  # (round 44: one warning a line, 9 million of them)
                warnings.warn(f"{path} line {n}: not a sweep record ({why}), ignored", stacklevel=2)
            continue
        key = rec["key"]
        if key in records and records[key]["status"] != "failed":  # a retry follows a failure
            raise InputError(
                f"{path} line {n}: job {key} is recorded again (first on line {first[key]}); "
                "a records file holds one result per job: remove one of the two lines"
            )
        records[key] = rec
        first.setdefault(key, n)
    if ignored > LINES_NAMED:
        warnings.warn(
            f"{path}: {ignored - LINES_NAMED} more line(s) not sweep records, ignored",
            stacklevel=2,
        )
    return records


#: the lines not sweep records that a warning names one by one (the rest are counted)
LINES_NAMED = 20
#: a file whose first this many non-blank lines hold no sweep record is refused there
#: (`set_aside_damaged`), not read to its end
LINES_WITHOUT_RECORD = 1000


def set_aside_damaged(
    path: str | Path,
    check: Callable[[dict], str | None] | None = None,
    remedy: str = "give another file or remove it",
) -> list[int]:
    """Move the lines of an output file that are not sweep records (a last line cut by a
    kill, a damaged line, a record whose fields its job cannot have written: `check`, the
    schema of the records' kind, see `Job`) to ``<path>.damaged`` with a warning naming
    each line and why, so that their jobs run again and the file holds only whole
    records; returns their line numbers.  The file is rewritten atomically (a temporary
    file renamed over it).  Raises InputError for a file `read_records` refuses (not a
    regular file, above the size cap, a line longer than MAX_RECORD_LINE), or a file of
    more than one line none of which is a record (another file given as the output:
    nothing moved; the message ends with `remedy`)."""
    path = Path(path)
    if not path.exists():
        return []
    good: list = []
    bad: list = []
    whys: dict[str, list[int]] = {}
    for n, line, rec, why in _record_lines(path, check):
        (good if rec is not None else bad).append((n, line if line.endswith("\n") else line + "\n"))
        if rec is None:
            whys.setdefault(why, []).append(n)
        if not good and len(bad) == LINES_WITHOUT_RECORD:  # (round 44: 9 million read first)
            raise InputError(
                f"{path}: none of its first {LINES_WITHOUT_RECORD} lines is a sweep record: "
                f"not the records of an earlier run (left as it is); {remedy}"
            )
    if not bad:
        return []
    if not good and len(bad) > 1:
        raise InputError(
            f"{path}: none of its {len(bad)} lines is a sweep record: not the records of an "
            f"earlier run (left as it is); {remedy}"
        )
    aside = path.with_name(path.name + ".damaged")
    with naming(aside), aside.open("a", encoding="utf-8") as f:
        f.writelines(line for _, line in bad)
    atomic_write(path, lambda f: f.writelines(line for _, line in good))
    numbers = [n for n, _ in bad]
    reasons = "; ".join(
        why if len(whys) == 1 else f"line(s) {_numbers_named(ns)}: {why}"
        for why, ns in whys.items()
    )
    warnings.warn(
        f"{path}: line(s) {_numbers_named(numbers)} not a whole sweep record "
        f"({reasons}): moved to {aside}; their jobs run again",
        stacklevel=2,
    )
    return numbers


def _numbers_named(numbers: list[int]) -> str:
    """Line numbers for a message: the first LINES_NAMED, the rest counted."""
    shown = ", ".join(map(str, numbers[:LINES_NAMED]))
    more = len(numbers) - LINES_NAMED
    return shown + (f" and {more} more" if more > 0 else "")


def atomic_write(
    path: str | Path, write: Callable, *, mode: str | None = "w", later: list | None = None
) -> Path:
    """Write a file atomically: into a temporary file beside it (hidden, same suffix, so
    that writers choosing the format by extension still do), renamed over `path` only when
    complete; the temporary file is removed if writing fails.  A file replaced keeps its
    permission bits (a records file of mode 0640 repaired stays 0640); a new one gets the
    mode ``open`` gives a new file (0o666 less the umask).  The one atomic write of
    stabctl.
    A symbolic link stays: the file it points to is the one replaced; a link that leads
    nowhere (broken, or a loop) is an error, and no directory it points to is created.
    A path that is neither a file nor a directory (a device or pipe: ``/dev/stdout``, a
    FIFO) is written in place, as no file can replace it; so is a temporary file this
    process holds (`stabctl.locking.is_held`: the writer of `atomic_writes` given its own).
    One of this process's open streams (``/dev/stdout``, ``/dev/fd/N``, a link to one:
    `stream_fd`) is written through its descriptor, at its position and in its mode:
    stdout sent to a log with ``>>`` was replaced by the output, the log's earlier lines
    lost.

    Parameters
    ----------
    path : str or Path
        The file; its directory is created if missing (not a symbolic link's).
    write : callable
        ``write(f)`` with the temporary file open in `mode`, or, with ``mode=None``,
        ``write(tmp_path)`` with the temporary file's path (a str; the file exists, empty).
    mode : {"w", "wb", None}
        How the temporary file is opened for `write`.
    later : list or None, optional
        Where to leave the rename, as (temporary file, path), the temporary file a
        `stabctl.scratch.Held` to release once renamed (`atomic_writes`: files renamed
        together once all are written); None: renamed at once.

    Returns
    -------
    Path
        `path`, as given.

    Raises
    ------
    OSError
        The directory cannot be created or written; `path` is a symbolic link that is
        broken or loops; whatever `write` raises.  One that names no file (a full disk,
        the file size limit: ``write`` fails without a name), or names the temporary
        file, names `path` (`naming`).
    """
    given = Path(path)
    with naming(given):
        fd = stream_fd(given)
        if fd is not None:
            _write_to_stream(fd, write, mode)
            return given
        path = Path(os.path.realpath(given, strict=True)) if given.is_symlink() else given
        if is_held(path) or (path.exists() and not (path.is_file() or path.is_dir())):
            if mode is None:
                write(str(path))
            else:
                with open(path, mode, **_utf8(mode)) as f:
                    write(f)
            return given
        if path.is_dir():  # (round 45: "Is a directory: 'd' -> None", from the rename)
            raise IsADirectoryError(errno.EISDIR, "a directory, not a file to write", str(given))
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, held = temp_file(path.parent, beside(path.name, "."), path.suffix)
        tmp = held.path
        try:
            with naming(given, tmp):
                if mode is None:
                    os.close(fd)
                    write(tmp)
                else:
                    with os.fdopen(fd, mode, **_utf8(mode)) as f:
                        write(f)
                try:  # the file replaced keeps its mode; a new one as open() makes it
                    keep = stat.S_IMODE(os.stat(path).st_mode) if path.is_file() else None
                except OSError:
                    keep = None
                os.chmod(tmp, 0o666 & ~_umask() if keep is None else keep)  # mkstemp: 0o600
                if later is None:
                    os.replace(tmp, path)
                else:
                    later.append((held, path))
        except BaseException:
            held.remove()
            raise
        if later is None:
            held.release()
    return given


#: how a path names one of this process's open streams (`stream_fd`)
_STREAM_PATHS = re.compile(r"/dev/std(in|out|err)|/dev/fd/(\d+)|/proc/(self|\d+)/fd/(\d+)")
_STD_FDS = {"in": 0, "out": 1, "err": 2}


def stream_fd(path: str | Path) -> int | None:
    """The descriptor of this process that `path` names, or None: ``/dev/stdout``,
    ``/dev/stderr``, ``/dev/fd/N``, ``/proc/self/fd/N`` (``/proc/<this pid>/fd/N``), or a
    chain of symbolic links through one of them, up to 40.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    int or None
    """
    p = os.path.abspath(path)
    for _ in range(40):
        hit = _STREAM_PATHS.fullmatch(p)
        if hit:
            std, n, pid, m = hit.groups()
            if std:
                return _STD_FDS[std]
            if n is not None:
                return int(n)
            return int(m) if pid == "self" or int(pid) == os.getpid() else None
        try:
            target = os.readlink(p)
        except OSError:
            return None
        p = os.path.abspath(os.path.join(os.path.dirname(p), target))
    return None


def _write_to_stream(fd: int, write: Callable, mode: str | None) -> None:
    """`atomic_write` into this process's open descriptor fd, through a copy of it (its
    position and mode kept: a log opened with ``>>`` is appended to): ``write(f)`` on it,
    or, with ``mode=None``, ``write(tmp_path)`` on a temporary file whose bytes are then
    copied to it (a writer given a path opens it afresh, truncating what it names)."""
    kind = "wb" if mode is None else mode
    with os.fdopen(os.dup(fd), kind, **_utf8(kind)) as out:
        if mode is not None:
            write(out)
            return
        with temp_dir("stabctl-stream-") as tmp:
            name = os.path.join(tmp.path, "out")
            write(name)
            with open(name, "rb") as src:
                shutil.copyfileobj(src, out)


def _utf8(mode: str) -> dict:
    """``open``'s keywords for `mode`: a text mode writes UTF-8 whatever the locale (an
    eigenvalue report's "±" failed with UnicodeEncodeError under LC_ALL=C, and would be
    another byte under a Latin-1 locale: a report's bytes were the locale's)."""
    return {} if "b" in mode else {"encoding": "utf-8"}


def atomic_writes(outputs) -> None:
    """Write several files together (`atomic_write` each): every one into its temporary
    file, all renamed only once all are written, so that a failure (a full disk, the
    file size limit) leaves every one of them as it was (`simulate --out x.csv --plot
    x.png` left a new x.png beside the error on x.csv).

    Parameters
    ----------
    outputs : iterable of (path, write)
        Each file and its ``write(tmp_path)`` (`atomic_write` with ``mode=None``).

    Raises
    ------
    OSError
        As `atomic_write`, naming the file; the temporary files are removed.
    """
    renames: list = []
    try:
        for path, write in outputs:
            atomic_write(path, write, mode=None, later=renames)
    except BaseException:
        for held, _ in renames:
            held.remove()
        raise
    with signals_held():  # all renamed, or none
        for held, path in renames:
            os.replace(held.path, path)
    for held, _ in renames:
        held.release()


#: the signals that interrupt a command (Ctrl-C, a batch system's stop, a closed terminal)
_STOPS = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


@contextmanager
def signals_held() -> Iterator[None]:
    """Hold Ctrl-C, SIGTERM and SIGHUP for the block: one that comes meanwhile is
    recorded and sent again after it, to the handlers the block found, so that a few
    renames that put several outputs in place happen all or none (`atomic_writes`;
    `stabctl paper`, whose output directory an interrupt between its moves left half
    replaced).  Keep the block short: nothing in it can be interrupted.  In the main
    thread (where Python runs signal handlers); elsewhere a plain block.

    Yields
    ------
    None
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    came: list[int] = []

    def hold(signum, frame):
        came.append(signum)

    before = {sig: signal.signal(sig, hold) for sig in _STOPS}
    try:
        yield
    finally:
        for sig, handler in before.items():  # None: one not set from Python, the default
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)
        if came:  # the first one, now that the block is done
            os.kill(os.getpid(), came[0])


@contextmanager
def naming(path: str | Path, *also: str | Path) -> Iterator[None]:
    """An OSError raised in the block names `path`: one that names no file (``write``
    failing on a full disk, ENOSPC, or past the file size limit, EFBIG: Python ignores
    SIGXFSZ, so the write fails instead of the process being killed) or names one of
    `also` (the temporary file written in its place) gets `path` as its ``filename``, so
    that the message says which output could not be written.  Errors naming another
    file are left as they are.

    Parameters
    ----------
    path : str or Path
        The output being written.
    *also : str or Path
        Files written for it (its temporary file), named as `path`.

    Yields
    ------
    None
    """
    try:
        yield
    except OSError as exc:
        if exc.filename is None or str(exc.filename) in {str(p) for p in also}:
            exc.filename = str(path)
            exc.filename2 = None
        raise


def _umask() -> int:
    """The process's umask (set back at once: reading it means setting it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def die_with_parent(parent: int) -> None:
    """Initializer of every worker process: on Linux the kernel kills the worker when its
    parent dies (prctl PR_SET_PDEATHSIG, SIGKILL), so a sweep killed with SIGKILL leaves
    no worker running (nor the resource tracker, which exits once no process holds its
    pipe); a worker whose parent is already gone exits at once.  Workers ignore SIGINT,
    SIGTERM and SIGHUP: Ctrl-C, a batch system's SIGTERM or a closed terminal's SIGHUP
    reaches the whole process group, and the parent stops the pool itself (`stop_pool`)
    rather than record its jobs as lost."""
    for sig in _GROUP_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    warnings.showwarning = _worker_warning
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no libc prctl
            pass
    if os.getppid() != parent:
        os._exit(1)


def _worker_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """How a worker process shows a warning: one ``warning:`` line on stderr, as the
    command line shows its own, instead of Python's file, line and source line in the
    middle of a progress bar (each worker shows a warning once per place, Python's
    default)."""
    text = " ".join(str(message).split())
    out = sys.stderr if file is None else file
    try:  # one write: two workers' lines were glued, each cut before its newline
        out.write(f"warning: {text}\n")
        out.flush()
    except (OSError, ValueError, AttributeError):  # stderr closed: nowhere to say it
        pass


@dataclass(frozen=True)
class _Warned:
    """A worker's job result with the warnings the job gave (`_told`): (category, text)
    pairs, each once."""

    result: Any
    said: tuple


def _told(words: str, func: Callable, *args) -> _Warned:
    """``func(*args)`` in a worker process (a pool's or Dask's) in the words of its
    parent's front (`stabctl.errors.front`: a command's options, not Python arguments),
    its warnings returned with its result, for the parent to give (`_given`).  Each worker
    showed them itself, in the library's words: ``estimate cct --step 0.0185`` gave its
    step warning once from the command and once more from each worker, those glued
    together between the progress bar's updates.  A job that raises shows its warnings in
    the worker (`_worker_warning`), as before."""
    with speaking(words), warnings.catch_warnings(record=True) as caught:
        try:
            result = func(*args)
        except BaseException:
            for w in caught:
                _worker_warning(w.message, w.category, w.filename, w.lineno)
            raise
    said = dict.fromkeys((w.category, " ".join(str(w.message).split())) for w in caught)
    return _Warned(result, tuple(said))


def _given(value: Any) -> Any:
    """A job's result as `_told` returned it, its warnings given here (each warned once
    per text, as this process's own: a command says them with its own, once); any other
    value (a job run in this process, a Dask worker's `_OtherSource`) as it is."""
    if not isinstance(value, _Warned):
        return value
    for category, text in value.said:
        try:
            warnings.warn(text, category, stacklevel=2)
        except TypeError:  # a category whose constructor takes more than the text
            warnings.warn(f"{category.__name__}: {text}", UserWarning, stacklevel=2)
    return value.result


_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>

#: the signals that reach a sweep's whole process group and that its parent alone acts on
_GROUP_SIGNALS = (
    signal.SIGINT,
    signal.SIGTERM,
    *([signal.SIGHUP] if hasattr(signal, "SIGHUP") else []),
)


def start_resource_tracker() -> None:
    """Start multiprocessing's resource tracker, if it is not running, with SIGHUP blocked
    for its life.  The tracker (the process that unlinks the semaphores of a pool left
    behind) ignores SIGINT and SIGTERM, but a SIGHUP to the process group (the terminal
    closed) killed it: the pool's shutdown then started a new one, which printed a
    traceback (``KeyError: '/mp-...'``) for every semaphore the first had registered.
    The signal mask is inherited through the tracker's fork and exec; it is set in this
    thread only for the start (a SIGHUP meanwhile is delivered after it).

    Notes
    -----
    Source: CPython 3.11 ``multiprocessing/resource_tracker.py`` (``ensure_running``,
    ``main``: the tracker unblocks only SIGINT and SIGTERM, which it ignores).
    """
    from multiprocessing import resource_tracker

    if not hasattr(signal, "SIGHUP") or not hasattr(signal, "pthread_sigmask"):
        resource_tracker.ensure_running()  # pragma: no cover - not POSIX
        return
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGHUP})
    try:
        resource_tracker.ensure_running()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


class _Pool(ProcessPoolExecutor):
    """A process pool whose workers are started with the process group's signals
    (`_GROUP_SIGNALS`) blocked: a spawned worker ignores them only once its initializer
    runs (`die_with_parent`), and a Ctrl-C to the group while its interpreter started
    ended it with "Fatal Python error: init_import_site" and a traceback (round 58 AZ21,
    `screen --workers 2` interrupted as it started its workers: 5 to 9 times in 25).
    The mask is inherited through the fork and exec; a signal that comes meanwhile stays
    pending, delivered to this process once its workers are started and discarded in
    each worker as its initializer ignores it (POSIX: setting SIG_IGN discards a pending
    signal).

    Notes
    -----
    Source: CPython 3.11 ``concurrent/futures/process.py``: the workers are started by
    ``_adjust_process_count`` (at the first submit, and again to replace one).
    """

    def _adjust_process_count(self):
        if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - not POSIX
            return super()._adjust_process_count()
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, set(_GROUP_SIGNALS))
        try:
            return super()._adjust_process_count()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def process_pool(workers: int) -> ProcessPoolExecutor:
    """A spawned process pool whose workers die with this process (`die_with_parent`),
    are started with the group's signals blocked (`_Pool`), and whose resource tracker is
    started to outlive a SIGHUP (`start_resource_tracker`)."""
    start_resource_tracker()
    return _Pool(
        workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=die_with_parent,
        initargs=(os.getpid(),),
    )


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Stop a pool at once (interrupted): pending jobs cancelled, running ones killed
    (their workers sent SIGKILL: they ignore SIGTERM) instead of waited for, and reaped:
    no worker outlives the sweep, not even as a zombie for init to collect."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    for proc in procs:
        try:
            proc.kill()
        except (OSError, ValueError, AttributeError):  # already gone
            pass
    deadline = time.monotonic() + REAP_TIMEOUT
    for proc in procs:
        _reap(proc, deadline)
    pool.shutdown(wait=False, cancel_futures=True)


def _reap(proc: Any, deadline: float) -> None:
    """Wait (until `deadline`, monotonic s) for a killed worker's exit code.  The pool's
    own management thread may reap the worker at the same moment: its waitpid then
    wins and ours sees no child until that thread has stored the code, so the code is
    polled rather than taken from one join."""
    try:
        while proc.exitcode is None and time.monotonic() < deadline:
            proc.join(timeout=0.05)
    except (OSError, ValueError, AssertionError):  # closed, or not started here
        pass


@contextmanager
def pooled(workers: int) -> Iterator[ProcessPoolExecutor]:
    """A spawned process pool (`process_pool`) for the duration of a with block: shut down
    normally at its end, stopped at once (`stop_pool`, running jobs killed) when the
    block is left by an exception (Ctrl-C included) or a generator holding it is closed.

    Parameters
    ----------
    workers : int
        Worker processes, >= 1.

    Yields
    ------
    ProcessPoolExecutor
    """
    pool = process_pool(workers)  # workers die with this process (SIGKILL included)
    try:
        yield pool
    except BaseException:
        stop_pool(pool)
        raise
    else:
        pool.shutdown(cancel_futures=True)


@contextmanager
def worker_pool(workers: int, scheduler: str | None = None) -> Iterator[Callable]:
    """A function ``map(func, jobs) -> results``, each job a dict passed as func's one
    argument, results in job order: in this process for workers == 1, else in a `pooled` process
    pool kept for the whole with block (so that each worker's caches, e.g. a simulator,
    are built once), or on a Dask cluster.

    Parameters
    ----------
    workers : int
        Worker processes, >= 1.
    scheduler : str, optional
        Dask scheduler address ('tcp://host:8786'), or 'local' for a local cluster of
        `workers` single-threaded processes (as :func:`run_sweep`).

    Yields
    ------
    callable
        ``map(func, jobs: list[dict], done=None) -> list``; func must be a module-level
        function taking one dict; ``done(k, n, i, result)``, if given, is called in this
        process as each job finishes (k of the n jobs done, in the order they finish; i
        the job's index in jobs, result its result: a caller may keep it at once); a
        ``done`` of two parameters is called ``done(k, n)``.

    Raises
    ------
    InputError
        Dask not installed or its scheduler unreachable; (from map, on Dask) a worker
        running another stabctl (`_on_worker`).
    SweepIncomplete
        (from map, on Dask) The cluster has had no worker for DASK_NO_WORKER_S, or lost
        the jobs (its scheduler gone: `_lost_by_cluster`); a job whose worker died runs
        again on another worker.  (From map, on processes) worker
        processes died more than `POOL_RESTARTS` times in one map (`_RestartedPool`).
    """
    if scheduler is not None:  # '' is refused (`check_scheduler`), never local
        with dask_client(scheduler, workers) as client, _quiet_dask():
            yield lambda func, jobs, done=None: _dask_map(client, func, jobs, done)
        return
    if workers == 1:
        yield _in_process
        return
    with ExitStack() as stack:
        yield _RestartedPool(workers, stack).map


class _RestartedPool:
    """`worker_pool`'s map on `pooled` processes, kept for the with block (`stack`): a
    pool broken by a worker that died (killed, out of memory: every job not finished is
    lost with it, BrokenProcessPool) is replaced by a new one for those jobs, up to
    `POOL_RESTARTS` times in one map (beyond, `SweepIncomplete`), as a sweep's
    (`_local`): a placement whose worker was killed stopped with a traceback."""

    def __init__(self, workers: int, stack: ExitStack):
        self.workers, self.stack = workers, stack
        self.pool = stack.enter_context(pooled(workers))

    def map(self, func, jobs: list, done=None) -> list:
        """func(job) for each job, results in job order; done(k, n, i, result) as each
        finishes."""
        results: dict = {}
        left, restarts = list(range(len(jobs))), 0
        while True:
            lost = self._run(func, jobs, left, results, done)
            if not lost:
                return [results[k] for k in range(len(jobs))]
            restarts += 1
            _restart_or_stop(restarts, len(lost), len(jobs), "run again")
            stop_pool(self.pool)
            self.pool = self.stack.enter_context(pooled(self.workers))
            left = lost

    def _run(self, func, jobs: list, left: list, results: dict, done) -> list:
        """Run the jobs `left` (indices) on the pool into `results`; returns those lost
        with a broken pool, in order (a job's own exception is raised)."""
        futures: dict = {}
        for k in left:
            try:
                futures[self.pool.submit(_told, front(), func, jobs[k])] = k
            except BrokenProcessPool:
                break
        lost = left[len(futures) :]  # not sent
        for fut in _as_finished(futures, self.pool):
            k = futures[fut]
            try:
                results[k] = _given(fut.result())
            except BrokenProcessPool:
                lost.append(k)
                continue
            if done is not None:
                _tell(done, len(results), len(jobs), k, results[k])
        return sorted(lost)


def _as_finished(futures, pool) -> Iterator:
    """The process pool's `futures` as each finishes.  While none finishes for
    `STALL_CHECK_S`, the pool's workers are looked at: one stopped (SIGSTOP, Ctrl-Z
    sent to it alone, a debugger) is named once, at once (logged as a warning, as a
    Dask worker lost is), as its job waits for it without end (a stopped process
    neither runs nor dies)."""
    pending, named = set(futures), set[int]()
    while pending:
        done, pending = wait(pending, timeout=STALL_CHECK_S, return_when=FIRST_COMPLETED)
        yield from done
        if not done:
            _name_stopped(pool, named)


def _name_stopped(pool, named: set) -> None:
    """Log a warning of each worker process of `pool` that is stopped (Linux's /proc
    state T or t) and not in `named` (then added): which, and how its job goes on."""
    for pid in list(getattr(pool, "_processes", None) or {}):
        if pid in named or _proc_state(pid) not in ("T", "t"):
            continue
        named.add(pid)
        _log.warning(
            "worker process %d is stopped (SIGSTOP, SIGTSTP or a debugger): the job it runs "
            "waits until it is continued (kill -CONT %d); killed instead, its job runs again "
            "on a new worker",
            pid,
            pid,
        )


def _proc_state(pid: int) -> str:
    """A process's state letter from /proc/PID/stat ('' where there is no /proc or the
    process is gone)."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            stat_line = fh.read().decode("ascii", "replace")
    except OSError:
        return ""
    return stat_line[stat_line.rfind(")") + 1 :].split()[0] if ")" in stat_line else ""


#: seconds without a finished job after which a process pool's workers are looked at
#: for a stopped one (`_as_finished`)
STALL_CHECK_S = 10.0


def _finished(futures, workers):
    """Dask futures as each finishes; while none is ready, the cluster's workers are
    checked every 10 ms (`_DaskWorkers.check`, which raises `_NoWorker`), and at the
    start and the end whatever the timing (a worker lost while results kept coming is
    said)."""
    from distributed import as_completed

    workers.check(force=True)  # the count the sweep starts with
    pending = as_completed(futures, loop=workers.client.loop)  # not the default client's
    while not pending.is_empty():
        if not pending.has_ready():
            workers.check()
            time.sleep(0.01)
            continue
        yield next(pending)
    workers.check(force=True)  # a loss while results kept coming is said too


def _dask_map(client, func: Callable[[dict], Any], jobs: list, done=None) -> list:
    """`worker_pool`'s map on Dask: each result taken, and its future released, as it
    finishes (so that a worker's death makes no finished job run again: a job its worker
    was running runs again on another); a job's exception is raised; `SweepIncomplete`
    when the cluster has had no worker for DASK_NO_WORKER_S."""
    from stabctl._jit.cache import package_digest

    digest = package_digest()
    futures = {
        client.submit(_on_worker, digest, _told, front(), func, j, pure=False): i
        for i, j in enumerate(jobs)
    }
    results: list = [None] * len(jobs)
    address = client.scheduler.address  # (named when the cluster is gone)
    try:
        workers = _DaskWorkers(client)
        for fut in _finished(futures, workers):
            k = futures[fut]
            try:
                results[k] = _given(_dask_result(fut, workers))
            finally:
                fut.release()
            del futures[fut]
            if done is not None:
                _tell(done, len(jobs) - len(futures), len(jobs), k, results[k])
    except _NoWorker as exc:
        raise SweepIncomplete(
            f"{len(futures)} of {len(jobs)} jobs not run: the Dask cluster at {address} {exc.why}"
        ) from None
    except Exception as exc:
        if not _lost_by_cluster(exc):
            raise  # the job's own error
        said = textwrap.shorten(" ".join(str(exc).split()), 160, placeholder=" ...")
        raise SweepIncomplete(
            f"{len(futures)} of {len(jobs)} jobs not run: the Dask cluster at {address} "
            f"lost them ({type(exc).__name__}: {said})"
        ) from None
    finally:
        for fut in futures:
            fut.release()
    return results


def _lost_by_cluster(exc: BaseException) -> bool:
    """Whether `exc`, raised while a Dask map waited for its results, is the cluster's
    (its scheduler gone: a future cancelled, a connection closed) rather than a job's
    own error, which Dask raises as the job raised it."""
    import asyncio
    import concurrent.futures

    if isinstance(exc, (asyncio.CancelledError, concurrent.futures.CancelledError)):
        return True
    return type(exc).__module__.split(".")[0] in ("distributed", "tornado")


def _tell(done: Callable, k: int, n: int, i: int, result) -> None:
    """Call a map's ``done`` callback with k of n jobs done and the job's index and
    result, or, a callback of two parameters (the earlier ``done(k, n)``), with k, n."""
    try:
        inspect.signature(done).bind(k, n, i, result)
    except TypeError:
        done(k, n)
    except ValueError:  # no signature to read (a builtin): the full call
        done(k, n, i, result)
    else:
        done(k, n, i, result)


def _in_process(func: Callable[[dict], Any], jobs: list, done=None) -> list:
    """`worker_pool`'s map for one worker: each job in turn in this process."""
    out = []
    for j in jobs:
        out.append(func(j))
        if done is not None:
            _tell(done, len(out), len(jobs), len(out) - 1, out[-1])
    return out


def run_sweep(
    jobs,
    out: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool | Callable = True,
    retry_failed: bool = False,
    pool=None,
    stage: str | None = None,
    label: str | None = None,
) -> SweepReport:
    """Run `jobs` (Job) not yet recorded in `out`, appending one JSON line per job.

    Args:
        workers: local processes (default: the available cores); 1 runs in this process.
        pool: a `pooled` process pool to run on (kept open, so that sweeps run one after
            the other reuse its workers and their caches); overrides `workers`.
        scheduler: Dask scheduler address ('tcp://host:8786'): run there instead;
            'local': a Dask LocalCluster of `workers` single-threaded processes.
        progress: a bar on stderr (True, `stabctl.progress.bar`), none (False), or a
            callable(done, total) called after each record written.  retry_failed: rerun
            keys recorded as failed.
        stage: what these jobs are when a study runs several sweeps into one file (e.g.
            'bus faults'), named in the progress bar after the file's name.
        label: the progress bar's name (default: the records file's); a study whose
            records file is its own temporary one names the work instead.

    Raises:
        WrongTypeError: workers, scheduler or progress of another type (`check_runner`).
        InputError: duplicate keys; `out` holds a key with other inputs; workers < 1;
            Dask not installed or its scheduler unreachable; another process is writing
            `out` (its lock, `stabctl.locking.exclusive`, names the holder's pid).
        KeyboardInterrupt: after cancelling pending jobs; finished ones are in `out`.
            Whatever ends it, its Dask client and local cluster are closed.
    """
    jobs = list(jobs)
    check_runner(workers, scheduler, progress, "run_sweep")
    require_flag(retry_failed, "run_sweep(retry_failed)")
    workers = None if workers is None else int(workers)
    out = Path(out)
    if out.is_file() and not os.access(out, os.W_OK):  # an archive: shown, nothing written
        return _sweep_read_only(jobs, out, retry_failed)
    with ExitStack() as held:
        with naming(out):  # the pid written in the lock file on a full disk names `out`
            held.enter_context(exclusive(out))
        name = (label or out.name) + (f" ({stage})" if stage else "")
        return _sweep_locked(jobs, out, workers, scheduler, progress, retry_failed, pool, name)


def _to_run(jobs, done: dict, retry_failed: bool) -> list:
    """The jobs of a sweep its records `done` do not hold (or hold failed, with
    `retry_failed`), in order."""
    return [
        j
        for j in jobs
        if j.key not in done or (retry_failed and done[j.key].get("status") == "failed")
    ]


def _sweep_read_only(jobs, out: Path, retry_failed: bool) -> SweepReport:
    """`run_sweep` of an `out` that cannot be written (read-only, or on a read-only mount:
    an archived study, a colleague's directory): its records shown when they hold every
    job (nothing to run, nothing written, no lock taken), else InputError naming how
    many jobs remain."""
    check = _schema(jobs)
    done = read_records(out, check=check)
    _check_jobs(jobs, done, out)
    todo = _to_run(jobs, done, retry_failed)
    if todo:
        raise InputError(
            f"{out}: the file is not writable and {len(todo)} of {len(jobs)} job(s) are not "
            "in it (or are to run again): give a file that can be written"
        )
    failed_keys = tuple(j.key for j in jobs if done[j.key]["status"] == "failed")
    return SweepReport(
        out=out,
        records={j.key: done[j.key] for j in jobs},
        ran=0,
        skipped=len(jobs),
        failed=0,
        wall_time_s=0.0,
        failed_before=len(failed_keys),
        failed_before_keys=failed_keys,
        ran_keys=(),
    )


def _sweep_locked(
    jobs, out: Path, workers, scheduler, progress, retry_failed, pool, name: str
) -> SweepReport:
    """`run_sweep`'s work once it holds `out`'s lock: repair, read, run, append."""
    check = _schema(jobs)
    set_aside_damaged(out, check)
    done = read_records(out, check=check)
    _check_jobs(jobs, done, out)
    todo = _to_run(jobs, done, retry_failed)
    rerun = {j.key for j in todo}
    failed_keys = tuple(
        j.key for j in jobs if j.key not in rerun and done[j.key]["status"] == "failed"
    )
    wall = time.perf_counter()
    failed = written = 0
    if todo:
        out.parent.mkdir(parents=True, exist_ok=True)
        _check_space(out, len(todo))
        with (
            _records(todo, scheduler, workers, pool) as results,
            _appender(out) as f,
            progress_bar(len(todo), name, show=progress is True) as bar,
        ):
            for rec in results:
                line = _line(rec)
                f.append(line)
                rec = done[rec["key"]] = json.loads(line)  # as it reads back
                failed += rec["status"] == "failed"
                bar.set_postfix(failed=failed, refresh=False)  # drawn with the update
                bar.update()
                written += 1
                if callable(progress):
                    progress(written, len(todo))
    return SweepReport(
        out=out,
        records={j.key: done[j.key] for j in jobs},
        ran=len(todo),
        skipped=len(jobs) - len(todo),
        failed=failed,
        wall_time_s=time.perf_counter() - wall,
        failed_before=len(failed_keys),
        failed_before_keys=failed_keys,
        ran_keys=tuple(j.key for j in todo),
    )


def _schema(jobs) -> Callable[[dict], str | None] | None:
    """The check of a record by the schema of its job's kind (`Job.check`), for the
    records of these jobs; those of other keys are checked as any record only."""
    checks = {j.key: j.check for j in jobs if j.check is not None}
    if not checks:
        return None

    def check(rec: dict) -> str | None:
        mine = checks.get(rec["key"])
        return None if mine is None else mine(rec)

    return check


#: Record fields that change from run to run (timings, process ids, tracebacks with the
#: install's paths): left out of the reproducible copy written by `write_reproducible`.
RUN_DEPENDENT = frozenset(
    {"wall_time_s", "worker", "traceback", "solve_time_s", "solve_times_s", "solve_wall_s"}
)


def strip_run_dependent(obj):
    """A copy of a JSON-able object without the RUN_DEPENDENT keys (at any depth)."""
    if isinstance(obj, dict):
        return {k: strip_run_dependent(v) for k, v in obj.items() if k not in RUN_DEPENDENT}
    if isinstance(obj, list):
        return [strip_run_dependent(v) for v in obj]
    return obj


def natural_key(key: str) -> tuple:
    """Sort key of a job key with its numbers compared as numbers (seed2 before seed10)."""
    return tuple(
        (0, int(t), "") if t.isdigit() else (1, 0, t) for t in re.split(r"(\d+)", key) if t
    )


def write_reproducible(src: str | Path, dst: str | Path) -> dict:
    """Write the records of the sweep file `src` (the last line of each key) to `dst` in
    a form that depends only on the jobs' results: sorted by `natural_key`, without the
    RUN_DEPENDENT fields, one line each.  `dst` is written to a temporary file in its
    directory and renamed over any old file only when complete.  Returns what was left
    out, for a run log: {"jobs", "failed", "job_wall_s" (sum), "longest_job_s",
    "longest_job"}."""
    records = read_records(src)
    atomic_write(
        dst,
        lambda f: f.writelines(
            json.dumps(strip_run_dependent(records[key]), default=_jsonable) + "\n"
            for key in sorted(records, key=natural_key)
        ),
    )
    walls: dict[str, float] = {
        k: r["wall_time_s"]
        for k, r in records.items()
        if isinstance(r.get("wall_time_s"), (int, float))
    }
    longest = max(walls, key=walls.__getitem__, default=None)
    return {
        "jobs": len(records),
        "failed": sum(r.get("status") == "failed" for r in records.values()),
        "job_wall_s": round(sum(walls.values()), 3),
        "longest_job_s": None if longest is None else round(walls[longest], 3),
        "longest_job": longest,
    }


def _check_jobs(jobs, done: dict, out: Path) -> None:
    """InputError for a key given twice, a job `out` holds with other inputs, or a record
    of `out` run on a case none of `jobs` runs on or on other content of one of their
    cases (`check_records_case`)."""
    if out.exists():
        cases = {j.inputs.get("case"): j.inputs.get("case_digest") for j in jobs}
        if cases and None not in cases:  # jobs without a case input are not checked
            check_records_case(out, cases, "give another output file (--out)")
    seen = set()
    for j in jobs:
        if j.key in seen:
            raise InputError(f"duplicate job key {j.key!r}")
        seen.add(j.key)
        if j.key not in done:
            continue
        old = done[j.key].get("inputs")
        same = j.compared or (lambda inputs: inputs)
        if not isinstance(old, dict) or same(old) != same(_normalised(j.inputs)):
            raise InputError(
                f"{out} already holds job {j.key!r} with other inputs ("
                f"{input_differences(old if isinstance(old, dict) else {}, j.inputs, same)}); "
                "use another output file"
            )


def check_records_case(path: str | Path, cases: Mapping, remedy: str) -> None:
    """Refuse records of another case, or of other content of the case, in a records file.

    A record's inputs name its ``case`` (a built-in name or a case file) and
    ``case_digest``, the digest of the case's content it was run on
    (`stabctl.case.Case.digest`): a resumed sweep would keep records of another case
    beside its own, or keep the results of a case file edited since as those of its new
    content.  Records without a ``case`` input are not checked.

    Parameters
    ----------
    path : str or pathlib.Path
        The records file (JSON lines, `run_sweep`'s output).
    cases : Mapping
        Case input -> its content's digest (None: its digest is not checked).
    remedy : str
        What the user does instead, ending each message.

    Raises
    ------
    InputError
        Naming the file, the line and job of the first record run on a case not in
        `cases`, or on one whose digest differs from the given (the case changed since,
        or the record has none: made before records carried it).
    """
    for n, _, rec, _why in _record_lines(Path(path)):
        inputs = (rec or {}).get("inputs")
        if rec is None or not isinstance(inputs, dict) or inputs.get("case") is None:
            continue
        case = inputs["case"]
        where = f"{path} line {n}: job {rec['key']} was run on case {case!r}"
        if case not in cases:
            mine = ", ".join(sorted(map(str, cases)))
            same = next((c for c in cases if _same_file(case, c)), None)
            if same is not None:
                raise InputError(
                    f"{where}, this run's {same!r} is the same file named otherwise: records "
                    f"are keyed by the case as the command gives it; give it as {case!r}"
                )
            raise InputError(
                f"{where}, not on this run's ({mine}): the file holds another case's "
                f"records; {remedy}"
            )
        old = inputs.get("case_digest")
        if cases[case] is not None and old != cases[case]:
            why = (
                "before records carried the digest of a case's content: whether the case "
                "changed since cannot be told"
                if old is None
                else f"as it was then: its content has changed since (digest {old} there, "
                f"{cases[case]} now)"
            )
            raise InputError(f"{where} {why}; {remedy}")


def _same_file(a, b) -> bool:
    """Whether two case inputs name one existing file (``./x.json`` and ``x.json``, a
    relative and an absolute path)."""
    try:
        return os.path.samefile(str(a), str(b))
    except (OSError, ValueError):  # a built-in case's name, a missing file
        return False


def other_records(path: str | Path, keys: Iterable[str], whose: Callable[[dict], str]) -> list[str]:
    """The records of a records file that are none of a run's jobs, named: a run that
    reports on its own jobs only (a screening's table) names them rather than leave them
    out without a word (a file may hold a wider screening's or a sweep-cct's records).

    Parameters
    ----------
    path : str or pathlib.Path
        The records file (JSON lines, `run_sweep`'s output); a missing file has none.
    keys : iterable of str
        The run's job keys.
    whose : callable
        ``whose(record)``: whose record it is, in words (``"a sweep-cct record"``).

    Returns
    -------
    list of str
        One per such record, in file order: ``"line N: job KEY (whose)"``.
    """
    path, mine = Path(path), set(keys)
    if not path.exists():
        return []
    return [
        f"line {n}: job {rec['key']} ({whose(rec)})"
        for n, _, rec, _why in _record_lines(path)
        if rec is not None and rec["key"] not in mine
    ]


#: records of other jobs a run names when its records file holds them (`warn_others`)
OTHERS_SHOWN = 5


def warn_others(path: str | Path, jobs, whose: Callable[[dict], str], run: str, left: str) -> None:
    """Warn (UserWarning) of the records in `path` of none of `jobs` (`other_records`),
    the first OTHERS_SHOWN named: kept in the file, but no part of what the run shows.

    Parameters
    ----------
    path : str or pathlib.Path
        The records file.
    jobs : sequence of Job
        The run's jobs.
    whose : callable
        ``whose(record)``: whose record it is, in words.
    run : str
        The run, as the warning names it (``"this sweep's 4 job(s)"``).
    left : str
        What becomes of them in what it shows (``"not counted here"``).
    """
    others = other_records(path, (j.key for j in jobs), whose)
    if others:
        shown = "; ".join(others[:OTHERS_SHOWN]) + ("; ..." if len(others) > OTHERS_SHOWN else "")
        warnings.warn(
            f"{path} holds {len(others)} record(s) of none of {run}, kept in the file and "
            f"{left}: {shown}",
            stacklevel=3,
        )


def input_differences(old: dict, new: Mapping, same: Callable[[dict], dict] | None = None) -> str:
    """The inputs that differ between a record's and a job's, named.

    Parameters
    ----------
    old : dict
        The record's inputs (as read from its file).
    new : Mapping
        The job's inputs.
    same : callable or None, optional
        The form the inputs are compared in (`Job.compared`); None (default): as they are.

    Returns
    -------
    str
        ``"KEY: OLD there, NEW now"`` for each input whose compared forms differ, in key
        order, comma-separated (the values as recorded and given).
    """
    new = _normalised(new)
    a, b = (old, new) if same is None else (same(old), same(new))
    return ", ".join(
        f"{k}: {old.get(k)!r} there, {new.get(k)!r} now"
        for k in sorted(set(a) | set(b))
        if a.get(k) != b.get(k)
    )


def _normalised(inputs: Mapping) -> dict:
    """Inputs as they read back from the file (tuples become lists)."""
    return json.loads(json.dumps(dict(inputs)))


def _line(rec: dict) -> str:
    try:
        return json.dumps(rec, default=_jsonable) + "\n"
    except (TypeError, ValueError) as exc:
        bad = {k: rec[k] for k in ("key", "inputs", "wall_time_s", "worker")}
        bad.update(status="failed", error=f"result is not JSON-serialisable: {exc}")
        return json.dumps(bad, default=str) + "\n"


def _jsonable(x):
    """numpy scalars and arrays -> Python numbers and lists; anything else is an error."""
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"{type(x).__name__} is not JSON-serialisable")


#: bytes a sweep record may take (a CCT search's record is about 1 KB; a failure's
#: traceback a few)
RECORD_BYTES = 8192


def _check_space(out: Path, n_jobs: int) -> None:
    """InputError before any job runs when the file system of ``out`` has less free space
    than ``n_jobs`` records may need (RECORD_BYTES each)."""
    free = shutil.disk_usage(out.parent).free
    need = n_jobs * RECORD_BYTES
    if free < need:
        raise InputError(
            f"{out}: {n_jobs} job(s) need up to {_size(need)} for their records, "
            f"{_size(free)} are free there"
        )


def _size(n: int) -> str:
    """A byte count for a message, in the unit that shows it (bytes, KiB, MiB, GiB)."""
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n} bytes"


class _appender:
    """A sweep file open for appending whole records (unbuffered bytes), opened (made if
    need be) by the first record: a sweep stopped before any leaves the file as it was, or
    none (not an empty file of 0 records).  A last line cut short by a kill is ended before
    the first record (so records stay one per line), and a record whose write fails (a
    disk full) is cut off again, so that the file holds only whole records (the sweep holds
    the file's lock: no one else appends)."""

    def __init__(self, path: Path):
        self.path = path
        self.f: io.FileIO | None = None

    def __enter__(self):
        return self

    def append(self, line: str) -> None:
        """Write ``line`` whole; if a write fails, truncate the file to where it began.  A
        file deleted since the last record is made again from the records held open (with
        a warning); one replaced by another file stops the sweep (`_replaced`)."""
        if self.f is not None and (kept := self._check_still_there()) is not None:
            with naming(Path(kept.name)), kept:  # this record kept with the others
                kept.write(line.encode())
            raise _replaced(self.path, Path(kept.name))
        if self.f is None:
            made = not self.path.exists()
            self.f = self.path.open("a+b", buffering=0)
            if made:  # locked as `locking.exclusive` locks a file there before it: a hard
                # link made to it mid-sweep let a second sweep append to it too
                fcntl.flock(self.f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            size = os.fstat(self.f.fileno()).st_size
            if size and os.pread(self.f.fileno(), 1, size - 1) != b"\n":
                line = "\n" + line
        fd = self.f.fileno()
        start = os.fstat(fd).st_size
        data = memoryview(line.encode())
        try:
            with naming(self.path):
                while data:
                    data = data[self.f.write(data) :]
        except OSError:
            os.ftruncate(fd, start)
            raise

    def _check_still_there(self) -> io.FileIO | None:
        """None when the path still names the file this sweep appends to, or when it was
        deleted, its directory with it or not (made again from what the sweep holds open,
        with a warning: a removed directory ended the sweep naming a '.kept' file the user
        never made); replaced by
        another file: a copy of the held records beside it, for the sweep to stop
        (`_replaced`).  Before, every later record went to the deleted file (a rerun did
        all the work again) or to one the path no longer names, and the sweep said
        nothing."""
        assert self.f is not None
        held = os.fstat(self.f.fileno())
        try:
            now = os.stat(self.path)
        except FileNotFoundError:
            now = None
        if now is not None and (now.st_dev, now.st_ino) == (held.st_dev, held.st_ino):
            return None
        gone = "" if self.path.parent.is_dir() else " (its directory too, made again)"
        if gone:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        copy = self._copy_held()
        if now is None:
            try:
                os.link(copy.name, self.path)
            except FileExistsError:  # replaced meanwhile
                now = os.stat(self.path)
            else:
                os.unlink(copy.name)
                self.f.close()
                self.f = copy
                warnings.warn(
                    f"{self.path}: deleted while the sweep ran{gone}: made again from the "
                    "records the sweep held open, and the sweep goes on",
                    stacklevel=3,
                )
                return None
        return copy

    def _copy_held(self) -> io.FileIO:
        """A new file beside the path holding the bytes of the file held open, locked as
        the sweep's, open for appending."""
        assert self.f is not None
        fd = self.f.fileno()
        made, name = tempfile.mkstemp(
            dir=self.path.parent, prefix=self.path.name + ".", suffix=".kept"
        )
        os.close(made)
        copy = io.FileIO(name, "a+")  # held as the records file, closed by the appender
        fcntl.flock(copy.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        offset, size = 0, os.fstat(fd).st_size
        with naming(Path(name)):
            while offset < size:
                chunk = os.pread(fd, min(1 << 20, size - offset), offset)
                if not chunk:
                    break
                copy.write(chunk)
                offset += len(chunk)
        return copy

    def __exit__(self, *exc):
        if self.f is not None:
            self.f.close()


def _replaced(path: Path, kept: Path) -> SweepIncomplete:
    """The error that stops a sweep whose records file was replaced by another file while
    it ran: the sweep's records are kept at `kept`, the other file is left as it is."""
    return SweepIncomplete(
        f"{path} was replaced by another file while the sweep ran: the sweep's records "
        f"(those it read and those it wrote) are kept in {kept}, the file now at {path} is "
        "left as it is; the sweep stopped (move the kept records back to the path and run "
        "the same command to finish)"
    )


def _local(jobs: list, workers: int | None, pool=None) -> Generator[dict, None, None]:
    """Records in completion order from a process pool: `pool` if given, else one of
    `workers` processes for these jobs (in this process if workers == 1).

    A pool broken by a worker that died (killed, out of memory: every job not finished
    is lost with it) is replaced by a new one for those jobs, up to `POOL_RESTARTS`
    times (beyond, they are not recorded: `SweepIncomplete`, and the same command runs
    them).  The jobs that were running when it broke run again first, each alone: one
    whose worker dies again is recorded failed (as Dask records a job that killed its
    workers, KilledWorker); a job that never ran is never recorded."""
    n = min(workers or default_workers(), len(jobs))
    if pool is None and n == 1:
        for j in jobs:
            yield run_job(j.func, j.key, j.inputs)
        return
    left, restarts = list(jobs), 0
    with temp_dir("stabctl-running-") as held:
        marks = held.path
        while left:
            given = pool is not None and not getattr(pool, "_broken", False)
            with nullcontext(pool) if given else pooled(n) as p:
                left, running = yield from _completed(p, left, marks)
            if not left:
                return
            restarts += 1
            keys = [j.key for j in left]
            more = f" and {len(keys) - 3} more" if len(keys) > 3 else ""
            _restart_or_stop(
                restarts,
                len(left),
                len(jobs),
                "run again"
                + (f", the {len(running)} then running each alone first" if running else ""),
                f" (not run: {', '.join(keys[:3])}{more}); the finished records are kept, "
                "and the same command runs the rest",
            )
            for j in running:
                with pooled(1) as alone:
                    again, _ = yield from _completed(alone, [j], marks)
                if again:
                    yield _lost(j, BrokenProcessPool(_DIED_ALONE))
            left = [j for j in left if not any(j is r for r in running)]


def _restart_or_stop(restarts: int, n_left: int, n_jobs: int, how: str, stopped: str = "") -> None:
    """The accounting of a process pool replaced after a worker's death (`_RestartedPool`,
    `_local`): restart number `restarts` of a map or sweep of `n_jobs` jobs whose `n_left`
    were not finished is warned of (RuntimeWarning, saying `how` they go on), or, beyond
    `POOL_RESTARTS`, raised as `SweepIncomplete` (`stopped` added to its message)."""
    if restarts > POOL_RESTARTS:
        raise SweepIncomplete(
            f"{n_left} of {n_jobs} jobs not run: worker processes died {restarts} times "
            f"(killed, or out of memory){stopped}"
        )
    warnings.warn(
        f"a worker process died (killed, or out of memory): {n_left} job(s) not finished "
        f"{how} (pool restart {restarts} of at most {POOL_RESTARTS})",
        RuntimeWarning,
        stacklevel=3,
    )


#: why a job is recorded failed when its worker dies again running it alone (`_local`)
_DIED_ALONE = (
    "its worker process died while it ran, then again when it ran alone (killed, or out of memory)"
)


#: times a sweep replaces a process pool broken by a worker's death (`_local`)
POOL_RESTARTS = 5


def _marked(marks: str, index: int, func, key: str, inputs) -> dict:
    """`run_job` in a worker, its job's index written to a file of the worker's pid in
    the directory `marks` while it runs (left there if the worker dies: `_completed`).  A
    mark that cannot be written (the directory removed meanwhile: a clean-up of the
    temporary directory) does not stop the job: without it, a worker's death tells only
    that one of the jobs not finished was running, and they all run again on a new pool
    (each job was recorded failed, "FileNotFoundError ... stabctl-running-...")."""
    path = os.path.join(marks, str(os.getpid()))
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
        with os.fdopen(fd, "w", encoding="ascii") as fh:
            fh.write(str(index))
    except OSError:
        path = ""
    rec = run_job(func, key, inputs)
    if path:
        with contextlib.suppress(OSError):
            os.unlink(path)
    return rec


def _completed(pool, jobs: list, marks: str) -> Generator[dict, None, tuple[list, list]]:
    """Records of `jobs` run on `pool` (`_marked` in `marks`), in completion order;
    returns (the jobs not finished when the pool broke, none recorded; those of them
    that were running then)."""
    futures: dict = {}  # future -> index of its job
    for k, j in enumerate(jobs):
        try:
            futures[pool.submit(_told, front(), _marked, marks, k, j.func, j.key, j.inputs)] = k
        except BrokenProcessPool:
            break
    broken = set(range(len(futures), len(jobs)))  # not sent
    for fut in _as_finished(futures, pool):
        try:
            rec = _given(fut.result())
        except BrokenProcessPool:
            broken.add(futures[fut])
            continue
        except UnsharedCaseError:  # not run: the sweep stops (`run_job`)
            raise
        except Exception as exc:  # noqa: BLE001 - the job could not be sent or returned
            rec = _lost(jobs[futures[fut]], exc)
        yield rec
    running = set()
    try:
        names = os.listdir(marks)
    except OSError:  # removed meanwhile (`_marked`)
        names = []
    for name in names:  # the workers that died, and those stopped with them
        path = os.path.join(marks, name)
        with contextlib.suppress(OSError, ValueError):
            running.add(int(Path(path).read_text("ascii")))
        with contextlib.suppress(OSError):
            os.unlink(path)
    return [jobs[k] for k in sorted(broken)], [jobs[k] for k in sorted(running & broken)]


#: seconds the first contact with a Dask scheduler may take before it is given up
SCHEDULER_TIMEOUT_S = 10.0


#: how an address is given, for the messages of `check_scheduler`
_SCHEDULER_FORMS = "give 'local' or a Dask scheduler's tcp://host:port"


def check_runner(workers, scheduler, progress, name: str) -> None:
    """Refuse where a study's runs go when it cannot be meant (`RunnerOptions`,
    `run_sweep`): ``workers=2.5`` ran on 2 processes, ``nan`` and ``True`` were taken,
    ``progress="no"`` drew a bar.

    Parameters
    ----------
    workers : object
        None or a whole number >= 1 of processes.
    scheduler : object
        None or a scheduler address (`check_scheduler`).
    progress : object
        True, False or a callable(done, total).
    name : str
        The caller, named in the message (``"RunnerOptions"``).

    Raises
    ------
    WrongTypeError
        Any of them of another type.
    InputError
        workers < 1, or an address `check_scheduler` refuses.
    """
    if workers is not None:
        if not is_whole_number(workers):
            raise WrongTypeError(
                f"{name}(workers): a whole number of processes >= 1 (or None: one per "
                f"core) is needed, got {workers!r} ({type(workers).__name__})"
            )
        if workers < 1:
            raise InputError(f"{name}(workers): workers must be >= 1, got {workers}")
    if scheduler is not None:
        if not isinstance(scheduler, str):
            raise WrongTypeError(
                f"{name}(scheduler): an address ('tcp://host:8786'), 'local' or None is "
                f"needed, got {scheduler!r} ({type(scheduler).__name__})"
            )
        check_scheduler(scheduler)
    if not (isinstance(progress, (bool, np.bool_)) or callable(progress)):
        raise WrongTypeError(
            f"{name}(progress): True (a bar), False (none) or a callable(done, total) is "
            f"needed, got {progress!r} ({type(progress).__name__})"
        )


def check_scheduler(address: str) -> str:
    """``address`` once it is "local", a Dask TCP address ``tcp://host[:port]`` (port
    1-65535, Dask's 8786 if left out) or a cluster in this process (``inproc://``).

    Raises
    ------
    InputError
        An empty or blank address (it is no scheduler: local processes are had by
        leaving --scheduler out), 'local' in other letters ('LOCAL') or with a port (a
        local cluster has none), an inproc:// address not of Dask's form, another
        scheme (tls:// and ucx:// need a configuration stabctl does not pass), no host, a
        port out of range, or text that is no URL (``tcp://[::1``).
    """
    from urllib.parse import urlsplit

    if address == "local" or re.fullmatch(r"inproc://[^/\s]+/\d+/\d+", address):
        return address  # inproc: a cluster of this process (Dask's inproc://HOST/PID/N)
    if address.startswith("inproc://"):
        raise InputError(
            f"--scheduler {address}: not an address of a Dask cluster in this process "
            f"(inproc://HOST/PID/N, as Dask gives it); {_SCHEDULER_FORMS}"
        )
    if address.strip().lower() == "local":
        raise InputError(
            f"--scheduler {address!r}: give 'local' (in lower case) for a local Dask cluster, "
            f"or tcp://{address.strip()}:8786 for a scheduler on a host of that name"
        )
    if not address.strip():
        raise InputError(
            f"--scheduler {address!r}: an empty address; {_SCHEDULER_FORMS}, or leave "
            "--scheduler out to run on local processes"
        )
    if address.startswith("local:"):
        raise InputError(
            f"--scheduler {address}: 'local' takes no port (it starts a local Dask cluster "
            "of --workers processes); give 'local', or tcp://local:PORT for a scheduler on a "
            "host named local"
        )
    try:
        parts = urlsplit(address if "://" in address else f"tcp://{address}")
    except ValueError as exc:  # an unclosed IPv6 bracket
        raise InputError(
            f"--scheduler {address}: not an address ({exc}); {_SCHEDULER_FORMS}"
        ) from None
    try:
        port = parts.port
    except ValueError:
        port = -1
    given = parts.netloc.rpartition("]")[2].partition(":")[2]  # the port as written
    digits = given.lstrip("0")  # more than 5 of them: out of range, and too long for int()
    if given.isascii() and given.isdigit() and not (len(digits) <= 5 and 0 < int(given) < 65536):
        shown = digits if len(digits) <= 12 else f"of {len(digits)} digits"
        raise InputError(
            f"--scheduler {address if len(address) <= 80 else address[:60] + '...'}: port "
            f"{shown or 0} is out of range (1-65535); {_SCHEDULER_FORMS}"
        )
    if parts.scheme != "tcp" or not parts.hostname or port == -1 or parts.path:
        raise InputError(
            f"--scheduler {address}: {_SCHEDULER_FORMS} (port 1-65535; tls:// and ucx:// "
            "are not supported)"
        )
    host = f"[{parts.hostname}]" if ":" in parts.hostname else parts.hostname  # IPv6
    return f"tcp://{host}:{port or 8786}"


@contextmanager
def dask_client(scheduler: str, workers: int = 1, timeout: float | None = None) -> Iterator[Any]:
    """A connected Dask distributed client for the duration of a with block: of the
    cluster at `scheduler` (`check_scheduler`), or for scheduler="local" of a new local
    cluster of `workers` single-threaded processes, each sent only the job it runs
    (worker-saturation 1.0).

    The client is closed, and a local cluster with it, when the block is left however
    (its end, an exception, Ctrl-C, a generator holding it closed), and so is a client
    whose start failed or was interrupted: none is left to Dask's finaliser, which closes
    a forgotten client whenever the garbage collector finds it (the finding: a collection
    inside a later cluster's start, which holds distributed's class-wide ``LoopRunner``
    lock, ran the forgotten client's close, which waits for that lock: a hang).  The
    client is not made Dask's default one (``set_as_default=False``): a sweep leaves
    ``distributed.default_client()`` and ``dask.config``'s scheduler as they were.

    Parameters
    ----------
    scheduler : str
        'local', or a Dask scheduler's address ('tcp://host:8786').
    workers : int, optional
        Worker processes of a 'local' cluster, >= 1 (unused with an address).
    timeout : float, optional
        Seconds the first contact with the scheduler may take (default
        SCHEDULER_TIMEOUT_S).

    Yields
    ------
    distributed.Client
        Connected (it answered within `timeout`).

    Raises
    ------
    InputError
        A bad address (`check_scheduler`), Dask distributed not installed, or no Dask
        scheduler answering at the address within `timeout` (a missing one, or a service
        that is not a Dask scheduler): raised before the block runs.

    Notes
    -----
    Sources: distributed 2026.8 ``client.py``: ``Client.__del__`` (closes a client that
    is garbage collected; ``close`` stops its ``LoopRunner``), ``Client.__init__`` and
    ``start`` (``set_as_default`` sets ``dask.config``'s scheduler and registers the
    client in ``distributed.client._global_clients``); ``utils.py``: ``LoopRunner``
    (``start`` and ``stop`` take the one ``LoopRunner._lock``).
    """
    client = _connect(scheduler, workers, SCHEDULER_TIMEOUT_S if timeout is None else timeout)
    try:
        yield client
    finally:
        _close(client)


def _connect(scheduler: str, workers: int, timeout: float):
    """`dask_client`'s client, connected at once (within `timeout`) so that a missing
    Dask, a wrong address or a service that is not a Dask scheduler fails before
    anything is written (InputError); nothing is left open when it fails."""
    address = check_scheduler(scheduler)
    try:
        from distributed import LocalCluster
    except ImportError:
        raise InputError(
            f"--scheduler {scheduler} needs Dask distributed, which is not "
            "installed: pip install 'stabctl[dask]'"
        ) from None
    if address == "local":
        import dask

        # a worker is sent only the job it runs (Dask's default, 1.1, queues a second
        # one there, which a worker killed by the first counts against: KilledWorker);
        # a cluster whose start fails closes itself (SpecCluster.__init__); its worker
        # processes log nothing below CRITICAL (silence_logs): what they say as an
        # interrupted sweep closes them is not shown, the sweep says what it kept (the
        # warnings of the jobs they cancel, "Async instruction ... ended with
        # CancelledError", two per running job; the error and traceback of a heartbeat
        # that met the scheduler closed, "Failed to communicate with scheduler"), and a
        # job's own error is in its record;
        # its worker processes ignore SIGINT (`dask_setup`): Ctrl-C at a terminal reaches
        # the whole process group, and a worker's event loop turned it into tracebacks
        # (CancelledError, KeyboardInterrupt) printed over the sweep's one line, while the
        # sweep closes the cluster itself;
        # its processes' semaphores are tracked by a tracker that outlives a SIGHUP; the
        # scratch space of its scheduler and workers (``dask-scratch-space``, left in the
        # temporary directory by Dask) is a directory of its own, removed with the cluster
        start_resource_tracker()
        held = temp_dir("stabctl-dask-")
        scratch = held.path
        try:
            settings = {
                "distributed.scheduler.worker-saturation": 1.0,
                # each worker process ignores the terminal's Ctrl-C (`dask_setup`)
                "distributed.worker.preload": [__name__],
            }
            with dask.config.set({**settings, "temporary-directory": scratch}):
                cluster = LocalCluster(
                    n_workers=workers,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    silence_logs=logging.CRITICAL,
                    local_directory=scratch,
                    # no dashboard; the scheduler's own HTTP server on a free port
                    scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                )
        except BaseException:
            held.remove()
            raise
        cluster.stabctl_scratch = held  # type: ignore[attr-defined] # removed by `_close`
        try:
            return _started_client(cluster)
        except BaseException:
            _close_cluster(cluster)
            raise
    try:
        if address.startswith("tcp://"):  # (an inproc:// cluster runs on this process's loop)
            _handshake(address, timeout)
        return _started_client(address, timeout=timeout)
    except Exception as exc:  # noqa: BLE001 - whatever a foreign service makes Dask raise
        said = " ".join(str(exc).split())[:200] or "no word"
        if type(exc) in (ConnectionError, TimeoutError):  # nothing listens, or silent
            raise InputError(
                f"no Dask scheduler answers at {address} within {timeout:g} s ({said})"
            ) from None
        kind = f"{type(exc).__name__}: "
        raise InputError(  # an echo server read as "no answer within 10 s" after 1 s
            f"no Dask scheduler answers at {address}: what answers there closed the "
            f"connection or does not speak Dask's protocol ({kind}{said})"
        ) from None


def _handshake(address: str, timeout: float) -> None:
    """Open a Dask connection to `address` and close it, the whole within `timeout` s,
    before a client connects: Dask's ``connect`` times out the TCP connection but waits
    for the peer's handshake without end, so a client of a peer that accepts and says
    nothing (a scheduler hung, another program's port) waited for ever, its time-out
    notwithstanding.

    Parameters
    ----------
    address : str
        A Dask TCP address (``tcp://host:port``).
    timeout : float
        Seconds.

    Raises
    ------
    TimeoutError
        No handshake within `timeout` s (said so in its message).
    ConnectionError
        Nothing listens at the address, or its host is not known (said so).
    OSError
        No connection (Dask's other errors).

    Notes
    -----
    Run on an event loop of its own in a thread of its own, as the client's start runs
    on its own loop thread: a caller's thread may run a loop already (a notebook's).
    Source: distributed 2026.8 ``comm/core.py``: ``connect`` (the TCP connection
    retried within its time-out, then ``await comm.read()`` of the handshake with
    none).
    """
    import asyncio

    from distributed.comm import connect

    async def shake() -> None:
        comm = await asyncio.wait_for(connect(address, timeout=timeout), timeout)
        await comm.close()

    ended: list[BaseException | None] = []

    def run() -> None:
        try:
            asyncio.run(shake())
        except BaseException as exc:  # noqa: BLE001 - handed to the caller's thread
            ended.append(exc)
        else:
            ended.append(None)

    thread = threading.Thread(target=run, name="stabctl-dask-handshake", daemon=True)
    thread.start()
    thread.join()  # (a daemon: Ctrl-C ends the wait, the thread ends within timeout)
    # Dask retries a refused connection till the time-out, then says "Timed out trying
    # to connect" (an OSError) or asyncio's wait ends first (a TimeoutError): either way
    # whether anything listens is asked of the port itself
    if isinstance(ended[0], OSError) and (why := _no_listener(address)):
        raise ConnectionError(
            f"{why}, through the {timeout:g} s a starting scheduler is waited for"
        )
    if isinstance(ended[0], TimeoutError):
        raise TimeoutError("it accepted the connection and sent no Dask handshake")
    if ended[0] is not None:
        raise ended[0]


def _no_listener(address: str) -> str:
    """Why nothing takes a TCP connection at the Dask address `address` (''
    if something does): refused, unreachable, or the host unknown."""
    from urllib.parse import urlsplit

    parts = urlsplit(address)
    try:
        socket.create_connection((parts.hostname, parts.port), timeout=1.0).close()
    except socket.gaierror as exc:
        return f"the host {parts.hostname} is not known here ({exc.strerror or exc})"
    except OSError as exc:
        return f"nothing listens there ({exc.strerror or type(exc).__name__})"
    return ""


def dask_setup(worker) -> None:
    """Dask's preload hook, run in each worker process of a local cluster (`_connect`) as
    it starts, in its main thread: SIGINT ignored, as a process pool's workers ignore it
    (`die_with_parent`).  Ctrl-C at a terminal signals the whole process group; the
    worker's event loop (asyncio's runner) turned it into a cancelled task and a
    KeyboardInterrupt, each printed as a traceback, while the sweep's own process closes
    the cluster and says what it kept.

    Parameters
    ----------
    worker : distributed.Worker
        The worker starting (unused).
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


def _started_client(address, **kwargs):
    """``distributed.Client(address, set_as_default=False, **kwargs)``, whose start (in its
    constructor) connects to the scheduler; if that fails or is interrupted, the
    half-started client is closed here before the error goes on (a client whose
    constructor raised is otherwise closed by its finaliser, whenever the garbage
    collector gets to it: the traceback of the error holds it)."""
    from distributed import Client

    client = Client.__new__(Client)  # a handle on it even if its __init__ raises
    try:
        Client.__init__(client, address, set_as_default=False, **kwargs)
    except BaseException:
        _close(client)
        raise
    return client


def _close(client) -> None:
    """Close a Dask client and the local cluster it started with (`_connect`), the
    cluster even if closing the client fails; distributed's own logs of a scheduler
    already gone are not shown (the sweep says what it lost), and an error of the
    close itself is logged (debug), not raised over the sweep's outcome."""
    cluster = getattr(client, "cluster", None)  # ours (scheduler="local") or None
    with _quiet_dask():
        try:
            client.close()
        except Exception as exc:  # noqa: BLE001 - e.g. a scheduler gone: nothing to keep
            _log.debug("closing the Dask client: %s: %s", type(exc).__name__, exc)
        finally:
            if cluster is not None:
                _close_cluster(cluster)


def _close_cluster(cluster) -> None:
    """Close a local cluster of `_connect` and remove its workers' scratch directory."""
    with _quiet_dask():
        try:
            cluster.close()
        finally:
            scratch = getattr(cluster, "stabctl_scratch", None)
            if scratch is not None:
                scratch.remove()


@contextmanager
def _quiet_dask() -> Iterator[None]:
    """distributed's loggers, and tornado's (its event loop, which logs a traceback of
    distributed's when Ctrl-C lands inside one of its calls), at CRITICAL for the block:
    it logs a traceback of its own when the scheduler goes away; the jobs it lost are
    said in one line (SweepIncomplete)."""
    dask_logs = [
        logging.getLogger(name)
        for name in dict.fromkeys(["tornado.application", *logging.root.manager.loggerDict])
        if name == "distributed" or name.startswith(("distributed.", "tornado.application"))
    ]
    levels = [log.level for log in dask_logs]
    for log in dask_logs:
        log.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for log, lvl in zip(dask_logs, levels, strict=True):
            log.setLevel(lvl)


@contextmanager
def _records(
    jobs: list, scheduler: str | None, workers: int | None, pool=None
) -> Iterator[Iterator[dict]]:
    """`run_sweep`'s records in completion order, for a with block: from a Dask cluster
    (`dask_client`: connected on entering, before the sweep's file is touched, and
    closed with its local cluster on leaving, however the block is left, even before
    the first record) or from local processes (`_local`)."""
    if scheduler is None:  # '' is refused (`check_scheduler`), never local
        with closing(_local(jobs, workers, pool)) as records:
            yield records
        return
    n = min(workers or default_workers(), len(jobs))
    with (
        dask_client(scheduler, n) as client,
        _quiet_dask(),
        closing(_dask_records(client, jobs)) as records,
    ):
        yield records


def _dask_records(client, jobs: list) -> Generator[dict, None, None]:
    """Records in completion order from a Dask cluster (see the module docstring).

    A job running on a worker that dies is run again by Dask on another worker (the
    scheduler's ``distributed.scheduler.allowed-failures``, 3 by default); each future is
    released as soon as its record is taken, so that the death of a worker does not make
    Dask run again the finished jobs whose results it held.  A job that killed its worker
    every time it ran (Dask's KilledWorker) is recorded as failed.  Jobs the cluster lost
    otherwise are not recorded: `SweepIncomplete` once the others are in, naming them;
    this includes every job left when the cluster has had no worker for
    DASK_NO_WORKER_S after having one (its last worker died).  Each job runs only on a
    worker whose stabctl is this one (`_on_worker`): a worker running another stops the
    sweep (InputError, `_dask_result`), its job unrecorded."""
    from distributed import KilledWorker

    from stabctl._jit.cache import package_digest

    digest = package_digest()
    lost: list[str] = []
    address = client.scheduler.address  # (named when the cluster is gone)
    try:
        futures = {
            client.submit(
                _on_worker,
                digest,
                _told,
                front(),
                run_job,
                j.func,
                j.key,
                dict(j.inputs),
                pure=False,
                retries=DASK_RETRIES,
            ): j
            for j in jobs
        }
        workers = _DaskWorkers(client)
        for fut in _finished(futures, workers):
            job = futures.pop(fut)
            try:
                rec = _given(_dask_result(fut, workers))
            except KilledWorker as exc:  # the job killed its worker, each time it ran
                rec = _lost(job, exc)
            except _NoWorker:
                futures[fut] = job  # not run either
                raise
            except InputError:  # another stabctl there, or another case (UnsharedCaseError)
                raise
            except Exception as exc:  # noqa: BLE001 - the cluster lost the job: not a result
                said = textwrap.shorten(" ".join(str(exc).split()), 160, placeholder=" ...")
                lost.append(f"{type(exc).__name__}: {said}")
                continue
            finally:
                fut.release()  # the scheduler forgets it: never run again
            yield rec
        if lost:
            raise SweepIncomplete(
                f"{len(lost)} of {len(jobs)} jobs not run: the Dask cluster at {address} "
                f"lost them ({lost[0]}); the finished records are kept, and the same "
                "command runs the rest"
            )
    except _NoWorker as exc:
        left = [j.key for j in futures.values()]
        more = f" and {len(left) - 3} more" if len(left) > 3 else ""
        raise SweepIncomplete(
            f"{len(left) + len(lost)} of {len(jobs)} jobs not run: the Dask cluster at "
            f"{address} {exc.why} (not run: {', '.join(left[:3])}{more}); the finished "
            "records are kept, and the same command, once the cluster is back, runs the rest"
        ) from None


#: what a cluster whose workers died says of one cause a client cannot see: a worker that
#: cannot import stabctl dies on the first job it is sent (it cannot unpickle the job)
_DIED_AT_ONCE = (
    "a worker that cannot import this stabctl dies on its first job: its log then ends in "
    "an ImportError"
)

#: seconds a Dask sweep waits for a worker when its cluster has none left (the last one
#: died: a nanny restarts its worker within a few seconds) before it gives up the jobs
#: not run (`SweepIncomplete`); a cluster that has had no worker yet is waited for
DASK_NO_WORKER_S = 30.0

#: seconds a Dask sweep waits for its cluster's first worker before it says (a log
#: warning, once) that the cluster has none and it is waiting for one to join; it keeps
#: waiting (workers may be starting; Ctrl-C stops it, keeping the finished records)
DASK_NO_WORKER_YET_S = 10.0


class _NoWorker(Exception):
    """The Dask cluster cannot run the jobs left: it has had no worker for
    DASK_NO_WORKER_S (the default reason), or its scheduler has not answered for
    SCHEDULER_GIVE_UP_S (`why` says which, after "the Dask cluster at ADDRESS")."""

    def __init__(self, why: str = ""):
        super().__init__(why)
        self.why = why or (
            f"has had no worker for {DASK_NO_WORKER_S:g} s (its last one died or left; "
            f"{_DIED_AT_ONCE})"
        )


def _dask_result(fut, workers: _DaskWorkers) -> Any:
    """A finished future's record (a job submitted through `_on_worker`); if its result
    was lost with its worker before it was fetched, Dask runs the job again: waited for
    while the cluster has workers.  InputError if the worker runs another stabctl source
    (`_OtherSource`): the job was not run there."""
    while True:
        try:
            result = fut.result(timeout=1.0)
        except TimeoutError:
            workers.check()
            continue
        if isinstance(result, _OtherSource):
            from stabctl._jit.cache import package_digest

            raise InputError(
                f"Dask worker {result.worker} runs another stabctl than this one (package "
                f"digest {result.digest[:12]} there, {package_digest()[:12]} here): install "
                "this stabctl on every worker of the cluster at "
                f"{workers.client.scheduler.address}; the finished records are kept"
            )
        return result


@dataclass(frozen=True)
class _OtherSource:
    """What a Dask worker returns instead of a job's result when its stabctl is not the
    client's (`_on_worker`): its address and its `package_digest`."""

    worker: str
    digest: str


def _on_worker(digest: str, func: Callable, *args) -> Any:
    """``func(*args)`` on a Dask worker whose stabctl is the client's (its `package_digest`
    is ``digest``); on a worker running another (an uncommitted edit, another version)
    the job is not run: an `_OtherSource` is returned instead (a value, not an exception,
    which Dask would retry on another worker), refused by the client (`_dask_result`)."""
    from distributed import get_worker

    from stabctl._jit.cache import package_digest

    here = package_digest()
    if here != digest:
        return _OtherSource(get_worker().address, here)
    return func(*args)


#: seconds one question to a Dask scheduler may take (`_DaskWorkers.ask`), how long it
#: may go without answering before a sweep says so, and before it gives up the jobs not
#: run (`SweepIncomplete`: none recorded, the same command runs them)
SCHEDULER_ANSWER_S, SILENT_SCHEDULER_S, SCHEDULER_GIVE_UP_S = 5.0, 30.0, 120.0

#: seconds a Dask worker may go without a heartbeat reaching the scheduler before a
#: sweep names it (stopped, hung or cut off: its job waits for it until the scheduler
#: drops it, after its ``distributed.scheduler.worker-ttl``, 5 min by default)
SILENT_WORKER_S = 30.0


class _DaskWorkers:
    """The worker count of a Dask sweep's cluster, asked at most once a second: a lost
    worker is said (log warning: its running job goes to another worker), a cluster
    without a worker for DASK_NO_WORKER_S after it had one raises `_NoWorker`, and one
    that has had none for DASK_NO_WORKER_YET_S since the sweep began is said once (log
    warning: the sweep waits for a worker to join).  Every STALL_CHECK_S the workers'
    heartbeats are looked at: one whose last heartbeat has not moved for
    SILENT_WORKER_S is named once (log warning; a SIGSTOPped worker kept a sweep waiting
    without a word); a scheduler that has not answered for SILENT_SCHEDULER_S is said
    once (`ask`) and waited for."""

    def __init__(self, client):
        self.client = client
        self.count: int | None = None
        self.seen = False
        self.none_since: float | None = None
        self.next_check = 0.0
        self.began = time.monotonic()
        self.said_none_yet = False
        self.next_heartbeats = self.began
        #: worker address -> (its last heartbeat as the scheduler saw it, when this
        #: process saw that value first); the silent workers named
        self.heard: dict[str, tuple[Any, float]] = {}
        self.named: set[str] = set()
        #: since when (this process's clock) the scheduler has not answered; said or not
        self.unanswered: float | None = None
        self.said_unanswered = False

    def check(self, force: bool = False) -> None:
        """Ask the scheduler (if a second has passed, or `force`)."""
        now = time.monotonic()
        if now < self.next_check and not force:
            return
        self.next_check = now + 1.0
        info = self.ask(n_workers=0)
        if info is None:  # the scheduler did not answer: said, and asked again
            return
        n = int(info.get("n_workers", 0))
        if self.count is not None and n < self.count:
            _log.warning(
                "Dask worker(s) lost: %d of %d left; %s",
                n,
                self.count,
                "their running jobs go to another worker"
                if n
                else f"waiting up to {DASK_NO_WORKER_S:g} s for one before giving up the "
                "jobs not run",
            )
        waited = now - self.began
        if n == 0 and not (self.seen or self.said_none_yet) and waited >= DASK_NO_WORKER_YET_S:
            _log.warning(
                "the Dask cluster at %s has no worker (none for %g s): waiting for one to "
                "join; Ctrl-C stops the sweep, keeping its finished records",
                self.client.scheduler.address,
                DASK_NO_WORKER_YET_S,
            )
            self.said_none_yet = True
        if n == 0 and self.seen:
            self.none_since = self.none_since or now
            if now - self.none_since >= DASK_NO_WORKER_S:
                raise _NoWorker
        else:
            self.none_since = None
        self.seen = self.seen or n > 0
        self.count = n
        if now >= self.next_heartbeats:
            self.next_heartbeats = now + STALL_CHECK_S
            self.name_silent(now)

    def ask(self, n_workers: int) -> dict | None:
        """The scheduler's identity (`n_workers` workers' details: -1 all), or None when
        it has not answered within SCHEDULER_ANSWER_S: once it has been silent for
        SILENT_SCHEDULER_S, that is said (log warning, once; a SIGSTOPped scheduler kept a
        sweep waiting without a word, as the client's own call waits for ever); after
        SCHEDULER_GIVE_UP_S `_NoWorker` is raised: the jobs left are not run.  A
        connection closed (the scheduler killed: distributed's CommClosedError, which
        reached the user in Dask's own words) raises `_NoWorker` at once."""
        client = self.client
        try:
            info = client.sync(
                client.scheduler.identity, n_workers=n_workers, callback_timeout=SCHEDULER_ANSWER_S
            )
        except OSError as exc:  # distributed's CommClosedError: the scheduler is gone
            if isinstance(exc, TimeoutError):
                self._unanswered()
                return None
            said = textwrap.shorten(" ".join(str(exc).split()), 120, placeholder=" ...")
            raise _NoWorker(
                f"closed its connection (its scheduler stopped or was killed: "
                f"{type(exc).__name__}: {said})"
            ) from None
        if self.said_unanswered:
            _log.warning("the Dask scheduler at %s answers again", client.scheduler.address)
        self.unanswered, self.said_unanswered = None, False
        return info

    def _unanswered(self) -> None:
        """`ask`'s question unanswered: said after SILENT_SCHEDULER_S, given up
        (`_NoWorker`) after SCHEDULER_GIVE_UP_S."""
        client = self.client
        now = time.monotonic()
        self.unanswered = self.unanswered or now - SCHEDULER_ANSWER_S
        if now - self.unanswered >= SCHEDULER_GIVE_UP_S:
            silent = now - self.unanswered
            raise _NoWorker(
                f"has not answered for {silent:.0f} s (its scheduler stopped, hung or cut off)"
            )
        if now - self.unanswered >= SILENT_SCHEDULER_S and not self.said_unanswered:
            self.said_unanswered = True
            _log.warning(
                "the Dask scheduler at %s has not answered for %.0f s (stopped, hung or "
                "cut off): the sweep waits for it up to %g s in all, then gives up the "
                "jobs not run; Ctrl-C stops it now, keeping its finished records",
                client.scheduler.address,
                now - self.unanswered,
                SCHEDULER_GIVE_UP_S,
            )

    def name_silent(self, now: float) -> None:
        """Log a warning of each worker whose heartbeat (the scheduler's ``last_seen``)
        has not moved for SILENT_WORKER_S of this process's time, once per worker."""
        workers = (self.ask(n_workers=-1) or {}).get("workers", {})
        for address, info in workers.items():
            beat = info.get("last_seen")
            before = self.heard.get(address)
            if before is None or before[0] != beat:
                self.heard[address] = (beat, now)
                continue
            if now - before[1] >= SILENT_WORKER_S and address not in self.named:
                self.named.add(address)
                _log.warning(
                    "Dask worker %s has sent no heartbeat for %.0f s (stopped, hung or cut "
                    "off): its running job waits for it until the scheduler drops it "
                    "(distributed.scheduler.worker-ttl, 5 min by default) and runs it on "
                    "another worker; Ctrl-C stops the sweep, keeping its finished records",
                    address,
                    now - before[1],
                )
