"""Standard output of the `stabctl` command: a write that fails there is an error of its own.

A command's results go to stdout (a table, ``--json``); when they cannot be written the
command must not end with exit status 0, nor blame a file: stdout closed (``>&-``), a
full disk (``> /dev/full``) end with one line ``error: cannot write to standard output
(stdout): <reason>`` and exit status 2 (:func:`checked_stdout`, :func:`cannot_write`).  A
closed pipe (``stabctl cases | head``) stays the quiet end it is
(:func:`stabctl.cli.options.reports_errors`).

Standard output is replaced for the run by a stream over file descriptor 1 whose failed
writes raise :class:`StdoutError` (a write of a closed descriptor raises one too, and
/dev/null holds descriptor 1 meanwhile, so that no file the command opens gets it, nor
its child processes' output).  Only the process's own stdout is replaced: a caller's
(click's ``CliRunner``, pytest's capture) is left alone.
"""

from __future__ import annotations

import errno
import io
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager

import click


class StdoutError(OSError):
    """A write or flush of standard output failed (other than a closed pipe)."""


class _Stdout(io.FileIO):
    """File descriptor 1 whose failed writes raise `StdoutError`; after `discard`, every
    write is taken and dropped (what was not written when an error was said)."""

    def __init__(self, closed: bool):
        super().__init__(1, "wb", closefd=False)
        self.closed_at_start = closed
        self.discarding = False

    def write(self, data):
        """Write `data` (bytes-like) to descriptor 1 (io.RawIOBase.write)."""
        if self.discarding:
            return memoryview(data).nbytes
        if self.closed_at_start:
            raise StdoutError(errno.EBADF, "it is closed")
        try:
            return super().write(data)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise StdoutError(exc.errno, exc.strerror or str(exc)) from None


def cannot_write(exc: OSError) -> str:
    """The error line of a failed write to standard output, the unwritten rest dropped.

    Parameters
    ----------
    exc : OSError
        The failure (a `StdoutError`).

    Returns
    -------
    str
        ``"error: cannot write to standard output (stdout): <reason>"``.
    """
    raw = getattr(getattr(sys.stdout, "buffer", None), "raw", None)
    if isinstance(raw, _Stdout):
        raw.discarding = True
    return f"error: cannot write to standard output (stdout): {exc.strerror or exc}"


@contextmanager
def checked_stdout() -> Iterator[None]:
    """Run the block with a checked standard output (module docstring): flushed at the
    end, and a write or flush that fails, there or in the block, said in one line with
    exit status 2 (``SystemExit``).

    Yields
    ------
    None
    """
    previous = sys.stdout
    if previous is not sys.__stdout__:  # a caller's stream (CliRunner, pytest)
        yield
        return
    try:
        os.fstat(1)
        closed = False
    except OSError:
        closed = True
    if closed:  # descriptor 1 held by /dev/null: no file opened now gets it
        null = os.open(os.devnull, os.O_WRONLY)
        if null != 1:
            os.dup2(null, 1)
            os.close(null)
    elif previous is not None:
        previous.flush()
    raw = _Stdout(closed)
    sys.stdout = io.TextIOWrapper(
        io.BufferedWriter(raw),
        encoding=getattr(previous, "encoding", None) or "utf-8",
        errors=getattr(previous, "errors", None) or "strict",
        line_buffering=bool(getattr(previous, "line_buffering", False)),
    )
    try:
        try:
            yield
        except SystemExit as exc:
            if exc.code in (0, None):
                sys.stdout.flush()
            raise
        else:
            sys.stdout.flush()
    except StdoutError as exc:
        click.echo(cannot_write(exc), err=True)
        sys.exit(2)
    finally:
        raw.discarding = True  # nothing more to say: the stream's own last flush is quiet
        sys.stdout = previous
