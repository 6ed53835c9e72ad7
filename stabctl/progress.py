"""Progress of long work, reported one way everywhere.

A function that reports progress takes ``progress``, a callable(str) told one line per
step; where it is None the lines go to the `logging` logger of the function's module at
level INFO (``logging.getLogger(__name__)``), which the command line shows on stderr
(`stabctl.cli`) and a library user shows or silences as any logger.  Batches report
through two context managers:

- `Heartbeat`: such a callable that also repeats its latest status whenever nothing was
  said for HEARTBEAT_S, so that a long batch of runs is never silent;
- `bar`: a tqdm bar on stderr, one step per job, or nothing when asked to be silent;
  a line said while one is shown goes above it (`bars_cleared`), not onto its line.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable
from contextlib import AbstractContextManager

from tqdm import tqdm

#: Longest silence of a `Heartbeat` while it has a status (s).
HEARTBEAT_S = 8.0


class Heartbeat:
    """A progress callable that repeats its latest status (`note`) whenever nothing was
    said for `every` seconds (a daemon thread, from entering to leaving the context).

    Parameters
    ----------
    say : callable(str) or None
        Where the lines go; None: nowhere (no thread either).
    line : callable(str) -> str, optional
        The repeated line of a status; default ``"... <status>"``.
    every : float, optional
        Longest silence, s; default HEARTBEAT_S.
    """

    def __init__(
        self,
        say: Callable[[str], None] | None,
        line: Callable[[str], str] = "... {}".format,
        every: float = HEARTBEAT_S,
    ):
        self._say, self._line, self._every = say, line, every
        self.status, self._last = "", time.monotonic()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    def __enter__(self) -> Heartbeat:
        if self._say is not None:
            self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()

    def __call__(self, msg: str) -> None:
        """Say msg (one line) now."""
        with self._lock:
            self._last = time.monotonic()
        if self._say is not None:
            self._say(msg)

    def note(self, status: str) -> None:
        """The status repeated from now on (not said now)."""
        self.status = status

    def _loop(self) -> None:
        while not self._stop.wait(0.5):
            if self.status and time.monotonic() - self._last >= self._every:
                self(self._line(self.status))


def bar(total: int, desc: str, show: bool = True, unit: str = "job") -> tqdm:
    """A tqdm bar of `total` steps (``update()`` one) on stderr, a context manager;
    show False: silent (the same object, disabled)."""
    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, disable=not show)


def bars_cleared() -> AbstractContextManager:
    """A context manager during which the progress bars on stderr (`bar`) are cleared, and
    after which they are drawn again: a line written to stderr inside it stands on a line
    of its own above them (written beside a bar, it was appended to the bar's line).

    Returns
    -------
    contextlib.AbstractContextManager
        tqdm's ``external_write_mode`` for stderr.
    """
    return tqdm.external_write_mode(file=sys.stderr)
