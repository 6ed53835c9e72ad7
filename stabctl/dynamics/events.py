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

import re
from dataclasses import asdict, dataclass

import numpy as np

from stabctl.case import Case
from stabctl.dynamics.model import FAULT_B, StageConfig
from stabctl.errors import CaseError, InputError
from stabctl.network.ybus import circuit_row


class _AtOneTime:
    """An event that happens at one instant ``self.t`` (s)."""

    def __str__(self) -> str:
        """The event in words for messages, e.g. ``line trip 3-101 (circuit 1) at 1 s``."""
        kind = re.sub(r"(?<!^)(?=[A-Z])", " ", type(self).__name__).lower()
        f = {k: v for k, v in vars(self).items() if k != "t"}
        if "from_bus" in f:
            what = f"{f.pop('from_bus')}-{f.pop('to_bus')}"
            f = {"circuit": f.pop("circuit", 1), **f}
        else:
            what = ""
        detail = ", ".join(
            f"{k} {v:g}" if isinstance(v, float) else f"{k} {v}" for k, v in f.items()
        )
        return " ".join(
            t for t in (kind, what, f"({detail})" if detail else "", f"at {self.t:g} s") if t
        )

    def times(self):
        """The event's times.

        Returns
        -------
        list of float
            ``[t]``, s.
        """
        return [self.t]


@dataclass(frozen=True)
class Fault:
    """Three-phase fault at `bus` from `t`, cleared as PST's ``sw_con`` sequence
    (``y_switch.m``, PST manual section 2.5).

    At `clear_near` the faulted circuit opens at the near end (`bus`), the far end still
    feeding the fault through it; at `clear_far` it opens at the far end too and the fault is
    gone, the circuit staying out (a line opened as PST: reactance 1e7 pu; its charging
    kept under pstess, removed under ieee):
    PST's fault type 0.  With equal near and far times the zero-length interval between
    the two openings is kept, as PSTess does.  The times are checked against the case when the
    run starts (`Simulator.run`): InputError for a clearing before the fault or a far end
    before the near end, CaseError / UnknownBusError for an unknown bus or line.

    Attributes
    ----------
    bus : int
        Faulted bus number (as in the data; the near end of the faulted line).
    t : float
        Fault start, s (absolute run time, >= 0).
    clear_near : float or None, optional
        Absolute time the near end clears, s (>= `t`); None (default): never cleared.
    clear_far : float or None, optional
        Absolute time the far end clears, s (>= `clear_near`); None (default): with the
        near end.
    far_bus : int or None, optional
        Bus number of the far end of the faulted line, tripped at clearing; None (default):
        the fault is cleared at `clear_near` without loss of a line.
    circuit : int, optional
        Which of the parallel circuits between `bus` and `far_bus` is faulted (1 = the
        first branch row joining them); default 1.
    r, x : float, optional
        Fault resistance and reactance, pu on the system base; ``r = x = 0`` (default) is
        PST's bolted fault (shunt susceptance -1e7 pu at the bus).  A negative `x` is
        taken as 0.
    """

    bus: int
    t: float
    clear_near: float | None = None
    clear_far: float | None = None
    far_bus: int | None = None
    circuit: int = 1
    r: float = 0.0
    x: float = 0.0

    @property
    def admittance(self) -> complex:
        """Fault shunt admittance (pu, system base): ``-1j * 1e7`` for a bolted fault, else
        ``1 / (r + j max(x, 0))``."""
        if self.r == 0 and self.x == 0:
            return -1j * FAULT_B
        return 1.0 / complex(self.r, max(self.x, 0.0))

    def times(self):
        """The event's times that are set.

        Returns
        -------
        list of float
            Fault start, near-end clearing and far-end clearing (`far_clear`), s, those
            that are not None, in that order.
        """
        return [t for t in (self.t, self.clear_near, self.far_clear) if t is not None]

    @property
    def far_clear(self):
        """Far-end clearing time (s): `clear_far`, or `clear_near` when that is None."""
        return self.clear_near if self.clear_far is None else self.clear_far

    def __str__(self) -> str:
        """The fault in words for messages, e.g. ``fault at bus 3 on line 3-101 at 1 s,
        cleared at 1.1 s``."""
        line = "" if self.far_bus is None else f" on line {self.bus}-{self.far_bus}"
        if self.far_bus is not None and self.circuit != 1:
            line += f" (circuit {self.circuit})"
        if self.clear_near is None:
            return f"fault at bus {self.bus}{line} at {self.t:g} s, never cleared"
        far = "" if self.far_clear == self.clear_near else f", far end at {self.far_clear:g} s"
        return (
            f"fault at bus {self.bus}{line} at {self.t:g} s, cleared at {self.clear_near:g} s{far}"
        )


