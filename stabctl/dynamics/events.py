"""Disturbances of a dynamic run and the network configuration they give at each time.

Faults follow PST's switching sequence (`y_switch.m`, PST manual section 2.5): a
three-phase fault at a bus, cleared at the near end (the faulted circuit opens there and the
far end keeps feeding the fault through it) and later at the far end (the circuit is out);
a fault without a far bus is cleared without loss of a line.  A line is opened as PST does:
its reactance becomes 1e7 pu; its charging stays connected under the pstess conventions and
goes with it under ieee (docs/conventions.md 9); a line opened by a trip or a fault's
clearing may be closed again (`LineClose`, a reclosure).  A machine's exciter voltage
reference and its governor's power reference can be stepped (`VrefStep`, `PrefStep`: PSS/E's
change of VREF and of PREF, the PSS/E Program Operation Manual's ``change_vref`` /
``change_gref``).  Any number of events per run, in any order.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from stabctl.case import Case, require_case
from stabctl.case.events import EVENT_KINDS as EVENT_KINDS
from stabctl.case.events import (
    ConverterTrip,
    Fault,
    GeneratorTrip,
    LineClose,
    LineTrip,
    LoadStep,
    MotorSwitch,
    Playback,
    PrefStep,
    VrefStep,
    check_event,
    check_totals,
    events_of_records,
)
from stabctl.case.events import as_record as as_record
from stabctl.dynamics.model import StageConfig
from stabctl.errors import CaseError, InputError, WrongTypeError, advice, require_number

#: the classes an event of a run may be (a case's own records' and a playback source)
EVENT_TYPES = (*EVENT_KINDS.values(), Playback)


def validate(case: Case, events, t_end: float) -> None:
    """Check every event against the case (buses, lines, machines, times finite and >= 0,
    the size of each load, VREF and PREF step and their running sums:
    `stabctl.case.events.check_event`, `check_totals`); raises UnknownBusError, CaseError,
    InputError, and TypeError for an object that is no event.  Events after t_end are
    allowed (not reached).
    A circuit opened twice (a line trip of the line a fault's clearing opens, two trips of
    one circuit without a `LineClose` between) or a machine tripped twice is an InputError:
    the second would do nothing; so is a `LineClose` of a circuit that is not open then
    (or whose fault is not cleared at both ends yet)."""
    opened: dict = {}
    switchings: dict = {}
    for ev in events:
        if not isinstance(ev, EVENT_TYPES):  # a str, None: failed on .times()
            raise WrongTypeError(
                f"run(events): each event is a Fault, LineTrip, ... (stabctl.case.events), "
                f"got {type(ev).__name__} {ev!r}"
            )
        odd = [t for t in ev.times() if not np.isfinite(t)]
        if odd:  # a NaN time compares false with everything: such an event never came
            raise InputError(f"event {ev} has a time that is not a finite number ({odd[0]} s)")
        check_event(case, ev)  # the one check of what it names and its size, at load too
        if isinstance(ev, Fault):
            if ev.clear_near is not None and ev.clear_near < ev.t:
                raise InputError(
                    f"fault at bus {ev.bus}: cleared at {ev.clear_near} s "
                    f"before it starts at {ev.t} s"
                )
            if (
                ev.far_clear is not None
                and ev.clear_near is not None
                and ev.far_clear < ev.clear_near
            ):
                raise InputError(f"fault at bus {ev.bus}: far end clears before near end")
            if ev.far_bus is not None:
                row = case.circuit_row(ev.bus, ev.far_bus, ev.circuit)
                if ev.clear_near is not None:
                    switchings.setdefault(row, []).append((ev.clear_near, ev.far_clear, ev))
        elif isinstance(ev, (LineTrip, LineClose)):
            row = case.circuit_row(ev.from_bus, ev.to_bus, ev.circuit)
            switchings.setdefault(row, []).append((ev.t, ev.t, ev))
        elif isinstance(ev, (VrefStep, PrefStep)):
            _controlled(case, ev)
        elif isinstance(ev, GeneratorTrip):
            _open_once(opened, f"machine {ev.machine}", ev)
        elif isinstance(ev, ConverterTrip):
            _open_once(opened, f"converter {ev.converter}", ev)
        elif isinstance(ev, Playback):
            _check_playback(case, ev)
        # a LoadStep or MotorSwitch: check_event was all (any other is refused above)
        refuse_negative_time(ev)
    for row, sw in switchings.items():
        _check_switchings(_circuit(case, row), sw)
    check_totals(case, events)


def warn_unfinished(events, t_end: float) -> None:
    """Warn (RuntimeWarning) of the first fault that has begun before `t_end` (s) and is
    cleared at or after it: the run ends with it still on, and its verdict is of the
    fault held on, not of its clearing (the CLI refuses such a run, `simulate --tf`).
    A fault never cleared (no clearing time) is meant so: no warning.
    `stabctl.stability.cct.fault_on_failure` holds a fault on to the end on purpose."""
    for ev in events:
        if isinstance(ev, Fault) and ev.t < t_end and any(t >= t_end for t in ev.times()):
            warnings.warn(
                f"run ends at {t_end:g} s with a fault still on (a clearing at or after the "
                f"end does not happen; its verdict is of the fault held on): {ev}",
                RuntimeWarning,
                stacklevel=5,
            )
            return


def _check_switchings(what: str, sw: list) -> None:
    """InputError unless the openings (a `LineTrip`, a `Fault`'s clearing) and closings
    (`LineClose`) of one circuit alternate, starting closed, each closing strictly after
    the opening before it is complete (a fault's far-end clearing).  sw: (time, time the
    opening is complete, event), in any order."""
    last = None
    for t, _done, ev in sorted(sw, key=lambda s: (s[0], isinstance(s[2], LineClose))):
        closing = isinstance(ev, LineClose)
        if closing and last is None:
            raise InputError(f"{what}: {ev} closes it while it is not open")
        if closing and not t > last[1]:
            opened = last[2]
            raise InputError(
                f"{what}: {ev} comes at or before the far end of the fault at bus "
                f"{opened.bus} (at {opened.t:g} s) clears at {last[1]:g} s: the circuit is "
                "open only from then"
                if isinstance(opened, Fault)
                else f"{what}: {ev} comes at or before {opened}, which opens it"
            )
        if not closing and last is not None:
            raise InputError(
                f"{what} is tripped twice, by {last[2]} and by {ev}: the second would do "
                f"nothing (close it between with {advice('LineClose', '--close')}, or give "
                f"{advice('it', 'each --trip and --fault')} once)"
            )
        last = None if closing else (t, _done, ev)


def _controlled(case: Case, ev) -> None:
    """CaseError if the machine of a `VrefStep` has no exciter or that of a `PrefStep` no
    governor (the machine itself looked up by `check_names`)."""
    table, what = (
        (case.exciters, "exciter (exc_con)")
        if isinstance(ev, VrefStep)
        else (case.governors, "governor (tg_con)")
    )
    if ev.machine not in set(np.asarray(table.machine, int).tolist()):
        raise CaseError(f"{ev}: machine {ev.machine} has no {what} whose reference to step")


def _check_playback(case: Case, ev: Playback) -> None:
    """CaseError if ``ev``'s machine is not a playback source (its values and times are
    checked when it is made, `Playback`)."""
    m = case.machine_index(ev.machine)
    if case.machines.playback[m] != 1:
        raise CaseError(f"machine {ev.machine} is not a playback source (mac_con playback 0)")


def _circuit(case: Case, row: int) -> str:
    br = case.branches
    return f"circuit {int(br.from_bus[row])}-{int(br.to_bus[row])} (branch row {row + 1})"


def refuse_negative_time(ev) -> None:
    """InputError if any time of event ``ev`` (its ``times()``, s) is negative: a run
    starts at t = 0 (`validate`; the CLI's options name themselves around it)."""
    if any(t < 0 for t in ev.times()):
        raise InputError(f"event {ev} has a negative time (a run starts at t = 0 s)")


def _open_once(opened: dict, what: str, ev) -> None:
    """Record that ``ev`` trips ``what`` (a machine or a converter, "KIND NUMBER");
    InputError if an earlier event trips it already."""
    first = opened.setdefault(what, ev)
    if first is not ev:
        raise InputError(
            f"{what} is tripped twice, by {first} and by {ev}: the second would do nothing "
            f"(give each {what.split()[0]} once)"
        )


def stage_boundaries(events, t_end: float) -> list[tuple[float, int, int]]:
    """Every change of network configuration before t_end, in time order:
    (time, event index, phase), phase counting the event's own changes (a fault: 1 on,
    2 near end cleared, 3 far end cleared).  A fault cleared at both ends at the same
    instant keeps its two changes, as PSTess keeps the zero-length interval between them
    (one step of h = 0 in the near-end-cleared network)."""
    out = []
    for i, ev in enumerate(events):
        if isinstance(ev, Fault):
            times = (
                [ev.t]
                if ev.clear_near is None
                else [ev.t, ev.clear_near] + ([ev.far_clear] if ev.far_bus is not None else [])
            )
        else:
            times = ev.times()
        out += [(float(t), i, k + 1) for k, t in enumerate(times) if t < t_end]
    return sorted(out)


def configuration(case: Case, events, phases, V0: np.ndarray) -> StageConfig:
    """Network configuration with phases[i] changes of event i applied (see
    `stage_boundaries`)."""
    faults, feeds, tripped, loads, lines, converters = [], [], [], [], [], []
    on = {k: bool(case.motors.in_service[k]) for k in range(len(case.motors))}
    switched, played = [], []
    vref: dict = {}
    pref: dict = {}
    for ev, n in zip(events, phases):
        if n == 0:
            continue
        if isinstance(ev, Fault):
            if n == 1:
                faults.append((case.bus_index(ev.bus), ev.admittance))
            elif ev.far_bus is not None:
                row = case.circuit_row(ev.bus, ev.far_bus, ev.circuit)
                feeds.append((row, ev.far_bus, n == 2))
                lines.append((ev.clear_near, row, True))
        elif isinstance(ev, (LineTrip, LineClose)):
            row = case.circuit_row(ev.from_bus, ev.to_bus, ev.circuit)
            lines.append((ev.t, row, isinstance(ev, LineTrip)))
        elif isinstance(ev, VrefStep):
            m = case.machine_index(ev.machine)
            vref[m] = vref.get(m, 0.0) + ev.dV
        elif isinstance(ev, PrefStep):
            m = case.machine_index(ev.machine)
            pref[m] = pref.get(m, 0.0) + ev.dP
        elif isinstance(ev, GeneratorTrip):
            tripped.append(case.machine_index(ev.machine))
        elif isinstance(ev, ConverterTrip):
            converters.append(case.converter_index(ev.converter))
        elif isinstance(ev, LoadStep):
            b = case.bus_index(ev.bus)
            loads.append((b, complex(ev.P, -ev.Q) / abs(V0[b]) ** 2))
        elif isinstance(ev, MotorSwitch):
            switched.append((ev.t, case.motor_index(ev.motor), ev.on))
        elif isinstance(ev, Playback):
            played.append((case.machine_index(ev.machine), ev.dV[n - 1], ev.df[n - 1]))
    for _t, k, state in sorted(switched):  # the last switching of each motor holds
        on[k] = state
    is_open: dict = {}
    for _t, row, state in sorted(lines):  # the last switching of each circuit holds
        is_open[row] = state
    faulted = {f[0] for f in feeds}
    return StageConfig(
        faults=tuple(faults),
        opened=tuple(sorted(r for r, o in is_open.items() if o and r not in faulted)),
        fault_feeds=tuple(f for f in feeds if is_open[f[0]]),
        tripped_machines=tuple(sorted(set(tripped))),
        tripped_converters=tuple(sorted(set(converters))),
        load_steps=tuple(loads),
        motors_on=tuple(k for k, v in on.items() if v),
        playback=tuple(played),
        vref_steps=tuple(sorted(vref.items())),
        pref_steps=tuple(sorted(pref.items())),
    )


def stages(case: Case, events, t_end: float, V0: np.ndarray):
    """(start times, configurations) of the run's intervals, the first starting at 0.  A
    start time repeats only between the phases of one fault (PSTess's zero-length
    interval); simultaneous changes of different events form one stage."""
    phases = [0] * len(events)
    starts, configs, last = [0.0], [configuration(case, events, phases, V0)], None
    for t, i, k in stage_boundaries(events, t_end):
        phases[i] = k
        merge = t == starts[-1] and (len(starts) == 1 or last != i)  # t = 0, or another event
        if merge:
            configs[-1] = configuration(case, events, phases, V0)
        else:
            starts.append(t)
            configs.append(configuration(case, events, phases, V0))
        last = i
    return starts, configs


def fault_with_clearing(
    case: Case,
    bus: int,
    far_bus: int | None,
    t_fault: float,
    clear_cycles: float,
    far_clear_cycles: float | None = None,
    circuit: int = 1,
) -> Fault:
    """A fault cleared after a number of cycles at the near end and at the far end (the
    CLI's ``--clear-cycles`` / ``--far-clear-cycles``).

    Parameters
    ----------
    case : Case
        The case; its nominal frequency `freq_hz` (Hz) sets the cycle length 1 / freq_hz s.
    bus : int
        Faulted bus number (as in the data; the near end of the line).
    far_bus : int or None
        Far-end bus number of the faulted line, tripped at clearing; None: the fault is
        cleared without loss of a line.
    t_fault : float
        Fault start, s (absolute run time).
    clear_cycles : float
        Near-end clearing time, cycles of the case frequency after `t_fault` (>= 0).
    far_clear_cycles : float or None, optional
        Far-end clearing time, cycles after `t_fault` (>= `clear_cycles`); None (default):
        with the near end.
    circuit : int, optional
        Which of the parallel circuits between `bus` and `far_bus`; default 1.

    Returns
    -------
    Fault
        With ``clear_near = t_fault + clear_cycles / freq_hz`` and ``clear_far = t_fault +
        far_clear_cycles / freq_hz`` (s), checked against the case as a run checks it
        (`validate`).

    Raises
    ------
    InputError
        `clear_cycles` negative or not finite, `far_clear_cycles` below `clear_cycles`, both
        0 (a fault of no length), a `circuit` other than 1 or a `far_clear_cycles` other than
        `clear_cycles` without `far_bus`, a fault time that is negative or not finite.
    UnknownBusError, CaseError
        No bus `bus`, or no circuit `circuit` between `bus` and `far_bus`.
    TypeError
        `case` not a `Case`; a number of another type (`stabctl.errors.WrongTypeError`).
    """
    case = require_case(case, "fault_with_clearing(case)")
    near = require_number(clear_cycles, "fault_with_clearing(clear_cycles)", "cycles")
    far = near if far_clear_cycles is None else far_clear_cycles
    far = require_number(far, "fault_with_clearing(far_clear_cycles)", "cycles")
    if not (0 <= near < math.inf and near <= far < math.inf):
        raise InputError(
            "clearing cycles must be finite and >= 0 and the far end no earlier than the near "
            f"end, got {near:g} and {far:g}"
            + advice(" (clear_cycles, far_clear_cycles)", " (--clear-cycles, --far-clear-cycles)")
        )
    if far == 0:
        raise InputError(
            "fault_with_clearing(clear_cycles): 0 cycles at both ends, cleared as it starts: "
            "a fault of no length would do nothing (a line trip alone is "
            "LineTrip(t, from_bus, to_bus))"
        )
    if far_bus is None and circuit != 1:
        raise InputError(
            f"fault_with_clearing(circuit): circuit {circuit} given without far_bus (a bus "
            "fault loses no line)"
        )
    if far_bus is None and far_clear_cycles is not None and far != near:
        raise InputError(
            f"fault_with_clearing(far_clear_cycles): {far:g} cycles given without far_bus: "
            "a bus fault has no far end (it is cleared at clear_cycles); give the line's "
            "far_bus, or leave far_clear_cycles out"
        )
    cyc = 1.0 / case.freq_hz
    t_fault = require_number(t_fault, "fault_with_clearing(t_fault)", "s")
    fault = Fault(
        bus=bus,
        t=t_fault,
        clear_near=t_fault + near * cyc,
        clear_far=t_fault + far * cyc,
        far_bus=far_bus,
        circuit=circuit,
    )
    validate(case, [fault], math.inf)
    return fault


def from_case(case: Case) -> list:
    """The events of the case's own disturbance records (`Case.events`, written by
    `as_record`; `stabctl.case.events.events_of_records`), in their order.

    Parameters
    ----------
    case : Case
        The case (its records were checked when it was made).

    Returns
    -------
    list
        One event per record.
    """
    return events_of_records(case.events)


def from_sw_con(case: Case) -> list:
    """The disturbance of the case's own PST sw_con (types 0 fault, 4 line trip, 6 none)."""
    sw = case.sw_con
    if sw is None or len(sw) < 4:
        return []
    ftype = int(sw[1, 5])
    if ftype == 0:
        far = int(sw[1, 2]) if sw[1, 2] else None
        return [
            Fault(
                bus=int(sw[1, 1]),
                t=float(sw[1, 0]),
                clear_near=float(sw[2, 0]),
                clear_far=float(sw[3, 0]),
                far_bus=far,
            )
        ]
    if ftype == 4:
        return [LineTrip(int(sw[1, 1]), int(sw[1, 2]), float(sw[1, 0]))]
    if ftype == 6:
        return []
    raise CaseError(f"sw_con fault type {ftype} is not supported (0, 4 and 6 are)")
