"""`stabctl simulate`: one nonlinear time-domain run of a case."""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass

import click

from stabctl.cli.checks import OUT_SUFFIXES, PLOT_SUFFIXES, check_method, check_suffix
from stabctl.cli.format import (
    describe_esd,
    end_note,
    islanding_lines,
    machine_buses,
    machine_list,
    plot_writer,
    print_json,
    print_storage,
    q_limits_text,
    shown,
    step_text,
)
from stabctl.cli.options import (
    _RANGES,
    FLOAT,
    INT,
    TF_AFTER_FAULT_S,
    check_option_events,
    check_storage_given,
    circuit_option,
    clear_cycles_option,
    controller,
    esd_model_option,
    far_end,
    fault_options,
    fault_text,
    json_option,
    model_options,
    named_option,
    out_file_option,
    plot_option,
    q_limits_option,
    refuse_cycles_of_no_length,
    refuse_fault_of_no_length,
    refuse_given,
    reports_errors,
    storage_options,
    subintervals_chosen,
    tf_option,
    warnings_so_far,
)
from stabctl.dynamics.results import FLAT_DRIFT_PU
from stabctl.errors import InputError, counted
from stabctl.io.inputs import plain_number


def _bus_fault(spec: str, t_on: float, t_off: float):
    """The `Fault` of one ``--bus-fault BUS[:R:X] T_ON T_OFF`` (no line lost; T_OFF inf:
    never cleared); InputError naming the option for a malformed BUS[:R:X] or times."""
    from stabctl.dynamics.events import Fault

    parts = spec.split(":")
    try:
        if not plain_number(spec):
            raise ValueError(spec)
        bus = int(parts[0])
        r, x = (float(parts[1]), float(parts[2])) if len(parts) == 3 else (0.0, 0.0)
    except ValueError:
        parts = []
    if len(parts) not in (1, 3):
        raise InputError(
            f"--bus-fault {spec} {t_on:g} {t_off:g}: BUS is a bus number or BUS:R:X "
            "(fault resistance and reactance, pu on the system base)"
        )
    if not (0 <= r < math.inf and 0 <= x < math.inf):
        raise InputError(f"--bus-fault {spec}: R and X must be >= 0 pu (finite numbers)")
    if not 0 <= t_on <= t_off:
        raise InputError(f"--bus-fault {spec} {t_on:g} {t_off:g}: need 0 <= T_ON <= T_OFF (s)")
    latest = _RANGES["--t-fault"][1]  # as a line fault's start
    if t_on > latest or latest < t_off < math.inf:
        raise InputError(
            f"--bus-fault {spec} {t_on:g} {t_off:g}: T_ON and T_OFF must be at most "
            f"{latest:g} s (T_OFF inf: never cleared)"
        )
    if t_on == t_off:
        raise InputError(
            f"--bus-fault {spec} {t_on:g} {t_off:g}: cleared at {t_on:g} s, as it starts: a "
            "fault of no length would do nothing (give T_OFF > T_ON)"
        )
    clear = None if t_off == float("inf") else t_off
    return Fault(bus=bus, t=t_on, clear_near=clear, r=r, x=x)


def _line_close(a: int, b: str, t: float):
    """LineClose of --close FROM TO[:K] T."""
    from stabctl.dynamics.events import LineClose

    to, k = far_end(b, "--close")
    return LineClose(a, to, t, circuit=k)


