"""`stabctl estimate rmse|closed-loop|cct`: speed estimation from simulated PMU data.

The old form ``stabctl estimate CASE ...`` still works: it runs ``estimate rmse``, or with
the old flags ``--closed-loop`` / ``--cct`` the subcommand of that name.
"""

from __future__ import annotations

import errno
import functools
import glob
import json
import re
import warnings
from pathlib import Path

import click
import numpy as np

from stabctl.cli.checks import check_step_given, check_suffix, model_settings
from stabctl.cli.format import (
    closed_loop_lines,
    control_record,
    counted,
    estimator_cct_lines,
    print_estimate,
    print_json,
    shown,
)
from stabctl.cli.options import (
    FLOAT,
    INT,
    STORAGE_SETTINGS,
    PlainIntRange,
    _apply,
    check_storage_given,
    controller,
    esd_model_option,
    fault_options,
    given_options,
    json_option,
    keep_until_end,
    model_options,
    out_file_option,
    q_limits_option,
    refuse_given,
    reports_errors,
    storage_options,
)
from stabctl.cli.pmu_options import (
    ESTIMATOR,
    IDCODE,
    PMU_AT,
    WINDOW,
    check_latency,
    fail_short,
    fault_event,
    fault_run_options,
    keep_interrupted,
    kept_at,
    pmu_noise_options,
    pmu_settings,
    rate_for_case,
    rate_latency_options,
    stream_controller,
    stream_idcodes,
    write_kept,
    write_recording,
)
from stabctl.errors import InputError, StabctlError

#: the storage settings that mean nothing without --esd-pct here (--coi also picks the
#: centre of inertia the relative speeds are taken from)
_STORAGE_NOT_COI = tuple(n for n in STORAGE_SETTINGS if n != "coi")
#: `estimate rmse`'s controller options: the rule of the false ESD actions of its ambient
#: runs (its fault run's storage, with --esd-pct, takes the paper's settings)
_FALSE_ACTION_RULE = ("deadband_hz", "v_gate", "hysteresis_hz")

#: the old mode flags of `estimate CASE`, by the subcommand they select (one at most)
_LEGACY_FLAGS = (("--cct", "cct"), ("--closed-loop", "closed-loop"))


class _EstimateGroup(click.Group):
    """The `estimate` subcommands; arguments not starting with one (the old
    `estimate CASE ...`) go to `rmse`, or with the old --cct / --closed-loop flag to that
    subcommand."""

    def parse_args(self, ctx, args):
        if args and args[0] not in self.commands and args[0] not in ctx.help_option_names:
            modes = [flag for flag, _ in _LEGACY_FLAGS if flag in args]
            if len(modes) > 1:
                raise click.UsageError(
                    f"{' and '.join(modes)} select different subcommands (estimate "
                    f"{', estimate '.join(dict(_LEGACY_FLAGS)[f] for f in modes)}): give one",
                    ctx,
                )
            mode = dict(_LEGACY_FLAGS)[modes[0]] if modes else "rmse"
            args = [mode, *(a for a in args if a not in dict(_LEGACY_FLAGS))]
        return super().parse_args(ctx, args)


@click.group(cls=_EstimateGroup)
def estimate():
    """Machine and COI speed estimation from simulated PMU data, against the truth.

    \b
    rmse         errors of the raw PMU frequency, the Kalman filter (kf) and the
                 swing-equation EKF (ekf) against the true speeds, false ESD actions
    closed-loop  the fault with the ESDs commanded by each estimator in the loop
    cct          the fault's CCT with each estimator in the loop over noise seeds
    track        the speeds estimated from a recording or a C37.118.2 stream, no
                 simulation (field data)

    `stabctl estimate CASE ...` (no subcommand) is `stabctl estimate rmse CASE ...`;
    the old flags --closed-loop and --cct select those subcommands (one of them).
    """


def _runs_seed(func):
    return _apply(
        func,
        (
            click.option(
                "--runs",
                type=INT,
                default=20,
                show_default=True,
                metavar="N",
                help="Monte-Carlo runs (PMU noise seeds S, S+1, ..., S+N-1).",
            ),
            click.option(
                "--seed",
                type=INT,
                default=0,
                show_default=True,
                metavar="S",
                help="Seed of the first run.",
            ),
        ),
    )


