"""`stabctl compile`: warm the on-disk kernel cache for the built-in cases, or check it."""

from __future__ import annotations

import importlib
import os
import time
from pathlib import Path

import click

from stabctl.cli.options import reports_errors


def _filter_kernels() -> list:
    """The estimation filters' kernels that Python calls (`njit`, not `CompiledOnly`):
    those of the estimation modules that declare kernels."""
    from numba.core.dispatcher import Dispatcher

    from stabctl._jit.cache import declaring_modules
    from stabctl._jit.decorators import CompiledOnly

    found = []
    for name in declaring_modules():
        if name.startswith("stabctl.estimation."):
            found += [
                d
                for d in vars(importlib.import_module(name)).values()
                if isinstance(d, Dispatcher)
                and not isinstance(d, CompiledOnly)
                and d.py_func.__module__ == name
            ]
    return found


def _kernels() -> dict[str, list]:
    """What a first command compiles, by name: the dispatchers of each part (the
    simulator's model evaluation and integrator, `eig`'s linearisation, `estimate`'s
    filters and storage control, and the converters' set-up, which the first case with
    converters compiles)."""
    from stabctl.dynamics.integrator import integrate
    from stabctl.dynamics.model import evaluate_kernel, kernel_outputs
    from stabctl.models.converters import derivatives_at
    from stabctl.models.converters.pvd1 import commands
    from stabctl.smallsignal.linearise import _differences
    from stabctl.storage.control import desired_modes
    from stabctl.studies.estimation import _count_actions

    return {
        "model evaluation": [evaluate_kernel, kernel_outputs],  # each run allocates by it
        "filters": _filter_kernels(),
        "storage control": [desired_modes, _count_actions],
        "linearisation": [_differences],
        "converter set-up": [derivatives_at, commands],
        "integrator": [integrate],
    }


def _warm_steps(case):
    """(part, action) in the order a cold first command takes them: building the
    simulator (`stabctl.dynamics.driver.Simulator`) compiles the model's evaluation and
    starts compiling the integrator in a child process, while this process compiles the
    filters, the storage control, the linearisation and the converters' set-up; then the
    integrator is loaded here, for this case's argument types."""
    import numpy as np

    from stabctl._jit.background import await_background
    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.integrator import integrate
    from stabctl.dynamics.model import evaluate_address
    from stabctl.estimation.filters import compile_filters
    from stabctl.estimation.models import machine_models
    from stabctl.estimation.pmu import machine_pmus
    from stabctl.models.converters import N_STATES, derivatives_at
    from stabctl.models.converters.pvd1 import commands
    from stabctl.models.converters.table import PACKED
    from stabctl.smallsignal.linearise import compile_differences
    from stabctl.storage import devices as st
    from stabctl.storage.control import BangBangCOI, desired_modes
    from stabctl.studies.estimation import _count_actions

    built = {}

    def model_evaluation():  # the simulator's set-up evaluates its model: timed here
        built["sim"] = sim = Simulator(case)
        evaluate_address(sim.model.params)

    def storage_control():  # as `estimate` calls them (closed-loop; rmse's false actions)
        sa = st.pack(st.uniform_fleet(case, 1.0, BangBangCOI()), case, np.arange(case.n_bus))
        n = sa.mac.size  # one device per machine
        desired_modes(sa, np.zeros(n, np.int64), np.zeros(n))
        # rmse's relative speeds come in both layouts ((1, n) would be both at once)
        _count_actions(sa, np.zeros((2, n)))
        _count_actions(sa, np.zeros((2, n), order="F"))

    def converter_setup():  # `initialise`'s types, on no device (case-independent)
        P, x = np.zeros((0, len(PACKED))), np.zeros((N_STATES, 0))
        V = np.zeros(0, np.complex128)
        derivatives_at(P, x, V, V.copy(), np.zeros_like(x))
        commands(P, x, V)

    def integrator():
        await_background(integrate)
        integrate.compile(tuple(built["sim"].run_argument_types()))

    return [
        ("model evaluation", model_evaluation),
        ("filters", lambda: compile_filters(machine_models(case, machine_pmus(case)))),
        ("storage control", storage_control),
        ("linearisation", lambda: compile_differences(built["sim"].model)),
        ("converter set-up", converter_setup),
        ("integrator", integrator),
    ]