@dataclass(frozen=True)
class LineTrip(_AtOneTime):
    """Open one circuit of the line `from_bus`-`to_bus` at `t`, without fault (PST's
    ``sw_con`` type 4; the line opened as PST: reactance 1e7 pu, its charging kept under
    the pstess conventions, removed under ieee).

    Attributes
    ----------
    from_bus, to_bus : int
        Bus numbers (as in the data) of the line's ends, in either order.
    t : float
        Opening time, s (absolute run time, >= 0).
    circuit : int, optional
        Which of the parallel circuits between the two buses (1 = the first branch row
        joining them); default 1.  An unknown line raises CaseError when the run starts.
    """

    from_bus: int
    to_bus: int
    t: float
    circuit: int = 1


@dataclass(frozen=True)
class LineClose(_AtOneTime):
    """Close again at `t` one circuit of the line `from_bus`-`to_bus` that an earlier
    `LineTrip` or a `Fault`'s clearing opened (a reclosure; PSS/E's ``dist_branch_close``):
    from `t` the line is back in the network with its charging.

    Attributes
    ----------
    from_bus, to_bus : int
        Bus numbers (as in the data) of the line's ends, in either order.
    t : float
        Closing time, s (absolute run time, >= 0); after the opening (and after a fault's
        far-end clearing), else InputError when the run starts.
    circuit : int, optional
        Which of the parallel circuits between the two buses (1 = the first branch row
        joining them); default 1.
    """

    from_bus: int
    to_bus: int
    t: float
    circuit: int = 1


@dataclass(frozen=True)
class GeneratorTrip(_AtOneTime):
    """Disconnect a generator at `t`.

    Attributes
    ----------
    machine : int
        Machine number (as in the data, PST ``mac_con`` column 1); an unknown machine
        raises CaseError when the run starts.
    t : float
        Disconnection time, s (absolute run time, >= 0).
    """

    machine: int
    t: float


@dataclass(frozen=True)
class LoadStep(_AtOneTime):
    """Add P + jQ of constant-impedance load at `bus` from `t`.

    The load is the shunt admittance (P - jQ) / abs(V0)^2, V0 the bus voltage of the power
    flow, so it draws P + jQ at that voltage and scales with abs(V)^2; negative values remove
    load (a pulse is two steps of opposite sign).

    Attributes
    ----------
    bus : int
        Bus number (as in the data); an unknown bus raises UnknownBusError when the run
        starts.
    t : float
        Time of the step, s (absolute run time, >= 0).
    P : float
        Real power added, pu on the system base (+ drawn from the network).
    Q : float, optional
        Reactive power added, pu on the system base (+ inductive, drawn); default 0.
    """

    bus: int
    t: float
    P: float
    Q: float = 0.0


@dataclass(frozen=True)
class VrefStep(_AtOneTime):
    """Step the voltage reference of a machine's exciter by `dV` at `t` (PSS/E's change of
    VREF, ``change_vref``; ANDES's Alter of an exciter's ``vref0``): from `t` the exciter's
    summing junction takes VREF0 + dV, VREF0 its initial reference.  Steps of one machine
    add up.

    Attributes
    ----------
    machine : int
        Machine number (as in the data, ``mac_con`` column 1); a machine without an exciter
        (``exc_con``) raises CaseError when the run starts.
    t : float
        Time of the step, s (absolute run time, >= 0).
    dV : float
        Change of the reference, pu of the machine's terminal voltage base.
    """

    machine: int
    t: float
    dV: float


@dataclass(frozen=True)
class PrefStep(_AtOneTime):
    """Step the power reference of a machine's governor by `dP` at `t` (PSS/E's change of
    PREF, ``change_gref``; ANDES's Alter of a governor's ``pref0``): from `t` the governor
    takes PREF0 + dP, PREF0 its initial reference (its load reference).  With droop R the
    speed settles (1 / R) dP per unit of the machine's own reference change, the others'
    governors sharing it.  Steps of one machine add up.

    Attributes
    ----------
    machine : int
        Machine number (as in the data, ``mac_con`` column 1; a cross-compound unit's HP
        machine); a machine without a governor (``tg_con``) raises CaseError when the run
        starts.
    t : float
        Time of the step, s (absolute run time, >= 0).
    dP : float
        Change of the reference, pu on the machine's base.
    """

    machine: int
    t: float
    dP: float


@dataclass(frozen=True)
class MotorSwitch(_AtOneTime):
    """Switch an induction motor (`stabctl.models.motors`, the case's ``motors``) on or
    off at `t` (ANDES's Toggle of a Motor5): on, it is a dynamic load at its bus from its
    present states (at the first switching all 0: energised at synchronous speed without
    flux, as ANDES's); off, it draws nothing and its states stand still.

    Attributes
    ----------
    motor : int
        Motor number (``mot_con`` column 1); an unknown motor raises CaseError when the
        run starts.
    t : float
        Switching time, s (absolute run time, >= 0).
    on : bool, optional
        True (default) to switch on, False off.
    """

    motor: int
    t: float
    on: bool = True


