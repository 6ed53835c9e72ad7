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

import fcntl
import hashlib
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from stabctl._jit.cache import package_digest
from stabctl.errors import InputError
from stabctl.locking import private_file

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
    (one ``{"key": ..., "result": ...}`` a line).

    Parameters
    ----------
    path : str or os.PathLike
        The file; its directory is made (mode 0700) when missing.

    Attributes
    ----------
    path : Path
    results : dict
        Key -> result of every job kept.
    n_read, n_reused, n_written, n_damaged : int
        Results read from the file when opened, handed back instead of a run, written by
        this plan, and lines passed over as not whole (a writer killed while writing).

    Raises
    ------
    InputError
        The file or its directory belongs to another user or may be written by others
        than its owner, is not a regular file, is larger than MAX_MEMO_BYTES, or cannot
        be made or read; each naming it.
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self.results: dict[str, Any] = {}
        self.n_read = self.n_reused = self.n_written = self.n_damaged = 0
        private_file(self.path)
        self._read()

    def _read(self) -> None:
        """Load the file's whole lines (a missing file holds nothing)."""
        try:
            with open(self.path, "rb") as fh:
                size = os.fstat(fh.fileno()).st_size
                if size > MAX_MEMO_BYTES:
                    raise InputError(
                        f"{self.path}: {size} bytes, more than a plan's simulations take "
                        f"(at most {MAX_MEMO_BYTES}): not read"
                    )
                lines = fh.read().splitlines()
        except FileNotFoundError:
            return
        except OSError as exc:
            raise InputError(f"{self.path}: cannot be read ({exc.strerror})") from None
        for line in lines:
            try:
                rec = json.loads(line)
                self.results[rec["key"]] = rec["result"]
            except (ValueError, TypeError, KeyError, RecursionError):
                self.n_damaged += 1
        self.n_read = len(self.results)

    def add(self, key: str, result: Any) -> None:
        """Append one finished job's result (one write of a whole line, under an exclusive
        lock of the file, so that two plans of one case never interleave lines).

        Parameters
        ----------
        key : str
            `job_key` of the job.
        result : JSON-able
            Its result.
        """
        line = json.dumps({"key": key, "result": result}, default=_jsonable) + "\n"
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            os.write(fd, line.encode())
        finally:
            os.close(fd)
        self.results[key] = result
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
            The same signature; ``done`` is told of the jobs run only.
        """

        def mapped(func, jobs, done=None):
            keys = [job_key(func, j) for j in jobs]
            todo = [i for i, k in enumerate(keys) if k not in self.results]
            self.n_reused += len(jobs) - len(todo)

            def finished(k, n, i, result):
                self.add(keys[todo[i]], result)
                if done is not None:
                    done(k, n, i, result)

            if todo:
                run_map(func, [jobs[i] for i in todo], done=finished)
            return [_loaded(self.results[k]) for k in keys]

        return mapped

    def remove(self) -> None:
        """Remove the file (the plan has ended: nothing to resume)."""
        self.path.unlink(missing_ok=True)

    def kept(self) -> str:
        """What an interrupted plan keeps, in words (the CLI's "interrupted:" line)."""
        n = len(self.results)
        if not n:
            return f"no simulation had finished, so nothing is kept (in {self.path})"
        return (
            f"{n} finished simulation job(s) are kept in {self.path}; the same command "
            "runs only the others"
        )


def _jsonable(x):
    """numpy scalars and arrays as JSON (a result is made of floats, ints, lists)."""
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"{type(x).__name__} is not JSON-able")


def _loaded(result):
    """A result as read back (a fresh copy: the plan may change what it is handed)."""
    return json.loads(json.dumps(result, default=_jsonable))


__all__ = ["MAX_MEMO_BYTES", "Memo", "job_key"]
