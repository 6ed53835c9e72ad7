"""numba's ``njit`` with an on-disk cache that stays consistent across stabctl's modules.

numba invalidates a cached function only when its own source file changes, not when a
function it inlines from another module does (numba documentation, "Cache invalidation").
Our kernels call across modules and subpackages, so before the first kernel is compiled we
hash every stabctl source file (all subpackages) and delete the cached kernels of the
whole package whenever the hash differs from the one they were compiled with.

Every compiled kernel of stabctl is declared with :func:`njit` (callable from Python too)
or :func:`kernel` (called only from other kernels) from this module; importing ``stabctl``
itself compiles nothing and touches no file.
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import importlib
import os
import pickle
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numba
from numba.core import event
from numba.core.registry import CPUDispatcher

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


def cached(dispatcher) -> bool:
    """Whether a kernel has an entry in the on-disk cache (numba's index file of it), i.e.
    a new process loads it instead of compiling it (for the argument types it was compiled
    for; stale entries are gone, `ensure_fresh_cache`)."""
    py = dispatcher.py_func
    stem = f"{py.__module__.rsplit('.', 1)[-1]}.{py.__qualname__}-"
    return any(Path(dispatcher.stats.cache_path).glob(stem + "*.nbi"))


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


def _writable(directory: Path) -> bool:
    try:
        directory.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=directory):
            return True
    except OSError:
        return False


#: compiles under way in child processes (`compile_in_background`), by dispatcher name
_BACKGROUND: dict[str, tuple[subprocess.Popen, object]] = {}


def _name(dispatcher) -> str:
    return f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}"


def compile_in_background(dispatcher, argtypes, opt: int | None = None) -> bool:
    """Start compiling a kernel for given argument types in a child process, which writes
    it to the on-disk cache; `await_background` then waits for it and the kernel loads
    from the cache.  This process meanwhile compiles other kernels: the simulator's
    integrator (`stabctl.dynamics.simulation.integrate`) and the model's evaluation do not
    link each other (`stabctl.dynamics.model.call_evaluate`), so on two cores a cold first
    run compiles them side by side.

    Nothing is started (returns False) when the kernel is already compiled in this process
    or cached (`cached`), or a compile of it is under way, or its cache directory cannot be
    written (the child's work could not reach this process).  A child still running when
    this process exits is stopped (no orphan process).

    Parameters
    ----------
    dispatcher : numba dispatcher
        A kernel with ``cache=True`` defined at module level.
    argtypes : sequence of numba types
        Its argument types, e.g. ``[numba.typeof(a) for a in args]``.
    opt : int, optional
        LLVM optimisation level of the child (``NUMBA_OPT``, 0-3); default numba's (3).
        The kernel and the kernels it compiles with it are cached at that level.

    Returns
    -------
    bool
        Whether a child process was started.
    """
    name = _name(dispatcher)
    if (name in _BACKGROUND or dispatcher.signatures or cached(dispatcher)
            or not _writable(Path(dispatcher.stats.cache_path))):
        return False
    err = tempfile.TemporaryFile()
    env = dict(os.environ, **({} if opt is None else {"NUMBA_OPT": str(opt)}))
    proc = subprocess.Popen([sys.executable, "-m", "stabctl._jitcache",
                             dispatcher.py_func.__module__, dispatcher.py_func.__qualname__],
                            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=err,
                            env=env)
    proc.stdin.write(pickle.dumps(tuple(argtypes)))
    proc.stdin.close()
    _BACKGROUND[name] = (proc, err)
    atexit.register(_stop, proc)
    return True


def await_background(dispatcher) -> None:
    """Wait for the child process compiling `dispatcher` (`compile_in_background`), if
    one was started, so that its next call loads the kernel from the cache.  The wait is
    announced as a numba compile event (the CLI's notice and its heartbeat go on).  If
    the child failed, a RuntimeWarning gives its last error line and the kernel is
    compiled here, as without a child.
    """
    started = _BACKGROUND.pop(_name(dispatcher), None)
    if started is None:
        return
    proc, err = started
    if proc.poll() is None:
        data = {"dispatcher": dispatcher, "args": None, "return_type": None}
        event.start_event("numba:compile", data=data)
        try:
            proc.wait()
        finally:
            event.end_event("numba:compile", data=data)
    if proc.returncode != 0:
        err.seek(0)
        lines = err.read().decode(errors="replace").strip().splitlines() or ["no message"]
        warnings.warn(f"compiling {_name(dispatcher)} in a child process failed "
                      f"(exit {proc.returncode}: {lines[-1]}); compiling it here",
                      RuntimeWarning, stacklevel=2)
    err.close()


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        proc.wait()


ensure_fresh_cache()

#: ``numba.njit`` with ``cache=True``: the decorator of a kernel that Python code calls.
#: No C-callable (``cfunc``) wrapper: nothing takes a kernel's C address.
njit = functools.partial(numba.njit, cache=True, no_cfunc_wrapper=True)


class CompiledOnly(CPUDispatcher):
    """A numba dispatcher compiled without a Python entry point (`kernel`).  A call from
    Python (tests, a one-off check) goes through a compiled trampoline built on its first
    use, instead of jumping into the missing entry point."""

    def __call__(self, *args, **kwargs):
        if kwargs:
            raise TypeError(f"{self.py_func.__qualname__}: keyword arguments from Python "
                            "are not supported (a kernel for compiled callers)")
        trampoline = self.__dict__.get("_from_python")
        if trampoline is None:
            target = self
            if self.targetoptions.get("inline", "never") == "never":
                trampoline = numba.njit(lambda *a: target(*a))
            else:        # numba inlines no kernel into a call with *args: compile its source
                trampoline = numba.njit(self.py_func)
            self._from_python = trampoline
        return trampoline(*args)


def kernel(func=None, **options):
    """Decorator of a kernel called only from other kernels: ``numba.njit`` with
    ``cache=True`` and without the CPython and C wrappers that a call from Python needs.
    Each wrapper unpacks every argument (a NamedTuple of arrays field by field); leaving
    them out took about 4 s off a cold first simulation when it compiled in one process
    (39 -> 35 s on this 2-core machine).

    Parameters
    ----------
    func : callable, optional
        The function (``@kernel``), or None (``@kernel(inline="always")``).
    **options
        Further ``numba.njit`` options (e.g. ``inline="always"``).

    Returns
    -------
    CompiledOnly
        The dispatcher (a call from Python compiles a trampoline first).
    """
    def declare(f):
        dispatcher = numba.njit(f, cache=True, no_cpython_wrapper=True,
                                no_cfunc_wrapper=True, **options)
        dispatcher.__class__ = CompiledOnly
        return dispatcher

    return declare if func is None else declare(func)


@kernel
def assign(dst, src) -> None:
    """``dst[...] = src`` inside a kernel, element by element (arrays of one size, any
    layout; no check).  numba's slice assignment from an array compiles a formatter for
    its shape-mismatch message (f-strings, ``str.join``, integer reprs): about 2-3 s of
    a cold first call in every process that compiles one.  Kernels use this instead.

    Parameters
    ----------
    dst : ndarray
        Written in place (a view, e.g. ``x[k]`` or ``F[3:, 3:]``).
    src : ndarray
        Same size and element order (C order for more than one dimension).
    """
    for j in range(dst.size):
        dst.flat[j] = src.flat[j]


@kernel
def max_abs(a) -> float:
    """``np.max(np.abs(a))`` inside a kernel, without compiling numba's generic reduction
    (``np.max`` with its ``take`` helpers: about 0.3-0.4 s of every cold process that
    compiles one).  NaN propagates as in numpy: the first NaN is returned.

    Parameters
    ----------
    a : ndarray
        1-D, real or complex, not empty (numpy raises on an empty array; this returns 0).

    Returns
    -------
    float
        The largest magnitude, or NaN.
    """
    m = 0.0
    for j in range(a.size):
        v = abs(a[j])
        if v != v:
            return v
        if v > m:
            m = v
    return m


if __name__ == "__main__":       # the child of `compile_in_background`
    _module, _qualname = sys.argv[1:3]
    getattr(importlib.import_module(_module), _qualname).compile(
        pickle.load(sys.stdin.buffer))
