"""The decorators of stabctl's kernels: `njit` (called from Python) and `kernel` (called
only from other kernels).

Importing this module checks the on-disk cache first (`stabctl._jit.cache.
ensure_fresh_cache`), so that no kernel is declared, let alone loaded, against a stale one,
and refuses numba's compiler turned off (ImportError, `stabctl._jit.environment.JIT_OFF`).
"""

from __future__ import annotations

import numba
from numba.core.registry import CPUDispatcher

from stabctl._jit.cache import ensure_fresh_cache, guard
from stabctl._jit.environment import JIT_OFF, jit_disabled

if numba.config.DISABLE_JIT:  # compiled-only kernels cannot be plain Python functions
    raise ImportError(JIT_OFF.format(value=jit_disabled() or "1"))
ensure_fresh_cache()

#: numba's error model of every kernel: "numpy", a float division by zero gives inf or nan
#: (which a run's health check reports, `stabctl.dynamics.integrator`) instead of raising,
#: so that no division carries a branch and LLVM can vectorise the loops around it; the
#: results are bit for bit those of the "python" model (`benchmarks/fingerprint.py`), an
#: ACTIVSg2000 probe 3 % faster (0.2253-0.2293 -> 0.2192-0.2231 CPU-s, three pairs).
ERROR_MODEL = "numpy"


def njit(func=None, **options):
    """Decorator of a kernel that Python code calls: ``numba.njit`` with an on-disk cache
    (``cache=True`` unless given False: `stabctl._jit.cache.guard`'s, guarded against
    damaged entries, its directory made when a kernel is first saved), no C-callable
    (``cfunc``) wrapper (nothing takes a kernel's C address) and numpy's error model
    (`ERROR_MODEL`).

    Parameters
    ----------
    func : callable, optional
        The function (``@njit``), or None (``@njit(...)`` with options).
    **options
        Further ``numba.njit`` options.

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The dispatcher.
    """

    cache = options.pop("cache", True)
    options = {"no_cfunc_wrapper": True, "error_model": ERROR_MODEL, **options}

    def declare(f):
        dispatcher = numba.njit(f, **options)  # without numba's cache, which makes its dir
        return guard(dispatcher) if cache else dispatcher

    return declare if func is None else declare(func)


class CompiledOnly(CPUDispatcher):
    """A numba dispatcher compiled without a Python entry point (`kernel`).  A call from
    Python (tests, a one-off check) goes through a compiled trampoline built on its first
    use, instead of jumping into the missing entry point.

    Raises
    ------
    TypeError
        A call from Python with keyword arguments.
    """

    def __call__(self, *args, **kwargs):
        if kwargs:
            raise TypeError(
                f"{self.py_func.__qualname__}: keyword arguments from Python "
                "are not supported (a kernel for compiled callers)"
            )
        trampoline = self.__dict__.get("_from_python")
        if trampoline is None:
            target = self
            if self.targetoptions.get("inline", "never") == "never":
                trampoline = numba.njit(lambda *a: target(*a))
            else:  # numba inlines no kernel into a call with *args: compile its source
                trampoline = numba.njit(self.py_func)
            self._from_python = trampoline
        return trampoline(*args)


def kernel(func=None, **options):
    """Decorator of a kernel called only from other kernels: ``numba.njit`` with
    ``cache=True`` (`stabctl._jit.cache.guard`'s cache, as `njit`), numpy's error model
    (`ERROR_MODEL`) and without the CPython
    and C wrappers that a call from Python needs.  Each wrapper unpacks every argument (a
    NamedTuple of arrays field by field); leaving them out took about 4 s off a cold first
    simulation when it compiled in one process (39 -> 35 s on this 2-core machine).

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

    cache = options.pop("cache", True)

    def declare(f):
        dispatcher = numba.njit(
            f, no_cpython_wrapper=True, no_cfunc_wrapper=True, error_model=ERROR_MODEL, **options
        )
        dispatcher.__class__ = CompiledOnly
        return guard(dispatcher) if cache else dispatcher

    return declare if func is None else declare(func)
