"""The `stabctl` command's entry point: signals handled from the first instant.

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

This module is the console script (``stabctl = stabctl._entry:main``) and what
``python -m stabctl`` runs; `stabctl.cli.main` (the click group) is imported inside.
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


def _early(signum, frame):
    """Raise `EarlyInterrupt` (the handler of `main`)."""
    raise EarlyInterrupt(signum)


#: read by `stabctl.cli.options` (which installs its own SIGINT handler only in place of
#: Python's default or this one)
_early.stabctl_early = True  # type: ignore[attr-defined]

#: the signals handled from the start: those a command ends on
_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")


def install() -> None:
    """Install `_early` for SIGINT (in place of Python's default handler), SIGTERM and
    SIGHUP (in place of the default action); an ignored signal stays ignored."""
    for name in _SIGNALS:
        sig = getattr(signal, name, None)
        if sig is None:  # pragma: no cover - SIGHUP on Windows
            continue
        now = signal.getsignal(sig)
        if now is signal.default_int_handler or now is signal.SIG_DFL:
            signal.signal(sig, _early)


def _ignore_all() -> None:
    """Ignore further signals while the process says why it ends."""
    for name in _SIGNALS:
        sig = getattr(signal, name, None)
        if sig is not None:
            signal.signal(sig, signal.SIG_IGN)


def main() -> None:
    """Run the `stabctl` command line with signals handled from the start (module
    docstring)."""
    install()
    try:
        from stabctl.cli import main as cli_main

        cli_main()
    except EarlyInterrupt as exc:
        _ignore_all()
        argv = shlex.join(["stabctl", *sys.argv[1:]])
        line = f"interrupted: nothing is kept; the work starts again; resume with: {argv}\n"
        try:
            sys.stderr.flush()
            os.write(2, line.encode())
        except OSError:  # stderr closed: the status alone says it
            pass
        sys.exit(128 + exc.signum)
