"""Compilation of stabctl's numba kernels, in one place, one module per job:

- :mod:`~stabctl._jit.decorators`: `njit` (a kernel Python calls) and `kernel` (a kernel
  only kernels call: no CPython or C entry point; `CompiledOnly`);
- :mod:`~stabctl._jit.cache`: the on-disk cache, its key (`source_digest` over the
  modules that feed the kernels, found by a scan: `kernel_sources`), its directories,
  clearing it, whether a kernel is in it; and `package_digest`, which stabctl a process
  runs (a Dask sweep refuses a worker whose digest is not its own);
- :mod:`~stabctl._jit.background`: compiling a kernel in a child process while this one
  compiles another;
- :mod:`~stabctl._jit.notify`: the notice and heartbeat while the first kernels compile;
- :mod:`~stabctl._jit.address`: calling a kernel by its machine-code address (rule 7);
- :mod:`~stabctl._jit.arrays`: `assign` and `max_abs`, the loops kernels use instead of
  numpy idioms that are slow to compile;
- :mod:`~stabctl._jit.borrow`: `borrowed`, arrays without a reference count for the hot
  loops (rule 8).

Importing ``stabctl`` compiles nothing and touches no file; importing a module that
declares kernels checks the cache key first (`stabctl._jit.cache.ensure_fresh_cache`).

Kernel coding rules (what a first call waits for is compile time: ``python
benchmarks/bench_compile.py``; docs/simulator.md gives the measurements; tests/test_jit_rules.py
checks each rule):

1. Every compiled function is declared at module level with `njit` or `kernel` from
   :mod:`~stabctl._jit.decorators` (``cache=True``): a bare ``numba.njit`` would not be
   cached, or be cached without the package-wide key.
2. A `kernel` is called only from compiled code; package code never calls one from Python
   (the trampoline of `CompiledOnly` is for tests, one-off checks and the filterpy
   reference implementations, classes named ``*Reference``).
3. No kernel assigns an array into a slice (``a[:] = b``, ``F[3:, 3:] = A``): it calls
   `stabctl._jit.arrays.assign`.  numba's slice assignment from an array compiles a
   formatter for its shape-mismatch message, 2-3 s of a cold first call.  A scalar fill
   (``a[:] = 0.0``) is fine.
4. Flags and row or column numbers passed from a kernel to a kernel are numpy scalars
   (``np.bool_(True)``, ``np.int64(0)``, or module constants holding them such as
   `stabctl.dynamics.model.BUS_VOLTAGES`), not Python ``True``/``False`` or ints, literal
   or module constants: numba types those as literals and compiles the callee (and its
   callers) once per value, and once more for a caller passing a variable.
5. No ``np.linalg`` in kernels: its numba implementation copies its inputs with a slice
   assignment (rule 3); LAPACK is called by symbol name (`stabctl.network.solution`'s
   ``dgesv``), which keeps the kernels cacheable.
6. No numba generic reductions where a loop says the same: ``np.max(np.abs(a))`` is
   `stabctl._jit.arrays.max_abs`.
7. Two large units do not link each other: the integrator and the linearisation call the
   model's evaluation by machine-code address (`stabctl.dynamics.model.call_evaluate`,
   made by :mod:`~stabctl._jit.address`), so LLVM emits the model once and the units can
   compile in parallel processes (:mod:`~stabctl._jit.background`).
8. A kernel that calls other kernels once per machine, exciter, stabiliser or governor
   borrows the arrays it passes (`stabctl._jit.borrow.borrowed`) at its top, from its own
   arguments (what its caller holds for the whole call); arrays it allocates itself are
   handed to a kernel of their own that borrows them (`stabctl.dynamics.model.
   _evaluate_into`).  A borrowed array is never returned or stored.  Without it each
   call counted references atomically: half of a run's time on ACTIVSg2000
   (``python benchmarks/bench_refcounts.py`` prints the increments left per step).
"""
