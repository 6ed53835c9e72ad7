"""The shared vocabulary of the `stabctl` commands: option decorators, checks, errors.

One concept, one option: the same name, type, unit and default on every command that
takes it (tests/cli/test_cli_vocabulary.py checks this by introspecting the commands).

Conventions:

* ``--out FILE`` is always an output *file*, ``--out-dir DIR`` always a directory.
* ``--tf`` is the end of each run (s), by default the fault start + 5 s.
* ``--faults FILE.csv|DEFAULT`` is a CSV of line faults (``--contingencies``: hidden,
  deprecated alias).
* ``--scheduler`` comes with ``--workers`` wherever jobs run in parallel.
* The storage options (``--esd-pct``, ``--deadband-hz``, ``--v-gate``, ``--coi``,
  ``--hysteresis-hz``) come as one set (:func:`storage_options`).

Errors in the input (stabctl.errors.StabctlError) are printed as one line naming what
and where, with exit status 2; nothing is written in that case (:func:`reports_errors`).
"""

from __future__ import annotations

import _thread
import functools
import math
import os
import shlex
import signal
import sys
import threading
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import click

from stabctl.cli.format import one_line
from stabctl.cli.stdout import StdoutError, cannot_write
from stabctl.errors import InputError, StabctlError, number_text, on_command_line
from stabctl.io.inputs import UNDERFLOW, plain_number, underflows

#: seconds a run continues after the fault start when --tf is not given
TF_AFTER_FAULT_S = 5.0


class AliasedOption(click.Option):
    """A click option whose second and later long names are hidden, deprecated aliases:
    they still work, but ``--help`` shows only the first name."""

    def get_help_record(self, ctx):
        shown, self.opts = self.opts, self.opts[:1]
        try:
            return super().get_help_record(ctx)
        finally:
            self.opts = shown


class Interrupted(KeyboardInterrupt):
    """Ctrl-C (SIGINT) while a command runs: a KeyboardInterrupt that carries its signal's
    number.  A subclass and not Python's own KeyboardInterrupt because the interpreter
    run as ``python -m stabctl`` remembers a bare KeyboardInterrupt that went through Python
    code C ran as a string (``PyRun_String``: Cython's module start-ups, imported inside a
    command) and, once the command had printed its ``interrupted:`` line and exited 130,
    killed itself with SIGINT (status -2) on its way out; it compares the type exactly.

    Parameters
    ----------
    signum : int
        The signal's number (SIGINT unless a subclass says otherwise).
    """

    def __init__(self, signum: int = signal.SIGINT):
        super().__init__(signum)
        self.signum = int(signum)


class Terminated(Interrupted):
    """SIGTERM (``kill``, a batch system's time limit) or SIGHUP (the terminal or the ssh
    session closed) raised as an interrupt, so that a command ends as on Ctrl-C (its
    pools shut down, finished records kept, its lock released) with exit status 128 + the
    signal's number (143, 129).

    Parameters
    ----------
    signum : int
        The signal's number.
    """

    def __init__(self, signum: int = signal.SIGTERM):
        super().__init__(signum)


#: the signal that ended the running command (`_interrupt`), None while none came
_received: list[int] = []

#: the signal whose interrupt was dropped, raised inside Python code that C called and
#: that drops what it raises (`_unraisable`), until it is raised again
_dropped: list[int] = []

#: seconds after which a dropped interrupt is delivered again (`_deliver_again`)
AGAIN_S = 0.05


def _raise_terminated(signum, frame):
    """SIGTERM or SIGHUP as `Terminated`, remembered (`_received`)."""
    _received.append(signum)
    _dropped.clear()
    raise Terminated(signum)


def _raise_interrupt(signum, frame):
    """SIGINT as `Interrupted` (Python's handler raises a bare KeyboardInterrupt),
    remembered (`_received`)."""
    _received.append(signum)
    _dropped.clear()
    raise Interrupted(signum)


def _as_interrupt(signum: int) -> Interrupted:
    """The interrupt a signal ends a command with: `Interrupted` for SIGINT, else
    `Terminated`."""
    return Interrupted(signum) if signum == signal.SIGINT else Terminated(signum)


def _unraisable(previous):
    """The ``sys.unraisablehook`` while a command runs.  A signal handled while Python
    code that C called runs (a ctypes callback: llvmlite's object-cache notification while
    numba compiles) raises its interrupt there, and the C caller prints the exception
    (``Exception ignored on calling ctypes callback function ... Terminated: 15``) and
    drops it: the command ran on.  Such an interrupt is not printed but delivered again
    `AGAIN_S` s later in the main thread (`_deliver_again`), in the code that runs then,
    again until it is raised where it propagates; a command that returns first ends on it
    (`_sigterm_as_interrupt`).  Any other error goes to `previous`.

    Parameters
    ----------
    previous : callable
        The hook before (Python's default, or one a caller installed).

    Returns
    -------
    callable
        The hook.
    """

    def hook(unraisable):
        if isinstance(unraisable.exc_value, KeyboardInterrupt) and _received:
            _dropped[:] = [_received[-1]]
            again = threading.Timer(AGAIN_S, _deliver_again)
            again.daemon = True
            again.start()
        else:
            previous(unraisable)

    return hook


def _deliver_again() -> None:
    """The dropped signal (`_dropped`) delivered to the main thread again, as if it came
    anew (its handler runs there), if it was not raised meanwhile."""
    if _dropped:
        _thread.interrupt_main(signal.Signals(_dropped[0]))


#: the signals a command ends on as on Ctrl-C (`Terminated`)
_ENDING_SIGNALS = (signal.SIGTERM, signal.SIGHUP)


