"""Energy-storage devices (ESDs), fleets and their packing for the compiled loop (paper
Section 5).

An ESD at a bus is a real-power sink/source P in [-Pmax, +Pmax] (pu on the system base,
+ absorbs, as the paper), drawn at its bus in the network solution.  Ideal (instant) by
default; optionally a first-order lag, a ramp limit and an energy (state-of-charge) range.
The control laws a fleet shares are in `stabctl.storage.control` (re-exported here).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from stabctl._jitcache import njit
from stabctl.case import Case
from stabctl.errors import CaseError, InputError
from stabctl.storage.control import NO_LAW, NO_STORAGE, BangBangCOI, ControlLaw


#: largest storage rating of `uniform_fleet`, % of the machine's MVA (a device larger than
#: its generator is outside the paper's use and its control law)
MAX_ESD_PCT = 100.0


@dataclass(frozen=True)
class StorageDevice:
    """One ESD.

    Attributes:
        bus: bus number where it connects.
        machine: number of the generator whose relative speed drives it (None: a device
            commanded from outside, e.g. an ambient load fluctuation, `stabctl.estimation.ambient`).
        pmax_mw: rating (MW), > 0.
        lag_s: first-order power lag (s), 0 = ideal.
        ramp_mw_s: ramp limit (MW/s), inf = none.
        energy_mj: usable energy (MJ), inf = unlimited; soc0: initial state of charge (0..1).
    """

    bus: int
    machine: int | None
    pmax_mw: float
    lag_s: float = 0.0
    ramp_mw_s: float = float("inf")
    energy_mj: float = float("inf")
    soc0: float = 0.5

    def __post_init__(self):
        if not self.pmax_mw > 0:
            raise InputError(f"storage at bus {self.bus}: rating must be > 0 MW, got {self.pmax_mw}")
        if self.lag_s < 0 or self.ramp_mw_s <= 0 or self.energy_mj <= 0 or not 0 <= self.soc0 <= 1:
            raise InputError(f"storage at bus {self.bus}: lag >= 0, ramp > 0, energy > 0 and "
                             "0 <= soc0 <= 1 are required")


@dataclass(frozen=True)
class StorageFleet:
    """Devices and the controller they share."""

    devices: tuple = ()
    controller: ControlLaw = field(default_factory=BangBangCOI)

    @property
    def buses(self) -> list[int]:
        return [d.bus for d in self.devices]


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


def uniform_fleet(case: Case, pct: float, controller=None, at: str = "hv") -> StorageFleet:
    """An ESD of pct % of each generator's MVA at its HV bus (at="hv") or terminal bus.

    Raises InputError for a non-positive percentage.
    """
    if not 0 < pct <= MAX_ESD_PCT:
        raise InputError(f"storage rating must be in (0, {MAX_ESD_PCT:g}] % of machine MVA, "
                         f"got {pct}")
    devs = []
    for num, bus, mva in zip(case.machines.number, case.machines.bus, case.machines.mva):
        b = hv_bus(case, int(num)) if at == "hv" else int(bus)
        devs.append(StorageDevice(bus=b, machine=int(num), pmax_mw=pct / 100.0 * mva))
    return StorageFleet(tuple(devs), controller or BangBangCOI())


class StorageArrays(NamedTuple):
    """Fleet packed for the compiled loop (n_dev entries each; system-base pu, s)."""

    pos: np.ndarray       # index of the device bus among the kept buses
    bus: np.ndarray       # bus index (for its voltage)
    mac: np.ndarray       # machine index (-1: none)
    pmax: np.ndarray
    lag: np.ndarray
    ramp: np.ndarray      # pu/s
    emax: np.ndarray      # pu*s
    e0: np.ndarray        # pu*s
    kind: int             # law kind (stabctl.storage.control: NO_STORAGE, BANG_BANG, ...)
    db: float             # deadband, pu speed
    hyst: float           # hysteresis, pu speed
    vgate: float
    rest: bool
    Kv: float             # pu per pu speed
    Ka: float             # pu per pu speed per s


def pack(fleet: StorageFleet | None, case: Case, nc_idx: np.ndarray) -> StorageArrays:
    """Pack a fleet for the kernels; nc_idx are the kept buses of the dynamic model.

    Raises CaseError when a device bus is not kept (build the Simulator with the fleet's
    buses as injection buses) or names an unknown machine.
    """
    base, f0 = case.base_mva, case.freq_hz
    devs = () if fleet is None else fleet.devices
    bus = np.array([case.bus_index(d.bus) for d in devs], np.int64)
    pos = np.array([int(np.nonzero(nc_idx == b)[0][0]) if np.any(nc_idx == b) else -1
                    for b in bus], np.int64)
    if np.any(pos < 0):
        raise CaseError(f"storage bus {devs[int(np.argmin(pos))].bus} is not kept in the "
                        "reduced network: pass the fleet to the Simulator")
    f = lambda attr: np.array([getattr(d, attr) for d in devs], float)  # noqa: E731
    law = NO_LAW if fleet is None else fleet.controller.packed(f0)
    return StorageArrays(
        pos=pos, bus=bus, mac=np.array([-1 if d.machine is None else case.machine_index(d.machine)
                                        for d in devs], np.int64),
        pmax=f("pmax_mw") / base, lag=f("lag_s"), ramp=f("ramp_mw_s") / base,
        emax=f("energy_mj") / base,
        e0=np.where(np.isfinite(f("energy_mj")), f("soc0") * f("energy_mj"), 0.0) / base,
        kind=law.kind if devs else NO_STORAGE, db=law.db, hyst=law.hyst, vgate=law.vgate,
        rest=law.rest, Kv=law.Kv, Ka=law.Ka)


# -- compiled device kernel (used by stabctl.dynamics.simulation.integrate) -------------------

@njit(cache=True)
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