def _study_events(case, bus_faults, closes, trips, load_steps, vref_steps, pref_steps):
    """The events of the PSS/E-study options, in the order given per option (trips: the
    --trip-gen and --trip-converter pairs); InputError naming the option of the first
    whose bus, line, machine or converter the case lacks."""
    from stabctl.case.events import check_totals
    from stabctl.dynamics.events import ConverterTrip, GeneratorTrip, LoadStep, PrefStep, VrefStep

    gen_trips, converter_trips = trips
    given = [
        *((f"--bus-fault {s} {a:g} {b:g}", _bus_fault(s, a, b)) for s, a, b in bus_faults),
        *((f"--close {a} {b} {t:g}", _line_close(a, b, t)) for a, b, t in closes),
        *((f"--trip-gen {m} {t:g}", GeneratorTrip(m, t)) for m, t in gen_trips),
        *((f"--trip-converter {c} {t:g}", ConverterTrip(c, t)) for c, t in converter_trips),
        *(
            (f"--load-step {b} {t:g} {p:g} {q:g}", LoadStep(b, t, p, q))
            for b, t, p, q in load_steps
        ),
        *((f"--vref-step {m} {t:g} {dv:g}", VrefStep(m, t, dv)) for m, t, dv in vref_steps),
        *((f"--pref-step {m} {t:g} {dp:g}", PrefStep(m, t, dp)) for m, t, dp in pref_steps),
    ]
    check_option_events(case, given)
    options = {"LoadStep": "--load-step", "VrefStep": "--vref-step", "PrefStep": "--pref-step"}
    check_totals(case, [ev for _, ev in given], options)  # steps that add up
    return [ev for _, ev in given]


def _build_events(
    case,
    fault,
    far_bus,
    t_fault,
    clear_cycles,
    far_clear_cycles,
    circuit,
    trips,
    t_trips,
    pstess_default,
    case_events,
):
    from stabctl.dynamics.events import (
        Fault,
        LineTrip,
        fault_with_clearing,
        from_case,
        from_sw_con,
    )

    if case_events and not case.events:
        raise InputError(
            f"--case-events: case {case.name} has no events of its own; give --fault, "
            "--trip, --bus-fault, ... (a PST data file's sw_con runs with --pstess-default)"
        )
    if pstess_default and case.sw_con is None:
        raise InputError(
            f"--pstess-default: case {case.name} has no PST sw_con disturbance of its own; "
            "give --fault, --trip, --bus-fault, ..."
        )
    own: list = []
    for option, given in (
        ("--pstess-default", from_sw_con(case) if pstess_default else []),
        ("--case-events", from_case(case) if case_events else []),
    ):
        for ev in given:
            if isinstance(ev, Fault):
                refuse_fault_of_no_length(ev, f"{option}: the case's own {ev}")
        own += given
    events: list = []
    if fault is None:
        refuse_given(
            ("far_bus", "circuit", "t_fault", "clear_cycles", "far_clear_cycles"),
            "without --fault (--bus-fault has its own times)",
        )
    else:
        if far_bus is None:
            refuse_given(
                ("circuit", "far_clear_cycles"),
                "without --far-bus (the fault is cleared at --clear-cycles, no line lost)",
            )
        if clear_cycles < 0:
            raise InputError(f"--clear-cycles must be >= 0, got {clear_cycles:g}")
        if far_clear_cycles is not None and far_clear_cycles < 0:
            raise InputError(f"--far-clear-cycles must be >= 0, got {far_clear_cycles:g}")
        if t_fault < 0:
            raise InputError(f"--t-fault must be >= 0 s, got {t_fault:g}")
        far = "" if far_clear_cycles is None else f" --far-clear-cycles {far_clear_cycles:g}"
        named = f"{fault_text(fault, far_bus, circuit)} --clear-cycles {clear_cycles:g}{far}"
        hint = ": give --clear-cycles > 0" + (
            ""
            if far_bus is None
            else f" (the line's trip alone: --trip {fault} {far_bus}"
            + ("" if circuit == 1 else f":{circuit}")
            + ")"
        )
        refuse_cycles_of_no_length(clear_cycles, far_clear_cycles, t_fault, named, hint)
        with named_option(fault_text(fault, far_bus, circuit)):
            ev = fault_with_clearing(
                case, fault, far_bus, t_fault, clear_cycles, far_clear_cycles, circuit=circuit
            )
        refuse_fault_of_no_length(ev, named, hint)
        check_option_events(case, [(fault_text(fault, far_bus, circuit), ev)])
        events.append(ev)
    if trips:
        times = list(t_trips) or [1.0]
        if len(times) == 1:
            times = times * len(trips)
        if len(times) != len(trips):
            raise InputError(
                f"{len(trips)} --trip but {len(t_trips)} --t-trip: give one "
                "--t-trip for all or one per --trip"
            )
        for (a, b), t in zip(trips, times):
            if t < 0:
                raise InputError(f"--t-trip must be >= 0 s, got {t:g}")
            to, k = far_end(b, "--trip")
            events.append(LineTrip(a, to, t, circuit=k))
            check_option_events(case, [(f"--trip {a} {b}", events[-1])])
    elif t_trips:
        raise InputError("--t-trip given without --trip")
    return own, events


