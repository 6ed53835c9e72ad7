"""numba's ``njit`` with an on-disk cache that stays consistent across stabctl's modules.

numba invalidates a cached function only when its own source file changes, not when a
function it inlines from another module does (numba documentation, "Cache invalidation").
Our kernels call across modules and subpackages, so before the first kernel is compiled we
hash every stabctl source file (all subpackages) and delete the cached kernels of the
whole package whenever the hash differs from the one they were compiled with.

Every compiled kernel of stabctl is declared with :func:`njit` from this module; importing
``stabctl`` itself compiles nothing and touches no file.
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

import numba

_PKG = Path(__file__).resolve().parent


def source_digest() -> str:
    """SHA-256 over the names and contents of every ``*.py`` file of the package."""
    digest = hashlib.sha256()
    for f in sorted(_PKG.rglob("*.py")):
        digest.update(str(f.relative_to(_PKG)).encode())
        digest.update(f.read_bytes())
    return digest.hexdigest()


def ensure_fresh_cache() -> None:
    """Delete stabctl's numba cache files (``*.nbi``, ``*.nbc`` in every ``__pycache__``)
    if any source file changed since they were written.  A read-only installation is left
    alone (numba then compiles in memory)."""
    stamp = _PKG / "__pycache__" / "numba-sources.sha256"
    now = source_digest()
    try:
        if stamp.exists() and stamp.read_text() == now:
            return
        for cache in _PKG.rglob("__pycache__"):
            for f in list(cache.glob("*.nbi")) + list(cache.glob("*.nbc")):
                f.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(now)
    except OSError:
        pass


def on_first_compile(notify):
    """Call ``notify()`` once, when numba starts compiling the first stabctl kernel of
    this process (numba's event API, ``numba:compile``); loading cached kernels does not
    count.

    Parameters
    ----------
    notify : callable
        Called with no arguments.

    Returns
    -------
    callable
        Stops listening (no call after it).
    """
    from numba.core import event

    class _Once(event.Listener):
        done = False

        def on_start(self, ev):
            if not self.done and ev.data["dispatcher"].py_func.__module__.startswith("stabctl."):
                self.stop()
                notify()

        def on_end(self, ev):
            pass

        def stop(self):
            if not self.done:
                self.done = True
                event.unregister("numba:compile", self)

    listener = _Once()
    event.register("numba:compile", listener)
    return listener.stop


ensure_fresh_cache()

#: ``numba.njit`` with ``cache=True``: the decorator of every stabctl kernel.
njit = functools.partial(numba.njit, cache=True)