@dataclass(frozen=True)
class Playback:
    """Move a playback source's targets (a machine with ``playback`` 1: ANDES's PLBVFU1)
    at given times: from at[k] on, its E' target is its initial E' + dV[k] and its speed
    target 1 + df[k] (pu), held until the next time (ANDES's TimeSeries, mode 1); E' and
    the speed follow through the lags pb_Tv, pb_Tf.  From a recorded V, f series (ANDES:
    Vts, fts with Vscale, fscale): dV = (V - V[0]) / Vscale, df = (f - f[0]) / fscale.

    Attributes
    ----------
    machine : int
        Machine number (``mac_con`` column 1) of a playback source; another raises
        CaseError when the run starts.
    at : tuple of float
        Times of the values, s, rising, >= 0.
    dV, df : tuple of float
        The targets' changes from those times on, pu (as many as `at`).
    """

    machine: int
    at: tuple
    dV: tuple
    df: tuple

    def times(self):
        """The times the targets change.

        Returns
        -------
        list of float
            ``at``, s.
        """
        return [float(t) for t in self.at]


def validate(case: Case, events, t_end: float) -> None:
    """Check every event against the case (buses, lines, machines, times >= 0); raises
    UnknownBusError, CaseError, InputError.  Events after t_end are allowed (not reached).
    A circuit opened twice (a line trip of the line a fault's clearing opens, two trips of
    one circuit without a `LineClose` between) or a machine tripped twice is an InputError:
    the second would do nothing; so is a `LineClose` of a circuit that is not open then
    (or whose fault is not cleared at both ends yet)."""
    opened: dict = {}
    switchings: dict = {}
    for ev in events:
        if isinstance(ev, Fault):
            case.bus_index(ev.bus)
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
                row = circuit_row(case, ev.bus, ev.far_bus, ev.circuit)
                if ev.clear_near is not None:
                    switchings.setdefault(row, []).append((ev.clear_near, ev.far_clear, ev))
        elif isinstance(ev, (LineTrip, LineClose)):
            row = circuit_row(case, ev.from_bus, ev.to_bus, ev.circuit)
            switchings.setdefault(row, []).append((ev.t, ev.t, ev))
        elif isinstance(ev, (VrefStep, PrefStep)):
            _controlled(case, ev)
        elif isinstance(ev, GeneratorTrip):
            case.machine_index(ev.machine)
            _open_once(opened, f"machine {ev.machine}", ev)
        elif isinstance(ev, LoadStep):
            case.bus_index(ev.bus)
        elif isinstance(ev, MotorSwitch):
            _motor_index(case, ev.motor)
        elif isinstance(ev, Playback):
            _check_playback(case, ev)
        else:
            raise InputError(f"unknown event {ev!r}")
        if any(t < 0 for t in ev.times()):
            raise InputError(
                f"event {ev} has a negative time (events after t_end = {t_end} s "
                "simply do not happen)"
            )
    for row, sw in switchings.items():
        _check_switchings(_circuit(case, row), sw)


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
            raise InputError(
                f"{what}: {ev} closes it at or before {last[2]} opens it ({last[1]:g} s)"
            )
        if not closing and last is not None:
            raise InputError(
                f"{what} is tripped twice, by {last[2]} and by {ev}: the second would do "
                "nothing (close it between with LineClose, or give it once)"
            )
        last = None if closing else (t, _done, ev)


def _controlled(case: Case, ev) -> None:
    """CaseError if the machine of a `VrefStep` has no exciter or that of a `PrefStep` no
    governor (UnknownBusError-like CaseError for an unknown machine)."""
    case.machine_index(ev.machine)
    table, what = (
        (case.exciters, "exciter (exc_con)")
        if isinstance(ev, VrefStep)
        else (case.governors, "governor (tg_con)")
    )
    if ev.machine not in set(np.asarray(table.machine, int).tolist()):
        raise CaseError(f"{ev}: machine {ev.machine} has no {what} whose reference to step")


def _check_playback(case: Case, ev: Playback) -> None:
    """CaseError if ``ev``'s machine is not a playback source; InputError for values that
    are not one per time or times that do not rise."""
    m = case.machine_index(ev.machine)
    if case.machines.playback[m] != 1:
        raise CaseError(f"machine {ev.machine} is not a playback source (mac_con playback 0)")
    if not len(ev.at) == len(ev.dV) == len(ev.df) or not len(ev.at):
        raise InputError(f"playback of machine {ev.machine}: one dV and one df per time")
    if np.any(np.diff(ev.at) <= 0):
        raise InputError(f"playback of machine {ev.machine}: the times must rise")


