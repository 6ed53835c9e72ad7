"""The disturbances of a run as data, and the records a case keeps of its own.

The event classes (a fault, a line trip or closure, a generator trip, a load, VREF or
PREF step, a motor switching, a playback source's targets) are plain frozen dataclasses:
`stabctl.dynamics.events` checks them against a case and turns them into the network
stages of a run.  A case's own disturbance (`Case.events`, as ``import-andes`` stores
ANDES's Toggle, Fault and Alter records) is a tuple of records, each its event's class
name as ``kind``, its fields and its ``source``; `events_of_records` makes them events,
and a case is made only if it can (`stabctl.case.Case`): a case with a malformed event is
a malformed case.  `check_names` looks up the buses, lines, machines and motors an event
names in a case (`stabctl.dynamics.events.validate` when a run starts), `check_values`
the size of a load, VREF or PREF step against its bound in the case (`step_limit`; 0, a
step that would do nothing, refused too) and `check_totals` the steps' running sums;
`check_event` does the first two, `check_case_events` all three for a case's own records
(a case file's reader, when it is loaded); the event's times against each other are
checked when it runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from numbers import Real
from typing import TYPE_CHECKING

import numpy as np

from stabctl.errors import CaseError, InputError, check_fields, require_items, require_number

if TYPE_CHECKING:
    from stabctl.case.system import Case

__all__ = [
    "FAULT_B",
    "Fault",
    "LineTrip",
    "LineClose",
    "GeneratorTrip",
    "ConverterTrip",
    "LoadStep",
    "VrefStep",
    "PrefStep",
    "MotorSwitch",
    "Playback",
    "EVENT_KINDS",
    "as_record",
    "described",
    "events_of_records",
    "check_names",
    "VREF_STEP_MAX",
    "step_limit",
    "check_values",
    "check_event",
    "check_totals",
    "check_case_events",
]

#: PST's bolted-fault shunt susceptance (1/1e-7), pu
FAULT_B = 1e7


class _AtOneTime:
    """An event that happens at one instant ``self.t`` (s)."""

    t: float  # each subclass's field (a plain annotation: no field of this base)

    def __post_init__(self):
        check_fields(self)  # a text bus or time named here, not deep in a run

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
    before the near end, CaseError / UnknownBusError for an unknown bus or line.  A field
    of another type (a bus given as text, a time as a bool) is refused when the fault is
    made (`stabctl.errors.WrongTypeError`, `stabctl.errors.check_fields`), as it is by every
    event class.

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
        PST's bolted fault (shunt susceptance -1e7 pu at the bus); each finite and >= 0
        (`check_values`, when a run starts).
    """

    bus: int
    t: float
    clear_near: float | None = None
    clear_far: float | None = None
    far_bus: int | None = None
    circuit: int = 1
    r: float = 0.0
    x: float = 0.0

    def __post_init__(self):
        check_fields(self)  # Fault('3', 1.0) ran as bus 3

    @property
    def admittance(self) -> complex:
        """Fault shunt admittance (pu, system base): ``-1j * 1e7`` for a bolted fault, else
        ``1 / (r + j x)``."""
        if self.r == 0 and self.x == 0:
            return -1j * FAULT_B
        return 1.0 / complex(self.r, self.x)

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
        """The fault in words, as messages and the CLI give it: ``3-phase fault at bus 3
        at 1 s on line 3-101 (circuit 1), cleared at 1.1 s (after 100.0 ms), line
        tripped``."""
        z = "" if self.r == 0 and self.x == 0 else f" through {self.r:g}{self.x:+g}j pu"
        s = f"3-phase fault{z} at bus {self.bus} at {self.t:g} s"
        if self.clear_near is None:
            return s + ", never cleared"
        near = f"at {_ms(self.clear_near)} s (after {_after(self.clear_near - self.t)} ms)"
        if self.far_bus is None:
            return s + f", cleared {near} without loss of a line"
        far = f"at {_ms(self.far_clear)} s (after {_after(self.far_clear - self.t)} ms)"
        return (
            s
            + f" on line {self.bus}-{self.far_bus} (circuit {self.circuit}), cleared "
            + (near if far == near else f"{near} near / {far} far end")
            + ", line tripped"
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

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        return (
            f"line {self.from_bus}-{self.to_bus} (circuit {self.circuit}) tripped at {self.t:g} s"
        )


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

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        return f"line {self.from_bus}-{self.to_bus} (circuit {self.circuit}) closed at {self.t:g} s"


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

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        return f"machine {self.machine} tripped at {self.t:g} s"


@dataclass(frozen=True)
class ConverterTrip(_AtOneTime):
    """Disconnect a converter (a REGCA1/REGCB1 plant, a PVD1, an ESD1, a DERA1; the
    case's ``converters``) at `t`: from then on it injects nothing and its states stand
    still (PSS/E's ``dist_machine_trip`` of a renewable machine).

    Attributes
    ----------
    converter : int
        Converter number (``ibr_con`` column 1); an unknown converter raises CaseError
        when the run starts.
    t : float
        Disconnection time, s (absolute run time, >= 0).
    """

    converter: int
    t: float

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        return f"converter {self.converter} tripped at {self.t:g} s"


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

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        return f"load step {self.P:g}{self.Q:+g}j pu at bus {self.bus} at {self.t:g} s"


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

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        return f"VREF of machine {self.machine} stepped by {self.dV:+g} pu at {self.t:g} s"


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

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        return f"PREF of machine {self.machine} stepped by {self.dP:+g} pu at {self.t:g} s"


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

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        return f"motor {self.motor} switched {'on' if self.on else 'off'} at {self.t:g} s"


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

    Raises
    ------
    InputError
        Values that are not one per time, no time, or times that do not rise.
    WrongTypeError
        A field of another type (a text, an item that is no number).
    """

    machine: int
    at: tuple
    dV: tuple
    df: tuple

    def __post_init__(self):
        check_fields(self)
        for name in ("at", "dV", "df"):  # one number a time, as tuples (hashable)
            items = require_items(getattr(self, name), f"Playback({name})", "a list of numbers")
            values = tuple(require_number(v, f"Playback({name})") for v in items)
            object.__setattr__(self, name, values)
        if not len(self.at) == len(self.dV) == len(self.df) or not self.at:
            raise InputError(
                f"playback of machine {self.machine}: one dV and one df per time, at least one "
                f"(at {len(self.at)}, dV {len(self.dV)}, df {len(self.df)})"
            )
        if not all(b > a for a, b in zip(self.at, self.at[1:])):  # NaN too
            raise InputError(f"playback of machine {self.machine}: the times (at) must rise")

    def times(self):
        """The times the targets change.

        Returns
        -------
        list of float
            ``at``, s.
        """
        return [float(t) for t in self.at]

    def __str__(self) -> str:
        """The event in words, as messages and the CLI give it."""
        start = f" from {self.at[0]:g} s" if len(self.at) else ""
        return f"playback of machine {self.machine} at {len(self.at)} time(s){start}"


#: the event classes a case's own records may name (`Case.events`, ``kind``)
EVENT_KINDS = {
    cls.__name__: cls
    for cls in (
        Fault,
        LineTrip,
        LineClose,
        GeneratorTrip,
        ConverterTrip,
        LoadStep,
        VrefStep,
        PrefStep,
        MotorSwitch,
    )
}


def described(ev, case: Case) -> str:
    """How a summary names event `ev` of `case`: its text, its machine (if it has one)
    named as every output names machines (`Case.machine_name`: ``G4 (bus 12) tripped at
    5 s`` for ``machine 4 tripped at 5 s``).

    Parameters
    ----------
    ev : event
        One of the event classes.
    case : Case
        The case it belongs to.

    Returns
    -------
    str
    """
    text = str(ev)
    machine = getattr(ev, "machine", None)
    if machine is None:
        return text
    return text.replace(f"machine {machine}", case.machine_name(machine), 1)


def as_record(ev, source: str) -> dict:
    """A `Case.events` record of an event: its class name as ``kind``, its fields, and
    ``source`` (where it came from, e.g. ``"Toggle Toggler_1 (ieee14.xlsx)"``).

    Parameters
    ----------
    ev : Fault, LineTrip, LineClose, GeneratorTrip, ConverterTrip, LoadStep, VrefStep, \
PrefStep or MotorSwitch
        The event.
    source : str
        The record it was read from.

    Returns
    -------
    dict
        JSON-ready (numbers and strings).
    """
    return {"kind": type(ev).__name__, **asdict(ev), "source": source}


def events_of_records(records) -> list:
    """The events of a case's own records (`Case.events`, written by `as_record`), in
    their order.

    Parameters
    ----------
    records : iterable of Mapping
        Each with ``kind`` (a name of :data:`EVENT_KINDS`), that class's fields and
        optionally ``source`` (where it was read from).

    Returns
    -------
    list
        One event per record.

    Raises
    ------
    CaseError
        A record that is not a mapping with a text ``kind``, of an unknown kind, with a
        field its class does not take or without one it needs, or with a value that is
        not of its field's kind (a finite number; an integer for a bus, machine or
        circuit; true/false for ``on``; null only where the field may be absent); named
        ``events[k]`` with its ``source``.
    """
    return [_event_of_record(k, rec) for k, rec in enumerate(records)]


def _event_of_record(k: int, rec):
    """The event of record ``k`` (`events_of_records`)."""
    if not isinstance(rec, Mapping) or not isinstance(rec.get("kind"), str):
        raise CaseError(f"events[{k}]: not a record with a 'kind' (an event class name)")
    where = f"events[{k}] ({rec.get('source', 'no source')})"
    cls = EVENT_KINDS.get(rec["kind"])
    if cls is None:
        raise CaseError(
            f"{where}: unknown event kind {rec['kind']!r} (known: {', '.join(EVENT_KINDS)})"
        )
    values = {f: v for f, v in rec.items() if f not in ("kind", "source")}
    for f in fields(cls):
        if f.name in values and not _fits(str(f.type), values[f.name]):
            raise CaseError(
                f"{where}: {rec['kind']} field '{f.name}': {values[f.name]!r} is not "
                f"{_KIND_TEXT.get(str(f.type), str(f.type))}"
            )
    try:
        return cls(**values)
    except TypeError as e:
        raise CaseError(f"{where}: {rec['kind']} {e}") from None


def check_names(case: Case, ev) -> None:
    """Look up in ``case`` every bus, line, machine and motor ``ev`` names.

    Parameters
    ----------
    case : Case
        The case.
    ev : Fault, LineTrip, LineClose, GeneratorTrip, ConverterTrip, LoadStep, VrefStep, PrefStep, \
