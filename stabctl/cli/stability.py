"""`stabctl cct`, `stabctl sweep-cct` and `stabctl screen`: critical clearing times."""

from __future__ import annotations

from dataclasses import asdict, replace
from pathlib import Path

import click

from stabctl.cli.checks import (
    PLOT_SUFFIXES,
    check_power_flow,
    check_run_end,
    check_step_given,
    check_suffix,
    model_settings,
    search_settings,
)
from stabctl.cli.format import (
    critical_group_line,
    end_note,
    islanding_lines,
    machine_buses,
    print_cct,
    print_json,
    print_screening,
    print_sweep,
    q_limits_text,
    step_text,
)
from stabctl.cli.options import (
    INT,
    check_number,
    check_option_events,
    check_storage_given,
    circuit_option,
    comma_list,
    controller,
    esd_model_option,
    far_end,
    fault_options,
    fault_text,
    faults_option,
    json_option,
    model_options,
    named_option,
    out_file_option,
    parallel_options,
    plot_option,
    q_limits_option,
    read_fault_list,
    records_file,
    refuse_given,
    reports_errors,
    storage_options,
    tf_option,
    tol_options,
)
from stabctl.errors import InputError, counted


def _trips(trip) -> tuple[tuple[int, int], ...]:
    """cct's --trip FROM TO[:K] pairs: circuit 1 only (`LineFault.trips`)."""
    out = []
    for a, b in trip:
        to, k = far_end(b, "--trip")
        if k != 1:
            raise InputError(
                f"--trip {a} {b}: cct opens circuit 1 of a further line; to open both "
                f"circuits of {a}-{to}, fault circuit 2 (--circuit 2) and --trip {a} {to}"
            )
        out.append((a, to))
    return tuple(out)


#: --search of cct and screen: how a CCT search finds its bracket
search_option = click.option(
    "--search",
    "method",
    type=click.Choice(["bisection", "sime"]),
    default="bisection",
    show_default=True,
    help="How the bracket is found: the bound checks, doubling and bisection, or a run at "
    "--t-max first (robust in one run when no machine swings 1 rad there), then from "
    "SIME's margins of the unstable runs, clearing at once checked only when no probe "
    "was stable first (the same CCT cells on Kundur and miniWECC, 3-8 % fewer runs per "
    "CCT there, but up to 10 % more on IEEE 14 and the GB network; 30 % less time a "
    "search on a sample of ACTIVSg2000's N-1, most of it robust; docs/cli.md).",
)