@estimate.command()
@fault_run_options
@PMU_AT
@storage_options(
    " In the fault run, controlled on the true speeds with the paper's "
    "settings; the controller options set the rule of the false actions."
)
@esd_model_option
@_runs_seed
@click.option(
    "--settle-ms",
    type=FLOAT,
    default=100.0,
    show_default=True,
    metavar="MS",
    help="Errors are taken from this long after the clearing to the end (ms).",
)
@click.option(
    "--ambient-s",
    type=FLOAT,
    default=60.0,
    show_default=True,
    metavar="S",
    help="Length of the runs without fault for the false ESD actions (s; 0: skip).",
)
@click.option(
    "--ambient-pct",
    type=FLOAT,
    default=1.0,
    show_default=True,
    metavar="P",
    help="Ambient load fluctuation in the runs without fault: standard deviation "
    "of every load's P (%; 0: PMU noise only).",
)
@click.option(
    "--ambient-tau-s",
    type=FLOAT,
    default=2.0,
    show_default=True,
    metavar="T",
    help="Correlation time of the ambient load fluctuation (s).",
)
@click.option(
    "--ambient-runs",
    type=INT,
    default=5,
    show_default=True,
    metavar="N",
    help="Runs without fault (load and PMU noise seeds S..S+N-1).",
)
@click.option(
    "--source",
    metavar="tcp://HOST:PORT[,...]|FILE",
    default=None,
    help="Take the PMU frames of the fault run from C37.118.2 streams over TCP (e.g. "
    "`stabctl pmu serve` with the same fault and --seed) or from a recording, instead of "
    "drawing --runs streams here; one run, no runs without fault.",
)
@model_options
@q_limits_option
@json_option("the figures")
@reports_errors
def rmse(
    case_name,
    fault,
    far_bus,
    t_fault,
    clear_cycles,
    tf,
    rate,
    latency_ms,
    drop,
    tve_pct,
    fe_hz,
    rfe_hz_s,
    k_sigma,
    window_cycles,
    pmu_at,
    esd_pct,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    esd_model,
    runs,
    seed,
    settle_ms,
    ambient_s,
    ambient_pct,
    ambient_tau_s,
    ambient_runs,
    source,
    conventions,
    step,
    q_limits,
    as_json,
):
    """Errors of the speed estimators against the truth, and false ESD actions.

    The fault run is simulated once (with --esd-pct, storage acts on the true speeds; with
    --esd-model wecc the devices are WECC batteries); then, per Monte-Carlo run, every
    generator's PMU stream is drawn (IEEE C37.118.1 noise limits read as k-sigma bounds,
    latency, lost frames) and fed frame by frame to the raw PMU frequency, the baseline
    Kalman filter on frequency/ROCOF (kf) and the swing-equation EKF (ekf).

    \b
    Printed per estimator, mean +- standard deviation over the runs (mHz): RMSE of the
    machine speeds, of the COI speed and of the relative speeds f_i - f_COI the ESD
    controllers use, at the frame time stamps from --settle-ms after the clearing to
    --tf; the relative-speed RMSE at each frame's arrival (latency included), as
    delivered and forecast to the arrival; the fraction of normalised innovations
    squared inside their 95 % chi-square interval (consistency: about 0.95).  Then, on
    --ambient-runs runs without fault of --ambient-s with ambient load fluctuation (every
    load's P an Ornstein-Uhlenbeck process of --ambient-pct standard deviation and
    --ambient-tau-s correlation time, stabctl.estimation.ambient), the number of ESD
    actions (Table 3 rule with --deadband-hz) each estimate would trigger (all are
    false), the largest abs(f_i - f_COI) and the largest standard deviation of f_i - f_COI
    (true: the ambient spread).

    With --source the frames come from C37.118.2 streams (docs/estimation.md 6): the
    figures of the one stream received, the same seed's figures in process beside them.

    \b
    Example:
      stabctl estimate rmse kundur --fault 3 --far-bus 101 --runs 2
    """
    from stabctl.estimation import ambient as am
    from stabctl.studies.estimate import ErrorRuns, error_window, estimator_errors

    _check_positive(tf=tf, runs=runs, deadband_hz=deadband_hz)
    if min(settle_ms, ambient_s, seed) < 0 or ambient_runs < 1:
        raise InputError("--settle-ms, --ambient-s and --seed must be >= 0, --ambient-runs >= 1")
    src = _source(source)
    if ambient_s == 0:
        refuse_given(
            ("ambient_pct", "ambient_tau_s", "ambient_runs"), "with --ambient-s 0 (no ambient run)"
        )
    ambient = am.AmbientLoad(ambient_pct, ambient_tau_s, seed)
    settings = pmu_settings(
        rate, latency_ms, drop, tve_pct, fe_hz, rfe_hz_s, k_sigma, window_cycles
    )
    # the controller options set the rule of the false actions, counted on the ambient
    # runs, which have no storage: they need ambient runs, not --esd-pct (round 56 AT)
    if src is not None or ambient_s == 0:
        refuse_given(
            _FALSE_ACTION_RULE,
            f"with {'--source' if src is not None else '--ambient-s 0'} (no ambient run: "
            "they set the rule of the false ESD actions, counted on the runs without "
            "fault; the fault run's storage takes the paper's settings)",
        )
    check_storage_given(esd_pct, ("esd_model",))
    case, ev, tf = fault_event(case_name, fault, far_bus, t_fault, clear_cycles, tf)
    settings = rate_for_case(settings, rate, case)
    if 0 < ambient_s < 1 / settings.rate:  # was said without the option (round 55 AS)
        raise InputError(
            f"--ambient-s {ambient_s:g}: an ambient run lasts at least one PMU frame interval, "
            f"1/{settings.rate:g} s (or give 0: no ambient run)"
        )
    check_latency(settings, error_window(ev, settle_ms / 1000, tf)[0], tf, f"--tf {tf:g} s")
    mc = ErrorRuns(
        runs=runs,
        seed=seed,
        pmu_at=pmu_at,
        coi=coi,
        control=controller(deadband_hz, v_gate, coi, hysteresis_hz),
        ambient=ambient,
        ambient_s=ambient_s,
        ambient_runs=ambient_runs,
    )
    d = estimator_errors(
        case,
        ev,
        mc,
        settings=settings,
        esd_pct=esd_pct,
        settle_s=settle_ms / 1000,
        t_end=tf,
        model=model_settings(conventions, step, q_limits),
        esd_model=esd_model,
        source=src,
        progress=src is None,
    )
    out = {
        **_what_ran(case, (fault, far_bus, t_fault, clear_cycles), esd_pct, settings, seed),
        "esd_model": esd_model,
        "runs": 1 if src else runs,
        "source": d.get("source"),
        "window_s": d["window_s"],
        "stable": d["stable"],
        "estimators": d["estimators"],
        "false_actions": d["false_actions"],
        "ambient": {
            "t_s": ambient_s,
            **control_record(deadband_hz, v_gate, coi, hysteresis_hz),  # the false actions' rule
            "pct": ambient_pct,
            "tau_s": ambient_tau_s,
            "runs": ambient_runs,
        },
    }
    out["pmu"]["at"] = pmu_at
    if as_json:
        print_json(out)
        return
    print_estimate(out)


