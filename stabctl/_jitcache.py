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
import os
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


def cache_dirs() -> list[Path]:
    """The directories numba keeps stabctl's compiled kernels in: each source directory's
    ``__pycache__``, or, when ``NUMBA_CACHE_DIR`` is set, its ``<dir name>_<sha1 of the
    directory path>`` directory there (numba's ``UserProvidedCacheLocator``)."""
    sources = sorted({f.parent for f in _PKG.rglob("*.py")})
    root = numba.config.CACHE_DIR
    if not root:
        return [d / "__pycache__" for d in sources]
    return [Path(root) / f"{d.name}_{hashlib.sha1(os.path.abspath(d).encode()).hexdigest()}"
            for d in sources]


def clear_cache() -> int:
    """Delete stabctl's compiled kernels (``*.nbi``, ``*.nbc`` in `cache_dirs`), as after
    a fresh installation; returns how many files."""
    files = [f for d in cache_dirs() for f in (*d.glob("*.nbi"), *d.glob("*.nbc"))]
    for f in files:
        f.unlink(missing_ok=True)
    return len(files)


def simulator_cached() -> bool:
    """Whether the simulator's main kernel (`stabctl.dynamics.simulation.integrate`, which
    links the whole model) is in the cache, i.e. a new process loads it instead of
    compiling it."""
    return any(any(d.glob("simulation.integrate-*.nbi")) for d in cache_dirs()
               if d.name.startswith("dynamics") or d.parent.name == "dynamics")


def ensure_fresh_cache() -> None:
    """Delete stabctl's compiled kernels (`clear_cache`) if any source file changed since
    they were written (the stamp sits beside the first cache directory).  A read-only
    installation is left alone (numba then compiles in memory)."""
    stamp = cache_dirs()[0] / "numba-sources.sha256"
    now = source_digest()
    try:
        if stamp.exists() and stamp.read_text() == now:
            return
        clear_cache()
        stamp.parent.mkdir(parents=True, exist_ok=True)
        stamp.write_text(now)
    except OSError:
        pass


def on_first_compile(notify, still=None, every_s: float = 10.0):
    """Call ``notify()`` once, when numba starts compiling the first stabctl kernel of
    this process (numba's event API, ``numba:compile``); loading cached kernels does not
    count.  Then, whenever compiling has gone on for `every_s` seconds, call
    ``still(seconds since that compile began)``, and again every `every_s` seconds (also
    across compiles that follow one another), so that a long compile is never a silent
    wait.

    Parameters
    ----------
    notify : callable
        Called with no arguments.
    still : callable, optional
        Called with the seconds (float) the compile under way has lasted, from a
        background thread.
    every_s : float
        Interval of the `still` calls (s).

    Returns
    -------
    callable
        Stops listening (no call after it).
    """
    import threading
    import time

    from numba.core import event

    class _Compiles(event.Listener):
        depth, noticed, t_begin, last = 0, False, 0.0, 0.0

        def on_start(self, ev):
            if self.depth == 0:              # a compile begins (numba's overloads nest)
                self.t_begin = now = time.perf_counter()
                if now - self.last > every_s:   # else it follows the last one: keep the
                    self.last = now             # beat, never more than every_s apart
            self.depth += 1
            if not self.noticed and ev.data["dispatcher"].py_func.__module__.startswith(
                    "stabctl."):
                self.noticed = True
                notify()
                if still is not None:
                    threading.Thread(target=self.beat, daemon=True).start()

        def on_end(self, ev):
            self.depth -= 1

        def beat(self):
            while not halt.wait(min(1.0, every_s)):
                now = time.perf_counter()
                if self.depth > 0 and now - self.last >= every_s:
                    self.last = now
                    still(now - self.t_begin)

    listener, halt = _Compiles(), threading.Event()

    def stop():
        if not halt.is_set():
            halt.set()
            event.unregister("numba:compile", listener)

    event.register("numba:compile", listener)
    return stop


ensure_fresh_cache()

#: ``numba.njit`` with ``cache=True``: the decorator of every stabctl kernel.
njit = functools.partial(numba.njit, cache=True)