@click.command()
@click.argument("case_name", metavar="CASE")
@fault_options(required=True, far_required=False)
@circuit_option
@click.option(
    "--trip",
    type=(INT, str),
    multiple=True,
    metavar="FROM TO[:K]",
    help="Also open circuit 1 of line FROM-TO at the clearing instant "
    "(repeatable; TO or TO:1, the option's form in simulate); both circuits of a double "
    "line: --circuit 2 --trip BUS FAR_BUS.",
)
@storage_options(critical=True)
@esd_model_option
@tol_options()
@tf_option()
@search_option
@model_options
@q_limits_option
@json_option()
@reports_errors
def cct(
    case_name,
    fault,
    far_bus,
    circuit,
    t_fault,
    trip,
    esd_pct,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    esd_model,
    tol_ms,
    t_max,
    tf,
    method,
    conventions,
    step,
    q_limits,
    as_json,
):
    """Critical clearing time of a line or bus fault, searched on the clearing time.

    The fault at BUS on line BUS-FAR_BUS starts at --t-fault and is cleared at both ends
    at once after the clearing time (s after the fault start); the line stays out.
    Without --far-bus the fault at BUS is cleared without loss of a line (as `screen`'s
    bus faults).

    \b
    Criterion: unstable if a rotor angle leaves the centre of inertia (H*MVA weights) by
    more than pi rad before --tf (default fault time + 5 s); runs stop at separation.
    A fault whose clearing cuts machines off the main grid (a generator's step-up
    transformer) has the CCT, or the verdict, of the rest of the system: the islanded
    machines are lost and named with their buses.
    Clearing times are multiples of --tol-ms.  --search bisection checks stability at
    zero clearing (the line trip alone), doubles the upper bound from 0.1 s while stable
    (up to --t-max), then bisects (the default).  --search sime starts at 0.1 s (doubled
    while stable; zero clearing checked only when no probe was stable first),
    extrapolates SIME's unstable margin (close to linear in the clearing time) from two
    unstable runs to the CCT, probes there on both sides and bisects only what is left.
    Both end in the same bracket when the verdict is monotone in the clearing time.
    The CCT printed is the stable end of the final bracket (conservative).  Its numerical
    error bar: the bracket's ends rerun at half the step (the search continued there if a
    verdict changes); numerical_error_s = abs(CCT(h/2) - CCT(h)) (0: below the tolerance).

    \b
    Examples:
      stabctl cct kundur --fault 3 --far-bus 101
      stabctl cct kundur --fault 3
      stabctl cct miniwecc --fault 83 --far-bus 33 --json

    A fault still stable when cleared at --t-max is a verdict (the CCT is above it: exit
    0, ``"cct_s": null``, ``"above_t_max_s"`` and ``"verdict": "above t_max"`` in
    --json); so is one unstable even when cleared at once (N-1 insecure: exit 0,
    ``"cct_s": 0`` and ``"verdict": "N-1 insecure"``); the JSON gives the reason, the
    fault and the settings as a CCT's does.  Bad input (unknown bus or line, storage
    not available) exits with status 2 and one `error:` line.
    """
    from stabctl.dynamics.events import validate as validate_events
    from stabctl.errors import AboveSearchLimit, InsecureContingency
    from stabctl.io import load_case
    from stabctl.stability.cct import LineFault, check_trips, critical_clearing_time
    from stabctl.storage.devices import uniform_fleet

    check_storage_given(esd_pct)
    if far_bus is None:
        refuse_given(("circuit",), "without --far-bus (a bus fault loses no line)")
    search = replace(search_settings(tol_ms, t_max, tf), method=method)
    model = model_settings(conventions, None, q_limits)
    case = load_case(case_name)
    line_fault = LineFault(fault, far_bus, t_fault, circuit, _trips(trip))
    check_run_end([line_fault], search)  # before the simulator is built
    fault_ev, *trip_evs = line_fault.events(0.0)
    check_option_events(
        case,
        [
            (fault_text(fault, far_bus, circuit), fault_ev),
            *((f"--trip {a} {b}", ev) for (a, b), ev in zip(trip, trip_evs)),
        ],
    )
    check_trips(case, line_fault, "--trip")  # before the events' check names none
    validate_events(case, line_fault.events(0.0), t_fault + 1.0)  # before compiling
    sim = model.simulator(case)
    base = None
    if esd_pct is not None and coi == "critical":
        base = _without_storage(sim, line_fault, search, step)
    storage = (
        None
        if esd_pct is None
        else uniform_fleet(
            case,
            esd_pct,
            controller(deadband_hz, v_gate, coi, hysteresis_hz, base.separated if base else ()),
            model=esd_model,
        )
    )
    group = (
        {}
        if base is None
        else {
            "critical_group": {
                "machines": list(base.separated),
                "buses": machine_buses(case, base.separated),
                "cct_without_storage_s": base.cct_s,
                # False: none separated, the run failing first (round 45: said to separate)
                "separated": base.unstable_end_failure is None,
            }
        }
    )
    try:
        res = critical_clearing_time(sim, line_fault, search, storage=storage, h=step)
    except (InsecureContingency, AboveSearchLimit) as exc:  # a verdict, not a failure
        insecure = isinstance(exc, InsecureContingency)
        if as_json:
            fault_d = asdict(line_fault)
            fault_d["t_fault_s"] = fault_d.pop("t_fault")
            h = sim.default_h if step is None else step
            print_json(
                {
                    "case": case.name,
                    "esd_pct": esd_pct,
                    "esd_model": esd_model,
                    "fault": fault_d,
                    "cct_s": 0.0 if insecure else None,
                    **({} if insecure else {"above_t_max_s": search.t_max}),
                    "verdict": exc.label,
                    "reason": str(exc),
                    "n_simulations": exc.n_simulations,
                    "islanded": list(exc.islanded),
                    "end_concerns": list(exc.end_concerns),
                    "end_t_s": exc.end_t_s,
                    "conventions": model.conventions,
                    "tol_s": search.tol,
                    "t_max_s": search.t_max,
                    "step_s": h,
                    "sub_stepped_exciters": sim.sub_stepped(h),
                    "search": search.method,
                    "criterion": "no_separation",
                    "q_limits": q_limits,
                    **group,
                }
            )
        else:
            said = "CCT 0 s, N-1 insecure" if insecure else "CCT above the search limit"
            click.echo(f"{said}: {exc}{_runs_said(exc)}")
            if group:
                click.echo(critical_group_line(case, group["critical_group"]))
            _echo_islanding(case, exc.islanded)
            if exc.end_concerns and exc.end_t_s is not None:
                click.echo(f"note: cleared at the limit, {end_note(exc.end_t_s, exc.end_concerns)}")
        return
    out = {"case": case.name, "esd_pct": esd_pct, "esd_model": esd_model}
    for key, value in res.to_dict().items():
        out[key] = value
        if key == "separated_machines":  # their buses beside them
            out["separated_buses"] = machine_buses(case, value)
    out["q_limits"] = q_limits
    out.update(group)
    if as_json:
        print_json(out)
    else:
        print_cct(case, esd_pct, out)


