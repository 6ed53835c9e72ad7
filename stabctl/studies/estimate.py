"""The three studies of `stabctl estimate`, callable without the command line.

- :func:`estimator_errors` (`estimate rmse`): one fault run, then Monte-Carlo PMU
  streams fed to every estimator, errors against the truth, and false ESD actions on
  runs without fault (:mod:`stabctl.studies.estimation`);
- :func:`closed_loop_verdicts` (`estimate closed-loop`): the fault simulated with the
  ESDs commanded by each estimator in the loop;
- :func:`estimator_ccts` (`estimate cct`): the fault's CCT with each estimator in the
  loop over noise seeds (:func:`stabctl.estimation.closed_loop.cct_study`).
"""

from __future__ import annotations

import os
from contextlib import nullcontext
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from stabctl.errors import InputError, require_instance
from stabctl.locking import temp_dir
from stabctl.progress import bar

if TYPE_CHECKING:
    from stabctl.estimation.ambient import AmbientLoad
    from stabctl.storage.control import BangBangCOI


@dataclass(frozen=True)
class ErrorRuns:
    """The Monte-Carlo set-up of `estimator_errors`.

    Attributes
    ----------
    runs, seed : int
        Monte-Carlo runs with PMU noise seeds seed .. seed + runs - 1.
    pmu_at : {"terminal", "hv"}
        Where the PMUs measure.
    coi : {"system", "rest"}
        The centre of inertia the relative speeds are taken from.
    control : stabctl.storage.control.BangBangCOI
        The ESD rule whose false actions are counted.
    ambient : stabctl.estimation.ambient.AmbientLoad
        Ambient load fluctuation of the runs without fault (run r: seed + r).
    ambient_s : float
        Length of the runs without fault (s; 0: no false-action count).
    ambient_runs : int
        Runs without fault.
    """

    runs: int
    seed: int
    pmu_at: str
    coi: str
    control: BangBangCOI
    ambient: AmbientLoad
    ambient_s: float
    ambient_runs: int


def error_window(event, settle_s: float, t_end: float) -> tuple[float, float]:
    """The time stamps `estimator_errors` evaluates: from ``settle_s`` after the fault's
    clearing to the run's end.

    Parameters
    ----------
    event : stabctl.dynamics.events.Fault
        The fault, with its clearing.
    settle_s, t_end : float
        Settling time after the clearing and the run's end, s.

    Returns
    -------
    tuple of float
        (start, end), s.

    Raises
    ------
    InputError
        ``t_end`` not after the start, naming --tf.
    """
    start = max(event.times()) + settle_s
    if not start < t_end:
        raise InputError(f"--tf {t_end:g} s ends before the errors start ({start:g} s)")
    return start, t_end


