"""Energy-storage devices (ESDs) and their controllers (paper Section 5, Table 3).

An ESD at a bus is a real-power sink/source P in [-Pmax, +Pmax] (pu on the system base,
+ absorbs, as the paper), drawn at its bus in the network solution.  Ideal (instant) by
default; optionally a first-order lag, a ramp limit and an energy (state-of-charge) range.

Controllers:
- `BangBangCOI`, the paper's: each device watches its own generator's speed relative to the
  centre of inertia (eq. 40, inertia-weighted, of the whole system or of the rest of it):
  absorb +Pmax above the deadband (100 mHz), inject -Pmax below minus the deadband, nothing
  inside; only while its bus voltage is at least the gate (0.8 pu).  Optional hysteresis:
  a device switches off only when the relative speed is back inside deadband - hysteresis.
- `LinearFeedback`, the Section 3 laws in multi-machine form: P = Kv (omega_i - omega_COI)
  + Ka d(omega_i - omega_COI)/dt (rad/s and rad/s^2 of electrical speed), clipped to
  +-Pmax; the acceleration is the one of the latest evaluation (the algebraic loop is
  broken by one stage).

Switching instants of the bang-bang law are located inside the step (linear interpolation
of the switching function between the step ends) and the step is re-integrated in two
parts (`stabctl.dynamics.simulation.integrate`); the number of switchings per device is reported.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from stabctl.case import Case
from stabctl.errors import CaseError, InputError


#: largest storage rating of `uniform_fleet`, % of the machine's MVA (a device larger than
#: its generator is outside the paper's use and its control law)
MAX_ESD_PCT = 100.0
#: largest voltage gate of the bang-bang law (pu)
MAX_V_GATE_PU = 2.0


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
class BangBangCOI:
    """The paper's controller (Table 3); see the module docstring.

    deadband_hz: |f_i - f_COI| below which the device is idle (Hz); v_gate_pu: minimum bus
    voltage for the device to act; coi: "system" (eq. 40 over all machines) or "rest"
    (excluding the device's own machine); hysteresis_hz: switch-off margin inside the band.
    """

    deadband_hz: float = 0.1
    v_gate_pu: float = 0.8
    coi: str = "system"
    hysteresis_hz: float = 0.0

    def __post_init__(self):
        if self.coi not in ("system", "rest"):
            raise InputError(f"coi must be 'system' or 'rest', got {self.coi!r}")
        if not (0 <= self.deadband_hz < float("inf")
                and 0 <= self.hysteresis_hz <= self.deadband_hz):
            raise InputError("need deadband >= 0 and 0 <= hysteresis <= deadband (finite, Hz)")
        if not 0 <= self.v_gate_pu <= MAX_V_GATE_PU:
            raise InputError(f"voltage gate must be in [0, {MAX_V_GATE_PU:g}] pu, got "
                             f"{self.v_gate_pu}")


@dataclass(frozen=True)
class LinearFeedback:
    """Section 3 laws for many machines: P = Kv * dw + Ka * d(dw)/dt, clipped to +-Pmax.

    Kv in pu per rad/s, Ka in pu per rad/s^2, dw = omega_i - omega_COI in electrical rad/s.
    """

    Kv: float = 0.0
    Ka: float = 0.0
    coi: str = "system"
    v_gate_pu: float = 0.0


@dataclass(frozen=True)
class StorageFleet:
    """Devices and the controller they share."""

    devices: tuple = ()
    controller: object = field(default_factory=BangBangCOI)

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
    kind: int             # 0 none, 1 bang-bang, 2 linear
    db: float             # deadband, pu speed
    hyst: float           # hysteresis, pu speed
    vgate: float
    rest: bool
    Kv: float             # pu per pu speed
    Ka: float             # pu per pu speed per s


NO_STORAGE, BANG_BANG, LINEAR, EXTERNAL = 0, 1, 2, 3


@dataclass(frozen=True)
class ExternalCommands:
    """Devices commanded from outside the simulation (estimator in the loop): their
    set-points in units of the rating (Table 3 modes -1 inject, 0 idle, +1 absorb; other
    values for a scaled power such as an ambient load deviation) come from
    `Simulator.run_commanded` at measurement-frame arrival times; the voltage gate
    (v_gate_pu, the same for every device of the fleet) still applies."""

    v_gate_pu: float = 0.8


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
    ctrl = None if fleet is None else fleet.controller
    kind = NO_STORAGE if not devs else (BANG_BANG if isinstance(ctrl, BangBangCOI) else
                                        EXTERNAL if isinstance(ctrl, ExternalCommands) else LINEAR)
    ws = 2 * np.pi * f0
    return StorageArrays(
        pos=pos, bus=bus, mac=np.array([-1 if d.machine is None else case.machine_index(d.machine)
                                        for d in devs], np.int64),
        pmax=f("pmax_mw") / base, lag=f("lag_s"), ramp=f("ramp_mw_s") / base,
        emax=f("energy_mj") / base,
        e0=np.where(np.isfinite(f("energy_mj")), f("soc0") * f("energy_mj"), 0.0) / base, kind=kind,
        db=getattr(ctrl, "deadband_hz", 0.0) / f0, hyst=getattr(ctrl, "hysteresis_hz", 0.0) / f0,
        vgate=getattr(ctrl, "v_gate_pu", 0.0), rest=getattr(ctrl, "coi", "system") == "rest",
        Kv=getattr(ctrl, "Kv", 0.0) * ws, Ka=getattr(ctrl, "Ka", 0.0) * ws)


# -- compiled controller kernels (used by stabctl.dynamics.simulation.integrate) -------------------
from stabctl._jitcache import njit  # noqa: E402


@njit(cache=True)
def relative_speeds(x, nm, inertia, sa, out):
    """omega_i - omega_COI (pu) of each device's machine: COI of all machines (eq. 40) or of
    the rest of the system (sa.rest); 0 for a device without a machine."""
    M = inertia.sum()
    coi = (x[nm:2 * nm] * inertia).sum() / M
    for d in range(sa.mac.size):
        i = sa.mac[d]
        w = x[nm + i]
        if i < 0:
            out[d] = 0.0
        elif sa.rest:
            out[d] = w - (coi * M - w * inertia[i]) / (M - inertia[i])
        else:
            out[d] = w - coi


@njit(cache=True)
def desired_mode(sa, d, mode, r, v):
    """Table 3: +1 absorb above the deadband, -1 inject below, 0 inside or below the voltage
    gate; with hysteresis a running device stops only inside deadband - hysteresis."""
    if v < sa.vgate:
        return 0
    if mode == 1 and r > sa.db - sa.hyst:
        return 1
    if mode == -1 and r < -(sa.db - sa.hyst):
        return -1
    if r > sa.db:
        return 1
    if r < -sa.db:
        return -1
    return 0


@njit(cache=True)
def crossing(sa, mode, want, r_a, r_b, v_a, v_b):
    """Where, as a fraction of the step, a device left `mode` for `want`, and the mode it
    takes there: linear interpolation of the switching function between the step ends
    (the voltage gate if it changed side, else the speed boundary of the transition; a
    jump from +1 to -1 first crosses into 0)."""
    if (v_a >= sa.vgate) != (v_b >= sa.vgate):
        ga, gb = v_a - sa.vgate, v_b - sa.vgate
        new = want
    else:
        if mode == 1:
            thr, new = sa.db - sa.hyst, (0 if want == -1 else want)
        elif mode == -1:
            thr, new = -(sa.db - sa.hyst), (0 if want == 1 else want)
        else:
            thr, new = (sa.db if want == 1 else -sa.db), want
        ga, gb = r_a - thr, r_b - thr
    theta = ga / (ga - gb) if ga != gb else 1.0
    return min(max(theta, 0.0), 1.0), new


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