def _runs_said(verdict) -> str:
    """`` (3 simulations)``: the runs a search's verdict took, when it counted them."""
    n = verdict.n_simulations
    return "" if n is None else f" ({counted(n, 'simulation')})"


def _echo_islanding(case, islanded) -> None:
    """Print a search's islanding (`stabctl.cli.format.islanding_lines`), one line each."""
    for line in islanding_lines(case, islanded, timed=False):
        click.echo(f"the contingency's trip: {line}")


def _with_buses(case, row: dict) -> dict:
    """A screening row with ``separated_buses`` beside its ``separated`` machines (if any)."""
    out = {}
    for key, value in row.items():
        out[key] = value
        if key == "separated":
            out["separated_buses"] = machine_buses(case, value)
    return out


def _without_storage(sim, line_fault, search, step):
    """The CCT search without storage that names ``--coi critical``'s critical machines
    (the machines separated at its unstable end, SIME's critical group).

    Raises
    ------
    InputError
        No critical group: the fault is N-1 insecure or still stable at --t-max
        without storage.
    """
    from stabctl.errors import AboveSearchLimit, InsecureContingency
    from stabctl.stability.cct import critical_clearing_time

    try:
        return critical_clearing_time(sim, line_fault, search, h=step)
    except (InsecureContingency, AboveSearchLimit) as exc:
        raise InputError(
            f"--coi critical: no critical group without storage ({exc}); the law needs "
            "the machines that separate when the fault is cleared just too late"
        ) from None


def _ratings(values) -> list:
    """The storage ratings of sweep-cct's --esd-pct.

    Parameters
    ----------
    values : sequence of str
        The option's values (repeatable, comma-separated, 'none' = no storage).

    Returns
    -------
    list of float or None
        The ratings in order (None: no storage; default ``[None]``).

    Raises
    ------
    InputError
        Not a number or 'none', out of range, empty or given twice (`comma_list`).
    """
    out = comma_list(values or ("none",), "--esd-pct", _rating, "a number or 'none'")
    for v in out:
        if v == 0:  # a rating of 0 is the run without storage, which has its own word
            raise InputError(
                "--esd-pct 0: a rating must be above 0 % of machine MVA; the run without "
                "storage is 'none' (--esd-pct none,5)"
            )
        if v is not None:
            check_number("--esd-pct", v)
    return out