def _misses(dispatchers) -> int:
    return sum(sum(d.stats.cache_misses.values()) for d in dispatchers)


def _warm(cases) -> None:
    """Compile (or load) every part for each (name, case) of `cases`, one line per part
    and case: compiled if a kernel of the part was not in the cache before or numba
    compiled one (new argument types)."""
    from stabctl._jit.background import compiled_seconds
    from stabctl._jit.cache import cached
    from stabctl.dynamics.integrator import integrate

    kernels, t_all, n_compiled = _kernels(), time.perf_counter(), 0
    for name, case in cases:
        cold = {part: not all(map(cached, ds)) for part, ds in kernels.items()}
        for part, action in _warm_steps(case):
            misses, t0 = _misses(kernels[part]), time.perf_counter()
            action()
            compiled = cold[part] or _misses(kernels[part]) > misses
            n_compiled += compiled
            took, beside = time.perf_counter() - t0, ""
            child = compiled_seconds(integrate) if part == "integrator" else None
            if compiled and child is not None:  # its time in the child, not the wait
                took, beside = child, "  (in a child process, beside the above)"
            click.echo(
                f"{name:<10} {part:<17} {'compiled' if compiled else 'loaded':<9}"
                f"{took:6.1f} s{beside}"
            )
    click.echo(
        f"kernel cache warm ({_location(kernels)}): {n_compiled} compiled, "
        f"{time.perf_counter() - t_all:.1f} s in all"
    )


def _location(kernels: dict[str, list]) -> str:
    """Where numba caches the kernels, from their own caches (not NUMBA_CACHE_DIR, which
    numba passes over when it cannot write there): the package's __pycache__
    directories, or the directory holding their cache directories."""
    from stabctl._jit.cache import _PKG

    paths = {Path(d.stats.cache_path) for ds in kernels.values() for d in ds}
    in_tree = {p for p in paths if p.name == "__pycache__" and _PKG in p.parents}
    places = ["the package's __pycache__ directories"] if in_tree else []
    if paths - in_tree:
        places.append(os.path.commonpath(sorted(paths - in_tree)))
    return " and ".join(places)


def _check() -> bool:
    """Print whether each part's kernels are in the on-disk cache; True if all are."""
    from stabctl._jit.cache import cached

    warm, kernels = True, _kernels()
    for part, dispatchers in kernels.items():
        missing = [d.py_func.__qualname__ for d in dispatchers if not cached(d)]
        warm = warm and not missing
        click.echo(f"{part:<17} " + (f"not cached: {', '.join(missing)}" if missing else "cached"))
    click.echo(f"kernel cache {'warm' if warm else 'cold'} ({_location(kernels)})")
    return warm


@click.command("compile")
@click.argument("case_names", metavar="[CASE]...", nargs=-1)
@click.option(
    "--check",
    is_flag=True,
    help="Only report whether the kernels are in the on-disk cache (exit status 1 "
    "if any is not); compile nothing.",
)
@reports_errors
def compile_kernels(case_names, check):
    """Compile every kernel set the commands use into the on-disk cache: the
    simulator's (model evaluation, integrator, converters' set-up), the linearisation's
    (`eig`) and the estimators' (filters, storage control), so that the first real
    command loads them (about a second) instead of compiling them (docs/setup.md gives
    the CPU seconds).

    CASE: built-in cases (`stabctl cases`) whose argument types to compile for; default
    every one.  Printed per case and part (model evaluation, filters, storage control,
    linearisation, converter set-up, integrator): compiled or loaded from the cache, and
    the seconds.  The integrator
    compiles in a child process beside the other parts, as in a first simulation.  The
    cache is NUMBA_CACHE_DIR if set (a directory), else the package's __pycache__
    directories; a change of a kernel source empties it (the next command, or this one,
    compiles again).  --check makes no file or directory.

    \b
    Examples:
      stabctl compile
      stabctl compile kundur
      stabctl compile --check
    """
    from stabctl.io import list_cases, load_case

    # every case read first: an unknown one is an error before any compiling, and with
    # --check too (which compiles for no case)
    names = list(case_names) or ([] if check else list(list_cases()))
    cases = [(name, load_case(name)) for name in names]
    if check:
        if not _check():
            raise SystemExit(1)
        return
    _warm(cases)