def estimator_errors(
    case,
    event,
    mc: ErrorRuns,
    *,
    settings,
    esd_pct,
    settle_s: float,
    t_end: float,
    model=None,
    esd_model: str = "ideal",
    source=None,
    progress: bool = False,
) -> dict:
    """Errors of every estimator against the simulated truth, and false ESD actions.

    Parameters
    ----------
    case : stabctl.case.Case
    event : stabctl.dynamics.events.Fault
        The fault (with its clearing) of the fault run.
    mc : ErrorRuns
        Noise runs and seed, PMU placement, COI, ESD rule, ambient runs.
    settings : stabctl.estimation.settings.PMUSettings
    esd_pct : float or None
        Storage in the fault run (% of machine MVA, paper's controller on the true
        speeds); None: none.
    settle_s, t_end : float
        Errors are taken from ``settle_s`` after the clearing to ``t_end`` (s), the end of
        the fault run.
    model : stabctl.dynamics.options.ModelOptions or None
        Conventions, step and Q limits (None: the defaults).
    esd_model : {"ideal", "wecc"}, optional
        The model of the fault run's storage (`stabctl.storage.devices.StorageFleet.model`);
        the runs without fault have none (their false actions are counted, not simulated).
    source : stabctl.estimation.sources.Source or None, optional
        Frames of this fault run received from a recording or over TCP (one run, labelled
        with ``mc.seed``) instead of ``mc.runs`` streams drawn here; no runs without fault.
    progress : bool, optional
        Show a bar of the noise and ambient runs on stderr (`stabctl.progress.bar`: the
        fraction done and the time left; round 47: `estimate rmse --runs 30` was silent
        for minutes); default False.

    Returns
    -------
    dict
        ``window_s``, ``stable`` (the fault run), ``estimators`` (figures per estimator,
        :func:`stabctl.studies.estimation.monte_carlo`) and ``false_actions`` (None
        without ambient runs or with a source); with a source also ``source``: its counts
        (`stabctl.estimation.sources.Received.summary`) and the mean figures of the same
        seed's stream drawn in process as it is (``in_process``) and encoded and parsed
        back as on the wire (``on_wire``, `stabctl.estimation.c37.on_wire`).

    Raises
    ------
    InputError
        A PMU rate that is not one of the case's nominal frequency
        (`stabctl.estimation.settings.check_rate`), before the fault run; ``t_end``
        before the errors start; a source as
        `stabctl.estimation.sources.read_frames`, or one whose streams stop before the
        run's end, or with a gap of reporting instants longer than
        `stabctl.estimation.sources.FILL_S` (`stabctl.estimation.sources.Received.breaks`)
        or a PMU whose values are unusable that long (`sources.longest_unusable`).
    """
    from stabctl.dynamics.options import ModelOptions
    from stabctl.estimation import ambient as am
    from stabctl.estimation.filters import compile_filters
    from stabctl.estimation.models import machine_models
    from stabctl.estimation.pmu import machine_pmus
    from stabctl.estimation.settings import check_rate
    from stabctl.storage.devices import uniform_fleet
    from stabctl.studies import estimation as study

    check_rate(settings.rate, case.freq_hz)
    window = error_window(event, settle_s, t_end)
    fleet = None if esd_pct is None else uniform_fleet(case, esd_pct, model=esd_model)
    sim = (model or ModelOptions()).simulator(
        case, injection_buses=() if fleet is None else fleet.buses
    )
    compile_filters(machine_models(case, machine_pmus(case, mc.pmu_at)))
    res = sim.run([event], t_end=t_end, storage=fleet)
    if source is not None:
        return {
            "window_s": list(window),
            "stable": res.stable,
            **_received(case, res, settings, source, mc, window),
            "false_actions": None,
        }
    ambient = mc.ambient_runs if mc.ambient_s > 0 else 0
    with bar(mc.runs + ambient, "estimate: noise and ambient runs", progress, "run") as shown:
        figures = study.monte_carlo(
            case, res, settings, mc.runs, mc.seed, window, mc.pmu_at, mc.coi, shown.update
        )
        flat = []
        for r in range(ambient):
            flat.append(
                am.simulate(sim, mc.ambient_s, replace(mc.ambient, seed=mc.seed + r), settings.rate)
            )
            shown.update()
    actions = None
    if ambient:
        actions = study.false_actions(case, flat, settings, mc.seed, mc.control, mc.pmu_at)
    return {
        "window_s": list(window),
        "stable": res.stable,
        "estimators": figures,
        "false_actions": actions,
    }