def _motor_index(case: Case, number: int) -> int:
    """The row of motor ``number`` in ``case.motors``; CaseError if it has none."""
    hit = np.flatnonzero(case.motors.number == number)
    if hit.size == 0:
        raise CaseError(f"motor {number} does not exist in mot_con")
    return int(hit[0])


def _circuit(case: Case, row: int) -> str:
    br = case.branches
    return f"circuit {int(br.from_bus[row])}-{int(br.to_bus[row])} (branch row {row + 1})"


def _open_once(opened: dict, what: str, ev) -> None:
    """Record that ``ev`` trips ``what`` (a machine); InputError if an earlier event trips
    it already."""
    first = opened.setdefault(what, ev)
    if first is not ev:
        raise InputError(
            f"{what} is tripped twice, by {first} and by {ev}: the second would do nothing "
            "(give each machine once)"
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
    faults, feeds, tripped, loads, lines = [], [], [], [], []
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
                row = circuit_row(case, ev.bus, ev.far_bus, ev.circuit)
                feeds.append((row, ev.far_bus, n == 2))
                lines.append((ev.clear_near, row, True))
        elif isinstance(ev, (LineTrip, LineClose)):
            row = circuit_row(case, ev.from_bus, ev.to_bus, ev.circuit)
            lines.append((ev.t, row, isinstance(ev, LineTrip)))
        elif isinstance(ev, VrefStep):
            m = case.machine_index(ev.machine)
            vref[m] = vref.get(m, 0.0) + ev.dV
        elif isinstance(ev, PrefStep):
            m = case.machine_index(ev.machine)
            pref[m] = pref.get(m, 0.0) + ev.dP
        elif isinstance(ev, GeneratorTrip):
            tripped.append(case.machine_index(ev.machine))
        elif isinstance(ev, LoadStep):
            b = case.bus_index(ev.bus)
            loads.append((b, complex(ev.P, -ev.Q) / abs(V0[b]) ** 2))
        elif isinstance(ev, MotorSwitch):
            switched.append((ev.t, _motor_index(case, ev.motor), ev.on))
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
        far_clear_cycles / freq_hz`` (s).  Buses and lines are checked when the run starts.

    Raises
    ------
    InputError
        `clear_cycles` negative, or `far_clear_cycles` below `clear_cycles`.
    """
    if clear_cycles < 0 or (far_clear_cycles is not None and far_clear_cycles < clear_cycles):
        raise InputError(
            "clearing cycles must be >= 0 and the far end no earlier than the near end"
        )
    cyc = 1.0 / case.freq_hz
    far = clear_cycles if far_clear_cycles is None else far_clear_cycles
    return Fault(
        bus=bus,
        t=t_fault,
        clear_near=t_fault + clear_cycles * cyc,
        clear_far=t_fault + far * cyc,
        far_bus=far_bus,
        circuit=circuit,
    )


#: the event classes a case's own records may name (`Case.events`, ``kind``)
EVENT_KINDS = {
    cls.__name__: cls
    for cls in (
        Fault,
        LineTrip,
        LineClose,
        GeneratorTrip,
        LoadStep,
        VrefStep,
        PrefStep,
        MotorSwitch,
    )
}


def as_record(ev, source: str) -> dict:
    """A `Case.events` record of an event: its class name as ``kind``, its fields, and
    ``source`` (where it came from, e.g. ``"Toggle Toggler_1 (ieee14.xlsx)"``).

    Parameters
    ----------
    ev : Fault, LineTrip, LineClose, GeneratorTrip, LoadStep, VrefStep, PrefStep or MotorSwitch
        The event.
    source : str
        The record it was read from.

    Returns
    -------
    dict
        JSON-ready (numbers and strings).
    """
    return {"kind": type(ev).__name__, **asdict(ev), "source": source}


def from_case(case: Case) -> list:
    """The events of the case's own disturbance records (`Case.events`, written by
    `as_record`), in their order.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    list
        One event per record.

    Raises
    ------
    CaseError
        A record of an unknown ``kind`` or with fields its class does not take, named
        with its ``source``.
    """
    out = []
    for k, rec in enumerate(case.events):
        fields = {f: v for f, v in rec.items() if f not in ("kind", "source")}
        where = f"events[{k}] ({rec.get('source', 'no source')})"
        cls = EVENT_KINDS.get(rec["kind"])
        if cls is None:
            raise CaseError(
                f"{where}: unknown event kind {rec['kind']!r} (known: {', '.join(EVENT_KINDS)})"
            )
        try:
            out.append(cls(**fields))
        except TypeError as e:
            raise CaseError(f"{where}: {rec['kind']} {e}") from None
    return out


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
