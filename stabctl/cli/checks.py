"""Checks of the `stabctl` command line made before any work: output files, CCT settings.

Each raises stabctl.errors.InputError naming the option (printed as one `error:` line,
exit status 2, by :func:`stabctl.cli.options.reports_errors`).
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

import click

from stabctl.cli.format import undecoded
from stabctl.errors import InputError
from stabctl.locking import temp_file
from stabctl.parallel import stream_fd


def _check_name(text: str, option: str) -> None:
    """Refuse an output name that is not UTF-8: the JSON naming it (``--json``'s
    ``files``, the records) would hold a lone surrogate, which strict JSON readers
    refuse.  (A name with a newline is legal: the lines naming it show it escaped,
    `stabctl.cli.format.shown`.)"""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        raise InputError(
            f"{option} {undecoded(text)}: a name that is not UTF-8: the JSON outputs "
            "and records naming the file could not; give another name"
        ) from None


def check_writable(path, option: str, directory: bool = False, records: bool = False) -> None:
    """Check, before any work, that an output file or directory can be written.

    Parameters
    ----------
    path : str or Path
        The output file, or with ``directory`` the output directory (which may be
        created, inside an existing one).
    option : str
        The option named in the error message.
    directory : bool
        ``path`` is a directory.
    records : bool
        ``path`` is a resumable study's records file: an existing one that cannot be
        written is let through (`stabctl.parallel.run_sweep` shows a finished study's
        records read-only, and refuses when jobs remain).

    Raises
    ------
    InputError
        Unless a file can be created where ``path`` is (tried with a temporary file,
        removed at once); ``path`` is a symbolic link that is broken or loops (writing
        would create the directories it points to, or fail after the work); a directory
        or another non-regular file (a file is wanted) or a file (a directory is wanted);
        or it exists and is not writable; an empty name (``Path("")`` is the current
        directory: the outputs landed there), or a file name ending in ``/`` (Path drops
        it: ``x.csv/`` wrote ``x.csv``); a name that is not UTF-8 (`_check_name`).
    """
    _check_name(str(path), option)
    if not str(path):
        kind = "directory" if directory else "file"
        raise InputError(
            f"{option} {str(path)!r}: an empty {kind} name; give a {kind}"
            + (" (. for the current one)" if directory else "")
        )
    if not directory and str(path).endswith((os.sep, "/")):  # Path("x.csv/") is x.csv
        raise InputError(f"{option} {path}: a name ending in / is a directory's; give a file")
    p = Path(path)
    _leads_somewhere(p, option, "directory" if directory else "file")
    if records and p.is_file() and not os.access(p, os.W_OK):
        return
    if directory:
        if p.exists() and not p.is_dir():
            raise InputError(f"{option} {path}: not a directory")
        where = p if p.is_dir() else p.parent
    else:
        if p.is_dir():
            raise InputError(f"{option} {path} is a directory")
        if p.exists() and not p.is_file():
            raise InputError(
                f"{option} {path}: not a regular file (a device, a pipe or a link to one); "
                "give a file"
            )
        where = p.parent
    where = where if str(where) else Path(".")
    if where.exists() and not where.is_dir():  # x.csv/r.jsonl with x.csv a file
        raise InputError(f"{option} {path}: {where} is a file, not a directory")
    if not where.is_dir():
        raise InputError(
            f"{option} {path}: directory {where} does not exist (create it "
            "first; it is not created for you)"
        )
    try:
        fd, held = temp_file(where, ".stabctl-write-test.")
        try:
            os.close(fd)
        finally:
            held.remove()
    except OSError as exc:
        raise InputError(
            f"{option} {path}: cannot write in {where} ({exc.strerror or exc})"
        ) from None
    if not directory:
        if p.exists():
            _replaceable(p, option)
        not_an_input(p, option)


def _leads_somewhere(path: Path, option: str, kind: str) -> None:
    """An output given as a symbolic link must lead to something that exists (a file
    written through it, a directory written into): a broken link or a loop of links is
    refused, naming it and the `kind` ("file" or "directory") to give instead."""
    if not path.is_symlink() or stream_fd(path) is not None:  # a link to stdout: a pipe
        return
    try:
        os.path.realpath(path, strict=True)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise InputError(
                f"{option} {path}: a looping symbolic link (it leads back to itself); give a {kind}"
            ) from None
        raise InputError(
            f"{option} {path}: a broken symbolic link (to {os.readlink(path)}, "
            f"{exc.strerror or exc}); give a {kind}, or create what it points to"
        ) from None


def _replaceable(path: Path, option: str) -> None:
    """An existing output file must be writable in place: not read-only, and not
    append-only or immutable (``chattr +a``/``+i``, which the write's final rename over it
    would hit only after the work), tried by opening it for update (nothing written)."""
    if not os.access(path, os.W_OK):
        raise InputError(f"{option} {path}: the file is not writable")
    try:
        with open(path, "r+b"):
            pass
    except OSError as exc:
        raise InputError(
            f"{option} {path}: the file cannot be replaced ({exc.strerror or exc}; "
            "append-only or immutable?)"
        ) from None


def not_an_input(path: Path, option: str) -> None:
    """Raise InputError when the output file ``path`` of ``option`` is a file that another
    parameter of the running command names (its case, ``--faults``, ``--screening``,
    ``--source`` ...): writing it would overwrite an input; or another output of the
    command (``--plot`` the file ``--out`` names), existing or not.  Outside a command
    nothing is checked."""
    ctx = click.get_current_context(silent=True)
    if ctx is None:
        return
    for param in ctx.command.params:
        if option in param.opts:
            continue
        value = ctx.params.get(param.name or "")
        output = param.name in _OUTPUT_PARAMS
        for v in value if isinstance(value, (list, tuple)) else (value,):
            if isinstance(v, (str, Path)) and _same_file(v, path, output):
                name = (
                    param.opts[0] if isinstance(param, click.Option) else param.human_readable_name
                )
                if param.name in _OUTPUT_PARAMS:
                    raise InputError(
                        f"{option} {path} is also the output {name} {v}: one would overwrite "
                        "the other; give two files"
                    )
                raise InputError(
                    f"{option} {path} is also the input {name} {v}: writing it would overwrite "
                    "that input; give another file"
                )


#: the parameters that name a command's outputs, not its inputs (`not_an_input`)
_OUTPUT_PARAMS = frozenset(("out_path", "plot_path", "out", "out_dir"))


def _same_file(value, path: Path, output: bool = False) -> bool:
    """Whether `value` names the file `path`: both existing files, the same one; for
    another output (`output`) also the same path not written yet."""
    if not str(value):
        return False
    if os.path.isfile(value) and path.is_file():
        return os.path.samefile(value, path)
    return output and os.path.abspath(value) == os.path.abspath(path)


OUT_SUFFIXES = (".csv", ".npz")
PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def check_suffix(path, allowed, option, records: bool = False) -> Path | None:
    """The output file ``path`` (None: none) once its suffix and writability are checked.

    Parameters
    ----------
    path : str or None
    allowed : tuple of str
        Allowed suffixes, lower case with the dot.
    option : str
        The option named in error messages.
    records : bool, optional
        A resumable study's records file (`check_writable`); default False.

    Returns
    -------
    Path or None

    Raises
    ------
    InputError
        A file another parameter names as an input (said first: the graver mistake),
        another suffix, a directory, or a place that cannot be written.
    """
    if path is None:
        return None
    p = Path(path)
    not_an_input(p, option)
    if p.suffix.lower() not in allowed:
        raise InputError(f"{option} {path}: the file name must end in {' or '.join(allowed)}")
    if p.exists() and p.is_dir():
        raise InputError(f"{option} {path} is a directory")
    check_writable(path, option, records=records)
    return p


def search_settings(tol_ms, t_max, tf, tf_option: bool = True):
    """The CCT search settings of ``--tol-ms``, ``--t-max`` and ``--tf``.

    Parameters
    ----------
    tol_ms : float
        ``--tol-ms``.
    t_max : float
        ``--t-max``, s.
    tf : float or None
        ``--tf``, s (None: not given).
    tf_option : bool, optional
        Whether the command has ``--tf`` (named in a refusal of --t-max); default True.

    Returns
    -------
    stabctl.stability.cct.SearchOptions
        ``tol`` (s), ``t_max`` (s) and ``t_end`` (s, None: fault start + 5 s).

    Raises
    ------
    InputError
        A value not > 0, a --t-max below the tolerance (no search could run:
        `stabctl.stability.cct.check_search_range`), or without --tf a --t-max that
        leaves less than `stabctl.stability.cct.MIN_AFTER_CLEARING_S` of the runs after
        the latest clearing.
    """
    if not tol_ms > 0:
        raise InputError(f"--tol-ms must be > 0, got {tol_ms:g}")
    if not t_max > 0:
        raise InputError(f"--t-max must be > 0 s, got {t_max:g}")
    if tf is not None and not tf > 0:
        raise InputError(f"--tf must be > 0 s, got {tf:g}")
    from stabctl.stability.cct import (
        MIN_AFTER_CLEARING_S,
        T_AFTER_FAULT,
        SearchOptions,
        check_search_range,
        default_run_end_problem,
    )

    if tf is None and T_AFTER_FAULT - t_max < MIN_AFTER_CLEARING_S - 1e-9:
        raise InputError(default_run_end_problem(t_max, "--t-max", "--tf" if tf_option else None))
    search = SearchOptions(tol=tol_ms / 1000.0, t_max=t_max, t_end=tf)
    try:
        check_search_range(search)
    except InputError as exc:
        raise InputError(f"--tol-ms {tol_ms:g} with --t-max {t_max:g} s: {exc}") from None
    return search


def check_run_end(faults, search) -> None:
    """Refuse, before any search runs, a --tf that ends a fault's runs less than
    `stabctl.stability.cct.MIN_AFTER_CLEARING_S` after its latest clearing (each search
    would fail on its own, recorded as a failed job, or read a probe cleared past the
    CCT stable: the CCT above --t-max).

    Parameters
    ----------
    faults : sequence of stabctl.stability.cct.LineFault
    search : stabctl.stability.cct.SearchOptions
        ``t_end`` (s; None: each fault's start + 5 s) and ``t_max`` (s).

    Raises
    ------
    InputError
        Naming the first such fault, its latest clearing, --tf, the minimum and what to
        change.
    """
    from stabctl.stability.cct import MIN_AFTER_CLEARING_S

    if search.t_end is None:
        return
    least = MIN_AFTER_CLEARING_S
    for f in faults:
        latest = f.t_fault + search.t_max
        if search.t_end - latest < least - 1e-9:
            most = search.t_end - f.t_fault - least
            lower = f" or --t-max {most:g} s or less" if most > 0 else ""
            raise InputError(
                f"--tf {search.t_end:g} s: {f.describe()} is cleared as late as "
                f"{latest:g} s (its start + --t-max {search.t_max:g} s); the runs must end "
                f"at least {least:g} s after it, the time a probe cleared past the CCT "
                "can take to separate (one that has not separated reads stable: the CCT "
                f"comes out high, or above --t-max): give --tf {latest + least:g} s or "
                f"more{lower}"
            )


def model_settings(conventions: str, step, q_limits: bool = True):
    """The model settings of ``--conventions``, ``--step``, ``--no-q-limits`` and
    ``--single-rate`` (`stabctl.cli.options.subintervals_chosen`).

    Returns
    -------
    stabctl.dynamics.options.ModelOptions

    Raises
    ------
    InputError
        Unknown conventions or a step not > 0.
    """
    from stabctl.cli.options import subintervals_chosen
    from stabctl.dynamics.options import ModelOptions

    return ModelOptions(
        conventions=conventions, h=step, q_limits=q_limits, subintervals=subintervals_chosen()
    )


def check_power_flow(case, model) -> None:
    """Solve the base case's power flow before a batch dispatches any job: a case whose
    power flow does not converge, or that has no machines (a static case), is refused
    once (every job ran and failed with the same error, the batch exited 0 with a file of
    failures).

    Parameters
    ----------
    case : stabctl.case.Case
        The case the batch studies.
    model : stabctl.dynamics.options.ModelOptions
        Its settings (`model_settings`): the power flow with or without Q limits, as
        the jobs solve it.

    Raises
    ------
    PowerFlowError
        The power flow does not converge (names the case, the iterations and the worst
        mismatch bus).
    InputError
        The case has no machines.
    """
    from stabctl.network.powerflow import solve_powerflow

    case.require_machines("a CCT search needs at least one")
    solve_powerflow(case, q_limits=model.q_limits)


def check_step_given(case, model, t_end: float | None = None) -> None:
    """Check ``--step`` against the case before a batch dispatches any job, as `cct` and
    `place` do when they build their simulator: a step too large for the case's fastest
    time constant was recorded as every job's failure, the command exiting 0.

    Parameters
    ----------
    case : stabctl.case.Case
        The case the batch studies.
    model : stabctl.dynamics.options.ModelOptions
        Its settings (`model_settings`); without a step (the case's default) nothing is
        checked.
    t_end : float, optional
        The latest end of the batch's runs, s: the step's count to it is checked too
        (`stabctl.dynamics.grid.check_step_count`, as each run checks it).

    Raises
    ------
    InputError
        The step is not below twice the case's fastest time constant
        (`stabctl.dynamics.grid.check_step`, as the jobs' simulators check it), or needs
        too many steps to t_end.
    """
    from stabctl.dynamics.grid import check_step_count

    if model.h is not None:
        model.simulator(case, background_compile=False)
        if t_end is not None:
            check_step_count(t_end, model.h, case)


def check_method(method: str, conventions: str, storage: bool) -> None:
    """Refuse, before any work, an integration method with options it does not implement.

    Parameters
    ----------
    method : str
        ``--method`` (``"heun"`` or ``"trapezoid"``).
    conventions : str
        ``--conventions``.
    storage : bool
        Whether storage devices are asked for (``--esd-pct``).

    Raises
    ------
    InputError
        ``--method trapezoid`` with ``--conventions pstess`` (whose event semantics are
        PSTess's: the corrector of the step ending at an event uses the post-event network;
        the trapezoid's each step its own interval's) or with storage (its switchings
        located inside Heun's steps), naming both options and what to give instead.
    """
    if method != "trapezoid":
        return
    if conventions == "pstess":
        raise InputError(
            "--method trapezoid cannot be used with --conventions pstess, whose event "
            "semantics are PSTess's (the step ending at an event corrected on the post-event "
            "network; the trapezoid's steps each use their own interval's): give --conventions "
            "ieee (the default) with --method trapezoid, or --method heun (the default) to "
            "reproduce PSTess's run"
        )
    if storage:
        raise InputError(
            "--method trapezoid cannot be used with --esd-pct: the storage devices' "
            "switching instants are located inside Heun's steps; give --method heun (the "
            "default)"
        )