def _received(case, res, settings, source, mc: ErrorRuns, window) -> dict:
    """`estimator_errors`' figures of a source's frames, with the same seed's in-process
    figures as drawn and as on the wire."""
    from stabctl.estimation import c37, sources
    from stabctl.estimation import pmu as pm
    from stabctl.estimation.c37_tcp import End
    from stabctl.studies import estimation as study

    pmus = pm.machine_pmus(case, mc.pmu_at)
    end = End(tf=float(res.t[-1]) - 0.5 / settings.rate)  # the run's last reporting instant
    got = sources.read_frames(source, case, pmus, settings.rate, end)
    if len(got.frames) and (first := float(got.frames.t[0])) < -0.5 / settings.rate:
        raise InputError(  # before "short": a CFG-2 stamped late was named short (round 40)
            f"--source {source} starts at t = {first:.4f} s, {round(-first * settings.rate)} "
            "reporting instant(s) before the run's first (t = 0, the CFG-2's time stamp): "
            "frames of before the run, or a CFG-2 stamped after its first data frame: not "
            "a stream of this run"
        )
    if got.short:
        raise InputError(
            f"--source {source} is short of the run's {res.t[-1]:g} s: {'; '.join(got.short)}"
        )
    if len(got.frames) and (first := float(got.frames.t[0])) > 0.5 / settings.rate:
        raise InputError(  # as one cut at its end (round 38: its start was never counted)
            f"--source {source} starts at t = {first:.4f} s, {round(first * settings.rate)} "
            "reporting instant(s) after the run's first (t = 0, the CFG-2's time stamp): the "
            "run's start is not in it (a recording cut at its beginning)"
        )
    if got.breaks:
        raise InputError(
            f"--source {source}: {sources.gap_line(got)}: a gap longer than "
            f"{sources.FILL_S:g} s, which the estimators cannot be evaluated across"
        )
    if lost := sources.longest_unusable(got.frames, [p.label for p in pmus]):
        raise InputError(
            f"--source {source}: {lost}: longer than {sources.FILL_S:g} s without a usable "
            "value, which the estimators cannot be evaluated across (as a gap)"
        )
    truth = pm.phasor_truth(case, res, pmus, settings.window_cycles)
    drawn = pm.measure(truth, settings, mc.seed)
    wire = c37.on_wire(c37.stream_config(case, pmus, settings.rate), drawn)
    at = (mc.seed, window, mc.pmu_at, mc.coi)
    means = lambda figs: {e: {m: v["mean"] for m, v in f.items()} for e, f in figs.items()}  # noqa: E731
    return {
        "estimators": study.received_errors(case, res, settings, got.frames, *at),
        "source": {
            "address": str(source),
            **got.summary(),
            "in_process": means(study.monte_carlo(case, res, settings, 1, *at)),
            "on_wire": means(study.received_errors(case, res, settings, wire, *at)),
        },
    }


def closed_loop_verdicts(
    case,
    event,
    *,
    t_end: float,
    settings,
    esd_pct: float,
    seed: int,
    control,
    deadband_hz: float,
    model=None,
    esd_model: str = "ideal",
    transport: str = "process",
) -> dict:
    """The fault simulated with the ESDs commanded by each estimator in the loop.

    Parameters
    ----------
    case : stabctl.case.Case
    event : stabctl.dynamics.events.Fault
    t_end : float
        End of the run (s).
    settings : stabctl.estimation.settings.PMUSettings
    esd_pct : float
        Storage rating (% of machine MVA).
    seed : int
        PMU noise seed.
    control : stabctl.storage.devices.BangBangCOI
    deadband_hz : float
        Deadband of the false-action count (Hz).
    model : stabctl.dynamics.options.ModelOptions or None
        Conventions, step and Q limits (None: the defaults).
    esd_model : {"ideal", "wecc"}, optional
        The ESDs' model (`stabctl.storage.devices.StorageFleet.model`).
    transport : {"process", "codec", "tcp"}, optional
        How the frames reach the controller (`stabctl.estimation.closed_loop.LoopOptions`);
        the ideal estimator, which reads the true speeds, runs in process.

    Returns
    -------
    dict
        Per estimator (`stabctl.estimation.closed_loop.ESTIMATORS`): ``stable``,
        ``mode_commands`` (sent to the devices: a device's voltage gate may hold one
        idle), ``false_actions``, ``frames`` (the frames the controller acted
        on), ``frames_formed`` (those whose relative speeds it could form, every
        machine's speed estimated: dropped frames leave the devices idle) and ``link``
        (over TCP the link's figures, `stabctl.estimation.c37_loop.LinkStats.summary`;
        else None).

    Raises
    ------
    InputError
        A PMU rate that is not one of the case's nominal frequency
        (`stabctl.estimation.settings.check_rate`), before any run.
    """
    from stabctl.dynamics.options import ModelOptions
    from stabctl.estimation import closed_loop as cl
    from stabctl.estimation.filters import compile_filters
    from stabctl.estimation.models import machine_models
    from stabctl.estimation.pmu import machine_pmus
    from stabctl.estimation.settings import check_rate

    check_rate(settings.rate, case.freq_hz)
    sim, rows = (model or ModelOptions()).simulator(case), {}
    compile_filters(machine_models(case, machine_pmus(case)))
    for e in cl.ESTIMATORS:
        run = cl.run_closed_loop(
            sim,
            [event],
            t_end,
            cl.LoopOptions(
                esd_pct,
                e,
                settings,
                seed,
                control,
                esd_model=esd_model,
                transport="process" if e == "ideal" else transport,
            ),
        )
        rows[e] = loop_row(run, deadband_hz)
    return rows