def _source(text):
    """The `sources.Source` of --source (None without); the Monte-Carlo and ambient
    options given with it are refused, not ignored."""
    if text is None:
        return None
    from stabctl.estimation.sources import parse_source

    clash = given_options("runs", "ambient_s", "ambient_pct", "ambient_tau_s", "ambient_runs")
    if clash:
        raise InputError(
            f"--source evaluates the one stream received; {', '.join(clash)} cannot go with it"
        )
    return parse_source(text)


def _check_positive(**values) -> None:
    for name, value in values.items():
        if value is not None and not value > 0:
            raise InputError(f"--{name.replace('_', '-')} must be > 0, got {value:g}")


@estimate.command("closed-loop")
@fault_run_options
@storage_options(" Required: the ESDs the estimators command.")
@esd_model_option
@click.option(
    "--seed", type=INT, default=0, show_default=True, metavar="S", help="Seed of the PMU noise."
)
@click.option(
    "--transport",
    type=click.Choice(["process", "codec", "tcp"]),
    default="process",
    show_default=True,
    help="How the frames reach the controller: in memory; in memory through the C37.118.2 "
    "frame codec; or as a C37.118.2 stream over loopback TCP with the modes sent back "
    "(round trips measured).",
)
@model_options
@q_limits_option
@json_option("the verdicts")
@reports_errors
def closed_loop(
    case_name,
    fault,
    far_bus,
    t_fault,
    clear_cycles,
    tf,
    rate,
    latency_ms,
    drop,
    tve_pct,
    fe_hz,
    rfe_hz_s,
    k_sigma,
    window_cycles,
    esd_pct,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    esd_model,
    seed,
    transport,
    conventions,
    step,
    q_limits,
    as_json,
):
    """The fault simulated with the ESDs commanded by each estimator in the loop.

    For each estimator (ideal, raw, kf, ekf; PMU noise seed --seed) the verdict, the
    number of mode commands the controller sent the ESDs (JSON `mode_commands`: each a
    switching, unless the device's voltage gate --v-gate holds it idle, as while a fault
    is on) and the false actions; with --transport tcp also the frames and their measured
    round trips (docs/estimation.md 6).

    \b
    Example:
      stabctl estimate closed-loop kundur --fault 3 --far-bus 101 --esd-pct 5
    """
    from stabctl.studies.estimate import closed_loop_verdicts

    _check_positive(tf=tf, deadband_hz=deadband_hz)
    if esd_pct is None:
        raise InputError("estimate closed-loop needs --esd-pct")
    settings = pmu_settings(
        rate, latency_ms, drop, tve_pct, fe_hz, rfe_hz_s, k_sigma, window_cycles
    )
    case, ev, tf = fault_event(case_name, fault, far_bus, t_fault, clear_cycles, tf)
    settings = rate_for_case(settings, rate, case)
    check_latency(settings, t_fault, tf, f"--tf {tf:g} s")
    rows = closed_loop_verdicts(
        case,
        ev,
        t_end=tf,
        settings=settings,
        esd_pct=esd_pct,
        seed=seed,
        control=controller(deadband_hz, v_gate, coi, hysteresis_hz),
        deadband_hz=deadband_hz,
        model=model_settings(conventions, step, q_limits),
        esd_model=esd_model,
        transport=transport,
    )
    law = control_record(deadband_hz, v_gate, coi, hysteresis_hz)
    out = {
        **_what_ran(case, (fault, far_bus, t_fault, clear_cycles), esd_pct, settings, seed),
        "control": law,
        "closed_loop": rows,
        "transport": transport,
        "esd_model": esd_model,
        "lines": closed_loop_lines(rows, fault, far_bus, esd_pct, seed, esd_model, law),
    }
    click.echo(json.dumps(out, indent=1) if as_json else "\n".join(out["lines"]))


