"""Output directories a command creates for its files: gone again when the command ends
before writing into them.

A report writer (``stabctl eig --report --out-dir NEW``) creates its directory and then
works for seconds (figures) before its first file lands there; interrupted (Ctrl-C,
SIGTERM) or failing in between, it must leave nothing behind, not even an empty
directory.  :func:`output_directory` creates the missing directories of a path and, when
the block it guards raises, removes those it created that are still empty.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["output_directory"]


@contextmanager
def output_directory(path: str | os.PathLike) -> Iterator[Path]:
    """Create directory `path` with its missing parents for the block; if the block
    raises (an exception or KeyboardInterrupt), remove again those created here that are
    still empty (innermost first) and re-raise.

    Parameters
    ----------
    path : str or path-like
        The output directory.

    Yields
    ------
    Path
        The directory, existing.

    Raises
    ------
    OSError
        The directory cannot be created (as `Path.mkdir`); whatever the block raises.
    """
    out = Path(path)
    missing = []
    p = out.absolute()
    while not p.exists():
        missing.append(p)
        p = p.parent
    out.mkdir(parents=True, exist_ok=True)
    try:
        yield out
    except BaseException:
        for d in missing:  # innermost first
            try:
                d.rmdir()
            except OSError:  # not empty (files written there) or gone: kept
                break
        raise