def loop_row(run, deadband_hz: float, controller_here: bool = True) -> dict:
    """One closed-loop run's row, as `closed_loop_verdicts` gives it.

    Parameters
    ----------
    run : stabctl.estimation.closed_loop.ClosedLoopRun
        The run.
    deadband_hz : float
        Deadband of the false-action count (Hz).
    controller_here : bool, optional
        Whether the controller ran in this process (its frames counted); False for
        `pmu plant`, whose controller is remote: the row has no ``frames``.

    Returns
    -------
    dict
        ``stable``, ``mode_commands``, ``false_actions``, (``frames``, ``frames_formed``)
        and ``link``, as `closed_loop_verdicts` says.
    """
    from stabctl.estimation.closed_loop import false_actions

    row = {
        "stable": run.result.stable,
        # commands sent, not switchings: a device's voltage gate may hold it idle
        "mode_commands": len(run.result.meta.get("switchings", [])),
        "false_actions": false_actions(run, deadband_hz),
    }
    if controller_here:
        row |= {
            "frames": int(run.diagnostics.t.size),
            "frames_formed": int(run.diagnostics.formed.sum()),
        }
    return row | {"link": run.link}


def estimator_ccts(
    case_name: str,
    bus: int,
    far_bus: int,
    *,
    esd_pct: float,
    runs: int,
    seed: int,
    settings,
    model=None,
    esd_model: str = "ideal",
    records: str | os.PathLike | None = None,
) -> dict:
    """CCT of a line fault with each estimator in the loop, over ``runs`` noise seeds.

    Parameters
    ----------
    case_name : str
        A built-in case's name or a case file (`stabctl.io.load_case`): the file given is
        simulated, not the built-in case its ``name`` field may name.
    bus, far_bus : int
        The faulted line.
    esd_pct : float
        Storage rating (% of machine MVA).
    runs, seed : int
        Noise seeds seed .. seed + runs - 1.
    settings : stabctl.estimation.settings.PMUSettings
        Its rate, latency and frequency window are used.
    model : stabctl.dynamics.options.ModelOptions or None
        Conventions, step and Q limits (None: the defaults).
    esd_model : {"ideal", "wecc"}
        The storage devices' model (`stabctl.storage.devices.StorageFleet.model`).
    records : str, os.PathLike or None
        The searches' JSON-lines records, kept there (a search already recorded is not
        run again: an interrupted study resumes); None: a temporary file, removed.

    Returns
    -------
    dict
        Estimator -> statistics of the CCT in cycles (mean, std, min, max, runs, failed),
        :func:`stabctl.estimation.closed_loop.cct_study`.

    Raises
    ------
    InputError
        As `stabctl.estimation.closed_loop.cct_study`: a PMU rate that is not one of the
        case's nominal frequency among them, before any search.
    """
    from stabctl.estimation import closed_loop as cl
    from stabctl.estimation.settings import PMUSettings
    from stabctl.stability.cct import LineFault

    require_instance(settings, PMUSettings, "estimator_ccts(settings)")  # None: no 'rate'
    pmu = PMUSettings(
        rate=settings.rate, latency_s=settings.latency_s, window_cycles=settings.window_cycles
    )
    with nullcontext(None) if records is not None else temp_dir("stabctl-estimate-") as held:
        return cl.cct_study(
            case_name,
            LineFault(bus, far_bus),
            [esd_pct],
            runs,
            Path(held.path) / "cct.jsonl" if held is not None else records,
            seed=seed,
            pmu=pmu,
            model=model,
            esd_model=esd_model,
            label="estimate cct",  # its records file is not the user's to open
        )[esd_pct]