def _say_others(out_path, jobs) -> None:
    """Warn of the records in `out_path` of none of a sweep's `jobs` (another sweep's, a
    screening's): kept in the file, not counted in its summary (a screening says the same
    of a sweep's records in its file; a sweep said nothing)."""
    from stabctl.parallel import warn_others

    run = f"this sweep's {len(jobs)} job(s)"
    warn_others(out_path, jobs, lambda r: "another run's", run, "not counted here")


def _rating(item: str) -> float | None:
    return None if item.lower() == "none" else float(item)


@click.command("sweep-cct")
@click.argument("case_name", metavar="CASE")
@faults_option
@storage_options(multiple=True, rating_help=" Every fault runs at every rating.")
@esd_model_option
@out_file_option(
    None,
    "FILE.jsonl",
    "JSON lines, one per finished job; rerunning with it skips the jobs already there "
    "[default: sweep_<CASE>.jsonl, CASE's file name without .json].",
)
@parallel_options
@click.option("--retry-failed", is_flag=True, help="Rerun the jobs recorded as failed.")
@tol_options()
@tf_option()
@model_options
@q_limits_option
@json_option("every record")
@reports_errors
def sweep_cct(
    case_name,
    faults_src,
    esd_pct,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    esd_model,
    out_path,
    workers,
    scheduler,
    retry_failed,
    tol_ms,
    t_max,
    tf,
    conventions,
    step,
    q_limits,
    as_json,
):
    """CCT of every (fault, storage rating) pair, in parallel, resumable.

    Each job is one `stabctl cct` search; its line in --out holds its key
    (CASE/BUS-FAR/tT_FAULT/esdP, + /ctrl-... with other controller options than the
    paper's), inputs and result, or `failed` with the reason (e.g. a
    diverging run). Lines are written as jobs finish, so an interrupted sweep (Ctrl-C)
    keeps them; rerun the same command to finish it. A progress bar goes to stderr.
    Criterion and search as `stabctl cct` (see its --help).

    \b
    Examples:
      stabctl sweep-cct kundur --faults DEFAULT --esd-pct none,5,10 --out kundur.jsonl
      stabctl sweep-cct miniwecc --faults faults.csv --scheduler tcp://10.0.0.5:8786

    Exit status: 0 every job reached a verdict (a CCT, robust, N-1 insecure); 1 a job
    failed (listed and recorded with its reason); 2 bad input.
    """
    from stabctl.io import load_case
    from stabctl.parallel import run_sweep
    from stabctl.stability.cct import T_AFTER_FAULT, storage_fleet
    from stabctl.studies.sweeps import controlled_cct_jobs

    search = search_settings(tol_ms, t_max, tf)
    model = model_settings(conventions, step, q_limits)
    ctrl = controller(deadband_hz, v_gate, coi, hysteresis_hz)
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be >= 1, got {workers}")
    out_path = records_file(out_path, case_name, "sweep")
    check_suffix(out_path, (".jsonl",), "--out", records=True)
    case = load_case(case_name)
    ratings = _ratings(esd_pct)
    check_storage_given(next((p for p in ratings if p is not None), None))
    for p in ratings:
        storage_fleet(case, p)
    faults = read_fault_list(case, case_name, faults_src)
    check_run_end(faults, search)
    check_power_flow(case, model)  # before any job: not one failure per job
    t_end = search.t_end or max(f.t_fault for f in faults) + T_AFTER_FAULT
    check_step_given(case, model, t_end)
    jobs = controlled_cct_jobs(
        case_name, faults, ratings, ctrl, search=search, model=model, esd_model=esd_model
    )
    _say_others(out_path, jobs)
    settings = _settings(case_name, model, search)  # before the jobs, once
    rep = run_sweep(
        jobs, out_path, workers=workers, scheduler=scheduler, retry_failed=retry_failed
    )  # Ctrl-C: reports_errors, exit 130
    if as_json:
        print_json(
            {
                "out": str(rep.out),
                "ran": rep.ran,
                "skipped": rep.skipped,
                "failed": rep.failed,
                "failed_before": rep.failed_before,
                "wall_time_s": rep.wall_time_s,
                "settings": settings["json"],
                "records": list(rep.records.values()),
            }
        )
    else:
        click.echo(settings["line"])
        print_sweep(rep, len(jobs), case)
    from stabctl.stability.screening import verdict

    failed = [r for r in rep.records.values() if verdict(r) == "failed"]
    _exit_on_failures(failed, rep.out, ("job", "jobs"))


