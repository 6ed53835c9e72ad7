"""A placement's finished simulations kept across an interrupt (`Memo`).

`stabctl.placement.plan.plan` runs its simulations as JSON-able worker jobs
(`stabctl.placement.evaluation`: a contingency's CCT search at given ratings, a check run,
its gradient).  A `Memo` writes each job's result to a JSON-lines file the moment the job
finishes, keyed by the SHA-256 of the job's function and the job's canonical JSON (which
holds the case's digest, the ratings, the law and every setting its result depends on),
and hands the result back instead of running the job again.  A plan interrupted (Ctrl-C,
SIGTERM) and run again therefore redoes only the jobs that had not finished, and ends
with the same plan: the runs are deterministic and the results come back as they were
sent (floats written with their 17 digits).

The file holds JSON only (no pickle): what it can do is hand back a result.  `place`
keeps it in this user's cache directory (`stabctl.locking.kept_path`, mode 0700; one
that belongs to another user or that others may write is refused) and removes it when
the plan has ended.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import os
import warnings
from collections.abc import Callable
from typing import Any

from stabctl._jit.cache import package_digest
from stabctl.errors import InputError
from stabctl.locking import locked_at, private_file

#: the most bytes of a memo file read (a plan of ACTIVSg2000 keeps about 30 MB): a larger
#: one is refused (a damaged or foreign file), the plan then simulating everything
MAX_MEMO_BYTES = 512 << 20


def job_key(func: Callable, job: dict) -> str:
    """The key of a worker job: SHA-256 (hex) of the package's code
    (`stabctl._jit.cache.package_digest`: another stabctl's results are never reused),
    the job's function (module and name) and its canonical JSON (keys sorted).

    Parameters
    ----------
    func : callable
        The module-level function the job runs.
    job : dict
        Its JSON-able argument.

    Returns
    -------
    str
    """
    text = json.dumps(job, sort_keys=True, separators=(",", ":"), default=_jsonable)
    name = f"{package_digest()}\n{func.__module__}.{func.__qualname__}"
    return hashlib.sha256(f"{name}\n{text}".encode()).hexdigest()


class Memo:
    """The finished worker jobs of a plan, read from and written to one JSON-lines file
    (one ``{"key": ..., "sha": ..., "result": ...}`` a line, ``sha`` the SHA-256 of the
    key and the result's canonical JSON: a line edited or damaged is passed over, not
    handed back).  The file is held (an exclusive ``flock``) for as long as the memo is
    open, so that no two plans write it at once.

    Parameters
    ----------
    path : str or os.PathLike
        The file; it and its directory (mode 0700) are made when missing.

    Attributes
    ----------
    path : Path
    results : dict
        Key -> result of every job kept.
    n_read, n_reused, n_repeated, n_written, n_damaged : int
        Results read from the file when opened (an earlier, interrupted plan's); jobs
        handed back from those instead of a run; jobs handed back that this plan had run
        already (a repeat within the plan, not an earlier plan's work); results written
        by this plan; and lines passed over (not whole: a writer killed while writing; or
        not as written: edited).
    unwritable : str
        Why the file took no more results ('' while it takes them): a full disk, a quota;
        the plan goes on, its later results not kept (a RuntimeWarning says so once).

    Raises
    ------
    InputError
        The file or its directory belongs to another user or may be written by others
        than its owner, is not a regular file, is larger than MAX_MEMO_BYTES, cannot be
        made, read or written (a read-only file system), or is held by another running
        plan; each naming it.
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self._fd: int | None = None
        self.path = private_file(path)
        self.results: dict[str, Any] = {}
        self.n_read = self.n_reused = self.n_repeated = self.n_written = self.n_damaged = 0
        #: the keys read from the file when opened (`n_reused` counts those handed back)
        self._read_keys: frozenset[str] = frozenset()
        self.unwritable = ""
        self._removed = False
        self._fd = self._held()
        self._whole = self._read(self._fd)

    def _held(self) -> int:
        """A descriptor of the file holding its exclusive lock; the file locked is the one
        at the path (one its holder removed meanwhile is opened again).  Raises
        InputError: the file cannot be made or written, or is held by another plan
        (`MemoHeld`), or cannot be locked."""

        def refused(fd: int, exc: OSError) -> Exception:
            if isinstance(exc, BlockingIOError):
                return MemoHeld(
                    f"{self.path}: held by another plan of the same case and settings, running"
                )
            # a file system without locks (NFS without lockd)
            return InputError(f"{self.path}: cannot be locked ({exc.strerror})")

        flags = os.O_RDWR | os.O_APPEND | os.O_NOFOLLOW
        try:
            return locked_at(self.path, flags, 0o600, refused)
        except OSError as exc:  # the open's: refused's are InputErrors
            raise InputError(f"{self.path}: cannot be written ({exc.strerror})") from None

    def _read(self, fd: int) -> bool:
        """Load the file's whole lines whose sha matches; whether it ends with a whole
        line (an empty file does)."""
        size = os.fstat(fd).st_size
        if size > MAX_MEMO_BYTES:
            self.close()
            raise InputError(
                f"{self.path}: {size} bytes, more than a plan's simulations take (at most "
                f"{MAX_MEMO_BYTES}): not read"
            )
        try:
            text = os.pread(fd, size, 0) if size else b""
        except OSError as exc:
            self.close()
            raise InputError(f"{self.path}: cannot be read ({exc.strerror})") from None
        for line in text.splitlines():
            try:
                rec = json.loads(line)
                key, result = rec["key"], rec["result"]
                whole = rec["sha"] == _sha(key, result)
            except (ValueError, TypeError, KeyError, RecursionError):
                whole = False
            if whole:
                self.results[key] = result
            else:
                self.n_damaged += 1
        self.n_read = len(self.results)
        self._read_keys = frozenset(self.results)
        return not text or text.endswith(b"\n")

    def add(self, key: str, result: Any) -> None:
        """Append one finished job's result (one write of a whole line; after a line a
        killed writer left unfinished, a line end first).  A write the system refuses (a
        full disk, a quota) keeps the result for this plan only and stops writing
        (`unwritable`, one RuntimeWarning).

        Parameters
        ----------
        key : str
            `job_key` of the job.
        result : JSON-able
            Its result.
        """
        self.results[key] = result
        if self._fd is None or self.unwritable:
            return
        line = json.dumps(
            {"key": key, "sha": _sha(key, result), "result": result}, default=_jsonable
        )
        data = ("" if self._whole else "\n") + line + "\n"
        try:
            written = os.write(self._fd, data.encode())
        except OSError as exc:
            written, why = 0, exc.strerror or str(exc)
        else:
            why = "" if written == len(data.encode()) else "a short write (a full disk)"
        self._whole = not why
        if why:
            self.unwritable = why
            warnings.warn(
                f"{self.path} cannot be written ({why}): the plan goes on, its simulations "
                "from now on not kept (an interrupt then keeps only those before)",
                RuntimeWarning,
                stacklevel=2,
            )
            return
        self.n_written += 1

    def wrap(self, run_map: Callable) -> Callable:
        """``run_map(func, jobs, done=None)`` that hands back the kept results and runs
        only the other jobs on `run_map` (a `stabctl.parallel.worker_pool` map), keeping
        each result as its job finishes.

        Parameters
        ----------
        run_map : callable
            ``run_map(func, jobs, done=None) -> results`` in job order; ``done(k, n, i,
            result)`` called as each job finishes.

        Returns
        -------
        callable
            The same signature; ``done`` is told of the kept jobs at once, as
            ``done(kept, n)`` (no job index or result), then of each job run.
        """

        takes_done = "done" in inspect.signature(run_map).parameters

        def mapped(func, jobs, done=None):
            keys = [job_key(func, j) for j in jobs]
            todo = [i for i, k in enumerate(keys) if k not in self.results]
            reused = len(jobs) - len(todo)
            from_file = sum(k in self._read_keys for k in keys)
            self.n_reused += from_file
            self.n_repeated += reused - from_file

            def finished(k, n, i, result):  # as the caller's jobs count: reused ones done
                self.add(keys[todo[i]], result)
                if done is not None:
                    done(reused + k, len(jobs), todo[i], result)

            if todo and reused and done is not None:  # the kept jobs are done already
                done(reused, len(jobs))
            if todo:
                run = [jobs[i] for i in todo]
                out = run_map(func, run, done=finished) if takes_done else run_map(func, run)
                for i, result in zip(todo, out):  # a map that tells of none as it ends
                    if keys[i] not in self.results:
                        self.add(keys[i], result)
            return [_loaded(self.results[k]) for k in keys]

        return mapped

    def close(self) -> None:
        """Let the file go (its lock released), keeping it for the same plan run again."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> Memo:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:
        self.close()

    def remove(self) -> None:
        """Remove the file (the plan has ended: nothing to resume) and let it go."""
        if self._fd is not None:
            self.path.unlink(missing_ok=True)
            self._removed = True
        self.close()

    def __getstate__(self) -> dict:
        """A copy holds no descriptor (it is this process's): it reads nothing more,
        writes nothing and closes nothing."""
        return {**self.__dict__, "_fd": None}

    def kept(self) -> str:
        """What an interrupted plan keeps in its file, in words (the CLI's "interrupted:"
        line): the results read from it and written to it whole."""
        n = 0 if self._removed else self.n_read + self.n_written
        if not n:
            return f"no simulation had finished, so nothing is kept (in {self.path})"
        short = f" (later ones not: {self.unwritable})" if self.unwritable else ""
        return (
            f"{n} finished simulation job(s) are kept in {self.path}{short}; the same "
            "command runs only the others"
        )


class MemoHeld(InputError):
    """A memo file held by another running plan (`Memo`): the same plan started twice."""


def _sha(key: str, result) -> str:
    """The SHA-256 (hex) of a job's key and its result's canonical JSON: what a memo line
    carries, so that a line edited or damaged is not handed back."""
    text = json.dumps(result, sort_keys=True, separators=(",", ":"), default=_jsonable)
    return hashlib.sha256(f"{key}\n{text}".encode()).hexdigest()


def _jsonable(x):
    """numpy scalars and arrays as JSON (a result is made of floats, ints, lists)."""
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"{type(x).__name__} is not JSON-able")


def _loaded(result):
    """A result as read back (a fresh copy: the plan may change what it is handed)."""
    return json.loads(json.dumps(result, default=_jsonable))


__all__ = ["MAX_MEMO_BYTES", "Memo", "MemoHeld", "job_key"]