@dataclass(frozen=True)
class _RunEnd:
    """Where a run's end time came from, for messages: ``where`` (``--tf 2 s``, its
    default, the case's sw_con row) and what the user does about an event it cuts."""

    where: str
    remedy: str


def _check_ends(own: list, given: list, tf: float, end: _RunEnd) -> None:
    """InputError naming the first event, the case's own (``own``) or the options'
    (``given``), that changes the network again at or after the run's end ``tf`` (a
    clearing the run would never reach, while its summary called the fault cleared),
    and where ``tf`` came from (``end``)."""
    for events, hint in (
        (own, f"it is the case's own (--pstess-default, --case-events): {end.remedy}"),
        (given, f"{end.remedy}, or give T_OFF inf to --bus-fault for a fault never cleared"),
    ):
        cut = [e for e in events if any(tf <= t < math.inf for t in e.times())]
        if cut:
            raise InputError(f"{cut[0]}: ends at or after the end of the run ({end.where}); {hint}")


@click.command()
@click.argument("case_name", metavar="CASE")
@fault_options(required=False)
@circuit_option
@clear_cycles_option("Near-end clearing after N cycles of the case frequency")
@click.option(
    "--far-clear-cycles",
    type=FLOAT,
    default=None,
    metavar="M",
    help="Far-end clearing after M cycles from fault start (cycles; default: N).",
)
@click.option(
    "--trip",
    type=(INT, str),
    multiple=True,
    metavar="FROM TO[:K]",
    help="Trip circuit K (default 1; in data order, as --circuit counts) of line FROM-TO "
    "without fault (repeatable).",
)
@click.option(
    "--t-trip",
    type=FLOAT,
    multiple=True,
    metavar="S",
    help="Trip time (s): once for all trips or once per --trip (default 1.0).",
)
@click.option(
    "--bus-fault",
    type=(str, FLOAT, FLOAT),
    multiple=True,
    metavar="BUS[:R:X] T_ON T_OFF",
    help="Three-phase fault at BUS from T_ON to T_OFF (s; inf: never cleared), no line "
    "lost (PSS/E's dist_bus_fault, dist_clear_fault); bolted, or through R + jX (pu on "
    "the system base) as BUS:R:X (repeatable).",
)
@click.option(
    "--close",
    type=(INT, str, FLOAT),
    multiple=True,
    metavar="FROM TO[:K] T",
    help="Close again at T (s) circuit K (default 1) of line FROM-TO, opened before by "
    "--trip, a fault's clearing or the case's own events: a reclosure (repeatable).",
)
@click.option(
    "--trip-gen",
    type=(INT, FLOAT),
    multiple=True,
    metavar="MACHINE T",
    help="Disconnect machine MACHINE (number as in the data) at T (s) (repeatable).",
)
@click.option(
    "--trip-converter",
    type=(INT, FLOAT),
    multiple=True,
    metavar="CONVERTER T",
    help="Disconnect converter CONVERTER (number as in the data: a REGCA1/REGCB1 plant, "
    "PVD1, ESD1 or DERA1; `stabctl cases CASE` lists them) at T (s): from then it injects "
    "nothing and its states stand still (repeatable).",
)
@click.option(
    "--load-step",
    type=(INT, FLOAT, FLOAT, FLOAT),
    multiple=True,
    metavar="BUS T P Q",
    help="Add P + jQ (pu on the system base at the power-flow voltage, constant "
    "impedance; negative: shed) at bus BUS at T (s) (repeatable; abs(P + jQ) and the "
    "steps' sum at most the case's total load or rating, Kundur 36 pu).",
)
@click.option(
    "--vref-step",
    type=(INT, FLOAT, FLOAT),
    multiple=True,
    metavar="MACHINE T DV",
    help="Step the voltage reference of machine MACHINE's exciter by DV (pu) at T (s): "
    "PSS/E's change of VREF (repeatable; steps add up, to at most 1 pu).",
)
@click.option(
    "--pref-step",
    type=(INT, FLOAT, FLOAT),
    multiple=True,
    metavar="MACHINE T DP",
    help="Step the power reference of machine MACHINE's governor by DP (pu on the "
    "machine base) at T (s): PSS/E's change of PREF (repeatable; steps add up, to at "
    "most the larger of 1 pu and the governor's Tmax).",
)
@click.option(
    "--case-events",
    is_flag=True,
    help="Run the case file's own disturbance events (imported from ANDES's Toggle, "
    "Fault and Alter records by import-andes), with any of the above added.",
)
@click.option(
    "--pstess-default",
    is_flag=True,
    help="Run the case file's own PST sw_con disturbance (with any of the above "
    "added); --tf then defaults to its end time.  It runs under --conventions (default "
    "ieee): add --conventions pstess to reproduce PSTess's own run.",
)
@tf_option("; no disturbance: 5 s; with --pstess-default: the end of the data file's run")
@model_options
@q_limits_option
@click.option(
    "--separation-limit",
    type=FLOAT,
    default=3.141592653589793,
    show_default="pi",
    metavar="RAD",
    help="Loss of synchronism: a rotor angle more than RAD from the centre of inertia (rad).",
)
@click.option("--stop-at-separation", is_flag=True, help="Stop the run at loss of synchronism.")
@click.option(
    "--check-step",
    is_flag=True,
    help="Run again at half the step and report both verdicts: a verdict that changes "
    "there is within the step's error (a fault cleared near its CCT; `stabctl cct` gives "
    "the CCT with its half-step error bar).",
)
@click.option(
    "--method",
    type=click.Choice(["heun", "trapezoid"]),
    default="heun",
    show_default=True,
    help="Integration method: heun, the compiled predictor-corrector (PSTess's); "
    "trapezoid, the implicit trapezoidal rule (ANDES's; ieee conventions, no storage; "
    "a Python loop, slower).",
)
@click.option(
    "--suspect-starts",
    type=click.Choice(["refuse", "run"]),
    default="refuse",
    show_default=True,
    help="Controls whose initial point lies outside their own limits: refuse the case "
    "(naming them), or run on as PSS/E does from its 'initial conditions suspect', each "
    "listed, the limiter taking the state to its limit at the first step (the run then "
    "does not start at rest). The import's --leave-out-infeasible is the third way.",
)
@out_file_option(metavar="FILE.csv|FILE.npz", help="The trajectories (CSV or numpy .npz).")
@plot_option("speeds, angles from the COI and bus voltages")
@storage_options()
@esd_model_option
@json_option("the run summary")
@reports_errors
def simulate(
    case_name,
    fault,
    far_bus,
    circuit,
    t_fault,
    clear_cycles,
    far_clear_cycles,
    trip,
    t_trip,
    bus_fault,
    close,
    trip_gen,
    trip_converter,
    load_step,
    vref_step,
    pref_step,
    case_events,
    pstess_default,
    tf,
    conventions,
    step,
    q_limits,
    separation_limit,
    stop_at_separation,
    check_step,
    method,
    suspect_starts,
    out_path,
    plot_path,
    esd_pct,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    esd_model,
    as_json,
):
    """Nonlinear multi-machine time-domain simulation (PSTess models and integrator).

    CASE is a built-in name (see `stabctl cases`) or a case file (.json, PST .m). The run
    starts from the solved power flow. With no disturbance option the run is flat (no
    disturbance); --pstess-default runs the data file's own sw_con.

    \b
    Fault (as PST's sw_con, y_switch): a bolted three-phase fault at BUS from --t-fault;
    after N cycles the near end of line BUS-FAR_BUS opens (the far end keeps feeding the
    fault through the line), after M cycles the far end opens too and the line stays out.
    A verdict (separated or not) of a fault cleared within a few ms of its critical
    clearing time may depend on the step (the run at half the step can give the other
    one): --check-step runs again at h/2 and says whether the verdict holds; `stabctl cct`
    reports the CCT with its half-step error bar.

    \b
    PSS/E study events, each with its time, in any number and order: --bus-fault (through
    an impedance as BUS:R:X), --trip with --close (a reclosure), --trip-gen,
    --trip-converter, --load-step, --vref-step, --pref-step; --case-events adds the case's
    own (ANDES Toggle, Fault, Alter).

    \b
    Units: times s, cycles of the case frequency (60 Hz: 1 cycle = 16.67 ms), speeds pu,
    angles rad (absolute, synchronous frame, as PSTess), pelect pu on the system base,
    pmech pu on the machine base, efd pu, qelect (PSS/E's QELEC) pu on the system base,
    bus voltages pu and rad.

    \b
    CSV columns: t, speed_pu.G<k>, angle_rad.G<k>, pelect_pu.G<k>, pmech_pu_mbase.G<k>,
    efd_pu.G<k>, qelect_pu.G<k> per machine k (machine number k; --json's `machine_names` gives each
    one's bus, and its ID in a PSS/E case: "G2 (bus 102, id '1')"), vmag_pu.B<n>,
    vang_rad.B<n> per bus n, and with
    --esd-pct pesd_pu.D<d> per device (+ absorbs); --json then also gives the storage
    settings (`esd`), per device switchings, energy absorbed and delivered (MJ), peak
    power used (MW), seconds commanded and of those with no power taken (its bus below
    the 0.5 pu low-voltage switch, or its energy at a limit: commanded_s,
    commanded_idle_s) (`storage`), and every switching as {t_s, device, bus, machine, mode
    (absorb, idle, inject), mode_code (+1, 0, -1), rel_speed_hz (machine minus COI speed
    seen by the controller)} (`switchings`).  A case with converters (ANDES PVD1, ESD1;
    docs/ibr.md) adds pibr_pu.C<c> and qibr_pu.C<c>, the P and Q each injects (system
    base; --json's `converter_names` and `cases CASE --bus-table` give each one's bus).

    \b
    Examples:
      stabctl simulate kundur --pstess-default --out kundur.csv
      stabctl simulate kundur --fault 3 --far-bus 101 --t-fault 1 --clear-cycles 21 --json
      stabctl simulate miniwecc --trip 40 44 --t-trip 1 --tf 10 --plot wecc.png
      stabctl simulate miniwecc --fault 83 --far-bus 33 --clear-cycles 6 --esd-pct 5 --json
      stabctl simulate kundur --bus-fault 3:0:0.05 1 1.1 --trip 3 101 --t-trip 1.1 \\
        --close 3 101 1.6 --vref-step 2 3 0.02 --pref-step 1 4 0.05 --tf 10

    Bad input (unknown case or bus, no such line, negative cycles, power flow not
    converging) and a run that diverges exit with status 2 and one `error:` line; no file
    is written then (a diverged run reports where it stopped).
    """
    from stabctl.case.events import described
    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import validate as validate_events
    from stabctl.dynamics.grid import check_step_count
    from stabctl.io import load_case
    from stabctl.parallel import atomic_writes

    out_p = check_suffix(out_path, OUT_SUFFIXES, "--out")
    plot_p = check_suffix(plot_path, PLOT_SUFFIXES, "--plot")
    check_method(method, conventions, esd_pct is not None)
    if not separation_limit > 0:
        raise InputError(f"--separation-limit must be > 0 rad, got {separation_limit:g}")
    case = load_case(case_name)
    own, events = _build_events(
        case,
        fault,
        far_bus,
        t_fault,
        clear_cycles,
        far_clear_cycles,
        circuit,
        trip,
        t_trip,
        pstess_default,
        case_events,
    )
    given = events + _study_events(
        case, bus_fault, close, (trip_gen, trip_converter), load_step, vref_step, pref_step
    )
    events = own + given  # the case's own first
    end = _RunEnd(f"--tf {tf:g} s" if tf is not None else "", "lengthen --tf")
    if tf is None and pstess_default and case.sw_con is not None:
        tf = float(case.sw_con[-1, 0])  # the data file's own end, named as such
        end = _RunEnd(
            f"{case_name}: sw_con row {len(case.sw_con)} (its last), column 1 (time): "
            f"{tf:g} s, the end of the data file's run",
            "give --tf, or correct that time",
        )
    elif tf is None:
        tf = min((min(e.times()) for e in events), default=0.0) + TF_AFTER_FAULT_S
        end = _RunEnd(f"--tf {tf:g} s, by default", "give a longer --tf")
    if not tf > 0:
        raise InputError(
            f"--tf must be > 0 s, got {tf:g}"
            if end.where.startswith("--tf")
            else f"{end.where}: a run must end after 0 s; {end.remedy}"
        )
    late = [e for e in events if min(e.times()) >= tf]
    if late:
        raise InputError(
            f"{late[0]}: starts at or after the end of the run ({end.where}); {end.remedy}"
        )
    _check_ends(own, given, tf, end)
    if step is not None:
        check_step_count(tf, step, case)  # refused before any work (building the model)
    check_storage_given(esd_pct)
    fleet = None
    if esd_pct is not None:
        from stabctl.storage.devices import uniform_fleet

        fleet = uniform_fleet(
            case, esd_pct, controller(deadband_hz, v_gate, coi, hysteresis_hz), model=esd_model
        )
    try:
        validate_events(case, events, tf)  # an unknown bus or line before compiling
    except InputError as exc:  # a reclosure named by its option
        said = str(exc)
        for a, b, t in close:
            said = said.replace(str(_line_close(a, b, t)), f"--close {a} {b} at {t:g} s")
        raise InputError(said) from None
    sim = Simulator(
        case,
        conventions=conventions,
        q_limits=q_limits,
        suspect_starts=suspect_starts,
        subintervals=subintervals_chosen(),
    )
    sim.check_separation_limit(separation_limit, "--separation-limit")
    h = sim.default_h if step is None else step
    sub = sim.sub_stepped(h, method)
    from stabctl.progress import RUN_SHOWN_AFTER_S, runs_shown

    run = functools.partial(
        sim.run,
        events,
        t_end=tf,
        separation_limit=separation_limit,
        stop_at_separation=stop_at_separation,
        storage=fleet,
        method=method,
    )
    with runs_shown():  # a run longer than a few seconds shows a bar of simulated time
        result = run(h=h)
        halved = _step_check(run(h=h / 2), h / 2) if check_step else None
    if not events:
        _say_drift(result, case)
    esd = (
        None
        if esd_pct is None
        else {
            "pct_of_machine_mva": esd_pct,
            "model": esd_model,
            "devices": len(fleet.devices),  # type: ignore[union-attr]
            # infinite buses (H = 0): the rest of the system, no site
            "none_at": [case.machine_name(k) for k in sorted(case.infinite_buses())],
            "control": "bang-bang COI (paper Table 3)",
            "deadband_hz": deadband_hz,
            "v_gate_pu": v_gate,
            "coi": coi,
            "hysteresis_hz": hysteresis_hz,
        }
    )
    outputs: list = []  # written together: a failure leaves every one as it was
    if out_p is not None:
        npz = out_p.suffix.lower() == ".npz"
        outputs.append((out_p, result.to_npz if npz else result.to_csv))
    if plot_p is not None:
        title = f"{case.name}: " + (
            "; ".join(described(e, case) for e in _in_time_order(events)) or "flat run"
        )
        if esd is not None:
            title += "\n" + describe_esd(esd, short=True)
        outputs.append((plot_p, plot_writer(result, title, case)))
    if outputs and result.meta.get("wall_time_s", 0.0) > RUN_SHOWN_AFTER_S:
        # a run long enough to show its bar: its outputs take a while too, said (round
        # 57 AV: a 660-s run's bar was cleared at 96 %, then 24 s without a line)
        click.echo(f"writing {', '.join(str(p) for p, _ in outputs)} ...", err=True)
    atomic_writes(outputs)
    written = [str(p) for p, _ in outputs]
    summary = result.summary()
    summary["separated_buses"] = machine_buses(case, summary["separated_machines"])
    if esd is not None:
        summary["switchings"] = result.switching_records()
    if as_json:
        print_json(
            {
                **summary,
                "step_s": h,
                "sub_stepped_exciters": sub,
                "method": method,
                "conventions": conventions,
                "q_limits": q_limits,
                "esd": esd,
                "events": [described(e, case) for e in _in_time_order(events)],
                "suspect_starts": list(sim.suspect),
                "stiff_intervals": result.meta.get("stiff_intervals", []),
                "end_state": {
                    **result.end_state(case.freq_hz),
                    "concerns": result.end_concerns(case.freq_hz),
                },
                "machine_names": {
                    str(int(k)): case.machine_name(int(k)) for k in case.machines.number
                },
                **({"converter_names": names} if (names := _converter_names(case, fleet)) else {}),
                "files": written,
                **({} if halved is None else {"step_check": halved}),
                "warnings": warnings_so_far(),  # (stderr's warning: lines, for its reader)
            }
        )
        return
    click.echo(
        f"case {case.name}: {counted(len(case.machines), 'machine')}, "
        f"{counted(case.n_bus, 'bus', 'buses')}; 0-{float(result.t[-1]):g} s, "
        f"{counted(summary['n_steps'], 'step')} (h = {step_text(h)}"
        + (", shorter where said below" if result.meta.get("stiff_intervals") else "")
        + f", {method}"
        + (f" with {sub} exciter(s) in sub-intervals" if sub else "")
        + f", {conventions} conventions, {q_limits_text(q_limits)}), "
        f"wall {summary.get('wall_time_s', float('nan')):.2f} s"
    )
    for e in [described(e, case) for e in _in_time_order(events)] or ["flat run (no disturbance)"]:
        click.echo(f"  {e}")
    for line in sim.suspect:
        click.echo(f"  initial condition suspect, run on: {line}")
    for cut in result.meta.get("stiff_intervals", []):
        click.echo(
            f"  stepped at {step_text(cut['step_s'])} from {cut['t_start_s']:g} s to "
            f"{cut['t_end_s']:g} s: {case.machine_name(cut['machine'])}'s subtransient time "
            f"constant in that network is {step_text(cut['time_constant_s'])}, shorter than "
            "the step"
        )
    for line in islanding_lines(
        case, result.meta.get("islanded", []), result.meta.get("tripped", [])
    ):
        click.echo(f"  {line}")
    if esd is not None:
        print_storage(esd, result)
    if result.de_energised_s is not None:
        click.echo(
            f"de-energised at t = {result.de_energised_s:g} s: no machine left in service "
            "in the main grid (its load lost); no stability verdict"
        )
    elif result.stable:
        click.echo(
            f"stable: largest angle from the COI {summary['max_angle_from_coi_rad']:.4f} rad"
        )
        if concerns := result.end_concerns(case.freq_hz):
            click.echo(f"  note: {end_note(float(result.t[-1]), concerns)}")
    else:
        click.echo(
            f"loss of synchronism at t = {result.t_separation:.4f} s: machine(s) "
            f"{machine_list(case, result.separated)} separate"
            + (" (run stopped)" if stop_at_separation else "")
        )
        if runaway := result.meta.get("runaway"):
            click.echo(f"  note: {runaway}")
    if halved is not None:
        click.echo(_step_check_line(result, halved, method))
    for w in written:
        click.echo(f"wrote {shown(w)}")


