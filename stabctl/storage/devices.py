"""Energy-storage devices (ESDs), fleets and their packing for the compiled loop (paper
Section 5).

An ESD at a bus is a real-power sink/source P in [-Pmax, +Pmax] (pu on the system base,
+ absorbs, as the paper), drawn at its bus in the network solution.  Ideal (instant) by
default; optionally a first-order lag, a ramp limit and an energy (state-of-charge) range.
A fleet of model ``"wecc"`` makes each device a WECC battery instead (`battery_case`: a
REGCA1 converter with its REECA1 electrical control in the storage current range and a
REPCA1 plant control, `stabctl.models.converters`, docs/storage.md): the law's power is
then the plant's P reference, and the converter's current limit, lags and voltage logic
decide what reaches the grid.
The control laws a fleet shares are in `stabctl.storage.control` (re-exported by
`stabctl.storage`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.case import Case, require_case
from stabctl.errors import (
    CaseError,
    InputError,
    WrongTypeError,
    advice,
    check_fields,
    require_items,
    require_number,
)
from stabctl.models import converters as conv
from stabctl.storage.control import NO_LAW, NO_STORAGE, BangBangCOI, ControlLaw

#: largest storage rating of `uniform_fleet`, % of the machine's MVA (a device larger than
#: its generator is outside the paper's use and its control law)
MAX_ESD_PCT = 100.0

#: storage device models: "ideal" (the law's power drawn at the bus, `StorageDevice`'s lag,
#: ramp and energy applied) or "wecc" (a WECC battery taking the law's power as its plant
#: reference, `battery_case`)
ESD_MODELS = ("ideal", "wecc")


def model_inputs(esd_model: str) -> dict:
    """A parallel job's inputs naming the devices' model (`StorageFleet.model`): none for
    "ideal", so that the default's jobs, keys and records stay as they were, and
    ``{"esd_model": model}`` otherwise (the workers build their fleet of that model).

    Parameters
    ----------
    esd_model : {"ideal", "wecc"}

    Returns
    -------
    dict
    """
    return {} if esd_model == "ideal" else {"esd_model": esd_model}


#: a WECC battery's converter row (ibr_con fields, `stabctl.models.converters.CONVERTER`)
#: where it differs from the table's defaults (ANDES 2.0's): a REGCA1 (converter lag Tg
#: 0.02 s) with a REECA1 in the storage current range (Ip in [-Ipmax, Ipmax], P order in
#: [-1, 1] of its rating, active-current priority, apparent current limit Imax 1 pu of
#: its rating) and a REPCA1 plant control without a monitored line whose P path passes
#: its reference straight on (Fflag 1, PLflag 1, proportional gain 1, no integral, no
#: frequency droop, error limits open, output [-1, 1]); its voltage control (Q path) and
#: the REECA1's dip logic (frozen below Vdip 0.8 pu, reactive current Kqv per pu voltage
#: error) are ANDES's defaults.  Idle at the operating point (pfrac = qfrac = 0: P0 = Q0
#: = 0).  Device base: the device's rating, MVA = MW.
WECC_BATTERY: dict[str, float] = {
    "type": float(conv.REGCA1),
    "pfrac": 0.0,
    "qfrac": 0.0,
    "pqflag": 1.0,
    "Tg": 0.02,
    "reec": float(conv.REECA1),
    "storage": 1.0,
    "PMAX": 1.0,
    "PMIN": -1.0,
    "Imax": 1.0,
    "repc": float(conv.REPCA1),
    "pc_Fflag": 1.0,
    "pc_PLflag": 1.0,
    "pc_Kpg": 1.0,
    "pc_Kig": 0.0,
    "pc_Ddn": 0.0,
    "pc_Dup": 0.0,
    "pc_femax": 999.0,
    "pc_femin": -999.0,
    "pc_Pmax": 1.0,
    "pc_Pmin": -1.0,
}


#: the largest storage rating a device may have, MW (100 GW)
MAX_DEVICE_MW = 1e5


@dataclass(frozen=True)
class StorageDevice:
    """One energy-storage device (paper Section 5): a real-power sink/source at a bus,
    P in [-Pmax, +Pmax] (+ absorbs), ideal (instant) unless a lag, a ramp limit or a finite
    energy is given.  Converted to pu on the system base when packed for a run.

    Attributes
    ----------
    bus : int
        Bus number (as in the data) where it connects.
    machine : int or None
        Number of the generator whose speed relative to the COI drives it; None: a device
        commanded from outside (`stabctl.storage.control.ExternalCommands`, e.g. an
        ambient load fluctuation, `stabctl.estimation.ambient`).
    pmax_mw : float
        Rating, MW, > 0.
    lag_s : float, optional
        First-order power lag time constant, s, >= 0; 0 (default) = ideal.
    ramp_mw_s : float, optional
        Ramp limit, MW/s, > 0; inf (default) = none.
    energy_mj : float, optional
        Usable energy, MJ, > 0; inf (default) = unlimited.  A full device does not absorb,
        an empty one does not inject.
    soc0 : float, optional
        Initial state of charge, fraction of `energy_mj` in [0, 1]; default 0.5.

    Raises
    ------
    InputError
        A rating that is not > 0 or is above MAX_DEVICE_MW, a negative lag, a ramp limit or
        energy that is not > 0, or soc0 outside [0, 1].
    WrongTypeError
        A field of another type (a bus given as text, a rating as a bool).
    """

    bus: int
    machine: int | None
    pmax_mw: float
    lag_s: float = 0.0
    ramp_mw_s: float = float("inf")
    energy_mj: float = float("inf")
    soc0: float = 0.5

    def __post_init__(self):
        check_fields(self)
        if not 0 < self.pmax_mw < float("inf"):
            raise InputError(
                f"storage at bus {self.bus}: rating must be a finite number > 0 MW, got "
                f"{self.pmax_mw}"
            )
        if self.pmax_mw > MAX_DEVICE_MW:  # (round 45: 1e308 MW ran "stable", moving 0 MJ)
            raise InputError(
                f"storage at bus {self.bus}: rating {self.pmax_mw:g} MW is above "
                f"{MAX_DEVICE_MW:g} MW, more than any plant of a planning case (the largest "
                "power station is about 22 GW): no device is that large"
            )
        if not (
            self.lag_s >= 0 and self.ramp_mw_s > 0 and self.energy_mj > 0 and 0 <= self.soc0 <= 1
        ):  # NaN is none of these (a NaN lag was taken)
            raise InputError(
                f"storage at bus {self.bus}: lag >= 0, ramp > 0, energy > 0 and "
                "0 <= soc0 <= 1 are required"
            )


@dataclass(frozen=True)
class StorageFleet:
    """Storage devices and the control law they share.

    Attributes
    ----------
    devices : tuple of StorageDevice, optional
        The devices, numbered 1, 2, ... in this order in the results; default none.
    controller : ControlLaw, optional
        The law driving every device (`stabctl.storage.control`: `BangBangCOI`, the
        paper's, by default; `LinearFeedback`; `ExternalCommands` for
        `Simulator.run_commanded`).
    model : {"ideal", "wecc"}, optional
        ``"ideal"`` (default): each device draws the law's power at its bus (with its
        lag, ramp and energy); ``"wecc"``: each device is a WECC battery whose plant
        takes the law's power as its P reference (`battery_case`; the devices' lag and
        ramp are then the converter's, and their energy its state of charge, WECC REEC_C).
    battery : dict, optional
        ibr_con fields of the WECC batteries replacing `WECC_BATTERY`'s or the table's
        defaults (e.g. ``{"Imax": 1.2}``); only with model "wecc".
    machines_at : tuple of (int, int), optional
        (machine number, terminal bus) of the devices' machines in the case the fleet was
        built for (`uniform_fleet` sets it); a run on a case whose machines sit elsewhere
        is refused (`pack`).  Default none: not checked.

    Raises
    ------
    InputError
        An unknown model, a battery field that is not an ibr_con field, or battery fields
        with model "ideal".
    WrongTypeError
        `devices` not a list of `StorageDevice`, `controller` no control law, `battery`
        no dict.
    """

    devices: tuple = ()
    controller: ControlLaw = field(default_factory=BangBangCOI)
    model: str = "ideal"
    battery: dict = field(default_factory=dict)
    machines_at: tuple = field(default=(), compare=False)

    def __post_init__(self):
        devices = require_items(self.devices, "StorageFleet(devices)", "a list of StorageDevice")
        odd = [d for d in devices if not isinstance(d, StorageDevice)]
        if odd:
            raise WrongTypeError(
                f"StorageFleet(devices): each a StorageDevice (StorageDevice(bus, machine, "
                f"pmax_mw)), got {odd[0]!r} ({type(odd[0]).__name__})"
            )
        object.__setattr__(self, "devices", tuple(devices))
        _require_law(self.controller, "StorageFleet(controller)")
        if not isinstance(self.battery, Mapping):
            raise WrongTypeError(
                f"StorageFleet(battery): a dict of ibr_con fields, got {self.battery!r}"
            )
        if self.model not in ESD_MODELS:
            raise InputError(
                f"storage model must be one of {', '.join(ESD_MODELS)}, got {self.model!r}"
            )
        unknown = sorted(set(self.battery) - set(conv.CONVERTER.names))
        if unknown:
            raise InputError(f"WECC battery: {', '.join(unknown)} not ibr_con fields")
        if self.battery and self.model != "wecc":
            raise InputError("battery fields are for storage model 'wecc' only")

    @property
    def buses(self) -> list[int]:
        """Bus numbers of the devices, in device order (kept in the reduced network)."""
        return [d.bus for d in self.devices]


def _require_law(law, name: str) -> None:
    """WrongTypeError naming `name` unless `law` is a control law (it packs its constants:
    `stabctl.storage.control.ControlLaw`)."""
    if not callable(getattr(law, "packed", None)):
        raise WrongTypeError(
            f"{name}: a control law (BangBangCOI(), LinearFeedback(), ExternalCommands()) is "
            f"needed, got {law!r}"
        )


def hv_bus(case: Case, machine: int) -> int:
    """High-voltage bus of a generator: the neighbour of its terminal bus (through a
    branch) with the highest rated kV; the terminal bus itself if none is higher.

    Raises CaseError for an unknown machine.
    """
    i = case.machine_index(machine)
    term = int(case.machines.bus[i])
    br = case.branches
    nbrs = np.concatenate([br.to_bus[br.from_bus == term], br.from_bus[br.to_bus == term]])
    if nbrs.size == 0:
        return term
    kv = case.buses.kv[case.bus_indices(nbrs)]
    best = int(nbrs[int(np.argmax(kv))])
    return best if kv.max() > case.buses.kv[case.bus_index(term)] else term


def battery_case(case: Case, fleet: StorageFleet) -> tuple[Case, np.ndarray]:
    """The case with each device of a "wecc" fleet as a WECC battery: a converter row per
    device at its bus, rated its MW (MVA), its energy and initial state of charge as the
    battery's (En, SOCinit: WECC REEC_C's state of charge, which stops discharging empty
    and charging full), the fields of `WECC_BATTERY` and the fleet's ``battery``
    overrides, numbered after the case's converters.

    Parameters
    ----------
    case : Case
        The case the fleet runs on.
    fleet : StorageFleet
        Its devices (model "wecc").

    Returns
    -------
    tuple of (Case, ndarray of int, shape (n_dev,))
        The case with the batteries' rows appended, and each device's row in its
        converter table.

    Raises
    ------
    CaseError
        A battery field out of its range (`stabctl.models.converters.CONVERTER`), naming
        the row and field.
    """
    t = case.converters
    n0 = len(t)
    first = int(t.number.max()) + 1 if n0 else 1
    fields = {**WECC_BATTERY, **fleet.battery}
    rows = []
    for j, d in enumerate(fleet.devices):
        row = {
            "number": first + j,
            "bus": d.bus,
            "mva": d.pmax_mw,
            "En": d.energy_mj / 3600.0 if math.isfinite(d.energy_mj) else 0.0,  # MWh; 0: none
            "SOCinit": d.soc0,
            **fields,
        }
        rows.append([row.get(c, type(t).DEFAULTS.get(c, 0.0)) for c in t.columns()])
    table = type(t).from_matrix(np.vstack([t.matrix(), np.array(rows, float)]))
    return case.replace(converters=table), np.arange(n0, n0 + len(rows))


def uniform_fleet(
    case: Case, pct: float, controller=None, at: str = "hv", model: str = "ideal"
) -> StorageFleet:
    """One ideal ESD per generator, rated pct % of the generator's MVA, at its HV
    bus or its terminal bus; none for an infinite bus (H = 0: PSS/E's GENCLS holding the
    rest of the system, no site: `stabctl.case.Case.infinite_buses`, as
    `stabctl.placement.program.candidate_sites`).

    Parameters
    ----------
    case : Case
        The case; one device per row of its machine table, in that order, but its
        infinite buses.
    pct : float
        Rating of each device, % of its generator's MVA rating, in (0, MAX_ESD_PCT] (100).
    controller : ControlLaw or None, optional
        The fleet's control law; None (default): `BangBangCOI()` (paper Table 3).
    at : str, optional
        ``"hv"`` (default): the generator's high-voltage bus (`hv_bus`: the neighbour of
        its terminal bus with the highest rated kV); ``"terminal"``: the terminal bus.
    model : {"ideal", "wecc"}, optional
        The devices' model (`StorageFleet.model`); default "ideal".

    Returns
    -------
    StorageFleet
        Devices driven by their own generator's speed, unlimited energy, no lag or ramp
        limit.

    Raises
    ------
    InputError
        `pct` not in (0, MAX_ESD_PCT], an unknown model, or `at` neither "hv" nor
        "terminal".
    TypeError
        `case` is not a `Case`, `pct` not a number, or `controller` no control law
        (`stabctl.errors.WrongTypeError`).

    Examples
    --------
    The paper's 5 % fleet on Kundur's system (900 MVA machines, HV buses 10, 20, 110,
    120):

    >>> import stabctl
    >>> fleet = stabctl.uniform_fleet(stabctl.load_case("kundur"), 5)
    >>> [(d.bus, d.machine, float(d.pmax_mw)) for d in fleet.devices]
    [(10, 1, 45.0), (20, 2, 45.0), (110, 3, 45.0), (120, 4, 45.0)]
    """
    case = require_case(case, "uniform_fleet(case)")
    if controller is not None:
        _require_law(controller, "uniform_fleet(controller)")
    pct = require_number(pct, "uniform_fleet(pct)", "%")
    if not 0 < pct <= MAX_ESD_PCT:
        raise InputError(
            f"{advice('uniform_fleet(pct)', '--esd-pct')}: storage rating must be in (0, "
            f"{MAX_ESD_PCT:g}] % of machine MVA, got {pct}"
        )
    if at not in ("hv", "terminal"):
        raise InputError(f"uniform_fleet(at) must be 'hv' or 'terminal', got {at!r}")
    devs, sites = [], []
    infinite = case.infinite_buses()  # the rest of the system: no site
    for num, bus, mva in zip(case.machines.number, case.machines.bus, case.machines.mva):
        if int(num) in infinite:
            continue
        b = hv_bus(case, int(num)) if at == "hv" else int(bus)  # `at` checked above
        devs.append(StorageDevice(bus=b, machine=int(num), pmax_mw=pct / 100.0 * mva))
        sites.append((int(num), int(bus)))
    return StorageFleet(
        tuple(devs), controller or BangBangCOI(), model=model, machines_at=tuple(sites)
    )


def energy_excursion(t, p_mw) -> dict:
    """Energy a device moves along one run, from its power trajectory.

    Parameters
    ----------
    t : array_like, shape (n_t,)
        Time, s (increasing).
    p_mw : array_like, shape (n_t,)
        Device power, MW, + absorbing (the paper's sign; `SimulationResult.pesd` times the
        system base).  A mode trajectory (+1, 0, -1) gives the figures per MW of rating.

    Returns
    -------
    dict
        ``absorbed_mj`` and ``delivered_mj`` (>= 0): the integrals of the positive and
        negative parts of the power; ``soc_high_mj`` (>= 0) and ``soc_low_mj`` (<= 0):
        the highest and lowest stored energy relative to the start (the running integral
        of the power, trapezoid rule, over the samples given); ``need_mwh``:
        the usable energy of a device started half full (`StorageDevice.soc0` = 0.5) that
        never reaches either end, 2 max(soc_high, -soc_low) / 3600.

    Notes
    -----
    For a simulated device, `SimulationResult.meta["storage"]` holds these figures
    integrated between its located switchings; from power sampled on the grid, a step
    containing a switching is averaged across it (an error up to half a step at full power
    per switching).

    A device whose usable energy exceeds ``need_mwh`` (and starts half full) follows
    exactly the unlimited trajectory: the simulator only clips absorption when full and
    injection when empty (`device_power`).
    """
    t = np.asarray(t, float)
    p = np.asarray(p_mw, float)
    dt = np.diff(t)
    mid = 0.5 * (p[1:] + p[:-1])
    e = np.concatenate([[0.0], np.cumsum(mid * dt)])
    pos = 0.5 * (np.maximum(p[1:], 0) + np.maximum(p[:-1], 0))
    neg = 0.5 * (np.maximum(-p[1:], 0) + np.maximum(-p[:-1], 0))
    high, low = float(e.max()), float(e.min())
    return {
        "absorbed_mj": float(pos @ dt),
        "delivered_mj": float(neg @ dt),
        "soc_high_mj": high,
        "soc_low_mj": low,
        "need_mwh": 2 * max(high, -low) / 3600.0,
    }


class StorageArrays(NamedTuple):
    """Fleet packed for the compiled loop (n_dev entries each; system-base pu, s)."""

    pos: np.ndarray  # index of the device bus among the kept buses
    xslot: np.ndarray  # a WECC battery's plant-reference slot in the flat state (-1: ideal)
    bus: np.ndarray  # bus index (for its voltage)
    mac: np.ndarray  # machine index (-1: none)
    pmax: np.ndarray
    lag: np.ndarray
    ramp: np.ndarray  # pu/s
    emax: np.ndarray  # pu*s
    e0: np.ndarray  # pu*s
    kind: int  # law kind (stabctl.storage.control: NO_STORAGE, BANG_BANG, ...)
    db: float  # deadband, pu speed
    hyst: float  # hysteresis, pu speed
    vgate: float
    rest: bool
    Kv: float  # pu per pu speed
    Ka: float  # pu per pu speed per s
    group: np.ndarray  # (n_mac,) 1 critical, 0 other (coi="critical"); empty otherwise


def pack(fleet: StorageFleet | None, case: Case, nc_idx: np.ndarray, xslot=None) -> StorageArrays:
    """Pack a fleet for the kernels; nc_idx are the kept buses of the dynamic model, xslot
    (n_dev,) the flat state index of each WECC battery's plant P reference
    (`stabctl.models.converters.PLANT_PREF_SLOT` of its converter; None: ideal devices).

    Raises CaseError when a device bus is not kept (build the Simulator with the fleet's
    buses as injection buses), names an unknown machine, or the fleet was built for a
    case whose machines sit elsewhere (`StorageFleet.machines_at`).
    """
    base, f0 = case.base_mva, case.freq_hz
    devs = () if fleet is None else fleet.devices
    for num, at in () if fleet is None else fleet.machines_at:
        here = int(case.machines.bus[case.machine_index(num)])
        if here != at:
            raise CaseError(
                f"storage fleet built for a case whose machine {num} is at bus {at}: case "
                f"'{case.name}' has it at bus {here}; build the fleet from this case "
                "(uniform_fleet(case, pct))"
            )
    bus = np.array([case.bus_index(d.bus) for d in devs], np.int64)
    pos = np.array(
        [int(np.nonzero(nc_idx == b)[0][0]) if np.any(nc_idx == b) else -1 for b in bus], np.int64
    )
    if np.any(pos < 0):
        raise CaseError(
            f"storage bus {devs[int(np.argmin(pos))].bus} is not kept in the "
            "reduced network: pass the fleet to the Simulator"
        )
    f = lambda attr: np.array([getattr(d, attr) for d in devs], float)  # noqa: E731
    law = NO_LAW if fleet is None else fleet.controller.packed(f0)
    return StorageArrays(
        pos=pos,
        xslot=np.full(len(devs), -1, np.int64) if xslot is None else np.asarray(xslot, np.int64),
        bus=bus,
        mac=np.array(
            [-1 if d.machine is None else case.machine_index(d.machine) for d in devs], np.int64
        ),
        pmax=f("pmax_mw") / base,
        lag=f("lag_s"),
        ramp=f("ramp_mw_s") / base,
        # WECC batteries keep their state of charge in the converter (`battery_case`)
        emax=f("energy_mj") / base if xslot is None else np.full(len(devs), np.inf),
        e0=np.where(np.isfinite(f("energy_mj")) & (xslot is None), f("soc0") * f("energy_mj"), 0)
        / base,
        kind=law.kind if devs else NO_STORAGE,
        db=law.db,
        hyst=law.hyst,
        vgate=law.vgate,
        rest=law.rest,
        Kv=law.Kv,
        Ka=law.Ka,
        group=_groups(case, law.critical),
    )


def _groups(case: Case, critical) -> np.ndarray:
    """(n_mac,) int: 1 for the machines numbered in `critical`, 0 for the others; empty
    when `critical` is (no critical group).  Raises CaseError naming an unknown machine."""
    if not critical:
        return np.zeros(0, np.int64)
    out = np.zeros(len(case.machines.number), np.int64)
    out[[case.machine_index(m) for m in critical]] = 1
    return out


# -- compiled device kernel (used by stabctl.dynamics.integrator.integrate) -------------------


@kernel
def device_power(sa, d, target, P, e, h):
    """Device power after h seconds following `target` from P (ideal, lag or ramp), with the
    energy range: no absorption when full, no injection when empty."""
    if sa.lag[d] > 0:
        Pn = target + (P - target) * np.exp(-h / sa.lag[d])
    else:
        Pn = target
    step = sa.ramp[d] * h
    Pn = min(max(Pn, P - step), P + step)
    if np.isfinite(sa.emax[d]) and ((Pn > 0 and e >= sa.emax[d]) or (Pn < 0 and e <= 0)):
        Pn = 0.0
    return Pn