@contextmanager
def _sigterm_as_interrupt():
    """SIGTERM and SIGHUP raise :class:`Terminated` while the block runs (main thread
    only, where Python delivers signals), the previous handlers restored after; SIGINT
    raises :class:`Interrupted`, a KeyboardInterrupt, as Python's handler would (when the
    process has that handler or
    the entry point's, `stabctl.__main__`: an ignored SIGINT, of a background job, stays
    ignored).  A signal the process was
    started with ignored stays ignored: ``nohup stabctl screen ...`` goes on when its
    terminal closes.  Each signal is remembered
    (`_received`), so that an error the interrupt caused in code that does not let it
    through ends the command as the interrupt does (`_interrupt`), and an interrupt that
    code called from C dropped is delivered again (`_unraisable`), or raised when the block
    ends if it has not come again by then.  After the block, a signal the entry point
    handled is ignored: the process ends with the command's status."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _received.clear()
    _dropped.clear()
    hook, sys.unraisablehook = sys.unraisablehook, _unraisable(sys.unraisablehook)
    previous = {
        sig: signal.signal(sig, _raise_terminated)
        for sig in _ENDING_SIGNALS
        if signal.getsignal(sig) is not signal.SIG_IGN  # nohup's SIGHUP stays ignored
    }
    now = signal.getsignal(signal.SIGINT)
    if now is signal.default_int_handler or getattr(now, "stabctl_early", False):
        # Python's handler, or the entry point's until the command's (`stabctl.__main__`)
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, _raise_interrupt)
    try:
        if early := getattr(now, "received", None):  # a signal the entry point's handler
            raise _as_interrupt(early[0])  # got but Python dropped: the command ends on it
        yield
        if _dropped:  # the block ended before the dropped interrupt came again
            raise _as_interrupt(_dropped[0])
    finally:
        _dropped.clear()
        sys.unraisablehook = hook
        for sig, handler in previous.items():
            # the entry point's handler said "nothing is kept" and exit 130 to a signal
            # that came after the command had ended (its outputs written, its status
            # given): the process only ends now, and such a signal is ignored
            ending = getattr(handler, "stabctl_early", False)
            signal.signal(sig, signal.SIG_IGN if ending else handler)


def _interrupt(exc: BaseException) -> KeyboardInterrupt | None:
    """The interrupt behind an error, if a signal that ends a command came while it ran:
    an interrupt raised inside code that turns it into another error (numba's code
    generation, Ctrl-C landing mid-compile, raised ``RuntimeError: no compiled object
    yet``) or swallows it, or the error's cause or context (chained from the interrupt).

    Parameters
    ----------
    exc : BaseException
        The error that ended the command.

    Returns
    -------
    KeyboardInterrupt or None
        The interrupt (`Terminated` for SIGTERM and SIGHUP) to end the command with, or
        None when no signal came and none is chained to the error.
    """
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return cause
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    if not _received:
        return None
    return _as_interrupt(_received[0])


def _quiet_stdout() -> None:
    """Point stdout at /dev/null, so that the interpreter's final flush of a closed pipe
    raises nothing more (Python's documented handling of SIGPIPE)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def reports_errors(func):
    """Decorate a command so that stabctl errors become one line and exit status 2.

    Parameters
    ----------
    func : callable
        The command's callback.

    Returns
    -------
    callable
        The wrapped callback: numeric options are checked first (:func:`check_number`:
        finite, in range); Python warnings raised meanwhile are held back and printed as
        ``warning:`` lines on stderr on success or the command's own exit status (on
        error only the ``error:`` line); an
        ``OSError`` (a disk full, a file the system refuses) is one ``error:`` line too
        (exit status 2; the outputs are written whole or not at all, and a sweep's
        finished records stay), one saying ``cannot write to standard output`` when it
        is stdout that failed (closed, its disk full: `stabctl.cli.stdout`); so is a
        ``MemoryError`` (an input or a run beyond the machine's memory); Ctrl-C
        prints what was kept (exit status 130), and so do SIGTERM and SIGHUP (exit
        status 143, 129), also when the interrupt surfaced as another error (raised in
        code that turned it into one: `_interrupt`); a closed pipe on stdout (``stabctl
        cases | head``) ends the command without a word (exit status 141, as SIGPIPE).
    """

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return _reported(func, args, kwargs)
        except KeyboardInterrupt as exc:  # a signal as the handling below began or ended
            click.echo(_interrupted(kwargs, exc), err=True)  # (click said "Aborted!", 1)
            sys.exit(_status(exc))

    return wrapper


def _reported(func, args, kwargs):
    """`reports_errors`'s call of the command ``func(*args, **kwargs)``, what it kept let
    go at its end (`keep_until_end`)."""
    try:
        return _reported_once(func, args, kwargs)
    finally:
        _released()


def _reported_once(func, args, kwargs):
    """`_reported`'s call of the command."""
    _WRITTEN.clear()  # this command's
    _KEEPING.clear()
    _ON_END.clear()
    _RELEASE.clear()
    with (
        warnings.catch_warnings(record=True) as caught,
        _sigterm_as_interrupt(),
        on_command_line(),
    ):
        warnings.simplefilter("default")
        _CAUGHT[:] = [caught]  # this command's
        try:
            try:
                _check_numbers(kwargs)
                _check_single_rate(kwargs)
                _check_scheduler(kwargs)
                out = func(*args, **kwargs)
            except Exception as exc:  # re-raised, or the interrupt behind it
                stop = _interrupt(exc)
                if stop is None:
                    raise
                raise stop from exc
        except StabctlError as exc:
            click.echo(f"error: {one_line(exc)}", err=True)
            sys.exit(2)
        except StdoutError as exc:  # stdout closed, its disk full
            click.echo(cannot_write(exc), err=True)
            sys.exit(2)
        except MemoryError as exc:  # an input or a run larger than this machine holds
            said = f" ({one_line(exc)})" if str(exc) else ""
            click.echo(
                f"error: out of memory{said}: the input or the run is larger than this "
                "machine (or its memory limit, ulimit -v) holds; no output is left "
                "half-written",
                err=True,
            )
            sys.exit(2)
        except BrokenPipeError:  # the reader went away (`stabctl cases | head`)
            _quiet_stdout()
            sys.exit(141)  # as a process killed by SIGPIPE
        except OSError as exc:  # a read or write the system refused (disk full, ...)
            where = f"{exc.filename}: " if exc.filename else ""
            click.echo(f"error: {where}{exc.strerror or one_line(exc)}", err=True)
            sys.exit(2)
        except KeyboardInterrupt as exc:
            click.echo(_interrupted(kwargs, exc), err=True)
            sys.exit(_status(exc))
        except SystemExit:  # the command's own status (`compile --check`'s 1)
            _ended()
            _say(caught)
            raise
    _ended()
    _say(caught)
    return out


def _status(exc: KeyboardInterrupt) -> int:
    """The exit status of a command an interrupt ended: 128 + its signal's number (130
    for a KeyboardInterrupt that carries none)."""
    return 128 + (exc.signum if isinstance(exc, Interrupted) else signal.SIGINT)


def _say(caught) -> None:
    """The warnings held back while a command ran, one ``warning:`` line each, a warning
    given again from another place (a setting checked by the command, then by each of
    its runs) once."""
    for text in _texts(caught):
        click.echo(f"warning: {text}", err=True)


def _texts(caught) -> list[str]:
    """The texts of the warnings `caught`, each once, on one line each."""
    return list(dict.fromkeys(" ".join(str(w.message).split()) for w in caught))


#: the warnings the running command has been given so far (`_reported`'s list)
_CAUGHT: list = []


def warnings_so_far() -> list[str]:
    """The warnings the running command has been given so far, each once, as its
    ``warning:`` lines will give them: for a JSON output, whose reader sees no stderr
    (``simulate --json``'s ``warnings``: a trapezoid step of 0.2 s gave a wrong verdict
    whose warning only stderr carried).

    Returns
    -------
    list of str
    """
    return _texts(_CAUGHT[-1]) if _CAUGHT else []


# -- numeric options checked at the edge -------------------------------------------------

_INF = float("inf")
#: allowed range of each numeric option: (low, high, low included, high included, unit).
#: Every float option, listed or not, must also be finite (no nan, inf). The OMIB ranges
#: (H, Pmax, f0) keep the swing frequency below about 25 Hz, so that the CCT bisection's
#: runs stay short (H = 0.001 s, f0 = 1000 Hz ran for many minutes).
_RANGES = {
    "--fault-cycles": (0, 600, True, True, "cycles"),
    "--H": (0.5, 50, True, True, "s"),
    "--pm": (0, 10, False, True, "pu"),
    "--delta0": (0, 1.5707963267948966, False, False, "rad"),
    "--pmax": (0, 10, False, True, "pu"),
    "--f0": (10, 400, True, True, "Hz"),
    "--t-fault": (0, 1000, True, True, "s"),
    "--clear-cycles": (0, 600, True, True, "cycles"),
    "--far-clear-cycles": (0, 600, True, True, "cycles"),
    "--t-trip": (0, 1000, True, True, "s"),
    # a run shorter than a microsecond is none: --tf 1e-320 reported "0-0 s, 0 steps, stable"
    "--tf": (1e-6, 3600, True, True, "s"),
    "--step": (0, 1, False, True, "s"),
    "--separation-limit": (0, 100, False, True, "rad"),
    "--esd-pct": (0, 100, False, True, "% of machine MVA"),
    "--deadband-hz": (0, 10, True, True, "Hz"),
    "--v-gate": (0, 2, True, True, "pu"),
    "--hysteresis-hz": (0, 10, True, True, "Hz"),
    "--tol-ms": (0.001, 1000, True, True, "ms"),  # stability.cct.MIN_TOL
    "--t-max": (0, 100, False, True, "s"),
    "--workers": (1, 1024, True, True, ""),
    "--circuit": (1, 99, True, True, ""),
    "--areas": (1, 1000, True, True, ""),
    "--target-cct-gain": (0, 1000, False, True, "%"),
    "--zeta-min": (0, 1, True, False, ""),
    "--max-sites": (1, 100000, True, True, ""),
    "--max-site-pct": (0, 100, False, True, "% of machine MVA"),
    # costs in any currency: a bound far above any real price, so that the optimisation
    # stays well scaled (--cost-mw 1e308 ended in a solver error)
    "--cost-mw": (0, 1e9, True, True, "per MW"),
    "--cost-mwh": (0, 1e9, True, True, "per MWh"),
    "--cost-site": (0, 1e9, True, True, "per site"),
    "--amplitude-hz": (0, 10, False, True, "Hz"),
    "--max-iter": (1, 1000, True, True, ""),
    "--rate": (1, 1000, True, True, "frames/s"),
    "--latency-ms": (0, 10000, True, True, "ms"),
    "--drop": (0, 1, True, False, ""),
    "--window-cycles": (1, 60, True, True, "cycles"),  # settings.WINDOW_CYCLES_MIN
    "--tve-pct": (0, 100, True, True, "%"),
    "--fe-hz": (0, 10, True, True, "Hz"),
    "--rfe-hz-s": (0, 100, True, True, "Hz/s"),
    "--k-sigma": (0.001, 100, True, True, ""),  # settings.K_SIGMA_MIN
    "--runs": (1, 100000, True, True, ""),
    "--seed": (0, 2**32 - 1, True, True, ""),
    "--settle-ms": (0, 100000, True, True, "ms"),
    "--ambient-s": (0, 36000, True, True, "s"),
    "--ambient-pct": (0, 100, True, True, "%"),
    "--ambient-tau-s": (0, 3600, False, True, "s"),
    "--ambient-runs": (1, 10000, True, True, ""),
    "--speed": (0, 1000, True, True, "time-stamp s per s"),
    # a PMU link's longest silence: 0 or below waited for ever or timed out at once
    "--timeout": (0, 86400, False, True, "s"),
}


class _Plain(click.ParamType):
    """A click number type that refuses what `plain_number` refuses before converting."""

    def convert(self, value, param, ctx):
        if isinstance(value, str) and not plain_number(value):
            self.fail(f"{value!r}: write numbers in ASCII digits, without '_'", param, ctx)
        return super().convert(value, param, ctx)


class PlainInt(_Plain, click.types.IntParamType):
    """click's integer type, `plain_number` spellings only."""


class PlainFloat(_Plain, click.types.FloatParamType):
    """click's float type, `plain_number` spellings only, -0 read as 0 (``--t-fault -0``
    was printed as a fault at -0 s), a number below the smallest float refused (``--tf
    1e-400`` was read as 0 and refused as ``--tf 0``)."""

    def convert(self, value, param, ctx):
        """The value as a float, -0 as 0 (click's `ParamType.convert`)."""
        out = super().convert(value, param, ctx) + 0.0
        if isinstance(value, str) and underflows(value, out):
            self.fail(f"{value}: {UNDERFLOW}", param, ctx)
        if isinstance(value, str) and math.isinf(out) and "inf" not in value.lower():
            shown = value if len(value) <= 24 else f"{value[:20]}... ({len(value)} characters)"
            self.fail(f"{shown}: beyond the largest number a float holds", param, ctx)
        return out


class PlainIntRange(_Plain, click.IntRange):
    """click's IntRange, `plain_number` spellings only."""


#: the number types of every option and argument (``type=int`` would read ``1_01`` as 101)
INT, FLOAT = PlainInt(), PlainFloat()


def interval(spec) -> str:
    """The allowed range of a :data:`_RANGES` entry as text, e.g. ``(0, 10] pu``.

    Parameters
    ----------
    spec : tuple
        (low, high, low included, high included, unit).

    Returns
    -------
    str
    """
    lo, hi, lo_in, hi_in, unit = spec
    return f"{'[' if lo_in else '('}{number_text(lo)}, {number_text(hi)}{']' if hi_in else ')'}" + (
        f" {unit}" if unit else ""
    )


def check_number(label: str, value) -> None:
    """Check one numeric option value against its allowed range.

    Parameters
    ----------
    label : str
        The option (``--tf``) or argument name, a key of :data:`_RANGES` or not.
    value : int or float
        The value given.

    Raises
    ------
    InputError
        Unless ``value`` is finite and inside the range of ``label`` (without one: at most
        :data:`ANY_NUMBER_MAX` in magnitude); the message names the option, the value and
        the allowed range.
    """
    spec = _RANGES.get(label)
    allowed = f" in {interval(spec)}" if spec else ""
    if isinstance(value, float) and not math.isfinite(value):
        raise InputError(f"{label} {value}: must be a finite number{allowed}")
    if spec is None:
        if abs(value) > ANY_NUMBER_MAX:
            raise InputError(
                f"{label} {number_text(value)}: beyond any value it can take (at most "
                f"{ANY_NUMBER_MAX:g} in magnitude)"
            )
        return
    lo, hi, lo_in, hi_in, _ = spec
    if not ((value >= lo if lo_in else value > lo) and (value <= hi if hi_in else value < hi)):
        raise InputError(f"{label} {number_text(value)}: must be{allowed}")


def _check_numbers(kwargs) -> None:
    """Check every numeric option of the running command (:func:`check_number`)."""
    ctx = click.get_current_context(silent=True)
    if ctx is None:
        return
    for param in ctx.command.params:
        if param.name not in kwargs:
            continue
        label = _option_name(param)
        for value in _numbers(kwargs[param.name]):
            # the options of _INF_MEANS are bounded by their command: only nan and -inf here
            if label not in _INF_MEANS or math.isnan(value) or value == -math.inf:
                check_number(label, value)


#: arguments that carry an option's further values, named as that option (`omib
#: --fault-cycles 6 12 15`: 12 and 15 are the argument MORE_CYCLES; round 48: "MORE_CYCLES
#: 0" named what the user never typed)
_VALUES_OF = {"MORE_CYCLES": "--fault-cycles"}


def _option_name(param: click.Parameter) -> str:
    """How messages name a parameter: its first long option name (``--dyr-conventions``,
    not its hidden alias or its Python name), or an argument's name (that of the option
    whose further values it carries, `_VALUES_OF`)."""
    name = next((o for o in param.opts if o.startswith("--")), None) or param.human_readable_name
    return _VALUES_OF.get(name, name)


#: largest magnitude of a number whose option has no range of its own (a time, a bus
#: number, a load step in pu): --load-step 4 1 1e308 0 ran, a load of 1e308 pu
ANY_NUMBER_MAX = 1e9

#: options where inf has a meaning (``--bus-fault``'s T_OFF: never cleared), checked
#: in place by their command
_INF_MEANS = {"--bus-fault"}


def comma_list(texts, option: str, convert, what: str) -> list:
    """The items of a comma-separated option value (or of several: ``multiple=True``),
    each converted, in order.

    Parameters
    ----------
    texts : str or sequence of str
        The option's value(s).
    option : str
        The option named in error messages.
    convert : callable
        ``convert(item) -> value``; raises ValueError for an item that is not one.
    what : str
        What an item is, for the message (e.g. "a bus number").

    Raises
    ------
    InputError
        An empty item (two commas in a row, a comma at an end), an item written with other
        than ASCII characters or with ``_`` (`plain_number`: int() reads ``1_3`` as 13),
        an item `convert` refuses, a number that is not finite (inf, nan, 1e400), or a
        value given twice.
    """
    out = []
    for text in (texts,) if isinstance(texts, str) else texts:
        for item in (x.strip() for x in str(text).split(",")):
            if not item:
                raise InputError(
                    f"{option} {text!r}: an empty item (two commas in a row or one at an end)"
                )
            value = _list_item(item, option, convert, what)
            if value in out:
                raise InputError(f"{option}: {item} given twice")
            out.append(value)
    return out


def _list_item(item: str, option: str, convert, what: str):
    """One item of `comma_list`, converted: InputError unless `plain_number`, accepted by
    `convert` and, a float, finite."""
    if not plain_number(item):
        raise InputError(f"{option} {item!r}: write numbers in ASCII digits, without '_'")
    try:
        value = convert(item)
    except ValueError:
        raise InputError(f"{option} {item!r}: not {what}") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise InputError(f"{option} {item}: must be a finite number")
    if isinstance(value, float) and underflows(item, value):
        raise InputError(f"{option} {item}: {UNDERFLOW}")
    return value


def _numbers(value):
    if isinstance(value, (tuple, list)):
        for v in value:
            yield from _numbers(v)
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        yield value


#: what an interrupted command keeps, by command (default: nothing)
_KEPT = {
    "sweep-cct": "finished jobs are in {out}; they are skipped",
    "screen": "finished searches are in {out}; they are skipped",
    "paper": "finished sweep records are kept in {out}/.paper-work for --resume",
}


#: files a command has written whole so far (`note_written`), said if it is interrupted
_WRITTEN: list[str] = []


def note_written(path) -> None:
    """Note that the running command has written `path` whole (renamed into place): an
    interrupt after it says so instead of "nothing is kept" (`import-psse`'s case,
    written before its summary is printed).

    Parameters
    ----------
    path : str or Path
        The file written.
    """
    _WRITTEN.append(str(path))


#: what the running command keeps should it be interrupted, in words (`note_keeping`)
_KEEPING: list = []


def note_keeping(what) -> None:
    """Note what the running command keeps should it be interrupted: an interrupt says
    ``interrupted: <what()>; run again with: <command>`` (`place`'s finished simulations).

    Parameters
    ----------
    what : callable
        ``what() -> str``, called when the interrupt is reported.
    """
    _KEEPING.append(what)


#: what removes the running command's kept work once the command has ended (`keep_until_end`)
_ON_END: list = []


def keep_until_end(kept, remove, release=None) -> None:
    """Note what the running command keeps should it be interrupted (`note_keeping`), and
    that ``remove()`` is called once the command has ended with its output delivered (it
    returned, or exited with its own status, `place`'s 1 "not verified").  Interrupted,
    refused (a scheduler not answering, a plan infeasible), its output not written (a
    full disk) or its workers lost, the work stays: the same command then reuses it
    (round 39: it was removed as the plan returned, before its output was written, and
    on any refusal; kept work untouched for `stabctl.locking.KEPT_DAYS` days is removed by
    the next command of its kind).  A removal that fails is a warning.

    Parameters
    ----------
    kept : callable
        ``kept() -> str``: what is kept, in words.
    remove : callable
        Removes what was kept.
    release : callable or None, optional
        Lets the kept work go (its file closed, its lock released) however the command
        ends, after `remove` if that is called.
    """
    note_keeping(kept)
    _ON_END.append(remove)
    if release is not None:
        _RELEASE.append(release)


#: what lets the running command's kept work go however it ends (`keep_until_end`)
_RELEASE: list = []


def _released() -> None:
    """Call the `keep_until_end` releases (every command's end)."""
    while _RELEASE:
        _RELEASE.pop()()


def _ended() -> None:
    """Call the `keep_until_end` removals of a command that has ended with its output
    delivered; one that fails (a directory made read-only) is a warning."""
    while _ON_END:
        try:
            _ON_END.pop()()
        except OSError as exc:  # (after the command's warnings were gathered)
            click.echo(f"warning: kept work not removed: {exc}", err=True)


def _paper_records(out) -> bool:
    """Whether an interrupted `stabctl paper` kept sweep records to resume from (in its
    output directory's work directory, `stabctl.studies.paper.WORK_DIR`)."""
    from stabctl.studies.paper import WORK_DIR

    try:
        return any(f.stat().st_size for f in (Path(out or ".") / WORK_DIR).glob("*.jsonl"))
    except OSError:
        return False


def _interrupted(kwargs, exc: BaseException | None = None) -> str:
    """The one line printed on Ctrl-C (SIGINT) or SIGTERM by every command: what was kept
    and the command that resumes (paper: with --resume); what the command itself said it
    kept, if it did (the interrupt's ``kept`` attribute: `pmu record`'s partial
    recording, what `estimate track` had received), and the command that runs it again."""
    ctx = click.get_current_context(silent=True)
    name = ctx.info_name if ctx is not None else ""
    argv = ["stabctl", *sys.argv[1:]]
    if said := getattr(exc, "kept", None):
        return f"interrupted: {said}; run again with: {shlex.join(argv)}"
    if _KEEPING:  # kept work the same command resumes from, or nothing kept after all
        said = _KEEPING[-1]()
        again = "run again with" if "nothing is kept" in said else "resume with"
        return f"interrupted: {said}; {again}: {shlex.join(argv)}"
    if name == "paper" and "--resume" not in argv:
        argv.append("--resume")
    out = kwargs.get("out_path") or kwargs.get("out_dir") or ""
    if name in ("sweep-cct", "screen") and out:
        from stabctl.parallel import read_records

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                out = f"{out} ({len(read_records(out))} recorded)"
            except (StabctlError, OSError):  # a file no longer read (above the size cap)
                pass
    if name in _LIVE:
        return f"interrupted: {_LIVE[name]}; run again with: {shlex.join(argv)}"
    if _WRITTEN:
        files = ", ".join(_WRITTEN)
        return f"interrupted: {files} had been written whole; run again with: {shlex.join(argv)}"
    kept = _KEPT.get(name or "")
    if name == "paper" and not _paper_records(out):
        kept = None  # no sweep had finished a job (the analytic part has none)
    if kept is None:  # nothing to resume from
        return f"interrupted: nothing is kept; run again with: {shlex.join(argv)}"
    return f"interrupted: {kept.format(out=out)}; resume with: {shlex.join(argv)}"


#: what an interrupted live command (a server, a closed loop) leaves: nothing to resume
_LIVE = {
    "plant": "the plant's run stopped with its controller's loop (a closed loop is not resumed)",
    "serve": "the server stopped (a live stream is not resumed: its PDCs connect again)",
    "replay": "the server stopped (a live stream is not resumed: its PDCs connect again)",
    "control": "the controller stopped (a closed loop is not resumed)",
}


# -- option decorators -------------------------------------------------------------------


def _apply(func, options):
    for opt in reversed(options):
        func = opt(func)
    return func


def json_option(what: str = "the result"):
    """``--json``: print ``what`` as JSON instead of text."""
    return click.option("--json", "as_json", is_flag=True, help=f"Print {what} as JSON.")


def _lower_first(text: str) -> str:
    """`text` with its first letter lowered to follow a colon, unless it starts an acronym
    (``"JSON lines"`` stays as it is)."""
    return text if text[1:2].isupper() else text[:1].lower() + text[1:]


def out_file_option(default=None, metavar="FILE", help="Output file."):
    """``--out FILE``: an output file (never a directory), into ``out_path``."""
    return click.option(
        "--out",
        "out_path",
        type=click.Path(dir_okay=False),
        default=default,
        show_default=default is not None,
        metavar=metavar,
        help=f"Output file: {_lower_first(help)}",
    )


def records_file(out_path: str | None, case_name: str, kind: str) -> str:
    """``--out`` of a resumable command, or its default ``KIND_<CASE>.jsonl`` (CASE's file
    name without ``.json``): one file per case, so that two cases studied in one directory
    neither refuse nor resume each other's records.

    Parameters
    ----------
    out_path : str or None
        The ``--out`` given, None when not.
    case_name : str
        The command's CASE, as given.
    kind : str
        ``"screening"`` or ``"sweep"``.

    Returns
    -------
    str
    """
    if out_path is not None:
        return out_path
    name = Path(case_name).name
    return f"{kind}_{name[:-5] if name.lower().endswith('.json') else name}.jsonl"


def out_dir_option(help="Report directory."):
    """``--out-dir DIR`` (hidden alias ``--out``): an output directory, into ``out_dir``."""
    # a path, checked by the command (check_writable): a file there is one `error:` line
    return click.option(
        "--out-dir",
        "--out",
        "out_dir",
        cls=AliasedOption,
        default="reports",
        show_default=True,
        metavar="DIR",
        type=click.Path(),
        help=f"Output directory: {_lower_first(help)}",
    )


def plot_option(what: str):
    """``--plot FILE.png|.pdf|.svg``: a figure file (.png, .pdf or .svg) of ``what``, into
    ``plot_path``."""
    return click.option(
        "--plot",
        "plot_path",
        type=click.Path(dir_okay=False),
        default=None,
        metavar="FILE.png|.pdf|.svg",
        help=f"Figure file (.png, .pdf or .svg): {what}.",
    )


def conventions_option(func):
    """``--conventions ieee|pstess``, the model conventions."""
    return click.option(
        "--conventions",
        type=click.Choice(["ieee", "pstess"]),
        default="ieee",
        show_default=True,
        help="Model conventions: ieee (IEEE 421.5 limiters, results converge "
        "with the step) or pstess (PSTess 1.1 bit for bit, quirks "
        "included); docs/conventions.md.",
    )(func)


#: where ``--single-rate`` is kept in the command's click context (`subintervals_chosen`)
_SINGLE_RATE = "stabctl.single_rate"


def _remember_single_rate(ctx, _param, value):
    ctx.meta[_SINGLE_RATE] = bool(value)
    return value


def _check_single_rate(kwargs) -> None:
    """Refuse --single-rate with --conventions pstess: PSTess never integrates an exciter
    in sub-intervals, so the option would change nothing."""
    if kwargs.get("conventions") == "pstess" and not subintervals_chosen():
        raise InputError(
            "--single-rate given with --conventions pstess: the pstess conventions always "
            "integrate the whole model at one step (sub-intervals are an ieee option)"
        )


def _check_scheduler(kwargs) -> None:
    """Refuse a --scheduler address that is none (`stabctl.parallel.check_scheduler`: an
    empty one, 'local' with a port, no URL) before any work: given, it is never taken for
    local processes; and --workers beside a scheduler's address, whose cluster has the
    workers it has (it was left unused without a word)."""
    address = kwargs.get("scheduler")
    if address is not None:
        from stabctl.parallel import check_scheduler

        check_scheduler(address)
        if address != "local" and kwargs.get("workers") is not None:
            raise InputError(
                f"--workers {kwargs['workers']} with --scheduler {address}: the jobs run on "
                "that cluster's workers, as many as it has; drop --workers (it sizes local "
                "processes, or a --scheduler local cluster)"
            )


def subintervals_chosen() -> bool:
    """Whether the running command integrates fast exciter loops in sub-intervals: True
    unless it was given ``--single-rate`` (`model_options`; True outside a command)."""
    ctx = click.get_current_context(silent=True)
    return not (ctx is not None and ctx.meta.get(_SINGLE_RATE, False))


def model_options(func):
    """``--conventions``, ``--step`` and ``--single-rate``, the same on every command that
    simulates (``--single-rate`` read through `subintervals_chosen`)."""
    func = click.option(
        "--single-rate",
        is_flag=True,
        expose_value=False,
        callback=_remember_single_rate,
        help="Integrate the whole model at one step: no exciter in sub-intervals "
        "(ieee; docs/simulator.md; refused with --conventions pstess, which never uses "
        "them).  The default step then falls to half the time constant of the fastest "
        "exciter loop where that is shorter (ACTIVSg2000: 1.2 ms instead of half a "
        "cycle); a case with no such loop (Kundur, miniWECC) runs as without it.",
    )(func)
    func = click.option(
        "--step",
        type=FLOAT,
        default=None,
        metavar="H",
        help="Integration step (s); default: ieee half a cycle capped at "
        "half the case's fastest time constant (Kundur and miniWECC "
        "5 ms); pstess the data file's step (Kundur 10 ms, miniWECC "
        "1/480 s).",
    )(func)
    return conventions_option(func)


def q_limits_option(func):
    """``--q-limits/--no-q-limits`` on every command that starts a run or linearises."""
    return click.option(
        "--q-limits/--no-q-limits",
        "q_limits",
        default=True,
        show_default=True,
        help="Power flow: PV buses switch to PQ at their reactive limits "
        "(PST's chq_lim) or keep their voltage without limits (ANDES's "
        "default, for comparisons with ANDES).",
    )(func)


def tf_option(extra: str = ""):
    """``--tf S``: end of each run (s), default the fault start + 5 s (into ``tf``)."""
    return click.option(
        "--tf",
        type=FLOAT,
        default=None,
        metavar="S",
        help=f"End of each run (s); default: the fault start + {TF_AFTER_FAULT_S:g} s{extra}.",
    )


def fault_text(fault, far_bus, circuit: int = 1) -> str:
    """The options of a fault as given: ``--fault BUS [--far-bus FAR] [--circuit K]``.

    Parameters
    ----------
    fault : int
        --fault's bus.
    far_bus : int or None
        --far-bus's bus, None if not given.
    circuit : int, optional
        --circuit's value (named only when not 1).

    Returns
    -------
    str
        For messages.
    """
    far = "" if far_bus is None else f" --far-bus {far_bus}"
    return f"--fault {fault}{far}" + (f" --circuit {circuit}" if circuit != 1 else "")


def check_option_events(case, given) -> None:
    """Look up in ``case`` the buses, lines, machines and motors the events of the options
    name, and check the size of each step (`stabctl.case.events.check_event`), before any
    work.

    Parameters
    ----------
    case : stabctl.case.Case
        The case.
    given : iterable of (str, event)
        Each event with the option that gave it, as given (``"--trip 3 77"``).

    Raises
    ------
    InputError
        The first event naming what the case lacks, at a negative time, or a load, VREF
        or PREF step of 0 or beyond its bound (`stabctl.case.events.step_limit`): the
        option as given, and the bus, line, machine or motor missing, the time, or the
        step's size, the bound and why.
    """
    from stabctl.case.events import check_event
    from stabctl.dynamics.events import refuse_negative_time

    for option, ev in given:
        with named_option(option):
            check_event(case, ev)
            refuse_negative_time(ev)  # the option named (round 55 AQ aside)


@contextmanager
def named_option(option: str) -> Iterator[None]:
    """Refuse what the block refuses (a CaseError or an InputError: an unknown bus or
    line, a value out of range) as an InputError naming the option that gave it first.

    Parameters
    ----------
    option : str
        The option as given (``"--fault 3 --far-bus 13"``).

    Yields
    ------
    None

    Raises
    ------
    InputError
        ``"{option}: {the block's message}"``.
    """
    from stabctl.errors import CaseError

    try:
        yield
    except (CaseError, InputError) as exc:
        raise InputError(f"{option}: {exc}") from None


def refuse_fault_of_no_length(ev, given: str, hint: str = "") -> None:
    """Refuse a fault cleared at both ends as it starts: it would do nothing (a zero-length
    interval of fault, the line, if any, tripped without one), as a second trip is
    refused.

    Parameters
    ----------
    ev : stabctl.case.events.Fault
        The fault.
    given : str
        The options that gave it, as given (``"--bus-fault 3 1 1"``).
    hint : str, optional
        What to give instead, completing the message.

    Raises
    ------
    InputError
        `ev` is cleared (near end, and far end if it has one) at its start: the message
        names `given`, the time and why.
    """
    if ev.clear_near is not None and ev.far_clear == ev.t:
        raise InputError(_no_length(given, ev.t, hint))
    if ev.clear_near is not None and ev.far_clear - ev.t < SHORTEST_FAULT_S:
        raise InputError(
            f"{given}: cleared {ev.far_clear - ev.t:.3g} s after it starts, under "
            f"{SHORTEST_FAULT_S:g} s: no step of a run is that short, so it would do "
            f"nothing{hint}"
        )


def refuse_cycles_of_no_length(
    near: float, far: float | None, t_fault: float, given: str, hint: str = ""
) -> None:
    """Refuse clearing cycles of 0 at both ends before the fault is built
    (`stabctl.dynamics.events.fault_with_clearing`, which refuses them in its arguments'
    words), as `refuse_fault_of_no_length` says it.

    Parameters
    ----------
    near, far : float, float or None
        The near- and far-end clearing cycles (``--clear-cycles``, ``--far-clear-cycles``;
        None: with the near end).
    t_fault : float
        The fault's start, s.
    given : str
        The options that gave it, as given.
    hint : str, optional
        What to give instead, completing the message.

    Raises
    ------
    InputError
        Both ends cleared at 0 cycles: the message names `given`, the time and why.
    """
    if (near if far is None else far) == 0:
        raise InputError(_no_length(given, t_fault, hint))


def _no_length(given: str, t: float, hint: str) -> str:
    return f"{given}: cleared at {t:g} s, as it starts: a fault of no length would do nothing{hint}"


#: the shortest fault a command runs, s: a microsecond, the resolution of the time stamps
#: (C37.118.2's TIME_BASE) and far below any integration step
SHORTEST_FAULT_S = 1e-6


def fault_options(required: bool, t_fault: bool = True, far_required: bool | None = None):
    """``--fault BUS --far-bus BUS`` and (``t_fault``) ``--t-fault S``: a bolted fault;
    `far_required` (default `required`): whether --far-bus must be given (without it the
    fault is cleared without loss of a line)."""
    far_required = required if far_required is None else far_required

    def default(required: bool) -> dict:
        # no default=None beside required=True: click >= 8.3 no longer enforces required
        # on an option that has a default, even None
        return {} if required else {"default": None}

    return lambda func: _apply(
        func,
        (
            click.option(
                "--fault",
                type=INT,
                required=required,
                **default(required),
                metavar="BUS",
                help="Three-phase (bolted) fault at bus BUS (bus number as in the data).",
            ),
            click.option(
                "--far-bus",
                type=INT,
                required=far_required,
                **default(far_required),
                metavar="BUS",
                help="Far end of the faulted line BUS-FAR_BUS, tripped at clearing."
                + (
                    ""
                    if far_required
                    else " Without it the fault is cleared without loss of a line."
                ),
            ),
            *(
                [
                    click.option(
                        "--t-fault",
                        type=FLOAT,
                        default=1.0,
                        show_default=True,
                        metavar="S",
                        help="Fault start time (s).",
                    )
                ]
                if t_fault
                else []
            ),
        ),
    )


def circuit_option(func):
    """``--circuit K``: which of parallel circuits BUS-FAR_BUS is faulted."""
    return click.option(
        "--circuit",
        type=INT,
        default=1,
        show_default=True,
        metavar="K",
        help="Which of parallel circuits BUS-FAR_BUS (in data order) is faulted.",
    )(func)


def clear_cycles_option(help="Clearing after N cycles of the case frequency."):
    """``--clear-cycles N`` (cycles)."""
    return click.option(
        "--clear-cycles",
        type=FLOAT,
        default=6.0,
        show_default=True,
        metavar="N",
        help=f"{help} (cycles).",
    )


def faults_option(func):
    """``--faults FILE.csv|DEFAULT`` (hidden, deprecated alias ``--contingencies``)."""
    return click.option(
        "--faults",
        "--contingencies",
        "faults_src",
        cls=AliasedOption,
        required=True,
        metavar="FILE.csv|DEFAULT",
        help="CSV with a header bus,far_bus[,t_fault,circuit], one line fault per row "
        "(cleared at both ends, line tripped; an empty far_bus: a bus fault, an empty "
        "t_fault or circuit: 1 s or 1, as without the column); DEFAULT: the built-in list (kundur: "
        "3-101, 13-101; miniwecc: 83-33, 40-44; faults at 1 s).",
    )(func)


def read_fault_list(case, case_name: str, src: str):
    """The faults of ``--faults``: the built-in list for DEFAULT, else the CSV file; each
    fault's buses and lines looked up in the case before any work.

    Parameters
    ----------
    case : stabctl.case.Case
        The case loaded from `case_name`.
    case_name : str
        The command's CASE, as given.
    src : str
        ``DEFAULT`` or a CSV path.

    Returns
    -------
    sequence of stabctl.stability.cct.LineFault

    Raises
    ------
    InputError
        A file the table refuses (`stabctl.stability.cct.read_faults`), or a fault of a
        bus or line the case lacks: ``--faults`` with the file and line, the fault and
        what is missing named.
    """
    # the one place the CLI imports the paper's default fault lists
    from stabctl.stability.cct import read_fault_rows
    from stabctl.studies.cases import default_faults

    if not src.strip():  # read_fault_rows would name the file only as "fault list"
        raise InputError("--faults: an empty path; give a file or DEFAULT")
    if src == "DEFAULT":
        rows = [(f, f"--faults {src}") for f in default_faults(case_name)]
    else:  # each fault named with its file:line; the file's own refusals with the option
        with named_option("--faults"):
            read = read_fault_rows(src)
        rows = [(f, f"--faults {src}:{line}") for f, line in read]
    for f, where in rows:
        check_option_events(case, ((f"{where}: {f.describe()}", ev) for ev in f.events(0)))
    return [f for f, _ in rows]


def tol_options(
    t_max: float = 1.0,
    t_max_help: str = "a fault still stable there is a verdict: CCT above it, robust",
):
    """``--tol-ms MS`` and ``--t-max S`` of the CCT searches."""
    return lambda func: _apply(
        func,
        (
            click.option(
                "--tol-ms",
                type=FLOAT,
                default=1.0,
                show_default=True,
                metavar="MS",
                help="Width of the final bracket of each CCT search (ms).",
            ),
            click.option(
                "--t-max",
                type=FLOAT,
                default=t_max,
                show_default=True,
                metavar="S",
                help=f"Longest clearing time tried (s); {t_max_help}.",
            ),
        ),
    )


def esd_model_option(func):
    """``--esd-model ideal|wecc``: the storage devices' model (`stabctl.storage.devices`
    `StorageFleet.model`): ideal power sources, or WECC batteries (REGCA1 + REECA1 in the
    storage current range + REPCA1) taking the law's power as their plant's reference."""
    return click.option(
        "--esd-model",
        type=click.Choice(["ideal", "wecc"]),
        default="ideal",
        show_default=True,
        help="Storage devices: ideal power sources, or WECC batteries (converter current "
        "limit, lags, voltage-dip logic, plant control; docs/storage.md) whose plant "
        "takes the controller's power as its reference.",
    )(func)


def storage_options(
    rating_help: str = "",
    multiple: bool = False,
    with_rating: bool = True,
    critical: bool = False,
):
    """The storage option set: ``--esd-pct`` (one rating, or with ``multiple`` a list),
    ``--deadband-hz``, ``--v-gate``, ``--coi``, ``--hysteresis-hz``: the paper's bang-bang
    COI control (Table 3). ``with_rating`` False: the controller options only (`place`
    sizes the storage itself). ``critical``: ``--coi`` offers ``critical`` too (only a
    command that finds the fault's critical machines, `stabctl cct`, can take it)."""
    esd = (
        click.option(
            "--esd-pct",
            multiple=True,
            metavar="P",
            help="Storage ratings (% of machine MVA): repeat or comma-separate; "
            "'none' = no storage (the default)." + rating_help,
        )
        if multiple
        else click.option(
            "--esd-pct",
            type=FLOAT,
            default=None,
            metavar="P",
            help="ESD of P % of each generator's MVA at its HV bus (% of "
            "machine MVA), the paper's bang-bang COI control (Table 3)." + rating_help,
        )
    )
    return lambda func: _apply(
        func,
        (
            *([esd] if with_rating else []),
            click.option(
                "--deadband-hz",
                type=FLOAT,
                default=0.1,
                show_default=True,
                help="ESD controller deadband on f_i - f_COI (Hz).",
            ),
            click.option(
                "--v-gate",
                type=FLOAT,
                default=0.8,
                show_default=True,
                help="ESDs act only while their bus voltage is at least this (pu).",
            ),
            click.option(
                "--coi",
                type=click.Choice(["system", "rest", *(["critical"] if critical else [])]),
                default="system",
                show_default=True,
                help="COI of the whole system or of the rest of it"
                + (
                    "; critical (not the paper's law): of the other group, the fault's "
                    "critical machines (SIME, from the run without storage) or the rest."
                    if critical
                    else "."
                ),
            ),
            click.option(
                "--hysteresis-hz",
                type=FLOAT,
                default=0.0,
                show_default=True,
                help="A running ESD stops only inside deadband - hysteresis (Hz).",
            ),
        ),
    )


def far_end(spec: str, option: str) -> tuple[int, int]:
    """(bus, circuit) of a line's far end given as TO or TO:K (circuit K, default 1).

    Parameters
    ----------
    spec : str
        The option's TO[:K] value.
    option : str
        The option's name, for the message.

    Returns
    -------
    tuple of int
        (TO, K).

    Raises
    ------
    InputError
        Not integers, or K < 1.
    """
    head, sep, ckt = spec.partition(":")
    try:
        if not plain_number(spec):
            raise ValueError(spec)
        if sep and not ckt:  # "101:" (round 45: read as circuit 1)
            raise ValueError(spec)
        to, k = int(head), int(ckt) if ckt else 1
    except ValueError:
        msg = f"{option} ... {spec}: give the far bus as TO or TO:K (integers)"
        raise InputError(msg) from None
    if k < 1:
        raise InputError(f"{option} ... {spec}: circuit K must be >= 1")
    return to, k


#: the storage options that mean nothing without a rating (`check_storage_given`)
STORAGE_SETTINGS = ("esd_model", "deadband_hz", "v_gate", "coi", "hysteresis_hz")


def given_options(*names: str) -> list[str]:
    """The options among `names` given on the command line (not left at their defaults).

    Parameters
    ----------
    *names : str
        Parameter names of the running command (``far_bus``).

    Returns
    -------
    list of str
        Those given, by their first long option name (``--far-bus``; ``--out`` for
        ``out_path``; an on/off flag as given, ``--no-guess``), in the order of `names`;
        empty outside a command.
    """
    ctx = click.get_current_context(silent=True)
    if ctx is None:
        return []
    params = {p.name: p for p in ctx.command.params}
    return [
        _given_name(params[name], ctx.params[name])
        for name in names
        if name in ctx.params
        and ctx.get_parameter_source(name) is click.core.ParameterSource.COMMANDLINE
    ]


def _given_name(param: click.Parameter, value) -> str:
    """How a message names an option given on the command line: an on/off flag's off
    form when that was given (``--no-guess``), else `_option_name`."""
    off = [o for o in getattr(param, "secondary_opts", ()) if o.startswith("--")]
    return off[0] if off and value is False else _option_name(param)


def refuse_given(names: tuple[str, ...], reason: str) -> None:
    """Refuse options that have no effect in this run, rather than ignore them.

    Parameters
    ----------
    names : tuple of str
        Parameter names of the running command.
    reason : str
        Why they have none, completing "OPTIONS given ...": ``"without --fault"``.

    Raises
    ------
    InputError
        One of them given on the command line, naming every such option.
    """
    stray = given_options(*names)
    if stray:
        raise InputError(f"{', '.join(stray)} given {reason}")


def check_storage_given(esd_pct, settings: tuple[str, ...] = STORAGE_SETTINGS) -> None:
    """Refuse storage settings given on the command line without --esd-pct: InputError
    naming them (nothing is ignored silently).

    Parameters
    ----------
    esd_pct : float or None
        The command's --esd-pct.
    settings : tuple of str, optional
        The parameter names checked: the storage settings, less those with a meaning of
        their own in the command (the estimators' ``coi``, the speed they estimate).

    Raises
    ------
    InputError
        A storage setting given without a rating.
    """
    if esd_pct is None:
        refuse_given(settings, "without --esd-pct (no storage to set)")


def controller(deadband_hz, v_gate, coi, hysteresis_hz, critical=()):
    """The ESD controller of the storage options.

    Parameters
    ----------
    deadband_hz, v_gate, coi, hysteresis_hz : float, float, str, float
        The options' values (`stabctl.storage.control.BangBangCOI`).
    critical : tuple of int, optional
        The critical machines of ``--coi critical`` (found by the command).

    Returns
    -------
    stabctl.storage.devices.BangBangCOI

    Raises
    ------
    InputError
        ``--coi critical`` in a command that does not find the critical machines.
    """
    from stabctl.storage.control import BangBangCOI

    if coi == "critical" and not critical:
        raise InputError(
            "--coi critical needs the fault's critical machines, which only `stabctl cct` "
            "finds (from its search without storage)"
        )
    return BangBangCOI(deadband_hz, v_gate, coi, hysteresis_hz, critical)


def parallel_options(func):
    """``--workers N`` and ``--scheduler ADDRESS``, the runner of
    :func:`stabctl.parallel.run_sweep`."""
    return _apply(
        func,
        (
            click.option(
                "--workers",
                type=INT,
                default=None,
                metavar="N",
                help="Local worker processes (default: the available cores, at most "
                "one per job); with --scheduler local, the Dask workers.",
            ),
            click.option(
                "--scheduler",
                default=None,
                metavar="ADDRESS",
                help="Dask distributed scheduler (tcp://host:8786) to run on instead, "
                "or 'local' for a local Dask cluster of --workers processes "
                "(needs pip install 'stabctl[dask]').  A cluster without a worker is "
                "waited for until one joins, said after 10 s.",
            ),
        ),
    )
