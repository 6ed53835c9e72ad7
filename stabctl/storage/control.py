"""Control laws of the energy-storage devices (paper Section 5, Table 3; Section 3) and
their compiled kernels.

Every law implements the `ControlLaw` protocol: a `kind` (how `integrate` treats it) and
`packed(f0)`, its constants in the units of the compiled loop (`LawConstants`).  The
fleet packing (`stabctl.storage.devices.pack`) asks the law, never tests its class.

- `BangBangCOI`, the paper's: each device watches its own generator's speed relative to the
  centre of inertia (eq. 40, inertia-weighted, of the whole system or of the rest of it):
  absorb +Pmax above the deadband (100 mHz), inject -Pmax below minus the deadband, nothing
  inside; only while its bus voltage is at least the gate (0.8 pu).  Optional hysteresis:
  a device switches off only when the relative speed is back inside deadband - hysteresis.
  Its option ``coi="critical"`` (not the paper's) takes as reference, instead of the COI,
  the COI of the other group, the groups being SIME's critical machines of a contingency
  and the rest: a device at a critical machine brakes it while it runs ahead of the rest,
  every other device drives its machine after the critical group (and brakes it once it
  runs ahead of that group).
- `LinearFeedback`, the Section 3 laws in multi-machine form: P = Kv (omega_i - omega_COI)
  + Ka d(omega_i - omega_COI)/dt (rad/s and rad/s^2 of electrical speed), clipped to
  +-Pmax; the acceleration is the one of the latest evaluation (the algebraic loop is
  broken by one stage).
- `ExternalCommands`: set-points decided outside the simulation (estimator in the loop).

Switching instants of the bang-bang law are located inside the step (`crossing`, linear
interpolation of the switching function between the step ends) and the step is
re-integrated in two parts (`stabctl.dynamics.integrator.integrate`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, NamedTuple, Protocol, runtime_checkable

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import (
    InputError,
    WrongTypeError,
    advice,
    check_fields,
    is_whole_number,
    require_items,
)

#: largest voltage gate of the bang-bang law (pu)
MAX_V_GATE_PU = 2.0
#: the widest deadband and hysteresis (Hz) a controller takes (the CLI's --deadband-hz
#: range): BangBangCOI(deadband_hz=100), 100 mHz meant, left every device idle
MAX_DEADBAND_HZ = 10.0

#: law kinds of the compiled loop
NO_STORAGE, BANG_BANG, LINEAR, EXTERNAL = 0, 1, 2, 3


class LawConstants(NamedTuple):
    """A control law's constants in the compiled loop's units (`ControlLaw.packed`).

    kind: NO_STORAGE, BANG_BANG, LINEAR or EXTERNAL; db, hyst: deadband and hysteresis
    (pu speed); vgate: voltage gate (pu); rest: COI of the other machines (else of all);
    Kv: pu power per pu speed; Ka: pu power per pu speed per s; critical: machine numbers
    of the critical group (``coi="critical"``; empty for every other law).
    """

    kind: int
    db: float
    hyst: float
    vgate: float
    rest: bool
    Kv: float
    Ka: float
    critical: tuple[int, ...] = ()


#: the constants of no law (a run without storage)
NO_LAW = LawConstants(NO_STORAGE, 0.0, 0.0, 0.0, False, 0.0, 0.0)

#: the reference speeds of `BangBangCOI.coi`
COI_CHOICES = ("system", "rest", "critical")


@runtime_checkable
class ControlLaw(Protocol):
    """What a storage control law tells the compiled loop.

    Attributes
    ----------
    kind : int
        BANG_BANG, LINEAR or EXTERNAL: which branch of `integrate` drives the devices.
    """

    kind: ClassVar[int]

    def packed(self, f0: float) -> LawConstants:
        """The law's constants for the kernels.

        Parameters
        ----------
        f0 : float
            Nominal frequency of the case (Hz), to turn Hz into pu speed.

        Returns
        -------
        LawConstants
        """
        ...


@dataclass(frozen=True)
class BangBangCOI:  # fields of a dataclass: numpydoc ignore=PR02
    """The paper's controller (Table 3); see the module docstring.

    Parameters
    ----------
    deadband_hz : float
        abs(f_i - f_COI) below which the device is idle (Hz), in [0, MAX_DEADBAND_HZ].
    v_gate_pu : float
        Minimum bus voltage for the device to act (pu), in [0, MAX_V_GATE_PU].
    coi : {"system", "rest", "critical"}
        COI of all machines (eq. 40) or of all but the device's own machine; "critical"
        (not the paper's): the COI of the group the device's machine is not in (the
        machines of `critical`, or the others), per island (the island's COI when it
        lacks one of the groups).
    hysteresis_hz : float
        Switch-off margin inside the band (Hz), in [0, deadband_hz].
    critical : tuple of int
        Machine numbers of the critical group (SIME's critical machines of the
        contingency, `stabctl.stability.sime.critical_machines`); required with
        coi="critical", empty otherwise.

    Raises
    ------
    InputError
        Any value outside its range; `critical` empty with coi="critical" or given with
        another coi.
    WrongTypeError
        A field of another type (a text where a number goes, `critical` not machine
        numbers).
    """

    deadband_hz: float = 0.1
    v_gate_pu: float = 0.8
    coi: str = "system"
    hysteresis_hz: float = 0.0
    critical: tuple[int, ...] = ()
    kind: ClassVar[int] = BANG_BANG

    def __post_init__(self):
        check_fields(self)
        if self.coi not in COI_CHOICES:
            raise InputError(f"coi must be one of {COI_CHOICES}, got {self.coi!r}")
        critical = require_items(self.critical, "BangBangCOI(critical)", "machine numbers")
        if (self.coi == "critical") != bool(critical):
            raise InputError(
                "coi='critical' needs the critical machines (critical=(...)), and only it "
                f"takes them: got coi={self.coi!r}, critical={tuple(critical)!r}"
            )
        if not all(is_whole_number(m) for m in critical):
            raise WrongTypeError(f"BangBangCOI(critical): machine numbers, got {critical!r}")
        object.__setattr__(self, "critical", tuple(int(m) for m in critical))
        if not (
            0 <= self.deadband_hz <= MAX_DEADBAND_HZ and 0 <= self.hysteresis_hz <= self.deadband_hz
        ):
            raise InputError(
                f"deadband {self.deadband_hz:g} Hz, hysteresis {self.hysteresis_hz:g} Hz: "
                f"need 0 <= deadband <= {MAX_DEADBAND_HZ:g} Hz (in Hz: 0.1 is 100 mHz) and "
                "0 <= hysteresis <= deadband "
                + advice("(deadband_hz, hysteresis_hz)", "(--deadband-hz, --hysteresis-hz)")
            )
        if not 0 <= self.v_gate_pu <= MAX_V_GATE_PU:
            raise InputError(
                f"voltage gate ({advice('v_gate_pu', '--v-gate')}) must be in "
                f"[0, {MAX_V_GATE_PU:g}] pu, got {self.v_gate_pu}"
            )

    def packed(self, f0: float) -> LawConstants:
        """The law's constants for the kernels.

        Parameters
        ----------
        f0 : float
            Nominal frequency of the case, Hz (> 0), to turn Hz into pu speed.

        Returns
        -------
        LawConstants
            Kind BANG_BANG, deadband and hysteresis in pu speed (`deadband_hz / f0`,
            `hysteresis_hz / f0`), the voltage gate (pu), the COI choice (``rest`` True
            for ``coi="rest"``), gains 0, the critical machines.
        """
        return LawConstants(
            self.kind,
            self.deadband_hz / f0,
            self.hysteresis_hz / f0,
            self.v_gate_pu,
            self.coi == "rest",
            0.0,
            0.0,
            self.critical,
        )


@dataclass(frozen=True)
class LinearFeedback:  # fields of a dataclass: numpydoc ignore=PR02
    """Section 3 laws for many machines: P = Kv * dw + Ka * d(dw)/dt, clipped to +-Pmax.

    Parameters
    ----------
    Kv : float
        Gain in pu power per electrical rad/s of dw = omega_i - omega_COI.
    Ka : float
        Gain in pu power per electrical rad/s^2.
    coi : {"system", "rest"}
        As `BangBangCOI`.
    v_gate_pu : float
        Minimum bus voltage for the device to act (pu).
    """

    Kv: float = 0.0
    Ka: float = 0.0
    coi: str = "system"
    v_gate_pu: float = 0.0
    kind: ClassVar[int] = LINEAR

    def __post_init__(self):
        check_fields(self)

    def packed(self, f0: float) -> LawConstants:
        """Gains per pu speed (times 2 pi f0), the gate, the COI."""
        ws = 2 * np.pi * f0
        return LawConstants(
            self.kind, 0.0, 0.0, self.v_gate_pu, self.coi == "rest", self.Kv * ws, self.Ka * ws
        )


@dataclass(frozen=True)
class ExternalCommands:  # fields of a dataclass: numpydoc ignore=PR02
    """Devices commanded from outside the simulation (estimator in the loop): their
    set-points in units of the rating (Table 3 modes -1 inject, 0 idle, +1 absorb; other
    values for a scaled power such as an ambient load deviation) come from
    `Simulator.run_commanded` at measurement-frame arrival times.

    Parameters
    ----------
    v_gate_pu : float
        Voltage gate (pu), the same for every device of the fleet; it still applies.
    """

    v_gate_pu: float = 0.8
    kind: ClassVar[int] = EXTERNAL

    def __post_init__(self):
        check_fields(self)

    def packed(self, f0: float) -> LawConstants:
        """Only the gate."""
        return LawConstants(self.kind, 0.0, 0.0, self.v_gate_pu, False, 0.0, 0.0)


# -- compiled kernels (used by stabctl.dynamics.integrator.integrate) ----------------------


@kernel
def coi_value(values, inertia):
    """Centre-of-inertia value (paper eq. 40) of per-machine values (n_mac,) with weights
    inertia (n_mac,) (H * MVA): sum(values * inertia) / sum(inertia).  The compiled
    counterpart of `stabctl.dynamics.coi.coi_speed` (same value, summed in this order)."""
    return (values * inertia).sum() / inertia.sum()


@njit
def island_coi(values, inertia, island):
    """Each machine's centre-of-inertia value and inertia: eq. 40 over the machines of its
    island.  values, inertia (n_mac,); island (n_mac,) int labels 0, 1, ...
    (`stabctl.network.topology.machine_islands`).  Returns coi, M (n_mac,) each; in one
    island, `coi_value` and sum(inertia) for every machine (same digits)."""
    nm = values.size
    n_islands = island.max() + 1
    if n_islands == 1:
        return np.full(nm, coi_value(values, inertia)), np.full(nm, inertia.sum())
    coi, M = np.empty(nm), np.empty(nm)
    for k in range(n_islands):
        w = np.where(island == k, inertia, 0.0)
        m = w.sum()
        c = coi_value(values, w)
        for i in range(nm):
            if island[i] == k:
                coi[i], M[i] = c, m
    return coi, M


@njit
def relative_speeds(x, nm, inertia, island, sa, out):
    """omega_i - omega_COI (pu) of each device's machine: COI of the machines of its island
    (eq. 40; the whole system when connected) or of the rest of them (sa.rest); with a
    critical group (sa.group, `BangBangCOI` coi="critical"), the COI of the other group in
    its island (`group_reference`).

    Exactly 0 (the device idles under every law) for a device without a machine and for
    one whose machine carries its island's whole COI weight: a machine alone in its island
    (cut off from the rest of the network, `stabctl.dynamics.partition`: its own COI is
    itself), a tripped machine (alone in an island of its own in a stage's partition, so
    in no other machine's COI) or an infinite bus (the reference of its island).  Its
    relative speed is 0 by definition there, not the round-off of w - (w M) / M, and the
    "rest" of its island, empty or weightless, is never divided by.

    Parameters
    ----------
    x : ndarray, shape (n_state,)
        Flat state, or its derivatives (speeds in x[nm:2 nm], pu; or pu/s).
    nm : int
        Machines.
    inertia : ndarray, shape (n_mac,)
        COI weights (MW s, `stabctl.dynamics.coi.coi_inertia` over `island`).
    island : ndarray of int, shape (n_mac,)
        Each machine's island, labels 0, 1, ... (`island_coi`); the run's stage's
        (`stabctl.dynamics.integrator.RunOptions`).
    sa : stabctl.storage.devices.StorageArrays
        The devices (their machines sa.mac, -1: none).
    out : ndarray, shape (n_dev,)
        Written with the relative speeds, pu (pu/s for derivatives).
    """
    w_all = x[nm : 2 * nm]
    coi, M = island_coi(w_all, inertia, island)
    ref = group_reference(w_all, inertia, island, sa.group) if sa.group.size else coi
    for d in range(sa.mac.size):
        i = sa.mac[d]
        w = x[nm + i]
        if i < 0 or inertia[i] == M[i]:
            out[d] = 0.0
        elif sa.rest:
            out[d] = w - (coi[i] * M[i] - w * inertia[i]) / (M[i] - inertia[i])
        elif sa.group.size:
            out[d] = w - ref[i]
        else:
            out[d] = w - coi[i]


@njit
def group_reference(speed, inertia, island, group):
    """Each machine's reference speed under a critical group (pu): within its island, the
    COI speed (eq. 40) of the machines of the other group (group (n_mac,) int, 1 critical,
    0 the rest); the island's COI when the island lacks one of the two groups.  speed,
    inertia (n_mac,).  Returns (n_mac,)."""
    out = np.empty(speed.size)
    for k in range(island.max() + 1):
        m, s = np.zeros(2), np.zeros(2)
        for j in range(speed.size):
            if island[j] == k:
                m[group[j]] += inertia[j]
                s[group[j]] += inertia[j] * speed[j]
        for j in range(speed.size):
            if island[j] != k:
                continue
            g = 1 - group[j]
            out[j] = s[g] / m[g] if m[0] > 0 and m[1] > 0 else (s[0] + s[1]) / (m[0] + m[1])
    return out


@njit
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


@njit
def desired_modes(sa, modes, rel_mac):
    """`desired_mode` of every device (n_dev,) int from its present mode (n_dev,) and the
    relative speed of each machine rel_mac (n_mac,) pu, the voltage gate open: the
    commands of a controller that sees speeds only (`stabctl.estimation.closed_loop`)."""
    out = np.empty(modes.size, np.int64)
    for d in range(modes.size):
        out[d] = desired_mode(sa, d, modes[d], rel_mac[sa.mac[d]], 1.0)
    return out


@kernel
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
