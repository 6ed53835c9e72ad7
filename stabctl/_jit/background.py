"""Compiling a kernel in a child process while this one compiles another.

The child writes the kernel to the on-disk cache (`stabctl._jit.cache`); this process waits
for it only when it needs the kernel (`await_background`) and then loads it.  Two kernels
that do not link each other (the integrator and the model's evaluation, which the
integrator calls by address: `stabctl.dynamics.model.call_evaluate`) thus compile side by
side on two cores.  Run as ``python -m stabctl._jit.background MODULE QUALNAME`` with the
pickled argument types on stdin, this module is the child.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib
import os
import pickle
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from numba.core import event

from stabctl._jit.cache import cached, make_private_dirs, stamp_cache

#: compiles under way in child processes (`compile_in_background`), by dispatcher name
_BACKGROUND: dict[str, tuple[subprocess.Popen, object]] = {}


def _name(dispatcher) -> str:
    return f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}"


def _writable(directory: Path) -> bool:
    try:
        make_private_dirs(directory)
        with tempfile.TemporaryFile(dir=directory):
            return True
    except OSError:
        return False


def compile_in_background(dispatcher, argtypes, opt: int | None = None) -> bool:
    """Start compiling a kernel for given argument types in a child process, which writes
    it to the on-disk cache; `await_background` then waits for it and the kernel loads
    from the cache.  This process meanwhile compiles other kernels: the simulator's
    integrator (`stabctl.dynamics.integrator.integrate`) and the model's evaluation do not
    link each other (`stabctl.dynamics.model.call_evaluate`), so on two cores a cold first
    run compiles them side by side.

    Nothing is started (returns False) when the kernel is already compiled in this process
    or cached (`stabctl._jit.cache.cached`), or a compile of it is under way, or its cache
    directory cannot be written (the child's work could not reach this process).  A child
    still running when this process exits is stopped (no orphan process).

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
    if (
        name in _BACKGROUND
        or dispatcher.signatures
        or cached(dispatcher)
        or not _writable(Path(dispatcher.stats.cache_path))
    ):
        return False
    stamp_cache()  # the child finds the cache's key up to date: it clears nothing
    err = tempfile.TemporaryFile()  # noqa: SIM115 - the child's stderr, read after it exits
    out = tempfile.TemporaryFile()  # noqa: SIM115 - the child's compile time, read likewise
    env = dict(os.environ, **({} if opt is None else {"NUMBA_OPT": str(opt)}))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            __name__,
            dispatcher.py_func.__module__,
            dispatcher.py_func.__qualname__,
            str(os.getpid()),
        ],
        stdin=subprocess.PIPE,
        stdout=out,
        stderr=err,
        env=env,
    )
    proc.stdin.write(pickle.dumps(tuple(argtypes)))
    proc.stdin.close()
    _BACKGROUND[name] = (proc, err, out)
    atexit.register(_stop, proc)
    return True


def await_background(dispatcher) -> None:
    """Wait for the child process compiling `dispatcher` (`compile_in_background`), if
    one was started, so that its next call loads the kernel from the cache.  The wait is
    announced as a numba compile event (the CLI's notice and its heartbeat go on).  If
    the child failed, a RuntimeWarning gives its last error line and the kernel is
    compiled here, as without a child.
    """
    running = _BACKGROUND.pop(_name(dispatcher), None)
    if running is None:
        return
    proc, err, out = running
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
        warnings.warn(
            f"compiling {_name(dispatcher)} in a child process failed "
            f"(exit {proc.returncode}: {lines[-1]}); compiling it here",
            RuntimeWarning,
            stacklevel=2,
        )
    else:
        out.seek(0)
        with contextlib.suppress(ValueError):
            COMPILED_S[_name(dispatcher)] = float(out.read().decode(errors="replace") or "nan")
    err.close()
    out.close()


#: seconds each kernel compiled in a child process took there (`await_background`),
#: by name: what `stabctl compile` reports for it
COMPILED_S: dict[str, float] = {}


def compiled_seconds(dispatcher) -> float | None:
    """The seconds a child process took to compile `dispatcher` (`compile_in_background`,
    once `await_background` has waited for it); None if no child compiled it.

    Parameters
    ----------
    dispatcher : numba dispatcher

    Returns
    -------
    float or None
    """
    return COMPILED_S.get(_name(dispatcher))


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        proc.wait()


def _die_with(parent: int) -> None:
    """In the child: the kernel kills it when its parent dies (Linux prctl
    PR_SET_PDEATHSIG, SIGKILL), so a SIGKILLed parent leaves no compile running; a child
    whose parent is already gone exits at once."""
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        try:
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no libc prctl
            pass
    if os.getppid() != parent:
        os._exit(1)


if __name__ == "__main__":  # the child of `compile_in_background`
    _module, _qualname, _parent = sys.argv[1:4]
    _die_with(int(_parent))
    _t0 = time.perf_counter()
    getattr(importlib.import_module(_module), _qualname).compile(pickle.load(sys.stdin.buffer))
    print(f"{time.perf_counter() - _t0:.3f}", end="")