MotorSwitch or Playback
        The event.

    Raises
    ------
    UnknownBusError
        A bus not in the case (`Case.bus_index`), the message naming it.
    CaseError
        A line (circuit) not in the case (`Case.circuit_row`), a machine
        (`Case.machine_index`), a converter (`Case.converter_index`) or a motor
        (`Case.motor_index`) it lacks, the message naming it.
    """
    if isinstance(ev, Fault):
        case.bus_index(ev.bus)
        if ev.far_bus is not None:
            case.circuit_row(ev.bus, ev.far_bus, ev.circuit)
    elif isinstance(ev, (LineTrip, LineClose)):
        case.circuit_row(ev.from_bus, ev.to_bus, ev.circuit)
    elif isinstance(ev, LoadStep):
        case.bus_index(ev.bus)
    elif isinstance(ev, (GeneratorTrip, VrefStep, PrefStep, Playback)):
        case.machine_index(ev.machine)
    elif isinstance(ev, MotorSwitch):
        case.motor_index(ev.motor)
    elif isinstance(ev, ConverterTrip):
        case.converter_index(ev.converter)


#: largest VREF step, pu: the reference is the terminal voltage's set point, about 1 pu,
#: which a step of 1 pu doubles or takes to 0, far outside the 0.9-1.1 pu a terminal runs
#: at; every exciter's output reaches its ceiling or floor well before (on Kundur a step
#: of +1e9 pu holds machine 1's field at its ceiling, 5 pu, as +0.3 pu does), so a larger
#: step does nothing more
VREF_STEP_MAX = 1.0

#: why each step is bounded, completing "beyond BOUND pu, "
_WHY = {
    "LoadStep": "the largest of the case's total load, its machines' and converters' total "
    "rating and the 1 pu base: a step of more than the whole system is no load its machines "
    "could pick up, a constant impedance that large pulls the bus down as a fault does (a "
    "Fault through r + jx models that)",
    "VrefStep": "the terminal voltage's set point (about 1 pu) doubled or taken to 0: every "
    "exciter is at its ceiling or floor well before, a larger step does nothing more",
    "PrefStep": "the larger of the machine's rating (1 pu) and its governor's maximum power "
    "order (tg_con Tmax): the governor holds its power order within its limits, so a larger "
    "step cannot move the turbine further",
}


def step_limit(case: Case, ev) -> float:
    """The largest size a step event may have in ``case``.

    A `LoadStep`'s ``abs(P + jQ)`` (pu, system base) at most the largest of the case's
    total load ``abs(sum(pload) + j sum(qload))``, its machines' and converters' total
    rating (their MVA over the base) and 1 pu: a step of more than the whole system is no
    load change the machines could pick up but a collapse (a constant impedance that large
    holds the bus down as a fault does; Kundur: 36 pu, its four 900 MVA machines).  A
    `VrefStep`'s ``abs(dV)`` at most :data:`VREF_STEP_MAX` (1 pu: the set point doubled or
    taken to 0, every exciter at its ceiling or floor well before).  A `PrefStep`'s
    ``abs(dP)`` (machine base) at most the larger of 1 pu (the machine's rating, the whole
    way from no load to full load) and its governor's maximum power order (tg_con Tmax):
    the governor keeps its order within its limits, a larger step moves nothing further.

    Parameters
    ----------
    case : Case
        The case.
    ev : LoadStep, VrefStep or PrefStep
        The step (another event: no limit).

    Returns
    -------
    float
        The bound, pu (inf for an event that is no step).
    """
    if isinstance(ev, LoadStep):
        load = abs(complex(np.sum(case.buses.pload), np.sum(case.buses.qload)))
        rating = (np.sum(case.machines.mva) + np.sum(case.converters.mva)) / case.base_mva
        return float(max(load, rating, 1.0))
    if isinstance(ev, VrefStep):
        return VREF_STEP_MAX
    if isinstance(ev, PrefStep):
        own = np.asarray(case.governors.machine, int) == ev.machine
        return float(max([1.0, *np.abs(np.asarray(case.governors.Tmax, float)[own])]))
    return math.inf


def _amount(ev) -> complex | float:
    """What a step event adds, pu: a load's P + jQ, a VREF step's dV, a PREF step's dP
    (its magnitude is `step_limit`'s measure)."""
    if isinstance(ev, LoadStep):
        return complex(ev.P, ev.Q)
    return ev.dV if isinstance(ev, VrefStep) else ev.dP


def check_values(case: Case, ev) -> None:
    """Check the size of a load, VREF or PREF step against its bound in ``case``, and a
    fault's impedance.

    Parameters
    ----------
    case : Case
        The case.
    ev : Fault, LineTrip, LineClose, GeneratorTrip, ConverterTrip, LoadStep, VrefStep, PrefStep, \
MotorSwitch or Playback
        The event (only the steps have sizes to check).

    Raises
    ------
    InputError
        A step that is not a finite number or of size 0 (it would do nothing), or one
        beyond `step_limit`: the message names the event, its size, the bound and why; a
        fault's r or x negative or not a finite number (x = inf was no fault at all).
    """
    if isinstance(ev, Fault):
        if not all(math.isfinite(v) and v >= 0 for v in (ev.r, ev.x)):
            raise InputError(
                f"{ev}: fault impedance r = {ev.r:g}, x = {ev.x:g} pu: each must be a finite "
                "number >= 0 (r = x = 0: a bolted fault)"
            )
        return
    if not isinstance(ev, (LoadStep, VrefStep, PrefStep)):
        return
    size, limit = abs(_amount(ev)), step_limit(case, ev)
    if not math.isfinite(size):  # a NaN step ran on into a "voltage collapse"
        raise InputError(f"{ev}: a step that is not a finite number")
    if size == 0:
        raise InputError(f"{ev}: a step of 0 would do nothing")
    if size > limit:
        mva = f" ({size * case.base_mva:g} MVA)" if isinstance(ev, LoadStep) else ""
        raise InputError(
            f"{ev}: {size:g} pu{mva} is beyond {limit:g} pu, {_WHY[type(ev).__name__]}"
        )


def check_event(case: Case, ev) -> None:
    """Check one event against ``case``: what it names (`check_names`) and the size of a
    step (`check_values`).

    Parameters
    ----------
    case : Case
        The case.
    ev : Fault, LineTrip, LineClose, GeneratorTrip, ConverterTrip, LoadStep, VrefStep, PrefStep, \
MotorSwitch or Playback
        The event.

    Raises
    ------
    UnknownBusError, CaseError
        As `check_names`.
    InputError
        As `check_values`.
    """
    check_names(case, ev)
    check_values(case, ev)


def check_totals(case: Case, events, labels: Mapping[str, str] | None = None) -> None:
    """Check the running sums of steps that add up against their bounds (`step_limit`):
    each machine's VREF steps, each machine's PREF steps, and the load steps of the whole
    case (as one load added to the system), in time order, those of one instant together.

    Parameters
    ----------
    case : Case
        The case.
    events : iterable
        The run's events (others than steps are passed over).
    labels : Mapping of str to str, optional
        What gave the steps of each kind (``{"VrefStep": "--vref-step"}``), to start the
        message; default none.

    Raises
    ------
    InputError
        A running sum beyond its bound: the message names the machine (or the load
        steps), the sum, the time, the bound and why.
    """
    sums: dict = {}
    steps = sorted(
        (ev for ev in events if isinstance(ev, (LoadStep, VrefStep, PrefStep))),
        key=lambda ev: ev.t,
    )
    for k, ev in enumerate(steps):
        kind = type(ev).__name__
        key = (kind, None if isinstance(ev, LoadStep) else ev.machine)
        sums[key] = sums.get(key, 0) + _amount(ev)
        if k + 1 < len(steps) and steps[k + 1].t == ev.t:
            continue  # the instant's other steps first
        for (kind_, machine), total in sums.items():
            limit = step_limit(case, _STEP_OF[kind_](machine))
            if abs(total) > limit:
                what = (
                    "the load steps"
                    if machine is None
                    else f"the {kind_[:4].upper()} steps of machine {machine}"
                )
                given = (labels or {}).get(kind_)
                raise InputError(
                    ("" if given is None else f"{given}: ")
                    + f"{what} add up to {_signed(total)} pu at {ev.t:g} s, beyond "
                    f"{limit:g} pu, {_WHY[kind_]}"
                )


#: a step of each kind for `step_limit` (its machine the only field that counts)
_STEP_OF = {
    "LoadStep": lambda machine: LoadStep(0, 0.0, 0.0),
    "VrefStep": lambda machine: VrefStep(machine, 0.0, 0.0),
    "PrefStep": lambda machine: PrefStep(machine, 0.0, 0.0),
}


def _signed(value) -> str:
    """A sum of steps in words: ``+1.5`` or, a load, ``2+0.5j``."""
    return f"{value.real:g}{value.imag:+g}j" if isinstance(value, complex) else f"{value:+g}"


def check_case_events(case: Case) -> None:
    """Check a case's own events (`Case.events`): the buses, lines, machines and motors
    they name (`check_names`), the size of each step (`check_values`) and their running
    sums (`check_totals`).

    Parameters
    ----------
    case : Case
        The case.

    Raises
    ------
    CaseError
        An event naming what the case lacks (UnknownBusError for a bus), or a step of 0 or
        beyond its bound: the message names the record (``events[k]`` with its
        ``source``), the event in words and what is wrong; steps adding up beyond a bound:
        the steps, the sum and the bound.
    """
    events = events_of_records(case.events)
    for k, (ev, rec) in enumerate(zip(events, case.events)):
        try:
            check_event(case, ev)
        except (CaseError, InputError) as exc:
            where = f"events[{k}] ({rec.get('source', 'no source')})"
            cls = type(exc) if isinstance(exc, CaseError) else CaseError
            text = str(exc) if str(exc).startswith(str(ev)) else f"{ev}: {exc}"
            raise cls(f"{where}: {text}") from None
    try:
        check_totals(case, events)
    except InputError as exc:
        raise CaseError(f"events: {exc}") from None


#: what a value of each field annotation of the event classes must be
_KIND_TEXT = {
    "int": "an integer",
    "int | None": "an integer or null",
    "float": "a finite number",
    "float | None": "a finite number or null",
    "bool": "true or false",
}


def _fits(annotation: str, value) -> bool:
    """Whether ``value`` (as read from JSON, or a numpy scalar as an importer makes it)
    is of the kind ``annotation`` names."""
    if value is None or isinstance(value, (bool, np.bool_)):
        return ("None" in annotation) if value is None else annotation == "bool"
    if not isinstance(value, Real) or not math.isfinite(value):
        return False
    return "float" in annotation or float(value).is_integer()


def _after(dt: float) -> str:
    """A fault's duration dt (s) in ms for its description: one decimal (100.0), and
    three significant digits below 0.1 ms (0.0167), which one decimal showed as 0.0."""
    ms = 1000 * dt
    return f"{ms:.1f}" if ms >= 0.1 or ms == 0 else f"{ms:.3g}"


def _ms(t: float) -> str:
    """A time in s to the ms, without trailing zeros (1.18333 -> 1.183, 1.35 -> 1.35)."""
    return f"{t:.3f}".rstrip("0").rstrip(".")
