"""The `stabctl` command line: one subcommand per study, `--json` where figures come out.

The click group :func:`main` (run by the console script ``stabctl = stabctl.__main__:main``) and its
commands, one module per family: :mod:`~stabctl.cli.omib` (omib), :mod:`~stabctl.cli.paper`
(paper), :mod:`~stabctl.cli.io` (cases, import-psse, import-andes), :mod:`~stabctl.cli.simulate`,
:mod:`~stabctl.cli.stability` (cct, sweep-cct, screen), :mod:`~stabctl.cli.eig`,
:mod:`~stabctl.cli.place`, :mod:`~stabctl.cli.estimate` and :mod:`~stabctl.cli.compile`
(compile: the kernel cache). Shared options, checks and error handling are in
:mod:`~stabctl.cli.options`, text and JSON output in :mod:`~stabctl.cli.format`, a
checked standard output (a failed write is an error) in :mod:`~stabctl.cli.stdout`.

Errors in the input (stabctl.errors.StabctlError) are printed as one line naming what and
where, with exit status 2; nothing is written in that case.  The library's progress lines
(its ``stabctl.*`` loggers at level INFO, `stabctl.progress`) go to stderr as lines of
their own.
"""

from __future__ import annotations

import logging
import os
import sys
from typing import IO, Any

import click

#: commands that run the compiled simulator (the others never compile anything)
_SIMULATING = {"paper", "simulate", "cct", "sweep-cct", "screen", "eig", "place", "estimate", "pmu"}
#: `stabctl compile` itself: a cold cache said nothing for minutes, until its first part
#: ended (round 40: 286 s), where every other command says it compiles and then every 10 s
_SIMULATING |= {"compile"}

#: the kernel sets a command may compile (`stabctl compile` prints them as its parts:
#: the simulator's model evaluation, integrator and converters' set-up; the
#: linearisation; the estimators' filters and storage control), when not the simulator's
_KERNEL_SETS = {
    "eig": ("the simulator's model", "the linearisation"),
    "place": ("the simulator", "the linearisation"),
    "estimate": ("the simulator", "the estimators"),
    "pmu": ("the simulator", "the estimators"),
    "paper": ("the simulator", "the linearisation", "the estimators"),
    "compile": ("the simulator", "the linearisation", "the estimators"),
}


def compile_notice(command: str) -> str:
    """The notice printed on stderr when `command` starts compiling kernels: which kernel
    sets it uses, that each set compiles once and is then loaded from the on-disk cache,
    and that ``stabctl compile`` compiles every set at once.

    Parameters
    ----------
    command : str
        A subcommand's name, e.g. ``"eig"``.

    Returns
    -------
    str
        Two lines, without a final newline.
    """
    sets = _KERNEL_SETS.get(command, ("the simulator",))
    named = sets[0] if len(sets) == 1 else ", ".join(sets[:-1]) + " and " + sets[-1]
    then = (
        "a line as each part ends; minutes on an empty cache"
        if command == "compile"
        else "`stabctl compile` compiles every set at once"
    )
    return (
        f"stabctl: compiling the kernels of {named} not yet in the on-disk cache\n"
        f"  (each set compiles once, later runs load it in about a second; {then})"
    )


class UsageLine(click.ClickException):
    """A usage error (an option's value of the wrong type, an unknown or missing option)
    shown as the input errors are: one ``error:`` line naming the option and the command's
    ``--help``, exit status 2 (click's own shows the usage and a capitalised ``Error:``
    after a blank line)."""

    exit_code = 2

    def __init__(self, exc: click.UsageError):
        names: list[str] = []
        ctx = exc.ctx
        while ctx is not None and ctx.parent is not None:
            names.append(ctx.info_name or "")
            ctx = ctx.parent
        help_ = " ".join(["stabctl", *reversed(names), "--help"])
        text = " ".join(exc.format_message().split()).rstrip(".")
        super().__init__(f"{text} (see `{help_}`)")

    def show(self, file: IO[Any] | None = None) -> None:
        """Print the one line on stderr."""
        click.echo(f"error: {self.format_message()}", err=True, file=file)