@estimate.command("cct")
@click.argument("case_name", metavar="CASE")
@fault_options(required=True, t_fault=False)
@rate_latency_options
@click.option(
    "--esd-pct",
    type=FLOAT,
    required=True,
    metavar="P",
    help="ESD of P % of each generator's MVA at its HV bus (% of machine MVA), "
    "the paper's bang-bang COI control (Table 3).",
)
@WINDOW
@_runs_seed
@esd_model_option
@model_options
@q_limits_option
@json_option("the CCTs")
@reports_errors
def cct(
    case_name,
    fault,
    far_bus,
    rate,
    latency_ms,
    esd_pct,
    window_cycles,
    runs,
    seed,
    esd_model,
    conventions,
    step,
    q_limits,
    as_json,
):
    """CCT of the fault line with each estimator in the loop, over --runs noise seeds.

    The CCT searches run in parallel; printed per estimator: mean and spread (cycles).

    \b
    Example:
      stabctl estimate cct kundur --fault 3 --far-bus 101 --esd-pct 5 --runs 4
    """
    from stabctl.studies.estimate import estimator_ccts

    _check_positive(runs=runs)
    settings = pmu_settings(rate, latency_ms, window_cycles=window_cycles)
    case, ev, t_end = fault_event(case_name, fault, far_bus, 1.0, 6.0, None)  # checks the line
    settings = rate_for_case(settings, rate, case)
    check_latency(
        settings, ev.t, t_end, f"the runs' end {t_end:g} s (the fault at {ev.t:g} s + 5 s)"
    )
    model = model_settings(conventions, step, q_limits)
    check_step_given(case, model, t_end)  # before the searches: not one failure per run
    _check_estimable(case, model)
    search = {
        "case": case.digest(),
        "fault": [fault, far_bus],
        "esd_pct": esd_pct,
        "runs": runs,
        "seed": seed,
        "pmu": dict(settings.__dict__),
        "model": model.to_inputs(),
        "esd_model": esd_model,
    }
    records = _kept_records(search)  # None: in a temporary file, removed
    if records is not None:  # (held by no one: `_kept_records`)
        keep_until_end(lambda: _kept_searches(records), lambda: _remove_kept(records))
    study = functools.partial(
        estimator_ccts,
        case_name,  # the file given, not the case's name: an edited copy of a built-in
        fault,
        far_bus,
        esd_pct=esd_pct,
        runs=runs,
        seed=seed,
        settings=settings,
        model=model,
        esd_model=esd_model,
    )
    try:
        table = study(records=records)
    except InputError as exc:  # its records taken meanwhile: by the same command
        if records is None or not str(exc).startswith(f"{records}: another stabctl"):
            raise
        raise _running(records, re.search(r"\(pid (\w+)\)", str(exc))) from None
    except OSError as exc:  # its cache full or read-only meanwhile: kept nowhere then
        if records is None or exc.errno not in _UNWRITABLE:
            raise
        warnings.warn(
            f"{records}: cannot be written ({exc.strerror}): the searches are run again in "
            "a temporary file, not kept",
            stacklevel=2,
        )
        table = study(records=None)
    if all(row["failed"] == row["runs"] for row in table.values()):
        why = sorted({e for row in table.values() for e in row["errors"]})
        raise InputError(f"every CCT search failed: {'; '.join(why) or 'no reason recorded'}")
    out = {
        # the searches fault at 1 s (round 41: null here, as if none had a time)
        **_what_ran(case, (fault, far_bus, ev.t, None), esd_pct, settings, seed),
        "runs": runs,
        "cct_cycles": table,
        "esd_model": esd_model,
        "lines": estimator_cct_lines(
            table, fault, far_bus, esd_pct, settings, runs, seed, esd_model, case.freq_hz
        ),
    }
    click.echo(json.dumps(out, indent=1) if as_json else "\n".join(out["lines"]))