@click.command()
@click.argument("case_name", metavar="CASE")
@click.option(
    "--buses",
    default=None,
    metavar="B1,B2,...",
    help="Buses to fault (default: every bus); --lines still faults every branch "
    "(some branches only: `stabctl sweep-cct --faults FILE.csv`).",
)
@click.option(
    "--lines",
    is_flag=True,
    help="Also fault the from-end of every branch with the branch tripped (N-1).",
)
@click.option(
    "--guess/--no-guess",
    default=True,
    show_default=True,
    help="With --lines, start each branch fault's search from its bus fault's CCT (fewer "
    "runs where a trip moves the CCT little; none where the trip cuts machines off; "
    "--no-guess: every search from scratch).",
)
@tol_options(0.5)
@out_file_option(
    None,
    "FILE.jsonl",
    "JSON lines, one per finished search (rerunning resumes) [default: "
    "screening_<CASE>.jsonl, CASE's file name without .json].",
)
@plot_option(
    "network map: bus faults (circles) and branch faults (squares, mid-branch) coloured by "
    "CCT, robust, N-1 insecure and failed ones marked"
)
@parallel_options
@click.option("--retry-failed", is_flag=True, help="Rerun the searches recorded as failed.")
@search_option
@model_options
@q_limits_option
@json_option("every row")
@reports_errors
def screen(
    case_name,
    buses,
    lines,
    guess,
    tol_ms,
    t_max,
    out_path,
    plot_path,
    workers,
    scheduler,
    retry_failed,
    method,
    conventions,
    step,
    q_limits,
    as_json,
):
    """Contingency screening: CCT of a three-phase fault at every bus (and with --lines of
    every branch fault with the branch tripped), in parallel and resumable.

    Bus faults are cleared without loss of a line (PST sw_con type 7); the CCT search
    (--search) and its stability criterion are `stabctl cct`'s. Rows are sorted by CCT,
    most critical first; a fault still stable when cleared at --t-max is robust (CCT
    above it, shown as ">t_max", its verdict "above t_max"); a failed search (e.g.
    voltage collapse during the fault) is listed with its reason, and the last line
    counts each kind.  A branch fault that islands load buses or machines names them
    above its row (a machine islanded apart from the main grid is lost: the row's CCT
    or verdict is the rest's), and the last line counts those too.  A search an earlier
    run recorded as failed is shown as recorded, marked so, and not run again unless
    --retry-failed.  With --lines the bus faults run first, then each branch fault at a
    screened bus starts its search from that bus fault's CCT (its cell and neighbours;
    a guess that finds no cell there leaves the search as without it; none where the
    trip cuts machines off each other, which the bus fault kept): the same CCTs
    where the verdict is monotone in the clearing time, in fewer runs where a trip
    moves the CCT little (on ACTIVSg2000 half the runs of such a search; Kundur's trips
    move its CCTs up to 0.24 s and the guesses cost runs there: --no-guess).

    Exit status: 0 every search reached a verdict (a CCT, robust, N-1 insecure, with
    islanding or not); 1 a search failed (listed and recorded with its reason); 2 bad
    input.

    \b
    Example:
      stabctl screen kundur --lines --workers 2 --plot kundur_map.png
    """
    from stabctl.io import load_case
    from stabctl.parallel import RunnerOptions
    from stabctl.stability import screening
    from stabctl.stability.cct import T_AFTER_FAULT
    from stabctl.stability.screening import screen as run_screen

    if not lines:
        refuse_given(("guess",), "without --lines (only branch faults start from a guess)")
    case = load_case(case_name)
    bus_list = None if buses is None else _bus_list(buses)
    if bus_list is not None:
        with named_option(f"--buses {buses}" if len(buses) <= 40 else "--buses"):
            case.bus_indices(bus_list)  # an unknown bus named before any work
    plot_p = check_suffix(plot_path, PLOT_SUFFIXES, "--plot")
    out_path = records_file(out_path, case_name, "screening")
    check_suffix(out_path, (".jsonl",), "--out", records=True)
    model = model_settings(conventions, step, q_limits)
    check_power_flow(case, model)  # before any search: not one failure per fault
    check_step_given(case, model, screening.T_FAULT + T_AFTER_FAULT)
    search = replace(search_settings(tol_ms, t_max, None, tf_option=False), method=method)
    settings = _settings(case_name, model, search)  # before the searches, once
    rows = run_screen(
        case_name,
        out_path,
        buses=bus_list,
        lines=lines,
        guess=guess,
        search=search,
        model=model,
        runner=RunnerOptions(workers, scheduler),
        retry_failed=retry_failed,
    )
    rows.sort(key=lambda r: r.get("cct_s", float("inf")))
    if plot_p is not None:  # written atomically (round 47: in place, a reader saw it empty)
        from stabctl.parallel import atomic_write
        from stabctl.plotting import figures as plotting

        atomic_write(plot_p, lambda tmp: plotting.screening_map(case, rows, Path(tmp)), mode=None)
    rows = [_with_buses(case, r) for r in rows]
    if as_json:
        print_json([{**row, "settings": settings["json"]} for row in rows])
    else:
        click.echo(settings["line"])
        print_screening(case, rows, tol_ms / 1000, out_path)
    failed = [r for r in rows if r["verdict"] == "failed"]
    _exit_on_failures(failed, out_path, ("search", "searches"))


