"""`python -m stabctl`, the `stabctl` command's entry point: signals handled from the
moment it starts.

Starting a command imports click, numpy, numba and the command's modules (about a second
and more); the command's own handling of Ctrl-C, SIGTERM and SIGHUP (one ``interrupted:``
line, exit status 128 + the signal's number: `stabctl.cli.options.reports_errors`) comes
after.  A signal before it printed a Python traceback ending in KeyboardInterrupt
(Ctrl-C), or killed the process without a word (SIGTERM).  `main` installs a minimal
handler first, with nothing but the standard library imported, so that a signal at any
time before the command's handlers (or after them, while the process ends) ends it the
same way: one ``interrupted:`` line, nothing done, exit status 130 (SIGINT), 143
(SIGTERM) or 129 (SIGHUP).  A signal the process was started with ignored
(``nohup``, a background job's SIGINT) stays ignored.

That moment is after the interpreter's own start-up (about a tenth of a second in which
Python imports `site` and the installation's path hooks, before this module runs): a
signal then is Python's to handle, and no code of stabctl can: SIGINT ends with Python's
"Fatal Python error: init_import_site" or a KeyboardInterrupt traceback (exit status 1),
SIGTERM and SIGHUP kill the process without a word.

`main` is the console script (``stabctl = stabctl.__main__:main``), what ``python -m
stabctl`` and ``python -m stabctl.cli`` run; `stabctl.cli.main` (the click group) is
imported inside.
"""

from __future__ import annotations

import os
import shlex
import signal
import sys


class EarlyInterrupt(BaseException):
    """A signal that came before the command's own handlers (a BaseException but not a
    KeyboardInterrupt: click turns the latter into ``Aborted!`` and exit status 1).

    Parameters
    ----------
    signum : int
        The signal's number.
    """

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = int(signum)


#: the signals `_early` received (an import may turn the exception it raises into
#: another error, e.g. numba's ``RuntimeError: Error calling __set_name__``, or swallow
#: it: the record still ends the process as the signal does)
_received: list[int] = []


def _early(signum, frame):
    """Remember the signal and raise `EarlyInterrupt` (the handler of `main`)."""
    _received.append(int(signum))
    raise EarlyInterrupt(signum)


#: read by `stabctl.cli.options` (which installs its own SIGINT handler only in place of
#: Python's default or this one, and ends the command at once on a signal this one
#: received but could not raise: `_unraisable`)
_early.stabctl_early = True  # type: ignore[attr-defined]
_early.received = _received  # type: ignore[attr-defined]


def _unraisable(previous):
    """The ``sys.unraisablehook`` from the start: an `EarlyInterrupt` raised where Python
    cannot raise it (an import lock's weakref callback, a finaliser) printed "Exception
    ignored in ... Traceback ... EarlyInterrupt: 1" and was dropped.  It is dropped
    without a word, the signal remembered (`_received`): `main` ends on it after the
    command's import, `stabctl.cli.options` when the command starts.  Anything else goes
    to `previous`."""

    def hook(unraisable):
        if not isinstance(unraisable.exc_value, EarlyInterrupt):
            previous(unraisable)

    return hook


#: the signals handled from the start: those a command ends on
_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")


def install() -> None:
    """Install `_early` for SIGINT (in place of Python's default handler), SIGTERM and
    SIGHUP (in place of the default action); an ignored signal stays ignored; and the
    hook that keeps an `EarlyInterrupt` Python could not raise quiet (`_unraisable`)."""
    sys.unraisablehook = _unraisable(sys.unraisablehook)
    for name in _SIGNALS:
        sig = getattr(signal, name, None)
        if sig is None:  # pragma: no cover - SIGHUP on Windows
            continue
        now = signal.getsignal(sig)
        if now is signal.default_int_handler or now is signal.SIG_DFL:
            signal.signal(sig, _early)


def _ignore_all() -> None:
    """Ignore the signals from now on: the process is ending (the interpreter's own
    shutdown puts back their default action, which killed it without its status)."""
    for name in _SIGNALS:
        sig = getattr(signal, name, None)
        if sig is not None and signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, signal.SIG_IGN)


#: the exit statuses of a command a signal ended (`_end`, `stabctl.cli.options`)
_SIGNAL_STATUSES = frozenset(128 + getattr(signal, n, 0) for n in _SIGNALS) - {128}


def _quiet_finalisers() -> None:
    """Drop what finalisers raise from now on: the process ends on a signal, which may
    have cut an object's construction short (llvmlite's ``OutputString`` without its
    ``_owned``), and its ``__del__`` at exit printed "Exception ignored ... Traceback"
    under the ``interrupted:`` line."""
    sys.unraisablehook = lambda unraisable: None


def _end(signum: int) -> None:
    """Say that the command was interrupted before it started and exit 128 + signum."""
    _ignore_all()
    _quiet_finalisers()
    argv = shlex.join(["stabctl", *sys.argv[1:]])
    line = f"interrupted: nothing is kept; run again with: {argv}\n"
    try:
        sys.stderr.flush()
        os.write(2, line.encode())
    except OSError:  # stderr closed: the status alone says it
        pass
    sys.exit(128 + signum)


def _hold_closed_stderr() -> None:
    """A process started with descriptor 2 closed (``2>&-``, a daemon) has no
    ``sys.stderr`` (None), or one on whatever file took the free descriptor before Python
    started (pyenv's shim script, read-only): the progress bars of `screen` and
    `sweep-cct` failed on it, exit status 1, nothing written or said.  The descriptor is
    then held by /dev/null, so that no file the command opens takes it (a records file
    written into by every warning), and ``sys.stderr`` writes there: the command runs,
    its messages go nowhere, as asked."""
    import fcntl

    try:
        if fcntl.fcntl(2, fcntl.F_GETFL) & os.O_ACCMODE != os.O_RDONLY:
            return  # a stream that takes writes
    except OSError:  # closed
        pass
    null = os.open(os.devnull, os.O_WRONLY)
    if null != 2:
        os.dup2(null, 2)
        os.close(null)
    sys.stderr = open(2, "w", closefd=False)  # noqa: SIM115 - the process's own stream


def main() -> None:
    """Run the `stabctl` command line with signals handled from the start (module
    docstring)."""
    _hold_closed_stderr()
    install()
    try:
        try:
            from stabctl.cli import main as cli_main
        except Exception:  # an extension module's start that the signal made fail
            if _received:  # (scipy's "ImportError: initialization failed")
                _end(_received[0])
            raise
        if _received:  # raised inside an import that turned it into something else
            _end(_received[0])
        cli_main()
    except EarlyInterrupt as exc:
        _end(exc.signum)
    except SystemExit as exc:  # the command's own status
        if exc.code in _SIGNAL_STATUSES:  # it ended on a signal (`reports_errors`)
            _quiet_finalisers()
        raise
    finally:
        _ignore_all()  # done: a signal now leaves the command's status as it is


if __name__ == "__main__":  # pragma: no cover
    main()