def _kept_records(search: dict):
    """The records file of `estimate cct`'s searches (this user's
    `stabctl.locking.kept_path`, named by the package's code and the search's every
    setting, `search`), so that the same command after an interrupt runs only the
    searches not yet recorded; telling on stderr how many it holds.  None, with a
    warning, where none can be kept (a read-only cache and temporary directory): the
    searches are then recorded in a temporary file, as before."""
    import hashlib

    from stabctl._jit.cache import package_digest
    from stabctl.locking import holder, kept_path, remove_old_kept
    from stabctl.parallel import read_records

    text = json.dumps([package_digest(), search], sort_keys=True, default=str)
    name = hashlib.sha256(text.encode()).hexdigest()[:32] + ".jsonl"
    try:
        path = kept_path("stabctl-estimate", name)
    except InputError as exc:
        warnings.warn(
            f"{exc}: the searches are not kept (an interrupted run starts again)",
            stacklevel=2,
        )
        return None
    if (pid := holder(path)) is not None:  # before its records are read or kept
        raise _running(path, pid)
    remove_old_kept(path.parent)
    if path.stat().st_size:
        try:
            n = len(read_records(path))
        except (StabctlError, OSError) as exc:
            warnings.warn(f"{exc}: the searches it kept are run again", stacklevel=2)
            _remove_kept(path)
            return path
        click.echo(
            f"{n} finished CCT search(es) of an interrupted run of this command read from "
            f"{path}: not run again",
            err=True,
        )
    return path


#: the errors of a cache that takes no more (`estimate cct`'s kept records)
_UNWRITABLE = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS)


def _running(records, pid) -> InputError:
    """The error of an `estimate cct` whose kept records another process holds: the same
    command running (pid: a text, a regular-expression match of it, or None)."""
    if isinstance(pid, re.Match):
        pid = pid.group(1)
    return InputError(
        f"the same estimate cct is running (pid {pid or 'unknown'}), keeping its searches "
        f"in {records}: wait for it to end, or run this one with other settings"
    )


def _remove_kept(records) -> None:
    """Remove `estimate cct`'s kept records and what reading them set aside
    (``<records>.damaged``: `stabctl.parallel.set_aside_damaged`)."""
    for path in (records, *records.parent.glob(glob.escape(records.name) + ".damaged*")):
        path.unlink(missing_ok=True)


def _kept_searches(records) -> str:
    """What an interrupted `estimate cct` keeps, in words."""
    from stabctl.parallel import read_records

    try:
        n = len(read_records(records)) if records.exists() else 0
    except (StabctlError, OSError):
        n = 0
    if not n:
        return f"no CCT search had finished, so nothing is kept (in {records})"
    return (
        f"{n} finished CCT search(es) are kept in {records}; the same command runs only the others"
    )