def _settings(case_name, model, search) -> dict:
    """The settings of a batch's searches (`sweep-cct`, `screen`): tolerance, search
    limit, step (the case's default when none is given), conventions and Q limits, as
    `cct` gives them: ``line``, their text (round 39: a screening's text said none of
    them, and the Q limits move a CCT), ``json``, their fields (round 41: `screen --json`
    rows carried none)."""
    from stabctl.stability.cct import cached_simulator

    step = model.h if model.h is not None else cached_simulator(case_name, model).default_h
    line = (
        f"settings: tolerance {1000 * search.tol:g} ms, search limit {search.t_max:g} s, "
        f"step {step_text(step)}, {model.conventions} conventions, "
        f"{q_limits_text(model.q_limits)}"
    )
    fields = {
        "tol_s": search.tol,
        "t_max_s": search.t_max,
        "step_s": step,
        "conventions": model.conventions,
        "q_limits": model.q_limits,
    }
    return {"line": line, "json": fields}


def _exit_on_failures(failed: list, out, what: tuple[str, str]) -> None:
    """Exit with status 1, saying so on stderr, when a job failed (a numerical or input
    failure, not a verdict: robust, N-1 insecure and islanding are results), after the
    results are printed and recorded: a script checking the status sees it."""
    if failed:
        click.echo(
            f"{counted(len(failed), *what)} failed (listed above with the reasons, recorded in "
            f"{out}; --retry-failed reruns them): exit status 1",
            err=True,
        )
        raise SystemExit(1)


def _bus_list(text: str) -> list[int]:
    """--buses B1,B2,...: bus numbers (InputError naming the first that is not one, an
    empty item or a bus given twice: `comma_list`)."""
    if not text.strip():
        raise InputError("--buses: no bus number given")
    return comma_list(text, "--buses", int, "a bus number")