def _say_drift(result, case) -> None:
    """Warn of a flat run (no disturbance) that moved more than FLAT_DRIFT_PU from its
    start (round 49: Nordic 44 with its IEEET2 misread drifted 1.06 pu of Efd in 10 s,
    said "stable" and nothing else)."""
    d = result.drift()
    if d["pu"] <= FLAT_DRIFT_PU:
        return
    what = {"speed": "the speed of", "efd": "the field voltage of", "vmag": "the voltage of"}
    where = f"bus {d['where']}" if d["quantity"] == "vmag" else case.machine_name(d["where"])
    warnings.warn(
        f"the flat run (no disturbance) did not stay at rest: {what[d['quantity']]} "
        f"{where} moved {d['pu']:.2e} pu by t = {d['t_s']:g} s (more than {FLAT_DRIFT_PU:g} "
        "pu): the starting point is no stable equilibrium of the models as read "
        "(`stabctl eig` names any unstable mode), or the data hold an error",
        UserWarning,
        stacklevel=2,
    )


def _in_time_order(events) -> list:
    """The events as the summary names them: by their first time, those of one time in
    the order the run takes them (the case's own, then the options' by kind)."""
    return sorted(events, key=lambda e: min(e.times()))


def _verdict(result) -> str:
    """A run's verdict in one word: stable, separated or de-energised."""
    if result.de_energised_s is not None:
        return "de-energised"
    return "stable" if result.stable else "separated"