def _what_ran(case, fault: tuple, esd_pct, settings, seed) -> dict:
    """The head of an `estimate` command's JSON: the case, the fault (bus, far bus, start
    s and clearing cycles; None where the command searches them), the storage rating, the
    PMU settings and the noise seed (closed-loop's and cct's JSON had none of these)."""
    bus, far_bus, t_fault, clear_cycles = fault
    return {
        "case": case.name,
        "fault": {
            "bus": bus,
            "far_bus": far_bus,
            "t_fault_s": t_fault,
            "clear_cycles": clear_cycles,
        },
        "esd_pct": esd_pct,
        "pmu": dict(settings.__dict__),
        "seed": seed,
    }


def _check_estimable(case, model) -> None:
    """Before `estimate cct` dispatches its searches (each would fail alike, the command
    exiting 0 with every estimator "failed"): the case's power flow, and the estimators'
    machine models (`stabctl.estimation.models.machine_models`: PST tg governors only).

    Raises
    ------
    PowerFlowError, CaseError
        As `check_power_flow` and `machine_models`.
    """
    from stabctl.cli.checks import check_power_flow
    from stabctl.estimation.models import machine_models
    from stabctl.estimation.pmu import machine_pmus

    check_power_flow(case, model)
    machine_models(case, machine_pmus(case))