class _Group(click.Group):
    """The `stabctl` group: its commands' usage errors as one line (`UsageLine`), its
    standard output checked (`stabctl.cli.stdout.checked_stdout`: a failed write is an
    error, not a silent exit status 0)."""

    def main(self, *args, **kwargs):
        """Run the command line (click's ``main``) on a checked standard output, or say
        what is wrong with numba's settings in the environment (exit status 2)."""
        from stabctl.cli.stdout import checked_stdout

        if _ENVIRONMENT_PROBLEM:
            click.echo(f"error: {_ENVIRONMENT_PROBLEM}", err=True)
            sys.exit(2)
        with checked_stdout():
            return super().main(*args, **kwargs)

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except click.UsageError as exc:
            raise UsageLine(exc) from None


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="stabctl")
@click.pass_context
def main(ctx):
    """stabctl: transient-stability control with distributed energy storage."""
    # The simulator works on many small dense matrices: multi-threaded BLAS only adds
    # overhead there and oversubscribes the cores when sweeps run one simulation per
    # process.  Set before any command imports numpy; a user's own setting wins.
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    _log_to_stderr()
    from stabctl._jit.environment import cache_dir_note

    if note := cache_dir_note():
        click.echo(f"warning: {note}", err=True)
    if ctx.invoked_subcommand in _SIMULATING and "--help" not in sys.argv:
        from stabctl._jit.notify import on_first_compile, still_line

        # said when compiling starts (never for cached kernels; bad input fails before)
        ctx.call_on_close(
            on_first_compile(
                lambda: click.echo(compile_notice(ctx.invoked_subcommand), err=True),
                still=lambda *a: click.echo(still_line(*a), err=True),
            )
        )


class _Echo(logging.Handler):
    """A log record as one line on stderr (`click.echo`), as the commands' own lines."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            from stabctl.progress import bars_cleared

            with bars_cleared():  # a progress bar shown: the line goes above it
                click.echo(self.format(record), err=True)
        except Exception:  # noqa: BLE001 - a logging handler reports its own failures
            self.handleError(record)


_ECHO = _Echo(logging.INFO)


def _log_to_stderr() -> None:
    """Show the library's loggers (``stabctl.*``) from level INFO on stderr (once)."""
    logger = logging.getLogger("stabctl")
    logger.setLevel(logging.INFO)
    if _ECHO not in logger.handlers:
        logger.addHandler(_ECHO)


def _register() -> None:
    from stabctl.cli import compile as compile_
    from stabctl.cli import eig, estimate, io, omib, paper, place, pmu, simulate, stability

    for cmd in (
        omib.omib,
        paper.paper,
        io.cases,
        simulate.simulate,
        stability.cct,
        stability.sweep_cct,
        stability.screen,
        eig.eig,
        estimate.estimate,
        pmu.pmu,
        place.place,
        io.import_psse,
        io.import_andes,
        compile_.compile_kernels,
    ):
        _one_value_each(cmd)
        main.add_command(cmd)


def _one_value_each(cmd: click.Command) -> None:
    """Make `cmd` (each command of a group) refuse an option of one value given twice: click
    keeps the last without a word (`cct --fault 3 --fault 13` searched bus 13's fault), and
    an on/off flag given both ways (`--q-limits --no-q-limits`).  A usage error
    (`UsageLine`); a flag in one form and repeatable options may come more than once."""
    if isinstance(cmd, click.Group):
        for sub in cmd.commands.values():
            _one_value_each(sub)
        return
    single = {
        name: param
        for param in cmd.params
        if isinstance(param, click.Option) and not (param.multiple or param.count or param.is_flag)
        for name in param.opts
    }
    paired = {
        name: param
        for param in cmd.params
        if isinstance(param, click.Option) and param.is_flag and param.secondary_opts
        for name in (*param.opts, *param.secondary_opts)
    }
    parse = cmd.parse_args

    def parse_args(ctx, args):
        seen: dict[str, str] = {}
        for token in args:
            if token == "--":
                break
            name = str(token).split("=", 1)[0]  # click takes numbers from a caller too
            param = single.get(name)
            if param is not None and param.name in seen:
                first = seen[str(param.name)]
                again = "twice" if first == name else f"after {first}, the same option"
                raise click.UsageError(f"{name} given {again}: it takes one value", ctx=ctx)
            flag = paired.get(name)
            if flag is not None and seen.get(str(flag.name), name) != name:
                first = seen[str(flag.name)]
                raise click.UsageError(f"{name} given after {first}: one or the other", ctx=ctx)
            for given in (param, flag):
                if given is not None:
                    seen[str(given.name)] = name
        return parse(ctx, args)

    cmd.parse_args = parse_args  # type: ignore[method-assign]


def _environment_problem() -> str:
    """numba's settings in the environment checked before any command imports numba
    (`stabctl._jit.environment`): '' or the error, said when the command line runs."""
    from stabctl._jit.environment import environment_problem

    return environment_problem()


_ENVIRONMENT_PROBLEM = _environment_problem()
if not _ENVIRONMENT_PROBLEM:  # numba may not even import: no command is registered
    _register()
