"""The PMU options `stabctl estimate` and `stabctl pmu` share, each declared once: reporting
rate, latency, the C37.118.1 noise limits, the PMU placement, and the fault run they
measure."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import click

from stabctl.cli.options import (
    FLOAT,
    TF_AFTER_FAULT_S,
    _apply,
    check_option_events,
    clear_cycles_option,
    fault_options,
    fault_text,
    named_option,
    refuse_cycles_of_no_length,
    refuse_fault_of_no_length,
    tf_option,
)
from stabctl.errors import InputError, number_text
from stabctl.estimation.settings import RATES, RATES_TEXT, check_rate, nominal_rate
from stabctl.estimation.settings import PMUSettings as _PMU  # its defaults are the CLI's
from stabctl.io.inputs import plain_integer, shown_field

RATE = click.option(
    "--rate",
    type=FLOAT,
    default=None,
    show_default="60 at 60 Hz, 50 at 50 Hz",
    metavar="FPS",
    help="PMU reporting rate (frames/s), one of the case's nominal frequency (C37.118.1): "
    "10, 12, 15, 20, 30, 60 or 120 at 60 Hz; 10, 25, 50 or 100 at 50 Hz; by default the "
    "nominal frequency's, one frame per cycle.",
)
IDCODE = click.option(
    "--idcode",
    default="1",
    show_default=True,
    metavar="N[,N...]",
    help="IDCODE of the C37.118.2 stream to receive, which the commands address (a server "
    "drops a PDC that addresses another stream): one for every server, or one per server "
    "in the order given; `pmu serve` (--each-pmu too), `plant` and the replay of their "
    "recordings send 1.",
)


def stream_idcodes(text: str, servers: int) -> list[int]:
    """The IDCODE each of `servers` TCP servers is addressed with, from ``--idcode``: one
    for all, or one per server.

    Parameters
    ----------
    text : str
        The option's value, ``N[,N...]``.
    servers : int
        The servers of the source.

    Returns
    -------
    list of int
        One IDCODE per server.

    Raises
    ------
    InputError
        An item that is not a number in 1-65534 written in ASCII digits (an empty one
        too), or a count that is neither 1 nor `servers`.
    """
    codes = []
    for item in (x.strip() for x in text.split(",")):
        code = plain_integer(item, 5) if item.isdigit() else None
        if code is None or not 1 <= code <= 65534:
            raise InputError(
                f"--idcode {shown_field(text)!r}: {shown_field(item)!r} is not an IDCODE "
                "(a number in 1-65534; C37.118.2 reserves 0 and 65535)"
            )
        codes.append(code)
    if len(codes) not in (1, servers):
        raise InputError(
            f"--idcode {text}: {len(codes)} IDCODEs for {servers} server(s); give one for "
            "all, or one per server in the order of the source"
        )
    return codes * servers if len(codes) == 1 else codes


PMU_AT = click.option(
    "--pmu-at",
    type=click.Choice(["terminal", "hv"]),
    default="terminal",
    show_default=True,
    help="PMU of each generator at its terminal or HV bus.",
)


def rate_latency_options(func):
    return _apply(
        func,
        (
            RATE,
            click.option(
                "--latency-ms",
                type=FLOAT,
                default=1000 * _PMU.latency_s,
                show_default=True,
                metavar="MS",
                help="Delay from a frame's time stamp to its arrival (ms).",
            ),
        ),
    )


def pmu_noise_options(func):
    return _apply(
        func,
        (
            click.option(
                "--drop",
                type=FLOAT,
                default=_PMU.drop_prob,
                show_default=True,
                metavar="P",
                help="Probability that a frame is lost.",
            ),
            click.option(
                "--tve-pct",
                type=FLOAT,
                default=100 * _PMU.tve,
                show_default=True,
                help="Total vector error limit (%), C37.118.1 Table 3.",
            ),
            click.option(
                "--fe-hz",
                type=FLOAT,
                default=_PMU.fe_hz,
                show_default=True,
                help="Frequency error limit (Hz), C37.118.1 Table 4.",
            ),
            click.option(
                "--rfe-hz-s",
                type=FLOAT,
                default=_PMU.rfe_hz_s,
                show_default=True,
                help="ROCOF error limit (Hz/s), C37.118.1 Table 4.",
            ),
            click.option(
                "--k-sigma",
                type=FLOAT,
                default=_PMU.k_sigma,
                show_default=True,
                help="The limits are this many standard deviations of the errors.",
            ),
            WINDOW,
        ),
    )


WINDOW = click.option(
    "--window-cycles",
    type=FLOAT,
    default=_PMU.window_cycles,
    show_default=True,
    metavar="C",
    help="Frequency and ROCOF estimation window (cycles): "
    "the phase advance over it; 2 = P class (C37.118.1-2011 Annex C).",
)


def pmu_settings(
    rate,
    latency_ms,
    drop=_PMU.drop_prob,
    tve_pct=100 * _PMU.tve,
    fe_hz=_PMU.fe_hz,
    rfe_hz_s=_PMU.rfe_hz_s,
    k_sigma=_PMU.k_sigma,
    window_cycles=_PMU.window_cycles,
):
    """The PMUSettings of the command line's values (its units: %, ms), checked before the
    case is read.

    Parameters
    ----------
    rate : float or None
        ``--rate``; None (not given): the settings hold the API default until
        `rate_for_case` gives them the case's nominal rate.
    latency_ms : float
        ``--latency-ms``.
    drop, tve_pct, fe_hz, rfe_hz_s, k_sigma, window_cycles : float
        ``--drop``, ``--tve-pct``, ``--fe-hz``, ``--rfe-hz-s``, ``--k-sigma``,
        ``--window-cycles``.

    Returns
    -------
    PMUSettings
        The settings; pass them through `rate_for_case` once the case is known.

    Raises
    ------
    InputError
        A rate C37.118.1 lists for neither 50 nor 60 Hz systems, naming --rate; a value
        `PMUSettings` refuses.
    """
    if rate is not None and rate not in RATES:
        raise InputError(
            f"--rate {number_text(rate)}: must be one of {RATES_TEXT} (C37.118.1 reporting rates)"
        )
    return _PMU(
        rate=_PMU.rate if rate is None else rate,
        tve=tve_pct / 100,
        fe_hz=fe_hz,
        rfe_hz_s=rfe_hz_s,
        k_sigma=k_sigma,
        latency_s=latency_ms / 1000,
        drop_prob=drop,
        window_cycles=window_cycles,
    )


def rate_for_case(settings, rate, case):
    """The settings of `pmu_settings` with --rate resolved for `case`, as soon as it is
    read: the case's nominal rate (`nominal_rate`: 60 frames/s at 60 Hz, 50 at 50 Hz)
    when --rate was not given, else the rate given if it is one of the case's frequency.

    Parameters
    ----------
    settings : stabctl.estimation.settings.PMUSettings
        As `pmu_settings` made them.
    rate : float or None
        ``--rate``, None when not given.
    case : stabctl.case.Case
        The case (its ``freq_hz``).

    Returns
    -------
    stabctl.estimation.settings.PMUSettings
        The settings at the rate used.

    Raises
    ------
    InputError
        A rate given that is not one of the case's nominal frequency
        (`stabctl.estimation.settings.check_rate`), naming --rate, the frequency and its
        rates, and suggesting ``--rate`` of its nominal rate.
    """
    if rate is None:
        return replace(settings, rate=nominal_rate(case.freq_hz))
    check_rate(rate, case.freq_hz, "--rate {}", "give {}")
    return settings


def check_latency(settings, t_first: float, t_end: float, end: str) -> None:
    """Refuse, before any run, a --latency-ms under which no frame the command uses
    arrives within the run (its figures or commands would all come after the run's end).

    Parameters
    ----------
    settings : stabctl.estimation.settings.PMUSettings
        Its latency.
    t_first : float
        Time stamp of the first frame the command uses, s (the fault's start, or the
        start of the errors' window).
    t_end : float
        The run's end, s.
    end : str
        The run's end as the message names it, e.g. ``"--tf 2 s"``.

    Raises
    ------
    InputError
        That frame arriving (``t_first`` + the latency) at or after ``t_end``, naming
        --latency-ms and ``end``.
    """
    arrival = t_first + settings.latency_s
    if not arrival < t_end:
        raise InputError(
            f"--latency-ms {1000 * settings.latency_s:g} with {end}: no PMU frame used "
            f"arrives within the run (the first, time-stamped at {t_first:g} s, arrives at "
            f"{arrival:g} s); give a shorter latency or a later end"
        )


def fault_event(case_name, fault, far_bus, t_fault, clear_cycles, tf):
    """The case, the fault event and the end of the run (default: fault + 5 s); an unknown
    bus or line refused before any work, naming --fault / --far-bus
    (`check_option_events`)."""
    from stabctl.dynamics.events import fault_with_clearing
    from stabctl.io import load_case

    tf = t_fault + TF_AFTER_FAULT_S if tf is None else tf
    if not tf > 0:
        raise InputError(f"--tf must be > 0, got {tf:g}")
    case = load_case(case_name)
    given = f"{fault_text(fault, far_bus)} --clear-cycles {clear_cycles:g}"
    refuse_cycles_of_no_length(clear_cycles, None, t_fault, given, ": give --clear-cycles > 0")
    with named_option(fault_text(fault, far_bus)):
        ev = fault_with_clearing(case, fault, far_bus, t_fault, clear_cycles)
    refuse_fault_of_no_length(ev, given, ": give --clear-cycles > 0")
    check_option_events(case, [(fault_text(fault, far_bus), ev)])
    if late := [t for t in ev.times() if t >= tf]:
        what = "starts" if late[0] == min(ev.times()) else "is cleared"
        raise InputError(
            f"{fault_text(fault, far_bus)} --t-fault {t_fault:g} --clear-cycles "
            f"{clear_cycles:g}: the fault {what} at {late[0]:g} s, at or after the end of "
            f"the run (--tf {tf:g} s): give a later --tf, or an earlier or shorter fault"
        )
    return case, ev, tf


def fault_run_options(func):
    """The options of a PMU run through a fault (estimate rmse and closed-loop, pmu plant):
    case, fault, clearing, end time, PMU rate and latency, PMU noise."""
    return _apply(
        func,
        (
            click.argument("case_name", metavar="CASE"),
            fault_options(required=True),
            clear_cycles_option("Clearing after N cycles, both ends"),
            tf_option(),
            rate_latency_options,
            pmu_noise_options,
        ),
    )


#: the speed estimator of a controller fed from outside (pmu control, estimate track)
ESTIMATOR = click.option(
    "--estimator",
    type=click.Choice(["raw", "kf", "ekf"]),
    default="ekf",
    show_default=True,
    help="The speed estimator fed the frames.",
)


def stream_controller(case, estimator, settings, esd_pct, law, pmu_at):
    """The `LoopController` of CASE fed frames from outside (its PMUs, `estimator`, Table 3
    with `law` on ESDs of esd_pct % of machine MVA, 1 % if None), its filters compiled
    before the first frame arrives."""
    from stabctl.estimation.closed_loop import LoopController
    from stabctl.estimation.filters import compile_filters
    from stabctl.storage.devices import uniform_fleet

    devices = uniform_fleet(case, 1.0 if esd_pct is None else esd_pct).devices
    ctrl = LoopController(case, devices, estimator, settings, 0, 1.0, law, pmu_at)
    compile_filters(ctrl.models)
    return ctrl


def write_recording(out, cfg2: bytes, data) -> None:
    """A C37.118.2 recording written atomically to `out`: the CFG-2 frame, then the data
    frames (`pmu record`; what `estimate track` had received when interrupted).

    Parameters
    ----------
    out : str or Path
        The file.
    cfg2 : bytes
        The stream's CFG-2 frame.
    data : sequence of bytes
        Its data frames, in order.
    """
    from stabctl.parallel import atomic_write

    atomic_write(out, lambda f: f.write(cfg2 + b"".join(data)), mode="wb")


def kept_at(out) -> Path:
    """Where a stream cut short keeps what it brought: `out` itself when no file is there,
    else a sibling ``STEM.partial.SUFFIX`` (``STEM.partial-2.SUFFIX``, ... when that is
    taken too), so a file at `out` is replaced only by a whole result and the frames that
    came are not lost (`pmu record`, `estimate track`).

    Parameters
    ----------
    out : str or Path
        The output file asked for.

    Returns
    -------
    Path
        A path where no file is.
    """
    out = Path(out)
    n = 1
    at = out
    while at.exists() or at.is_symlink():
        tag = "partial" if n == 1 else f"partial-{n}"
        at = out.with_name(f"{out.stem}.{tag}{out.suffix}")
        n += 1
    return at


def where_kept(out, at) -> str:
    """Where `kept_at` put a partial result, as a message ends: ``"in OUT"``, or ``"in
    SIBLING (OUT is left as it was)"``.

    Parameters
    ----------
    out : str or Path
        The output file asked for.
    at : str or Path
        Where the partial result was written.

    Returns
    -------
    str
        The words.
    """
    return f"in {at}" if Path(at) == Path(out) else f"in {at} ({out} is left as it was)"


def write_kept(at, write, why: str | None, kept: str) -> None:
    """``write(at)``; when the stream stopped before its end (`why`), a write that fails
    (a disk full) says that too: it was "r.partial.c37: No space left on device" alone,
    the shortfall unsaid.

    Parameters
    ----------
    at : str or Path
        Where to write (`kept_at` for a stream cut short).
    write : callable
        ``write(path)``, atomic.
    why : str or None
        The stream and what cut it (`fail_short`), None or empty for a whole stream.
    kept : str
        What came, e.g. ``"121 received"``.

    Raises
    ------
    InputError
        The write failed after a stream cut short: both named.
    OSError
        The write failed after a whole stream.
    """
    try:
        write(at)
    except OSError as exc:
        if not why:
            raise
        raise InputError(
            f"{why}; the {kept} could not be kept: {at}: {exc.strerror or exc}"
        ) from None


def fail_short(out, at, why: str, kept: str) -> None:
    """Name, as an error, a stream that stopped before its end: `at` (`kept_at`) holds what
    it brought, written whole as far as the stream came, so the frames received are kept
    while the exit status says the result is partial.

    Parameters
    ----------
    out : str or Path
        The output file asked for.
    at : str or Path
        Where what came was written.
    why : str
        The stream and what cut it.
    kept : str
        What came, e.g. ``"121 received"``.

    Raises
    ------
    InputError
        Always: the message names the shortfall and where what came is (exit status 2).
    """
    raise InputError(f"{why}; the {kept} are {where_kept(out, at)}")


def keep_interrupted(out, what: str, n: int, noun: str, partial: str, write) -> str:
    """What an interrupted command keeps, for its ``interrupted:`` line: `n` items (the
    frames `pmu record` received, the frames `estimate track` estimated) written by
    `write` (atomically) to `out`, or beside it when a file is there (`kept_at`: left as
    it was, as for any stream cut short).  A second interrupt while writing leaves the
    files as they were.

    Parameters
    ----------
    out : str or Path
        The output file asked for.
    what : str
        What was done before the interrupt, as the line starts.
    n : int
        The items kept (at least 1).
    noun : str
        What they are, after their number, singular for one (``"received"``, ``"frames
        estimated"``, ``"frame estimated"``).
    partial : str
        What the file written then is (``"a partial recording"``).
    write : callable
        ``write(path)`` writes them to `path`, atomically, as a partial result.

    Returns
    -------
    str
        Where the items are, or why they are lost.
    """
    are = "is" if n == 1 else "are"
    at = kept_at(out)
    try:
        write(at)
    except OSError as exc:
        return f"{what}; the {n} {noun} {are} lost: {at}: {exc.strerror or exc}"
    except KeyboardInterrupt:
        return f"{what}; the {n} {noun} {are} lost: interrupted again while writing {at}"
    left = "" if at == Path(out) else f" ({out} is left as it was)"
    return f"{what}; the {n} {noun} {are} in {at}, {partial}{left}"