@estimate.command("track")
@click.argument("case_name", metavar="CASE")
@click.option(
    "--source",
    required=True,
    metavar="tcp://HOST:PORT[,...]|FILE",
    help="The C37.118.2 streams over TCP or the recording to track.",
)
@click.option(
    "--until",
    "until_s",
    type=FLOAT,
    default=None,
    help="Last time stamp to track (s; t = 0 is the CFG-2's time stamp, SOC and fraction; "
    "the time elapsed, across a leap second too). A TCP source needs --until or --frames.",
)
@click.option(
    "--frames",
    type=PlainIntRange(1, 10_000_000),
    default=None,
    help="Data frames to take from each stream.",
)
@IDCODE
@ESTIMATOR
@rate_latency_options
@pmu_noise_options
@PMU_AT
@storage_options(" Optional: the ESDs whose Table 3 modes are written too.")
@out_file_option(metavar="FILE.csv", help="Needed: the estimates, a row per frame.")
@reports_errors
def track(
    case_name,
    source,
    until_s,
    frames,
    idcode,
    estimator,
    rate,
    latency_ms,
    drop,
    tve_pct,
    fe_hz,
    rfe_hz_s,
    k_sigma,
    window_cycles,
    pmu_at,
    esd_pct,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    out_path,
):
    """The speeds of CASE's machines estimated from PMU frames that come from outside (a
    field recording, a PDC over TCP) with no simulation: per frame, each machine's speed
    and the COI speed (Hz) and the relative speeds f_i - f_COI (mHz), forecast over
    --latency-ms as the ESD controllers use them, with --esd-pct the modes Table 3
    would command, and each machine's age (age_<PMU>_s: seconds since its last usable
    PMU value, 0 when measured in the frame; above 0 its speed is held (raw) or
    predicted (kf, ekf) across a gap).  The PMUs' station names must be CASE's generator PMUs
    (docs/estimation.md 6.1); the noise options state the PMUs' accuracy the filters are
    tuned to.  Over TCP the commands address stream --idcode, and every frame is checked
    (CRC; each data frame's IDCODE, type, size and FRACSEC count against its CFG-2, and
    its time stamp against the one before; a CFG-2 resent must be the one in use: a frame
    refused refuses the source, exit status 2 and nothing written, where `pmu record`
    keeps the frames before it) and must come whole within 30 s, each data frame within
    30 s of the one before.  A stream that stops before
    --until or --frames is tracked as far as it came,
    written, and named an error (exit status 2: the result is partial), unless --out
    exists: a file there is replaced only by the track of a whole stream (the file left
    as it was, refused before any tracking), as `pmu record` does.  Frames stamped off
    the reporting instants of their CFG-2's DATA_RATE refuse the source; reporting
    instants no stream sent are counted and said: a gap of at most 1 s is filled with
    missing values, after a longer one the estimator starts again.  Interrupted (Ctrl-C,
    SIGTERM) while estimating, the frames estimated so far are written likewise, as a
    partial estimate (exit status 130, 143), and said; interrupted before (a TCP stream is
    estimated once received), no frame is estimated and no CSV is written: it says how
    many frames had come, and writes each stream's frames received beside OUT as a
    partial recording, STEM.received.c37, to track with --source.  So does a source of
    several servers refused for one of them (one that sends no CFG-2, say): the other
    streams' frames are kept.

    \b
    Example:
      stabctl estimate track miniwecc --source wecc.c37 --out tracked.csv
      stabctl estimate track miniwecc --source tcp://127.0.0.1:4712 --until 60 --out t.csv
    """
    from stabctl.estimation import closed_loop as cl
    from stabctl.estimation import sources
    from stabctl.estimation.c37_tcp import End
    from stabctl.io import load_case

    if out_path is None:  # not click's required: --source is checked as it is parsed
        raise InputError("estimate track needs --out FILE.csv")
    check_suffix(out_path, (".csv",), "--out")
    settings = pmu_settings(
        rate, latency_ms, drop, tve_pct, fe_hz, rfe_hz_s, k_sigma, window_cycles
    )
    check_storage_given(esd_pct, _STORAGE_NOT_COI)
    refuse_given(
        ("drop", "window_cycles"),
        "to estimate track: its frames are the recorded ones (no PMU is simulated)",
    )
    refuse_given(
        ("v_gate",),
        "to estimate track: its ESD modes are the controller's commands, and no device is "
        "simulated to gate them by its bus voltage (the plant's devices do: pmu plant "
        "--v-gate)",
    )
    src = sources.parse_source(source)
    end = End(frames, until_s)
    if src.path is None and not end.given:
        raise InputError("a TCP --source needs its end: --until S or --frames N")
    if src.path is not None:
        refuse_given(
            ("idcode",),
            "with a recording as --source: it addresses a TCP server's stream (a "
            "recording's frames carry their own IDCODE)",
        )
    codes = stream_idcodes(idcode, len(src.servers)) if src.path is None else 1
    try:  # the case, its estimators (compiled if not cached) and the frames
        case = load_case(case_name)
        settings = rate_for_case(settings, rate, case)
        law = controller(deadband_hz, v_gate, coi, hysteresis_hz)
        ctrl = stream_controller(case, estimator, settings, esd_pct, law, pmu_at)
        got = sources.read_frames(src, case, ctrl.pmus, settings.rate, end, idcode=codes)
    except KeyboardInterrupt as exc:  # said with what had come, kept as a recording
        left = "left as it was" if Path(out_path).exists() else "not written"
        received = getattr(exc, "received", "")
        exc.kept = (  # type: ignore[attr-defined]
            f"nothing is tracked ({out_path} {left}): the {received} had come, short of "
            f"{end}, and a stream is tracked once received; "
            + _keep_received(out_path, getattr(exc, "recordings", []), case_name)
            if received and not received.startswith("0 ")
            else f"no frame was estimated: none had come from {src} yet, so nothing is "
            f"kept ({out_path} {left})"
        )
        raise
    except InputError as exc:  # a stream failed: the others' frames kept as on Ctrl-C
        if not (recordings := getattr(exc, "recordings", [])):
            raise
        kept = _keep_received(out_path, recordings, case_name)
        raise InputError(f"{exc}; nothing is tracked, but {kept}") from None
    why = f"--source {src} stopped before {end}: {'; '.join(got.short)}"
    kept = f"{_instants(got)} tracked"
    at = kept_at(out_path) if got.short else out_path
    try:
        d = cl.track(ctrl, got.frames, got.breaks)
    except KeyboardInterrupt as exc:  # what was estimated is kept, as record keeps frames
        d = ctrl.diagnostics()
        what = f"{len(d.t)} of the {counted(len(got.frames), 'frame')} from {src} estimated"
        exc.kept = (  # type: ignore[attr-defined]
            keep_interrupted(
                out_path,
                what,
                len(d.t),
                "frame estimated" if len(d.t) == 1 else "frames estimated",
                "a partial estimate",
                lambda to: _write_track(to, ctrl, d, esd_pct is not None),
            )
            if d.t.size
            else f"no frame was estimated yet, so nothing is kept: {what}"
        )
        raise
    short = why if got.short else None
    write_kept(at, lambda to: _write_track(to, ctrl, d, esd_pct is not None), short, kept)
    rel = np.where(d.formed[:, None], np.abs(d.rel), -1.0)
    worst = np.unravel_index(np.argmax(rel), rel.shape) if d.formed.any() else None
    named = [_measured(case, p) for p in ctrl.pmus]  # as every other output names them
    unformed = d.unformed(named)
    click.echo(
        f"tracked {_instants(got)} from {src} with {estimator}"
        + (
            ""
            if worst is None
            else f": largest |f_i - f_COI| {1e3 * abs(d.rel[worst]):.1f} mHz "
            f"({named[worst[1]]} at {d.t[worst[0]]:.3f} s)"
        )
        + (f"; {unformed}" if unformed else "")
        + (f"; {counted(d.starts, 'ESD start')}" if esd_pct is not None else "")
        + (f"; {flagged}" if (flagged := sources.unused_values(got.flagged)) else "")
        + (f"; {gaps}" if (gaps := sources.gap_line(got)) else "")
        + "".join(f"; {unsent}" for unsent in got.unsent)
        + f"; wrote {shown(at)}"
    )
    if got.short:
        fail_short(out_path, at, why, kept)


