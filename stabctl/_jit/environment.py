"""numba's settings from the environment (``NUMBA_*`` variables), checked before numba is
imported by the `stabctl` command.

numba reads its ``NUMBA_*`` variables once, as it is imported.  A value it cannot parse
(``NUMBA_OPT=x``) is ignored after a warning that prints a whole traceback;
``NUMBA_NUM_THREADS=0`` stops the import with a ValueError that does not name the
variable; a ``NUMBA_CACHE_DIR`` that is not a directory is passed over without a word, the
kernels then cached elsewhere; ``NUMBA_DISABLE_JIT`` on leaves the kernels Python
functions, which stabctl's compiled-only kernels cannot be (`JIT_OFF`).
`environment_problem` says each of these in one line naming the variable, and the
command refuses to run (`stabctl.cli`).
"""

from __future__ import annotations

import os
import re
import sys
import warnings
from collections.abc import Mapping
from pathlib import Path

#: numba's warning of a variable it could not parse (numba.core.config._readenv)
_UNPARSED = re.compile(
    r"Environment variable '(?P<name>\w+)' is defined but its associated value "
    r"'(?P<value>.*?)' could not be parsed",
    re.DOTALL,
)


#: why stabctl does not run with numba's compiler off (`environment_problem`; importing a
#: kernel module then raises ImportError, `stabctl._jit.decorators`)
JIT_OFF = (
    "NUMBA_DISABLE_JIT={value!r} in the environment: stabctl's kernels run only compiled "
    "(some have no Python entry point, and a run in pure Python would take hours); unset it"
)


def jit_disabled(environ: Mapping[str, str] | None = None) -> str:
    """The value of ``NUMBA_DISABLE_JIT`` when it turns numba's compiler off (a whole
    number other than 0, as numba reads it), else ''.

    Parameters
    ----------
    environ : mapping, optional
        The environment (default ``os.environ``).

    Returns
    -------
    str
    """
    value = (os.environ if environ is None else environ).get("NUMBA_DISABLE_JIT")
    try:
        return value if value is not None and int(value) != 0 else ""
    except ValueError:  # numba warns and leaves the compiler on: environment_problem
        return ""


def _not_a_directory(value: str) -> str:
    """The existing file that stops `value` from being (or becoming) a directory, or ''."""
    path = Path(value)
    for place in (path, *path.parents):
        if place.exists():
            return "" if place.is_dir() else str(place)
    return ""


def cache_dir_note(environ: Mapping[str, str] | None = None) -> str:
    """A warning when ``NUMBA_CACHE_DIR`` names a directory this process may not write
    (a read-only mount, another user's, ``/proc/self``), or a path that cannot be made
    for that reason: numba passes over it without a word and caches the kernels in the
    package's ``__pycache__`` directories, or compiles them in every run; or a path with
    blanks around it (a leading blank makes a relative path: the cache moves with the
    working directory).
    '' otherwise (unset, writable, or not a directory: `environment_problem` refuses
    that).

    Parameters
    ----------
    environ : mapping, optional
        The environment (default ``os.environ``).

    Returns
    -------
    str
    """
    cache = (os.environ if environ is None else environ).get("NUMBA_CACHE_DIR")
    if not cache or _not_a_directory(cache):
        return ""
    if cache != cache.strip():
        return (
            f"NUMBA_CACHE_DIR={cache!r} in the environment has blanks around it: numba "
            f"caches the kernels in {os.path.abspath(cache)!r}, blanks included"
            + ("" if os.path.isabs(cache) else ", under the directory each command runs in")
        )
    place = next(p for p in (Path(cache), *Path(cache).parents) if p.exists())
    if os.access(place, os.W_OK | os.X_OK):
        return ""
    return (
        f"NUMBA_CACHE_DIR={cache!r} in the environment: this process may not write in "
        f"{place}, so numba does not use it: the kernels are cached in the package's "
        "__pycache__ directories if it may write there, else compiled in every run"
    )


def environment_problem(environ: Mapping[str, str] | None = None) -> str:
    """What is wrong with numba's settings in the environment, in one line ('' if nothing).

    Checked: ``NUMBA_DISABLE_JIT`` not on (`JIT_OFF`); ``NUMBA_NUM_THREADS`` a whole
    number >= 1; ``NUMBA_CACHE_DIR`` a directory,
    or a path where one can be made; then numba is imported (if it is not yet), and a
    variable it could not parse is named with numba's reason.

    Parameters
    ----------
    environ : mapping, optional
        The environment (default ``os.environ``; numba itself reads ``os.environ``).

    Returns
    -------
    str
        E.g. ``"NUMBA_NUM_THREADS=0 in the environment: numba needs a whole number of
        threads >= 1 (unset it for one per core)"``, or ''.
    """
    env = os.environ if environ is None else environ
    if jit_disabled(env):
        return JIT_OFF.format(value=env["NUMBA_DISABLE_JIT"])
    threads = env.get("NUMBA_NUM_THREADS")
    if threads is not None:
        try:
            ok = int(threads) >= 1
        except ValueError:
            ok = False
        if not ok:
            return (
                f"NUMBA_NUM_THREADS={threads!r} in the environment: numba needs a whole "
                "number of threads >= 1 (unset it for one per core)"
            )
    cache = env.get("NUMBA_CACHE_DIR")
    if cache:
        blocked = _not_a_directory(cache)
        if blocked:
            return (
                f"NUMBA_CACHE_DIR={cache!r} in the environment: {blocked} is not a "
                "directory (numba's kernel cache is one; unset it to cache the kernels "
                "in the package's __pycache__ directories)"
            )
    if "numba" in sys.modules:
        return ""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        try:
            import numba  # noqa: F401 - numba reads its variables as it is imported
        except Exception as exc:  # noqa: BLE001 - whatever a setting makes it raise
            return f"numba does not start in this environment: {type(exc).__name__}: {exc}"
    problem = ""
    for w in caught:
        found = _UNPARSED.search(str(w.message))
        if found and not problem:
            reason = [line for line in str(w.message).splitlines() if line.strip()][-1]
            problem = (
                f"{found['name']}={found['value']!r} in the environment: numba cannot read "
                f"it ({reason.strip()}); correct or unset it"
            )
        elif not found:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return problem
