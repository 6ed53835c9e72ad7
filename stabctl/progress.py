"""Progress of long work, reported one way everywhere.

A function that reports progress takes ``progress``, a callable(str) told one line per
step; where it is None the lines go to the `logging` logger of the function's module at
level INFO (``logging.getLogger(__name__)``), which the command line shows on stderr
(`stabctl.cli`) and a library user shows or silences as any logger.  Batches report
through two context managers:

- `Heartbeat`: such a callable that also repeats its latest status whenever nothing was
  said for HEARTBEAT_S, so that a long batch of runs is never silent; a status may be
  a callable, worked out again at each repeat (`BatchClock.line`: jobs done and the time
  left, whose clock moves between two finished jobs);
- `bar`: a tqdm bar on stderr, one step per job, or nothing when asked to be silent;
  a line said while one is shown goes above it (`bars_cleared`), not onto its line.  On
  a stderr that is no terminal (a log file) it is drawn again every LOG_INTERVAL_S while
  no job ends, its rate the mean since it began, and its last line drawn once.

A long simulation run shows its own bar, of simulated time, when a caller asked for it
(`runs_shown`, the ``simulate`` command) and the run lasts longer than RUN_SHOWN_AFTER_S:
the run asks `run_progress` for it and tells it the simulated time at each of its pauses.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager

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
        self.status: str | Callable[[], str] = ""
        self._last = time.monotonic()
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

    def note(self, status: str | Callable[[], str]) -> None:
        """The status repeated from now on (not said now): a line, or a callable giving
        it at each repeat."""
        self.status = status

    def _loop(self) -> None:
        while not self._stop.wait(0.5):
            if self.status and time.monotonic() - self._last >= self._every:
                status = self.status() if callable(self.status) else self.status
                self(self._line(status))


class BatchClock:
    """How far a batch of `n` jobs is, as a line worked out when asked (`line`, a
    `Heartbeat` status): jobs done of n (the percentage rounded down: 100 % only when
    every job is done) and the time left at the pace of the jobs that finished, counted
    from the first finish the batch was told of (`done`), so that a batch waiting behind
    another's in a shared pool, or one whose kept jobs come back at once, does not take
    its waiting for its pace; the time left goes down between finishes, and once spent,
    the line says how long the jobs left have run past it instead of repeating it.

    Parameters
    ----------
    n : int
        Jobs in the batch.
    clock : callable, optional
        Seconds of a monotonic clock; default time.monotonic.
    """

    def __init__(self, n: int, clock: Callable[[], float] = time.monotonic):
        self.n, self.k, self._clock = n, 0, clock
        self.t0 = clock()
        self._base: tuple[int, float] | None = None  # (k, t) at the first finish told
        self._t_last = self.t0

    def done(self, k: int, *_) -> None:
        """k of the n jobs are done (a `stabctl.parallel.worker_pool` map's ``done``)."""
        now = self._clock()
        if self._base is None:
            self._base = (k, now)
        self.k, self._t_last = k, now

    def line(self) -> str:
        """'k of n job(s) done (p%)' and, while jobs are left, the time left (`left`)."""
        share = math.floor(100 * self.k / self.n) if self.n else 100
        head = f"{self.k} of {self.n} job(s) done ({share}%)"
        return head if self.k >= self.n else f"{head}, {self.left()}"

    def left(self) -> str:
        """The time left ('about 41 s left'), or since when nothing ended."""
        now, n, k = self._clock(), self.n, self.k
        if k >= n:
            return "none left"
        if self._base is None:
            return f"none ended in {now - self.t0:.0f} s"
        k0, t0 = self._base
        if k == k0:
            return "the time left known at the next job's end"
        pace = (self._t_last - t0) / (k - k0)  # s a job, the pool's workers together
        left = pace * (n - k) - (now - self._t_last)
        if left >= 0.5:
            return f"about {left:.0f} s left"
        gave = pace * (n - k)
        return (
            f"the {n - k} left running {now - self._t_last:.0f} s since the last ended "
            f"(the pace so far gave them {f'{gave:.0f} s' if gave >= 1 else 'under 1 s'})"
        )


#: seconds between two redraws of a bar on a stderr that is no terminal (a log file): a
#: screening of 5 206 faults drew about 10 000 frames onto one line of its log
LOG_INTERVAL_S = 30.0


def bar(total: int, desc: str, show: bool = True, unit: str = "job") -> tqdm:
    """A tqdm bar of `total` steps (``update()`` one) on stderr, a context manager;
    show False: silent (the same object, disabled).  On a stderr that is no terminal (a
    log file) it is `_LoggedBar`: drawn at most every LOG_INTERVAL_S as steps come, and
    again every LOG_INTERVAL_S while none comes, its time left from the mean rate since it
    began, its last line once."""
    try:
        terminal = sys.stderr.isatty()
    except (AttributeError, ValueError):  # closed or replaced by an object without it
        terminal = False
    return (tqdm if terminal else _LoggedBar)(
        total=total,
        desc=desc,
        unit=unit,
        file=sys.stderr,
        disable=not show,
        mininterval=0.1 if terminal else LOG_INTERVAL_S,
        maxinterval=10.0 if terminal else LOG_INTERVAL_S,
        **({} if terminal else {"bar_format": _LoggedBar.FORMAT, "smoothing": 0.0}),
    )


class _LoggedBar(tqdm):
    """A bar in a log file (`bar`): a daemon thread draws it again whenever it was not
    drawn for LOG_INTERVAL_S (a long job kept its line for minutes: the elapsed time and
    the time left stood still); its time left is a `BatchClock`'s (tqdm's, from the
    rate at the last step, said 4 s left of a sweep's last three jobs for two minutes);
    the step that completes it is drawn by its closing only (it was drawn twice, the
    two lines' rates differing)."""

    FORMAT = "{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}, {left}, {rate_fmt}{postfix}]"

    def __init__(self, *args, **kwargs):
        self._clock = BatchClock(kwargs.get("total") or 0)
        super().__init__(*args, **kwargs)
        self._halt = threading.Event()
        if not self.disable:
            threading.Thread(target=self._redraw, daemon=True).start()

    def _redraw(self) -> None:
        while not self._halt.wait(1.0):
            drawn = float(getattr(self, "last_print_t", 0.0))
            if self._time() - drawn >= LOG_INTERVAL_S:
                self.refresh()
                self.last_print_t = self._time()

    @property
    def format_dict(self) -> dict:
        """tqdm's, with ``left``: the clock's time left."""
        return {**super().format_dict, "left": self._clock.left()}

    def update(self, n: float | None = 1) -> bool | None:
        """n steps more; the last (the bar full) drawn when the bar closes."""
        self._clock.done(int(self.n + (n or 0)))
        if not self.disable and self.total is not None and self.n + (n or 0) >= self.total:
            self.n += n or 0
            return None
        return super().update(n)

    def close(self) -> None:
        """Stop redrawing, then draw the last line (tqdm's close)."""
        if hasattr(self, "_halt"):
            self._halt.set()
        super().close()


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


#: wall time a shown run goes before its bar appears (`runs_shown`), s
RUN_SHOWN_AFTER_S = 3.0

#: the delay of the bar of runs shown now (`runs_shown`), None: runs are not shown
_RUNS_SHOWN: list[float] = []


@contextmanager
def runs_shown(after_s: float = RUN_SHOWN_AFTER_S) -> Iterator[None]:
    """Within the block, a simulation run (`stabctl.dynamics.driver.Simulator.run`) that
    lasts longer than `after_s` of wall time shows a bar of its simulated time on stderr
    (the fraction done, the rate, the time left), cleared when it ends.

    Parameters
    ----------
    after_s : float, optional
        Wall time before a run's bar appears, s; default RUN_SHOWN_AFTER_S.

    Yields
    ------
    None
    """
    _RUNS_SHOWN.append(after_s)
    try:
        yield
    finally:
        _RUNS_SHOWN.pop()


class RunProgress:
    """The bar of one run (`run_progress`): called with the simulated time reached,
    `close` at the end.

    Parameters
    ----------
    t_start : float
        Where the run stands, s (its rate and time left count from there).
    t_end : float
        The run's end, s.
    after_s : float
        Wall time before the bar appears, s.
    """

    def __init__(self, t_start: float, t_end: float, after_s: float):
        self._bar = tqdm(
            total=round(t_end, 6),
            initial=round(t_start, 6),
            desc="simulated",
            unit="s",
            file=sys.stderr,
            delay=after_s,
            mininterval=0.0,  # drawn at each of the run's pauses (a quarter second apart)
            leave=False,
            bar_format="{desc} {n:.2f} of {total:g} s |{bar}| {percentage:3.0f}% "
            "[{elapsed} elapsed, {remaining} left]",
        )

    def __call__(self, t: float) -> None:
        """The run has reached t (s)."""
        self._bar.update(round(t, 6) - self._bar.n)

    def close(self) -> None:
        """The run ended (or was interrupted): the bar cleared."""
        self._bar.close()


def run_progress(t_start: float, t_end: float) -> RunProgress | None:
    """The bar of a run from `t_start` to `t_end` (s) inside `runs_shown`, None outside
    (or outside the main thread).

    Parameters
    ----------
    t_start : float
        Where the run stands, s.
    t_end : float
        The run's end, s.

    Returns
    -------
    RunProgress or None
    """
    if not _RUNS_SHOWN or threading.current_thread() is not threading.main_thread():
        return None
    return RunProgress(t_start, t_end, _RUNS_SHOWN[-1])