def _measured(case, pmu) -> str:
    """What a PMU's frequency is named by in `estimate track`'s text: its machine as every
    output names machines, with the PMU's station name, ``"G2 (bus 2; PMU B2:G2)"``
    (round 45: the station name alone, ``B2:G2``, where others say ``G2 (bus 2)``); a
    PMU of no machine by its station name."""
    if pmu.machine is None:
        return f"PMU {pmu.label}"
    return f"{case.machine_name(pmu.machine)[:-1]}; PMU {pmu.label})"


def _keep_received(out_path, recordings: list, case_name: str) -> str:
    """What an `estimate track` interrupted while receiving keeps of its TCP streams,
    for its ``interrupted:`` line: each stream's CFG-2 and data frames (`recordings`:
    (server, CFG-2 bytes, data frames), `sources.read_frames`) written beside --out as a
    partial recording, ``STEM.received.c37`` (``STEM.received-K.c37`` for stream K of
    several; `keep_interrupted`: beside a file already there), to be tracked with
    ``--source`` that file."""
    out = Path(out_path)
    said = []
    for k, (server, cfg2, frames) in enumerate(recordings, 1):
        tag = "received" if len(recordings) == 1 else f"received-{k}"
        at = out.with_name(f"{out.stem}.{tag}.c37")
        said.append(
            keep_interrupted(
                at,
                f"{server} sent {'it' if len(frames) == 1 else 'them'}",
                len(frames),
                "data frame received" if len(frames) == 1 else "data frames received",
                "a partial recording",
                lambda to, cfg2=cfg2, frames=frames: write_recording(to, cfg2, frames),
            )
        )
    if not said:
        return "they are lost"
    return (
        "; ".join(said) + f" (track it: stabctl estimate track {case_name} --source FILE --out ...)"
    )


def _instants(got) -> str:
    """What `estimate track` tracked: its frames, or, where gaps were filled with missing
    values (`stabctl.estimation.sources.Gap`), the reporting instants, the received apart
    from the filled."""
    n = len(got.frames)
    filled = sum(g.frames for g in got.gaps if g.filled)
    if not filled:
        return counted(n, "frame")
    return (
        f"{counted(n, 'reporting instant')} ({n - filled} received, {filled} of gaps "
        "filled with missing values)"
    )


def _write_track(out_path, ctrl, d, with_modes: bool) -> None:
    """`estimate track`'s CSV (`_track_columns`) written atomically to ``out_path``."""
    from stabctl.parallel import atomic_write

    head, rows = _track_columns(ctrl, d, with_modes)
    atomic_write(
        out_path,
        lambda f: np.savetxt(f, rows, delimiter=",", header=head, comments="", fmt="%.9g"),
    )


def _track_columns(ctrl, d, with_modes: bool) -> tuple[str, np.ndarray]:
    """`estimate track`'s CSV header and rows: t, each machine's speed (Hz), the COI speed
    (Hz), each relative speed (mHz), with_modes: each ESD's mode; then each machine's
    age (s since its last usable PMU value, `Diagnostics.age`: 0 measured in the frame,
    above 0 held (raw) or predicted (kf, ekf) across a gap; round 44: a held value was
    written as a measured one)."""
    labels = [p.label for p in ctrl.pmus]
    head = ["t_s", *(f"f_{x}_hz" for x in labels), "f_coi_hz"]
    head += [f"rel_{x}_mhz" for x in labels]
    cols = [d.t[:, None], d.freq, (d.freq - d.rel)[:, :1], 1e3 * d.rel]  # nan: not formed
    if with_modes:
        buses = ctrl.case.buses.number[ctrl.sa.bus]
        head += [f"mode_esd{k + 1}_bus{int(b)}" for k, b in enumerate(buses)]
        cols.append(d.modes)
    head += [f"age_{x}_s" for x in labels]
    cols.append(d.age)
    return ",".join(head), np.hstack(cols) if d.t.size else np.zeros((0, len(head)))