def _step_check(result, h: float) -> dict:
    """The run at half the step (`--check-step`), for the summary: its step (s), verdict,
    separation time (s, None if none) and largest angle from the COI (rad)."""
    return {
        "step_s": h,
        "verdict": _verdict(result),
        "t_separation_s": None if result.stable else result.t_separation,
        "max_angle_from_coi_rad": result.max_angle_from_coi,
    }


#: relative difference of the largest angle between the step and half of it above which
#: `--check-step` says the figure depends on the step
ANGLE_CHECK_REL = 0.01


def _step_check_line(result, halved: dict, method: str = "heun") -> str:
    """`--check-step`'s line: the verdict holds at h/2, or it changes there (the
    clearing within the step's error of the CCT); a largest angle that moves beyond
    ANGLE_CHECK_REL says so, with what to do (the trapezoid only to a run of another
    method)."""
    at = f"at half the step (h = {step_text(halved['step_s'])})"
    if halved["verdict"] == _verdict(result):
        line = f"step check: {halved['verdict']} {at} too"
        if halved["verdict"] != "stable":
            return line
        a, b = result.max_angle_from_coi, halved["max_angle_from_coi_rad"]
        line += f"; largest angle from the COI {b:.4f} rad there ({b - a:+.4f} rad)"
        if abs(b - a) > ANGLE_CHECK_REL * abs(b):
            other = ", or --method trapezoid for a lightly damped swing" * (method != "trapezoid")
            line += f": it depends on the step by {abs(b - a) / abs(b):.1%} (halve it again{other})"
        return line
    return (
        f"step check: {halved['verdict']} {at}, {_verdict(result)} at the step: the verdict "
        "depends on the step (a clearing within its error of the CCT; `stabctl cct` gives "
        "the CCT with its half-step error bar)"
    )


def _converter_names(case, fleet) -> dict[str, str]:
    """`simulate --json`'s ``converter_names``: each converter of the run, the case's and
    a WECC-battery fleet's (`stabctl.storage.devices.battery_case`: its ``pibr_pu.C<k>``
    columns were named nowhere), as ``"C11 (bus 4, WECC battery)"``."""
    names = {
        str(int(k)): f"C{int(k)} (bus {int(b)})"
        for k, b in zip(case.converters.number, case.converters.bus)
    }
    if fleet is not None and fleet.model == "wecc":
        from stabctl.storage.devices import battery_case

        run = battery_case(case, fleet)[0].converters
        for k, b in list(zip(run.number, run.bus))[len(case.converters) :]:
            names[str(int(k))] = f"C{int(k)} (bus {int(b)}, WECC battery)"
    return names
